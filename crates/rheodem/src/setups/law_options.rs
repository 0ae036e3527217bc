//! The adhesive law as a set-up's options, shared by every set-up that takes one (the
//! split-bottom cell, the chute): the fields `law`, `surface_tension`, `volume_nl`,
//! `contact_angle_deg`, `max_force` and `adhesive_stiffness`, and how their values, over a
//! config's `cohesion` table, become the spec's [`LawSpec`].

use crate::contact::{LawKind, LawSpec};
use crate::scenario::{ScenarioError, invalid};
use crate::setups::schema::{Values, given};

/// A set-up's fields with the adhesive law's fields between `before` and `after`:
/// `fields_with_law!([before…]; [after…])` is the `&'static [Field]` of
/// [`crate::setups::schema::SetUpSchema::FIELDS`]. The law's fields are read by the set-up
/// through [`cohesion`].
macro_rules! fields_with_law {
    ([$($before:expr),* $(,)?]; [$($after:expr),* $(,)?]) => {
        &[
            $($before,)*
            $crate::setups::schema::Field::adhesive_law("law", "Adhesive law between all particles and with the walls")
                .note(" [default: none, or the config's cohesion table]")
                .by_set_up(),
            $crate::setups::schema::Field::number(
                "surface_tension",
                "N/m",
                "Surface tension γ_s of a liquid bridge (liquid_bridge, rabinovich)",
                $crate::setups::schema::Range::Above(0.0),
            )
            .note(" [default with a liquid bridge: 0.02]")
            .by_set_up(),
            $crate::setups::schema::Field::number(
                "volume_nl",
                "nl = 1e-12 m³",
                "Bridge volume V_b of a liquid bridge",
                $crate::setups::schema::Range::AtLeast(0.0),
            )
            .note(
                " (0, Willett's only: attraction only while touching), with a rupture distance \
                 below the mean diameter [default with a liquid bridge: 75]",
            )
            .by_set_up(),
            $crate::setups::schema::Field::number(
                "contact_angle_deg",
                "degrees",
                "Contact angle θ of a liquid bridge",
                $crate::setups::schema::Range::AtLeast(0.0),
            )
            .note(", below 90 [default with a liquid bridge: 20]")
            .by_set_up(),
            $crate::setups::schema::Field::number(
                "max_force",
                "N",
                "Maximum adhesive force f_a^max of a linear law",
                $crate::setups::schema::Range::Above(0.0),
            )
            .note(" (required with law linear_irreversible or reversible)")
            .by_set_up(),
            $crate::setups::schema::Field::number(
                "adhesive_stiffness",
                "N/m",
                "Adhesive stiffness k_c of a linear law",
                $crate::setups::schema::Range::Above(0.0),
            )
            .note(
                ", with f_a^max/k_c below the mean diameter (required with law linear_irreversible \
                 or reversible, unless the config's cohesion table gives its range)",
            )
            .by_set_up(),
            $($after,)*
        ]
    };
}
pub(crate) use fields_with_law;

/// The adhesive laws' parameters a set-up takes as options: the option's key, the law's
/// key, and the factor from the option's unit to the law's (volumes in nl).
const LAW_OPTIONS: &[(&str, &str, f64)] = &[
    ("surface_tension", "surface_tension", 1.0),
    ("volume_nl", "volume", 1e-12),
    ("contact_angle_deg", "contact_angle_deg", 1.0),
    ("max_force", "max_force", 1.0),
    ("adhesive_stiffness", "stiffness", 1.0),
];

/// The liquid bridges' (Willett's and Rabinovich's) values where none is given: the
/// papers' reference bridge (`γ_s` = 0.020 N/m, `V_b` = 75 nl; Roy et al. 2016).
const WILLETT_DEFAULTS: &[(&str, f64)] = &[("surface_tension", 0.020), ("volume", 75e-12)];

/// The adhesive law from `law` and its parameters in `values`, starting from the base
/// spec's law `base`: the same law keeps the base's values where none is given, another
/// starts from its own defaults (for the Willett law, the papers' reference bridge). Every
/// default the law declares is written out, so that the spec holds every value the run
/// uses; a parameter the law lacks, or one it needs and lacks, is an error naming it.
pub fn cohesion(base: LawSpec, values: &Values) -> Result<LawSpec, ScenarioError> {
    let law = match given(values, "law").and_then(toml::Value::as_str) {
        Some(name) => LawKind::from_name(name).map_err(|e| invalid("law", e.value, e.reason))?,
        None => base.law,
    };
    let mut spec = if law == base.law {
        base
    } else {
        LawSpec::new(law, [])
    };
    let declared = law.info().parameters;
    for (option, key, factor) in LAW_OPTIONS {
        let Some(v) =
            given(values, option).and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)))
        else {
            continue;
        };
        if !declared.iter().any(|p| p.key == *key) {
            let having: Vec<String> = crate::contact::adhesion::LAWS
                .iter()
                .filter(|l| l.parameters.iter().any(|p| p.key == *key))
                .map(|l| format!("law = {}", l.name))
                .collect();
            return Err(invalid(
                *option,
                v,
                format!(
                    "is not a parameter of law {law}: give {} or leave {option} out",
                    having.join(" or ")
                ),
            ));
        }
        // The option replaces the base's value and whatever the law takes instead of it
        // (a linear law's range for its stiffness, or the other way round).
        let replaced = declared.iter().filter_map(|p| match p.instead_of {
            Some(other) if other == *key => Some(p.key),
            _ if p.key == *key => p.instead_of,
            _ => None,
        });
        for other in replaced.collect::<Vec<_>>() {
            spec.values.remove(other);
        }
        spec.values.insert(key.to_string(), v * factor);
    }
    if matches!(law, LawKind::LiquidBridge | LawKind::Rabinovich) {
        for (key, v) in WILLETT_DEFAULTS {
            spec.values.entry(key.to_string()).or_insert(*v);
        }
    }
    let spec = spec.with_defaults();
    // What the law needs and lacks (a parameter given instead of another counts for it).
    let missing: Vec<&str> = declared
        .iter()
        .filter(|p| p.instead_of.is_none() && !spec.values.contains_key(p.key))
        .filter(|p| {
            !declared
                .iter()
                .any(|q| q.instead_of == Some(p.key) && spec.values.contains_key(q.key))
        })
        .map(|p| {
            LAW_OPTIONS
                .iter()
                .find(|(_, key, _)| *key == p.key)
                .map_or(p.key, |(option, _, _)| option)
        })
        .collect();
    if !missing.is_empty() {
        return Err(invalid(
            "law",
            format!("\"{law}\""),
            format!(
                "needs {} (as options, or in the config's cohesion table)",
                missing.join(" and ")
            ),
        ));
    }
    Ok(spec)
}

/// A law with its values in a run's or point's name: `dry`, `willett-g0.02-v75` (volume in
/// nl, a contact angle other than 20° as `-theta…`), `linear-f…-k…`, or any other law's
/// name with its values in key order.
pub fn law_name(c: &LawSpec) -> String {
    let value = |key: &str| c.value(key).unwrap_or(f64::NAN);
    match c.law {
        LawKind::None => "dry".to_string(),
        LawKind::LiquidBridge => {
            let angle = value("contact_angle_deg");
            let angle = if angle == 20.0 {
                String::new()
            } else {
                format!("-theta{angle}")
            };
            format!(
                "willett-g{}-v{}{angle}",
                value("surface_tension"),
                (value("volume") * 1e12 * 1e6).round() / 1e6
            )
        }
        LawKind::LinearIrreversible if c.value("stiffness").is_some() => {
            format!("linear-f{:e}-k{}", value("max_force"), value("stiffness"))
        }
        // Any other law (or a linear one given by its range): its name and its values in
        // key order.
        other => std::iter::once(other.name().replace('_', "-"))
            .chain(c.values.iter().map(|(k, v)| format!("{k}{v}")))
            .collect::<Vec<_>>()
            .join("-"),
    }
}
