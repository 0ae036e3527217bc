//! Normal contact laws: the repulsive force of two touching spheres along their normal
//! (docs/model.md §2.2), and the registry of these laws.
//!
//! Each law is one file implementing [`NormalModel`] (its name, aliases, the quantities
//! time steps and stiffness ratios are taken from, its resolved form) and [`NormalForce`]
//! (the force in lanes and the elastic energy). The [`normal_laws!`] line below registers
//! them; it generates the [`Normal`] enum the contact law stores, the [`ResolvedNormal`]
//! enum the pair loop matches on (one predictable branch per lane group, no dynamic
//! dispatch), the names [`NormalKind`] every scenario file and option accepts, and the list
//! [`NORMAL_LAWS`]. No other file lists the normal laws.
//!
//! Registered laws:
//! - [`LinearNormal`]: the linear spring and dashpot `k_n δ + γ_n dδ/dt`.
//! - [`LudingNormal`]: Luding's elasto-plastic adhesive spring, whose largest overlap
//!   reached is its per-contact state.
//! - [`HertzNormal`]: Hertz's elastic force with Tsuji's dashpot, from the materials'
//!   Young's moduli and Poisson's ratios.
//!
//! Adding a law: write one file beside `linear.rs` with a parameter struct implementing
//! [`NormalModel`] and a resolved form implementing [`NormalForce`], declare the module
//! below, and add one line to the `normal_laws!` invocation. The first law of the line is
//! stored as its bare parameters (the form contact laws had before the registry, so older
//! checkpoints load); every other law is stored tagged with its variant name.

pub mod hertz;
pub mod linear;
pub mod luding;

pub use hertz::{HertzNormal, Material};
pub use linear::LinearNormal;
pub use luding::LudingNormal;

use super::kernel::Touch;
use super::lanes::Real;
use super::names::{self, ModelInfo};
use super::parameters::{LawError, Parameter, Parameters, Registered, Spec};
use serde::Serialize;
use serde::de::DeserializeOwned;
use std::fmt::Debug;

/// A normal law as scenario files and set-ups give it: its parameters in SI units.
pub trait NormalModel: Copy + Debug + PartialEq + Serialize + DeserializeOwned {
    /// The name scenario files, options and results use (`snake_case`).
    const NAME: &'static str;
    /// Other spellings accepted for the name (kebab-case is always accepted too).
    const ALIASES: &'static [&'static str];
    /// One line saying what the law is, with its source.
    const SUMMARY: &'static str;
    /// The parameters a scenario file gives, in the order of the law's documentation.
    const PARAMETERS: &'static [Parameter];
    /// The law with its per-run constants computed, as the pair loop uses it.
    type Resolved: NormalForce;

    /// The law from named parameter values (checked against [`Self::PARAMETERS`]).
    fn from_parameters(p: &Parameters<'_>) -> Result<Self, LawError>;

    /// The linear law the springs' ratios refer to (a scenario's `stiffness_ratio` is a
    /// fraction of its `k_n`, `damping_ratio` of its dashpot): the law itself when linear;
    /// `None` for a law without a linear stiffness (springs then give their own).
    fn reference(&self) -> Option<LinearNormal>;

    /// The law with its constants resolved.
    fn resolve(&self) -> Self::Resolved;

    /// The largest stiffness (N/m) a contact of reduced radius `r_ij = a_i a_j/(a_i + a_j)`
    /// (m) follows, which overlap bounds are set from: `k_n` of a linear law; a law whose
    /// stiffness grows without bound with the overlap says at which overlap it quotes it.
    fn max_stiffness(&self, r_ij: f64) -> f64;

    /// Duration (s) of a binary collision of reduced mass `m_ij` (kg) and reduced radius
    /// `r_ij` (m) under this law, or `None` when the contact is overdamped (a law whose
    /// collisions depend on the impact speed says at which speed it quotes it).
    fn contact_time(&self, m_ij: f64, r_ij: f64) -> Option<f64>;

    /// Restitution coefficient of a binary collision of reduced mass `m_ij` (kg), or `None`
    /// when overdamped.
    fn restitution(&self, m_ij: f64) -> Option<f64>;

    /// The same law with its dashpot scaled by `factor` (used to quench a packing).
    fn damping_scaled(&self, factor: f64) -> Self;
}

/// A normal law with its per-run constants computed: what the pair loop evaluates on
/// touching pairs. `WALL` marks a sphere on a planar wall (`radius_j` unused).
pub trait NormalForce: Copy + Debug + PartialEq {
    /// Whether the law keeps a per-contact state ([`super::ContactHistory::state`]): one
    /// number carried with the contact's springs through steps, neighbour rebuilds, images
    /// and checkpoints, and reset to zero when the contact opens. The pair loop reads and
    /// writes it only for such a law.
    const KEEPS_STATE: bool = false;

    /// [`NormalForce::KEEPS_STATE`] of this law (of the law it holds, for
    /// [`ResolvedNormal`]).
    #[inline(always)]
    fn keeps_state(&self) -> bool {
        Self::KEEPS_STATE
    }

    /// Normal force (N) of touching pairs in lanes, at the overlaps of `k` closing at
    /// `overlap_rate` (m/s), advancing the contact's `state` (zero at the first touch; left
    /// alone by a law that keeps none), split into the part the Coulomb limits of the
    /// springs are measured from and an adhesive part of the law's own. Not clipped at
    /// zero.
    fn force_lanes<R: Real, const WALL: bool>(
        &self,
        k: &Touch<R>,
        overlap_rate: R,
        state: &mut R,
    ) -> NormalParts<R>;

    /// Elastic energy (J, ≥ 0) stored at overlap `δ > 0` (m) by a pair of radii `a_i`, `a_j`
    /// (m; `a_j = ∞` for a planar wall) whose contact has `state`.
    fn energy(&self, overlap: f64, a_i: f64, a_j: f64, state: f64) -> f64;
}

/// What a normal law gives for touching pairs (N, in lanes): `repulsive`, whose absolute
/// value sets the Coulomb limits of the springs (as the repulsive force of an adhesive
/// contact does, rheodem's convention of §2.3), and an adhesive part of the law's own
/// (`None` for a law without one), added to the normal force and to the pair's adhesive
/// force.
#[derive(Clone, Copy, Debug)]
pub struct NormalParts<R> {
    /// The force the Coulomb limits are measured from.
    pub repulsive: R,
    /// The law's own adhesive force (≤ 0), if it has one.
    pub adhesive: Option<R>,
}

/// Work to do with a normal law as its own type (see [`ResolvedNormal::with`]).
pub trait WithNormal {
    /// What the work gives.
    type Output;
    /// Does the work with the law `normal`.
    fn run<N: NormalForce>(self, normal: &N) -> Self::Output;
}

/// Generates, from one line per law, the enums and the list every part of rheodem takes
/// the normal laws from (see the module documentation).
macro_rules! normal_laws {
    (
        $(#[$bare_doc:meta])* $bare:ident => $bare_law:ty
        $(; $(#[$doc:meta])* $variant:ident => $law:ty)* $(;)?
    ) => {
        /// A normal law: one registered law with its parameters (SI units).
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum Normal {
            $(#[$bare_doc])* $bare($bare_law),
            $($(#[$doc])* $variant($law),)*
        }

        /// A [`Normal`] law with its per-run constants computed (see [`Normal::resolve`]).
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum ResolvedNormal {
            $(#[$bare_doc])* $bare(<$bare_law as NormalModel>::Resolved),
            $($(#[$doc])* $variant(<$law as NormalModel>::Resolved),)*
        }

        /// The name of a normal law, as scenario files, options and results give it.
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
        pub enum NormalKind {
            $(#[$bare_doc])* #[default] $bare,
            $($(#[$doc])* $variant,)*
        }

        /// Every registered normal law, the default first.
        pub const NORMAL_LAWS: &[ModelInfo<NormalKind>] = &[
            ModelInfo {
                kind: NormalKind::$bare,
                name: <$bare_law as NormalModel>::NAME,
                aliases: <$bare_law as NormalModel>::ALIASES,
                summary: <$bare_law as NormalModel>::SUMMARY,
                parameters: <$bare_law as NormalModel>::PARAMETERS,
            },
            $(ModelInfo {
                kind: NormalKind::$variant,
                name: <$law as NormalModel>::NAME,
                aliases: <$law as NormalModel>::ALIASES,
                summary: <$law as NormalModel>::SUMMARY,
                parameters: <$law as NormalModel>::PARAMETERS,
            },)*
        ];

        impl NormalKind {
            /// The law built from named parameter values.
            pub fn build(self, p: &Parameters<'_>) -> Result<Normal, LawError> {
                Ok(match self {
                    NormalKind::$bare => Normal::$bare(<$bare_law>::from_parameters(p)?),
                    $(NormalKind::$variant => Normal::$variant(<$law>::from_parameters(p)?),)*
                })
            }
        }

        impl Normal {
            /// The law's name.
            pub fn kind(&self) -> NormalKind {
                match self {
                    Normal::$bare(_) => NormalKind::$bare,
                    $(Normal::$variant(_) => NormalKind::$variant,)*
                }
            }

            /// The law with its per-run constants computed, as the pair loop uses it.
            pub fn resolve(&self) -> ResolvedNormal {
                match self {
                    Normal::$bare(law) => ResolvedNormal::$bare(law.resolve()),
                    $(Normal::$variant(law) => ResolvedNormal::$variant(law.resolve()),)*
                }
            }

            /// [`NormalModel::reference`].
            pub fn reference(&self) -> Option<LinearNormal> {
                match self {
                    Normal::$bare(law) => law.reference(),
                    $(Normal::$variant(law) => law.reference(),)*
                }
            }

            /// [`NormalModel::max_stiffness`] (N/m) at reduced radius `r_ij` (m).
            pub fn max_stiffness(&self, r_ij: f64) -> f64 {
                match self {
                    Normal::$bare(law) => law.max_stiffness(r_ij),
                    $(Normal::$variant(law) => law.max_stiffness(r_ij),)*
                }
            }

            /// [`NormalModel::contact_time`] (s) for reduced mass `m_ij` (kg) and reduced
            /// radius `r_ij` (m).
            pub fn contact_time(&self, m_ij: f64, r_ij: f64) -> Option<f64> {
                match self {
                    Normal::$bare(law) => NormalModel::contact_time(law, m_ij, r_ij),
                    $(Normal::$variant(law) => NormalModel::contact_time(law, m_ij, r_ij),)*
                }
            }

            /// [`NormalModel::restitution`] for reduced mass `m_ij` (kg).
            pub fn restitution(&self, m_ij: f64) -> Option<f64> {
                match self {
                    Normal::$bare(law) => NormalModel::restitution(law, m_ij),
                    $(Normal::$variant(law) => NormalModel::restitution(law, m_ij),)*
                }
            }

            /// The same law with its dashpot scaled by `factor`.
            pub fn damping_scaled(&self, factor: f64) -> Normal {
                match self {
                    Normal::$bare(law) => Normal::$bare(law.damping_scaled(factor)),
                    $(Normal::$variant(law) => Normal::$variant(law.damping_scaled(factor)),)*
                }
            }
        }

        impl ResolvedNormal {
            /// Calls `job` with the law as its own type, so that what it runs is compiled
            /// for that law alone (one `match` here instead of one per contact there).
            #[inline(always)]
            pub fn with<J: WithNormal>(&self, job: J) -> J::Output {
                match self {
                    ResolvedNormal::$bare(law) => job.run(law),
                    $(ResolvedNormal::$variant(law) => job.run(law),)*
                }
            }
        }

        /// The law held, matched per call: for one contact at a time ([`PairKernel`]'s
        /// scalar path); the pair loop calls [`ResolvedNormal::with`] instead.
        ///
        /// [`PairKernel`]: super::PairKernel
        impl NormalForce for ResolvedNormal {
            #[inline(always)]
            fn keeps_state(&self) -> bool {
                match self {
                    ResolvedNormal::$bare(law) => law.keeps_state(),
                    $(ResolvedNormal::$variant(law) => law.keeps_state(),)*
                }
            }

            #[inline(always)]
            fn force_lanes<R: Real, const WALL: bool>(
                &self,
                k: &Touch<R>,
                overlap_rate: R,
                state: &mut R,
            ) -> NormalParts<R> {
                match self {
                    ResolvedNormal::$bare(law) => {
                        law.force_lanes::<R, WALL>(k, overlap_rate, state)
                    }
                    $(ResolvedNormal::$variant(law) => {
                        law.force_lanes::<R, WALL>(k, overlap_rate, state)
                    })*
                }
            }

            fn energy(&self, overlap: f64, a_i: f64, a_j: f64, state: f64) -> f64 {
                match self {
                    ResolvedNormal::$bare(law) => law.energy(overlap, a_i, a_j, state),
                    $(ResolvedNormal::$variant(law) => law.energy(overlap, a_i, a_j, state),)*
                }
            }
        }

        names::bare_or_tagged!(Normal, $bare => $bare_law $(, $variant => $law)*);

        $(
            impl From<$law> for Normal {
                fn from(law: $law) -> Normal {
                    Normal::$variant(law)
                }
            }
        )*

        impl From<$bare_law> for Normal {
            fn from(law: $bare_law) -> Normal {
                Normal::$bare(law)
            }
        }
    };
}

normal_laws! {
    /// The linear spring and dashpot (Shi et al. 2020, Eq. 1).
    Linear => LinearNormal;
    /// Luding's elasto-plastic adhesive spring (Luding 2008, Eqs. 6–8).
    Luding => LudingNormal;
    /// Hertz's elastic force with Tsuji's dashpot (Hertz 1882; Tsuji et al. 1992).
    Hertz => HertzNormal;
}

impl Normal {
    /// The linear law's parameters, if the law is linear.
    pub fn linear(&self) -> Option<&LinearNormal> {
        match self {
            Normal::Linear(l) => Some(l),
            _ => None,
        }
    }

    /// Hertz's law's parameters, if the law is Hertz's.
    pub fn hertz(&self) -> Option<&HertzNormal> {
        match self {
            Normal::Hertz(h) => Some(h),
            _ => None,
        }
    }
}

names::kind_names!(NormalKind, NORMAL_LAWS, "normal law");

/// A normal law by name with its parameters, as a scenario file writes it:
/// `{ law = "linear", stiffness = 100.0, restitution = 0.8 }` (`law` defaults to `linear`).
pub type NormalSpec = Spec<NormalKind>;

impl Spec<NormalKind> {
    /// The law with its parameters checked.
    pub fn build(&self) -> Result<Normal, LawError> {
        self.law.build(&self.parameters())
    }
}

impl Registered for NormalKind {
    const WHAT: &'static str = "normal law";
    const DEFAULT: Option<NormalKind> = Some(NormalKind::Linear);

    fn from_name(name: &str) -> Result<NormalKind, String> {
        NormalKind::from_name(name)
    }

    fn name(self) -> &'static str {
        NormalKind::name(self)
    }

    fn parameters(self) -> &'static [Parameter] {
        self.info().parameters
    }
}

#[cfg(test)]
mod tests {
    use super::super::damping::Damping;
    use super::*;

    #[test]
    fn the_linear_law_is_stored_as_before_the_registry() {
        // Version 0.2.0 stored the normal law as the linear law's bare parameters: the
        // checkpoint (MessagePack) and JSON forms are unchanged, and read back.
        let law = LinearNormal {
            stiffness: 1.0e4,
            damping: Damping {
                per_mass: 27.6941,
                ..Damping::NONE
            },
        };
        let normal = Normal::from(law);
        assert_eq!(
            serde_json::to_string(&normal).expect("json"),
            serde_json::to_string(&law).expect("json")
        );
        let packed = rmp_serde::to_vec(&normal).expect("msgpack");
        assert_eq!(packed, rmp_serde::to_vec(&law).expect("msgpack"));
        let back: Normal = rmp_serde::from_slice(&packed).expect("reads back");
        assert_eq!(back, normal);
        let tagged: Normal = serde_json::from_str(&format!(
            "{{\"Linear\":{}}}",
            serde_json::to_string(&law).expect("json")
        ))
        .expect("tagged form");
        assert_eq!(tagged, normal);
    }
}
