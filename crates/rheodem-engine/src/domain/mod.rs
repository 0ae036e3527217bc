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
//! Each kind of boundary is a module of its own behind one interface, the trait
//! [`boundary::Boundary`] (whose defaults are the periodic box's answers): [`periodic`]
//! (the box with its periodic axes alone), [`lees_edwards`] (the sheared images across `y`,
//! their velocity jump, the shift and its wraps, the mean flow, affine drag) and [`wedge`]
//! (the rotated images, their wrap and the sector's volume); [`registry`] lists them in the
//! [`BoundaryKind`] a [`Domain`] holds, [`dynamics`] holds the shear dynamics and [`image`]
//! the image codes and transforms. [`Domain`] is the box `[lo, hi]` and asks its boundary.
//!
//! A pair that interacts across a periodic boundary is stored in the neighbour list with an
//! *image code*: which copy of the second particle it sees. The code is fixed between list
//! builds while the geometric transformation it stands for may change every step (a box
//! that is compressed, a Lees-Edwards shift). The force loop asks the domain for the
//! current transform of every code once per step.

pub mod boundary;
pub mod dynamics;
pub mod image;
pub mod lees_edwards;
pub mod periodic;
pub mod registry;
pub mod wedge;

pub use boundary::{Boundary, Frame};
pub use dynamics::ShearDynamics;
pub use image::{IDENTITY_IMAGE, IMAGE_COUNT, ImageTransform, image_code, image_offsets};
pub use lees_edwards::LeesEdwards;
pub use registry::BoundaryKind;
pub use wedge::Wedge;

use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

/// An axis-aligned box `[lo, hi]` with per-axis periodicity, closed by one boundary (the
/// periodic box alone, Lees-Edwards shear or an angular-periodic wedge).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "DomainRecord", into = "DomainRecord")]
pub struct Domain {
    /// Lower corner (m).
    pub lo: DVec3,
    /// Upper corner (m).
    pub hi: DVec3,
    /// Which of `x`, `y`, `z` are periodic.
    pub periodic: [bool; 3],
    /// The boundary that closes the box.
    pub boundary: BoundaryKind,
    /// Accumulated deformation gradient of the box's affine motion (shear, rescaling) since
    /// the start; the neighbour list compares it between builds.
    pub deformation: DMat3,
}

/// A domain as checkpoints and outputs hold it: the boundary as one optional field per
/// kind, as before boundaries were modules (so that earlier checkpoints load, and the
/// bytes are the same).
#[derive(Serialize, Deserialize)]
struct DomainRecord {
    lo: DVec3,
    hi: DVec3,
    periodic: [bool; 3],
    lees_edwards: Option<LeesEdwards>,
    #[serde(default)]
    wedge: Option<Wedge>,
    deformation: DMat3,
}

impl From<DomainRecord> for Domain {
    fn from(r: DomainRecord) -> Domain {
        let boundary = match (r.lees_edwards, r.wedge) {
            (Some(le), _) => BoundaryKind::LeesEdwards(le),
            (None, Some(w)) => BoundaryKind::Wedge(w),
            (None, None) => BoundaryKind::Periodic,
        };
        Domain {
            lo: r.lo,
            hi: r.hi,
            periodic: r.periodic,
            boundary,
            deformation: r.deformation,
        }
    }
}

impl From<Domain> for DomainRecord {
    fn from(d: Domain) -> DomainRecord {
        DomainRecord {
            lo: d.lo,
            hi: d.hi,
            periodic: d.periodic,
            lees_edwards: d.as_lees_edwards(),
            wedge: d.as_wedge(),
            deformation: d.deformation,
        }
    }
}

impl Domain {
    /// A box `[lo, hi]` with the given periodicity, no shear.
    pub fn new(lo: DVec3, hi: DVec3, periodic: [bool; 3]) -> Domain {
        Domain {
            lo,
            hi,
            periodic,
            boundary: BoundaryKind::Periodic,
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
        d.boundary = BoundaryKind::Wedge(Wedge {
            angle,
            inner_radius: inner,
            outer_radius: outer,
        });
        d
    }

    /// Adds Lees-Edwards shear at rate `shear_rate` (1/s), shift zero.
    pub fn with_lees_edwards(mut self, shear_rate: f64) -> Domain {
        self.boundary = BoundaryKind::LeesEdwards(LeesEdwards::new(shear_rate));
        self
    }

    /// The Lees-Edwards boundary, if the box is sheared.
    pub fn as_lees_edwards(&self) -> Option<LeesEdwards> {
        match self.boundary {
            BoundaryKind::LeesEdwards(le) => Some(le),
            _ => None,
        }
    }

    /// The Lees-Edwards boundary, to change it (its dynamics, its shift).
    pub fn as_lees_edwards_mut(&mut self) -> Option<&mut LeesEdwards> {
        match &mut self.boundary {
            BoundaryKind::LeesEdwards(le) => Some(le),
            _ => None,
        }
    }

    /// The wedge, if the region is one.
    pub fn as_wedge(&self) -> Option<Wedge> {
        match self.boundary {
            BoundaryKind::Wedge(w) => Some(w),
            _ => None,
        }
    }

    /// The box the boundary closes.
    #[inline]
    pub fn frame(&self) -> Frame {
        Frame {
            lo: self.lo,
            hi: self.hi,
            periodic: self.periodic,
        }
    }

    /// Velocity of the mean flow at `r` (m/s): `γ̇ (y − lo_y) x̂` under Lees-Edwards shear,
    /// zero otherwise.
    #[inline]
    pub fn mean_flow(&self, r: DVec3) -> DVec3 {
        self.boundary.mean_flow(&self.frame(), r)
    }

    /// The dynamics of the sheared particles ([`ShearDynamics::Lab`] without shear).
    #[inline]
    pub fn shear_dynamics(&self) -> ShearDynamics {
        self.boundary.dynamics()
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
        self.boundary.drag(&self.frame(), positions, free, dt);
    }

    /// Advances the box's own motion over `dt` (s): the Lees-Edwards shift grows by
    /// `γ̇ L_y dt` (with the current `L_y`).
    pub fn advance(&mut self, dt: f64) {
        let l = self.lengths();
        if let Some(increment) = self.boundary.advance(dt, l) {
            self.deformation = increment * self.deformation;
        }
    }

    /// The mean flow's velocity gradient `L` (1/s) that contacts subtract, as `L b`, from
    /// the relative velocity of a pair with branch `b`: the boundary's, where contacts
    /// measure against the mean flow (Lees-Edwards with peculiar contacts, docs/model.md
    /// §4.4); `None` otherwise.
    pub fn contact_velocity_gradient(&self) -> Option<DMat3> {
        self.boundary.contact_velocity_gradient()
    }

    /// How often the image codes have changed meaning (Lees-Edwards shift wraps).
    pub fn image_epoch(&self) -> u64 {
        self.boundary.image_epoch()
    }

    /// Box edge lengths (m).
    #[inline]
    pub fn lengths(&self) -> DVec3 {
        self.hi - self.lo
    }

    /// Volume of the region (m³): the box, or the wedge's sector `½ Φ (R_o² − R_i²) L_z`.
    pub fn volume(&self) -> f64 {
        self.boundary.volume(&self.frame())
    }

    /// The image codes the neighbour search must try besides the translations of the
    /// periodic axes, and for each the map of a query position: a pair `(i, j)` through
    /// image `c` is within `d` when `|T_c⁻¹ r_i − r_j| < d`. Empty without a wedge; the
    /// wedge's images rotate by `±Φ` (codes of offsets `(±1, 0, 0)`), one of them at `Φ = π`.
    pub fn rotated_images(&self) -> Vec<(u8, DMat3)> {
        self.boundary.rotated_images()
    }

    /// The wedge turns (multiples of `Φ`) of an image code: its `x` offset under a wedge,
    /// zero otherwise.
    #[inline]
    pub fn image_turns(&self, code: u8) -> i32 {
        self.boundary.image_turns(code)
    }

    /// The current transformation of every image code. Under Lees-Edwards shear the images
    /// across `y` are shifted by `c_y s` in `x` and, unless the particles are dragged
    /// affinely (their velocities then exclude the mean flow), move `c_y γ̇ L_y` faster in `x`.
    /// A wedge's images are rotations by `c_x Φ` about `z`.
    pub fn image_transforms(&self) -> [ImageTransform; IMAGE_COUNT] {
        self.boundary.image_transforms(&self.frame())
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
        self.boundary.wrap(&self.frame(), position, velocity, spin)
    }

    /// How many wedge angles `Φ` the azimuth of `r` lies outside `[0, Φ)` (zero without a
    /// wedge): [`Domain::wrap`] rotates such a particle by `−turns · Φ`.
    pub fn wedge_turns(&self, r: DVec3) -> i32 {
        self.boundary.turns(r)
    }

    /// Scales the box along `y` about its lower corner by `factor`, with the `y` coordinates.
    /// With full stored velocities, the velocities relative to the mean flow are scaled along
    /// `y` and kept along `x` (the mean flow `γ̇ (y − lo_y)` follows the moved coordinate).
    /// Under affine drag the stored velocities are relative to the whole affine motion, box
    /// rescaling included, and stay as they are.
    pub fn scale_y(&mut self, factor: f64, positions: &mut [DVec3], velocities: &mut [DVec3]) {
        let affine = self.drags_affinely();
        // The mean flow's `∂v_x/∂y`, which the moved coordinate carries.
        let rate = self.boundary.velocity_gradient().y_axis.x;
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
        self.boundary.rescale(s);
        self.deformation = DMat3::from_diagonal(s) * self.deformation;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> Domain {
        Domain::new(DVec3::ZERO, DVec3::splat(2.0), [true, true, false])
    }

    /// Checkpoints and outputs hold the boundary as one optional field per kind, as before
    /// boundaries were modules: the same JSON and MessagePack, and each kind reads back.
    #[test]
    fn the_boundary_is_stored_as_before() {
        let sheared = cube().with_lees_edwards(0.5);
        let wedge = Domain::wedge(0.5, 1.0, 3.0, 0.0, 1.0);
        for d in [cube(), sheared.clone(), wedge.clone()] {
            let json = serde_json::to_value(&d).expect("json");
            let mut keys: Vec<&str> = json
                .as_object()
                .expect("object")
                .keys()
                .map(String::as_str)
                .collect();
            keys.sort_unstable();
            assert_eq!(
                keys,
                [
                    "deformation",
                    "hi",
                    "lees_edwards",
                    "lo",
                    "periodic",
                    "wedge"
                ],
                "{json}"
            );
            let back: Domain = serde_json::from_value(json).expect("reads back");
            assert_eq!(back, d);
            let bytes = rmp_serde::to_vec_named(&d).expect("msgpack");
            assert_eq!(rmp_serde::from_slice::<Domain>(&bytes).expect("msgpack"), d);
        }
        let json = serde_json::to_value(&sheared).expect("json");
        assert_eq!(json["lees_edwards"]["shear_rate"], 0.5);
        assert!(json["wedge"].is_null());
        // A record without `wedge` (checkpoints from before the wedge) is the box.
        let mut old = serde_json::to_value(cube()).expect("json");
        old.as_object_mut().expect("object").remove("wedge");
        let read: Domain = serde_json::from_value(old).expect("old record");
        assert_eq!(read.boundary, BoundaryKind::Periodic);
    }

    /// The periodic box answers with the trait's defaults: no mean flow, the box's volume,
    /// images translated by the edges, wraps along the periodic axes only.
    #[test]
    fn the_periodic_box_is_the_default_boundary() {
        let d = cube();
        assert_eq!(d.boundary, BoundaryKind::Periodic);
        assert_eq!(d.mean_flow(DVec3::splat(1.0)), DVec3::ZERO);
        assert_eq!(d.contact_velocity_gradient(), None);
        assert_eq!(d.volume(), 8.0);
        assert!(d.rotated_images().is_empty());
        let t = d.image_transforms();
        assert_eq!(
            t[image_code([1, -1, 0]) as usize].shift,
            DVec3::new(2.0, -2.0, 0.0)
        );
        assert_eq!(t[image_code([1, -1, 0]) as usize].velocity_shift.x, 0.0);
        let mut sheared = cube().with_lees_edwards(0.5);
        sheared.as_lees_edwards_mut().expect("sheared").shift = 0.25;
        let t = sheared.image_transforms();
        assert_eq!(
            t[image_code([0, 1, 0]) as usize].shift,
            DVec3::new(0.25, 2.0, 0.0)
        );
        assert_eq!(t[image_code([0, 1, 0]) as usize].velocity_shift.x, 1.0);
        assert_eq!(sheared.mean_flow(DVec3::new(0.0, 1.5, 0.0)).x, 0.75);
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
        le.as_lees_edwards_mut().expect("sheared").dynamics = ShearDynamics::AffineDrag;
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
