//! The parameters of an adhesive law as a scenario file, an option or a set-up gives them:
//! declared once per law ([`Parameter`]), given by name ([`LawSpec`], [`Parameters`]),
//! checked against their declared bounds with an error that names the key.

use super::{Adhesion, LawKind};
use serde::de::{MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::collections::BTreeMap;

/// Where a parameter's value may lie.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bounds {
    /// A positive finite number.
    Positive,
    /// Zero or a positive finite number.
    NonNegative,
    /// The half-open interval `[lo, hi)`.
    HalfOpen(f64, f64),
}

impl Bounds {
    /// Whether `v` lies within the bounds.
    pub fn contains(self, v: f64) -> bool {
        v.is_finite()
            && match self {
                Bounds::Positive => v > 0.0,
                Bounds::NonNegative => v >= 0.0,
                Bounds::HalfOpen(lo, hi) => (lo..hi).contains(&v),
            }
    }

    /// The bounds in words, with the unit: `must be a positive finite number (N/m)`.
    pub fn describe(self, unit: &str) -> String {
        match self {
            Bounds::Positive => format!("must be a positive finite number ({unit})"),
            Bounds::NonNegative => format!("must be zero or positive ({unit})"),
            Bounds::HalfOpen(lo, hi) => format!("must lie in [{lo}, {hi}) {unit}"),
        }
    }
}

/// One parameter of an adhesive law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Parameter {
    /// Its key in scenario files and set-up specs.
    pub key: &'static str,
    /// Its unit as written in files (`N/m`, `m³`, `degrees`).
    pub unit: &'static str,
    /// What it is, with its symbol.
    pub meaning: &'static str,
    /// Where its value may lie.
    pub bounds: Bounds,
    /// Its value when not given; `None` when it must be given (or is one of a choice of
    /// keys the law explains in its error).
    pub default: Option<f64>,
    /// Said after the bounds when a value lies outside them (may be empty).
    pub note: &'static str,
    /// The key this one is given instead of (the two exclude each other), if any.
    pub instead_of: Option<&'static str>,
}

/// A law parameter that is missing, unknown or out of bounds: the key (relative to the
/// law's table, e.g. `volume`), the value as written and what is allowed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("`{key}` = {value}: {reason}")]
pub struct LawError {
    /// The key, relative to the law's table (`law` for the name itself, empty for the
    /// table as a whole).
    pub key: String,
    /// The offending value as written.
    pub value: String,
    /// What is allowed.
    pub reason: String,
}

/// The parameters of a linear adhesive law (reversible or irreversible): `f_a^max` and
/// either the stiffness `k_c` or the range `f_a^max / k_c` (read by [`Parameters::linear`]).
pub const LINEAR_LAW_PARAMETERS: &[Parameter] = &[
    Parameter {
        key: "max_force",
        unit: "N",
        meaning: "maximum adhesive force f_a^max",
        bounds: Bounds::Positive,
        default: None,
        note: "",
        instead_of: None,
    },
    Parameter {
        key: "stiffness",
        unit: "N/m",
        meaning: "adhesive stiffness k_c of the separation branch (or give `range`)",
        bounds: Bounds::Positive,
        default: None,
        note: "",
        instead_of: None,
    },
    Parameter {
        key: "range",
        unit: "m",
        meaning: "separation f_a^max / k_c where the attraction ends (instead of `stiffness`)",
        bounds: Bounds::Positive,
        default: None,
        note: "",
        instead_of: Some("stiffness"),
    },
];

/// Named values given for one law, read through its parameter table.
#[derive(Clone, Debug)]
pub struct Parameters<'a> {
    law: &'static str,
    table: &'static [Parameter],
    values: &'a BTreeMap<String, f64>,
}

impl<'a> Parameters<'a> {
    /// The values given for `law`.
    pub fn new(law: LawKind, values: &'a BTreeMap<String, f64>) -> Parameters<'a> {
        let info = law.info();
        Parameters {
            law: info.name,
            table: info.parameters,
            values,
        }
    }

    /// Fails on a key the law does not declare, listing those it does.
    pub fn check_keys(&self) -> Result<(), LawError> {
        for key in self.values.keys() {
            if !self.table.iter().any(|p| p.key == key) {
                let allowed: Vec<&str> = self.table.iter().map(|p| p.key).collect();
                return Err(LawError {
                    key: key.clone(),
                    value: self.values[key].to_string(),
                    reason: if allowed.is_empty() {
                        format!("the law `{}` takes no parameters", self.law)
                    } else {
                        format!(
                            "is not a parameter of the law `{}`; it takes {}",
                            self.law,
                            allowed.join(", ")
                        )
                    },
                });
            }
        }
        Ok(())
    }

    /// The value of `key` (or its default), checked against its bounds; `None` when it is
    /// neither given nor defaulted.
    ///
    /// # Panics
    /// If the law does not declare `key` (a programming error in the law's file).
    pub fn get(&self, key: &str) -> Result<Option<f64>, LawError> {
        let p = self
            .table
            .iter()
            .find(|p| p.key == key)
            .expect("a law reads only the parameters it declares");
        let Some(v) = self.values.get(key).copied().or(p.default) else {
            return Ok(None);
        };
        if p.bounds.contains(v) {
            Ok(Some(v))
        } else {
            Err(LawError {
                key: key.to_string(),
                value: v.to_string(),
                reason: format!("{}{}", p.bounds.describe(p.unit), p.note),
            })
        }
    }

    /// The value of `key` (or its default); an error when it is missing.
    pub fn require(&self, key: &str) -> Result<f64, LawError> {
        self.get(key)?.ok_or_else(|| LawError {
            key: key.to_string(),
            value: "(missing)".into(),
            reason: format!("the law `{}` needs it", self.law),
        })
    }

    /// `f_max` and `k_c` of a linear law given `max_force` and one of `stiffness` (N/m) or
    /// `range` (m, `k_c = f_max / range`).
    pub fn linear(&self) -> Result<(f64, f64), LawError> {
        self.check_keys()?;
        let f = self.require("max_force")?;
        let stiffness = self.get("stiffness")?;
        let range = self.get("range")?;
        match (stiffness, range) {
            (Some(_), Some(_)) => Err(LawError {
                key: String::new(),
                value: "stiffness and range".into(),
                reason: "give at most one of stiffness, range".into(),
            }),
            (Some(k), None) => Ok((f, k)),
            (None, Some(r)) => Ok((f, f / r)),
            (None, None) => Err(LawError {
                key: "stiffness".into(),
                value: "(missing)".into(),
                reason: "give `stiffness` (N/m) or `range` (m)".into(),
            }),
        }
    }
}

/// A set-up's adhesive strength, from which each law derives its parameters
/// ([`super::AdhesiveLaw::at_strength`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Strength {
    /// `f_a^max` (N) of the mean pair (two particles of diameter `mean_diameter`).
    pub max_force: f64,
    /// Rupture distance (m) of a law with a range of its own.
    pub rupture_distance: f64,
    /// Normal contact stiffness `k_n` (N/m).
    pub normal_stiffness: f64,
    /// Mean particle diameter `d_p` (m).
    pub mean_diameter: f64,
}

/// An adhesive law by name with its parameters, as a scenario file or set-up writes it:
/// `{ law = "liquid_bridge", surface_tension = 0.02, contact_angle_deg = 20, volume = 75e-12 }`.
/// The name may be an alias; it is written back under the law's own name.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LawSpec {
    /// The law.
    pub law: LawKind,
    /// Its parameters by key, in the units the law declares.
    pub values: BTreeMap<String, f64>,
}

impl LawSpec {
    /// The law `law` with `values`.
    pub fn new(law: LawKind, values: impl IntoIterator<Item = (&'static str, f64)>) -> LawSpec {
        LawSpec {
            law,
            values: values
                .into_iter()
                .map(|(k, v)| (k.to_string(), v))
                .collect(),
        }
    }

    /// The law with its parameters checked.
    pub fn build(&self) -> Result<Adhesion, LawError> {
        self.law.build(&Parameters::new(self.law, &self.values))
    }

    /// The value given for `key`, if any.
    pub fn value(&self, key: &str) -> Option<f64> {
        self.values.get(key).copied()
    }

    /// The same law with every default its parameters declare written out where no
    /// value is given, so that the spec holds every value the law uses.
    pub fn with_defaults(mut self) -> LawSpec {
        for p in self.law.info().parameters {
            if let Some(v) = p.default {
                self.values.entry(p.key.to_string()).or_insert(v);
            }
        }
        self
    }
}

impl Serialize for LawSpec {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(1 + self.values.len()))?;
        map.serialize_entry("law", self.law.name())?;
        for (k, v) in &self.values {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for LawSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<LawSpec, D::Error> {
        struct SpecVisitor;
        impl<'de> Visitor<'de> for SpecVisitor {
            type Value = LawSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a table with `law` (the law's name) and its numeric parameters")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<LawSpec, A::Error> {
                let mut law = None;
                let mut values = BTreeMap::new();
                while let Some(key) = map.next_key::<String>()? {
                    if key == "law" {
                        let name: String = map.next_value()?;
                        let kind = LawKind::from_name(&name).map_err(|e| {
                            serde::de::Error::custom(format!("law {} {}", e.value, e.reason))
                        })?;
                        law = Some(kind);
                    } else if let Some(v) = map.next_value::<Option<f64>>()? {
                        // A null (an option left out when written as JSON) is no value.
                        values.insert(key, v);
                    }
                }
                let law = law.ok_or_else(|| serde::de::Error::missing_field("law"))?;
                Ok(LawSpec { law, values })
            }
        }
        d.deserialize_map(SpecVisitor)
    }
}
