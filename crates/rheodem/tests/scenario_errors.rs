//! Malformed scenarios: each gives an error naming the offending key (and never panics).

use rheodem::scenario::{Scenario, build};
use std::path::Path;

/// A valid scenario; each case below breaks one thing in it.
const VALID: &str = r#"
seed = 3
[domain]
size = [0.02, 0.02, 0.02]
periodic = [true, true, true]
[[species]]
name = "glass"
density = 2000.0
[[contact]]
normal = { stiffness = 100.0, restitution = 0.8 }
friction = { stiffness_ratio = 0.2857, damping_ratio = 0.2857, mu = 0.5 }
[[particles]]
kind = "random"
species = "glass"
count = 50
mean_diameter = 2.2e-3
polydispersity = 2.0
[run]
steps = 10
"#;

fn error_of(text: &str) -> String {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    match Scenario::from_toml(text) {
        Err(e) => e.to_string(),
        Ok(s) => match build(&s, dir) {
            Err(e) => e.to_string(),
            Ok(_) => String::from("(no error)"),
        },
    }
}

#[test]
fn valid_scenario_builds() {
    assert_eq!(error_of(VALID), "(no error)");
}

#[test]
fn malformed_scenarios_name_the_key_and_range() {
    // (what is broken, replacement applied to VALID, words the message must contain)
    let cases: &[(&str, (&str, &str), &[&str])] = &[
        (
            "unknown key",
            ("seed = 3", "seed = 3\nsead = 4"),
            &["unknown field", "sead"],
        ),
        (
            "unknown key in a table",
            ("density = 2000.0", "density = 2000.0\ncolour = 1"),
            &["colour"],
        ),
        (
            "missing run table",
            ("[run]\nsteps = 10", ""),
            &["missing field", "run"],
        ),
        (
            "fields along an unknown axis",
            (
                "[run]",
                "[fields]\nbins = [8]\nwidth = 2e-3\naxis = \"w\"\n[run]",
            ),
            &["fields.axis", "\"x\", \"y\" or \"z\""],
        ),
        (
            "Cartesian fields with one cell count",
            (
                "[run]",
                "[fields]\ngrid = \"cartesian\"\nbins = [8]\nwidth = 2e-3\n[run]",
            ),
            &["fields.bins", "3 positive cell count"],
        ),
        (
            "fields with a kernel width of zero",
            ("[run]", "[fields]\nbins = [8]\nwidth = 0.0\n[run]"),
            &["fields.width"],
        ),
        (
            "negative density",
            ("density = 2000.0", "density = -1.0"),
            &["species[0].density", "positive"],
        ),
        (
            "restitution above one",
            ("restitution = 0.8", "restitution = 1.5"),
            &["contact[0].normal.restitution", "(0, 1]"],
        ),
        (
            "two damping laws",
            ("restitution = 0.8", "restitution = 0.8, damping = 0.1"),
            &["contact[0].normal", "at most one"],
        ),
        (
            "zero stiffness",
            ("stiffness = 100.0", "stiffness = 0.0"),
            &["contact[0].normal.stiffness", "positive"],
        ),
        (
            "an unknown normal law",
            ("stiffness = 100.0", "law = \"hertzian\", stiffness = 100.0"),
            &["contact[0]", "hertzian", "linear (hooke)", "luding"],
        ),
        (
            "Luding's law without its largest stiffness",
            (
                "stiffness = 100.0",
                "law = \"luding\", stiffness = 100.0, plasticity_depth = 0.05",
            ),
            &[
                "contact[0].normal.max_stiffness",
                "(missing)",
                "`luding` needs it",
            ],
        ),
        (
            "Luding's law with k_p below k_1",
            (
                "stiffness = 100.0",
                "law = \"luding\", stiffness = 100.0, max_stiffness = 50.0, plasticity_depth = 0.05",
            ),
            &["contact[0].normal.max_stiffness", "k_p > k_1"],
        ),
        (
            "Luding's law with a plasticity depth above one",
            (
                "stiffness = 100.0",
                "law = \"elasto-plastic\", stiffness = 100.0, max_stiffness = 500.0, plasticity_depth = 2.0",
            ),
            &["contact[0].normal.plasticity_depth", "(0, 1]"],
        ),
        (
            "a key of Luding's law under the linear law",
            (
                "stiffness = 100.0",
                "stiffness = 100.0, plasticity_depth = 0.05",
            ),
            &[
                "contact[0].normal.plasticity_depth",
                "not a parameter of the law `linear`",
            ],
        ),
        (
            "an unknown spring law",
            ("mu = 0.5", "mu = 0.5, law = \"velcro\""),
            &["contact[0].friction.law", "velcro", "linear (coulomb)"],
        ),
        (
            "negative friction",
            ("mu = 0.5", "mu = -0.5"),
            &["contact[0].friction.mu_static", "≥ 0"],
        ),
        (
            "friction without spring",
            ("stiffness_ratio = 0.2857, damping_ratio = 0.2857, ", ""),
            &["contact[0].friction.stiffness", "missing"],
        ),
        (
            "unknown species",
            ("species = \"glass\"\ncount", "species = \"sand\"\ncount"),
            &["particles[0].species", "\"sand\"", "\"glass\""],
        ),
        (
            "zero count",
            ("count = 50", "count = 0"),
            &["particles[0].count", "[1,"],
        ),
        (
            "impossible packing",
            ("count = 50", "count = 5000"),
            &["particles[0].count", "impossible packing", "0.35"],
        ),
        (
            "polydispersity below one",
            ("polydispersity = 2.0", "polydispersity = 0.5"),
            &["particles[0].polydispersity", "[1, 20]"],
        ),
        (
            "negative box edge",
            ("size = [0.02, 0.02, 0.02]", "size = [0.02, -0.02, 0.02]"),
            &["domain.size[1]", "positive"],
        ),
        (
            "box too small for periodic images",
            ("size = [0.02, 0.02, 0.02]", "size = [0.02, 0.02, 0.005]"),
            &["domain.size", "too small", "axis z"],
        ),
        (
            "time step too large",
            ("steps = 10", "steps = 10\ndt = 1.0"),
            &["run.dt", "t_c/10"],
        ),
        (
            "no run length",
            ("steps = 10", "dt_fraction = 0.02"),
            &["run", "exactly one of `duration`"],
        ),
        (
            "both run lengths",
            ("steps = 10", "steps = 10\nduration = 1.0"),
            &["run", "exactly one"],
        ),
        (
            "unknown particle kind",
            ("kind = \"random\"", "kind = \"poisson\""),
            &["unknown variant", "poisson"],
        ),
        (
            "wrong type",
            ("count = 50", "count = \"many\""),
            &["particles[0].count", "\"many\"", "whole number"],
        ),
        (
            "preparation target out of range",
            ("[run]", "[preparation]\nvolume_fraction = 0.9\n[run]"),
            &["preparation.volume_fraction", "(0, 0.70]"],
        ),
        (
            "missing packing file",
            (
                "kind = \"random\"\nspecies = \"glass\"\ncount = 50\nmean_diameter = 2.2e-3\npolydispersity = 2.0",
                "kind = \"file\"\nspecies = \"glass\"\npath = \"no/such/file.txt\"",
            ),
            &["cannot read", "no/such/file.txt"],
        ),
        (
            "overdamped contact",
            ("restitution = 0.8", "damping = 1000.0"),
            &["overdamped"],
        ),
        (
            "zero wall normal",
            (
                "[run]",
                "[[wall]]\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 0.0]\nspecies = \"glass\"\n[run]",
            ),
            &["wall[0].normal", "non-zero"],
        ),
        (
            "non-finite gravity",
            ("seed = 3", "seed = 3\ngravity = [0.0, 0.0, nan]"),
            &["gravity", "finite"],
        ),
        (
            "negative surface tension",
            (
                "mu = 0.5 }",
                "mu = 0.5 }\nadhesion = { law = \"liquid_bridge\", surface_tension = -0.02, contact_angle_deg = 20.0, volume = 75e-12 }",
            ),
            &["contact[0].adhesion.surface_tension", "positive"],
        ),
        (
            "contact angle of 90 degrees",
            (
                "mu = 0.5 }",
                "mu = 0.5 }\nadhesion = { law = \"liquid_bridge\", surface_tension = 0.02, contact_angle_deg = 90.0, volume = 75e-12 }",
            ),
            &["contact[0].adhesion.contact_angle_deg", "[0, 90)"],
        ),
        (
            "negative bridge volume (0 is the contact-only limit)",
            (
                "mu = 0.5 }",
                "mu = 0.5 }\nadhesion = { law = \"liquid_bridge\", surface_tension = 0.02, contact_angle_deg = 20.0, volume = -1e-12 }",
            ),
            &["contact[0].adhesion.volume", "zero or positive"],
        ),
        (
            "adhesion without stiffness or range",
            (
                "mu = 0.5 }",
                "mu = 0.5 }\nadhesion = { law = \"reversible\", max_force = 1e-4 }",
            ),
            &["contact[0].adhesion.stiffness", "range"],
        ),
        (
            "adhesion with stiffness and range",
            (
                "mu = 0.5 }",
                "mu = 0.5 }\nadhesion = { law = \"linear_irreversible\", max_force = 1e-4, stiffness = 1.0, range = 1e-4 }",
            ),
            &["contact[0].adhesion", "at most one"],
        ),
        (
            "negative adhesive force",
            (
                "mu = 0.5 }",
                "mu = 0.5 }\nadhesion = { law = \"reversible\", max_force = -1e-4, stiffness = 100.0 }",
            ),
            &["contact[0].adhesion.max_force", "positive"],
        ),
        (
            "unknown adhesion law",
            (
                "mu = 0.5 }",
                "mu = 0.5 }\nadhesion = { law = \"glue\", max_force = 1e-4 }",
            ),
            &["contact[0]", "glue"],
        ),
        (
            "shear without periodic y",
            (
                "periodic = [true, true, true]",
                "periodic = [true, false, true]\nshear_rate = 1.0",
            ),
            &["domain.shear_rate", "periodic x and y"],
        ),
        (
            "stress control without shear",
            (
                "[run]",
                "[stress_control]\ntarget = 100.0\nmodulus = 4.5e4\ntime = 0.01\n[run]",
            ),
            &["stress_control", "shear_rate"],
        ),
        (
            "unknown shear dynamics",
            (
                "periodic = [true, true, true]",
                "periodic = [true, true, true]\nshear_rate = 1.0\nshear_dynamics = \"sllod\"",
            ),
            &["sllod", "lab, peculiar-contacts or affine-drag"],
        ),
        (
            "shear dynamics without shear",
            (
                "periodic = [true, true, true]",
                "periodic = [true, true, true]\nshear_dynamics = \"affine-drag\"",
            ),
            &["domain.shear_dynamics", "affine-drag", "shear_rate"],
        ),
    ];
    for (what, (from, to), needles) in cases {
        assert!(VALID.contains(from), "case `{what}`: pattern not in VALID");
        let msg = error_of(&VALID.replacen(from, to, 1));
        for needle in *needles {
            assert!(
                msg.contains(needle),
                "case `{what}`: message `{msg}` lacks `{needle}`"
            );
        }
    }
}

/// A three-component value given with the wrong number of components is an error that
/// names the key: `domain.size`, `gravity`, `domain.periodic` and a sphere's `position`
/// (whose error names its particle group) with two or four entries. Too few entries are refused; too many are accepted and the
/// extra ones silently dropped (the `toml` deserializer does not check that a fixed-size
/// array is used up), so a typo such as `size = [0.02, 0.02, 0.02, 0.02]` goes unnoticed —
/// contrary to the format's promise that every invalid value is reported.
#[test]
fn three_vectors_need_exactly_three_components() {
    let with_sphere = VALID.replace(
        "[run]",
        "[[particles]]\nkind = \"explicit\"\nspecies = \"glass\"\nspheres = [{ radius = 1e-3, position = [0.01, 0.01, 0.01] }]\n[run]",
    );
    let cases = [
        (
            "size",
            "size = [0.02, 0.02, 0.02]",
            "[0.02, 0.02]",
            "[0.02, 0.02, 0.02, 0.02]",
        ),
        (
            "periodic",
            "periodic = [true, true, true]",
            "[true, true]",
            "[true, true, true, true]",
        ),
        (
            "gravity",
            "seed = 3",
            "[0.0, -9.81]",
            "[0.0, 0.0, -9.81, 0.0]",
        ),
        (
            "position",
            "position = [0.01, 0.01, 0.01]",
            "[0.01, 0.01]",
            "[0.01, 0.01, 0.01, 0.01]",
        ),
    ];
    for (key, from, few, many) in cases {
        for value in [few, many] {
            let to = if key == "gravity" {
                format!("seed = 3\ngravity = {value}")
            } else {
                format!("{key} = {value}")
            };
            let text = with_sphere.replace(from, &to);
            assert_ne!(text, with_sphere);
            let err = error_of(&text);
            // Inside a tagged particle group the path stops at the group.
            let needle = if key == "position" {
                "particles[1]"
            } else {
                key
            };
            assert!(err.contains(needle), "{key} = {value}: {err}");
        }
    }
}
