//! Neighbour search: linked cells feeding a Verlet list with a skin.
//!
//! The list is a *half* list in compressed-row form: for each particle slot `i`, the
//! partners `j > i` within `a_i + a_j + range + skin`, each with the image code of `j`
//! (see [`crate::domain`]). Contact history lives beside the pairs and is keyed by the
//! particles' permanent ids when the list is rebuilt, so it survives rebuilds and the
//! re-sorting of particles by cell that every rebuild performs for memory locality.
//!
//! A rebuild is due when two particles could have closed the skin since the last build.
//! Displacements are measured relative to the box's affine motion since the build (the
//! mean shear flow of Lees-Edwards boundaries, a compression or dilation): with `A` that
//! affine map minus the identity, `d_i` the non-affine displacements and `r_c` the largest
//! interaction cutoff, a pair outside the list (at least `r_c + skin` apart at the build)
//! can have come within reach only once `(1 + ‖A‖)(d_1 + d_2) + ‖A‖ (r_c + skin) ≥ skin`,
//! `d_1`, `d_2` the two largest `|d_i|`. Under
//! steady shear this rebuilds far less often than lab-frame displacement, which counts the
//! mean flow itself.

use crate::contact::ContactHistory;
use crate::domain::{Domain, IDENTITY_IMAGE, IMAGE_COUNT, ImageTransform, image_code};
use crate::integrate::PARTICLES_PER_TASK;
use crate::particles::{Motion, Particles};
use glam::{DMat3, DVec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};

/// Errors of the neighbour search.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum NeighborError {
    /// A periodic axis is shorter than three interaction cutoffs.
    #[error(
        "the box is too small along periodic axis {axis}: length {length:.6e} m must be at least \
         3 × the neighbour cutoff ({cutoff:.6e} m = largest diameter + interaction range + skin)"
    )]
    BoxTooSmall {
        /// Axis name (`x`, `y`, `z`).
        axis: char,
        /// Box length along it (m).
        length: f64,
        /// The neighbour cutoff (m).
        cutoff: f64,
    },
    /// A wedge so narrow that a particle near its inner radius would reach its own image.
    #[error(
        "the wedge is too narrow: at its inner radius {radius:.6e} m an angle of {angle_deg:.4}° \
         leaves a chord shorter than the reach of a particle to its own image ({cutoff:.6e} m = \
         largest diameter + interaction range); the angle must be at least {min_deg:.4}°"
    )]
    WedgeTooNarrow {
        /// The wedge's inner radius (m).
        radius: f64,
        /// The wedge angle (degrees).
        angle_deg: f64,
        /// The reach (m).
        cutoff: f64,
        /// The smallest angle that works (degrees).
        min_deg: f64,
    },
}

/// The smallest wedge angle (rad) whose chord `2 r sin(Φ/2)` at radius `radius` (m) is at
/// least `reach` (m), so that no particle reaches its own image; `None` if no angle up to
/// `π` does.
pub fn min_wedge_angle(radius: f64, reach: f64) -> Option<f64> {
    let s = reach / (2.0 * radius);
    (radius > 0.0 && s <= 1.0).then(|| 2.0 * s.asin())
}

/// Particles per block of the parallel neighbour build.
const BUILD_BLOCK: usize = 256;

/// Verlet list with contact history.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct NeighborList {
    /// Skin distance added to every cutoff (m).
    pub skin: f64,
    /// Interaction range beyond contact kept in the list (m); zero for contact-only laws.
    pub range: f64,
    offsets: Vec<u32>,
    partner: Vec<u32>,
    image: Vec<u8>,
    active: Vec<bool>,
    history: Vec<ContactHistory>,
    reference_position: Vec<DVec3>,
    reference_deformation: DMat3,
    reference_epoch: u64,
    reference_lo: DVec3,
    interaction_cutoff: f64,
    #[serde(skip)]
    last_rotations: Vec<(u32, DMat3)>,
    /// Number of builds so far.
    pub builds: u64,
}

/// Read-only and mutable views of the list used by the force loop.
pub struct PairSlices<'a> {
    /// Row offsets: the pairs of slot `i` are `offsets[i]..offsets[i + 1]`.
    pub offsets: &'a [u32],
    /// Partner slot `j` of each pair.
    pub partner: &'a [u32],
    /// Image code of `j` for each pair.
    pub image: &'a [u8],
    /// Whether each pair carries live history (in contact or attracting).
    pub active: &'a mut [bool],
    /// Contact history of each pair.
    pub history: &'a mut [ContactHistory],
}

impl NeighborList {
    /// An empty list with the given skin and interaction range (m); it builds on first use.
    pub fn new(skin: f64, range: f64) -> NeighborList {
        NeighborList {
            skin,
            range,
            ..NeighborList::default()
        }
    }

    /// Number of pairs in the list.
    pub fn len(&self) -> usize {
        self.partner.len()
    }

    /// Whether the list has no pairs.
    pub fn is_empty(&self) -> bool {
        self.partner.is_empty()
    }

    /// Views for the force loop.
    pub fn slices(&mut self) -> PairSlices<'_> {
        PairSlices {
            offsets: &self.offsets,
            partner: &self.partner,
            image: &self.image,
            active: &mut self.active,
            history: &mut self.history,
        }
    }

    /// Whether the list must be rebuilt before the next force evaluation.
    pub fn needs_rebuild(&self, particles: &Particles, domain: &Domain) -> bool {
        if self.reference_position.len() != particles.len()
            || domain.image_epoch() != self.reference_epoch
        {
            return true;
        }
        let affine = domain.deformation * self.reference_deformation.inverse() - DMat3::IDENTITY;
        let norm = (affine.x_axis.length_squared()
            + affine.y_axis.length_squared()
            + affine.z_axis.length_squared())
        .sqrt();
        // The two largest non-affine displacements (squared); max is order-independent, so
        // the parallel reduction is deterministic.
        let lo = self.reference_lo;
        let top2 = |a: (f64, f64), d: f64| {
            if d > a.0 {
                (d, a.0)
            } else if d > a.1 {
                (a.0, d)
            } else {
                a
            }
        };
        let (first, second) = particles
            .position
            .par_iter()
            .zip(self.reference_position.par_iter())
            .with_min_len(1024)
            .fold(
                || (0.0f64, 0.0f64),
                |acc, (r, r0)| top2(acc, (*r - *r0 - affine * (*r0 - lo)).length_squared()),
            )
            .reduce(|| (0.0, 0.0), |a, b| top2(top2(a, b.0), b.1));
        (1.0 + norm) * (first.sqrt() + second.sqrt()) + norm * (self.interaction_cutoff + self.skin)
            >= self.skin
    }

    /// Rebuilds the list: wraps positions into the region, re-sorts particles by cell, finds
    /// all pairs within cutoff and carries the contact history over by particle ids and the
    /// pair's wedge image. Particles appended since the last build (insertion) start
    /// without history; every other pair keeps its springs and bridges.
    pub fn build(
        &mut self,
        particles: &mut Particles,
        domain: &Domain,
    ) -> Result<(), NeighborError> {
        // Wrap first, remembering the wedge turns of every particle (by id) so that the
        // history of a pair follows its particles through the faces.
        let images = domain.image_transforms();
        let moves: Vec<(u32, i32, DMat3)> = particles
            .position
            .par_iter_mut()
            .zip(particles.velocity.par_iter_mut())
            .zip(particles.angular_velocity.par_iter_mut())
            .zip(particles.motion.par_iter_mut())
            .zip(particles.id.par_iter())
            .with_min_len(PARTICLES_PER_TASK)
            .filter_map(|((((r, v), w), motion), &id)| {
                let k = domain.wedge_turns(*r);
                let moved = domain.wrap(r, v, w);
                // A rotating wall particle moved to its periodic image rotates about the
                // image of its axis.
                if let Motion::Rotating { center, axis, .. } = motion {
                    *center = moved.position(*center);
                    *axis = moved.angular_velocity(*axis);
                }
                moved.rotation.map(|m| (id, k, m))
            })
            .collect();
        let mut turns = vec![0i32; particles.len()];
        let mut rotated = Vec::with_capacity(moves.len());
        for (id, k, m) in moves {
            turns[id as usize] = k;
            rotated.push((id, m));
        }
        self.last_rotations = rotated;
        let old = self.history_by_key(particles, domain, &images, &turns);

        let a_max = particles.radius.iter().copied().fold(0.0, f64::max);
        let cutoff = 2.0 * a_max + self.range + self.skin;
        if let Some(w) = &domain.wedge {
            let reach = 2.0 * a_max + self.range;
            if 2.0 * w.inner_radius * (0.5 * w.angle).sin() < reach {
                return Err(NeighborError::WedgeTooNarrow {
                    radius: w.inner_radius,
                    angle_deg: w.angle.to_degrees(),
                    cutoff: reach,
                    min_deg: min_wedge_angle(w.inner_radius, reach)
                        .map_or(f64::INFINITY, f64::to_degrees),
                });
            }
        }
        let grid = CellGrid::new(domain, cutoff)?;

        // Stable counting sort by cell: deterministic, and neighbours end up close in memory.
        let cell_of: Vec<u32> = particles
            .position
            .par_iter()
            .with_min_len(PARTICLES_PER_TASK)
            .map(|r| grid.cell_index(*r))
            .collect();
        let mut start = vec![0u32; grid.count() + 1];
        for &c in &cell_of {
            start[c as usize + 1] += 1;
        }
        for c in 0..grid.count() {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut order = vec![0u32; particles.len()];
        for (slot, &c) in cell_of.iter().enumerate() {
            order[fill[c as usize] as usize] = slot as u32;
            fill[c as usize] += 1;
        }
        particles.permute(&order);

        self.find_pairs(particles, &grid, &start, domain);

        self.active = vec![false; self.partner.len()];
        self.history = vec![ContactHistory::default(); self.partner.len()];
        if !old.is_empty() {
            let (offsets, partner, image, ids) =
                (&self.offsets, &self.partner, &self.image, &particles.id);
            let restored: Vec<Vec<(usize, ContactHistory)>> =
                (0..particles.len().div_ceil(BUILD_BLOCK))
                    .into_par_iter()
                    .map(|b| {
                        let mut found = Vec::new();
                        for i in b * BUILD_BLOCK..((b + 1) * BUILD_BLOCK).min(particles.len()) {
                            let id_i = ids[i];
                            for k in offsets[i] as usize..offsets[i + 1] as usize {
                                let id_j = ids[partner[k] as usize];
                                let c = domain.image_turns(image[k]);
                                let h = if id_i < id_j {
                                    old.get(&(id_i, id_j, c)).copied()
                                } else {
                                    // Kept in j's frame for the order (j, i): flip the order
                                    // and rotate into i's frame, where j is seen through
                                    // this pair's image.
                                    old.get(&(id_j, id_i, -c))
                                        .map(|h| h.flipped().rotated(&images[image[k] as usize]))
                                };
                                if let Some(h) = h {
                                    found.push((k, h));
                                }
                            }
                        }
                        found
                    })
                    .collect();
            for (k, h) in restored.into_iter().flatten() {
                self.active[k] = true;
                self.history[k] = h;
            }
        }

        self.reference_position = particles.position.clone();
        self.reference_deformation = domain.deformation;
        self.reference_epoch = domain.image_epoch();
        self.reference_lo = domain.lo;
        self.interaction_cutoff = 2.0 * a_max + self.range;
        self.builds += 1;
        Ok(())
    }

    /// The particles (ids) that the last build rotated through a wedge face, with the
    /// rotation applied; analytic walls rotate their per-particle history with them.
    pub fn last_rotations(&self) -> &[(u32, DMat3)] {
        &self.last_rotations
    }

    /// Live contact histories of the list as it stood before this build, keyed by
    /// `(lower id, higher id, wedge turns of the higher seen from the lower)` and expressed
    /// in the lower particle's frame after this build's wraps (`turns[id]` multiples of
    /// `Φ`, the particle rotated by `−turns·Φ`). Under translations only, the key's turns
    /// are zero and histories are not transformed: a box of at least three cutoffs per
    /// periodic axis sees each pair through one image only.
    fn history_by_key(
        &self,
        particles: &Particles,
        domain: &Domain,
        images: &[ImageTransform; IMAGE_COUNT],
        turns: &[i32],
    ) -> FxHashMap<(u32, u32, i32), ContactHistory> {
        let mut map = FxHashMap::default();
        // Rows exist for the particles present at the last build; particles appended since
        // (insertion) sit in the slots after them and have no history yet.
        let rows = self.offsets.len().saturating_sub(1).min(particles.len());
        let turn = |id: u32| turns[id as usize];
        let into_frame = |h: ContactHistory, id: u32| match domain.wedge {
            Some(w) if turn(id) != 0 => h.rotated(&ImageTransform {
                rotation: Some(w.rotation(-turn(id))),
                ..ImageTransform::IDENTITY
            }),
            _ => h,
        };
        for i in 0..rows {
            let id_i = particles.id[i];
            for k in self.offsets[i] as usize..self.offsets[i + 1] as usize {
                if !self.active[k] {
                    continue;
                }
                let id_j = particles.id[self.partner[k] as usize];
                let h = self.history[k];
                let c = domain.image_turns(self.image[k]);
                // j's image `R(cΦ) r_j` lies next to `r_i`; after the wraps `r_i → R(−t_i Φ) r_i`,
                // `r_j → R(−t_j Φ) r_j` it is `R((c − t_i + t_j) Φ) r_j`: the key's turns are
                // `c − t_i + t_j` (the signs of `t` were once reversed, which lost the
                // history of every pair whose particle wrapped through a face).
                if id_i < id_j {
                    let key = (id_i, id_j, c - turn(id_i) + turn(id_j));
                    map.insert(key, into_frame(h, id_i));
                } else {
                    let seen_from_j = h.rotated_back(&images[self.image[k] as usize]).flipped();
                    let key = (id_j, id_i, -c - turn(id_j) + turn(id_i));
                    map.insert(key, into_frame(seen_from_j, id_j));
                }
            }
        }
        map
    }

    /// Finds every pair within cutoff, rows in blocks of particles searched in parallel and
    /// concatenated in slot order (so the list does not depend on the thread count). Each
    /// particle searches the cells around itself (with the translations of the periodic
    /// axes) and, near a wedge face, around the rotated query position of each wedge image.
    fn find_pairs(
        &mut self,
        particles: &Particles,
        grid: &CellGrid,
        start: &[u32],
        domain: &Domain,
    ) {
        let n = particles.len();
        let pos = &particles.position;
        let rad = &particles.radius;
        let free: Vec<bool> = particles.motion.iter().map(|m| m.is_free()).collect();
        let reach = self.range + self.skin;
        let cutoff = grid.cutoff;
        let rotated = domain.rotated_images();
        let images = domain.image_transforms();
        let wedge = domain.wedge;
        let row_of = |i: usize, row: &mut Vec<(u32, u8)>| {
            row.clear();
            let ci = grid.cell_coords(pos[i]);
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let Some((cell, img)) = grid.neighbor(pos[i], ci, [dx, dy, dz]) else {
                            continue;
                        };
                        // The domain's transform of this image (a translation here).
                        let code = image_code(img);
                        let shift = images[code as usize].shift;
                        let (lo, hi) = (start[cell] as usize, start[cell + 1] as usize);
                        for j in lo.max(i + 1)..hi.max(i + 1) {
                            if !free[i] && !free[j] {
                                continue;
                            }
                            let cut = rad[i] + rad[j] + reach;
                            let d = pos[i] - (pos[j] + shift);
                            if d.length_squared() < cut * cut {
                                row.push((j as u32, code));
                            }
                        }
                    }
                }
            }
            // Wedge images: j seen at R r_j is within reach of r_i where R⁻¹ r_i is within
            // reach of r_j; only query positions within a cutoff of the wedge can find one.
            for &(code, inverse) in &rotated {
                let q = inverse * pos[i];
                if wedge.is_some_and(|w| w.distance(q) >= cutoff) {
                    continue;
                }
                let image = &images[code as usize];
                let cq = grid.cell_coords(q);
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            let Some((cell, _)) = grid.neighbor(q, cq, [dx, dy, dz]) else {
                                continue;
                            };
                            let (lo, hi) = (start[cell] as usize, start[cell + 1] as usize);
                            for j in lo.max(i + 1)..hi.max(i + 1) {
                                if !free[i] && !free[j] {
                                    continue;
                                }
                                let cut = rad[i] + rad[j] + reach;
                                let d = pos[i] - image.position(pos[j]);
                                if d.length_squared() < cut * cut {
                                    row.push((j as u32, code));
                                }
                            }
                        }
                    }
                }
            }
            // Partners sorted by slot for a predictable memory walk.
            row.sort_unstable();
        };
        let blocks: Vec<(Vec<u32>, Vec<u32>, Vec<u8>)> = (0..n.div_ceil(BUILD_BLOCK))
            .into_par_iter()
            .map(|b| {
                let (mut lens, mut partner, mut image) = (Vec::new(), Vec::new(), Vec::new());
                let mut row = Vec::new();
                for i in b * BUILD_BLOCK..((b + 1) * BUILD_BLOCK).min(n) {
                    row_of(i, &mut row);
                    lens.push(row.len() as u32);
                    partner.extend(row.iter().map(|p| p.0));
                    image.extend(row.iter().map(|p| p.1));
                }
                (lens, partner, image)
            })
            .collect();
        self.offsets.clear();
        self.partner.clear();
        self.image.clear();
        self.offsets.reserve(n + 1);
        self.offsets.push(0);
        for (lens, partner, image) in blocks {
            for len in lens {
                let last = *self.offsets.last().unwrap_or(&0);
                self.offsets.push(last + len);
            }
            self.partner.extend(partner);
            self.image.extend(image);
        }
    }

    /// Splits the slots `0..n` into `chunks` contiguous ranges with about equal pair counts;
    /// returns the `chunks + 1` boundaries.
    pub fn chunk_bounds(&self, chunks: usize) -> Vec<usize> {
        let n = self.offsets.len().saturating_sub(1);
        let total = self.partner.len() + n;
        let mut bounds = Vec::with_capacity(chunks + 1);
        bounds.push(0);
        for c in 1..chunks {
            let target = total * c / chunks;
            // First slot whose cumulative work (pairs + particles before it) reaches the target.
            let (mut lo, mut hi) = (0usize, n);
            while lo < hi {
                let mid = (lo + hi) / 2;
                if self.offsets[mid] as usize + mid < target {
                    lo = mid + 1;
                } else {
                    hi = mid;
                }
            }
            bounds.push(lo.max(bounds[c - 1]));
        }
        bounds.push(n);
        bounds
    }

    /// Whether any pair crosses a periodic boundary (image code other than identity).
    pub fn has_images(&self) -> bool {
        self.image.iter().any(|&c| c != IDENTITY_IMAGE)
    }

    /// Number of touching partners (`δ > 0`) of every particle slot, from the current
    /// positions and the domain's current images.
    pub fn contact_counts(&self, particles: &Particles, domain: &Domain) -> Vec<u32> {
        let images = domain.image_transforms();
        let mut count = vec![0u32; particles.len()];
        for i in 0..self.offsets.len().saturating_sub(1) {
            for k in self.offsets[i] as usize..self.offsets[i + 1] as usize {
                let j = self.partner[k] as usize;
                let code = self.image[k];
                let r_j = if code == IDENTITY_IMAGE {
                    particles.position[j]
                } else {
                    images[code as usize].position(particles.position[j])
                };
                let sum = particles.radius[i] + particles.radius[j];
                if (particles.position[i] - r_j).length_squared() < sum * sum {
                    count[i] += 1;
                    count[j] += 1;
                }
            }
        }
        count
    }
}

/// Linked-cell grid over the box.
struct CellGrid {
    lo: DVec3,
    lengths: DVec3,
    dims: [usize; 3],
    periodic: [bool; 3],
    /// Lees-Edwards shift of the images across `y` (m); zero without shear.
    shear_shift: f64,
    /// The neighbour cutoff the cells are sized for (m).
    cutoff: f64,
}

impl CellGrid {
    fn new(domain: &Domain, cutoff: f64) -> Result<CellGrid, NeighborError> {
        let lengths = domain.lengths();
        let mut dims = [1usize; 3];
        for axis in 0..3 {
            let n = (lengths[axis] / cutoff).floor().max(1.0) as usize;
            if domain.periodic[axis] && n < 3 {
                return Err(NeighborError::BoxTooSmall {
                    axis: ['x', 'y', 'z'][axis],
                    length: lengths[axis],
                    cutoff,
                });
            }
            // Bounded so that a huge box with tiny particles cannot exhaust memory.
            dims[axis] = n.min(1 << 10);
        }
        Ok(CellGrid {
            lo: domain.lo,
            lengths,
            dims,
            periodic: domain.periodic,
            shear_shift: domain.lees_edwards.map_or(0.0, |le| le.shift),
            cutoff,
        })
    }

    fn count(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    fn cell_coords(&self, r: DVec3) -> [i64; 3] {
        std::array::from_fn(|a| {
            let c = ((r[a] - self.lo[a]) / self.lengths[a] * self.dims[a] as f64).floor();
            (c.max(0.0) as i64).min(self.dims[a] as i64 - 1)
        })
    }

    fn cell_index(&self, r: DVec3) -> u32 {
        let c = self.cell_coords(r);
        (c[0] as usize + self.dims[0] * (c[1] as usize + self.dims[1] * c[2] as usize)) as u32
    }

    /// The cell at offset `d` from cell `c` (which holds position `r`), wrapped through
    /// periodic axes, with the image offset of the wrap; `None` past a non-periodic edge.
    /// Across `y` under Lees-Edwards shear the image row is shifted by `s` in `x`, so the
    /// `x` offset is taken around the cell of `x − c_y s`.
    fn neighbor(&self, r: DVec3, c: [i64; 3], d: [i32; 3]) -> Option<(usize, [i32; 3])> {
        let mut img = [0i32; 3];
        let mut cc = [0usize; 3];
        for a in [2, 1, 0] {
            let n = self.dims[a] as i64;
            let mut x = if a == 0 && img[1] != 0 {
                let shifted = r.x - img[1] as f64 * self.shear_shift;
                ((shifted - self.lo.x) / self.lengths.x * n as f64).floor() as i64 + d[0] as i64
            } else {
                c[a] + d[a] as i64
            };
            if x < 0 || x >= n {
                if !self.periodic[a] {
                    return None;
                }
                let k = x.div_euclid(n);
                img[a] = k as i32;
                x -= k * n;
            }
            cc[a] = x as usize;
        }
        Some((cc[0] + self.dims[0] * (cc[1] + self.dims[1] * cc[2]), img))
    }
}
