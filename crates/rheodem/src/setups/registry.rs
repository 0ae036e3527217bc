//! The registered set-ups: one line each. Everything that takes "any set-up" (the list of
//! `rheodem setups`, its parameter tables, the checks of `accepts`, the command line's
//! subcommand per set-up through `run`) reads this list; a set-up's parameters are
//! declared once, by its [`SetUpSchema`], and it runs as an [`Experiment`].

use super::chute::ChuteSpec;
use super::runner::{Event, Experiment, Finished, RunOptions};
use super::schema::{Field, SetUpSchema, Values, markdown};
use super::shear_box::ShearBoxSpec;
use super::split_bottom::SplitBottomSpec;
use super::studied::{PointTables, Studied, StudyFns};
use super::study::StudySpec;
use crate::run::RunError;
use crate::scenario::{ScenarioError, invalid};

/// What the registry holds about a set-up.
#[derive(Clone, Copy, Debug)]
pub struct SetUpInfo {
    /// [`SetUpSchema::NAME`].
    pub name: &'static str,
    /// [`SetUpSchema::SUMMARY`].
    pub summary: &'static str,
    /// [`SetUpSchema::FIELDS`].
    pub fields: &'static [Field],
    /// [`SetUpSchema::defaults`].
    pub defaults: fn() -> toml::Table,
    /// Whether [`SetUpSchema::from_values`] makes a valid spec of a base table and values
    /// (the error names the key).
    pub accepts: fn(toml::Table, &Values) -> Result<(), ScenarioError>,
    /// [`Experiment::FROM`].
    pub from: Option<&'static str>,
    /// [`Experiment::ESTIMATES_MEMORY`].
    pub estimates_memory: bool,
    /// Makes the spec of a base table and values ([`SetUpSchema::from_values`]) and runs
    /// it ([`Experiment::run`]), in the caller's thread pool.
    pub run: RunFn,
    /// What studies of it need ([`Studied`]), each point as its spec's table.
    pub study: StudyFns,
}

/// How [`SetUpInfo::run`] is called: the base table (a config file's, or empty), the
/// values given by key, the run options and the receiver of the run's events.
pub type RunFn = fn(
    toml::Table,
    &Values,
    &RunOptions<'_>,
    &mut dyn FnMut(Event<'_>),
) -> Result<Finished, RunError>;

fn accepts<S: SetUpSchema>(base: toml::Table, values: &Values) -> Result<(), ScenarioError> {
    S::from_values(base, values).map(|_| ())
}

fn run<S: Experiment>(
    base: toml::Table,
    values: &Values,
    options: &RunOptions<'_>,
    events: &mut dyn FnMut(Event<'_>),
) -> Result<Finished, RunError> {
    S::from_values(base, values)?.run(options, events)
}

const fn info<S: Studied>() -> SetUpInfo {
    SetUpInfo {
        name: S::NAME,
        summary: S::SUMMARY,
        fields: S::FIELDS,
        defaults: S::defaults,
        accepts: accepts::<S>,
        from: S::FROM,
        estimates_memory: S::ESTIMATES_MEMORY,
        run: run::<S>,
        study: StudyFns::of::<S>(),
    }
}

/// Every registered set-up.
pub const SETUPS: &[SetUpInfo] = &[
    info::<ShearBoxSpec>(),
    info::<SplitBottomSpec>(),
    info::<ChuteSpec>(),
];

/// The set-up named `name`; an error lists the known names.
pub fn find(name: &str) -> Result<&'static SetUpInfo, String> {
    SETUPS.iter().find(|s| s.name == name).ok_or_else(|| {
        let known: Vec<&str> = SETUPS.iter().map(|s| s.name).collect();
        format!("`{name}` is not a set-up; known: {}", known.join(", "))
    })
}

/// The set-up of `study` and the named points of its variant (`quick` or the full one),
/// each its spec's table; an unknown set-up or a bad point is an error naming it.
///
/// # Errors
/// [`ScenarioError`] for a `setup` that is not registered, a missing variant, or a point
/// out of range.
pub fn study_points(
    study: &StudySpec,
    quick: bool,
) -> Result<(&'static SetUpInfo, PointTables), ScenarioError> {
    let info = find(&study.setup).map_err(|e| invalid("setup", &study.setup, e))?;
    let variant = study.variant(quick)?;
    Ok((info, (info.study.points)(&variant)?))
}

impl SetUpInfo {
    /// The set-up's parameters as a markdown section: a heading, its summary and the table
    /// of its parameters with their units, ranges and defaults.
    pub fn markdown(&self) -> String {
        format!(
            "### `{}`\n\n{}\n\n{}",
            self.name,
            self.summary,
            markdown(self.fields, &(self.defaults)())
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::setups::schema::Kind;

    /// Every field of every set-up: a unique key that the spec stores (or the set-up
    /// reads), a default the field's own check accepts, and choices the spec reads.
    #[test]
    fn every_field_is_stored_checked_and_defaulted() {
        for s in SETUPS {
            let defaults = (s.defaults)();
            let mut keys: Vec<&str> = s.fields.iter().map(|f| f.key).collect();
            keys.sort();
            keys.dedup();
            assert_eq!(keys.len(), s.fields.len(), "{}: a key twice", s.name);
            for f in s.fields {
                let Some(key) = f.spec_key() else { continue };
                match defaults.get(key) {
                    Some(v) => f
                        .check(v)
                        .unwrap_or_else(|e| panic!("{}: default {e}", s.name)),
                    None => assert!(f.required, "{}: `{key}` has no default", s.name),
                }
            }
            // Every spec key is a field (nothing the spec holds lacks its declaration).
            for key in defaults.keys() {
                assert!(
                    s.fields.iter().any(|f| f.spec_key() == Some(key.as_str()))
                        || key == "cohesion",
                    "{}: spec key `{key}` is no field",
                    s.name
                );
            }
            // The required values, each the smallest round number its range takes.
            let required: Values = s
                .fields
                .iter()
                .filter(|f| f.required)
                .map(|f| (f.key, toml::Value::Float(0.01)))
                .collect();
            (s.accepts)(toml::Table::new(), &required)
                .unwrap_or_else(|e| panic!("{}: the defaults are refused: {e}", s.name));
            for f in s.fields {
                for name in f.choices() {
                    let mut values = required.clone();
                    values.push((f.key, toml::Value::String(name.to_string())));
                    if let Err(e) = (s.accepts)(toml::Table::new(), &values) {
                        // Only the linear laws of the set-ups that take the adhesive law's
                        // parameters as given (no default strength there) are refused, and
                        // by what they need.
                        let e = e.to_string();
                        assert!(
                            f.kind == Kind::AdhesiveLaw
                                && ["split-bottom", "chute"].contains(&s.name)
                                && ["reversible", "linear_irreversible"].contains(&name)
                                && e.contains("needs max_force and adhesive_stiffness"),
                            "{}: `{}` = {name}: {e}",
                            s.name,
                            f.key
                        );
                    }
                }
            }
        }
        assert!(
            find("hopper")
                .expect_err("no such set-up")
                .contains("shear-box, split-bottom, chute")
        );
    }

    /// A study file's `setup` takes the name of every registered set-up and gives its
    /// points; another name is refused with the known ones.
    #[test]
    fn studies_take_every_registered_set_up() {
        for s in SETUPS {
            // One point: the required values, each the smallest round number its range
            // takes.
            let mut text = format!(
                "title = \"t\"\nsetup = \"{}\"\nout = \"o\"\n[[point]]\n",
                s.name
            );
            for f in s.fields.iter().filter(|f| f.required) {
                text.push_str(&format!("{} = 0.01\n", f.spec_key().unwrap_or(f.key)));
            }
            let study = StudySpec::from_toml(&text).expect("a study file");
            let (info, points) = study_points(&study, false).expect("its points");
            assert_eq!(info.name, s.name);
            assert_eq!(points.len(), 1);
            // The point's table reads back as a spec of the set-up, which accepts it.
            (info.accepts)(points[0].1.clone(), &Values::new())
                .unwrap_or_else(|e| panic!("{}: its point is refused: {e}", s.name));
        }
        let study =
            StudySpec::from_toml("title = \"t\"\nsetup = \"hopper\"\nout = \"o\"").expect("parsed");
        let e = study_points(&study, false).expect_err("no hopper");
        assert!(
            e.to_string().contains("`setup` = hopper") && e.to_string().contains("chute"),
            "{e}"
        );
    }
}
