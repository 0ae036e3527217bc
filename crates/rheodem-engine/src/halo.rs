//! Where the chunks of the pair loop put their forces, and how the forces come together.
//!
//! The pair loop ([`crate::forces`]) splits the half Verlet list into contiguous slot
//! ranges, one chunk per member of the team. A pair `i < j` belongs to the chunk of `i`, so
//! a chunk writes the slots of its own range and, through the pairs reaching forward, some
//! slots of later chunks: its *halo*. During the loop a chunk writes its own slots straight
//! into the particle arrays (no other chunk writes them then) and its halo into buffers of
//! its own ([`ForceSink`]); afterwards each chunk's slots gather the halo sums of the earlier
//! chunks that reach them, in chunk order ([`gather`]).
//!
//! The particles are sorted by cell with `z` slowest ([`crate::neighbor`]), so a halo is
//! about one layer of cells past the chunk, plus, through a periodic boundary along `z`,
//! the last layer for the chunks that hold the first. A halo is therefore kept as two
//! windows of slots, split at the largest gap between the slots it reaches. The extra work
//! of a chunk (zeroing its buffers, adding them in) is its halo's size, not the particle
//! count: on the standard problem repeated to 32 768 spheres a step of 16 chunks costs
//! a few per cent more instructions than one of a single chunk (BENCHMARKS.md, "Many
//! threads"), where whole-length buffers per extra chunk cost 62 % more.
//!
//! Every slot ends with the sum the earlier scheme (every chunk past the first into a
//! buffer as long as the particle arrays, added in chunk order) gave, bit for bit: a slot
//! of chunk `c` receives `((h_0 + h_1) + … + h_{c−1}) + s_c`, the halo sums `h` of the
//! earlier chunks in order and its own chunk's sum `s_c` last. (An accumulator that starts
//! at `+0` is never `−0`, so the zeros that scheme added change nothing.)

use glam::DVec3;
use std::ops::Range;

/// The slots past a chunk that its pairs reach: two windows, `near` (right past the
/// chunk) and `far` (beyond the largest gap between the slots reached), either possibly
/// empty.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Halo {
    near: Range<usize>,
    far: Range<usize>,
}

impl Halo {
    /// The halo of the chunk ending at slot `end` whose pairs have the partners
    /// `partners` (slots; those below `end` are the chunk's own). `reached` is scratch.
    pub(crate) fn of(partners: &[u32], end: usize, reached: &mut Vec<u32>) -> Halo {
        reached.clear();
        reached.extend(partners.iter().copied().filter(|&j| j as usize >= end));
        reached.sort_unstable();
        reached.dedup();
        let (Some(&first), Some(&last)) = (reached.first(), reached.last()) else {
            return Halo::default();
        };
        // Split after the slot followed by the largest gap (none: one window).
        let split = reached
            .windows(2)
            .enumerate()
            .max_by_key(|&(k, w)| (w[1] - w[0], std::cmp::Reverse(k)))
            .filter(|(_, w)| w[1] - w[0] > 1)
            .map(|(k, _)| k);
        match split {
            None => Halo {
                near: first as usize..last as usize + 1,
                far: 0..0,
            },
            Some(k) => Halo {
                near: first as usize..reached[k] as usize + 1,
                far: reached[k + 1] as usize..last as usize + 1,
            },
        }
    }

    /// Slots in the halo's windows.
    pub(crate) fn len(&self) -> usize {
        self.near.len() + self.far.len()
    }

    /// The windows with their offsets into the buffer.
    fn windows(&self) -> [(Range<usize>, usize); 2] {
        [(self.near.clone(), 0), (self.far.clone(), self.near.len())]
    }
}

/// Where one chunk of the pair loop adds forces (N) and torques (N m): its own slots
/// `lo..hi` in the particle arrays, the slots of its [`Halo`] in buffers of its own.
///
/// A copy of raw pointers, offset so that slot `k` of each region sits at `k`: the pair
/// loop keeps them in registers (a struct behind a reference would be reloaded after every
/// store). It borrows the slices it was made from for `'a`; every copy must stay on the
/// thread of the chunk that made it.
#[derive(Clone, Copy)]
pub(crate) struct ForceSink<'a> {
    /// One past the chunk's own slots.
    hi: usize,
    /// One past the halo's near window.
    near_end: usize,
    own: (*mut DVec3, *mut DVec3),
    near: (*mut DVec3, *mut DVec3),
    far: (*mut DVec3, *mut DVec3),
    /// The chunk's first slot and the halo, for the debug checks.
    lo: usize,
    halo: &'a Halo,
    _slices: std::marker::PhantomData<&'a mut [DVec3]>,
}

impl<'a> ForceSink<'a> {
    /// The sink of the chunk of slots `lo..lo + force.len()`, whose own slots are `force`
    /// and `torque` and whose halo buffers hold `halo.len()` entries each; zeroes them all.
    ///
    /// # Panics
    /// If the lengths do not match.
    pub(crate) fn zeroed(
        lo: usize,
        force: &'a mut [DVec3],
        torque: &'a mut [DVec3],
        halo: &'a Halo,
        halo_force: &'a mut [DVec3],
        halo_torque: &'a mut [DVec3],
    ) -> ForceSink<'a> {
        assert!(force.len() == torque.len(), "one torque per force");
        assert!(
            halo_force.len() == halo.len() && halo_torque.len() == halo.len(),
            "halo buffers of the halo's length"
        );
        for v in [
            &mut *force,
            &mut *torque,
            &mut *halo_force,
            &mut *halo_torque,
        ] {
            v.fill(DVec3::ZERO);
        }
        // Pointers shifted back by each region's first slot; only the slots of the region
        // are ever reached through them (wrapping arithmetic: the shifted pointer itself
        // may lie outside the buffer).
        let at = |v: &mut [DVec3], first: usize, offset: usize| {
            v.as_mut_ptr().wrapping_add(offset).wrapping_sub(first)
        };
        let near_len = halo.near.len();
        ForceSink {
            hi: lo + force.len(),
            near_end: halo.near.end,
            own: (at(force, lo, 0), at(torque, lo, 0)),
            near: (
                at(halo_force, halo.near.start, 0),
                at(halo_torque, halo.near.start, 0),
            ),
            far: (
                at(halo_force, halo.far.start, near_len),
                at(halo_torque, halo.far.start, near_len),
            ),
            lo,
            halo,
            _slices: std::marker::PhantomData,
        }
    }

    /// The force and torque accumulators of the chunk's own slot `k`.
    ///
    /// # Safety
    /// `k` is one of the chunk's own slots, and no other reference to its accumulators is
    /// alive.
    #[inline(always)]
    pub(crate) unsafe fn own(self, k: usize) -> (&'a mut DVec3, &'a mut DVec3) {
        debug_assert!((self.lo..self.hi).contains(&k));
        // SAFETY: `k` lies in the own slots (the caller's contract), which `own` reaches
        // at `k`; the slices are borrowed for `'a`.
        unsafe {
            (
                &mut *self.own.0.wrapping_add(k),
                &mut *self.own.1.wrapping_add(k),
            )
        }
    }

    /// The force and torque accumulators of slot `k`.
    ///
    /// # Safety
    /// `k` is one of the chunk's slots or lies in its halo, and no other reference to its
    /// accumulators is alive.
    #[inline(always)]
    pub(crate) unsafe fn slot(self, k: usize) -> (&'a mut DVec3, &'a mut DVec3) {
        let (f, t) = if k < self.hi {
            self.own
        } else {
            self.halo_region(k)
        };
        // SAFETY: `k` lies in the region whose pointers were chosen (the caller's
        // contract), which they reach at `k`; the slices are borrowed for `'a`.
        unsafe { (&mut *f.wrapping_add(k), &mut *t.wrapping_add(k)) }
    }

    /// The pointers of the halo window holding slot `k`. Marked cold so that the pair
    /// loop branches to it (most partners are the chunk's own) instead of selecting
    /// between three regions on every write.
    #[cold]
    #[inline(always)]
    fn halo_region(self, k: usize) -> (*mut DVec3, *mut DVec3) {
        if k < self.near_end {
            debug_assert!(self.halo.near.contains(&k));
            self.near
        } else {
            debug_assert!(self.halo.far.contains(&k));
            self.far
        }
    }
}

/// Scratch of [`gather`], reused between steps.
#[derive(Clone, Debug, Default)]
pub(crate) struct Gathering {
    /// The windows reaching into the chunk, clipped to it: slots, buffer index of the
    /// first, source chunk; in chunk order.
    windows: Vec<(Range<usize>, usize, usize)>,
    /// Slots where a window starts or ends.
    cuts: Vec<usize>,
    /// The windows covering the piece between two cuts.
    cover: Vec<(usize, usize)>,
}

/// The halo sums of the earlier chunks added into the slots `lo..lo + force.len()` of one
/// chunk (`force`, `torque`: its own sums so far), in chunk order, as the module's
/// documentation says. `halos[c]` and `buffers[c]` (forces, torques) are the halo and its
/// sums of chunk `c`, for the earlier chunks.
pub(crate) fn gather(
    lo: usize,
    force: &mut [DVec3],
    torque: &mut [DVec3],
    halos: &[Halo],
    buffers: &[(&[DVec3], &[DVec3])],
    scratch: &mut Gathering,
) {
    let own = lo..lo + force.len();
    let Gathering {
        windows,
        cuts,
        cover,
    } = scratch;
    windows.clear();
    for (c, halo) in halos.iter().enumerate() {
        for (w, offset) in halo.windows() {
            let part = w.start.max(own.start)..w.end.min(own.end);
            if !part.is_empty() {
                windows.push((part.clone(), offset + (part.start - w.start), c));
            }
        }
    }
    // Cut the chunk where a window starts or ends: between two cuts the same windows
    // cover every slot, and their sums are added in chunk order.
    cuts.clear();
    cuts.extend(
        windows
            .iter()
            .flat_map(|(part, _, _)| [part.start, part.end]),
    );
    cuts.sort_unstable();
    cuts.dedup();
    for piece in cuts.windows(2) {
        let (from, to) = (piece[0], piece[1]);
        cover.clear();
        cover.extend(
            windows
                .iter()
                .filter(|(part, _, _)| part.start <= from && to <= part.end)
                .map(|(part, first, c)| (first + (from - part.start), *c)),
        );
        let Some((&(first, c), rest)) = cover.split_first() else {
            continue;
        };
        for k in 0..to - from {
            let (f, t) = buffers[c];
            let (mut sf, mut st) = (f[first + k], t[first + k]);
            for &(first, c) in rest {
                let (f, t) = buffers[c];
                sf += f[first + k];
                st += t[first + k];
            }
            let own = from + k - lo;
            force[own] = sf + force[own];
            torque[own] = st + torque[own];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_halo_splits_at_the_largest_gap_between_the_slots_it_reaches() {
        let mut scratch = Vec::new();
        // Own slots below 10; reached: 10..13 and, through a periodic face, 95..97.
        let partners = [3, 11, 10, 96, 12, 95, 11, 5];
        let halo = Halo::of(&partners, 10, &mut scratch);
        assert_eq!(halo.near, 10..13);
        assert_eq!(halo.far, 95..97);
        assert_eq!(halo.len(), 5);
        assert_eq!(
            halo.windows(),
            [(10..13, 0), (95..97, 3)],
            "windows laid end to end in the buffer"
        );
        // Contiguous slots make one window; none reached, none.
        assert_eq!(Halo::of(&[12, 13, 14], 10, &mut scratch).far, 0..0);
        assert_eq!(Halo::of(&[12, 13, 14], 10, &mut scratch).near, 12..15);
        assert_eq!(Halo::of(&[1, 2], 10, &mut scratch), Halo::default());
    }

    #[test]
    fn gathering_gives_the_sums_of_whole_length_buffers_added_in_chunk_order() {
        // Three chunks over 12 slots: 0..4, 4..8, 8..12. Contributions of awkward
        // magnitudes, so that the order of the sums shows in the bits.
        let value = |c: usize, k: usize| DVec3::splat(0.1 * (c + 1) as f64 + 1e16 * (k % 3) as f64);
        let bounds = [0, 4, 8, 12];
        // Chunk 0 reaches 4..6 and 10..12; chunk 1 reaches 8..10.
        let reach: [Vec<u32>; 3] = [vec![1, 4, 5, 10, 11], vec![8, 9, 5], vec![9]];
        let mut scratch = Vec::new();
        let halos: Vec<Halo> = (0..3)
            .map(|c| Halo::of(&reach[c], bounds[c + 1], &mut scratch))
            .collect();
        // The old scheme: whole-length buffers, chunk 0 straight into the total.
        let mut whole = vec![vec![DVec3::ZERO; 12]; 3];
        for (c, buf) in whole.iter_mut().enumerate() {
            let own = (bounds[c]..bounds[c + 1]).map(|k| k as u32);
            for j in own.chain(reach[c].iter().copied()) {
                buf[j as usize] += value(c, j as usize);
            }
        }
        let mut expected = whole[0].clone();
        for buf in &whole[1..] {
            for (e, b) in expected.iter_mut().zip(buf) {
                *e += *b;
            }
        }
        // The new one: own slots and halo buffers, then gathered.
        let mut force = vec![DVec3::ZERO; 12];
        let mut torque = vec![DVec3::ZERO; 12];
        let mut bufs: Vec<(Vec<DVec3>, Vec<DVec3>)> = halos
            .iter()
            .map(|h| (vec![DVec3::ZERO; h.len()], vec![DVec3::ZERO; h.len()]))
            .collect();
        for c in 0..3 {
            let (lo, hi) = (bounds[c], bounds[c + 1]);
            let (hf, ht) = &mut bufs[c];
            let (f, t) = (&mut force[lo..hi], &mut torque[lo..hi]);
            let sink = ForceSink::zeroed(lo, f, t, &halos[c], hf, ht);
            let own = (lo..hi).map(|k| k as u32);
            for j in own.chain(reach[c].iter().copied()) {
                let j = j as usize;
                if j >= lo {
                    // SAFETY: `j` is an own slot or was reached (it lies in the halo).
                    let (f, t) = unsafe { sink.slot(j) };
                    *f += value(c, j);
                    *t += value(c, j);
                }
            }
        }
        let mut scratch = Gathering::default();
        for c in 1..3 {
            let (lo, hi) = (bounds[c], bounds[c + 1]);
            let views: Vec<(&[DVec3], &[DVec3])> =
                bufs[..c].iter().map(|(f, t)| (&f[..], &t[..])).collect();
            gather(
                lo,
                &mut force[lo..hi],
                &mut torque[lo..hi],
                &halos[..c],
                &views,
                &mut scratch,
            );
        }
        assert_eq!(force, expected);
        assert_eq!(torque, expected);
    }
}
