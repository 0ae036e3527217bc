//! Smooth analytic walls: infinite planes and cylinders, fixed and infinitely heavy, with
//! the contact law of their species (docs/model.md §4.1).

use crate::contact::{ContactHistory, ContactTable, PairKinematics};
use crate::domain::ImageTransform;
use crate::observe::{ContactObserver, ContactView, NO_PART};
use crate::particles::Particles;
use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

/// The geometry of a smooth wall.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum WallShape {
    /// The plane through `point` with unit `normal` pointing into the granular region.
    Plane {
        /// A point on the plane (m).
        point: DVec3,
        /// Unit normal towards the particles.
        normal: DVec3,
    },
    /// The cylinder of `radius` about the axis through `point` along the unit `axis`;
    /// particles are inside it (`inside`, an outer wall) or outside it (an inner wall).
    Cylinder {
        /// A point on the axis (m).
        point: DVec3,
        /// Unit vector along the axis.
        axis: DVec3,
        /// Radius (m).
        radius: f64,
        /// Whether the particles are inside the cylinder.
        inside: bool,
    },
}

impl WallShape {
    /// Gap between the surface and the centre `r` (m, negative behind the wall) and the
    /// unit normal from the wall towards `r`.
    #[inline]
    pub fn gap(&self, r: DVec3) -> (f64, DVec3) {
        match *self {
            WallShape::Plane { point, normal } => ((r - point).dot(normal), normal),
            WallShape::Cylinder {
                point,
                axis,
                radius,
                inside,
            } => {
                let d = r - point;
                let radial = d - axis * d.dot(axis);
                let rho = radial.length();
                // On the axis the direction is arbitrary; any radial unit vector will do.
                let e = if rho > 0.0 {
                    radial / rho
                } else {
                    axis.any_orthonormal_vector()
                };
                if inside {
                    (radius - rho, -e)
                } else {
                    (rho - radius, e)
                }
            }
        }
    }
}

/// A smooth fixed wall.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Wall {
    /// Its geometry.
    pub shape: WallShape,
    /// Species of the wall material (selects the contact law with each particle species).
    pub species: u16,
    /// Wall part it belongs to ([`NO_PART`] for none).
    #[serde(default = "no_part")]
    pub part: u16,
    /// Contact history per particle id (grown as particles are inserted).
    history: Vec<ContactHistory>,
    /// Whether each particle id interacts with the wall.
    active: Vec<bool>,
    /// Slots of the free particles within reach of the wall at the last neighbour build
    /// (`None`: every particle is checked).
    #[serde(skip)]
    candidates: Option<Vec<u32>>,
}

fn no_part() -> u16 {
    NO_PART
}

impl Wall {
    /// A wall of the given shape and species, in no part.
    pub fn new(shape: WallShape, species: u16) -> Wall {
        Wall {
            shape,
            species,
            part: NO_PART,
            history: Vec::new(),
            active: Vec::new(),
            candidates: None,
        }
    }

    /// Lists the free particles whose surface is within `reach` (m: the interaction range
    /// plus the Verlet skin) of the wall, so that until the next neighbour build only they
    /// are checked. The build criterion keeps every displacement below the skin, so no
    /// other particle can come within the interaction range before then; particles left
    /// out here keep no history with the wall (they are beyond its range).
    pub fn find_candidates(&mut self, particles: &Particles, reach: f64) {
        let list = (0..particles.len())
            .filter(|&i| {
                particles.motion[i].is_free()
                    && self.shape.gap(particles.position[i]).0 - particles.radius[i] < reach
            })
            .map(|i| i as u32)
            .collect::<Vec<u32>>();
        // A particle leaving the list is beyond the wall's range: its history ends.
        let mut listed = vec![false; self.active.len()];
        for &i in &list {
            if let Some(l) = listed.get_mut(particles.id[i as usize] as usize) {
                *l = true;
            }
        }
        for (id, l) in listed.iter().enumerate() {
            if !l && self.active[id] {
                self.active[id] = false;
                self.history[id] = ContactHistory::default();
            }
        }
        self.candidates = Some(list);
    }

    /// The plane through `point` (m) with `normal` (normalised here) towards the particles.
    pub fn plane(point: DVec3, normal: DVec3, species: u16) -> Wall {
        Wall::new(
            WallShape::Plane {
                point,
                normal: normal.normalize(),
            },
            species,
        )
    }

    /// A cylinder of `radius` (m) about the axis through `point` along `axis` (normalised
    /// here), with the particles `inside` or outside it.
    pub fn cylinder(point: DVec3, axis: DVec3, radius: f64, inside: bool, species: u16) -> Wall {
        Wall::new(
            WallShape::Cylinder {
                point,
                axis: axis.normalize(),
                radius,
                inside,
            },
            species,
        )
    }

    /// Rotates the history of particle `id` with the particle (a wrap through a wedge face
    /// turned it by `rotation`; the wall is symmetric about the wedge axis).
    pub fn rotate_history(&mut self, id: u32, rotation: DMat3) {
        let image = ImageTransform {
            rotation: Some(rotation),
            ..ImageTransform::IDENTITY
        };
        if let Some(h) = self.history.get_mut(id as usize) {
            *h = h.rotated(&image);
        }
    }

    /// Adds the wall's forces and torques to the free particles, advancing contact history
    /// over `dt` (s), and shows every interacting contact to `obs`; `index` names the wall.
    pub fn apply<O: ContactObserver>(
        &mut self,
        index: u32,
        particles: &mut Particles,
        laws: &ContactTable,
        dt: f64,
        obs: &mut O,
    ) {
        let ids = particles.len();
        if self.history.len() < ids {
            self.history.resize(ids, ContactHistory::default());
            self.active.resize(ids, false);
        }
        let all: Vec<u32>;
        let slots = match &self.candidates {
            Some(c) => c.as_slice(),
            None => {
                all = (0..particles.len() as u32).collect();
                all.as_slice()
            }
        };
        for &slot in slots {
            let i = slot as usize;
            if !particles.motion[i].is_free() {
                continue;
            }
            let id = particles.id[i] as usize;
            let a = particles.radius[i];
            let (gap, normal) = self.shape.gap(particles.position[i]);
            let overlap = a - gap;
            let kernel = laws.kernel(particles.species[i], self.species);
            if overlap <= -kernel.range() {
                if self.active[id] {
                    self.active[id] = false;
                    self.history[id] = ContactHistory::default();
                }
                continue;
            }
            let k = PairKinematics {
                normal,
                overlap,
                radius_i: a,
                radius_j: f64::INFINITY,
                velocity: particles.velocity[i],
                omega_i: particles.angular_velocity[i],
                omega_j: DVec3::ZERO,
                reduced_mass: particles.mass[i],
            };
            let h = &mut self.history[id];
            let Some(f) = kernel.interact(&k, h, dt) else {
                self.active[id] = false;
                continue;
            };
            self.active[id] = true;
            particles.force[i] += f.force;
            particles.torque[i] += f.torque_i;
            if O::OBSERVES {
                obs.visit(&ContactView {
                    ids: [particles.id[i], index],
                    parts: [particles.part[i], self.part],
                    wall: Some(index),
                    image: &ImageTransform::IDENTITY,
                    position: particles.position[i],
                    branch: normal * gap,
                    kinematics: &k,
                    force: &f,
                    kernel,
                    history: h,
                });
            }
        }
    }
}
