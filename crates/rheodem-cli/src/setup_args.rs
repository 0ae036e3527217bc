//! A set-up's command-line options, derived from its parameters ([`SetUpInfo::fields`]):
//! one `--kebab-case` option per field, its help from the field's meaning, unit and range
//! with the default read from the set-up's spec. The values given become [`Values`] for
//! the set-up's `from_values`, which checks them with every other source.

use clap::{Arg, ArgAction, ArgMatches};
use rheodem::setups::registry::SetUpInfo;
use rheodem::setups::schema::{Kind, Values};

/// One option per parameter of the set-up `info`.
pub fn arguments(info: &SetUpInfo) -> Vec<Arg> {
    let defaults = (info.defaults)();
    info.fields
        .iter()
        .map(|f| {
            let default = f.spec_key().and_then(|k| defaults.get(k));
            let arg = Arg::new(f.key)
                .long(f.key.replace('_', "-"))
                .value_name(f.key.to_uppercase())
                .help(f.help(default));
            match f.kind {
                Kind::Number => arg.value_parser(clap::value_parser!(f64)),
                // A TOML file holds integers up to 2⁶³ − 1.
                Kind::Count => arg.value_parser(clap::value_parser!(u64).range(..=i64::MAX as u64)),
                Kind::Switch => arg.action(ArgAction::SetTrue),
                // Names are checked with the other sources, by the set-up.
                Kind::Choice(_) | Kind::AdhesiveLaw => arg.value_name("NAME"),
            }
        })
        .collect()
}

/// The parameter values given on the command line, by field key, in the order of the
/// fields.
pub fn values(info: &SetUpInfo, m: &ArgMatches) -> Values {
    let mut values = Values::new();
    for f in info.fields {
        let value = match f.kind {
            Kind::Number => m.get_one::<f64>(f.key).map(|x| toml::Value::Float(*x)),
            Kind::Count => m
                .get_one::<u64>(f.key)
                .and_then(|n| i64::try_from(*n).ok())
                .map(toml::Value::Integer),
            Kind::Switch => m.get_flag(f.key).then_some(toml::Value::Boolean(true)),
            Kind::Choice(_) | Kind::AdhesiveLaw => m
                .get_one::<String>(f.key)
                .map(|s| toml::Value::String(s.clone())),
        };
        if let Some(v) = value {
            values.push((f.key, v));
        }
    }
    values
}
