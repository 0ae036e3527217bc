//! A set-up's command-line options, derived from its parameters ([`SetUpSchema::FIELDS`]):
//! one `--kebab-case` option per field, its help from the field's meaning, unit and range
//! with the default read from the set-up's spec. The values given become [`Values`] for
//! [`SetUpSchema::from_values`], which checks them with every other source.

use anyhow::{Context, Result};
use clap::{Arg, ArgAction, ArgMatches, Command, FromArgMatches};
use rheodem::setups::schema::{Kind, SetUpSchema, Values};
use std::marker::PhantomData;
use std::path::Path;

/// The parameter values given on the command line for the set-up `S`.
pub struct Parameters<S> {
    /// The values, by field key, in the order of the fields.
    pub values: Values,
    set_up: PhantomData<fn() -> S>,
}

impl<S: SetUpSchema> Parameters<S> {
    /// The spec from a config file (none: the defaults) with these values over it.
    pub fn spec(&self, config: Option<&Path>) -> Result<S> {
        let base = match config {
            Some(path) => {
                let text = std::fs::read_to_string(path)
                    .with_context(|| format!("cannot read {}", path.display()))?;
                toml::from_str(&text)
                    .with_context(|| format!("{} is not valid TOML", path.display()))?
            }
            None => toml::Table::new(),
        };
        S::from_values(base, &self.values).with_context(|| match config {
            Some(path) => format!("{} from {} and the options", S::NAME, path.display()),
            None => format!("{} options", S::NAME),
        })
    }
}

impl<S: SetUpSchema> FromArgMatches for Parameters<S> {
    fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
        let mut values = Values::new();
        for f in S::FIELDS {
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
        Ok(Parameters {
            values,
            set_up: PhantomData,
        })
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

impl<S: SetUpSchema> clap::Args for Parameters<S> {
    fn augment_args(cmd: Command) -> Command {
        let defaults = S::defaults();
        S::FIELDS.iter().fold(cmd, |cmd, f| {
            let default = f.spec_key().and_then(|k| defaults.get(k));
            let arg = Arg::new(f.key)
                .long(f.key.replace('_', "-"))
                .value_name(f.key.to_uppercase())
                .help(f.help(default));
            cmd.arg(match f.kind {
                Kind::Number => arg.value_parser(clap::value_parser!(f64)),
                // A TOML file holds integers up to 2⁶³ − 1.
                Kind::Count => arg.value_parser(clap::value_parser!(u64).range(..=i64::MAX as u64)),
                Kind::Switch => arg.action(ArgAction::SetTrue),
                // Names are checked with the other sources, by the set-up.
                Kind::Choice(_) | Kind::AdhesiveLaw => arg.value_name("NAME"),
            })
        })
    }

    fn augment_args_for_update(cmd: Command) -> Command {
        Self::augment_args(cmd)
    }
}
