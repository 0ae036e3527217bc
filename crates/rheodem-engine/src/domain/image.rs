//! Image codes (which of the 3×3×3 neighbouring copies of the region a pair sees) and the
//! map of a particle onto one of its images.

use glam::{DMat3, DVec3};

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
