//! Stages of a run and when they end.
//!
//! A run is a sequence of stages (fill → settle → shear for the split-bottom cell), each with
//! its own parameters and end condition; the state at the end of a stage is a checkpoint
//! that later runs can start from. An [`EndCondition`] is checked on the measured rows of
//! its stage.

use serde::{Deserialize, Serialize};

/// When a stage ends.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EndCondition {
    /// After this simulated time in the stage (s).
    Time(f64),
    /// After this many steps of the stage.
    Steps(u64),
    /// After this shear strain `γ̇ t` in the stage, at shear rate `rate` (1/s).
    Strain {
        /// Strain to reach.
        strain: f64,
        /// Shear rate (1/s).
        rate: f64,
    },
    /// When the kinetic energy is below `ratio` times the elastic energy, no sooner than
    /// `min_time` (s) into the stage; at `max_time` (s) the stage ends anyway, with the
    /// criterion reported as not met.
    KineticBelow {
        /// `E_kin / E_el` to go below.
        ratio: f64,
        /// Earliest end (s).
        min_time: f64,
        /// Latest end (s).
        max_time: f64,
    },
}

/// The verdict of an end condition.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Verdict {
    /// The stage goes on.
    Continue,
    /// The stage ends with its criterion met.
    Met,
    /// The stage ends at its limit without the criterion met.
    Limit,
}

impl EndCondition {
    /// The verdict after `steps` steps and `time` (s) into the stage, with the energies of
    /// the current state if it was measured (`(kinetic, elastic)`, J).
    pub fn verdict(&self, steps: u64, time: f64, energies: Option<(f64, f64)>) -> Verdict {
        let done = |yes: bool| if yes { Verdict::Met } else { Verdict::Continue };
        match *self {
            EndCondition::Time(t) => done(time >= t),
            EndCondition::Steps(n) => done(steps >= n),
            EndCondition::Strain { strain, rate } => done(rate * time >= strain),
            EndCondition::KineticBelow {
                ratio,
                min_time,
                max_time,
            } => {
                let below = energies.is_some_and(|(k, e)| time >= min_time && k < ratio * e);
                if below {
                    Verdict::Met
                } else if time >= max_time {
                    Verdict::Limit
                } else {
                    Verdict::Continue
                }
            }
        }
    }

    /// An upper bound on the stage's steps at time step `dt` (s), for progress reports.
    pub fn max_steps(&self, dt: f64) -> u64 {
        let steps = |t: f64| (t / dt).ceil().max(1.0) as u64;
        match *self {
            EndCondition::Time(t) => steps(t),
            EndCondition::Steps(n) => n,
            EndCondition::Strain { strain, rate } => steps(strain / rate),
            EndCondition::KineticBelow { max_time, .. } => steps(max_time),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdicts() {
        assert_eq!(
            EndCondition::Time(1.0).verdict(5, 0.5, None),
            Verdict::Continue
        );
        assert_eq!(EndCondition::Time(1.0).verdict(5, 1.0, None), Verdict::Met);
        assert_eq!(EndCondition::Steps(10).verdict(10, 0.0, None), Verdict::Met);
        let strain = EndCondition::Strain {
            strain: 2.0,
            rate: 4.0,
        };
        assert_eq!(strain.verdict(0, 0.49, None), Verdict::Continue);
        assert_eq!(strain.verdict(0, 0.5, None), Verdict::Met);
        assert_eq!(strain.max_steps(0.01), 50);
        let settle = EndCondition::KineticBelow {
            ratio: 1e-4,
            min_time: 0.1,
            max_time: 1.0,
        };
        // Quiet too early, loud in time, quiet in time, loud at the limit, unmeasured.
        assert_eq!(settle.verdict(0, 0.05, Some((0.0, 1.0))), Verdict::Continue);
        assert_eq!(settle.verdict(0, 0.5, Some((1e-3, 1.0))), Verdict::Continue);
        assert_eq!(settle.verdict(0, 0.5, Some((0.5e-4, 1.0))), Verdict::Met);
        assert_eq!(settle.verdict(0, 1.0, Some((1e-3, 1.0))), Verdict::Limit);
        assert_eq!(settle.verdict(0, 0.5, None), Verdict::Continue);
        assert_eq!(settle.max_steps(0.01), 100);
    }
}
