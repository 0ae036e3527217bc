//! The simulation box: its extent, which axes are periodic, and the periodic images.
//!
//! A pair that interacts across a periodic boundary is stored in the neighbour list with an
//! *image code*: which copy of the second particle it sees. The code is fixed between list
//! builds while the geometric transformation it stands for may change every step (a box that
//! is compressed now; a Lees-Edwards shift or a rotated wedge image later). The force loop
//! asks the domain for the current [`ImageTransform`] of every code once per step.

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
        match self.rotation {
            None => w,
            Some(m) => m * w,
        }
    }
}

/// Lees-Edwards boundaries in the lab-frame convention (docs/model.md §4.3): shear along `x`,
/// gradient along `y`. The image across `y = L_y` is shifted by `shift` in `x` and moves
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
    /// "Peculiar contacts", for comparison only (docs/model.md §4.4): relative velocities at
    /// contacts exclude the mean-flow difference `γ̇ (y_i − y_j) x̂`, as in codes that move
    /// particles affinely and integrate only velocities relative to the mean flow. The
    /// default (false) is the lab frame, where damping and springs see the mean shear.
    #[serde(default)]
    pub peculiar_contacts: bool,
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
            deformation: DMat3::IDENTITY,
        }
    }

    /// Adds Lees-Edwards shear at rate `shear_rate` (1/s), shift zero.
    pub fn with_lees_edwards(mut self, shear_rate: f64) -> Domain {
        self.lees_edwards = Some(LeesEdwards {
            shear_rate,
            shift: 0.0,
            wraps: 0,
            peculiar_contacts: false,
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
            .filter(|le| le.peculiar_contacts)
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

    /// Box volume (m³).
    pub fn volume(&self) -> f64 {
        let l = self.lengths();
        l.x * l.y * l.z
    }

    /// The current transformation of every image code. Under Lees-Edwards shear the images
    /// across `y` are shifted by `c_y s` in `x` and move `c_y γ̇ L_y` faster in `x`.
    pub fn image_transforms(&self) -> [ImageTransform; IMAGE_COUNT] {
        let l = self.lengths();
        let (s, u) = self
            .lees_edwards
            .map_or((0.0, 0.0), |le| (le.shift, le.shear_rate * l.y));
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

    /// Maps a particle back into the primary box along its periodic axes. Crossing `y`
    /// under Lees-Edwards shear also shifts `x` by `∓s` and `v_x` by `∓γ̇ L_y`.
    pub fn wrap(&self, position: &mut DVec3, velocity: &mut DVec3) {
        let l = self.lengths();
        if let Some(le) = &self.lees_edwards {
            let mut k = ((position.y - self.lo.y) / l.y).floor();
            // One more crossing where rounding left y on the boundary.
            for _ in 0..3 {
                if k != 0.0 {
                    position.y -= k * l.y;
                    position.x -= k * le.shift;
                    velocity.x -= k * le.shear_rate * l.y;
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

    /// Scales the box along `y` about its lower corner by `factor`, with the `y` coordinates;
    /// velocities relative to the mean flow are scaled along `y` and kept along `x` (the mean
    /// flow `γ̇ (y − lo_y)` follows the moved coordinate).
    pub fn scale_y(&mut self, factor: f64, positions: &mut [DVec3], velocities: &mut [DVec3]) {
        let rate = self.lees_edwards.map_or(0.0, |le| le.shear_rate);
        for (r, v) in positions.iter_mut().zip(velocities.iter_mut()) {
            let dy = (r.y - self.lo.y) * (factor - 1.0);
            r.y += dy;
            v.x += rate * dy;
            v.y *= factor;
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
        let mut v = DVec3::ZERO;
        d.wrap(&mut r, &mut v);
        assert_eq!(r, DVec3::new(1.5, 0.5, 3.0));
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
