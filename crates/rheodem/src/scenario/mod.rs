//! Scenario files: parsing (TOML), validation with errors that name the key and the
//! allowed range, and assembly of a ready-to-run [`Simulation`](crate::Simulation).

mod build;
mod prepare;
pub mod spec;

pub use build::{Built, Checked, MAX_STEPS, Resolved, build, check, contact_table};
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
    pub fn from_toml(text: &str) -> Result<Scenario, ScenarioError> {
        let de = toml::Deserializer::parse(text)
            .map_err(|e| ScenarioError::Parse(format!("scenario: {e}")))?;
        serde_path_to_error::deserialize(de).map_err(|e| {
            let path = e.path().to_string();
            let inner = e.into_inner();
            if path.is_empty() || path == "." {
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
