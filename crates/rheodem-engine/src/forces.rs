//! The parallel pair-force loop.
//!
//! Scheme: a half Verlet list, split into as many contiguous slot ranges ("chunks") as the
//! [`Team`] has members, balanced by pair count. Each pair is evaluated once (half the
//! work of a full list), by the chunk of its first slot; a chunk adds forces and torques
//! into its own slots of the particle arrays and into buffers for the slots of later
//! chunks its pairs reach, which are then gathered in chunk order ([`crate::halo`]). Writes
//! need no atomics or colouring, the ordered gathering makes a run bit-identical for a
//! given thread count, whichever thread runs which chunk, and the extra work per chunk is
//! its halo, not the particle count.
//!
//! A partner seen through a rotated image (a wedge face) receives the reaction rotated back
//! into its own frame, `−Rᵀ f` and `Rᵀ τ_j`. What is measured besides the forces is up to
//! the [`ContactObserver`] of the call.

use crate::contact::kernel::{HistoryLanes, Touch};
use crate::contact::lanes::{F4, Real, V3};
use crate::contact::normal::{NormalForce, WithNormal};
use crate::contact::spring::{SpringModel, WithSpring};
use crate::contact::{ContactTable, HistoryView, PairForce, PairKernel, PairKinematics};
use crate::domain::{IDENTITY_IMAGE, IMAGE_COUNT, ImageTransform};
use crate::halo::{ForceSink, Gathering, Halo, gather};
use crate::neighbor::NeighborList;
use crate::observe::{ContactObserver, ContactView};
use crate::particles::Particles;
use crate::team::Team;
use glam::{DMat3, DVec3};

/// Per-chunk buffers of the pair loop, reused between steps (not part of the simulation
/// state).
#[derive(Clone, Debug, Default)]
pub struct ForceScratch {
    /// Per chunk: the slots of later chunks its pairs reach.
    halos: Vec<Halo>,
    /// The list structure ([`crate::neighbor::PairSlices::structure`]) and chunk bounds the
    /// halos were found for.
    halos_for: (u64, Vec<usize>),
    /// Per chunk: the sums of forces (N) and torques (N m) on its halo.
    halo_force: Vec<Vec<DVec3>>,
    halo_torque: Vec<Vec<DVec3>>,
    /// Per chunk: scratch of the gathering ([`crate::halo::gather`]).
    gathering: Vec<Gathering>,
    /// Scratch of [`Halo::of`].
    reached: Vec<u32>,
    found: Vec<Found>,
}

/// The pairs within reach that the first pass of a chunk found.
#[derive(Clone, Debug, Default)]
struct Found {
    /// Pairs within reach (the first `n` entries of a step; never shrunk).
    within: Vec<Candidate>,
    /// Pairs that had a force and are now out of reach (the first entries of a step;
    /// never shrunk).
    lost: Vec<u32>,
    /// Touching pairs, as indices into `within` (the first entries of a step; never
    /// shrunk).
    touching: Vec<u32>,
    /// Pairs apart within the interaction range (adhesive laws), as indices into `within`
    /// (the first entries of a step; never shrunk).
    apart: Vec<u32>,
    /// The pairs the last prune kept (the first `n_kept` entries; never shrunk).
    kept: Vec<Kept>,
    /// How many pairs the last prune kept.
    n_kept: usize,
    /// The stamp of the last prune ([`crate::prune::PrunePlan`]) and the chunk it covered.
    pruned: (u64, std::ops::Range<usize>),
}

/// A pair kept by a prune: its slots, its index in the chunk's pairs and the image code
/// of `j`.
#[derive(Clone, Copy, Debug, Default)]
struct Kept {
    i: u32,
    j: u32,
    local: u32,
    code: u8,
}

/// Read-only particle data of the loop.
struct Inputs<'a> {
    position: &'a [DVec3],
    velocity: &'a [DVec3],
    omega: &'a [DVec3],
    radius: &'a [f64],
    id: &'a [u32],
    part: &'a [u16],
    inv_mass: &'a [f64],
    species: &'a [u16],
    offsets: &'a [u32],
    first: &'a [u32],
    partner: &'a [u32],
    image: &'a [u8],
    images: &'a [ImageTransform; IMAGE_COUNT],
    laws: &'a ContactTable,
    /// The largest interaction range beyond contact of any law (m).
    max_range: f64,
    /// The largest range beyond contact of the laws that act on pairs apart without a
    /// bridge (reversible adhesion; m).
    free_range: f64,
    /// The boundary's mean-flow velocity gradient `L` (1/s) that contacts subtract as
    /// `L b` (`b` the branch); `None` when they do not.
    mean_flow: Option<DMat3>,
    dt: f64,
    /// Whether to run the plain copy of the loop even where the CPU has AVX2.
    plain: bool,
    /// The prune's stamp and margin beyond reach (m; zero to scan the whole list).
    prune: (u64, f64),
}

/// Zeroes the particle forces and torques and adds every pair force of the list, advancing
/// contact history over `dt` (s). `mean_flow` is the boundary's mean-flow velocity gradient
/// `L` (1/s) when contacts measure their relative velocity against the mean flow: `L b` is
/// then subtracted from each contact's relative velocity (`b` its branch); `None` in the lab
/// frame (see `Domain::contact_velocity_gradient`).
/// Every interacting pair is shown to the observer `O`, whose merged observations are
/// returned. The chunks are shared among the members of `team`. The list must have been
/// checked ([`NeighborList::needs_rebuild`], and rebuilt if need be) since the particles
/// last moved: between checks the loop scans only the pairs of the list's last prune
/// ([`crate::prune`]).
#[allow(clippy::too_many_arguments)]
pub fn pair_forces<O: ContactObserver>(
    particles: &mut Particles,
    list: &mut NeighborList,
    laws: &ContactTable,
    images: &[ImageTransform; IMAGE_COUNT],
    mean_flow: Option<DMat3>,
    dt: f64,
    scratch: &mut ForceScratch,
    team: &Team,
) -> O {
    pair_forces_in::<O>(
        particles, list, laws, images, mean_flow, dt, scratch, team, false,
    )
}

/// [`pair_forces`], in the plain copy of the loop even where the CPU has AVX2 when
/// `plain` (so that the tests compare the two copies on any machine).
#[allow(clippy::too_many_arguments)]
fn pair_forces_in<O: ContactObserver>(
    particles: &mut Particles,
    list: &mut NeighborList,
    laws: &ContactTable,
    images: &[ImageTransform; IMAGE_COUNT],
    mean_flow: Option<DMat3>,
    dt: f64,
    scratch: &mut ForceScratch,
    team: &Team,
    plain: bool,
) -> O {
    let n = particles.len();
    // The loop reads the particle arrays and the pair slots without bounds checks: every
    // index it uses comes from the list, so the list must fit the particles.
    assert!(
        list.fits(n),
        "the neighbour list does not fit the {n} particles: rebuild it before evaluating forces"
    );
    let p = &*particles;
    assert!(
        [
            p.position.len(),
            p.velocity.len(),
            p.angular_velocity.len(),
            p.radius.len(),
            p.inv_mass.len(),
            p.force.len(),
            p.torque.len(),
        ]
        .iter()
        .all(|&len| len == n),
        "particle arrays of unequal lengths"
    );
    let chunks = team.threads().min(n.max(1));
    let bounds = list.chunk_bounds(chunks);
    let slices = list.slices();
    let inputs = Inputs {
        position: &particles.position,
        velocity: &particles.velocity,
        omega: &particles.angular_velocity,
        radius: &particles.radius,
        id: &particles.id,
        part: &particles.part,
        inv_mass: &particles.inv_mass,
        species: &particles.species,
        offsets: slices.offsets,
        first: slices.first,
        partner: slices.partner,
        image: slices.image,
        images,
        laws,
        max_range: laws.max_range(),
        free_range: laws.free_range(),
        mean_flow,
        dt,
        plain,
        prune: (slices.prune.stamp, slices.prune.margin),
    };

    // The halos, found again whenever the list's structure or the chunks change.
    if scratch.halos_for.0 != slices.structure || scratch.halos_for.1 != bounds {
        scratch.halos = bounds
            .windows(2)
            .map(|b| {
                let pairs = inputs.offsets[b[0]] as usize..inputs.offsets[b[1]] as usize;
                Halo::of(&inputs.partner[pairs], b[1], &mut scratch.reached)
            })
            .collect();
        scratch.halos_for = (slices.structure, bounds.clone());
    }
    scratch.found.resize_with(chunks, Found::default);
    scratch.halo_force.resize_with(chunks, Vec::new);
    scratch.halo_torque.resize_with(chunks, Vec::new);
    scratch.gathering.resize_with(chunks, Gathering::default);
    for ((halo, f), t) in scratch
        .halos
        .iter()
        .zip(&mut scratch.halo_force)
        .zip(&mut scratch.halo_torque)
    {
        f.resize(halo.len(), DVec3::ZERO);
        t.resize(halo.len(), DVec3::ZERO);
    }

    // Carve the history and the particles' forces and torques into one disjoint slice per
    // chunk; each chunk zeroes its slices and its halo buffers inside its own task.
    let mut jobs = Vec::with_capacity(chunks);
    let (mut active, mut history) = (slices.active, slices.history);
    let mut own_force = own_slots(&mut particles.force, &bounds).into_iter();
    let mut own_torque = own_slots(&mut particles.torque, &bounds).into_iter();
    let mut halo_force = scratch.halo_force.iter_mut();
    let mut halo_torque = scratch.halo_torque.iter_mut();
    for (c, halo) in scratch.halos.iter().enumerate() {
        let (lo, hi) = (bounds[c], bounds[c + 1]);
        let pairs = (inputs.offsets[hi] - inputs.offsets[lo]) as usize;
        let (t_here, t_rest) = std::mem::take(&mut active).split_at_mut(pairs);
        let (h_here, h_rest) = std::mem::take(&mut history).split_at(pairs);
        active = t_rest;
        history = h_rest;
        let (Some(f), Some(t), Some(hf), Some(ht)) = (
            own_force.next(),
            own_torque.next(),
            halo_force.next(),
            halo_torque.next(),
        ) else {
            unreachable!("one slice and one halo buffer per chunk");
        };
        jobs.push((lo..hi, t_here, h_here, (f, t, halo, hf, ht)));
    }
    let mut jobs: Vec<_> = jobs
        .into_iter()
        .zip(scratch.found.iter_mut())
        .map(|(job, found)| (job, found, O::default()))
        .collect();
    team.for_each(
        &mut jobs,
        |((range, active, history, (force, torque, halo, hf, ht)), found, out)| {
            let sink = ForceSink::zeroed(range.start, force, torque, halo, hf, ht);
            *out = chunk_forces::<O>(&inputs, range.clone(), active, history, sink, found);
        },
    );
    let partial: Vec<O> = jobs.into_iter().map(|(_, _, out)| out).collect();

    if chunks > 1 {
        // Each chunk past the first gathers the halo sums of the earlier ones.
        let halos = &scratch.halos;
        let buffers: Vec<(&[DVec3], &[DVec3])> = scratch
            .halo_force
            .iter()
            .zip(&scratch.halo_torque)
            .map(|(f, t)| (&f[..], &t[..]))
            .collect();
        let mut gathers: Vec<_> = own_slots(&mut particles.force, &bounds)
            .into_iter()
            .zip(own_slots(&mut particles.torque, &bounds))
            .zip(scratch.gathering.iter_mut())
            .enumerate()
            .skip(1)
            .collect();
        team.for_each(&mut gathers, |(c, ((force, torque), sum))| {
            let c = *c;
            gather(bounds[c], force, torque, &halos[..c], &buffers[..c], sum);
        });
    }

    let mut total = O::default();
    for p in partial {
        total.merge(p);
    }
    total
}

/// `values` split into the chunks' own slots, `bounds[c]..bounds[c + 1]` for chunk `c`.
fn own_slots<'a>(mut values: &'a mut [DVec3], bounds: &[usize]) -> Vec<&'a mut [DVec3]> {
    bounds
        .windows(2)
        .map(|b| {
            let (here, rest) = std::mem::take(&mut values).split_at_mut(b[1] - b[0]);
            values = rest;
            here
        })
        .collect()
}

/// A list pair within reach, found by the first pass of [`chunk_forces`].
#[derive(Clone, Copy, Debug, Default)]
struct Candidate {
    /// The pair's index in the chunk's slice of the list.
    local: u32,
    /// Slots of `i` and `j`.
    i: u32,
    j: u32,
    /// Image code of `j`.
    code: u8,
    /// `r_i − r_j` through the image (m).
    branch: DVec3,
    /// `|r_i − r_j|²` (m²); the contact law takes its square root, four pairs at a time.
    dist: f64,
}

/// Forces of the pairs whose first slot lies in `range`, in two passes: the list is
/// scanned for pairs within reach, written compactly into `found` (touching pairs, and
/// pairs apart within an adhesive law's range), then the contact law runs over each kind
/// four pairs at a time. On x86-64 CPUs with AVX2 the same code is
/// compiled a second time for them and chosen at run time; both give the same bits.
fn chunk_forces<O: ContactObserver>(
    inp: &Inputs<'_>,
    range: std::ops::Range<usize>,
    active: &mut [bool],
    history: &mut HistoryView<'_>,
    sink: ForceSink<'_>,
    found: &mut Found,
) -> O {
    #[cfg(target_arch = "x86_64")]
    if !inp.plain && std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2, checked just above.
        return unsafe { chunk_forces_avx2::<O>(inp, range, active, history, sink, found) };
    }
    chunk_forces_generic::<O, false>(inp, range, active, history, sink, found)
}

/// [`chunk_forces_generic`] compiled with AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn chunk_forces_avx2<O: ContactObserver>(
    inp: &Inputs<'_>,
    range: std::ops::Range<usize>,
    active: &mut [bool],
    history: &mut HistoryView<'_>,
    sink: ForceSink<'_>,
    found: &mut Found,
) -> O {
    chunk_forces_generic::<O, true>(inp, range, active, history, sink, found)
}

/// With `AVX` (which the CPU must have) the law's lane groups are put together in
/// registers.
#[inline(always)]
fn chunk_forces_generic<O: ContactObserver, const AVX: bool>(
    inp: &Inputs<'_>,
    range: std::ops::Range<usize>,
    active: &mut [bool],
    history: &mut HistoryView<'_>,
    sink: ForceSink<'_>,
    found: &mut Found,
) -> O {
    let mut obs = O::default();
    let base = inp.offsets[range.start] as usize;
    let Found {
        within,
        lost,
        touching,
        apart,
        kept,
        n_kept,
        pruned,
    } = found;
    // Pass 1a: every pair within reach, compacted without a branch on the distance test
    // (`Scan`). A pair that had a force and is now out of reach drops its history. The
    // scan covers the pairs kept by the list's prune when this chunk holds them, and
    // otherwise the whole chunk, keeping the pairs for the prune (`crate::prune`).
    let end = inp.offsets[range.end] as usize;
    let pairs = end - base;
    if within.len() < pairs {
        within.resize(pairs, Candidate::default());
    }
    if lost.len() < pairs {
        lost.resize(pairs, 0);
    }
    let (stamp, margin) = inp.prune;
    let source = if margin == 0.0 {
        Source::List
    } else if pruned.0 == stamp && pruned.1 == range {
        Source::Kept(&kept[..*n_kept])
    } else {
        if kept.len() < pairs {
            kept.resize(pairs, Kept::default());
        }
        // Stamped once the scan is through, so that a scan cut short leaves no kept
        // pairs for the next call to trust.
        *pruned = (0, 0..0);
        Source::Prune {
            margin,
            kept: &mut kept[..],
            n_kept,
        }
    };
    // With one species, every pair has the same kernel.
    let uniform = inp.laws.species() == 1;
    // Under one irreversible law the scan itself sorts the pairs it finds into touching
    // pairs and pairs apart: it looks for pairs without a bridge up to contact only, so
    // every pair apart within reach is bridged and acts. Elsewhere pass 1b sorts them.
    let gated = inp.free_range < inp.max_range;
    // (`gated` implies a law with a range: `0 ≤ free_range < max_range`.)
    let sorts = uniform && gated;
    if sorts && touching.len() < pairs {
        touching.resize(pairs, 0);
        apart.resize(pairs, 0);
    }
    // Under irreversible laws alone, a pair apart acts only through its bridge, so only
    // bridged pairs are looked for beyond contact (most pairs apart within a bridge's
    // range have never touched).
    let scan = Scan {
        base,
        end,
        active: &*active,
        bridge: history.bridge,
        within,
        lost,
        touching,
        apart,
    };
    let prunes = matches!(source, Source::Prune { .. });
    let counts = if sorts {
        scan.run::<true, true>(inp, source)
    } else if gated {
        scan.run::<true, false>(inp, source)
    } else {
        scan.run::<false, false>(inp, source)
    };
    if prunes {
        *pruned = (stamp, range.clone());
    }
    for &local in &lost[..counts.lost] {
        active[local as usize] = false;
        history.clear(local as usize);
    }
    let n = counts.within;
    // Pass 1b, where the scan did not sort: touching pairs, and pairs apart within an
    // adhesive law's range, as indices into `within`, again without a branch on the
    // distance (under an adhesive law about half the pairs within reach touch). A pair
    // apart without a bridge under an irreversible law has no force and drops its
    // history.
    if touching.len() < n {
        touching.resize(n, 0);
        apart.resize(n, 0);
    }
    let (n_touching, n_apart) = if inp.max_range == 0.0 {
        // No law acts beyond contact: every pair within reach touches (`d² < fl(s²)`
        // gives `√d² ≤ s`, see [`touches`]), so they all go to the law, in order.
        for (q, t) in touching[..n].iter_mut().enumerate() {
            *t = q as u32;
        }
        (n, 0)
    } else if sorts {
        (counts.touching, counts.apart)
    } else {
        let split = Split {
            within: &within[..n],
            bridge: history.bridge,
            active,
            touching,
            apart,
            lost,
        };
        let (n_touching, n_apart, n_lost) = if inp.laws.forms_bridges() {
            split.run::<true>(inp, uniform)
        } else {
            split.run::<false>(inp, uniform)
        };
        for &local in &lost[..n_lost] {
            active[local as usize] = false;
            history.clear(local as usize);
        }
        (n_touching, n_apart)
    };
    // Pass 2: the contact law over each kind of pair, four at a time.
    let within = &within[..n];
    let same_kernel = |batch: &[u32]| {
        let first = inp.kernel_of(&within[batch[0] as usize]);
        batch
            .iter()
            .all(|&q| inp.kernel_of(&within[q as usize]) == first)
    };
    // The touching pairs, each lane group compiled for its normal law: the law is matched
    // once for the whole chunk when every pair has the same kernel, once per lane group
    // otherwise.
    if uniform {
        if n_touching > 0 {
            touching_pairs::<O, AVX>(
                inp,
                within,
                &touching[..n_touching],
                active,
                history,
                sink,
                &mut obs,
            );
        }
    } else {
        for batch in touching[..n_touching].chunks(LANES) {
            if same_kernel(batch) {
                touching_pairs::<O, AVX>(inp, within, batch, active, history, sink, &mut obs);
            } else {
                for q in batch {
                    touching_pairs::<O, AVX>(
                        inp,
                        within,
                        std::slice::from_ref(q),
                        active,
                        history,
                        sink,
                        &mut obs,
                    );
                }
            }
        }
    }
    for batch in apart[..n_apart].chunks(LANES) {
        if uniform || same_kernel(batch) {
            apart_batch::<O, AVX>(
                inp,
                inp.kernel_of(&within[batch[0] as usize]),
                within,
                batch,
                active,
                history,
                sink,
                &mut obs,
            );
        } else {
            for q in batch {
                apart_batch::<O, AVX>(
                    inp,
                    inp.kernel_of(&within[*q as usize]),
                    within,
                    std::slice::from_ref(q),
                    active,
                    history,
                    sink,
                    &mut obs,
                );
            }
        }
    }
    obs
}

/// Contacts per lane group of the law.
const LANES: usize = 4;

/// Pass 1a of [`chunk_forces`]: the arrays it reads and fills.
struct Scan<'a> {
    /// The chunk's first pair (index into the list).
    base: usize,
    /// One past the chunk's last pair.
    end: usize,
    /// Force flags of the chunk's pairs.
    active: &'a [bool],
    /// Bridge flags of the chunk's pairs.
    bridge: &'a [bool],
    /// Filled with the pairs within reach; holds at least as many as the chunk's pairs.
    within: &'a mut [Candidate],
    /// Filled with the pairs that had a force and are now out of reach (indices into the
    /// chunk's pairs); holds at least as many as the chunk's pairs.
    lost: &'a mut [u32],
    /// Filled, when the scan sorts the pairs it finds, with the touching ones (indices
    /// into `within`); holds at least as many as the chunk's pairs.
    touching: &'a mut [u32],
    /// Likewise with the pairs apart within reach.
    apart: &'a mut [u32],
}

/// The pairs pass 1a scans.
enum Source<'a> {
    /// Every pair of the chunk.
    List,
    /// Every pair of the chunk, keeping those within `margin` (m) of their reach in
    /// `kept` and their count in `n_kept`.
    Prune {
        margin: f64,
        kept: &'a mut [Kept],
        n_kept: &'a mut usize,
    },
    /// The pairs kept by the last prune.
    Kept(&'a [Kept]),
}

impl Scan<'_> {
    /// Writes every pair within reach into `within` and every pair that had a force and
    /// is out of reach into `lost`, without a branch on the distance test (about half the
    /// list pairs touch, so that branch would be unpredictable), in one flat loop over the
    /// pairs of `source` (a loop per row would end at an unpredictable length). The reach
    /// is the contact plus [`Inputs::max_range`], or, when `GATED`, plus
    /// [`Inputs::free_range`] for a pair without a bridge. With `SORT` the pairs within reach
    /// are also sorted into touching pairs and pairs apart. Returns the counts.
    #[inline(always)]
    fn run<const GATED: bool, const SORT: bool>(
        self,
        inp: &Inputs<'_>,
        source: Source<'_>,
    ) -> Counts {
        let Scan {
            base,
            end,
            active,
            bridge,
            within,
            lost,
            touching,
            apart,
        } = self;
        let pairs = end - base;
        assert!(active.len() >= pairs && bridge.len() >= pairs);
        assert!(within.len() >= pairs && lost.len() >= pairs);
        assert!(!SORT || (touching.len() >= pairs && apart.len() >= pairs));
        let (first, partner, image) = (
            &inp.first[base..end],
            &inp.partner[base..end],
            &inp.image[base..end],
        );
        let mut sink = Sink {
            active,
            bridge,
            within,
            lost,
            touching,
            apart,
            free: inp.free_range.to_bits(),
            bridged: inp.max_range.to_bits(),
            counts: Counts::default(),
        };
        match source {
            Source::List => {
                for local in 0..pairs {
                    // SAFETY: `local < pairs`, the length of the chunk's slices, whose
                    // rows and partners are slots (the list fits the particles, checked by
                    // `pair_forces`).
                    unsafe {
                        sink.visit::<GATED, SORT>(
                            inp,
                            at(first, local) as usize,
                            at(partner, local) as usize,
                            at(image, local),
                            local,
                        );
                    }
                }
            }
            Source::Prune {
                margin,
                kept,
                n_kept,
            } => {
                assert!(kept.len() >= pairs);
                let mut k = 0;
                for local in 0..pairs {
                    // SAFETY: as above; `k` is at most `local`, below the length of `kept`
                    // (asserted above).
                    unsafe {
                        let (i, j, code) = (at(first, local), at(partner, local), at(image, local));
                        let (d2, reach) =
                            sink.visit::<GATED, SORT>(inp, i as usize, j as usize, code, local);
                        let outer = reach + margin;
                        *at_mut(kept, k) = Kept {
                            i,
                            j,
                            local: local as u32,
                            code,
                        };
                        k += usize::from(d2 < outer * outer);
                    }
                }
                *n_kept = k;
            }
            Source::Kept(kept) => {
                for p in kept {
                    // SAFETY: the prune kept pairs of this chunk's slices (its stamp and
                    // range were checked by the caller), with their slots.
                    unsafe {
                        sink.visit::<GATED, SORT>(
                            inp,
                            p.i as usize,
                            p.j as usize,
                            p.code,
                            p.local as usize,
                        )
                    };
                }
            }
        }
        sink.counts
    }
}

/// How many pairs pass 1a wrote into each of its arrays.
#[derive(Clone, Copy, Debug, Default)]
struct Counts {
    /// Pairs within reach.
    within: usize,
    /// Pairs that had a force and are now out of reach.
    lost: usize,
    /// Touching pairs, when the scan sorts them.
    touching: usize,
    /// Pairs apart within reach, when the scan sorts them.
    apart: usize,
}

/// Where pass 1a writes the pairs it visits.
struct Sink<'a> {
    /// Force flags of the chunk's pairs.
    active: &'a [bool],
    /// Bridge flags of the chunk's pairs.
    bridge: &'a [bool],
    /// Pairs within reach, the first `n` of them found.
    within: &'a mut [Candidate],
    /// Pairs that had a force and are now out of reach, the first `counts.lost` of them
    /// found.
    lost: &'a mut [u32],
    /// Touching pairs found (indices into `within`), when sorting.
    touching: &'a mut [u32],
    /// Pairs apart within reach found (indices into `within`), when sorting.
    apart: &'a mut [u32],
    /// The bits of [`Inputs::free_range`] and [`Inputs::max_range`].
    free: u64,
    bridged: u64,
    counts: Counts,
}

impl Sink<'_> {
    /// The chunk's pair `local`, of slots `i` and `j` (seen through image `code`):
    /// written into `within` and `lost` (and with `SORT` into `touching` and `apart`),
    /// each count advancing when it belongs there. Returns its squared distance and its
    /// reach (m², m).
    ///
    /// # Safety
    /// `i` and `j` are slots of the particle arrays and `local` a pair of the chunk, below
    /// the lengths of `active` and `bridge`; fewer pairs have been visited than `within`
    /// and `lost` hold.
    #[inline(always)]
    unsafe fn visit<const GATED: bool, const SORT: bool>(
        &mut self,
        inp: &Inputs<'_>,
        i: usize,
        j: usize,
        code: u8,
        local: usize,
    ) -> (f64, f64) {
        // SAFETY: the caller's contract; `n` and `n_lost` count some of the pairs visited
        // before, fewer than `within` and `lost` hold.
        unsafe {
            let range = if GATED {
                // Chosen bit by bit, not by a branch: whether a pair is bridged is
                // unpredictable.
                let mask = 0u64.wrapping_sub(u64::from(at(self.bridge, local)));
                f64::from_bits(self.free ^ ((self.free ^ self.bridged) & mask))
            } else {
                inp.max_range
            };
            let (c, sum, reach) = inp.candidate(i, j, code, local, range);
            let (d2, inside) = (c.dist, c.dist < reach * reach);
            let n = &mut self.counts;
            let q = n.within;
            *at_mut(self.within, q) = c;
            n.within += usize::from(inside);
            *at_mut(self.lost, n.lost) = local as u32;
            n.lost += usize::from(at(self.active, local) & !inside);
            if SORT {
                let touches = touches(d2, sum);
                *at_mut(self.touching, n.touching) = q as u32;
                n.touching += usize::from(inside & touches);
                *at_mut(self.apart, n.apart) = q as u32;
                n.apart += usize::from(inside & !touches);
            }
            (d2, reach)
        }
    }
}

/// Pass 1b of [`chunk_forces`]: the arrays it reads and fills.
struct Split<'a> {
    /// Pairs within reach.
    within: &'a [Candidate],
    /// Bridge flags of the chunk's pairs.
    bridge: &'a [bool],
    /// Force flags of the chunk's pairs.
    active: &'a [bool],
    /// Filled with the touching pairs (indices into `within`); holds at least as many.
    touching: &'a mut [u32],
    /// Filled with the pairs apart that the law acts on; holds at least as many as `within`.
    apart: &'a mut [u32],
    /// Filled with the pairs apart that lose their force; holds at least as many as
    /// `within`.
    lost: &'a mut [u32],
}

impl Split<'_> {
    /// Sorts the pairs within reach into touching pairs, pairs apart that the law acts on
    /// and pairs apart that lose their force (apart without a bridge under an
    /// irreversible law, while they had a force), without a branch on the distance (under
    /// an adhesive law about half the pairs within reach touch). `BRIDGES` says whether
    /// any law of the table forms bridges (without, every pair apart goes to the law);
    /// `uniform` that every pair has the same kernel. Returns the three counts.
    #[inline(always)]
    fn run<const BRIDGES: bool>(self, inp: &Inputs<'_>, uniform: bool) -> (usize, usize, usize) {
        let Split {
            within,
            bridge,
            active,
            touching,
            apart,
            lost,
        } = self;
        assert!(touching.len() >= within.len() && apart.len() >= within.len());
        assert!(lost.len() >= within.len());
        let (mut n_touching, mut n_apart, mut n_lost) = (0, 0, 0);
        for (q, c) in within.iter().enumerate() {
            let (i, j, local) = (c.i as usize, c.j as usize, c.local as usize);
            let needs_bridge = BRIDGES && (uniform || inp.kernel_of(c).needs_bridge());
            // SAFETY: the pair was found in the list, which fits the particles: `i` and
            // `j` are slots, `local` a pair of the chunk's slices; `n_touching`, `n_apart`
            // and `n_lost` are at most `q`, below the length of `within` and so of
            // `touching`, `apart` and `lost` (asserted above).
            unsafe {
                let sum = at(inp.radius, i) + at(inp.radius, j);
                let touches = touches(c.dist, sum);
                let acts = !needs_bridge || at(bridge, local);
                *at_mut(touching, n_touching) = q as u32;
                n_touching += usize::from(touches);
                *at_mut(apart, n_apart) = q as u32;
                n_apart += usize::from(!touches & acts);
                if BRIDGES {
                    *at_mut(lost, n_lost) = local as u32;
                    n_lost += usize::from(!touches & !acts & at(active, local));
                }
            }
        }
        (n_touching, n_apart, n_lost)
    }
}

/// Whether a pair at squared distance `d2` (m²) touches, for the sum of radii `s` (m):
/// `s − √d2 ≥ 0` with the square root rounded, as the law computes it, without taking the
/// root save in rare cases. `d2 ≤ fl(s²)` implies it, as the rounded root is monotone and
/// the rounded root of a rounded square is the number itself (base 2, no underflow).
/// Above `fl(s²)` the root rounds down to `s` only within a relative `2⁻⁵⁰` of it, where
/// it is taken.
#[inline(always)]
fn touches(d2: f64, s: f64) -> bool {
    let s2 = s * s;
    if d2 > s2 && d2 <= s2 * (1.0 + 8.0 * f64::EPSILON) {
        return s - d2.sqrt() >= 0.0;
    }
    d2 <= s2
}

/// The pairs of `batch` (indices into `within`), one per lane; the lanes past
/// `batch.len()` repeat the first pair.
#[inline(always)]
fn lanes_of<'a>(within: &'a [Candidate], batch: &[u32]) -> [&'a Candidate; LANES] {
    std::array::from_fn(|l| &within[*batch.get(l).unwrap_or(&batch[0]) as usize])
}

/// `s[i]` without a bounds check.
///
/// # Safety
/// `i < s.len()`.
#[inline(always)]
unsafe fn at<T: Copy>(s: &[T], i: usize) -> T {
    debug_assert!(i < s.len());
    // SAFETY: the caller guarantees `i < s.len()`.
    unsafe { *s.get_unchecked(i) }
}

/// `&mut s[i]` without a bounds check.
///
/// # Safety
/// `i < s.len()`.
#[inline(always)]
unsafe fn at_mut<T>(s: &mut [T], i: usize) -> &mut T {
    debug_assert!(i < s.len());
    // SAFETY: the caller guarantees `i < s.len()`.
    unsafe { s.get_unchecked_mut(i) }
}

impl Inputs<'_> {
    /// The list pair of slots `i` and `j` (seen through image `code`), the chunk's pair
    /// `local`, with its branch vector and squared distance, and its reach (the contact
    /// plus `range`, m).
    ///
    /// # Safety
    /// `i` and `j` are slots of the particle arrays.
    #[inline(always)]
    unsafe fn candidate(
        &self,
        i: usize,
        j: usize,
        code: u8,
        local: usize,
        range: f64,
    ) -> (Candidate, f64, f64) {
        // SAFETY: `i` and `j` are slots (the caller's contract).
        let (r_i, a_i, r_j, a_j) = unsafe {
            (
                at(self.position, i),
                at(self.radius, i),
                at(self.position, j),
                at(self.radius, j),
            )
        };
        let r_j = if code == IDENTITY_IMAGE {
            r_j
        } else {
            self.images[code as usize].position(r_j)
        };
        let branch = r_i - r_j;
        let d2 = branch.length_squared();
        let sum = a_i + a_j;
        let reach = sum + range;
        let c = Candidate {
            local: local as u32,
            i: i as u32,
            j: j as u32,
            code,
            branch,
            dist: d2,
        };
        (c, sum, reach)
    }

    /// The kernel of a pair.
    #[inline(always)]
    fn kernel_of(&self, c: &Candidate) -> &PairKernel {
        self.laws
            .kernel(self.species[c.i as usize], self.species[c.j as usize])
    }

    /// Velocity and angular velocity of `j` seen through image `code`.
    #[inline(always)]
    fn partner_motion(&self, j: usize, code: u8) -> (DVec3, DVec3) {
        self.through_image(code, self.velocity[j], self.omega[j])
    }

    /// A partner's velocity `v` and angular velocity `w` seen through image `code`.
    #[inline(always)]
    fn through_image(&self, code: u8, v: DVec3, w: DVec3) -> (DVec3, DVec3) {
        if code == IDENTITY_IMAGE {
            (v, w)
        } else {
            let image = &self.images[code as usize];
            (image.velocity(v), image.angular_velocity(w))
        }
    }

    /// [`Inputs::partner_motion`] without bounds checks.
    ///
    /// # Safety
    /// `j` is a slot of the particle arrays.
    #[inline(always)]
    unsafe fn partner_motion_unchecked(&self, j: usize, code: u8) -> (DVec3, DVec3) {
        // SAFETY: the caller's contract.
        let (v, w) = unsafe { (at(self.velocity, j), at(self.omega, j)) };
        self.through_image(code, v, w)
    }

    /// The relative velocity (m/s) a contact with branch `branch` (m) sees, from the
    /// difference `dv` (m/s) of the stored velocities: less the mean flow's difference
    /// across the pair where contacts measure against it.
    #[inline(always)]
    fn relative_velocity(&self, dv: DVec3, branch: DVec3) -> DVec3 {
        match self.mean_flow {
            Some(gradient) => dv - gradient * branch,
            None => dv,
        }
    }

    /// The kinematics of a pair at distance `dist` (m; `overlap` of either sign).
    #[inline(always)]
    fn kinematics(&self, i: usize, j: usize, code: u8, branch: DVec3, dist: f64) -> PairKinematics {
        let (v_j, w_j) = self.partner_motion(j, code);
        PairKinematics {
            normal: branch * (1.0 / dist),
            overlap: self.radius[i] + self.radius[j] - dist,
            radius_i: self.radius[i],
            radius_j: self.radius[j],
            velocity: self.relative_velocity(self.velocity[i] - v_j, branch),
            omega_i: self.omega[i],
            omega_j: w_j,
            reduced_mass: 1.0 / (self.inv_mass[i] + self.inv_mass[j]),
        }
    }
}

/// Adds the forces of `pf` on `i` and (through the image) on `j`.
///
/// # Safety
/// `i` is one of the sink's own slots, `j` one of them or in its halo.
#[inline(always)]
unsafe fn add_pair(
    sink: ForceSink<'_>,
    image: &ImageTransform,
    i: usize,
    j: usize,
    pf: &PairForce,
) {
    // SAFETY: the caller's contract.
    let (f_i, t_i) = unsafe { sink.own(i) };
    *f_i += pf.force;
    *t_i += pf.torque_i;
    // SAFETY: the caller's contract.
    let (f_j, t_j) = unsafe { sink.slot(j) };
    if image.rotation.is_none() {
        *f_j -= pf.force;
        *t_j += pf.torque_j;
    } else {
        *f_j -= image.vector_back(pf.force);
        *t_j += image.vector_back(pf.torque_j);
    }
}

/// Up to [`LANES`] pairs apart within the interaction range with the same kernel,
/// evaluated in one lane group as [`touch_batch`] does. Their springs relax; the adhesive
/// law (and its bridge) alone may act.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn apart_batch<O: ContactObserver, const AVX: bool>(
    inp: &Inputs<'_>,
    kernel: &PairKernel,
    within: &[Candidate],
    batch: &[u32],
    active: &mut [bool],
    history: &mut HistoryView<'_>,
    sink: ForceSink<'_>,
    obs: &mut O,
) {
    let c = lanes_of(within, batch);
    let (mut branch, mut dist) = ([DVec3::ZERO; LANES], [0.0; LANES]);
    let (mut radius_i, mut radius_j) = ([0.0; LANES], [0.0; LANES]);
    let mut bridge = [false; LANES];
    for (l, bridged) in bridge.iter_mut().enumerate() {
        let (i, j) = (c[l].i as usize, c[l].j as usize);
        branch[l] = c[l].branch;
        dist[l] = c[l].dist;
        // SAFETY: the pair was found in a list that fits the particles (checked by
        // `pair_forces`): `i` and `j` are slots, `local` a pair of the chunk's slices.
        unsafe {
            radius_i[l] = at(inp.radius, i);
            radius_j[l] = at(inp.radius, j);
            *bridged = at(history.bridge, c[l].local as usize);
        }
    }
    // SAFETY: with `AVX` the CPU has AVX (the caller's contract).
    let (branch, dist, radius_i, radius_j) = unsafe {
        (
            V3::from_rows::<AVX>(branch),
            F4::from_array::<AVX>(dist),
            F4::from_array::<AVX>(radius_i),
            F4::from_array::<AVX>(radius_j),
        )
    };
    let dist = dist.sqrt();
    let normal = branch.scale(F4::splat(1.0) / dist);
    let separation = -((radius_i + radius_j) - dist);
    let (f_a, alive) = kernel.apart_lanes::<F4, false>(separation, radius_i, radius_j, bridge);
    let (rotation, keeps_state) = (kernel.resists_rotation(), kernel.keeps_state());
    let sliding_state = kernel.sliding_keeps_state();
    for (l, c) in c.iter().enumerate().take(batch.len()) {
        let (i, j, local) = (c.i as usize, c.j as usize, c.local as usize);
        // The springs relax. Those of rotation stay zero under a law without them, so
        // their slots (a cache line each) are left untouched.
        // SAFETY: `local` is a pair of the chunk's slices (see above).
        unsafe {
            *at_mut(history.tangential, local) = DVec3::ZERO;
            if rotation {
                *at_mut(history.rolling, local) = DVec3::ZERO;
                *at_mut(history.torsion, local) = DVec3::ZERO;
            }
            if keeps_state {
                *at_mut(history.state, local) = 0.0;
            }
            if sliding_state {
                *at_mut(history.sliding_state, local) = 0.0;
            }
            *at_mut(history.bridge, local) = alive[l];
            *at_mut(active, local) = f_a.0[l] != 0.0;
        }
        let f = f_a.0[l];
        if f == 0.0 {
            continue;
        }
        let pf = PairForce {
            force: normal.lane(l) * f,
            adhesive: f,
            ..PairForce::default()
        };
        let image = &inp.images[c.code as usize];
        // SAFETY: the pair was found in a list that fits the particles, and `force` and
        // `torque` hold one entry per particle (checked by `pair_forces`).
        unsafe { add_pair(sink, image, i, j, &pf) };
        if O::OBSERVES {
            obs.visit(&ContactView {
                ids: [inp.id[i], inp.id[j]],
                parts: [inp.part[i], inp.part[j]],
                wall: None,
                image,
                position: inp.position[i],
                branch: c.branch,
                kinematics: &inp.kinematics(i, j, c.code, c.branch, dist.0[l]),
                force: &pf,
                kernel,
                history: &history.get(local),
            });
        }
    }
}

/// The touching pairs `pairs` (indices into `within`), all with the same kernel, lane
/// group by lane group, compiled for the kernel's normal law (matched once here).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn touching_pairs<O: ContactObserver, const AVX: bool>(
    inp: &Inputs<'_>,
    within: &[Candidate],
    pairs: &[u32],
    active: &mut [bool],
    history: &mut HistoryView<'_>,
    sink: ForceSink<'_>,
    obs: &mut O,
) {
    let kernel = inp.kernel_of(&within[pairs[0] as usize]);
    kernel.normal().with(Touches::<O, AVX> {
        inp,
        kernel,
        within,
        pairs,
        active,
        history,
        sink,
        obs,
    });
}

/// Touching pairs with the same kernel, evaluated lane group by lane group with the
/// kernel's normal law as its own type ([`WithNormal`]).
struct Touches<'a, 'h, 's, O, const AVX: bool> {
    inp: &'a Inputs<'a>,
    kernel: &'a PairKernel,
    within: &'a [Candidate],
    pairs: &'a [u32],
    active: &'a mut [bool],
    history: &'a mut HistoryView<'h>,
    sink: ForceSink<'s>,
    obs: &'a mut O,
}

impl<O: ContactObserver, const AVX: bool> WithNormal for Touches<'_, '_, '_, O, AVX> {
    type Output = ();

    #[inline(always)]
    fn run<N: NormalForce>(self, normal: &N) {
        let kernel = self.kernel;
        kernel.tangential().with(TouchesWith {
            touches: self,
            normal,
        });
    }
}

/// [`Touches`] with the kernel's normal law as its own type, evaluated with its sliding
/// spring as its own type ([`WithSpring`]).
struct TouchesWith<'a, 'h, 's, 'n, O, const AVX: bool, N> {
    touches: Touches<'a, 'h, 's, O, AVX>,
    normal: &'n N,
}

impl<O: ContactObserver, const AVX: bool, N: NormalForce> WithSpring
    for TouchesWith<'_, '_, '_, '_, O, AVX, N>
{
    type Output = ();

    #[inline(always)]
    fn run<S: SpringModel>(self, sliding: &S) {
        let t = self.touches;
        for batch in t.pairs.chunks(LANES) {
            touch_batch::<O, AVX, N, S>(
                t.inp,
                t.kernel,
                self.normal,
                sliding,
                t.within,
                batch,
                t.active,
                t.history,
                t.sink,
                t.obs,
            );
        }
    }
}

/// Up to [`LANES`] touching pairs with the same kernel, evaluated in one lane group (the
/// lanes past `batch.len()` repeat the first pair and are discarded). With `AVX` (which
/// the CPU must have) the lane groups are put together in registers.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn touch_batch<O: ContactObserver, const AVX: bool, N: NormalForce, S: SpringModel>(
    inp: &Inputs<'_>,
    kernel: &PairKernel,
    normal: &N,
    sliding: &S,
    within: &[Candidate],
    batch: &[u32],
    active: &mut [bool],
    history: &mut HistoryView<'_>,
    sink: ForceSink<'_>,
    obs: &mut O,
) {
    let mut springs = HistoryLanes::<F4>::default();
    let (rotation, bridges) = (kernel.resists_rotation(), kernel.needs_bridge());
    let keeps_state = normal.keeps_state();
    let sliding_state = S::KEEPS_STATE && kernel.sliding_keeps_state();
    let c = lanes_of(within, batch);
    // Lane by lane into rows, then into lane groups.
    let (mut branch, mut velocity, mut omega_i, mut omega_j, mut tangential) = (
        [DVec3::ZERO; LANES],
        [DVec3::ZERO; LANES],
        [DVec3::ZERO; LANES],
        [DVec3::ZERO; LANES],
        [DVec3::ZERO; LANES],
    );
    let (mut dist, mut radius_i, mut radius_j, mut inv_mass_i, mut inv_mass_j) = (
        [0.0; LANES],
        [0.0; LANES],
        [0.0; LANES],
        [0.0; LANES],
        [0.0; LANES],
    );
    for (l, c) in c.iter().enumerate() {
        let (i, j, local) = (c.i as usize, c.j as usize, c.local as usize);
        // SAFETY: the pair was found in a list that fits the particles (checked by
        // `pair_forces`): `i` and `j` are slots, `local` a pair of the chunk's slices.
        unsafe {
            let (v_j, w_j) = inp.partner_motion_unchecked(j, c.code);
            branch[l] = c.branch;
            dist[l] = c.dist;
            radius_i[l] = at(inp.radius, i);
            radius_j[l] = at(inp.radius, j);
            velocity[l] = inp.relative_velocity(at(inp.velocity, i) - v_j, c.branch);
            omega_i[l] = at(inp.omega, i);
            omega_j[l] = w_j;
            inv_mass_i[l] = at(inp.inv_mass, i);
            inv_mass_j[l] = at(inp.inv_mass, j);
            tangential[l] = at(history.tangential, local);
        }
        if rotation {
            springs.rolling.set_lane(l, history.rolling[local]);
            springs.torsion.set_lane(l, history.torsion[local]);
        }
        if keeps_state {
            springs.state.0[l] = history.state[local];
        }
        if sliding_state {
            springs.sliding_state.0[l] = history.sliding_state[local];
        }
    }
    // SAFETY: with `AVX` the CPU has AVX (the caller's contract).
    let mut pair = unsafe {
        Touch {
            normal: V3::from_rows::<AVX>(branch),
            radius_i: F4::from_array::<AVX>(radius_i),
            radius_j: F4::from_array::<AVX>(radius_j),
            velocity: V3::from_rows::<AVX>(velocity),
            omega_i: V3::from_rows::<AVX>(omega_i),
            omega_j: V3::from_rows::<AVX>(omega_j),
            ..Touch::default()
        }
    };
    // SAFETY: as above.
    let (dist, inv_mass) = unsafe {
        springs.tangential = V3::from_rows::<AVX>(tangential);
        (
            F4::from_array::<AVX>(dist),
            F4::from_array::<AVX>(inv_mass_i) + F4::from_array::<AVX>(inv_mass_j),
        )
    };
    let one = F4::splat(1.0);
    let dist = dist.sqrt();
    pair.normal = pair.normal.scale(one / dist);
    pair.overlap = (pair.radius_i + pair.radius_j) - dist;
    pair.reduced_mass = one / inv_mass;
    let f =
        kernel.touching_lanes_with::<F4, false, N, S>(normal, sliding, &pair, &mut springs, inp.dt);
    for (l, c) in c.iter().enumerate().take(batch.len()) {
        let (i, j, local) = (c.i as usize, c.j as usize, c.local as usize);
        // SAFETY: `local` is a pair of the chunk's slices (see above).
        unsafe { *at_mut(history.tangential, local) = springs.tangential.lane(l) };
        if rotation {
            history.rolling[local] = springs.rolling.lane(l);
            history.torsion[local] = springs.torsion.lane(l);
        }
        if keeps_state {
            history.state[local] = springs.state.0[l];
        }
        if sliding_state {
            history.sliding_state[local] = springs.sliding_state.0[l];
        }
        // SAFETY: as above.
        unsafe {
            if bridges {
                *at_mut(history.bridge, local) = true;
            }
            *at_mut(active, local) = true;
        }
        let pf = PairForce {
            force: f.force.lane(l),
            torque_i: f.torque_i.lane(l),
            torque_j: f.torque_j.lane(l),
            repulsive: f.repulsive.0[l],
            adhesive: f.adhesive.0[l],
            sliding: f.sliding[l],
        };
        let image = &inp.images[c.code as usize];
        // SAFETY: `i` and `j` are slots, and `force` and `torque` hold one entry per
        // particle (checked by `pair_forces`).
        unsafe { add_pair(sink, image, i, j, &pf) };
        if O::OBSERVES {
            let kin = PairKinematics {
                normal: pair.normal.lane(l),
                overlap: pair.overlap.0[l],
                radius_i: pair.radius_i.0[l],
                radius_j: pair.radius_j.0[l],
                velocity: pair.velocity.lane(l),
                omega_i: pair.omega_i.lane(l),
                omega_j: pair.omega_j.lane(l),
                reduced_mass: pair.reduced_mass.0[l],
            };
            obs.visit(&ContactView {
                ids: [inp.id[i], inp.id[j]],
                parts: [inp.part[i], inp.part[j]],
                wall: None,
                image,
                position: inp.position[i],
                branch: c.branch,
                kinematics: &kin,
                force: &pf,
                kernel,
                history: &history.get(local),
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::standard::{bench_adhesion, bench_law, bench_law_with};
    use crate::contact::{Adhesion, ContactHistory, ContactLaw, Damping, LudingNormal, Resistance};
    use crate::contact::{LawKind, LinearIrreversible, NormalKind};
    use crate::domain::Domain;
    use crate::particles::{Motion, Sphere};
    use rand::{RngExt, SeedableRng};

    /// The bench law with `adhesion`, and with rolling and torsion resistance when `rotation`.
    fn law(adhesion: Adhesion, rotation: bool) -> ContactLaw {
        let mut law = bench_law();
        law.adhesion = adhesion;
        if rotation {
            let r = Resistance {
                stiffness: 1000.0,
                mu_static: 0.1,
                mu_dynamic: 0.1,
                ..*law
                    .tangential
                    .linear()
                    .expect("the bench's sliding spring is linear")
            };
            (law.rolling, law.torsion) = (r.into(), r.into());
        }
        law
    }

    /// 200 spheres of radius 0.4–0.6 and of species 0 or 1, dropped at random into a
    /// periodic box of edge 6 (φ ≈ 0.5, so that many overlap and many are apart within a
    /// bridge's range), moving and spinning at random.
    fn random_spheres(rng: &mut rand_xoshiro::Xoshiro256PlusPlus) -> (Particles, Domain) {
        let domain = Domain::new(DVec3::ZERO, DVec3::splat(6.0), [true; 3]);
        let mut p = Particles::default();
        let mut random_vector =
            |scale: f64| DVec3::new(rng.random::<f64>(), rng.random(), rng.random()) * scale;
        for k in 0..200 {
            let s = Sphere {
                position: random_vector(6.0),
                velocity: random_vector(2.0) - 1.0,
                angular_velocity: random_vector(4.0) - 2.0,
                radius: 0.4 + 0.2 * random_vector(1.0).x,
                species: (k % 2) as u16,
                motion: Motion::Free,
            };
            p.push(s, 1.0);
        }
        (p, domain)
    }

    /// The forces, torques and list histories that the scalar law gives, pair by pair in
    /// list order, for the list as it stands (which this advances as the loop would).
    fn scalar_forces(
        p: &Particles,
        list: &mut NeighborList,
        laws: &ContactTable,
        domain: &Domain,
        dt: f64,
    ) -> (Vec<DVec3>, Vec<DVec3>) {
        let images = domain.image_transforms();
        let (mut force, mut torque) = (vec![DVec3::ZERO; p.len()], vec![DVec3::ZERO; p.len()]);
        let mut s = list.slices();
        for i in 0..p.len() {
            for k in s.offsets[i] as usize..s.offsets[i + 1] as usize {
                let (j, image) = (s.partner[k] as usize, &images[s.image[k] as usize]);
                let branch = p.position[i] - image.position(p.position[j]);
                let dist = branch.length();
                let reach = p.radius[i] + p.radius[j] + laws.max_range();
                if branch.length_squared() >= reach * reach {
                    if s.active[k] {
                        s.active[k] = false;
                        s.history.clear(k);
                    }
                    continue;
                }
                let kin = PairKinematics {
                    normal: branch * (1.0 / dist),
                    overlap: p.radius[i] + p.radius[j] - dist,
                    radius_i: p.radius[i],
                    radius_j: p.radius[j],
                    velocity: p.velocity[i] - image.velocity(p.velocity[j]),
                    omega_i: p.angular_velocity[i],
                    omega_j: image.angular_velocity(p.angular_velocity[j]),
                    reduced_mass: 1.0 / (p.inv_mass[i] + p.inv_mass[j]),
                };
                let mut h: ContactHistory = s.history.get(k);
                let pf = laws
                    .get(p.species[i], p.species[j])
                    .interact(&kin, &mut h, dt);
                s.history.set(k, &h);
                s.active[k] = pf.is_some();
                if let Some(pf) = pf {
                    force[i] += pf.force;
                    force[j] -= pf.force;
                    torque[i] += pf.torque_i;
                    torque[j] += pf.torque_j;
                }
            }
        }
        (force, torque)
    }

    /// Under irreversible laws the list leaves out pairs apart without a bridge beyond the
    /// contact plus the skin; rebuilt again and again as bridges form, stretch and break,
    /// it gives the forces of the list of every pair within the bridge's range plus the
    /// skin (the same bits on one thread, where the pairs that act meet in the same order).
    #[test]
    fn a_list_without_idle_pairs_apart_gives_the_forces_of_the_full_list() {
        let willett = bench_adhesion(LawKind::LiquidBridge);
        let laws = ContactTable::uniform(1, law(willett, true));
        assert_eq!(laws.free_range(), 0.0);
        let (range, dt) = (laws.max_range(), 1e-4);
        for threads in [1, 2] {
            let team = Team::new(threads);
            let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(5);
            let (mut p0, domain) = random_spheres(&mut rng);
            p0.species.fill(0);
            let (mut p_short, mut p_full) = (p0.clone(), p0);
            // A skin below the bridge's range, so that bridges act beyond it.
            let (mut short, mut full) =
                (NeighborList::new(0.1, range), NeighborList::new(0.1, range));
            let mut scratch = ForceScratch::default();
            let mut kept_beyond = 0;
            for round in 0..8 {
                short
                    .build(&mut p_short, &domain, &team, 0.0)
                    .expect("list");
                full.build(&mut p_full, &domain, &team, range)
                    .expect("list");
                assert_eq!(p_short.position, p_full.position, "round {round}: slots");
                assert!(short.len() < full.len(), "round {round}: pairs left out");
                let (images, skin) = (domain.image_transforms(), short.skin);
                let s = short.slices();
                for i in 0..p_short.len() {
                    for k in s.offsets[i] as usize..s.offsets[i + 1] as usize {
                        let (j, image) = (s.partner[k] as usize, &images[s.image[k] as usize]);
                        let d =
                            (p_short.position[i] - image.position(p_short.position[j])).length();
                        let gap = d - p_short.radius[i] - p_short.radius[j];
                        assert!(gap <= skin || s.history.bridge[k], "an idle pair kept");
                        kept_beyond += usize::from(gap > skin && gap < range);
                    }
                }
                for (p, list) in [(&mut p_short, &mut short), (&mut p_full, &mut full)] {
                    pair_forces::<()>(p, list, &laws, &images, None, dt, &mut scratch, &team);
                }
                let scale = p_full.force.iter().map(|f| f.length()).fold(0.0, f64::max);
                for k in 0..p_full.len() {
                    let (a, b) = (p_short.force[k], p_full.force[k]);
                    let (ta, tb) = (p_short.torque[k], p_full.torque[k]);
                    if threads == 1 {
                        assert_eq!((a, ta), (b, tb), "round {round}, particle {k}");
                    } else {
                        let close = (a - b).length() <= 1e-12 * scale
                            && (ta - tb).length() <= 1e-12 * scale;
                        assert!(close, "round {round}, particle {k}: {a} vs {b}");
                    }
                }
                // Moves of up to 0.15 per axis: contacts open, bridges stretch past the
                // contact plus the skin, some break.
                for k in 0..p_full.len() {
                    let step = (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * 0.3;
                    p_short.position[k] += step;
                    p_full.position[k] += step;
                }
            }
            assert!(kept_beyond > 0, "some bridges hold pairs beyond the skin");
        }
    }

    /// Between checks the loop scans only the pairs the last prune kept; step after step,
    /// as particles drift and pairs come within reach and leave it, that gives the bits of
    /// a scan of the whole list (a clone of the list, which scans it whole), under laws
    /// with and without range and with bridges, on one and on two threads.
    #[test]
    fn the_pairs_kept_by_a_prune_give_the_bits_of_the_whole_list() {
        let tables = [
            ("frictional", law(Adhesion::None, false)),
            ("Willett", law(bench_adhesion(LawKind::LiquidBridge), true)),
            (
                "reversible",
                law(bench_adhesion(LawKind::Reversible), false),
            ),
        ];
        let dt = 1e-3;
        for (name, law) in tables {
            let laws = ContactTable::uniform(1, law);
            for threads in [1, 2] {
                let team = Team::new(threads);
                let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(17);
                let (mut p, domain) = random_spheres(&mut rng);
                p.species.fill(0);
                let images = domain.image_transforms();
                let mut list = NeighborList::new(0.3, laws.max_range());
                let mut scratch = ForceScratch::default();
                let (mut kept_steps, mut prunes, mut builds, mut last_stamp) = (0, 0, 0, 0);
                for step in 0..120 {
                    if list.needs_rebuild(&p, &domain, &team, laws.free_range()) {
                        list.build(&mut p, &domain, &team, laws.free_range())
                            .expect("list");
                        builds += 1;
                    }
                    let stamp = list.prune().stamp;
                    if list.prune().is_active() {
                        if stamp == last_stamp {
                            kept_steps += 1;
                        } else {
                            prunes += 1;
                        }
                    }
                    last_stamp = stamp;
                    let (mut p_whole, mut whole) = (p.clone(), list.clone());
                    assert!(!whole.prune().is_active(), "a clone scans the whole list");
                    pair_forces::<()>(
                        &mut p_whole,
                        &mut whole,
                        &laws,
                        &images,
                        None,
                        dt,
                        &mut ForceScratch::default(),
                        &team,
                    );
                    pair_forces::<()>(
                        &mut p,
                        &mut list,
                        &laws,
                        &images,
                        None,
                        dt,
                        &mut scratch,
                        &team,
                    );
                    let bits = |v: &[DVec3]| -> Vec<[u64; 3]> {
                        v.iter().map(|x| x.to_array().map(f64::to_bits)).collect()
                    };
                    let at = format!("{name}, {threads} threads, step {step}");
                    assert_eq!(bits(&p.force), bits(&p_whole.force), "{at}: forces");
                    assert_eq!(bits(&p.torque), bits(&p_whole.torque), "{at}: torques");
                    let (got, want) = (list.slices(), whole.slices());
                    assert_eq!(got.active, want.active, "{at}: force flags");
                    for k in 0..got.active.len() {
                        assert_eq!(got.history.get(k), want.history.get(k), "{at}, pair {k}");
                    }
                    // Drift with the spheres' own velocities (up to 0.002 per step and
                    // axis): contacts open and close, and pairs left out by a prune come
                    // within reach after a later one.
                    for k in 0..p.len() {
                        p.position[k] += p.velocity[k] * 0.002;
                    }
                }
                let at = format!("{name}, {threads} threads");
                assert!(
                    kept_steps > 60,
                    "{at}: {kept_steps} steps scanned the kept pairs"
                );
                assert!(prunes > 3, "{at}: {prunes} prunes");
                assert!(builds > 1, "{at}: {builds} builds");
            }
        }
    }

    /// The test without the root agrees with the law's `s − √d2 ≥ 0` on squared distances
    /// a few units in the last place around `fl(s²)` and at random, for sums of radii over
    /// twelve decades; above `fl(s²)` some still touch (the root rounds down to `s`).
    #[test]
    fn touching_is_told_from_the_squared_distance_as_from_the_distance() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(3);
        let mut above_and_touching = 0;
        for _ in 0..20_000 {
            let s = 10f64.powf(rng.random_range(-7.0..5.0)) * rng.random_range(1.0..10.0);
            let s2 = s * s;
            let mut d2 = s2;
            for _ in 0..6 {
                d2 = d2.next_down();
            }
            let near = (0..13).map(|_| {
                let x = d2;
                d2 = d2.next_up();
                x
            });
            let random = (0..4).map(|_| s2 * rng.random_range(0.5..1.5));
            for d2 in near.chain(random) {
                let law = s - d2.sqrt() >= 0.0;
                assert_eq!(touches(d2, s), law, "s = {s:e}, d² = {d2:e}");
                above_and_touching += usize::from(law && d2 > s2);
            }
        }
        assert!(above_and_touching > 0);
    }

    #[test]
    fn the_pair_loop_gives_the_scalar_law_pair_by_pair() {
        let willett = bench_adhesion(LawKind::LiquidBridge);
        let reversible = bench_adhesion(LawKind::Reversible);
        let linear = Adhesion::LinearIrreversible(LinearIrreversible {
            max_force: 185.0,
            stiffness: 2000.0,
        });
        // A table where some pairs form bridges and others do not, with rotation springs
        // on a third kind: the loop's per-pair paths (lanes of mixed kernels).
        let mut mixed = ContactTable::uniform(2, law(willett, false));
        mixed.set(0, 1, law(reversible, false));
        mixed.set(1, 1, law(Adhesion::None, true));
        // Luding's law keeps a state per contact (its largest overlap): alone, and beside
        // a law that keeps none, with a liquid bridge on top.
        let plastic = |adhesion| ContactLaw {
            normal: LudingNormal {
                stiffness: 1.0e4,
                max_stiffness: 5.0e4,
                adhesive_stiffness: 5.0e3,
                plasticity_depth: 0.05,
                damping: Damping {
                    per_mass: 27.6941,
                    ..Damping::NONE
                },
            }
            .into(),
            ..law(adhesion, true)
        };
        let mut plastic_mixed = ContactTable::uniform(2, plastic(willett));
        plastic_mixed.set(0, 1, law(Adhesion::None, false));
        // Hertz with Mindlin's spring keeps a state of the sliding spring (the contact
        // radius): alone with Rabinovich's bridges, and beside the linear law.
        let hertz = |adhesion| ContactLaw {
            adhesion,
            ..bench_law_with(NormalKind::Hertz)
        };
        let mut hertz_mixed = ContactTable::uniform(2, hertz(Adhesion::None));
        hertz_mixed.set(0, 1, law(willett, false));
        let tables = [
            (
                "frictional",
                ContactTable::uniform(1, law(Adhesion::None, false)),
            ),
            ("Willett", ContactTable::uniform(1, law(willett, true))),
            (
                "linear irreversible",
                ContactTable::uniform(1, law(linear, false)),
            ),
            (
                "reversible",
                ContactTable::uniform(1, law(reversible, false)),
            ),
            ("mixed", mixed),
            ("Luding", ContactTable::uniform(1, plastic(Adhesion::None))),
            ("Luding mixed", plastic_mixed),
            (
                "Hertz-Mindlin, Rabinovich",
                ContactTable::uniform(1, hertz(bench_adhesion(LawKind::Rabinovich))),
            ),
            ("Hertz-Mindlin mixed", hertz_mixed),
        ];
        let dt = 1e-4;
        let images = Domain::new(DVec3::ZERO, DVec3::splat(6.0), [true; 3]).image_transforms();
        for (name, laws) in &tables {
            let species = |k: usize| (k % laws.species()) as u16;
            for threads in [1, 2, 5] {
                let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(11);
                let (mut p, domain) = random_spheres(&mut rng);
                for k in 0..p.len() {
                    p.species[k] = species(k);
                }
                let team = Team::new(threads);
                let mut list = NeighborList::new(0.5, laws.max_range());
                list.build(&mut p, &domain, &team, laws.free_range())
                    .expect("list");
                assert!(list.fits(p.len()));
                let mut scratch = ForceScratch::default();
                let (mut bridges_apart, mut lost) = (0, 0);
                // Three evaluations, the particles moved at random in between (less than the
                // skin): bridges form, some contacts open under them, some bridges break.
                for round in 0..3 {
                    let mut reference = list.clone();
                    let (f_ref, t_ref) = scalar_forces(&p, &mut reference, laws, &domain, dt);
                    let before: Vec<bool> = list.slices().active.to_vec();
                    // The plain copy of the loop, on copies of the same state.
                    let (mut p_plain, mut list_plain) = (p.clone(), list.clone());
                    pair_forces_in::<()>(
                        &mut p_plain,
                        &mut list_plain,
                        laws,
                        &domain.image_transforms(),
                        None,
                        dt,
                        &mut ForceScratch::default(),
                        &team,
                        true,
                    );
                    pair_forces::<()>(
                        &mut p,
                        &mut list,
                        laws,
                        &domain.image_transforms(),
                        None,
                        dt,
                        &mut scratch,
                        &team,
                    );
                    let scale = f_ref.iter().map(|f| f.length()).fold(0.0, f64::max);
                    for k in 0..p.len() {
                        let (df, dtq) = (p.force[k] - f_ref[k], p.torque[k] - t_ref[k]);
                        assert!(
                            df.length() <= 1e-12 * scale && dtq.length() <= 1e-12 * scale,
                            "{name}, {threads} threads, round {round}, particle {k}: force {} \
                             vs {}, torque {} vs {}",
                            p.force[k],
                            f_ref[k],
                            p.torque[k],
                            t_ref[k]
                        );
                    }
                    // Both copies of the loop give the same bits.
                    let bits = |v: &[DVec3]| -> Vec<[u64; 3]> {
                        v.iter().map(|x| x.to_array().map(f64::to_bits)).collect()
                    };
                    assert_eq!(bits(&p.force), bits(&p_plain.force), "{name}: forces");
                    assert_eq!(bits(&p.torque), bits(&p_plain.torque), "{name}: torques");
                    let (got, plain) = (list.slices(), list_plain.slices());
                    for k in 0..got.active.len() {
                        let (a, b) = (got.history.get(k), plain.history.get(k));
                        assert_eq!(
                            (
                                got.active[k],
                                bits(&[a.tangential, a.rolling, a.torsion]),
                                a.bridge,
                                a.state.to_bits(),
                                a.sliding_state.to_bits()
                            ),
                            (
                                plain.active[k],
                                bits(&[b.tangential, b.rolling, b.torsion]),
                                b.bridge,
                                b.state.to_bits(),
                                b.sliding_state.to_bits()
                            ),
                            "{name}, {threads} threads, round {round}, pair {k}: plain copy"
                        );
                    }
                    let (got, want) = (list.slices(), reference.slices());
                    for k in 0..got.active.len() {
                        assert_eq!(
                            (got.active[k], got.history.get(k)),
                            (want.active[k], want.history.get(k)),
                            "{name}, {threads} threads, round {round}, pair {k}"
                        );
                        let i = got.offsets.partition_point(|&o| o as usize <= k) - 1;
                        let (j, image) = (got.partner[k] as usize, &images[got.image[k] as usize]);
                        let apart = (p.position[i] - image.position(p.position[j])).length()
                            > p.radius[i] + p.radius[j];
                        bridges_apart += usize::from(got.history.get(k).bridge && apart);
                        lost += usize::from(before[k] && !got.active[k]);
                    }
                    for r in &mut p.position {
                        *r += (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * 0.2;
                    }
                    // The loop scans the pairs of the last prune until a check renews them.
                    if list.needs_rebuild(&p, &domain, &team, laws.free_range()) {
                        list.build(&mut p, &domain, &team, laws.free_range())
                            .expect("list");
                    }
                }
                assert!(lost > 0, "{name}: some pairs lose their force");
                if laws.kernel(0, 0).keeps_state() {
                    let kept = list
                        .slices()
                        .history
                        .iter()
                        .filter(|h| h.state > 0.0)
                        .count();
                    assert!(kept > 0, "{name}: contacts keep their largest overlap");
                }
                if laws.kernel(0, 0).sliding_keeps_state() {
                    let kept = list
                        .slices()
                        .history
                        .iter()
                        .filter(|h| h.sliding_state > 0.0)
                        .count();
                    assert!(kept > 0, "{name}: contacts keep their radius");
                }
                if laws.forms_bridges() {
                    assert!(bridges_apart > 0, "{name}: some bridges hold pairs apart");
                }
            }
        }
    }
}
