//! How far the particles could have closed a neighbour list's skin since a reference
//! configuration (the list's build, or the last prune of its inner list).
//!
//! Displacements are measured relative to the box's affine motion since the reference
//! (the mean shear flow of Lees-Edwards boundaries, a compression or dilation): with `A`
//! that affine map minus the identity, `d_i` the non-affine displacements and `r_c` the
//! largest reach, a pair at least `r_c + s` apart at the reference is still farther apart
//! than its reach while `(1 + ‖A‖)(d_1 + d_2) + ‖A‖ (r_c + s) < s`, `d_1`, `d_2` the two
//! largest `|d_i|`. The left-hand side is [`Moves::closing`].

use crate::domain::Domain;
use crate::integrate::PARTICLES_PER_TASK;
use crate::particles::Particles;
use crate::team::Team;
use glam::{DMat3, DVec3};

/// Particles whose displacements are compared side by side.
const TOP_LANES: usize = 8;

/// Where the particles stood at a reference: positions (m), the box's deformation and its
/// lower corner (m).
pub type Reference<'a> = (&'a [DVec3], DMat3, DVec3);

/// The larger of `a.0` and `d`, and the larger of the rest: the two largest values seen,
/// without a branch. Written as comparisons rather than `f64::max` and `f64::min`, whose
/// treatment of NaN costs several instructions each: these compile to one `maxsd` or
/// `minsd`, and a NaN `d` is passed over all the same.
#[inline(always)]
fn top2((a0, a1): (f64, f64), d: f64) -> (f64, f64) {
    let larger = if d > a0 { d } else { a0 };
    let smaller = if d < a0 { d } else { a0 };
    (larger, if smaller > a1 { smaller } else { a1 })
}

/// The two largest of `moved(r[k], r0[k])` over the particles `k` (squared displacements,
/// m²), kept in [`TOP_LANES`] running pairs so that the maxima do not wait on each other.
#[inline(always)]
fn two_largest(r: &[DVec3], r0: &[DVec3], moved: impl Fn(&DVec3, &DVec3) -> f64) -> (f64, f64) {
    let mut acc = [(0.0f64, 0.0f64); TOP_LANES];
    for (r, r0) in r.chunks(TOP_LANES).zip(r0.chunks(TOP_LANES)) {
        for ((a, r), r0) in acc.iter_mut().zip(r).zip(r0) {
            *a = top2(*a, moved(r, r0));
        }
    }
    acc.into_iter()
        .fold((0.0, 0.0), |a, b| top2(top2(a, b.0), b.1))
}

/// The affine motion of the box since a reference, as the displacement check applies it.
#[derive(Clone, Copy)]
struct Affine {
    /// `F F₀⁻¹ − I`.
    matrix: DMat3,
    /// The reference's lower corner (m).
    lo: DVec3,
}

impl Affine {
    fn since(domain: &Domain, deformation: DMat3, lo: DVec3) -> Affine {
        Affine {
            matrix: domain.deformation * deformation.inverse() - DMat3::IDENTITY,
            lo,
        }
    }

    /// `‖A‖` (Frobenius).
    fn norm(&self) -> f64 {
        (self.matrix.x_axis.length_squared()
            + self.matrix.y_axis.length_squared()
            + self.matrix.z_axis.length_squared())
        .sqrt()
    }

    /// Whether only the matrix's `y` column is non-zero (no deformation at all, or simple
    /// shear along `x` with the gradient along `y` and a height that follows the stress).
    fn y_only(&self) -> bool {
        self.matrix.x_axis == DVec3::ZERO && self.matrix.z_axis == DVec3::ZERO
    }
}

/// `‖F F₀⁻¹ − I‖` (Frobenius): how far the box has deformed since a reference of
/// deformation `F₀`.
pub fn affine_norm(domain: &Domain, deformation: DMat3) -> f64 {
    Affine::since(domain, deformation, DVec3::ZERO).norm()
}

/// The particles' motion since a reference: the box's affine part and the two largest
/// displacements beyond it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Moves {
    /// `‖A‖`, the Frobenius norm of the affine map minus the identity.
    pub norm: f64,
    /// `d_1 + d_2`, the two largest non-affine displacements (m).
    pub sum: f64,
}

impl Moves {
    /// How far (m) a skin may have closed for pairs `reach` (their reach plus the skin, m)
    /// apart at the reference: `(1 + ‖A‖)(d_1 + d_2) + ‖A‖ reach`.
    pub fn closing(&self, reach: f64) -> f64 {
        (1.0 + self.norm) * self.sum + self.norm * reach
    }
}

/// The squared non-affine displacement `|r − r₀ − A (r₀ − lo)|²` when only `A`'s `y`
/// column is non-zero: that column times `r₀.y − lo.y` (the other columns' terms are
/// zeros, which change no square; without deformation the column is zero too, and
/// subtracting zeros changes no bit).
#[inline(always)]
fn sheared(a: Affine) -> impl Fn(&DVec3, &DVec3) -> f64 {
    let (column, lo_y) = (a.matrix.y_axis, a.lo.y);
    move |r: &DVec3, r0: &DVec3| (*r - *r0 - column * (r0.y - lo_y)).length_squared()
}

/// The squared non-affine displacement `|r − r₀ − A (r₀ − lo)|²` for any `A`.
#[inline(always)]
fn deformed(a: Affine) -> impl Fn(&DVec3, &DVec3) -> f64 {
    move |r: &DVec3, r0: &DVec3| (*r - *r0 - a.matrix * (*r0 - a.lo)).length_squared()
}

/// The particles' motion since `reference`, their displacements checked by the members
/// of `team` (the maxima do not depend on how they split the particles).
pub fn moves(
    particles: &Particles,
    domain: &Domain,
    team: &Team,
    (reference, deformation, lo): Reference<'_>,
) -> Moves {
    assert_eq!(
        reference.len(),
        particles.len(),
        "a reference of other particles"
    );
    let affine = Affine::since(domain, deformation, lo);
    let y_only = affine.y_only();
    let len = team.piece_len(particles.len(), PARTICLES_PER_TASK);
    let mut pieces: Vec<_> = particles
        .position
        .chunks(len)
        .zip(reference.chunks(len))
        .map(|(r, r0)| (r, r0, (0.0f64, 0.0f64)))
        .collect();
    team.for_each(&mut pieces, |(r, r0, top)| {
        *top = if y_only {
            two_largest(r, r0, sheared(affine))
        } else {
            two_largest(r, r0, deformed(affine))
        };
    });
    let (first, second) = pieces
        .iter()
        .fold((0.0, 0.0), |a, p| top2(top2(a, p.2.0), p.2.1));
    Moves {
        norm: affine.norm(),
        sum: first.sqrt() + second.sqrt(),
    }
}
