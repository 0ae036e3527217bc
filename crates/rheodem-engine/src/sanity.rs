//! Detection of states that are no longer a meaningful DEM state: numbers that stopped
//! being finite, particles that cross more than a fraction of a radius per step (contacts
//! are then not resolved in time), and overlaps so deep that the contact geometry has lost
//! its meaning. A run stops on the first such state and names its cause and particles,
//! instead of writing nonsense (a pressure of 10¹⁵ Pa) with exit status 0.
//!
//! Why these limits: in a binary collision at speed `v` the largest overlap is
//! `δ_max ≈ v t_c/π`, so a displacement per step `v Δt` of a fraction `q` of a radius means
//! `δ_max ≈ q (t_c/Δt)/π` radii — with the default `Δt = t_c/50` already 1.6 radii at
//! `q = 0.1`. An overlap beyond the smaller radius puts the smaller sphere's centre inside
//! the larger one; at twice the smaller radius the smaller sphere is swallowed and the
//! contact normal means nothing. Both limits can be raised per scenario (`[run]`
//! `max_displacement`, `max_overlap`) for deliberately extreme studies (a very soft
//! packing at `p* = 0.1` with `w = 3` has deep overlaps at its smallest particles).

use crate::domain::Domain;
use crate::particles::Particles;
use serde::{Deserialize, Serialize};

/// Default [`Limits::displacement`]: a fifth of the smallest radius per step.
pub const DEFAULT_DISPLACEMENT: f64 = 0.2;
/// Default [`Limits::overlap`]: the smaller radius of the pair.
pub const DEFAULT_OVERLAP: f64 = 1.0;

/// Limits of a sane state, as fractions of radii.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Limits {
    /// Largest displacement of a free particle in one step, relative to the mean flow, as a
    /// fraction of the smallest particle radius.
    pub displacement: f64,
    /// Largest overlap of a contact as a fraction of the smaller radius of the pair (of the
    /// particle's radius for a planar wall).
    pub overlap: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            displacement: DEFAULT_DISPLACEMENT,
            overlap: DEFAULT_OVERLAP,
        }
    }
}

/// The deepest contact of a force evaluation: overlap over the smaller radius, and the ids
/// of the two particles (`wall` set for a planar wall, whose index is then `pair[1]`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DeepestContact {
    /// `δ / min(a_i, a_j)` (dimensionless).
    pub ratio: f64,
    /// Overlap `δ` (m).
    pub overlap: f64,
    /// Particle ids (or particle id and wall index).
    pub pair: [u32; 2],
    /// Whether `pair[1]` is a planar wall's index.
    pub wall: bool,
}

impl DeepestContact {
    /// Keeps the deeper of `self` and `other`; ties go to the smaller ids, so the result
    /// does not depend on the order in which partial results are merged.
    #[inline]
    pub fn merge(&mut self, other: &DeepestContact) {
        let key = |c: &DeepestContact| (c.ratio, std::cmp::Reverse((c.pair, c.wall)));
        if key(other) > key(self) {
            *self = *other;
        }
    }
}

/// Why a state is not sane.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Instability {
    /// A position, velocity or spin is not a finite number.
    #[error("particle {id} has a non-finite position, velocity or spin")]
    NonFinite {
        /// Particle id.
        id: u32,
    },
    /// The particles are finite but a measured energy or stress is not (the force of a
    /// pair of coincident spheres, say).
    #[error("a measured energy or stress is not a finite number")]
    NonFiniteMeasurement,
    /// A particle moves too far per step.
    #[error(
        "particle {id} moves {displacement:.3e} m per step (speed {speed:.3e} m/s relative to the \
         mean flow), {ratio:.3} of the smallest radius {radius:.3e} m, beyond the limit \
         `run.max_displacement` = {limit}: contacts cannot be resolved at this speed"
    )]
    TooFast {
        /// Particle id.
        id: u32,
        /// Speed relative to the mean flow (m/s).
        speed: f64,
        /// Displacement per step (m).
        displacement: f64,
        /// Smallest particle radius (m).
        radius: f64,
        /// Displacement over radius.
        ratio: f64,
        /// The limit.
        limit: f64,
    },
    /// A contact overlaps too deeply.
    #[error(
        "{} overlap by {overlap:.3e} m, {ratio:.3} of the smaller radius, beyond the limit \
         `run.max_overlap` = {limit}",
        describe_pair(pair, *wall)
    )]
    TooDeep {
        /// Particle ids (or particle id and wall index).
        pair: [u32; 2],
        /// Whether `pair[1]` is a wall index.
        wall: bool,
        /// Overlap (m).
        overlap: f64,
        /// Overlap over the smaller radius.
        ratio: f64,
        /// The limit.
        limit: f64,
    },
}

fn describe_pair(pair: &[u32; 2], wall: bool) -> String {
    if wall {
        format!("particle {} and wall[{}]", pair[0], pair[1])
    } else {
        format!("particles {} and {}", pair[0], pair[1])
    }
}

/// Checks the particles' numbers and speeds against `limits` for a step of `dt` (s), and
/// the deepest contact of the last measurement if given.
pub fn check(
    particles: &Particles,
    domain: &Domain,
    dt: f64,
    limits: &Limits,
    deepest: Option<&DeepestContact>,
) -> Result<(), Instability> {
    if let Some(i) = (0..particles.len()).find(|&i| {
        !(particles.position[i].is_finite()
            && particles.velocity[i].is_finite()
            && particles.angular_velocity[i].is_finite())
    }) {
        return Err(Instability::NonFinite {
            id: particles.id[i],
        });
    }
    let radius = particles
        .radius
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    let fastest = (0..particles.len())
        .filter(|&i| particles.motion[i].is_free())
        .map(|i| {
            let v = domain.peculiar_velocity(particles.position[i], particles.velocity[i]);
            (v.length(), i)
        })
        .fold((0.0, usize::MAX), |a, b| if b.0 > a.0 { b } else { a });
    let displacement = fastest.0 * dt;
    if displacement > limits.displacement * radius {
        return Err(Instability::TooFast {
            id: particles.id[fastest.1],
            speed: fastest.0,
            displacement,
            radius,
            ratio: displacement / radius,
            limit: limits.displacement,
        });
    }
    if let Some(c) = deepest.filter(|c| c.ratio > limits.overlap) {
        return Err(Instability::TooDeep {
            pair: c.pair,
            wall: c.wall,
            overlap: c.overlap,
            ratio: c.ratio,
            limit: limits.overlap,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particles::{Motion, Sphere};
    use glam::DVec3;

    fn two_spheres(v: f64) -> Particles {
        let mut p = Particles::default();
        for x in [0.0, 3.0] {
            p.push(
                Sphere {
                    position: DVec3::new(x, 0.0, 0.0),
                    velocity: DVec3::new(v, 0.0, 0.0),
                    angular_velocity: DVec3::ZERO,
                    radius: 1.0,
                    species: 0,
                    motion: Motion::Free,
                },
                1.0,
            );
        }
        p
    }

    fn box_() -> Domain {
        Domain::new(DVec3::splat(-10.0), DVec3::splat(10.0), [true; 3])
    }

    #[test]
    fn a_particle_crossing_a_fifth_of_a_radius_per_step_is_too_fast() {
        let limits = Limits::default();
        // 0.19 radii per step passes, 0.21 does not.
        assert!(check(&two_spheres(0.19), &box_(), 1.0, &limits, None).is_ok());
        let err = check(&two_spheres(0.21), &box_(), 1.0, &limits, None).expect_err("too fast");
        assert!(matches!(err, Instability::TooFast { id: 0, .. }), "{err}");
        assert!(err.to_string().contains("run.max_displacement"), "{err}");
    }

    #[test]
    fn speed_is_measured_against_the_mean_flow() {
        // Under Lees-Edwards shear a particle moving with the flow is not fast.
        let domain = box_().with_lees_edwards(1.0);
        let mut p = two_spheres(0.0);
        for i in 0..p.len() {
            p.position[i].y = 5.0;
            p.velocity[i] = domain.mean_flow(p.position[i]);
        }
        assert!(p.velocity[0].x > 10.0);
        assert!(check(&p, &domain, 1.0, &Limits::default(), None).is_ok());
    }

    #[test]
    fn non_finite_numbers_name_the_particle() {
        let mut p = two_spheres(0.0);
        p.angular_velocity[1].z = f64::NAN;
        let err = check(&p, &box_(), 1.0, &Limits::default(), None).expect_err("nan");
        assert_eq!(err, Instability::NonFinite { id: 1 });
    }

    #[test]
    fn deepest_contact_beyond_the_limit_names_the_pair() {
        let deep = DeepestContact {
            ratio: 1.2,
            overlap: 1.2e-3,
            pair: [4, 7],
            wall: false,
        };
        let err = check(
            &two_spheres(0.0),
            &box_(),
            1.0,
            &Limits::default(),
            Some(&deep),
        )
        .expect_err("too deep");
        assert!(err.to_string().contains("particles 4 and 7"), "{err}");
        let loose = Limits {
            overlap: 1.5,
            ..Limits::default()
        };
        assert!(check(&two_spheres(0.0), &box_(), 1.0, &loose, Some(&deep)).is_ok());
    }

    #[test]
    fn merging_deepest_contacts_is_order_independent() {
        let a = DeepestContact {
            ratio: 0.5,
            overlap: 1.0,
            pair: [3, 9],
            wall: false,
        };
        let b = DeepestContact { pair: [1, 2], ..a };
        let c = DeepestContact { ratio: 0.1, ..a };
        let (mut x, mut y) = (a, b);
        x.merge(&b);
        x.merge(&c);
        y.merge(&c);
        y.merge(&a);
        assert_eq!(x, y);
        assert_eq!(x.pair, [1, 2]);
    }
}
