//! The simulation region and its boundaries: a box with periodic and Lees-Edwards axes, or
//! an angular-periodic wedge (docs/model.md §4.2–4.6).
//!
//! Every boundary answers the same questions, and the rest of the engine asks only these:
//! the current [`ImageTransform`] of every image code (translation and rotation, with the
//! velocity jump of Lees-Edwards images), [`Domain::rotated_images`] (the images the
//! neighbour search must query besides the translations of the periodic axes),
//! [`Domain::wrap`] of position, velocity *and* spin (returning the map applied, so that
//! contact history and prescribed motions follow it), [`Domain::volume`],
//! [`Domain::mean_flow`] and [`Domain::peculiar_velocity`] (what a stored velocity means
//! under the box's [`ShearDynamics`]).
//!
//! Each kind of boundary is a module of its own: [`lees_edwards`] (the sheared images across
//! `y`, their velocity jump, the shift and its wraps, the mean flow, affine drag), [`wedge`]
//! (the rotated images, their wrap and the sector's volume) and [`image`] (image codes and
//! transforms); the box with its periodic axes is [`Domain`] itself, which asks the
//! boundary it holds.
//!
//! A pair that interacts across a periodic boundary is stored in the neighbour list with an
//! *image code*: which copy of the second particle it sees. The code is fixed between list
//! builds while the geometric transformation it stands for may change every step (a box
//! that is compressed, a Lees-Edwards shift). The force loop asks the domain for the
//! current transform of every code once per step.

pub mod image;
pub mod lees_edwards;
pub mod wedge;

pub use image::{IDENTITY_IMAGE, IMAGE_COUNT, ImageTransform, image_code, image_offsets};
pub use lees_edwards::{LeesEdwards, ShearDynamics};
pub use wedge::Wedge;

use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

/// An axis-aligned box `[lo, hi]` with per-axis periodicity, optionally sheared by
/// Lees-Edwards boundaries.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Domain {
    /// Lower corner (m).
    pub lo: DVec3,
    /// Upper corner (m).
    pub hi: DVec3,
    /// Which of `x`, `y`, `z` are periodic.
    pub periodic: [bool; 3],
    /// Lees-Edwards shear in `x`–`y`, if any (needs `x` and `y` periodic).
    pub lees_edwards: Option<LeesEdwards>,
    /// Angular-periodic wedge about `z`, if any (then no axis is periodic and `lo`, `hi`
    /// bound the wedge's extent).
    #[serde(default)]
    pub wedge: Option<Wedge>,
    /// Accumulated deformation gradient of the box's affine motion (shear, rescaling) since
    /// the start; the neighbour list compares it between builds.
    pub deformation: DMat3,
}

impl Domain {
    /// A box `[lo, hi]` with the given periodicity, no shear.
    pub fn new(lo: DVec3, hi: DVec3, periodic: [bool; 3]) -> Domain {
        Domain {
            lo,
            hi,
            periodic,
            lees_edwards: None,
            wedge: None,
            deformation: DMat3::IDENTITY,
        }
    }

    /// The wedge `0 ≤ φ < angle` (rad) about the `z` axis between the radii `inner` and
    /// `outer` (m) and the heights `z_lo`, `z_hi` (m); `lo`, `hi` are set to its bounding box.
    pub fn wedge(angle: f64, inner: f64, outer: f64, z_lo: f64, z_hi: f64) -> Domain {
        let corner = |t: f64| DVec3::new(outer * t.cos(), outer * t.sin(), 0.0);
        let mut lo = DVec3::new(0.0, 0.0, z_lo)
            .min(corner(0.0))
            .min(corner(angle));
        let mut hi = DVec3::new(0.0, 0.0, z_hi)
            .max(corner(0.0))
            .max(corner(angle));
        for k in 1..=2 {
            let t = k as f64 * std::f64::consts::FRAC_PI_2;
            if t <= angle {
                lo = lo.min(corner(t));
                hi = hi.max(corner(t));
            }
        }
        lo.z = z_lo;
        hi.z = z_hi;
        let mut d = Domain::new(lo, hi, [false; 3]);
        d.wedge = Some(Wedge {
            angle,
            inner_radius: inner,
            outer_radius: outer,
        });
        d
    }

    /// Adds Lees-Edwards shear at rate `shear_rate` (1/s), shift zero.
    pub fn with_lees_edwards(mut self, shear_rate: f64) -> Domain {
        self.lees_edwards = Some(LeesEdwards::new(shear_rate));
        self
    }

    /// Velocity of the mean flow at `r` (m/s): `γ̇ (y − lo_y) x̂` under Lees-Edwards shear,
    /// zero otherwise.
    #[inline]
    pub fn mean_flow(&self, r: DVec3) -> DVec3 {
        match &self.lees_edwards {
            Some(le) => le.mean_flow(r.y - self.lo.y),
            None => DVec3::ZERO,
        }
    }

    /// The dynamics of the sheared particles ([`ShearDynamics::Lab`] without shear).
    pub fn shear_dynamics(&self) -> ShearDynamics {
        self.lees_edwards
            .map_or(ShearDynamics::Lab, |le| le.dynamics)
    }

    /// True when the box itself moves the particles with the mean flow
    /// ([`ShearDynamics::AffineDrag`]): stored velocities are then relative to it.
    #[inline]
    pub fn drags_affinely(&self) -> bool {
        self.shear_dynamics() == ShearDynamics::AffineDrag
    }

    /// The velocity relative to the mean flow (m/s) of a particle at `r` with stored
    /// velocity `v`: `v − γ̇ (y − lo_y) x̂` when stored velocities are full ones, `v` itself
    /// under affine drag. Kinetic stress, granular temperature and speed limits use it.
    #[inline]
    pub fn peculiar_velocity(&self, r: DVec3, v: DVec3) -> DVec3 {
        if self.drags_affinely() {
            v
        } else {
            v - self.mean_flow(r)
        }
    }

    /// The stored velocity (m/s) of a particle at `r` that moves with the mean flow plus
    /// `peculiar` (the inverse of [`Domain::peculiar_velocity`]).
    #[inline]
    pub fn stored_velocity(&self, r: DVec3, peculiar: DVec3) -> DVec3 {
        if self.drags_affinely() {
            peculiar
        } else {
            peculiar + self.mean_flow(r)
        }
    }

    /// The velocity in the lab (m/s) of a particle at `r` with stored velocity `v`: `v`
    /// itself, or `v + γ̇ (y − lo_y) x̂` under affine drag.
    #[inline]
    pub fn lab_velocity(&self, r: DVec3, v: DVec3) -> DVec3 {
        self.peculiar_velocity(r, v) + self.mean_flow(r)
    }

    /// Under affine drag, moves every free particle by the mean flow over `dt` (s),
    /// `x += γ̇ (y − lo_y) dt`; does nothing otherwise.
    pub fn drag_affinely(&self, positions: &mut [DVec3], free: impl Fn(usize) -> bool, dt: f64) {
        if let Some(le) = &self.lees_edwards {
            le.drag(positions, free, dt, self.lo.y);
        }
    }

    /// Advances the box's own motion over `dt` (s): the Lees-Edwards shift grows by
    /// `γ̇ L_y dt` (with the current `L_y`).
    pub fn advance(&mut self, dt: f64) {
        let l = self.lengths();
        if let Some(le) = &mut self.lees_edwards {
            let strain = le.advance(dt, l);
            let mut shear = DMat3::IDENTITY;
            shear.y_axis.x = strain;
            self.deformation = shear * self.deformation;
        }
    }

    /// The mean flow's velocity gradient `L` (1/s) that contacts subtract, as `L b`, from
    /// the relative velocity of a pair with branch `b`: the boundary's, where contacts
    /// measure against the mean flow (Lees-Edwards with peculiar contacts, docs/model.md
    /// §4.4); `None` otherwise.
    pub fn contact_velocity_gradient(&self) -> Option<DMat3> {
        self.lees_edwards
            .filter(|le| le.dynamics == ShearDynamics::PeculiarContacts)
            .map(|le| le.velocity_gradient())
    }

    /// How often the image codes have changed meaning (Lees-Edwards shift wraps).
    pub fn image_epoch(&self) -> u64 {
        self.lees_edwards.map_or(0, |le| le.wraps)
    }
    /// Box edge lengths (m).
    #[inline]
    pub fn lengths(&self) -> DVec3 {
        self.hi - self.lo
    }

    /// Volume of the region (m³): the box, or the wedge's sector `½ Φ (R_o² − R_i²) L_z`.
    pub fn volume(&self) -> f64 {
        let l = self.lengths();
        match &self.wedge {
            Some(w) => w.volume(l.z),
            None => l.x * l.y * l.z,
        }
    }

    /// The image codes the neighbour search must try besides the translations of the
    /// periodic axes, and for each the map of a query position: a pair `(i, j)` through
    /// image `c` is within `d` when `|T_c⁻¹ r_i − r_j| < d`. Empty without a wedge; the
    /// wedge's images rotate by `±Φ` (codes of offsets `(±1, 0, 0)`), one of them at `Φ = π`.
    pub fn rotated_images(&self) -> Vec<(u8, DMat3)> {
        self.wedge.map_or_else(Vec::new, |w| w.rotated_images())
    }

    /// The wedge turns (multiples of `Φ`) of an image code: its `x` offset under a wedge,
    /// zero otherwise.
    #[inline]
    pub fn image_turns(&self, code: u8) -> i32 {
        if self.wedge.is_some() {
            image_offsets(code)[0]
        } else {
            0
        }
    }

    /// The current transformation of every image code. Under Lees-Edwards shear the images
    /// across `y` are shifted by `c_y s` in `x` and, unless the particles are dragged
    /// affinely (their velocities then exclude the mean flow), move `c_y γ̇ L_y` faster in `x`.
    /// A wedge's images are rotations by `c_x Φ` about `z`.
    pub fn image_transforms(&self) -> [ImageTransform; IMAGE_COUNT] {
        if let Some(w) = &self.wedge {
            return w.image_transforms();
        }
        let l = self.lengths();
        let (s, u) = self
            .lees_edwards
            .map_or((0.0, 0.0), |le| (le.shift, le.velocity_jump(l.y)));
        std::array::from_fn(|code| {
            let c = image_offsets(code as u8);
            let (cx, cy, cz) = (c[0] as f64, c[1] as f64, c[2] as f64);
            ImageTransform {
                rotation: None,
                shift: DVec3::new(cx * l.x + cy * s, cy * l.y, cz * l.z),
                velocity_shift: DVec3::new(cy * u, 0.0, 0.0),
            }
        })
    }

    /// Maps a particle back into the primary region and returns the map applied
    /// (`r' = R r + shift`). Along periodic axes the position is translated; crossing `y`
    /// under Lees-Edwards shear also shifts `x` by `∓s` and, with full stored velocities
    /// (not under affine drag), `v_x` by `∓γ̇ L_y`; through a
    /// wedge face position, velocity and spin are rotated by a multiple of `Φ`.
    pub fn wrap(
        &self,
        position: &mut DVec3,
        velocity: &mut DVec3,
        spin: &mut DVec3,
    ) -> ImageTransform {
        if let Some(w) = &self.wedge {
            return w.wrap(position, velocity, spin);
        }
        let before = *position;
        self.wrap_translation(position, velocity);
        ImageTransform {
            shift: *position - before,
            ..ImageTransform::IDENTITY
        }
    }

    /// How many wedge angles `Φ` the azimuth of `r` lies outside `[0, Φ)` (zero without a
    /// wedge): [`Domain::wrap`] rotates such a particle by `−turns · Φ`.
    pub fn wedge_turns(&self, r: DVec3) -> i32 {
        self.wedge.map_or(0, |w| w.turns(r))
    }

    fn wrap_translation(&self, position: &mut DVec3, velocity: &mut DVec3) {
        let l = self.lengths();
        if let Some(le) = &self.lees_edwards {
            le.wrap_y(position, velocity, self.lo.y, self.hi.y, l.y);
        }
        for axis in 0..3 {
            if self.periodic[axis] && !(axis == 1 && self.lees_edwards.is_some()) {
                let x = position[axis];
                if x < self.lo[axis] || x >= self.hi[axis] {
                    let k = ((x - self.lo[axis]) / l[axis]).floor();
                    let mut w = x - k * l[axis];
                    if w >= self.hi[axis] {
                        w -= l[axis];
                    }
                    if w < self.lo[axis] {
                        w = self.lo[axis];
                    }
                    position[axis] = w;
                }
            }
        }
    }

    /// Scales the box along `y` about its lower corner by `factor`, with the `y` coordinates.
    /// With full stored velocities, the velocities relative to the mean flow are scaled along
    /// `y` and kept along `x` (the mean flow `γ̇ (y − lo_y)` follows the moved coordinate).
    /// Under affine drag the stored velocities are relative to the whole affine motion, box
    /// rescaling included, and stay as they are.
    pub fn scale_y(&mut self, factor: f64, positions: &mut [DVec3], velocities: &mut [DVec3]) {
        let affine = self.drags_affinely();
        let rate = self.lees_edwards.map_or(0.0, |le| le.shear_rate);
        for (r, v) in positions.iter_mut().zip(velocities.iter_mut()) {
            let dy = (r.y - self.lo.y) * (factor - 1.0);
            r.y += dy;
            if !affine {
                v.x += rate * dy;
                v.y *= factor;
            }
        }
        self.hi.y = self.lo.y + (self.hi.y - self.lo.y) * factor;
        self.deformation = DMat3::from_diagonal(DVec3::new(1.0, factor, 1.0)) * self.deformation;
    }

    /// Scales the box about its lower corner by `factor` along every periodic axis and maps
    /// positions affinely with it (used to compress a packing).
    pub fn scale_affine(&mut self, factor: f64, positions: &mut [DVec3]) {
        let s = DVec3::new(
            if self.periodic[0] { factor } else { 1.0 },
            if self.periodic[1] { factor } else { 1.0 },
            if self.periodic[2] { factor } else { 1.0 },
        );
        for r in positions.iter_mut() {
            *r = self.lo + (*r - self.lo) * s;
        }
        self.hi = self.lo + self.lengths() * s;
        if let Some(le) = &mut self.lees_edwards {
            le.shift *= s.x;
        }
        self.deformation = DMat3::from_diagonal(s) * self.deformation;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> Domain {
        Domain::new(DVec3::ZERO, DVec3::splat(2.0), [true, true, false])
    }

    #[test]
    fn image_codes_round_trip() {
        for code in 0..IMAGE_COUNT as u8 {
            assert_eq!(image_code(image_offsets(code)), code);
        }
        assert_eq!(image_offsets(IDENTITY_IMAGE), [0, 0, 0]);
    }

    #[test]
    fn wrap_only_periodic_axes() {
        let d = cube();
        let mut r = DVec3::new(-0.5, 4.5, 3.0);
        let (mut v, mut w) = (DVec3::ZERO, DVec3::ZERO);
        d.wrap(&mut r, &mut v, &mut w);
        assert_eq!(r, DVec3::new(1.5, 0.5, 3.0));
    }

    #[test]
    fn shear_dynamics_reads_names_and_the_older_boolean() {
        #[derive(Deserialize)]
        struct T {
            #[serde(alias = "peculiar_contacts")]
            d: ShearDynamics,
        }
        let read = |text: &str| serde_json::from_str::<T>(text).map(|t| t.d);
        for d in ShearDynamics::ALL {
            assert_eq!(read(&format!("{{\"d\": \"{d}\"}}")).expect("name"), d);
            assert_eq!(d.name().parse::<ShearDynamics>().expect("parse"), d);
        }
        assert_eq!(
            read(r#"{"peculiar_contacts": true}"#).expect("true"),
            ShearDynamics::PeculiarContacts
        );
        assert_eq!(
            read(r#"{"peculiar_contacts": false}"#).expect("false"),
            ShearDynamics::Lab
        );
        let e = read(r#"{"d": "sllod"}"#).expect_err("unknown").to_string();
        assert!(e.contains("sllod") && e.contains("affine-drag"), "{e}");
        // Checkpoints (MessagePack, named fields) of either spelling read back.
        let mut le = Domain::new(DVec3::ZERO, DVec3::ONE, [true; 3]).with_lees_edwards(2.0);
        le.lees_edwards.as_mut().expect("sheared").dynamics = ShearDynamics::AffineDrag;
        let bytes = rmp_serde::to_vec_named(&le).expect("encode");
        assert_eq!(rmp_serde::from_slice::<Domain>(&bytes).expect("decode"), le);
    }

    #[test]
    fn image_shift_matches_code() {
        let d = cube();
        let t = d.image_transforms();
        let code = image_code([1, -1, 0]);
        assert_eq!(
            t[code as usize].position(DVec3::ZERO),
            DVec3::new(2.0, -2.0, 0.0)
        );
        assert_eq!(t[IDENTITY_IMAGE as usize], ImageTransform::IDENTITY);
    }
}
