//! Preparation of a dense packing: isotropic affine compression of a periodic box with
//! frictionless contacts, then relaxation with the full contact laws.

use crate::Simulation;
use crate::contact::{Adhesion, Spring};
use crate::neighbor::NeighborError;
use serde::{Deserialize, Serialize};

/// What the compression aims at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// A volume fraction.
    VolumeFraction(f64),
    /// A mean stress `tr σ / 3` (Pa).
    Pressure(f64),
}

/// Errors of the preparation.
#[derive(Debug, thiserror::Error)]
pub enum PrepareError {
    /// The box became too small for the neighbour search.
    #[error(transparent)]
    Neighbor(#[from] NeighborError),
    /// The target could not be reached.
    #[error("{0}")]
    Unreachable(String),
}

/// What the preparation did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PreparationReport {
    /// Steps spent compressing.
    pub compression_steps: u64,
    /// Steps spent relaxing.
    pub relaxation_steps: u64,
    /// Volume fraction reached.
    pub volume_fraction: f64,
    /// Mean stress after relaxation (Pa).
    pub mean_stress: f64,
    /// Coordination number after relaxation.
    pub coordination: f64,
}

/// Volume fraction past which a pressure target is declared unreachable.
const PHI_LIMIT: f64 = 0.74;

/// Compresses the box at `strain_rate` (1/s) until `target` is reached, then relaxes for
/// `relax_steps` steps (at least one); resets the clock to zero afterwards.
pub fn prepare(
    sim: &mut Simulation,
    target: Target,
    strain_rate: f64,
    relax_steps: u64,
) -> Result<PreparationReport, PrepareError> {
    let laws = sim.laws.clone();
    let mut frictionless = laws.clone();
    frictionless.map(|law| {
        law.tangential = Spring::NONE;
        law.rolling = Spring::NONE;
        law.torsion = Spring::NONE;
        law.adhesion = Adhesion::None;
    });
    sim.laws = frictionless;
    let solid = sim.particles.free_volume();
    let step_factor = 1.0 - strain_rate * sim.dt;
    let mut compression_steps = 0u64;
    loop {
        let phi = solid / sim.domain.volume();
        let done = match target {
            Target::VolumeFraction(goal) => phi >= goal,
            Target::Pressure(goal) => {
                if phi > PHI_LIMIT {
                    return Err(PrepareError::Unreachable(format!(
                        "the mean stress stayed below {goal:e} Pa up to volume fraction {PHI_LIMIT}"
                    )));
                }
                compression_steps > 0 && sim.observables().mean_stress() >= goal
            }
        };
        if done {
            break;
        }
        let factor = match target {
            Target::VolumeFraction(goal) => step_factor.max((phi / goal).cbrt()),
            Target::Pressure(_) => step_factor,
        };
        sim.domain.scale_affine(factor, &mut sim.particles.position);
        sim.step(matches!(target, Target::Pressure(_)))?;
        compression_steps += 1;
    }
    sim.laws = laws;
    // At least one step, so that the report's contact sums belong to the final state.
    let relax_steps = relax_steps.max(1);
    for k in 0..relax_steps {
        sim.step(k + 1 == relax_steps)?;
    }
    sim.time = 0.0;
    sim.step = 0;
    let obs = sim.observables();
    Ok(PreparationReport {
        compression_steps,
        relaxation_steps: relax_steps,
        volume_fraction: obs.volume_fraction,
        mean_stress: obs.mean_stress(),
        coordination: obs.coordination,
    })
}
