//! The parameters of a contact law as a scenario file, an option or a set-up gives them:
//! declared once per law ([`Parameter`]), given by name ([`Parameters`]), checked against
//! their declared bounds with an error that names the key. Every registry (normal and
//! adhesive laws) reads its laws' parameters this way.

use serde::de::{MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::collections::BTreeMap;
use std::fmt::Debug;

/// Where a parameter's value may lie.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bounds {
    /// A positive finite number.
    Positive,
    /// Zero or a positive finite number.
    NonNegative,
    /// The half-open interval `[lo, hi)`.
    HalfOpen(f64, f64),
    /// The interval `(lo, hi]`.
    LeftOpen(f64, f64),
}

impl Bounds {
    /// Whether `v` lies within the bounds.
    pub fn contains(self, v: f64) -> bool {
        v.is_finite()
            && match self {
                Bounds::Positive => v > 0.0,
                Bounds::NonNegative => v >= 0.0,
                Bounds::HalfOpen(lo, hi) => (lo..hi).contains(&v),
                Bounds::LeftOpen(lo, hi) => v > lo && v <= hi,
            }
    }

    /// The bounds in words, with the unit: `must be a positive finite number (N/m)`.
    pub fn describe(self, unit: &str) -> String {
        match self {
            Bounds::Positive => format!("must be a positive finite number ({unit})"),
            Bounds::NonNegative => format!("must be zero or positive ({unit})"),
            Bounds::HalfOpen(lo, hi) => format!("must lie in [{lo}, {hi}) {unit}")
                .trim_end()
                .to_string(),
            Bounds::LeftOpen(lo, hi) => format!("must lie in ({lo}, {hi}] {unit}")
                .trim_end()
                .to_string(),
        }
    }
}

/// One parameter of a contact law.
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

/// Named values given for one law, read through its parameter table.
#[derive(Clone, Debug)]
pub struct Parameters<'a> {
    law: &'static str,
    table: &'static [Parameter],
    values: &'a BTreeMap<String, f64>,
}

impl<'a> Parameters<'a> {
    /// The values given for the law named `law`, whose parameters are `table`.
    pub fn of(
        law: &'static str,
        table: &'static [Parameter],
        values: &'a BTreeMap<String, f64>,
    ) -> Parameters<'a> {
        Parameters { law, table, values }
    }

    /// The name of the law the values are given for.
    pub fn law(&self) -> &'static str {
        self.law
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
}

/// The names of a registry's laws, as a [`Spec`] reads and writes them.
pub trait Registered: Copy + Debug + PartialEq + 'static {
    /// What the registry holds, for messages (`normal law`).
    const WHAT: &'static str;
    /// The law a spec without `law` names; `None` when `law` must be given.
    const DEFAULT: Option<Self>;
    /// The law from its name or an alias; the error says which names are known.
    fn from_name(name: &str) -> Result<Self, String>;
    /// The law's own name.
    fn name(self) -> &'static str;
    /// The law's parameter table.
    fn parameters(self) -> &'static [Parameter];
}

/// A law of a registry by name with its parameters, as a scenario file or set-up writes it:
/// `{ law = "…", key = value, … }`. The name may be an alias; it is written back under the
/// law's own name.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Spec<K> {
    /// The law.
    pub law: K,
    /// Its parameters by key, in the units the law declares.
    pub values: BTreeMap<String, f64>,
}

impl<K: Registered> Spec<K> {
    /// The law `law` with `values`.
    pub fn new(law: K, values: impl IntoIterator<Item = (&'static str, f64)>) -> Spec<K> {
        Spec {
            law,
            values: values
                .into_iter()
                .map(|(k, v)| (k.to_string(), v))
                .collect(),
        }
    }

    /// The values given, read through the law's parameter table.
    pub fn parameters(&self) -> Parameters<'_> {
        Parameters::of(self.law.name(), self.law.parameters(), &self.values)
    }

    /// The value given for `key`, if any.
    pub fn value(&self, key: &str) -> Option<f64> {
        self.values.get(key).copied()
    }

    /// The same law with every default its parameters declare written out where no
    /// value is given, so that the spec holds every value the law uses.
    pub fn with_defaults(mut self) -> Spec<K> {
        for p in self.law.parameters() {
            if let Some(v) = p.default {
                self.values.entry(p.key.to_string()).or_insert(v);
            }
        }
        self
    }
}

impl<K: Registered> Serialize for Spec<K> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(1 + self.values.len()))?;
        map.serialize_entry("law", self.law.name())?;
        for (k, v) in &self.values {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

impl<'de, K: Registered> Deserialize<'de> for Spec<K> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Spec<K>, D::Error> {
        struct SpecVisitor<K>(std::marker::PhantomData<K>);
        impl<'de, K: Registered> Visitor<'de> for SpecVisitor<K> {
            type Value = Spec<K>;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(
                    f,
                    "a table with `law` (the {}'s name) and its numeric parameters",
                    K::WHAT
                )
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Spec<K>, A::Error> {
                let mut law = None;
                let mut values = BTreeMap::new();
                while let Some(key) = map.next_key::<String>()? {
                    if key == "law" {
                        let name: String = map.next_value()?;
                        let kind = K::from_name(&name)
                            .map_err(|reason| serde::de::Error::custom(format!("law {reason}")))?;
                        law = Some(kind);
                    } else if let Some(v) = map.next_value::<Option<f64>>()? {
                        // A null (an option left out when written as JSON) is no value.
                        values.insert(key, v);
                    }
                }
                let law = law
                    .or(K::DEFAULT)
                    .ok_or_else(|| serde::de::Error::missing_field("law"))?;
                Ok(Spec { law, values })
            }
        }
        d.deserialize_map(SpecVisitor(std::marker::PhantomData))
    }
}
