//! The split-bottom cell's parameters (one list, from which its command-line options, their
//! help and the checks of every spec come) and how given values become a spec: the keys of
//! [`SplitBottomSpec`], `mu_p` for its `friction`, and the adhesive law as `law` with its
//! parameters, gathered into the spec's `cohesion` table.

use super::spec::SplitBottomSpec;
use crate::scenario::{ScenarioError, invalid};
use crate::setups::law_options::{cohesion, fields_with_law};
use crate::setups::schema::{Field, Range, SetUpSchema, Values, given, overlay, table_of};

impl SetUpSchema for SplitBottomSpec {
    const NAME: &'static str = "split-bottom";
    const SUMMARY: &'static str = "Split-bottom ring shear cell: fill, settle, shear; wall \
        torque and the shear band (Roy et al. 2016, Shi et al. 2020).";
    const FIELDS: &'static [Field] = fields_with_law!([
        Field::number(
            "omega",
            "rad/s",
            "Angular velocity Ω of the outer parts",
            Range::AtLeast(0.0),
        ),
        Field::number("gravity", "m/s²", "Gravity g along −z", Range::AtLeast(0.0)),
    ]; [
        Field::number("mu_p", "", "Particle friction μ_p", Range::AtLeast(0.0))
            .stored_as("friction"),
        Field::number("duration", "s", "Shear duration", Range::Above(0.0)),
        Field::number(
            "average_from",
            "s",
            "Start of the averaging window after the start of shear",
            Range::AtLeast(0.0),
        )
        .note(", below the duration"),
        Field::number(
            "scale",
            "",
            "Factor on the cell's lengths (not the particles)",
            Range::Above(0.0),
        )
        .note(
            ", at least about 0.18 (two diameters across each part; a small cell also needs \
             a wider wedge) and within the memory limit",
        ),
        Field::number(
            "wedge_deg",
            "degrees",
            "Wedge angle Φ",
            Range::AboveUpTo(0.0, 180.0),
        )
        .note(", wide enough at the inner wall for a particle not to reach its own image"),
        Field::choice(
            "time_step",
            "Time-step rule: shortest (1/50 of the lightest pair's contact time) or mean-pair \
             (the source papers' code: of the mean pair's)",
            &["shortest", "mean-pair"],
        ),
        Field::count("seed", "Random seed of the filling", Range::AtLeast(0.0)),
        Field::number(
            "inner_radius",
            "m",
            "Inner cylinder radius R_i",
            Range::Above(0.0),
        ),
        Field::number(
            "outer_radius",
            "m",
            "Outer cylinder radius R_o",
            Range::Above(0.0),
        ),
        Field::number(
            "split_radius",
            "m",
            "Radius R_s of the split in the bottom",
            Range::Above(0.0),
        ),
        Field::number(
            "height",
            "m",
            "Filling height H aimed at after settling",
            Range::Above(0.0),
        ),
        Field::number(
            "diameter",
            "m",
            "Mean particle diameter d_p",
            Range::Above(0.0),
        ),
        Field::number(
            "w",
            "",
            "Polydispersity w = d_max/d_min (uniform radii)",
            Range::AtLeast(1.0),
        ),
        Field::number(
            "density",
            "kg/m³",
            "Particle density ρ_p",
            Range::Above(0.0),
        ),
        Field::number(
            "stiffness",
            "N/m",
            "Normal stiffness k_n",
            Range::Above(0.0),
        ),
        Field::number(
            "damping",
            "kg/s",
            "Normal damping γ_n, fixed",
            Range::AtLeast(0.0),
        ),
        Field::number("stiffness_ratio", "", "k_t/k_n", Range::AtLeast(0.0)),
        Field::number("damping_ratio", "", "γ_t/γ_n", Range::AtLeast(0.0)),
        Field::number(
            "settle_damping",
            "",
            "Factor on every damping coefficient while settling",
            Range::Above(0.0),
        ),
        Field::number(
            "settle_kinetic_ratio",
            "",
            "Settling ends when the kinetic energy is below this fraction of the contact \
             springs' energy",
            Range::Above(0.0),
        ),
        Field::number(
            "settle_max_time",
            "s",
            "Settling ends at this time even if the kinetic criterion is not met",
            Range::Above(0.0),
        ),
        Field::count(
            "rows",
            "Time-series rows over the shear stage",
            Range::AtLeast(2.0),
        ),
        Field::count(
            "snapshots",
            "Snapshots over the shear stage (0 for none)",
            Range::AtLeast(0.0),
        ),
        Field::count(
            "checkpoints",
            "Checkpoints over the shear stage besides the final one",
            Range::AtLeast(0.0),
        ),
        Field::number(
            "wall_shell",
            "d_p",
            "Thickness of the frozen wall shell inside the walls, besides the layer touching \
             the mould",
            Range::Closed(0.0, 5.0),
        ),
        Field::number("skin", "d_p", "Verlet skin", Range::Above(0.0)),
        Field::choice(
            "cg_kernel",
            "Coarse-graining kernel of the fields",
            &["lucy", "gaussian"],
        ),
        Field::number("cg_width", "d_p", "Kernel width", Range::Above(0.0)),
        Field::number(
            "cg_spacing",
            "d_p",
            "Spacing of the (r, z) grid of the fields",
            Range::Above(0.0),
        ),
        Field::number(
            "cg_every",
            "s",
            "Time between the fields' samples in the averaging window; 0 for no fields",
            Range::AtLeast(0.0),
        ),
    ]);

    fn defaults() -> toml::Table {
        table_of(&SplitBottomSpec::default())
    }

    fn from_values(base: toml::Table, values: &Values) -> Result<SplitBottomSpec, ScenarioError> {
        let table = overlay(Self::FIELDS, base, values)?;
        let mut s = SplitBottomSpec::from_table(table)?;
        if given(values, "average_from").is_none() && s.average_from >= s.duration {
            return Err(invalid(
                "duration",
                s.duration,
                format!(
                    "ends before the averaging window starts (average_from = {} s, the default \
                     unless the config sets it): give average_from below the duration",
                    s.average_from
                ),
            ));
        }
        s.cohesion = cohesion(s.cohesion, values)?;
        s.geometry()?;
        Ok(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::LawKind;
    use toml::Value;

    fn spec(config: &str, values: &[(&'static str, Value)]) -> Result<SplitBottomSpec, String> {
        let base: toml::Table = toml::from_str(config).expect("TOML");
        SplitBottomSpec::from_values(base, &values.to_vec()).map_err(|e| e.to_string())
    }

    /// The names of earlier files are aliases; a law's defaults are written out; options
    /// land under the law's keys in its units; a law named anew starts from its defaults.
    #[test]
    fn the_law_is_a_registered_law_with_its_parameters() {
        let old = "cohesion = { law = \"willett\", surface_tension = 0.04, volume = 14e-12 }";
        let s = spec(old, &[]).expect("an earlier config");
        assert_eq!(s.cohesion.law, LawKind::LiquidBridge);
        assert_eq!(s.cohesion.value("contact_angle_deg"), Some(20.0));
        assert_eq!(s.cohesion.value("surface_tension"), Some(0.04));
        // Written back under the registered name.
        assert!(
            s.to_toml().contains("law = \"liquid_bridge\""),
            "{}",
            s.to_toml()
        );
        // An option overrides one value and keeps the others.
        let s = spec(old, &[("volume_nl", Value::Float(75.0))]).expect("a volume");
        assert_eq!(s.cohesion.value("surface_tension"), Some(0.04));
        assert!((s.cohesion.value("volume").expect("volume") - 75e-12).abs() < 1e-24);
        // Named by option with nothing else: the papers' reference bridge.
        let s = spec("", &[("law", Value::String("willett".into()))]).expect("Willett");
        assert_eq!(s.cohesion.value("surface_tension"), Some(0.02));
        assert_eq!(s.cohesion.value("volume"), Some(75e-12));
        // Another law than the config's starts from its own values.
        let s = spec(
            old,
            &[
                ("law", Value::String("reversible".into())),
                ("max_force", Value::Float(1e-4)),
                ("adhesive_stiffness", Value::Float(1e3)),
            ],
        )
        .expect("reversible");
        assert_eq!(s.cohesion.law, LawKind::Reversible);
        assert_eq!(s.cohesion.values.len(), 2, "{:?}", s.cohesion.values);
        assert_eq!(s.cohesion.value("stiffness"), Some(1e3));
        // A linear law's range from the config instead of its stiffness.
        let s = spec(
            "cohesion = { law = \"linear\", max_force = 1e-4, range = 1e-4 }",
            &[],
        )
        .expect("a range instead of the stiffness");
        assert_eq!(s.cohesion.law, LawKind::LinearIrreversible);
        assert_eq!(s.law().expect("the law").range(), 1e-4);
        // An option for the stiffness replaces the config's range.
        let s = spec(
            "cohesion = { law = \"linear\", max_force = 1e-4, range = 1e-4 }",
            &[("adhesive_stiffness", Value::Float(2.0))],
        )
        .expect("the stiffness instead of the range");
        assert_eq!(s.cohesion.value("range"), None);
        assert_eq!(s.law().expect("the law").range(), 5e-5);
        // A config table and a study point (read by `from_table`) give the same spec.
        let table = "cohesion = { law = \"willett\", surface_tension = 0.04 }";
        let from_table =
            SplitBottomSpec::from_table(toml::from_str(table).expect("TOML")).expect("a point");
        assert_eq!(from_table, spec(table, &[]).expect("a config"));
        assert_eq!(from_table.cohesion.value("volume"), Some(75e-12));
    }

    /// What a law lacks or does not have is named, with what to give instead.
    #[test]
    fn a_parameter_the_law_lacks_or_needs_is_named() {
        let e = spec("", &[("surface_tension", Value::Float(0.02))]).expect_err("dry");
        assert!(
            e.contains("`surface_tension` = 0.02: is not a parameter of law none")
                && e.contains(
                    "give law = liquid_bridge or law = rabinovich or leave surface_tension out"
                ),
            "{e}"
        );
        let e = spec(
            "",
            &[
                ("law", Value::String("willett".into())),
                ("max_force", Value::Float(1e-4)),
            ],
        )
        .expect_err("Willett has no f_max");
        assert!(
            e.contains("give law = reversible or law = linear_irreversible"),
            "{e}"
        );
        let e = spec("", &[("law", Value::String("reversible".into()))]).expect_err("bare");
        assert!(
            e.contains("`law` = \"reversible\": needs max_force and adhesive_stiffness"),
            "{e}"
        );
        let e = spec("cohesion = { law = \"dry\", volume = 1e-12 }", &[]).expect_err("a key");
        assert!(e.contains("cohesion"), "{e}");
    }
}
