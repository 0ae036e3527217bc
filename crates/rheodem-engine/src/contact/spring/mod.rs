//! Springs with history of a touching pair: sliding friction, rolling resistance and
//! torsion resistance (docs/model.md §2.3), and the registry of their laws.
//!
//! Each law is one file implementing [`SpringModel`]: its name and aliases, whether it acts
//! at all, the force of a spring that lives in the tangent plane (sliding, rolling) or along
//! the normal (torsion) in lanes, and its stored energy. The [`spring_laws!`] line below
//! registers them; it generates the [`Spring`] enum each of a contact law's three springs
//! holds (matched once per lane group in the pair loop, no dynamic dispatch), the names
//! [`SpringKind`] scenario files accept, and the list [`SPRING_LAWS`]. No other file lists
//! the spring laws.
//!
//! Registered laws:
//! - [`Resistance`]: a linear spring and dashpot capped by a Coulomb limit.
//! - [`Mindlin`]: Mindlin's spring `8 G* √(R* δ)` of a Hertzian contact, whose contact
//!   radius at the last step is its per-contact state (sliding friction only).
//!
//! Adding a law: write one file beside `linear.rs` with a parameter struct implementing
//! [`SpringModel`], declare the module below, and add one line to the `spring_laws!`
//! invocation. As for the normal laws, the first law of the line is stored as its bare
//! parameters and every other law tagged with its variant name.

pub mod linear;
pub mod mindlin;

pub use linear::Resistance;
pub use mindlin::Mindlin;

use super::kernel::Touch;
use super::lanes::{Real, V3};
use super::names::{self, ModelInfo};
use glam::DVec3;
use serde::Serialize;
use serde::de::DeserializeOwned;
use std::fmt::Debug;

/// A spring law with its parameters in SI units, as the pair loop uses it.
pub trait SpringModel: Copy + Debug + PartialEq + Serialize + DeserializeOwned {
    /// The name scenario files, options and results use (`snake_case`).
    const NAME: &'static str;
    /// Other spellings accepted for the name (kebab-case is always accepted too).
    const ALIASES: &'static [&'static str];
    /// One line saying what the law is, with its source.
    const SUMMARY: &'static str;
    /// Whether the law keeps a per-contact state when it is the sliding spring
    /// ([`super::ContactHistory::sliding_state`]): one number carried with the contact's
    /// springs through steps, neighbour rebuilds, images and checkpoints, zero at the first
    /// touch and reset when the contact opens. The pair loop reads and writes it only for
    /// such a law.
    const KEEPS_STATE: bool = false;

    /// Whether the spring can ever produce a force (the pair loop skips it otherwise).
    fn is_active(&self) -> bool;

    /// Advances a spring `xi` (m) that lives in the tangent plane of the contact `k` with
    /// unit normal `n`, driven by the relative velocity `v` (m/s, in the tangent plane) over
    /// `dt` (s), in lanes; returns the force (N) and whether the spring slips. `f_rep ≥ 0`
    /// (N) is the repulsive normal force that sets the Coulomb limit; `state` is the
    /// contact's state of [`SpringModel::KEEPS_STATE`] (left alone by a law that keeps
    /// none).
    #[allow(clippy::too_many_arguments)]
    fn in_plane_lanes<R: Real>(
        &self,
        xi: &mut V3<R>,
        n: V3<R>,
        v: V3<R>,
        k: &Touch<R>,
        f_rep: R,
        dt: f64,
        state: &mut R,
    ) -> (V3<R>, R::Mask);

    /// Like [`SpringModel::in_plane_lanes`] for a spring that lives along the normal `n`
    /// (torsion), `v` along `n`; a torsion spring keeps no state.
    fn along_normal_lanes<R: Real>(
        &self,
        xi: &mut V3<R>,
        n: V3<R>,
        v: V3<R>,
        k: &Touch<R>,
        f_rep: R,
        dt: f64,
    ) -> (V3<R>, R::Mask);

    /// Energy (J, ≥ 0) stored in a spring stretched by `xi` (m) in a contact of overlap `δ`
    /// (m) between radii `a_i`, `a_j` (m).
    fn energy(&self, xi: DVec3, overlap: f64, a_i: f64, a_j: f64) -> f64;

    /// The same law with its dashpot scaled by `factor` (used to quench a packing).
    fn damping_scaled(&self, factor: f64) -> Self;
}

/// A sliding spring as the pair loop evaluates it: a law as its own type (every
/// [`SpringModel`]), or the registry's [`Spring`] matched per call.
pub trait Sliding: Copy {
    /// [`SpringModel::KEEPS_STATE`] of the law (of the law it holds, for [`Spring`]).
    fn keeps_state(&self) -> bool;

    /// [`SpringModel::in_plane_lanes`] of the law.
    #[allow(clippy::too_many_arguments)]
    fn slide<R: Real>(
        &self,
        xi: &mut V3<R>,
        n: V3<R>,
        v: V3<R>,
        k: &Touch<R>,
        f_rep: R,
        dt: f64,
        state: &mut R,
    ) -> (V3<R>, R::Mask);
}

impl<S: SpringModel> Sliding for S {
    #[inline(always)]
    fn keeps_state(&self) -> bool {
        S::KEEPS_STATE
    }

    #[inline(always)]
    fn slide<R: Real>(
        &self,
        xi: &mut V3<R>,
        n: V3<R>,
        v: V3<R>,
        k: &Touch<R>,
        f_rep: R,
        dt: f64,
        state: &mut R,
    ) -> (V3<R>, R::Mask) {
        self.in_plane_lanes(xi, n, v, k, f_rep, dt, state)
    }
}

impl Sliding for Spring {
    #[inline(always)]
    fn keeps_state(&self) -> bool {
        Spring::keeps_state(self)
    }

    #[inline(always)]
    fn slide<R: Real>(
        &self,
        xi: &mut V3<R>,
        n: V3<R>,
        v: V3<R>,
        k: &Touch<R>,
        f_rep: R,
        dt: f64,
        state: &mut R,
    ) -> (V3<R>, R::Mask) {
        self.in_plane_lanes(xi, n, v, k, f_rep, dt, state)
    }
}

/// Work to do with a spring law as its own type (see [`Spring::with`]).
pub trait WithSpring {
    /// What the work gives.
    type Output;
    /// Does the work with the law `spring`.
    fn run<S: SpringModel>(self, spring: &S) -> Self::Output;
}

/// The Coulomb limit of a spring's trial force `trial` (N, in lanes): returns the force a
/// slipping contact carries, `μ_d f_rep` along the trial direction, and which lanes slip
/// (`|trial| > μ_s f_rep`).
#[inline(always)]
pub(crate) fn coulomb_cap<R: Real>(
    trial: V3<R>,
    mu_static: f64,
    mu_dynamic: f64,
    f_rep: R,
) -> (V3<R>, R::Mask) {
    let limit = R::splat(mu_static) * f_rep;
    let t2 = trial.dot(trial);
    let slip = t2.gt(limit * limit);
    (trial.scale(R::splat(mu_dynamic) * f_rep / t2.sqrt()), slip)
}

/// Generates, from one line per law, the enum and the list every part of rheodem takes the
/// spring laws from (see the module documentation).
macro_rules! spring_laws {
    (
        $(#[$bare_doc:meta])* $bare:ident => $bare_law:ty
        $(; $(#[$doc:meta])* $variant:ident => $law:ty)* $(;)?
    ) => {
        /// A spring law (sliding, rolling or torsion) with its parameters (SI units).
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum Spring {
            $(#[$bare_doc])* $bare($bare_law),
            $($(#[$doc])* $variant($law),)*
        }

        /// The name of a spring law, as scenario files, options and results give it.
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
        pub enum SpringKind {
            $(#[$bare_doc])* #[default] $bare,
            $($(#[$doc])* $variant,)*
        }

        /// Every registered spring law, the default first.
        pub const SPRING_LAWS: &[ModelInfo<SpringKind>] = &[
            ModelInfo {
                kind: SpringKind::$bare,
                name: <$bare_law as SpringModel>::NAME,
                aliases: <$bare_law as SpringModel>::ALIASES,
                summary: <$bare_law as SpringModel>::SUMMARY,
                parameters: &[],
            },
            $(ModelInfo {
                kind: SpringKind::$variant,
                name: <$law as SpringModel>::NAME,
                aliases: <$law as SpringModel>::ALIASES,
                summary: <$law as SpringModel>::SUMMARY,
                parameters: &[],
            },)*
        ];

        impl Spring {
            /// The law's name.
            pub fn kind(&self) -> SpringKind {
                match self {
                    Spring::$bare(_) => SpringKind::$bare,
                    $(Spring::$variant(_) => SpringKind::$variant,)*
                }
            }

            /// [`SpringModel::is_active`].
            #[inline(always)]
            pub fn is_active(&self) -> bool {
                match self {
                    Spring::$bare(law) => law.is_active(),
                    $(Spring::$variant(law) => law.is_active(),)*
                }
            }

            /// Calls `job` with the law as its own type, so that what it runs is compiled
            /// for that law alone (one `match` here instead of one per contact there).
            #[inline(always)]
            pub fn with<J: WithSpring>(&self, job: J) -> J::Output {
                match self {
                    Spring::$bare(law) => job.run(law),
                    $(Spring::$variant(law) => job.run(law),)*
                }
            }

            /// [`SpringModel::KEEPS_STATE`] of the law.
            #[inline(always)]
            pub fn keeps_state(&self) -> bool {
                match self {
                    Spring::$bare(_) => <$bare_law as SpringModel>::KEEPS_STATE,
                    $(Spring::$variant(_) => <$law as SpringModel>::KEEPS_STATE,)*
                }
            }

            /// [`SpringModel::in_plane_lanes`] of the law.
            #[allow(clippy::too_many_arguments)]
            #[inline(always)]
            pub fn in_plane_lanes<R: Real>(
                &self,
                xi: &mut V3<R>,
                n: V3<R>,
                v: V3<R>,
                k: &Touch<R>,
                f_rep: R,
                dt: f64,
                state: &mut R,
            ) -> (V3<R>, R::Mask) {
                match self {
                    Spring::$bare(law) => law.in_plane_lanes(xi, n, v, k, f_rep, dt, state),
                    $(Spring::$variant(law) => law.in_plane_lanes(xi, n, v, k, f_rep, dt, state),)*
                }
            }

            /// [`SpringModel::along_normal_lanes`] of the law.
            #[inline(always)]
            pub fn along_normal_lanes<R: Real>(
                &self,
                xi: &mut V3<R>,
                n: V3<R>,
                v: V3<R>,
                k: &Touch<R>,
                f_rep: R,
                dt: f64,
            ) -> (V3<R>, R::Mask) {
                match self {
                    Spring::$bare(law) => law.along_normal_lanes(xi, n, v, k, f_rep, dt),
                    $(Spring::$variant(law) => law.along_normal_lanes(xi, n, v, k, f_rep, dt),)*
                }
            }

            /// [`SpringModel::energy`] (J) of the law.
            pub fn energy(&self, xi: DVec3, overlap: f64, a_i: f64, a_j: f64) -> f64 {
                match self {
                    Spring::$bare(law) => law.energy(xi, overlap, a_i, a_j),
                    $(Spring::$variant(law) => law.energy(xi, overlap, a_i, a_j),)*
                }
            }

            /// The same law with its dashpot scaled by `factor`.
            pub fn damping_scaled(&self, factor: f64) -> Spring {
                match self {
                    Spring::$bare(law) => Spring::$bare(law.damping_scaled(factor)),
                    $(Spring::$variant(law) => Spring::$variant(law.damping_scaled(factor)),)*
                }
            }
        }

        names::bare_or_tagged!(Spring, $bare => $bare_law $(, $variant => $law)*);

        impl From<$bare_law> for Spring {
            fn from(law: $bare_law) -> Spring {
                Spring::$bare(law)
            }
        }

        $(
            impl From<$law> for Spring {
                fn from(law: $law) -> Spring {
                    Spring::$variant(law)
                }
            }
        )*
    };
}

spring_laws! {
    /// The linear spring and dashpot with a Coulomb limit (Shi et al. 2020, Eqs. 5–8).
    Linear => Resistance;
    /// Mindlin's tangential spring beside Hertz, rescaled as the contact shrinks.
    Mindlin => Mindlin;
}

impl Spring {
    /// A spring that never acts.
    pub const NONE: Spring = Spring::Linear(Resistance::NONE);

    /// The linear law's parameters, if the spring is linear.
    pub fn linear(&self) -> Option<&Resistance> {
        match self {
            Spring::Linear(r) => Some(r),
            _ => None,
        }
    }
}

impl Default for Spring {
    fn default() -> Spring {
        Spring::NONE
    }
}

names::kind_names!(SpringKind, SPRING_LAWS, "spring law");

#[cfg(test)]
mod tests {
    use super::super::damping::Damping;
    use super::*;

    #[test]
    fn the_linear_spring_is_stored_as_before_the_registry() {
        let law = Resistance {
            stiffness: 2857.142857,
            damping: Damping::NONE,
            mu_static: 0.5,
            mu_dynamic: 0.4,
        };
        let spring = Spring::from(law);
        let packed = rmp_serde::to_vec(&spring).expect("msgpack");
        assert_eq!(packed, rmp_serde::to_vec(&law).expect("msgpack"));
        let back: Spring = rmp_serde::from_slice(&packed).expect("reads back");
        assert_eq!(back, spring);
        assert_eq!(
            serde_json::to_string(&spring).expect("json"),
            serde_json::to_string(&law).expect("json")
        );
    }
}
