//! Per-contact observers: what a force evaluation measures besides the forces.
//!
//! The force loop hands every interacting pair (particle pairs and contacts with analytic
//! walls) as a [`ContactView`] to an observer chosen per call, monomorphised into the loop
//! (no dynamic dispatch; the observer `()` compiles the measurement away). Each thread
//! chunk gets its own observer, and the chunks' observers are merged in chunk order, so a
//! measurement is bit-identical for a given thread count. Observers compose as tuples.

use crate::contact::{ContactHistory, PairForce, PairKernel, PairKinematics};
use crate::domain::ImageTransform;
use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

pub use crate::particles::NO_PART;

/// Outer product `a ⊗ b`, entry `(row k, column l) = a_k b_l`.
#[inline]
pub fn outer(a: DVec3, b: DVec3) -> DMat3 {
    // glam matrices are column-major: column l holds a · b_l.
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// One interacting pair `(i, j)` as the force loop sees it, in `i`'s frame: `j` is seen
/// through `image` (for an analytic wall, `j` is the wall).
pub struct ContactView<'a> {
    /// Permanent ids of `i` and `j` (for a wall, `j` is the wall's index).
    pub ids: [u32; 2],
    /// Wall parts of `i` and `j` ([`NO_PART`] for a free particle).
    pub parts: [u16; 2],
    /// Index of the analytic wall that is `j`, if any.
    pub wall: Option<u32>,
    /// The image of `j` (identity for a wall).
    pub image: &'a ImageTransform,
    /// Centre of `i` (m).
    pub position: DVec3,
    /// Branch vector `r_i − r_j` through the image (m); for a wall, from the foot of the
    /// centre on the wall to the centre.
    pub branch: DVec3,
    /// The pair's kinematics (normal from `j` to `i`, overlap, radii, velocities).
    pub kinematics: &'a PairKinematics,
    /// The force and torques on `i` (and torque on `j`) of this step.
    pub force: &'a PairForce,
    /// The pair's contact law, resolved.
    pub kernel: &'a PairKernel,
    /// The pair's history after this step's update.
    pub history: &'a ContactHistory,
}

impl ContactView<'_> {
    /// Contact point in `i`'s frame (m): the middle of the overlap (or of the gap of a pair
    /// apart), `r_i − (a_i − δ/2) n`.
    #[inline]
    pub fn contact_point(&self) -> DVec3 {
        let k = self.kinematics;
        self.position - k.normal * (k.radius_i - 0.5 * k.overlap)
    }

    /// Force on `j` in `j`'s own frame (N): `−Rᵀ f`.
    #[inline]
    pub fn force_on_j(&self) -> DVec3 {
        -self.image.vector_back(self.force.force)
    }

    /// Contact point in `j`'s own frame (m).
    #[inline]
    pub fn contact_point_of_j(&self) -> DVec3 {
        self.image.position_back(self.contact_point())
    }

    /// Elastic energy stored in the pair (J), springs and adhesive potential.
    pub fn elastic_energy(&self) -> f64 {
        let k = self.kinematics;
        self.kernel
            .elastic_energy(k.overlap, k.radius_i, k.radius_j, self.history)
    }

    /// Energy stored in the pair's springs alone (J, ≥ 0), without the adhesive potential.
    pub fn spring_energy(&self) -> f64 {
        let k = self.kinematics;
        self.kernel
            .spring_energy(k.overlap, k.radius_i, k.radius_j, self.history)
    }
}

/// What a force evaluation gathers from its contacts.
pub trait ContactObserver: Default + Send {
    /// Whether the loop must build views at all (`false` only for `()`).
    const OBSERVES: bool = true;
    /// Takes one interacting pair.
    fn visit(&mut self, contact: &ContactView<'_>);
    /// Adds the observations of another chunk (called in chunk order).
    fn merge(&mut self, other: Self);
}

/// Forces only.
impl ContactObserver for () {
    const OBSERVES: bool = false;
    #[inline]
    fn visit(&mut self, _: &ContactView<'_>) {}
    fn merge(&mut self, _: Self) {}
}

impl<A: ContactObserver, B: ContactObserver> ContactObserver for (A, B) {
    const OBSERVES: bool = A::OBSERVES || B::OBSERVES;
    #[inline]
    fn visit(&mut self, c: &ContactView<'_>) {
        self.0.visit(c);
        self.1.visit(c);
    }
    fn merge(&mut self, other: Self) {
        self.0.merge(other.0);
        self.1.merge(other.1);
    }
}

/// The contact part of the stress sum alone, `Σ f ⊗ l` (N m): what stress control needs
/// every step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StressSum(pub DMat3);

impl Default for StressSum {
    fn default() -> Self {
        StressSum(DMat3::ZERO)
    }
}

impl ContactObserver for StressSum {
    #[inline]
    fn visit(&mut self, c: &ContactView<'_>) {
        self.0 += outer(c.force.force, c.branch);
    }
    fn merge(&mut self, other: Self) {
        self.0 += other.0;
    }
}

/// Force and torque that the contacts exert on one wall part.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PartLoad {
    /// Total contact force on the part (N).
    pub force: DVec3,
    /// Total torque of the contact forces about the origin, `Σ c × f` (N m), `c` the
    /// contact point and `f` the force on the part's particle (or wall).
    pub torque: DVec3,
    /// Contacts (and attracting pairs apart) with the part.
    pub contacts: u64,
}

impl PartLoad {
    /// Torque about the axis through `point` along the unit vector `axis` (N m):
    /// `((Σ c × f) − point × F) · axis`.
    pub fn torque_about(&self, point: DVec3, axis: DVec3) -> f64 {
        (self.torque - point.cross(self.force)).dot(axis)
    }
}

/// Loads on every wall part, indexed by part (grown as parts are met).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PartLoads(pub Vec<PartLoad>);

impl PartLoads {
    #[inline]
    fn add(&mut self, part: u16, point: DVec3, force: DVec3) {
        let p = part as usize;
        if self.0.len() <= p {
            self.0.resize(p + 1, PartLoad::default());
        }
        let load = &mut self.0[p];
        load.force += force;
        load.torque += point.cross(force);
        load.contacts += 1;
    }
}

impl ContactObserver for PartLoads {
    #[inline]
    fn visit(&mut self, c: &ContactView<'_>) {
        if c.parts[0] != NO_PART {
            self.add(c.parts[0], c.contact_point(), c.force.force);
        }
        if c.parts[1] != NO_PART {
            self.add(c.parts[1], c.contact_point_of_j(), c.force_on_j());
        }
    }
    fn merge(&mut self, other: Self) {
        if self.0.len() < other.0.len() {
            self.0.resize(other.0.len(), PartLoad::default());
        }
        for (a, b) in self.0.iter_mut().zip(other.0) {
            a.force += b.force;
            a.torque += b.torque;
            a.contacts += b.contacts;
        }
    }
}
