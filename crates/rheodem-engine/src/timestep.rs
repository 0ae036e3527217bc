//! Time-step selection from the binary collision time (docs/model.md §3.4).

use crate::contact::ContactTable;
use crate::particles::Particles;
use crate::walls::Wall;

/// Default fraction of the shortest contact time used as time step: `dt = t_c / 50`.
pub const DEFAULT_FRACTION: f64 = 1.0 / 50.0;
/// Largest accepted fraction: a user time step above `t_c / 10` is refused.
pub const MAX_FRACTION: f64 = 1.0 / 10.0;

/// Errors of the time-step selection.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum TimeStepError {
    /// A contact between the named species is overdamped and has no contact time.
    #[error(
        "the contact between species {a} and {b} is overdamped (γ_n ≥ 2 sqrt(k_n m_ij) for the lightest pair): lower its damping or raise its stiffness"
    )]
    Overdamped {
        /// First species index.
        a: u16,
        /// Second species index.
        b: u16,
    },
    /// There is no free particle, so no collision sets a time scale.
    #[error("there are no free particles: nothing sets a collision time")]
    NoFreeParticles,
}

/// The shortest binary contact time `t_c` (s) over every species pair that can meet,
/// evaluated for the lightest particles of each species with the smallest radius of the
/// species (prescribed particles and planar walls count as infinitely heavy, and a
/// sphere meeting one counts with its own radius).
pub fn shortest_contact_time(
    particles: &Particles,
    laws: &ContactTable,
    walls: &[Wall],
) -> Result<f64, TimeStepError> {
    let ns = laws.species();
    let mut lightest_free = vec![f64::INFINITY; ns];
    let mut smallest_free = vec![f64::INFINITY; ns];
    let mut has_prescribed = vec![false; ns];
    for i in 0..particles.len() {
        let s = particles.species[i] as usize;
        if particles.motion[i].is_free() {
            lightest_free[s] = lightest_free[s].min(particles.mass[i]);
            smallest_free[s] = smallest_free[s].min(particles.radius[i]);
        } else {
            has_prescribed[s] = true;
        }
    }
    for w in walls {
        has_prescribed[w.species as usize] = true;
    }
    let mut t_min = f64::INFINITY;
    for a in 0..ns {
        if !lightest_free[a].is_finite() {
            continue;
        }
        for b in 0..ns {
            let mut pairs = Vec::with_capacity(2);
            if b >= a && lightest_free[b].is_finite() {
                let (r_a, r_b) = (smallest_free[a], smallest_free[b]);
                pairs.push((
                    1.0 / (1.0 / lightest_free[a] + 1.0 / lightest_free[b]),
                    r_a * r_b / (r_a + r_b),
                ));
            }
            if has_prescribed[b] {
                pairs.push((lightest_free[a], smallest_free[a]));
            }
            for (m, r) in pairs {
                let overdamped = TimeStepError::Overdamped {
                    a: a as u16,
                    b: b as u16,
                };
                let law = &laws.get(a as u16, b as u16).normal;
                t_min = t_min.min(law.contact_time(m, r).ok_or(overdamped)?);
            }
        }
    }
    if t_min.is_finite() {
        Ok(t_min)
    } else {
        Err(TimeStepError::NoFreeParticles)
    }
}
