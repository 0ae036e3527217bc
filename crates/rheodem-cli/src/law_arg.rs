//! Adhesive laws on the command line: names, aliases and help texts come from the engine's
//! registry of laws, so a law registered there is accepted here without a change.

use rheodem::contact::LawKind;

/// Parses an adhesive law's name (or an alias, or either in kebab-case).
pub fn law_kind(name: &str) -> Result<LawKind, String> {
    LawKind::from_name(name).map_err(|e| format!("{} {}", e.value, e.reason))
}

/// `what`, followed by the registered laws' names (aliases in parentheses).
pub fn law_help(what: &str) -> String {
    format!("{what}; one of: {}", LawKind::known())
}

/// Parses a law parameter given as `key=value` (value a number in the law's units).
pub fn law_parameter(text: &str) -> Result<(String, f64), String> {
    let (key, value) = text
        .split_once('=')
        .ok_or_else(|| format!("`{text}`: write a law parameter as key=value"))?;
    let value: f64 = value
        .trim()
        .parse()
        .map_err(|_| format!("`{text}`: the value of `{}` is not a number", key.trim()))?;
    Ok((key.trim().to_string(), value))
}
