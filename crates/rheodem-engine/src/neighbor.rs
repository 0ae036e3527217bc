//! Neighbour search: linked cells feeding a Verlet list with a skin.
//!
//! The list is a *half* list in compressed-row form: for each particle slot `i`, the
//! partners `j > i` within `a_i + a_j + range + skin`, each with the image code of `j`
//! (see [`crate::domain`]). Contact history lives beside the pairs, one slot per pair
//! ([`HistorySlots`]). A rebuild re-sorts the particles by cell for memory locality and
//! carries every live history over to the pair's new slot: the old list's pairs are
//! renamed through the sort's permutation and gathered into short rows by their new
//! lower slot, which the new list then reads in order (no hashing, no search).
//!
//! A rebuild is due when two particles could have closed the skin since the last build,
//! displacements measured relative to the box's affine motion ([`crate::displacement`]).
//! Under steady shear this rebuilds far less often than lab-frame displacement, which
//! counts the mean flow itself. Between rebuilds the force loop scans an inner list, the
//! pairs within a smaller margin of reach, pruned every few steps ([`crate::prune`]).

use crate::cell_walk::{Candidates, Run};
use crate::contact::{ContactHistory, HistorySlots, HistoryView};
use crate::displacement::{Moves, affine_norm, moves};
use crate::domain::{Domain, IDENTITY_IMAGE, IMAGE_COUNT, ImageTransform, image_code};
use crate::integrate::PARTICLES_PER_TASK;
use crate::particles::{Motion, Particles};
use crate::prune::PrunePlan;
use crate::team::Team;
use glam::{DMat3, DVec3};
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

/// The process-wide source of list structure stamps (from 1: zero is none).
static NEXT_STRUCTURE: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// Particles per block of the parallel neighbour build.
const BUILD_BLOCK: usize = 256;

/// An infinite range (m).
fn unbounded() -> f64 {
    f64::INFINITY
}

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
    history: HistorySlots,
    reference_position: Vec<DVec3>,
    reference_deformation: DMat3,
    reference_epoch: u64,
    reference_lo: DVec3,
    interaction_cutoff: f64,
    #[serde(skip)]
    last_rotations: Vec<(u32, DMat3)>,
    /// The range beyond contact (m) within which the last build kept the pairs without a
    /// bridge ([`NeighborList::build`]); infinite when it kept them all, and for a list
    /// read back from a checkpoint (built for the laws stored with it).
    #[serde(skip, default = "unbounded")]
    unbridged_range: f64,
    /// Buffers of the history carried over the last rebuild, reused by the next.
    #[serde(skip)]
    carried: CarriedHistory,
    /// Number of builds so far.
    pub builds: u64,
    /// The particle count the list's structure was last found to fit ([`NeighborList::fits`]);
    /// cleared by every build.
    #[serde(skip)]
    fits_count: Option<usize>,
    /// The first slot `i` (the row) of each pair, written by [`NeighborList::fits`] from
    /// the row offsets, so that the force loop walks the pairs in one flat loop.
    #[serde(skip)]
    first: Vec<u32>,
    /// A process-unique stamp of the pair structure `first` was written for, so that what
    /// the force loop derives from the structure (its chunks' halos) is never taken for
    /// another list's or an older build's.
    #[serde(skip)]
    structure: u64,
    /// Which pairs the force loop scans ([`crate::prune`]).
    #[serde(skip)]
    prune: PrunePlan,
    /// Positions at the last prune (m).
    #[serde(skip)]
    prune_position: Vec<DVec3>,
    /// The box's deformation at the last prune.
    #[serde(skip)]
    prune_deformation: DMat3,
    /// The box's lower corner at the last prune (m).
    #[serde(skip)]
    prune_lo: DVec3,
    /// The two largest non-affine displacements since the build, summed, at the last
    /// prune (m).
    #[serde(skip)]
    prune_build_sum: f64,
}

/// Read-only and mutable views of the list used by the force loop.
pub struct PairSlices<'a> {
    /// Row offsets: the pairs of slot `i` are `offsets[i]..offsets[i + 1]`.
    pub offsets: &'a [u32],
    /// First slot `i` of each pair (its row).
    pub first: &'a [u32],
    /// Partner slot `j` of each pair.
    pub partner: &'a [u32],
    /// Image code of `j` for each pair.
    pub image: &'a [u8],
    /// Whether each pair carries live history (in contact or attracting).
    pub active: &'a mut [bool],
    /// Contact history of each pair.
    pub history: HistoryView<'a>,
    /// Which pairs the force loop scans.
    pub prune: &'a PrunePlan,
    /// A process-unique stamp of the list's pair structure (it changes with every build
    /// and every check by [`NeighborList::fits`] that rewrites the rows).
    pub structure: u64,
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

    /// Whether the list's structure fits `n` particles: `n + 1` non-decreasing row offsets
    /// from zero to the pair count, one image code (below `IMAGE_COUNT`), activity flag and
    /// history slot per pair, and every partner a slot below `n` and above its row (a half
    /// list: the force loop's chunks clear and sum the forces on that guarantee). The
    /// force loop reads the
    /// particle arrays and the pair slots without bounds checks on this guarantee. The
    /// answer is remembered until the next build, so the scan runs once per build (or per
    /// list read from a checkpoint). A list that fits also learns the row of each pair.
    pub fn fits(&mut self, n: usize) -> bool {
        if self.fits_count == Some(n) {
            return true;
        }
        let pairs = self.partner.len();
        let fits = self.offsets.len() == n + 1
            && self.offsets[0] == 0
            && self.offsets.windows(2).all(|w| w[0] <= w[1])
            && self.offsets[n] as usize == pairs
            && self.image.len() == pairs
            && self.active.len() == pairs
            && self.history.len() == pairs
            && self.partner.iter().all(|&j| (j as usize) < n)
            && self.image.iter().all(|&c| usize::from(c) < IMAGE_COUNT)
            && self.offsets.windows(2).enumerate().all(|(i, row)| {
                self.partner[row[0] as usize..row[1] as usize]
                    .iter()
                    .all(|&j| j as usize > i)
            });
        if fits {
            self.first.clear();
            self.first.reserve(pairs);
            for (i, row) in self.offsets.windows(2).enumerate() {
                let len = (row[1] - row[0]) as usize;
                self.first.extend(std::iter::repeat_n(i as u32, len));
            }
            self.fits_count = Some(n);
            self.structure = NEXT_STRUCTURE.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
        fits
    }

    /// Views for the force loop.
    pub fn slices(&mut self) -> PairSlices<'_> {
        PairSlices {
            offsets: &self.offsets,
            first: &self.first,
            partner: &self.partner,
            image: &self.image,
            active: &mut self.active,
            history: self.history.view(),
            prune: &self.prune,
            structure: self.structure,
        }
    }

    /// Whether the list must be rebuilt before the next force evaluation (the particles'
    /// displacements are checked by the members of `team`), for laws that need the pairs
    /// without a bridge within `unbridged_range` (m) beyond contact (see
    /// [`NeighborList::build`]). Call it whenever the particles have moved, before the
    /// forces: it also plans which pairs the force loop scans ([`crate::prune`]). While the
    /// pairs kept by the last prune still hold every pair within reach, only their margin
    /// is checked; otherwise the skin, and a list that keeps its skin prunes again.
    pub fn needs_rebuild(
        &mut self,
        particles: &Particles,
        domain: &Domain,
        team: &Team,
        unbridged_range: f64,
    ) -> bool {
        if self.reference_position.len() != particles.len()
            || domain.image_epoch() != self.reference_epoch
            || unbridged_range > self.unbridged_range
        {
            return true;
        }
        // While a prune holds, the displacements since it are checked, and they bound
        // those since the build (`NeighborList::bound_since_build`), so that the build's
        // need not be checked as well (one pass over the particles rather than two). The
        // list is rebuilt at the same steps as without the inner list: whenever the bound
        // does not settle that, the displacements since the build are checked exactly.
        let mut holds = false;
        if self.prune.is_active() && self.prune_position.len() == particles.len() {
            let margin = self.prune.margin;
            let since_prune = moves(
                particles,
                domain,
                team,
                (&self.prune_position, self.prune_deformation, self.prune_lo),
            );
            // A pair left out by the prune was at least `margin` beyond reach then, up to
            // the rounding of the prune's distance test (relative 1e-15), which the factor
            // below covers many times over.
            holds = since_prune.closing(self.interaction_cutoff + margin) < margin * (1.0 - 1e-9);
            if holds && self.bound_since_build(domain, since_prune) < self.skin {
                return false;
            }
        }
        let since_build = moves(
            particles,
            domain,
            team,
            (
                &self.reference_position,
                self.reference_deformation,
                self.reference_lo,
            ),
        );
        let closed = since_build.closing(self.interaction_cutoff + self.skin);
        if closed >= self.skin {
            return true;
        }
        if !holds {
            self.prune_at(particles, domain, self.skin - closed, since_build.sum);
        }
        false
    }

    /// An upper bound on how far the skin may have closed since the build, from the
    /// particles' moves since the last prune and the two largest non-affine displacements
    /// `p₁ + p₂` since the build then, with a margin for rounding (relative 1e-9).
    ///
    /// With `u_i` the non-affine displacement since the build (`A` the affine map minus
    /// the identity since then), `v_i` that since the prune (`B` likewise) and `lo_b`,
    /// `lo_p` the lower corners at the two: `A(t) − A(t_p) = B(t) (I + A(t_p))`, whence
    /// `u_i(t) = u_i(t_p) + v_i(t) + B(t) (u_i(t_p) + lo_b − lo_p)` and
    /// `d₁ + d₂ ≤ (1 + ‖B‖)(p₁ + p₂) + (v₁ + v₂) + 2 ‖B‖ |lo_b − lo_p|`.
    fn bound_since_build(&self, domain: &Domain, since_prune: Moves) -> f64 {
        let b = since_prune.norm;
        let shift = (self.reference_lo - self.prune_lo).length();
        let sum = (1.0 + b) * self.prune_build_sum + since_prune.sum + 2.0 * b * shift;
        let reach = self.interaction_cutoff + self.skin;
        let since_build = Moves {
            norm: affine_norm(domain, self.reference_deformation),
            sum,
        };
        since_build.closing(reach) * (1.0 + 1e-9) + 1e-12 * reach
    }

    /// Plans a prune at the particles' current positions, keeping the pairs within `left`
    /// (m, what is left of the skin) of reach, or no prune if that is too little;
    /// `build_sum` (m) is the sum of the two largest non-affine displacements since the
    /// build.
    fn prune_at(&mut self, particles: &Particles, domain: &Domain, left: f64, build_sum: f64) {
        self.prune = PrunePlan::within(left, self.skin);
        if self.prune.is_active() {
            self.prune_position.clone_from(&particles.position);
            self.prune_deformation = domain.deformation;
            self.prune_lo = domain.lo;
            self.prune_build_sum = build_sum;
        }
    }

    /// What the force loop scans: the whole list, or the pairs a prune keeps.
    pub fn prune(&self) -> &PrunePlan {
        &self.prune
    }

    /// Rebuilds the list: wraps positions into the region, re-sorts particles by cell, finds
    /// all pairs within cutoff and carries the contact history over by the particles and
    /// the pair's wedge image. Particles appended since the last build (insertion) start
    /// without history; every other pair keeps its springs and bridges.
    ///
    /// A pair without a bridge is kept only within `unbridged_range` (m) beyond contact,
    /// plus the skin: under irreversible laws a pair apart acts only through a bridge,
    /// which forms at contact, so a pair that has none cannot act before it has come
    /// closer than the skin. Laws that act apart without a bridge (reversible adhesion)
    /// need every pair: `unbridged_range` at least [`NeighborList::range`] (or infinite).
    pub fn build(
        &mut self,
        particles: &mut Particles,
        domain: &Domain,
        team: &Team,
        unbridged_range: f64,
    ) -> Result<(), NeighborError> {
        self.fits_count = None;
        // Wrap first, remembering the wedge turns of every particle (by id) so that the
        // history of a pair follows its particles through the faces.
        let images = domain.image_transforms();
        let len = team.piece_len(particles.len(), PARTICLES_PER_TASK);
        let mut pieces: Vec<_> = particles
            .position
            .chunks_mut(len)
            .zip(particles.velocity.chunks_mut(len))
            .zip(particles.angular_velocity.chunks_mut(len))
            .zip(particles.motion.chunks_mut(len))
            .zip(particles.id.chunks(len))
            .map(|piece| (piece, Vec::new()))
            .collect();
        team.for_each(&mut pieces, |(((((r, v), w), motion), id), moves)| {
            for k in 0..r.len() {
                let turns = domain.wedge_turns(r[k]);
                let moved = domain.wrap(&mut r[k], &mut v[k], &mut w[k]);
                // A rotating wall particle moved to its periodic image rotates about the
                // image of its axis.
                if let Motion::Rotating { center, axis, .. } = &mut motion[k] {
                    *center = moved.position(*center);
                    *axis = moved.angular_velocity(*axis);
                }
                if let Some(m) = moved.rotation {
                    moves.push((id[k], turns, m));
                }
            }
        });
        let moves: Vec<(u32, i32, DMat3)> = pieces.into_iter().flat_map(|p| p.1).collect();
        let mut turns = vec![0i32; particles.len()];
        let mut rotated = Vec::with_capacity(moves.len());
        for (id, k, m) in moves {
            turns[id as usize] = k;
            rotated.push((id, m));
        }
        self.last_rotations = rotated;

        let a_max = particles.radius.iter().copied().fold(0.0, f64::max);
        let cutoff = 2.0 * a_max + self.range + self.skin;
        if let Some(w) = domain.as_wedge() {
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
        let mut cell_of = vec![0u32; particles.len()];
        let mut pieces: Vec<_> = cell_of
            .chunks_mut(len)
            .zip(particles.position.chunks(len))
            .collect();
        team.for_each(&mut pieces, |(cells, r)| {
            for (c, r) in cells.iter_mut().zip(r.iter()) {
                *c = grid.cell_index(*r);
            }
        });
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
        let carried = self.carry_history(particles, domain, &images, &turns, &order, team);

        self.unbridged_range = if unbridged_range < self.range {
            unbridged_range
        } else {
            f64::INFINITY
        };
        let unbridged = self
            .unbridged_range
            .is_finite()
            .then_some((unbridged_range, &carried));
        self.find_pairs(particles, &grid, &start, domain, team, unbridged);

        // Every pair of the new list takes its carried history, or none; rows of blocks
        // of particles are written in parallel into their own stretch of the list.
        self.active.resize(self.partner.len(), false);
        self.history.resize(self.partner.len());
        let blocks = particles.len().div_ceil(BUILD_BLOCK);
        let mut jobs = Vec::with_capacity(blocks);
        let (mut active, mut history) = (&mut self.active[..], self.history.view());
        for b in 0..blocks {
            let rows = b * BUILD_BLOCK..((b + 1) * BUILD_BLOCK).min(particles.len());
            let pairs = (self.offsets[rows.end] - self.offsets[rows.start]) as usize;
            let (a_here, a_rest) = std::mem::take(&mut active).split_at_mut(pairs);
            let (h_here, h_rest) = std::mem::take(&mut history).split_at(pairs);
            (active, history) = (a_rest, h_rest);
            jobs.push((rows, a_here, h_here));
        }
        let (offsets, partner, image) = (&self.offsets, &self.partner, &self.image);
        team.for_each(&mut jobs, |(rows, active, history)| {
            let base = offsets[rows.start] as usize;
            for i in rows.clone() {
                for k in offsets[i] as usize..offsets[i + 1] as usize {
                    let turns = domain.image_turns(image[k]);
                    let h = carried.get(i as u32, partner[k], turns);
                    active[k - base] = h.is_some();
                    history.set(k - base, &h.unwrap_or_default());
                }
            }
        });
        self.carried = carried;

        self.reference_position = particles.position.clone();
        self.reference_deformation = domain.deformation;
        self.reference_epoch = domain.image_epoch();
        self.reference_lo = domain.lo;
        self.interaction_cutoff = 2.0 * a_max + self.range;
        self.builds += 1;
        // The first force evaluation scans the whole new list anyway: it prunes.
        self.prune_at(particles, domain, self.skin, 0.0);
        Ok(())
    }

    /// The particles (ids) that the last build rotated through a wedge face, with the
    /// rotation applied; analytic walls rotate their per-particle history with them.
    pub fn last_rotations(&self) -> &[(u32, DMat3)] {
        &self.last_rotations
    }

    /// Calls `f(i, k)` for every live pair `k` (with history) of the rows `rows`, in list
    /// order; plain loops, as an iterator chain compiled to slower code here.
    #[inline(always)]
    fn for_each_live(&self, rows: std::ops::Range<usize>, mut f: impl FnMut(usize, usize)) {
        for i in rows {
            for k in self.offsets[i] as usize..self.offsets[i + 1] as usize {
                if self.active[k] {
                    f(i, k);
                }
            }
        }
    }

    /// Live contact histories of the list as it stood before this build (whose slot `s`
    /// is now slot `new_slot[s]`, `order` listing the old slot of each new one), keyed by
    /// `(lower new slot, higher new slot, wedge turns of the higher seen from the lower)`
    /// and expressed in the lower particle's frame after this build's wraps (`turns[id]`
    /// multiples of `Φ`, the particle rotated by `−turns·Φ`). Under translations only, the
    /// key's turns are zero and histories are not transformed: a box of at least three
    /// cutoffs per periodic axis sees each pair through one image only. The old rows are
    /// split into one block per member of `team`, balanced by pair count, each carried
    /// into its own table in parallel. The buffers of the previous carry are reused.
    fn carry_history(
        &mut self,
        particles: &Particles,
        domain: &Domain,
        images: &[ImageTransform; IMAGE_COUNT],
        turns: &[i32],
        order: &[u32],
        team: &Team,
    ) -> CarriedHistory {
        let mut carried = std::mem::take(&mut self.carried);
        let mut new_slot = vec![0u32; order.len()];
        for (slot, &old) in order.iter().enumerate() {
            new_slot[old as usize] = slot as u32;
        }
        // Rows exist for the particles present at the last build; particles appended since
        // (insertion) sat in the slots after them and have no history yet.
        let rows = self.offsets.len().saturating_sub(1).min(particles.len());
        let bounds = self.chunk_bounds(team.threads().min(rows.max(1)));
        carried
            .blocks
            .resize_with(bounds.len() - 1, CarriedRows::default);
        let mut jobs: Vec<_> = bounds
            .windows(2)
            .map(|b| b[0].min(rows)..b[1].min(rows))
            .zip(carried.blocks.iter_mut())
            .collect();
        let this = &*self;
        let turn = |slot: u32| turns[particles.id[slot as usize] as usize];
        let into_frame = |h: ContactHistory, slot: u32| match domain.as_wedge() {
            Some(w) if turn(slot) != 0 => h.rotated(&ImageTransform {
                rotation: Some(w.rotation(-turn(slot))),
                ..ImageTransform::IDENTITY
            }),
            _ => h,
        };
        team.for_each(&mut jobs, |(rows, table)| {
            table.clear(particles.len());
            this.for_each_live(rows.clone(), |i, k| {
                let (a, b) = (new_slot[i], new_slot[this.partner[k] as usize]);
                table.count(a.min(b));
            });
            table.start_filling();
            this.for_each_live(rows.clone(), |i, k| {
                let (a, b) = (new_slot[i], new_slot[this.partner[k] as usize]);
                let h = this.history.get(k);
                let c = domain.image_turns(this.image[k]);
                // b's image `R(cΦ) r_b` lies next to `r_a`; after the wraps `r_a → R(−t_a Φ) r_a`,
                // `r_b → R(−t_b Φ) r_b` it is `R((c − t_a + t_b) Φ) r_b`: the key's turns are
                // `c − t_a + t_b` (the signs of `t` were once reversed, which lost the
                // history of every pair whose particle wrapped through a face).
                if a < b {
                    table.fill(a, b, c - turn(a) + turn(b), into_frame(h, a));
                } else {
                    let seen_from_b = h.rotated_back(&images[this.image[k] as usize]).flipped();
                    table.fill(b, a, -c - turn(b) + turn(a), into_frame(seen_from_b, b));
                }
            });
        });
        carried
    }

    /// Finds every pair within cutoff, rows in blocks of particles searched in parallel and
    /// concatenated in slot order (so the list does not depend on the thread count). Each
    /// particle searches the cells around itself (with the translations of the periodic
    /// axes) and, near a wedge face, around the rotated query position of each wedge image.
    /// With `unbridged` (a range beyond contact, m, and the carried histories), a pair
    /// farther than that range plus the skin is kept only if it carries a bridge.
    fn find_pairs(
        &mut self,
        particles: &Particles,
        grid: &CellGrid,
        start: &[u32],
        domain: &Domain,
        team: &Team,
        unbridged: Option<(f64, &CarriedHistory)>,
    ) {
        let n = particles.len();
        let pos = &particles.position;
        let rad = &particles.radius;
        let free: Vec<bool> = particles.motion.iter().map(|m| m.is_free()).collect();
        let candidates = Candidates::new(pos, rad, &free, false);
        let reach = self.range + self.skin;
        let cutoff = grid.cutoff;
        let rotated = domain.rotated_images();
        let images = domain.image_transforms();
        let wedge = domain.as_wedge();
        // The row of `i` in `row[..len]` (returned); `row` is a buffer that only grows, so
        // that its entries are not cleared for each particle.
        let row_of = |i: usize, row: &mut Vec<(u32, u8)>, stencil: &mut Stencil| -> usize {
            let ci = grid.cell_coords(pos[i]);
            stencil.update(grid, start, ci, pos[i]);
            let (r_i, a_i) = (pos[i], rad[i]);
            let runs = stencil.ranges(grid, start, ci, r_i);
            let mut len = candidates.scan(i, reach, runs, &images, row, 0);
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
                                    if row.len() == len {
                                        row.push((0, 0));
                                    }
                                    row[len] = (j as u32, code);
                                    len += 1;
                                }
                            }
                        }
                    }
                }
            }
            // Partners without a bridge beyond the unbridged reach cannot act before the
            // next build (few pairs: those between the two reaches).
            if let Some((range, carried)) = unbridged {
                let reach = range + self.skin;
                let mut kept = 0;
                for e in 0..len {
                    let (j, code) = row[e];
                    let cut = a_i + rad[j as usize] + reach;
                    let d = r_i - images[code as usize].position(pos[j as usize]);
                    if d.length_squared() < cut * cut
                        || carried.bridged(i as u32, j, domain.image_turns(code))
                    {
                        row[kept] = row[e];
                        kept += 1;
                    }
                }
                len = kept;
            }
            // Partners sorted by slot for a predictable memory walk.
            row[..len].sort_unstable();
            len
        };
        type Block = (usize, Vec<u32>, Vec<u32>, Vec<u8>);
        let mut blocks: Vec<Block> = (0..n.div_ceil(BUILD_BLOCK))
            .map(|b| (b, Vec::new(), Vec::new(), Vec::new()))
            .collect();
        team.for_each(&mut blocks, |(b, lens, partner, image)| {
            let mut row = Vec::new();
            let mut stencil = Stencil::default();
            for i in *b * BUILD_BLOCK..((*b + 1) * BUILD_BLOCK).min(n) {
                let len = row_of(i, &mut row, &mut stencil);
                lens.push(len as u32);
                partner.extend(row[..len].iter().map(|p| p.0));
                image.extend(row[..len].iter().map(|p| p.1));
            }
        });
        self.offsets.clear();
        self.partner.clear();
        self.image.clear();
        self.offsets.reserve(n + 1);
        self.offsets.push(0);
        for (_, lens, partner, image) in blocks {
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

/// The live contact histories of a list, carried over a rebuild: one table per block of
/// the old list's rows, in row order (see [`CarriedRows`]). A pair of the old list sits in
/// exactly one table; a lookup tries the tables in turn.
#[derive(Clone, Debug, Default)]
struct CarriedHistory {
    /// The blocks' tables, in the order of the old rows.
    blocks: Vec<CarriedRows>,
}

impl CarriedHistory {
    /// Whether the pair `(lower, higher)` through `turns` carries a bridge.
    fn bridged(&self, lower: u32, higher: u32, turns: i32) -> bool {
        self.blocks.iter().any(|b| b.bridged(lower, higher, turns))
    }

    /// The history of the pair `(lower, higher)` through `turns`, if it was live.
    fn get(&self, lower: u32, higher: u32, turns: i32) -> Option<ContactHistory> {
        self.blocks.iter().find_map(|b| b.get(lower, higher, turns))
    }
}

/// The live contact histories of a block of the old list's rows: rows by the lower
/// particle slot of the new list (compressed), each entry the higher slot, the wedge turns
/// of the pair and the history in the lower particle's frame. A lookup scans one row, a few entries long;
/// unlike a hash map, filling and reading it walk memory in order.
#[derive(Clone, Debug, Default)]
struct CarriedRows {
    /// Row starts by lower slot (`slots + 2` entries, see
    /// [`CarriedRows::start_filling`]).
    start: Vec<u32>,
    /// Higher slot and wedge turns of each entry.
    key: Vec<(u32, i32)>,
    /// History of each entry.
    history: Vec<ContactHistory>,
}

impl CarriedRows {
    /// Empties the rows, for particle slots below `slots`. The entries' buffers keep their
    /// length: every entry that a row will reach is written by [`CarriedRows::fill`].
    fn clear(&mut self, slots: usize) {
        self.start.clear();
        self.start.resize(slots + 2, 0);
    }

    /// Counts one entry in the row of `lower`.
    fn count(&mut self, lower: u32) {
        self.start[lower as usize + 2] += 1;
    }

    /// Turns the counts into row starts (shifted by one: `start[id + 1]` is where the
    /// next entry of row `id` goes), ready for [`CarriedRows::fill`].
    fn start_filling(&mut self) {
        for id in 2..self.start.len() {
            self.start[id] += self.start[id - 1];
        }
        let total = self.start[self.start.len() - 1] as usize;
        if self.key.len() < total {
            self.key.resize(total, (0, 0));
            self.history.resize(total, ContactHistory::default());
        }
    }

    /// Places an entry in the row of `lower`; once all are placed, `start[id]` is the
    /// start of row `id`.
    fn fill(&mut self, lower: u32, higher: u32, turns: i32, history: ContactHistory) {
        let slot = &mut self.start[lower as usize + 1];
        self.key[*slot as usize] = (higher, turns);
        self.history[*slot as usize] = history;
        *slot += 1;
    }

    /// Whether the pair `(lower, higher)` through `turns` carries a bridge.
    fn bridged(&self, lower: u32, higher: u32, turns: i32) -> bool {
        let Some(row) = self.start.get(lower as usize..lower as usize + 2) else {
            return false;
        };
        (row[0] as usize..row[1] as usize)
            .any(|e| self.key[e] == (higher, turns) && self.history[e].bridge)
    }

    /// The history of the pair `(lower, higher)` through `turns`, if it was live.
    fn get(&self, lower: u32, higher: u32, turns: i32) -> Option<ContactHistory> {
        let row = self.start.get(lower as usize..lower as usize + 2)?;
        (row[0] as usize..row[1] as usize)
            .find(|&e| self.key[e] == (higher, turns))
            .map(|e| self.history[e])
    }
}

/// The 27 cells around one cell as ranges of particle slots, found once for all the
/// particles in it (they sit in consecutive slots after the sort by cell). Cells next to
/// each other along `x`, seen through the same image, are one range of slots.
#[derive(Debug)]
struct Stencil {
    /// The cell the ranges are for (`[-1; 3]` before the first).
    cell: [i64; 3],
    /// Slot ranges `lo..hi` and the image code they are seen through.
    fixed: Vec<Run>,
    /// Offsets of the cells across the periodic `y` faces, found per particle
    /// ([`CellGrid::neighbor`]): under Lees-Edwards shear their `x` depends on the
    /// particle's position.
    across_y: Vec<[i32; 3]>,
    /// `fixed` followed by the ranges across `y` of the current particle.
    ranges: Vec<Run>,
}

impl Default for Stencil {
    fn default() -> Stencil {
        Stencil {
            cell: [-1; 3],
            fixed: Vec::with_capacity(27),
            across_y: Vec::with_capacity(27),
            ranges: Vec::with_capacity(27),
        }
    }
}

/// Appends the slots of `cell` seen through `code` to `ranges`, extending the last range
/// when the cell follows it in memory.
fn push_cell(ranges: &mut Vec<Run>, start: &[u32], cell: usize, code: u8) {
    let (lo, hi) = (start[cell], start[cell + 1]);
    match ranges.last_mut() {
        Some(last) if last.1 == lo && last.2 == code => last.1 = hi,
        _ => ranges.push((lo, hi, code)),
    }
}

impl Stencil {
    /// Makes the fixed ranges those of cell `c` (holding position `r`), unless they
    /// already are.
    fn update(&mut self, grid: &CellGrid, start: &[u32], c: [i64; 3], r: DVec3) {
        if c == self.cell {
            return;
        }
        self.cell = c;
        self.fixed.clear();
        self.across_y.clear();
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let y = c[1] + dy as i64;
                    if grid.periodic[1] && (y < 0 || y >= grid.dims[1] as i64) {
                        self.across_y.push([dx, dy, dz]);
                    } else if let Some((cell, img)) = grid.neighbor(r, c, [dx, dy, dz]) {
                        push_cell(&mut self.fixed, start, cell, image_code(img));
                    }
                }
            }
        }
    }

    /// All the ranges of a particle at `r` in cell `c` (after [`Stencil::update`]).
    fn ranges(&mut self, grid: &CellGrid, start: &[u32], c: [i64; 3], r: DVec3) -> &[Run] {
        if self.across_y.is_empty() {
            return &self.fixed;
        }
        self.ranges.clear();
        self.ranges.extend_from_slice(&self.fixed);
        for &d in &self.across_y {
            if let Some((cell, img)) = grid.neighbor(r, c, d) {
                push_cell(&mut self.ranges, start, cell, image_code(img));
            }
        }
        &self.ranges
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
            shear_shift: domain.as_lees_edwards().map_or(0.0, |le| le.shift),
            cutoff,
        })
    }

    fn count(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    fn cell_coords(&self, r: DVec3) -> [i64; 3] {
        std::array::from_fn(|a| {
            // Clamped at zero first, so that the cast's truncation is the floor (without
            // a call to `floor`, which the baseline x86-64 target has no instruction for).
            let c = (r[a] - self.lo[a]) / self.lengths[a] * self.dims[a] as f64;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particles::Sphere;

    /// Eight spheres of radius 0.5 on a line through a periodic box, each touching the next.
    fn chain() -> (Particles, Domain) {
        let mut p = Particles::default();
        for k in 0..8 {
            p.push(
                Sphere {
                    position: DVec3::new(0.95 * k as f64 + 0.5, 2.0, 2.0),
                    velocity: DVec3::ZERO,
                    angular_velocity: DVec3::ZERO,
                    radius: 0.5,
                    species: 0,
                    motion: Motion::Free,
                },
                1.0,
            );
        }
        let domain = Domain::new(DVec3::ZERO, DVec3::new(7.6, 4.0, 4.0), [true; 3]);
        (p, domain)
    }

    /// The chain and its list, built once with a skin of 0.1.
    fn built_chain() -> (Particles, Domain, Team, NeighborList) {
        let (mut p, domain) = chain();
        let team = Team::new(1);
        let mut list = NeighborList::new(0.1, 0.0);
        list.build(&mut p, &domain, &team, 0.0).expect("list");
        (p, domain, team, list)
    }

    /// A list built for laws that act apart only through bridges leaves out the pairs
    /// apart without one beyond the skin (here the second neighbours along the chain,
    /// 0.9 apart), and is stale for laws that need them.
    #[test]
    fn a_list_for_bridges_alone_is_stale_for_laws_acting_without_them() {
        let (mut p, _) = chain();
        // Wide enough across for the longer cutoff.
        let domain = Domain::new(DVec3::ZERO, DVec3::new(7.6, 8.0, 8.0), [true; 3]);
        let team = Team::new(1);
        let mut list = NeighborList::new(0.1, 0.85);
        list.build(&mut p, &domain, &team, 0.0).expect("list");
        assert_eq!(list.len(), 8, "touching neighbours only");
        assert!(!list.needs_rebuild(&p, &domain, &team, 0.0));
        assert!(list.needs_rebuild(&p, &domain, &team, 0.5));
        list.build(&mut p, &domain, &team, 0.85).expect("list");
        assert_eq!(list.len(), 16, "second neighbours too");
        assert!(!list.needs_rebuild(&p, &domain, &team, 0.85));
    }

    /// **Histories carried by a team are those of one thread, and none is lost**: 400
    /// spheres in a periodic box, every touching pair given its own random history (half
    /// of them a bridge), then moved, so that the sort by cell reorders the slots. Rebuilt
    /// by teams of one to three members (the old rows carried in as many blocks), the new
    /// lists have the same pairs, flags and histories bit for bit, and every live pair
    /// keeps the history given to it, seen from its new lower slot (flipped when the two
    /// swapped order). Without a range beyond contact the moves (under 0.14 each) keep every
    /// live pair within reach plus the skin of 0.3, and all are carried; with a range of 0.4
    /// for bridges alone and a skin of 0.1 (moves under 0.2), a live pair that ends beyond
    /// contact plus the skin stays listed, with its history, exactly when it has a bridge.
    #[test]
    fn histories_carried_by_a_team_are_those_of_one_thread() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(11);
        let mut random = |scale: f64| {
            DVec3::new(rng.random::<f64>(), rng.random(), rng.random()) * (2.0 * scale) - scale
        };
        let edge = 8.0;
        for (skin, range, step) in [(0.3, 0.0, 0.08), (0.1, 0.4, 0.115)] {
            let mut p = Particles::default();
            for k in 0..400 {
                let sphere = Sphere {
                    position: random(0.5 * edge) + 0.5 * edge,
                    velocity: DVec3::ZERO,
                    angular_velocity: DVec3::ZERO,
                    radius: 0.3 + 0.05 * (k % 5) as f64,
                    species: 0,
                    motion: Motion::Free,
                };
                p.push(sphere, 1.0);
            }
            let domain = Domain::new(DVec3::ZERO, DVec3::splat(edge), [true; 3]);
            let images = domain.image_transforms();
            let mut list = NeighborList::new(skin, range);
            list.build(&mut p, &domain, &Team::new(1), 0.0)
                .expect("list");
            let mut given = std::collections::HashMap::new();
            for i in 0..p.len() {
                for k in list.offsets[i] as usize..list.offsets[i + 1] as usize {
                    let j = list.partner[k] as usize;
                    let r_j = images[list.image[k] as usize].position(p.position[j]);
                    if (p.position[i] - r_j).length() < p.radius[i] + p.radius[j] {
                        let h = ContactHistory {
                            tangential: random(1.0),
                            rolling: random(1.0),
                            torsion: random(1.0),
                            bridge: k % 2 == 0,
                            state: random(1.0).x,
                            sliding_state: random(1.0).y,
                        };
                        list.active[k] = true;
                        list.history.view().set(k, &h);
                        let (a, b) = (p.id[i], p.id[j]);
                        let seen = if a < b { h } else { h.flipped() };
                        given.insert((a.min(b), a.max(b)), seen);
                    }
                }
            }
            assert!(given.len() > 150, "only {} contacts", given.len());
            for r in &mut p.position {
                *r += random(step);
            }
            let carry = |threads: usize| {
                let (mut p, mut list) = (p.clone(), list.clone());
                list.build(&mut p, &domain, &Team::new(threads), 0.0)
                    .expect("list");
                (p, list)
            };
            let (p1, one) = carry(1);
            let mut live = 0;
            for i in 0..p1.len() {
                for k in one.offsets[i] as usize..one.offsets[i + 1] as usize {
                    if one.active[k] {
                        let (a, b) = (p1.id[i], p1.id[one.partner[k] as usize]);
                        let h = given[&(a.min(b), a.max(b))];
                        let expected = if a < b { h } else { h.flipped() };
                        assert_eq!(one.history.get(k), expected, "pair of ids {a}, {b}");
                        live += 1;
                    }
                }
            }
            // The live pairs that must stay listed: those within contact plus the skin,
            // and the bridged ones.
            let slot_of: std::collections::HashMap<u32, usize> =
                (0..p1.len()).map(|s| (p1.id[s], s)).collect();
            let (mut kept, mut by_bridge) = (0, 0);
            for (&(a, b), h) in &given {
                let (i, j) = (slot_of[&a], slot_of[&b]);
                let mut d = p1.position[i] - p1.position[j];
                d -= (d / edge).round() * edge;
                let near = d.length() < p1.radius[i] + p1.radius[j] + skin;
                kept += usize::from(near || h.bridge);
                by_bridge += usize::from(!near && h.bridge);
            }
            assert_eq!(live, kept, "range {range}: live pairs carried");
            if range > 0.0 {
                assert!(by_bridge > 0, "no pair kept by its bridge alone");
                assert!(kept < given.len(), "no pair dropped for want of a bridge");
            } else {
                assert_eq!(kept, given.len());
            }
            for threads in [2, 3] {
                let (p, many) = carry(threads);
                assert!(p.id == p1.id, "{threads} threads: other slots");
                assert!(
                    (&many.offsets, &many.partner, &many.image)
                        == (&one.offsets, &one.partner, &one.image),
                    "range {range}, {threads} threads: other pairs"
                );
                let differ = (0..one.len())
                    .filter(|&k| {
                        many.active[k] != one.active[k] || many.history.get(k) != one.history.get(k)
                    })
                    .count();
                assert_eq!(
                    differ, 0,
                    "range {range}, {threads} threads: pairs with other histories"
                );
            }
        }
    }

    #[test]
    fn a_built_list_fits_its_particles_and_nothing_else() {
        let (mut p, domain, team, mut list) = built_chain();
        assert!(
            list.len() >= 8,
            "the chain's pairs, the periodic one included"
        );
        assert!(list.fits(8));
        assert!(!list.fits(7) && !list.fits(9));
        // A partner that is no slot (as a damaged checkpoint could hold) is refused.
        list.fits_count = None;
        let partner = list.partner[0];
        list.partner[0] = 8;
        assert!(!list.fits(8));
        // Nor a partner that is not above its row (a half list holds each pair once, from
        // its lower slot).
        let row = list.offsets.partition_point(|&o| o == 0) - 1;
        list.partner[0] = row as u32;
        assert!(!list.fits(8));
        list.partner[0] = partner;
        assert!(list.fits(8));
        // A rebuild forgets the answer and finds a fitting list again.
        list.build(&mut p, &domain, &team, 0.0).expect("list");
        assert_eq!(list.fits_count, None);
        assert!(list.fits(8));
    }

    #[test]
    fn a_fitting_list_knows_the_row_of_every_pair_even_after_a_checkpoint() {
        let (_, _, _, mut list) = built_chain();
        let rows = |list: &NeighborList| -> Vec<u32> {
            (0..8u32)
                .flat_map(|i| {
                    let (lo, hi) = (list.offsets[i as usize], list.offsets[i as usize + 1]);
                    (lo..hi).map(move |_| i)
                })
                .collect()
        };
        assert!(list.fits(8));
        assert_eq!(list.first, rows(&list));
        // A list read back from a checkpoint has no rows until it is found to fit.
        let bytes = rmp_serde::to_vec_named(&list).expect("serialise");
        let mut read: NeighborList = rmp_serde::from_slice(&bytes).expect("deserialise");
        assert!(read.first.is_empty() && read.fits_count.is_none());
        assert!(read.fits(8));
        assert_eq!(read.first, rows(&list));
    }

    /// Whether the list is stale after the box took `deformation` (from the identity at
    /// the build), every particle followed it affinely, and the first `pushed` particles
    /// moved 0.06 (0.6 of the skin) further along z.
    fn stale_after(deformation: DMat3, pushed: usize) -> bool {
        let mut p = Particles::default();
        for k in 0..6 {
            let position = DVec3::new(6.5 - k as f64, 1.0 + 0.9 * k as f64, 3.0);
            p.push(
                Sphere {
                    position,
                    velocity: DVec3::ZERO,
                    angular_velocity: DVec3::ZERO,
                    radius: 0.3,
                    species: 0,
                    motion: Motion::Free,
                },
                1.0,
            );
        }
        let mut domain = Domain::new(DVec3::ZERO, DVec3::splat(8.0), [true; 3]);
        let team = Team::new(1);
        let mut list = NeighborList::new(0.1, 0.0);
        list.build(&mut p, &domain, &team, 0.0).expect("list");
        domain.deformation = deformation;
        let affine = deformation - DMat3::IDENTITY;
        for (k, r) in p.position.iter_mut().enumerate() {
            *r += affine * (*r - domain.lo);
            if k < pushed {
                r.z += 0.06;
            }
        }
        list.needs_rebuild(&p, &domain, &team, f64::INFINITY)
    }

    #[test]
    fn the_skin_check_counts_only_what_departs_from_the_affine_flow() {
        // The particles climb in y as they step back in x, so a displacement taken from
        // the wrong coordinate shows. Rigid box, simple shear (only the y column moves: the tilt reaches 0.11 at the
        // top particle, more than the skin), shear with a height that follows the stress,
        // and a general deformation: each path of the check. One particle 0.6 skin off
        // the flow keeps the list; two make 1.2 skins together and renew it.
        let shear = DMat3::from_cols(DVec3::X, DVec3::new(0.02, 1.0, 0.0), DVec3::Z);
        let sheared_and_lower = DMat3::from_cols(DVec3::X, DVec3::new(0.02, 0.995, 0.0), DVec3::Z);
        let general = DMat3::from_cols(
            DVec3::new(1.002, 0.0, 0.001),
            DVec3::new(0.02, 1.0, 0.0),
            DVec3::Z,
        );
        for deformation in [DMat3::IDENTITY, shear, sheared_and_lower, general] {
            assert!(
                !stale_after(deformation, 0),
                "{deformation}: affine flow alone"
            );
            assert!(
                !stale_after(deformation, 1),
                "{deformation}: one particle off"
            );
            assert!(
                stale_after(deformation, 2),
                "{deformation}: two particles off"
            );
        }
    }

    /// The bound on the skin's closing since the build, from the moves since a prune,
    /// holds for any deformation and any shift of the box's corner between the two: 300
    /// random histories of 64 particles (shear, stretch and general maps, moves of up to
    /// 0.1 per axis, corners shifted by up to 0.2), half of them following the box's map
    /// after the prune (where the bound's terms in `‖B‖` matter).
    #[test]
    fn the_moves_since_a_prune_bound_those_since_the_build() {
        use rand::{RngExt, SeedableRng};
        type Rng = rand_xoshiro::Xoshiro256PlusPlus;
        let mut rng = Rng::seed_from_u64(3);
        let team = Team::new(2);
        let random = |rng: &mut Rng, scale: f64| {
            DVec3::new(rng.random::<f64>(), rng.random(), rng.random()) * (2.0 * scale) - scale
        };
        // A map of each kind, by turns: simple shear, a stretch of y, anything.
        let deform = |rng: &mut Rng, domain: &mut Domain, kind: usize| {
            let small = random(rng, 0.05);
            let step = match kind % 3 {
                0 => DMat3::from_cols(DVec3::X, DVec3::new(small.x, 1.0, 0.0), DVec3::Z),
                1 => DMat3::from_diagonal(DVec3::new(1.0, 1.0 + small.y, 1.0)),
                _ => {
                    let (a, b) = (random(rng, 0.03), random(rng, 0.03));
                    DMat3::IDENTITY + DMat3::from_cols(a, small, b)
                }
            };
            domain.deformation = step * domain.deformation;
        };
        let shift_and_move = |rng: &mut Rng, p: &mut Particles, domain: &mut Domain| {
            domain.lo += random(rng, 0.2);
            for r in &mut p.position {
                *r += random(rng, 0.1);
            }
        };
        let mut tight = 0.0f64;
        for trial in 0..300 {
            let mut p = Particles::default();
            for _ in 0..64 {
                let sphere = Sphere {
                    position: random(&mut rng, 4.0) + 4.0,
                    velocity: DVec3::ZERO,
                    angular_velocity: DVec3::ZERO,
                    radius: 0.3,
                    species: 0,
                    motion: Motion::Free,
                };
                p.push(sphere, 1.0);
            }
            let mut domain = Domain::new(DVec3::ZERO, DVec3::splat(8.0), [true; 3]);
            let mut list = NeighborList::new(0.4, 0.0);
            list.build(&mut p, &domain, &team, 0.0).expect("list");
            deform(&mut rng, &mut domain, trial);
            shift_and_move(&mut rng, &mut p, &mut domain);
            let build = |list: &NeighborList| {
                (
                    list.reference_position.clone(),
                    list.reference_deformation,
                    list.reference_lo,
                )
            };
            let (r0, f0, lo0) = build(&list);
            let at_prune = moves(&p, &domain, &team, (&r0, f0, lo0));
            list.prune_at(&p, &domain, list.skin, at_prune.sum);
            assert!(list.prune.is_active());
            // Every other history follows the box's map exactly after the prune, so that
            // the displacements since the build change only through it.
            let (before, lo) = (domain.deformation, domain.lo);
            deform(&mut rng, &mut domain, trial);
            if trial % 2 == 0 {
                let affine = domain.deformation * before.inverse() - DMat3::IDENTITY;
                for r in &mut p.position {
                    *r += affine * (*r - lo);
                }
                domain.lo += random(&mut rng, 0.2);
            } else {
                shift_and_move(&mut rng, &mut p, &mut domain);
            }
            let reach = list.interaction_cutoff + list.skin;
            let exact = moves(&p, &domain, &team, (&r0, f0, lo0)).closing(reach);
            let since_prune = moves(
                &p,
                &domain,
                &team,
                (&list.prune_position, list.prune_deformation, list.prune_lo),
            );
            let bound = list.bound_since_build(&domain, since_prune);
            assert!(exact <= bound, "trial {trial}: {exact} > {bound}");
            tight = tight.max(exact / bound);
        }
        // Not a bound that says nothing: at times it is close to the truth.
        assert!(
            tight > 0.5,
            "the bound is loose: at best {tight} of it is reached"
        );
    }

    #[test]
    #[should_panic(expected = "does not fit")]
    fn forces_refuse_a_list_of_other_particles() {
        let (mut p, domain, team, mut list) = built_chain();
        let extra = p.sphere(0);
        p.push(extra, 1.0);
        use crate::contact::{Adhesion, ContactLaw, Damping, LinearNormal, Spring};
        let law = ContactLaw {
            normal: LinearNormal {
                stiffness: 1.0e4,
                damping: Damping::NONE,
            }
            .into(),
            tangential: Spring::NONE,
            rolling: Spring::NONE,
            torsion: Spring::NONE,
            adhesion: Adhesion::None,
        };
        crate::forces::pair_forces::<()>(
            &mut p,
            &mut list,
            &crate::contact::ContactTable::uniform(1, law),
            &domain.image_transforms(),
            None,
            1e-4,
            &mut crate::forces::ForceScratch::default(),
            &team,
        );
    }
}
