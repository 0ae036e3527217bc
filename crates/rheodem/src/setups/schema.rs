//! A set-up's parameters, declared once.
//!
//! Each set-up lists its parameters as [`Field`]s: the key (a TOML key, a `--kebab-case`
//! option, a keyword of a library call), what it holds, its unit, its meaning and where its value may
//! lie. From that one list come the command-line options and their help (with the defaults
//! read from the set-up's own spec), the checks of every value however it was given (a
//! config file, a study point, an option) with an error that names the key and the allowed
//! range, and the parameter tables of `rheodem setups`. A set-up implements [`SetUpSchema`]
//! and is listed once in [`super::registry`].

use crate::contact::adhesion::LAWS;
use crate::scenario::{ScenarioError, invalid};

/// What a parameter holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// A real number, in the field's unit.
    Number,
    /// A whole number ≥ 0, at most 2⁶³ − 1 (the largest a TOML file holds).
    Count,
    /// A switch, off unless given (a flag on the command line).
    Switch,
    /// One of these names.
    Choice(&'static [&'static str]),
    /// The name (or an alias) of a registered adhesive law.
    AdhesiveLaw,
}

/// Where a number may lie.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Range {
    /// Any finite number.
    Any,
    /// Above a bound, `(lo, ∞)`.
    Above(f64),
    /// At least a bound, `[lo, ∞)`.
    AtLeast(f64),
    /// A closed interval `[lo, hi]`.
    Closed(f64, f64),
    /// A half-open interval `(lo, hi]`.
    AboveUpTo(f64, f64),
}

impl Range {
    /// Whether `v` lies in the range (never for a value that is not finite).
    pub fn contains(self, v: f64) -> bool {
        v.is_finite()
            && match self {
                Range::Any => true,
                Range::Above(lo) => v > lo,
                Range::AtLeast(lo) => v >= lo,
                Range::Closed(lo, hi) => (lo..=hi).contains(&v),
                Range::AboveUpTo(lo, hi) => v > lo && v <= hi,
            }
    }

    /// What an error says: `must lie in [0, 10]`, `must be a positive number`.
    pub fn requirement(self) -> String {
        match self {
            Range::Any => "must be a finite number".into(),
            Range::Above(0.0) => "must be a positive number".into(),
            Range::Above(lo) => format!("must exceed {lo}"),
            Range::AtLeast(0.0) => "must be zero or positive".into(),
            Range::AtLeast(lo) => format!("must be at least {lo}"),
            Range::Closed(lo, hi) => format!("must lie in [{lo}, {hi}]"),
            Range::AboveUpTo(lo, hi) => format!("must lie in ({lo}, {hi}]"),
        }
    }

    /// The range as the help shows it: `in [0, 10]`, `> 0`, `≥ 1`; empty for any number.
    pub fn short(self) -> String {
        match self {
            Range::Any => String::new(),
            Range::Above(lo) => format!("> {lo}"),
            Range::AtLeast(lo) => format!("≥ {lo}"),
            Range::Closed(lo, hi) => format!("in [{lo}, {hi}]"),
            Range::AboveUpTo(lo, hi) => format!("in ({lo}, {hi}]"),
        }
    }
}

/// Where a parameter's value goes in the set-up's spec.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Store {
    /// Under the same key.
    Same,
    /// Under another key (the spec's older name for it).
    As(&'static str),
    /// Read by the set-up itself ([`SetUpSchema::from_values`]), e.g. a law's parameter
    /// that goes into a nested table; the set-up checks it.
    BySetUp,
}

/// One parameter of a set-up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Field {
    /// Its key: in TOML files as written, on the command line in kebab-case
    /// (`transient_strain` → `--transient-strain`), as a keyword of a library call.
    pub key: &'static str,
    /// What it holds.
    pub kind: Kind,
    /// Its unit (`m`, `rad/s`; empty when dimensionless).
    pub unit: &'static str,
    /// What it is, with its symbol, starting with a capital.
    pub meaning: &'static str,
    /// Where a number may lie (numbers and counts).
    pub range: Range,
    /// Whether it must be given (no default).
    pub required: bool,
    /// Said after the range in the help (may be empty).
    pub note: &'static str,
    /// Where its value goes in the spec.
    pub store: Store,
}

impl Field {
    /// A real number with its unit, meaning and range; optional, stored under its key.
    pub const fn number(
        key: &'static str,
        unit: &'static str,
        meaning: &'static str,
        range: Range,
    ) -> Field {
        Field {
            key,
            kind: Kind::Number,
            unit,
            meaning,
            range,
            required: false,
            note: "",
            store: Store::Same,
        }
    }

    /// A whole number with its meaning and range.
    pub const fn count(key: &'static str, meaning: &'static str, range: Range) -> Field {
        Field {
            kind: Kind::Count,
            ..Field::number(key, "", meaning, range)
        }
    }

    /// A switch.
    pub const fn switch(key: &'static str, meaning: &'static str) -> Field {
        Field {
            kind: Kind::Switch,
            ..Field::number(key, "", meaning, Range::Any)
        }
    }

    /// One of `names`.
    pub const fn choice(
        key: &'static str,
        meaning: &'static str,
        names: &'static [&'static str],
    ) -> Field {
        Field {
            kind: Kind::Choice(names),
            ..Field::number(key, "", meaning, Range::Any)
        }
    }

    /// A registered adhesive law's name.
    pub const fn adhesive_law(key: &'static str, meaning: &'static str) -> Field {
        Field {
            kind: Kind::AdhesiveLaw,
            ..Field::number(key, "", meaning, Range::Any)
        }
    }

    /// The same field, required.
    pub const fn required(self) -> Field {
        Field {
            required: true,
            ..self
        }
    }

    /// The same field with a note after its range in the help.
    pub const fn note(self, note: &'static str) -> Field {
        Field { note, ..self }
    }

    /// The same field, stored under `key` in the spec.
    pub const fn stored_as(self, key: &'static str) -> Field {
        Field {
            store: Store::As(key),
            ..self
        }
    }

    /// The same field, read by the set-up itself.
    pub const fn by_set_up(self) -> Field {
        Field {
            store: Store::BySetUp,
            ..self
        }
    }

    /// The key in the spec where its value goes (`None` when the set-up reads it).
    pub fn spec_key(&self) -> Option<&'static str> {
        match self.store {
            Store::Same => Some(self.key),
            Store::As(key) => Some(key),
            Store::BySetUp => None,
        }
    }

    /// The names a choice accepts (for an adhesive law, every registered name).
    pub fn choices(&self) -> Vec<&'static str> {
        match self.kind {
            Kind::Choice(names) => names.to_vec(),
            Kind::AdhesiveLaw => LAWS.iter().map(|l| l.name).collect(),
            _ => Vec::new(),
        }
    }

    /// The field's help: meaning, unit, range or choices, note and default, e.g.
    /// `Particle friction μ_p, in [0, 10] (required).` or
    /// `Mean diameter d_p (m), > 0 [default: 0.0022].`
    pub fn help(&self, default: Option<&toml::Value>) -> String {
        let mut text = self.meaning.to_string();
        if !self.unit.is_empty() {
            text.push_str(&format!(" ({})", self.unit));
        }
        let allowed = match self.kind {
            Kind::Number | Kind::Count => self.range.short(),
            Kind::Choice(_) => format!("one of {}", self.choices().join(", ")),
            // With the aliases in brackets: `none (dry), reversible, …`.
            Kind::AdhesiveLaw => format!("one of {}", crate::contact::LawKind::known()),
            Kind::Switch => String::new(),
        };
        if !allowed.is_empty() {
            text.push_str(", ");
            text.push_str(&allowed);
        }
        text.push_str(self.note);
        if self.required {
            text.push_str(" (required)");
        } else if let Some(v) = default.and_then(shown) {
            text.push_str(&format!(" [default: {v}]"));
        }
        text.push('.');
        text
    }

    /// Checks a value given for the field (its type, range or name), naming the key.
    pub fn check(&self, value: &toml::Value) -> Result<(), ScenarioError> {
        let wrong = |what: &str| invalid(self.key, value, format!("must be {what}"));
        match self.kind {
            Kind::Number => {
                let v = value
                    .as_float()
                    .or_else(|| value.as_integer().map(|i| i as f64))
                    .ok_or_else(|| wrong("a number"))?;
                if !self.range.contains(v) {
                    return Err(invalid(self.key, v, self.range.requirement()));
                }
            }
            Kind::Count => {
                let v = value
                    .as_integer()
                    .filter(|i| *i >= 0)
                    .ok_or_else(|| wrong("a whole number ≥ 0"))?;
                if !self.range.contains(v as f64) {
                    return Err(invalid(self.key, v, self.range.requirement()));
                }
            }
            Kind::Switch => {
                value.as_bool().ok_or_else(|| wrong("true or false"))?;
            }
            Kind::Choice(names) => {
                let name = value.as_str().ok_or_else(|| wrong("a name"))?;
                if !names.contains(&name) {
                    return Err(wrong(&format!("one of {}", names.join(", "))));
                }
            }
            Kind::AdhesiveLaw => {
                let name = value.as_str().ok_or_else(|| wrong("a name"))?;
                crate::contact::LawKind::from_name(name)
                    .map_err(|e| invalid(self.key, value, e.reason))?;
            }
        }
        Ok(())
    }
}

/// A default as the help shows it: numbers as Rust prints them (`100`, `0.0022`), names
/// without quotes; none for a switch that is off.
fn shown(v: &toml::Value) -> Option<String> {
    match v {
        toml::Value::Float(x) => Some(x.to_string()),
        toml::Value::Integer(n) => Some(n.to_string()),
        toml::Value::String(s) => Some(s.clone()),
        toml::Value::Boolean(b) => b.then(|| "on".to_string()),
        _ => None,
    }
}

/// Parameter values given by key (command-line options, keywords), in the order
/// given.
pub type Values = Vec<(&'static str, toml::Value)>;

/// A set-up's parameters and how given values become its spec.
pub trait SetUpSchema: Sized {
    /// The set-up's name: its subcommand, its `setup` in study files.
    const NAME: &'static str;
    /// One line saying what the set-up is.
    const SUMMARY: &'static str;
    /// Its parameters, in the order of its documentation.
    const FIELDS: &'static [Field];

    /// The spec's values when none is given, by spec key (required keys absent).
    fn defaults() -> toml::Table;

    /// The spec from `base` (a config file's table, empty for none) with `values`
    /// (by field key) replacing the base's, checked: every error names the key and the
    /// allowed range.
    fn from_values(base: toml::Table, values: &Values) -> Result<Self, ScenarioError>;
}

/// The field of `fields` with key `key`.
pub fn field(fields: &'static [Field], key: &str) -> Option<&'static Field> {
    fields.iter().find(|f| f.key == key)
}

/// Checks every field stored in the spec `table` (by its spec key) against its kind and
/// range, in the order of `fields`; the error names the spec key. Fields the set-up reads
/// itself are left to it.
pub fn check_table(fields: &[Field], table: &toml::Table) -> Result<(), ScenarioError> {
    for f in fields {
        let Some(key) = f.spec_key() else { continue };
        if let Some(v) = table.get(key) {
            f.check(v).map_err(|e| match e {
                ScenarioError::Invalid { value, allowed, .. } => ScenarioError::Invalid {
                    key: key.to_string(),
                    value,
                    allowed,
                },
                other => other,
            })?;
        }
    }
    Ok(())
}

/// `base` with each value of `values` that the spec stores under a key of its own put
/// there (replacing the base's); values the set-up reads itself are left out. Every value
/// is checked against its field first: fails on a key that is not a field, on a value of
/// the wrong kind and on one out of its range.
pub fn overlay(
    fields: &'static [Field],
    mut base: toml::Table,
    values: &Values,
) -> Result<toml::Table, ScenarioError> {
    for (key, value) in values {
        let f = field(fields, key).ok_or_else(|| {
            let known: Vec<&str> = fields.iter().map(|f| f.key).collect();
            invalid(
                *key,
                value,
                format!("is not a parameter; known: {}", known.join(", ")),
            )
        })?;
        f.check(value)?;
        if let Some(spec_key) = f.spec_key() {
            base.insert(spec_key.to_string(), value.clone());
        }
    }
    Ok(base)
}

/// The value given for `key` in `values`, the last one if given twice.
pub fn given<'a>(values: &'a Values, key: &str) -> Option<&'a toml::Value> {
    values.iter().rev().find(|(k, _)| *k == key).map(|(_, v)| v)
}

/// A spec as a TOML table (a spec that cannot be written as TOML gives an empty table).
pub fn table_of<T: serde::Serialize>(spec: &T) -> toml::Table {
    match toml::Value::try_from(spec) {
        Ok(toml::Value::Table(t)) => t,
        _ => toml::Table::new(),
    }
}

/// The keys whose values differ between the spec of a run on disk (`old`) and the one
/// asked for (`new`), as `key: old → new`, in key order.
pub fn spec_changes<T: serde::Serialize>(old: &T, new: &T) -> Vec<String> {
    let (a, b) = (table_of(old), table_of(new));
    let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
    keys.sort();
    keys.dedup();
    keys.into_iter()
        .filter(|k| a.get(*k) != b.get(*k))
        .map(|k| {
            let show = |t: &toml::Table| t.get(k).map_or("(none)".into(), |v| v.to_string());
            format!("{k}: {} → {}", show(&a), show(&b))
        })
        .collect()
}

/// The parameters of `fields` as a markdown table (key, unit, meaning, allowed, default),
/// with the defaults of `defaults` (by spec key).
pub fn markdown(fields: &[Field], defaults: &toml::Table) -> String {
    let mut out =
        String::from("| key | unit | meaning | allowed | default |\n|---|---|---|---|---|\n");
    for f in fields {
        let allowed = match f.kind {
            Kind::Number | Kind::Count => f.range.short(),
            Kind::Switch => "true, false".into(),
            Kind::Choice(_) => f.choices().join(", "),
            Kind::AdhesiveLaw => crate::contact::LawKind::known(),
        };
        let default = if f.required {
            "required".to_string()
        } else {
            f.spec_key()
                .and_then(|k| defaults.get(k))
                .and_then(shown)
                .unwrap_or_else(|| "–".into())
        };
        let note = f.note.trim_start_matches([',', ';', ' ']);
        let meaning = if note.is_empty() {
            f.meaning.to_string()
        } else {
            format!("{}; {note}", f.meaning)
        };
        out.push_str(&format!(
            "| `{}` | {} | {} | {} | {} |\n",
            f.key,
            if f.unit.is_empty() { "–" } else { f.unit },
            meaning,
            if allowed.is_empty() { "any" } else { &allowed },
            default
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const FIELDS: &[Field] = &[
        Field::number(
            "mu_p",
            "",
            "Particle friction μ_p",
            Range::Closed(0.0, 10.0),
        )
        .required(),
        Field::number("diameter", "m", "Mean diameter d_p", Range::Above(0.0)),
        Field::count("particles", "Number of particles", Range::Closed(16.0, 1e7)),
        Field::choice("kernel", "Kernel", &["lucy", "gaussian"]),
        Field::number("friction", "", "Old name", Range::AtLeast(0.0)).stored_as("mu"),
        Field::number("volume_nl", "nl", "Bridge volume", Range::AtLeast(0.0)).by_set_up(),
    ];

    #[test]
    fn help_says_meaning_unit_range_and_default() {
        assert_eq!(
            FIELDS[0].help(None),
            "Particle friction μ_p, in [0, 10] (required)."
        );
        assert_eq!(
            FIELDS[1].help(Some(&toml::Value::Float(0.0022))),
            "Mean diameter d_p (m), > 0 [default: 0.0022]."
        );
        assert_eq!(
            FIELDS[3].help(Some(&toml::Value::String("lucy".into()))),
            "Kernel, one of lucy, gaussian [default: lucy]."
        );
    }

    #[test]
    fn values_are_checked_with_the_key_and_the_range() {
        let check = |f: &Field, v: toml::Value| f.check(&v).map_err(|e| e.to_string());
        assert!(check(&FIELDS[0], toml::Value::Float(10.0)).is_ok());
        assert!(check(&FIELDS[0], toml::Value::Integer(3)).is_ok());
        assert_eq!(
            check(&FIELDS[0], toml::Value::Float(10.5)).expect_err("refused"),
            "`mu_p` = 10.5: must lie in [0, 10]"
        );
        assert_eq!(
            check(&FIELDS[1], toml::Value::Float(0.0)).expect_err("refused"),
            "`diameter` = 0: must be a positive number"
        );
        assert!(check(&FIELDS[1], toml::Value::Float(f64::NAN)).is_err());
        assert_eq!(
            check(&FIELDS[2], toml::Value::Integer(8)).expect_err("refused"),
            "`particles` = 8: must lie in [16, 10000000]"
        );
        assert!(check(&FIELDS[2], toml::Value::Float(20.0)).is_err());
        assert_eq!(
            check(&FIELDS[3], toml::Value::String("cubic".into())).expect_err("refused"),
            "`kernel` = \"cubic\": must be one of lucy, gaussian"
        );
    }

    #[test]
    fn overlay_puts_values_under_their_spec_keys() {
        let base: toml::Table = toml::from_str("mu = 0.1\ndiameter = 0.001").expect("toml");
        let values: Values = vec![
            ("friction", toml::Value::Float(0.3)),
            ("volume_nl", toml::Value::Float(75.0)),
        ];
        let t = overlay(FIELDS, base, &values).expect("overlay");
        assert_eq!(t.get("mu"), Some(&toml::Value::Float(0.3)));
        assert_eq!(t.get("diameter"), Some(&toml::Value::Float(0.001)));
        assert!(t.get("volume_nl").is_none() && t.get("friction").is_none());
        assert_eq!(given(&values, "volume_nl"), Some(&toml::Value::Float(75.0)));
        let e = overlay(
            FIELDS,
            toml::Table::new(),
            &vec![("omgea", toml::Value::Float(1.0))],
        )
        .expect_err("unknown key");
        assert!(e.to_string().contains("omgea") && e.to_string().contains("mu_p"));
        let e = overlay(
            FIELDS,
            toml::Table::new(),
            &vec![("friction", toml::Value::Float(-1.0))],
        )
        .expect_err("out of range");
        assert_eq!(e.to_string(), "`friction` = -1: must be zero or positive");
        // A value the set-up reads itself is checked all the same.
        let e = overlay(
            FIELDS,
            toml::Table::new(),
            &vec![("volume_nl", toml::Value::Float(-1.0))],
        )
        .expect_err("out of range");
        assert_eq!(e.to_string(), "`volume_nl` = -1: must be zero or positive");
        // Checking a spec names the spec's own key.
        let spec: toml::Table = toml::from_str("mu = -2.0").expect("toml");
        let e = check_table(FIELDS, &spec).expect_err("out of range");
        assert_eq!(e.to_string(), "`mu` = -2: must be zero or positive");
    }
}
