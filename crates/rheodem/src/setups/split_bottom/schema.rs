//! The split-bottom cell's parameters (one list, from which its command-line options, their
//! help and the checks of every spec come) and how given values become a spec: the keys of
//! [`SplitBottomSpec`], `mu_p` for its `friction`, and the adhesive law as `law` with its
//! parameters, gathered into the spec's `cohesion` table.

use super::spec::{Cohesion, SplitBottomSpec};
use crate::scenario::{ScenarioError, invalid};
use crate::setups::schema::{Field, Range, SetUpSchema, Values, given, overlay, table_of};

/// The names `law` accepts.
const LAWS: &[&str] = &["dry", "willett", "linear"];

/// The parameters of the Willett law, and those of the linear irreversible law.
const WILLETT_KEYS: &[&str] = &["surface_tension", "volume_nl", "contact_angle_deg"];
const LINEAR_KEYS: &[&str] = &["max_force", "adhesive_stiffness"];

impl SetUpSchema for SplitBottomSpec {
    const NAME: &'static str = "split-bottom";
    const SUMMARY: &'static str = "Split-bottom ring shear cell: fill, settle, shear; wall \
        torque and the shear band (Roy et al. 2016, Shi et al. 2020).";
    const FIELDS: &'static [Field] = &[
        Field::number(
            "omega",
            "rad/s",
            "Angular velocity Ω of the outer parts",
            Range::AtLeast(0.0),
        ),
        Field::number("gravity", "m/s²", "Gravity g along −z", Range::AtLeast(0.0)),
        Field::choice(
            "law",
            "Adhesive law between all particles and at the walls",
            LAWS,
        )
        .note(" [default: dry, or the config's cohesion table]")
        .by_set_up(),
        Field::number(
            "surface_tension",
            "N/m",
            "Surface tension γ_s of the Willett law",
            Range::Above(0.0),
        )
        .note(" [default with law willett: 0.02]")
        .by_set_up(),
        Field::number(
            "volume_nl",
            "nl = 1e-12 m³",
            "Bridge volume V_b of the Willett law",
            Range::AtLeast(0.0),
        )
        .note(
            " (0: attraction only while touching), with a rupture distance below the mean \
             diameter [default with law willett: 75]",
        )
        .by_set_up(),
        Field::number(
            "contact_angle_deg",
            "degrees",
            "Contact angle θ of the Willett law",
            Range::AtLeast(0.0),
        )
        .note(", below 90 [default with law willett: 20]")
        .by_set_up(),
        Field::number(
            "max_force",
            "N",
            "f_a^max of the linear irreversible law",
            Range::Above(0.0),
        )
        .note(" (required with law linear)")
        .by_set_up(),
        Field::number(
            "adhesive_stiffness",
            "N/m",
            "k_c of the linear irreversible law",
            Range::Above(0.0),
        )
        .note(", with f_a^max/k_c below the mean diameter (required with law linear)")
        .by_set_up(),
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
    ];

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

/// The adhesive law from `law` and its parameters in `values`, starting from the base
/// spec's law `base` (a parameter not given keeps the base's value, or the papers' default).
fn cohesion(base: Cohesion, values: &Values) -> Result<Cohesion, ScenarioError> {
    let number = |key: &str| {
        given(values, key).and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)))
    };
    let law = match given(values, "law").and_then(toml::Value::as_str) {
        Some(name) => name,
        None => match base {
            Cohesion::Dry => "dry",
            Cohesion::Willett { .. } => "willett",
            Cohesion::Linear { .. } => "linear",
        },
    };
    for (keys, owner) in [(WILLETT_KEYS, "willett"), (LINEAR_KEYS, "linear")] {
        if let Some(key) = keys.iter().find(|k| given(values, k).is_some())
            && law != owner
        {
            return Err(invalid(
                *key,
                given(values, key).map_or(String::new(), ToString::to_string),
                format!(
                    "is a parameter of law {owner}, but the law is {law}: give law = {owner} or \
                     leave {key} out"
                ),
            ));
        }
    }
    Ok(match law {
        "willett" => {
            let (g0, v0, a0) = match base {
                Cohesion::Willett {
                    surface_tension,
                    volume,
                    contact_angle_deg,
                } => (surface_tension, volume, contact_angle_deg),
                _ => (0.020, 75e-12, 20.0),
            };
            Cohesion::Willett {
                surface_tension: number("surface_tension").unwrap_or(g0),
                volume: number("volume_nl").map_or(v0, |v| v * 1e-12),
                contact_angle_deg: number("contact_angle_deg").unwrap_or(a0),
            }
        }
        "linear" => {
            let (f0, k0) = match base {
                Cohesion::Linear {
                    max_force,
                    stiffness,
                } => (Some(max_force), Some(stiffness)),
                _ => (None, None),
            };
            match (
                number("max_force").or(f0),
                number("adhesive_stiffness").or(k0),
            ) {
                (Some(max_force), Some(stiffness)) => Cohesion::Linear {
                    max_force,
                    stiffness,
                },
                _ => {
                    return Err(invalid(
                        "law",
                        "\"linear\"",
                        "needs max_force and adhesive_stiffness (or both in the config's \
                         cohesion table)",
                    ));
                }
            }
        }
        _ => Cohesion::Dry,
    })
}
