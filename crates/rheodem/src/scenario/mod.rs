//! Scenario files: parsing (TOML), validation with errors that name the key and the
//! allowed range, and assembly of a ready-to-run [`Simulation`](crate::Simulation).

mod build;
mod prepare;
pub mod size;
pub mod spec;

pub use build::{Built, Checked, MAX_STEPS, Resolved, build, check, contact_table, law_error};
pub use prepare::PreparationReport;
pub use spec::Scenario;

use std::path::{Path, PathBuf};

/// Everything that can be wrong with a scenario.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("cannot read {path}")]
    Io {
        /// The path.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// TOML syntax error, unknown key, missing key or wrong type.
    #[error("{0}")]
    Parse(String),
    /// A value outside its allowed range.
    #[error("`{key}` = {value}: {allowed}")]
    Invalid {
        /// Dotted path of the key, e.g. `species[0].density`.
        key: String,
        /// The offending value as written.
        value: String,
        /// What is allowed.
        allowed: String,
    },
}

/// Shorthand for an [`ScenarioError::Invalid`].
pub fn invalid(
    key: impl Into<String>,
    value: impl ToString,
    allowed: impl Into<String>,
) -> ScenarioError {
    ScenarioError::Invalid {
        key: key.into(),
        value: value.to_string(),
        allowed: allowed.into(),
    }
}

impl Scenario {
    /// Parses a scenario from TOML text (no validation beyond the format).
    /// Errors name the key path (e.g. `particles[0].count`) and the line.
    ///
    /// Omitted keys take their defaults; an unknown key is an error that names it, and
    /// [`build`] then reports values outside their range:
    ///
    /// ```
    /// use rheodem::scenario::{Scenario, build};
    ///
    /// let text = r#"
    ///     [domain]
    ///     size = [0.01, 0.01, 0.01]
    ///     periodic = [true, true, true]
    ///     [[species]]
    ///     name = "glass"
    ///     density = 2000.0
    ///     [[contact]]
    ///     normal = { stiffness = 100.0, restitution = 0.8 }
    ///     [[particles]]
    ///     kind = "random"
    ///     species = "glass"
    ///     count = 20
    ///     mean_diameter = 1.0e-3
    ///     [run]
    ///     steps = 10
    /// "#;
    /// let s = Scenario::from_toml(text)?;
    /// assert_eq!(s.seed, 1); // the default
    /// assert_eq!(s.output.timeseries_rows, 200);
    /// let typo = Scenario::from_toml(&text.replace("density", "densty")).unwrap_err();
    /// assert!(typo.to_string().contains("densty"), "{typo}");
    /// let negative = Scenario::from_toml(&text.replace("2000.0", "-1.0"))?;
    /// let err = build(&negative, std::path::Path::new(".")).err().expect("invalid");
    /// assert_eq!(err.to_string(), "`species[0].density` = -1: must be a positive finite number");
    /// # Ok::<(), rheodem::scenario::ScenarioError>(())
    /// ```
    pub fn from_toml(text: &str) -> Result<Scenario, ScenarioError> {
        let de = toml::Deserializer::parse(text)
            .map_err(|e| ScenarioError::Parse(format!("scenario: {e}")))?;
        serde_path_to_error::deserialize(de).map_err(|e| {
            let path = e.path().to_string();
            let inner = e.into_inner();
            // A field checked inside a tagged group reports "`field` = value: allowed" at
            // the group's path: named here with its full key.
            let field = inner.message().strip_prefix('`').and_then(|rest| {
                let (field, tail) = rest.split_once('`')?;
                let (value, allowed) = tail.strip_prefix(" = ")?.split_once(": ")?;
                Some(invalid(format!("{path}.{field}"), value, allowed))
            });
            if let Some(named) = field.filter(|_| !(path.is_empty() || path == ".")) {
                named
            } else if path.is_empty() || path == "." {
                ScenarioError::Parse(format!("scenario: {inner}"))
            } else {
                ScenarioError::Parse(format!("scenario key `{path}`: {inner}"))
            }
        })
    }

    /// Reads and parses a scenario file.
    pub fn from_file(path: &Path) -> Result<Scenario, ScenarioError> {
        let text = std::fs::read_to_string(path).map_err(|source| ScenarioError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Scenario::from_toml(&text)
    }

    /// The scenario as TOML text.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self)
            .unwrap_or_else(|e| format!("# cannot serialise scenario: {e}\n"))
    }
}
