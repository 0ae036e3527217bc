//! Names of registered sub-models: each registry (normal laws, springs, adhesive laws) lists
//! its models with a name and aliases; these helpers find a model by any of them and list
//! them for messages, the same way for every registry.

/// Facts about one registered sub-model, for lookups, help texts and documentation.
#[derive(Clone, Copy, Debug)]
pub struct ModelInfo<K: 'static> {
    /// Its kind (the registry's enum of names).
    pub kind: K,
    /// The name scenario files, options and results use (`snake_case`).
    pub name: &'static str,
    /// Other spellings accepted for the name (kebab-case is always accepted too).
    pub aliases: &'static [&'static str],
    /// One line saying what the model is, with its source.
    pub summary: &'static str,
    /// The parameters a scenario file gives (empty where the registry reads its laws'
    /// keys another way).
    pub parameters: &'static [super::parameters::Parameter],
}

/// Whether `given` (trimmed, any `-` read as `_`) spells `name` or one of `aliases`.
pub fn spells(given: &str, name: &str, aliases: &[&str]) -> bool {
    let plain = given.trim().replace('-', "_");
    name == plain || aliases.iter().any(|a| a.replace('-', "_") == plain)
}

/// The model of `models` that `given` names (see [`spells`]).
pub fn find<K: Copy>(models: &[ModelInfo<K>], given: &str) -> Option<K> {
    models
        .iter()
        .find(|m| spells(given, m.name, m.aliases))
        .map(|m| m.kind)
}

/// `name (alias, …)` for a model, as messages list it.
pub fn with_aliases(name: &str, aliases: &[&str]) -> String {
    if aliases.is_empty() {
        name.to_string()
    } else {
        format!("{name} ({})", aliases.join(", "))
    }
}

/// Every model of `models` with its aliases, for messages: `linear (hooke), …`.
pub fn known<K>(models: &[ModelInfo<K>]) -> String {
    models
        .iter()
        .map(|m| with_aliases(m.name, m.aliases))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Implements `Serialize` and `Deserialize` for a registry's enum of laws with one
/// parameter struct per variant: the first law is stored as its bare parameters (the form
/// contact laws had before the registries, so that older checkpoints and files load), every
/// other law tagged with its variant name; both forms are read for every law.
macro_rules! bare_or_tagged {
    ($enum:ident, $bare:ident => $bare_law:ty $(, $variant:ident => $law:ty)*) => {
        const _: () = {
            /// Every law stored tagged with its variant name.
            #[derive(serde::Serialize, serde::Deserialize)]
            enum Tagged {
                $bare($bare_law),
                $($variant($law),)*
            }

            /// The forms a law is read from.
            #[derive(serde::Deserialize)]
            #[serde(untagged)]
            enum Stored {
                Bare($bare_law),
                Tagged(Tagged),
            }

            impl serde::Serialize for $enum {
                fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                    match *self {
                        $enum::$bare(law) => law.serialize(s),
                        $($enum::$variant(law) => Tagged::$variant(law).serialize(s),)*
                    }
                }
            }

            impl<'de> serde::Deserialize<'de> for $enum {
                fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<$enum, D::Error> {
                    Ok(match Stored::deserialize(d)? {
                        Stored::Bare(law) | Stored::Tagged(Tagged::$bare(law)) => $enum::$bare(law),
                        $(Stored::Tagged(Tagged::$variant(law)) => $enum::$variant(law),)*
                    })
                }
            }
        };
    };
}

pub(crate) use bare_or_tagged;

/// Implements the name lookups of a registry's enum of names `$kind` listed in `$list`:
/// `info`, `name`, `from_name` (the error names the known laws, `$what` saying what they
/// are) and `Display`.
macro_rules! kind_names {
    ($kind:ident, $list:ident, $what:literal) => {
        impl $kind {
            /// The facts the registry holds about this law.
            pub fn info(self) -> &'static ModelInfo<$kind> {
                $list
                    .iter()
                    .find(|m| m.kind == self)
                    .expect("every law of the enum is in its registry's list")
            }

            /// The law's name (`snake_case`).
            pub fn name(self) -> &'static str {
                self.info().name
            }

            /// The law from its name: the name itself, an alias, or either in kebab-case;
            /// the error lists the known names.
            pub fn from_name(name: &str) -> Result<$kind, String> {
                names::find($list, name).ok_or_else(|| {
                    format!(
                        concat!("\"{}\" is not a known ", $what, "; known: {}"),
                        name,
                        names::known($list)
                    )
                })
            }
        }

        impl std::fmt::Display for $kind {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }
    };
}

pub(crate) use kind_names;

#[cfg(test)]
mod tests {
    use super::*;

    const MODELS: &[ModelInfo<u8>] = &[
        ModelInfo {
            kind: 0,
            name: "linear",
            aliases: &["hooke"],
            summary: "",
            parameters: &[],
        },
        ModelInfo {
            kind: 1,
            name: "two_words",
            aliases: &[],
            summary: "",
            parameters: &[],
        },
    ];

    #[test]
    fn a_model_is_found_by_its_name_an_alias_or_kebab_case() {
        assert_eq!(find(MODELS, "linear"), Some(0));
        assert_eq!(find(MODELS, " hooke "), Some(0));
        assert_eq!(find(MODELS, "two-words"), Some(1));
        assert_eq!(find(MODELS, "hertz"), None);
        assert_eq!(known(MODELS), "linear (hooke), two_words");
    }

    #[test]
    fn every_registered_name_and_alias_finds_its_law() {
        use super::super::{NORMAL_LAWS, NormalKind, SPRING_LAWS, SpringKind};
        fn check<K: Copy + PartialEq + std::fmt::Debug>(
            models: &[ModelInfo<K>],
            from_name: impl Fn(&str) -> Result<K, String>,
            name: impl Fn(K) -> &'static str,
        ) {
            for m in models {
                assert_eq!(from_name(m.name), Ok(m.kind));
                assert_eq!(from_name(&m.name.replace('_', "-")), Ok(m.kind));
                assert_eq!(name(m.kind), m.name);
                for alias in m.aliases {
                    assert_eq!(from_name(alias), Ok(m.kind));
                }
            }
            let e = from_name("glue").expect_err("unknown");
            assert!(e.contains("glue") && e.contains(models[0].name), "{e}");
        }
        check(NORMAL_LAWS, NormalKind::from_name, NormalKind::name);
        check(SPRING_LAWS, SpringKind::from_name, SpringKind::name);
    }
}
