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
//! A pair that interacts across a periodic boundary is stored in the neighbour list with an
//! *image code*: which copy of the second particle it sees. The code is fixed between list
//! builds while the geometric transformation it stands for may change every step (a box
//! that is compressed, a Lees-Edwards shift). The force loop asks the domain for the
//! current transform of every code once per step.

use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

/// Number of image codes: one for each of the 3×3×3 neighbouring copies of the box.
pub const IMAGE_COUNT: usize = 27;
/// The image code of the particle itself (no shift).
pub const IDENTITY_IMAGE: u8 = 13;

/// Packs the cell offsets `(cx, cy, cz)`, each in `{-1, 0, 1}`, into an image code.
#[inline]
pub fn image_code(c: [i32; 3]) -> u8 {
    ((c[0] + 1) + 3 * (c[1] + 1) + 9 * (c[2] + 1)) as u8
}

/// Unpacks an image code into its cell offsets.
#[inline]
pub fn image_offsets(code: u8) -> [i32; 3] {
    let c = code as i32;
    [c % 3 - 1, (c / 3) % 3 - 1, c / 9 - 1]
}

/// How to map a particle onto one of its periodic images: `r' = R r + shift`,
/// `v' = R v + velocity_shift`, `ω' = R ω`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageTransform {
    /// Rotation `R`; `None` for a pure translation (the common case, kept cheap).
    pub rotation: Option<DMat3>,
    /// Translation added to positions (m).
    pub shift: DVec3,
    /// Velocity added to velocities (m/s).
    pub velocity_shift: DVec3,
}

impl ImageTransform {
    /// The identity transformation.
    pub const IDENTITY: ImageTransform = ImageTransform {
        rotation: None,
        shift: DVec3::ZERO,
        velocity_shift: DVec3::ZERO,
    };

    /// Image of a position (m).
    #[inline]
    pub fn position(&self, r: DVec3) -> DVec3 {
        match self.rotation {
            None => r + self.shift,
            Some(m) => m * r + self.shift,
        }
    }

    /// Image of a velocity (m/s).
    #[inline]
    pub fn velocity(&self, v: DVec3) -> DVec3 {
        match self.rotation {
            None => v + self.velocity_shift,
            Some(m) => m * v + self.velocity_shift,
        }
    }

    /// Image of an angular velocity (rad/s).
    #[inline]
    pub fn angular_velocity(&self, w: DVec3) -> DVec3 {
        self.vector(w)
    }

    /// Image of a free vector (a force, a spring, an axis): `R u`.
    #[inline]
    pub fn vector(&self, u: DVec3) -> DVec3 {
        match self.rotation {
            None => u,
            Some(m) => m * u,
        }
    }

    /// A vector (force, torque, spring) of the image frame seen in the original particle's
    /// frame: `Rᵀ u`.
    #[inline]
    pub fn vector_back(&self, u: DVec3) -> DVec3 {
        match self.rotation {
            None => u,
            Some(m) => m.transpose() * u,
        }
    }

    /// A position of the image frame mapped back to the original frame: `Rᵀ (r − shift)` (m).
    #[inline]
    pub fn position_back(&self, r: DVec3) -> DVec3 {
        self.vector_back(r - self.shift)
    }
}

/// An angular-periodic wedge `0 ≤ φ < Φ` about the `z` axis through the origin
/// (docs/model.md §4.6): a particle leaving through one face re-enters through the other with
/// its position, velocity and spin rotated by `∓Φ`, and pairs interact through the images
/// rotated by `±Φ`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Wedge {
    /// Opening angle `Φ` (rad), in `(0, π]`.
    pub angle: f64,
    /// Smallest distance from the axis at which particles are expected (m); it bounds the
    /// wedge's width for the neighbour search.
    pub inner_radius: f64,
    /// Largest distance from the axis at which particles are expected (m).
    pub outer_radius: f64,
}

impl Wedge {
    /// Rotation about `z` by `turns · Φ`.
    pub fn rotation(&self, turns: i32) -> DMat3 {
        DMat3::from_rotation_z(turns as f64 * self.angle)
    }

    /// Whether the images `+Φ` and `−Φ` are the same copy (`Φ = π`).
    pub fn half_turn(&self) -> bool {
        (self.angle - std::f64::consts::PI).abs() < 1e-12
    }

    /// Distance (m) from `q` (projected on `x`–`y`) to the wedge `0 ≤ φ ≤ Φ`: zero inside.
    pub fn distance(&self, q: DVec3) -> f64 {
        let p = DVec3::new(q.x, q.y, 0.0);
        let phi = p.y.atan2(p.x);
        let phi = if phi < 0.0 {
            phi + std::f64::consts::TAU
        } else {
            phi
        };
        if phi <= self.angle {
            return 0.0;
        }
        let to_ray = |theta: f64| {
            let u = DVec3::new(theta.cos(), theta.sin(), 0.0);
            let t = p.dot(u);
            if t <= 0.0 {
                p.length()
            } else {
                (p - u * t).length()
            }
        };
        to_ray(0.0).min(to_ray(self.angle))
    }
}

/// How a Lees-Edwards box moves its particles and what their stored velocities mean
/// (docs/model.md §4.3–4.5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ShearDynamics {
    /// Lab frame (the default, §4.3): velocities are full velocities, `dv/dt = F/m`; images
    /// across `y` move `±γ̇ L_y` along `x`, and contacts see the full relative velocity.
    #[default]
    Lab,
    /// The lab-frame dynamics, but every contact subtracts the mean-flow difference
    /// `γ̇ l_y x̂` of its two particles from its relative velocity (§4.4), for comparison.
    PeculiarContacts,
    /// Affine drag (§4.5, the dynamics of the source papers' code): velocities `c` are
    /// relative to the mean flow and obey `dc/dt = F/m`; every free particle is moved by
    /// `(c + γ̇ (y − lo_y) x̂) dt`; images carry no velocity jump and contacts see
    /// `c_i − c_j`.
    AffineDrag,
}

impl ShearDynamics {
    /// Every option, in the order of the documentation.
    pub const ALL: [ShearDynamics; 3] = [
        ShearDynamics::Lab,
        ShearDynamics::PeculiarContacts,
        ShearDynamics::AffineDrag,
    ];

    /// The name used in scenario files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ShearDynamics::Lab => "lab",
            ShearDynamics::PeculiarContacts => "peculiar-contacts",
            ShearDynamics::AffineDrag => "affine-drag",
        }
    }
}

impl std::fmt::Display for ShearDynamics {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for ShearDynamics {
    type Err = String;

    fn from_str(s: &str) -> Result<ShearDynamics, String> {
        ShearDynamics::ALL
            .into_iter()
            .find(|d| d.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown shear dynamics {s:?}: expected lab, peculiar-contacts or affine-drag"
                )
            })
    }
}

/// Reads a name (`"affine-drag"`), or the boolean of the older key `peculiar_contacts`
/// (`true` = [`ShearDynamics::PeculiarContacts`], `false` = [`ShearDynamics::Lab`]), so that
/// files written before the three options existed still read the same.
impl<'de> Deserialize<'de> for ShearDynamics {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<ShearDynamics, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = ShearDynamics;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("\"lab\", \"peculiar-contacts\" or \"affine-drag\"")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<ShearDynamics, E> {
                v.parse().map_err(E::custom)
            }
            fn visit_bool<E: serde::de::Error>(self, v: bool) -> Result<ShearDynamics, E> {
                Ok(if v {
                    ShearDynamics::PeculiarContacts
                } else {
                    ShearDynamics::Lab
                })
            }
        }
        d.deserialize_any(Visitor)
    }
}

/// Lees-Edwards boundaries (docs/model.md §4.3–4.5): shear along `x`, gradient along `y`.
/// The image across `y = L_y` is shifted by `shift` in `x`; in the lab frame it also moves
/// `γ̇ L_y` faster in `x`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LeesEdwards {
    /// Shear rate `γ̇` (1/s).
    pub shear_rate: f64,
    /// Accumulated shift `s = ∫ γ̇ L_y dt`, kept in `[−L_x/2, L_x/2)` (m).
    pub shift: f64,
    /// How often `shift` has been brought back into its range (each time the image codes
    /// of the neighbour list change meaning, so the list must be rebuilt).
    pub wraps: u64,
    /// The dynamics of the sheared particles (default the lab frame). Also read from the
    /// boolean `peculiar_contacts` of older checkpoints.
    #[serde(default, alias = "peculiar_contacts")]
    pub dynamics: ShearDynamics,
}

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
        self.lees_edwards = Some(LeesEdwards {
            shear_rate,
            shift: 0.0,
            wraps: 0,
            dynamics: ShearDynamics::Lab,
        });
        self
    }

    /// Velocity of the mean flow at `r` (m/s): `γ̇ (y − lo_y) x̂` under Lees-Edwards shear,
    /// zero otherwise.
    #[inline]
    pub fn mean_flow(&self, r: DVec3) -> DVec3 {
        match &self.lees_edwards {
            Some(le) => DVec3::new(le.shear_rate * (r.y - self.lo.y), 0.0, 0.0),
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
        let Some(le) = self
            .lees_edwards
            .filter(|le| le.dynamics == ShearDynamics::AffineDrag)
        else {
            return;
        };
        let (rate, lo_y) = (le.shear_rate * dt, self.lo.y);
        for (i, r) in positions.iter_mut().enumerate() {
            if free(i) {
                r.x += rate * (r.y - lo_y);
            }
        }
    }

    /// Advances the box's own motion over `dt` (s): the Lees-Edwards shift grows by
    /// `γ̇ L_y dt` (with the current `L_y`).
    pub fn advance(&mut self, dt: f64) {
        let l = self.lengths();
        if let Some(le) = &mut self.lees_edwards {
            let strain = le.shear_rate * dt;
            le.shift += strain * l.y;
            if le.shift >= 0.5 * l.x || le.shift < -0.5 * l.x {
                le.shift -= l.x * (le.shift / l.x).round();
                if le.shift >= 0.5 * l.x {
                    le.shift -= l.x;
                }
                le.wraps += 1;
            }
            let mut shear = DMat3::IDENTITY;
            shear.y_axis.x = strain;
            self.deformation = shear * self.deformation;
        }
    }

    /// Rate `γ̇` (1/s) of the mean-flow difference that contacts subtract from their
    /// relative velocity: non-zero only with peculiar contacts (docs/model.md §4.4).
    pub fn contact_flow_rate(&self) -> f64 {
        self.lees_edwards
            .filter(|le| le.dynamics == ShearDynamics::PeculiarContacts)
            .map_or(0.0, |le| le.shear_rate)
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
            Some(w) => 0.5 * w.angle * (w.outer_radius.powi(2) - w.inner_radius.powi(2)) * l.z,
            None => l.x * l.y * l.z,
        }
    }

    /// The image codes the neighbour search must try besides the translations of the
    /// periodic axes, and for each the map of a query position: a pair `(i, j)` through
    /// image `c` is within `d` when `|T_c⁻¹ r_i − r_j| < d`. Empty without a wedge; the
    /// wedge's images rotate by `±Φ` (codes of offsets `(±1, 0, 0)`), one of them at `Φ = π`.
    pub fn rotated_images(&self) -> Vec<(u8, DMat3)> {
        match &self.wedge {
            None => Vec::new(),
            Some(w) if w.half_turn() => vec![(image_code([1, 0, 0]), w.rotation(-1))],
            Some(w) => vec![
                (image_code([1, 0, 0]), w.rotation(-1)),
                (image_code([-1, 0, 0]), w.rotation(1)),
            ],
        }
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
            return std::array::from_fn(|code| {
                let turns = image_offsets(code as u8)[0];
                ImageTransform {
                    rotation: (turns != 0).then(|| w.rotation(turns)),
                    ..ImageTransform::IDENTITY
                }
            });
        }
        let l = self.lengths();
        let (s, u) = self.lees_edwards.map_or((0.0, 0.0), |le| {
            let jump = if le.dynamics == ShearDynamics::AffineDrag {
                0.0
            } else {
                le.shear_rate * l.y
            };
            (le.shift, jump)
        });
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
            let turns = self.wedge_turns(*position);
            if turns == 0 {
                return ImageTransform::IDENTITY;
            }
            let m = w.rotation(-turns);
            *position = m * *position;
            *velocity = m * *velocity;
            *spin = m * *spin;
            return ImageTransform {
                rotation: Some(m),
                ..ImageTransform::IDENTITY
            };
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
        self.wedge.map_or(0, |w| wedge_turns(w.angle, r))
    }

    fn wrap_translation(&self, position: &mut DVec3, velocity: &mut DVec3) {
        let l = self.lengths();
        if let Some(le) = &self.lees_edwards {
            let jump = if le.dynamics == ShearDynamics::AffineDrag {
                0.0
            } else {
                le.shear_rate * l.y
            };
            let mut k = ((position.y - self.lo.y) / l.y).floor();
            // One more crossing where rounding left y on the boundary.
            for _ in 0..3 {
                if k != 0.0 {
                    position.y -= k * l.y;
                    position.x -= k * le.shift;
                    velocity.x -= k * jump;
                }
                k = if position.y >= self.hi.y {
                    1.0
                } else if position.y < self.lo.y {
                    -1.0
                } else {
                    break;
                };
            }
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

/// How many wedge angles `Φ` the azimuth of `r` lies outside `[0, Φ)`: `⌊φ/Φ⌋` with `φ`
/// measured in `(−π, π]`, corrected where rounding leaves the rotated position on a face.
fn wedge_turns(angle: f64, r: DVec3) -> i32 {
    let phi = r.y.atan2(r.x);
    let mut turns = (phi / angle).floor() as i32;
    // The rotated azimuth must land in [0, Φ); fix the rare off-by-one at a face.
    for _ in 0..2 {
        let back = phi - turns as f64 * angle;
        if back < 0.0 {
            turns -= 1;
        } else if back >= angle {
            turns += 1;
        } else {
            break;
        }
    }
    turns
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
