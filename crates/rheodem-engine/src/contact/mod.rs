//! Contact laws between two spheres (docs/model.md §2).
//!
//! A [`ContactLaw`] combines independent sub-models, each chosen from its registry by name:
//! a [`Normal`] law (`normal/`), three [`Spring`]s (sliding, rolling, torsion; `spring/`)
//! and an [`Adhesion`] law (`adhesion/`). Per-contact state lives in one [`ContactHistory`]
//! record.
//! A [`ContactTable`] resolves each species pair's law into a [`PairKernel`]
//! (`kernel.rs`), the single implementation of the law, written generic over one contact
//! or four in lanes (`lanes.rs`); the force loop, the walls and [`ContactLaw::interact`]
//! all run it.
//! Sign convention: `n` points from the second particle `j` to the first `i`; the returned
//! force acts on `i`, and `−force` on `j`.

pub mod names;

pub mod adhesion;
pub mod curve;
pub mod damping;
pub mod equivalent;
pub mod kernel;
pub mod lanes;
pub mod normal;
pub mod parameters;
pub mod slots;
pub mod spring;
pub mod standard;

use crate::domain::ImageTransform;
use glam::DVec3;
use serde::{Deserialize, Serialize};

pub use adhesion::{
    Adhesion, LawKind, LawSpec, LinearIrreversible, LiquidBridge, Reversible, Strength,
};
pub use damping::Damping;
pub use kernel::PairKernel;
pub use names::ModelInfo;
pub use normal::{
    LinearNormal, LudingNormal, NORMAL_LAWS, Normal, NormalKind, NormalModel, NormalSpec,
};
pub use slots::{HistorySlots, HistoryView};
pub use spring::{Resistance, SPRING_LAWS, Spring, SpringKind, SpringModel};

/// The full contact law of one species pair.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactLaw {
    /// Repulsive normal force.
    pub normal: Normal,
    /// Sliding friction (stiffness `k_t` in N/m for the linear spring).
    pub tangential: Spring,
    /// Rolling resistance (acting on the rolling displacement).
    pub rolling: Spring,
    /// Torsion resistance (acting on the torsional displacement).
    pub torsion: Spring,
    /// Adhesive force added to the normal force.
    pub adhesion: Adhesion,
}

/// Per-contact history: the three springs (m) and the normal law's state, reset to zero
/// when the contact opens, and the liquid bridge of irreversible adhesive laws, which
/// outlives the contact until it ruptures.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ContactHistory {
    /// Tangential (sliding) spring `ξ_t`.
    pub tangential: DVec3,
    /// Rolling spring `ξ_r`.
    pub rolling: DVec3,
    /// Torsion spring `ξ_o` (along the normal).
    pub torsion: DVec3,
    /// Whether an irreversible law's bridge exists.
    pub bridge: bool,
    /// The per-contact state a normal law declares it keeps ([`normal::NormalForce::KEEPS_STATE`],
    /// a number in the law's own unit, e.g. the largest overlap reached in m); zero under a
    /// law that keeps none. Absent from records written before laws could keep state.
    #[serde(default)]
    pub state: f64,
    /// The per-contact state the sliding spring's law declares it keeps
    /// ([`spring::SpringModel::KEEPS_STATE`], e.g. Mindlin's contact radius at the last step
    /// in m); zero under a law that keeps none. Absent from records written before springs
    /// could keep state.
    #[serde(default)]
    pub sliding_state: f64,
}

impl ContactHistory {
    /// The same history seen from the other particle (pair order `j, i`). The sliding and
    /// torsion springs change sign with the pair order; the rolling spring does not (its
    /// velocity `−a'(ω_i − ω_j) × n` is symmetric).
    pub fn flipped(&self) -> ContactHistory {
        ContactHistory {
            tangential: -self.tangential,
            rolling: self.rolling,
            torsion: -self.torsion,
            bridge: self.bridge,
            state: self.state,
            sliding_state: self.sliding_state,
        }
    }

    /// The same history with its springs mapped into an image's frame: `R ξ` for each
    /// spring (unchanged under a pure translation); the normal law's state is a scalar and
    /// stays.
    pub fn rotated(&self, image: &ImageTransform) -> ContactHistory {
        self.map(|v| image.vector(v))
    }

    /// The same history with its springs mapped back from an image's frame: `Rᵀ ξ`.
    pub fn rotated_back(&self, image: &ImageTransform) -> ContactHistory {
        self.map(|v| image.vector_back(v))
    }

    fn map(&self, f: impl Fn(DVec3) -> DVec3) -> ContactHistory {
        ContactHistory {
            tangential: f(self.tangential),
            rolling: f(self.rolling),
            torsion: f(self.torsion),
            bridge: self.bridge,
            state: self.state,
            sliding_state: self.sliding_state,
        }
    }
}

/// Relative state of two spheres in contact, as seen from `i`.
#[derive(Clone, Copy, Debug)]
pub struct PairKinematics {
    /// Unit normal from `j` to `i`.
    pub normal: DVec3,
    /// Overlap `δ = a_i + a_j − |r_i − r_j|` (m).
    pub overlap: f64,
    /// Radius of `i` (m).
    pub radius_i: f64,
    /// Radius of `j` (m); for a planar wall, `f64::INFINITY`.
    pub radius_j: f64,
    /// `v_i − v_j` (m/s).
    pub velocity: DVec3,
    /// Angular velocity of `i` (rad/s).
    pub omega_i: DVec3,
    /// Angular velocity of `j` (rad/s).
    pub omega_j: DVec3,
    /// Reduced mass `m_ij = 1/(1/m_i + 1/m_j)` (kg); a prescribed particle is infinitely heavy.
    pub reduced_mass: f64,
}

/// Result of a pair evaluation.
#[derive(Clone, Copy, Debug, Default)]
pub struct PairForce {
    /// Force on `i` (N); `j` receives its negative.
    pub force: DVec3,
    /// Torque on `i` (N m).
    pub torque_i: DVec3,
    /// Torque on `j` (N m).
    pub torque_j: DVec3,
    /// Repulsive normal force `k_n δ + γ_n δ̇` (N), the reference of the Coulomb limits;
    /// zero for a pair apart.
    pub repulsive: f64,
    /// Adhesive normal force (N, ≤ 0).
    pub adhesive: f64,
    /// Whether the sliding spring slipped this step.
    pub sliding: bool,
}

impl ContactLaw {
    /// Interaction range beyond contact (m): where the adhesive law still pulls.
    pub fn range(&self) -> f64 {
        self.adhesion.range()
    }

    /// Evaluates a pair at any overlap and advances its history over `dt` (s). Returns
    /// `None` when the pair does not interact; its history is then reset (an irreversible
    /// bridge past its rupture distance is gone).
    ///
    /// A frictionless pair with reversible adhesion (`f_max = 1 mN`, `k_c = 10 N/m`, range
    /// `δ_a = 0.1 mm`) pushes with `k_n δ − f_max` in contact, pulls with `k_c S − f_max` at
    /// a separation `S < δ_a`, and no longer interacts beyond:
    ///
    /// ```
    /// use glam::DVec3;
    /// use rheodem_engine::contact::{
    ///     Adhesion, ContactHistory, ContactLaw, Damping, LinearNormal, PairKinematics, Reversible,
    ///     Spring,
    /// };
    ///
    /// let law = ContactLaw {
    ///     normal: LinearNormal { stiffness: 100.0, damping: Damping::NONE }.into(),
    ///     tangential: Spring::NONE,
    ///     rolling: Spring::NONE,
    ///     torsion: Spring::NONE,
    ///     adhesion: Adhesion::Reversible(Reversible { max_force: 1.0e-3, stiffness: 10.0 }),
    /// };
    /// assert_eq!(law.range(), 1.0e-4);
    /// let at = |overlap: f64| PairKinematics {
    ///     normal: DVec3::X, // from j to i
    ///     overlap,
    ///     radius_i: 1.0e-3,
    ///     radius_j: 1.0e-3,
    ///     velocity: DVec3::ZERO,
    ///     omega_i: DVec3::ZERO,
    ///     omega_j: DVec3::ZERO,
    ///     reduced_mass: 4.0e-6,
    /// };
    /// let mut h = ContactHistory::default();
    /// let touching = law.interact(&at(2.0e-5), &mut h, 1e-5).expect("in contact");
    /// assert!((touching.force.x - (100.0 * 2.0e-5 - 1.0e-3)).abs() < 1e-15);
    /// let apart = law.interact(&at(-4.0e-5), &mut h, 1e-5).expect("within range");
    /// assert!((apart.force.x - (10.0 * 4.0e-5 - 1.0e-3)).abs() < 1e-15);
    /// assert!(law.interact(&at(-2.0e-4), &mut h, 1e-5).is_none());
    /// ```
    pub fn interact(
        &self,
        k: &PairKinematics,
        h: &mut ContactHistory,
        dt: f64,
    ) -> Option<PairForce> {
        PairKernel::new(self).interact(k, h, dt)
    }

    /// Evaluates the contact of a touching pair (`overlap ≥ 0`) and advances its history
    /// over `dt` (s). The Coulomb limits use the repulsive part `|k_n δ + γ_n δ̇|` alone.
    pub fn evaluate(&self, k: &PairKinematics, h: &mut ContactHistory, dt: f64) -> PairForce {
        PairKernel::new(self).touching(k, h, dt)
    }

    /// Elastic energy stored in a pair (J): the normal law's and the springs' energies in
    /// contact (`½ k_n δ² + ½ k_t |ξ_t|² + ½ k_r |ξ_r|² + ½ k_o |ξ_o|²` for linear laws), plus the adhesive potential of the law (negative; zero
    /// once the pair is free) for radii `a_i`, `a_j` (m).
    pub fn elastic_energy(&self, overlap: f64, a_i: f64, a_j: f64, h: &ContactHistory) -> f64 {
        PairKernel::new(self).elastic_energy(overlap, a_i, a_j, h)
    }
}

/// Contact laws of every species pair, `n_species × n_species`, symmetric, with each law
/// resolved into the [`PairKernel`] the pair loop uses (derived, not serialised: a table
/// is stored as its species count and laws alone).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "StoredTable", into = "StoredTable")]
pub struct ContactTable {
    species: usize,
    laws: Vec<ContactLaw>,
    kernels: Vec<PairKernel>,
}

/// The serialised form of a [`ContactTable`].
#[derive(Clone, Serialize, Deserialize)]
struct StoredTable {
    species: usize,
    laws: Vec<ContactLaw>,
}

impl From<StoredTable> for ContactTable {
    fn from(t: StoredTable) -> ContactTable {
        ContactTable::from_laws(t.species, t.laws)
    }
}

impl From<ContactTable> for StoredTable {
    fn from(t: ContactTable) -> StoredTable {
        StoredTable {
            species: t.species,
            laws: t.laws,
        }
    }
}

impl ContactTable {
    /// A table where every pair of the `species` species uses `law`.
    pub fn uniform(species: usize, law: ContactLaw) -> ContactTable {
        ContactTable::from_laws(species, vec![law; species * species])
    }

    fn from_laws(species: usize, laws: Vec<ContactLaw>) -> ContactTable {
        let kernels = laws.iter().map(PairKernel::new).collect();
        ContactTable {
            species,
            laws,
            kernels,
        }
    }

    /// Number of species.
    pub fn species(&self) -> usize {
        self.species
    }

    /// Largest interaction range beyond contact over all pairs (m).
    pub fn max_range(&self) -> f64 {
        self.laws.iter().map(ContactLaw::range).fold(0.0, f64::max)
    }

    /// Largest range beyond contact (m) over the laws that act on pairs apart without a
    /// bridge (reversible adhesion); zero when every adhesive law is irreversible.
    pub fn free_range(&self) -> f64 {
        self.kernels
            .iter()
            .filter(|k| !k.needs_bridge())
            .map(PairKernel::range)
            .fold(0.0, f64::max)
    }

    /// Whether any pair's law forms bridges at contact (irreversible adhesion).
    pub fn forms_bridges(&self) -> bool {
        self.kernels.iter().any(PairKernel::needs_bridge)
    }

    /// Sets the law of the pair `(a, b)` (and `(b, a)`).
    pub fn set(&mut self, a: usize, b: usize, law: ContactLaw) {
        self.laws[a * self.species + b] = law;
        self.laws[b * self.species + a] = law;
        self.kernels[a * self.species + b] = PairKernel::new(&law);
        self.kernels[b * self.species + a] = PairKernel::new(&law);
    }

    /// Applies `f` to the law of every pair.
    pub fn map(&mut self, f: impl FnMut(&mut ContactLaw)) {
        self.laws.iter_mut().for_each(f);
        self.kernels = self.laws.iter().map(PairKernel::new).collect();
    }

    /// The law of the pair `(a, b)`.
    #[inline]
    pub fn get(&self, a: u16, b: u16) -> &ContactLaw {
        &self.laws[a as usize * self.species + b as usize]
    }

    /// The resolved kernel of the pair `(a, b)`.
    #[inline(always)]
    pub fn kernel(&self, a: u16, b: u16) -> &PairKernel {
        &self.kernels[a as usize * self.species + b as usize]
    }
}
