//! The angular-periodic wedge `0 ≤ φ < Φ` about the `z` axis (docs/model.md §4.6): its images
//! are rotations by `±Φ`, and a particle leaving through one face re-enters through the other
//! with its position, velocity and spin rotated.

use super::boundary::{Boundary, Frame};
use super::image::{IMAGE_COUNT, ImageTransform, image_code, image_offsets};
use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

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
    /// Volume (m³) of the wedge's sector between its radii over the height `l_z` (m):
    /// `½ Φ (R_o² − R_i²) L_z`.
    pub fn volume(&self, l_z: f64) -> f64 {
        0.5 * self.angle * (self.outer_radius.powi(2) - self.inner_radius.powi(2)) * l_z
    }

    /// The images the neighbour search queries, with the map of a query position: the
    /// rotations by `±Φ` (codes of offsets `(±1, 0, 0)`), one of them at `Φ = π`.
    pub fn rotated_images(&self) -> Vec<(u8, DMat3)> {
        if self.half_turn() {
            vec![(image_code([1, 0, 0]), self.rotation(-1))]
        } else {
            vec![
                (image_code([1, 0, 0]), self.rotation(-1)),
                (image_code([-1, 0, 0]), self.rotation(1)),
            ]
        }
    }

    /// The transformation of every image code: a rotation by `c_x Φ` about `z`.
    pub fn image_transforms(&self) -> [ImageTransform; IMAGE_COUNT] {
        std::array::from_fn(|code| {
            let turns = image_offsets(code as u8)[0];
            ImageTransform {
                rotation: (turns != 0).then(|| self.rotation(turns)),
                ..ImageTransform::IDENTITY
            }
        })
    }

    /// How many wedge angles `Φ` the azimuth of `r` lies outside `[0, Φ)`:
    /// [`Wedge::wrap`] rotates such a particle by `−turns · Φ`.
    pub fn turns(&self, r: DVec3) -> i32 {
        wedge_turns(self.angle, r)
    }

    /// Brings a particle that left through a face back into the wedge: position, velocity
    /// and spin rotated by `−turns · Φ`; returns the rotation applied.
    pub fn wrap(
        &self,
        position: &mut DVec3,
        velocity: &mut DVec3,
        spin: &mut DVec3,
    ) -> ImageTransform {
        let turns = self.turns(*position);
        if turns == 0 {
            return ImageTransform::IDENTITY;
        }
        let m = self.rotation(-turns);
        *position = m * *position;
        *velocity = m * *velocity;
        *spin = m * *spin;
        ImageTransform {
            rotation: Some(m),
            ..ImageTransform::IDENTITY
        }
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

impl Boundary for Wedge {
    /// The sector `½ Φ (R_o² − R_i²) L_z`.
    fn volume(&self, frame: &Frame) -> f64 {
        Wedge::volume(self, frame.lengths().z)
    }

    fn rotated_images(&self) -> Vec<(u8, DMat3)> {
        Wedge::rotated_images(self)
    }

    /// Its `x` offset: the images rotate by `c_x Φ`.
    #[inline]
    fn image_turns(&self, code: u8) -> i32 {
        image_offsets(code)[0]
    }

    fn turns(&self, r: DVec3) -> i32 {
        Wedge::turns(self, r)
    }

    fn image_transforms(&self, _frame: &Frame) -> [ImageTransform; IMAGE_COUNT] {
        Wedge::image_transforms(self)
    }

    fn wrap(
        &self,
        _frame: &Frame,
        position: &mut DVec3,
        velocity: &mut DVec3,
        spin: &mut DVec3,
    ) -> ImageTransform {
        Wedge::wrap(self, position, velocity, spin)
    }
}
