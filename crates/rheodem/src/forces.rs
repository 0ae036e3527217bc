//! The parallel pair-force loop.
//!
//! Scheme: a half Verlet list, split into as many contiguous slot ranges ("chunks") as the
//! thread pool has threads, balanced by pair count. Each chunk accumulates forces and
//! torques of both partners into its own buffer (chunk 0 directly into the particle
//! arrays); the buffers are then added into the particle arrays slot by slot in chunk order.
//! Each pair is evaluated once (half the work of a full list) and writes need no atomics or
//! colouring; the ordered reduction makes a run bit-identical for a given thread count,
//! whatever rayon's work stealing does. The price is one extra buffer pass per extra
//! thread, small against the pair work on a few cores.
//!
//! A partner seen through a rotated image (a wedge face) receives the reaction rotated back
//! into its own frame, `−Rᵀ f` and `Rᵀ τ_j`. What is measured besides the forces is up to
//! the [`ContactObserver`] of the call.

use crate::contact::{ContactHistory, ContactTable, PairKinematics};
use crate::domain::{IDENTITY_IMAGE, IMAGE_COUNT, ImageTransform};
use crate::neighbor::NeighborList;
use crate::observe::{ContactObserver, ContactView};
use crate::particles::Particles;
use glam::DVec3;
use rayon::prelude::*;

/// Per-thread force buffers, reused between steps (not part of the simulation state).
#[derive(Clone, Debug, Default)]
pub struct ForceScratch {
    force: Vec<Vec<DVec3>>,
    torque: Vec<Vec<DVec3>>,
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
    partner: &'a [u32],
    image: &'a [u8],
    images: &'a [ImageTransform; IMAGE_COUNT],
    laws: &'a ContactTable,
    max_range: f64,
    flow_rate: f64,
    dt: f64,
}

/// Zeroes the particle forces and torques and adds every pair force of the list, advancing
/// contact history over `dt` (s). `flow_rate` (1/s) is subtracted as `γ̇ l_y x̂` from each
/// contact's relative velocity (zero in the lab frame; see `LeesEdwards::peculiar_contacts`).
/// Every interacting pair is shown to the observer `O`, whose merged observations are
/// returned.
pub fn pair_forces<O: ContactObserver>(
    particles: &mut Particles,
    list: &mut NeighborList,
    laws: &ContactTable,
    images: &[ImageTransform; IMAGE_COUNT],
    flow_rate: f64,
    dt: f64,
    scratch: &mut ForceScratch,
) -> O {
    let n = particles.len();
    let chunks = rayon::current_num_threads().max(1).min(n.max(1));
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
        partner: slices.partner,
        image: slices.image,
        images,
        laws,
        max_range: laws.max_range(),
        flow_rate,
        dt,
    };

    scratch.force.resize_with(chunks - 1, Vec::new);
    scratch.torque.resize_with(chunks - 1, Vec::new);
    for buf in scratch.force.iter_mut().chain(scratch.torque.iter_mut()) {
        buf.clear();
        buf.resize(n, DVec3::ZERO);
    }
    particles.force.iter_mut().for_each(|f| *f = DVec3::ZERO);
    particles.torque.iter_mut().for_each(|t| *t = DVec3::ZERO);

    // Carve the history into one disjoint slice per chunk.
    let mut jobs = Vec::with_capacity(chunks);
    let (mut active, mut history) = (slices.active, slices.history);
    let mut force_bufs = std::iter::once(&mut particles.force).chain(scratch.force.iter_mut());
    let mut torque_bufs = std::iter::once(&mut particles.torque).chain(scratch.torque.iter_mut());
    for c in 0..chunks {
        let (lo, hi) = (bounds[c], bounds[c + 1]);
        let pairs = (inputs.offsets[hi] - inputs.offsets[lo]) as usize;
        let (t_here, t_rest) = std::mem::take(&mut active).split_at_mut(pairs);
        let (h_here, h_rest) = std::mem::take(&mut history).split_at_mut(pairs);
        active = t_rest;
        history = h_rest;
        let (Some(f), Some(t)) = (force_bufs.next(), torque_bufs.next()) else {
            unreachable!("one buffer per chunk");
        };
        jobs.push((lo..hi, t_here, h_here, f, t));
    }

    let partial: Vec<O> = jobs
        .into_par_iter()
        .map(|(range, active, history, force, torque)| {
            chunk_forces::<O>(&inputs, range, active, history, force, torque)
        })
        .collect();

    if chunks > 1 {
        let extra_f = &scratch.force;
        let extra_t = &scratch.torque;
        particles
            .force
            .par_iter_mut()
            .zip(particles.torque.par_iter_mut())
            .enumerate()
            .with_min_len(1024)
            .for_each(|(i, (f, t))| {
                for (bf, bt) in extra_f.iter().zip(extra_t) {
                    *f += bf[i];
                    *t += bt[i];
                }
            });
    }

    let mut total = O::default();
    for p in partial {
        total.merge(p);
    }
    total
}

/// Forces of the pairs whose first slot lies in `range`.
#[inline(never)]
fn chunk_forces<O: ContactObserver>(
    inp: &Inputs<'_>,
    range: std::ops::Range<usize>,
    active: &mut [bool],
    history: &mut [ContactHistory],
    force: &mut [DVec3],
    torque: &mut [DVec3],
) -> O {
    let mut obs = O::default();
    let base = inp.offsets[range.start] as usize;
    for i in range {
        let r_i = inp.position[i];
        let a_i = inp.radius[i];
        let mut f_i = DVec3::ZERO;
        let mut t_i = DVec3::ZERO;
        for k in inp.offsets[i] as usize..inp.offsets[i + 1] as usize {
            let j = inp.partner[k] as usize;
            let code = inp.image[k];
            let image = &inp.images[code as usize];
            let r_j = if code == IDENTITY_IMAGE {
                inp.position[j]
            } else {
                image.position(inp.position[j])
            };
            let branch = r_i - r_j;
            let d2 = branch.length_squared();
            let sum = a_i + inp.radius[j];
            let local = k - base;
            let reach = sum + inp.max_range;
            if d2 >= reach * reach {
                if active[local] {
                    active[local] = false;
                    history[local] = ContactHistory::default();
                }
                continue;
            }
            let dist = d2.sqrt();
            let inv_dist = 1.0 / dist;
            let (v_j, w_j) = if code == IDENTITY_IMAGE {
                (inp.velocity[j], inp.omega[j])
            } else {
                (
                    image.velocity(inp.velocity[j]),
                    image.angular_velocity(inp.omega[j]),
                )
            };
            let kin = PairKinematics {
                normal: branch * inv_dist,
                overlap: sum - dist,
                radius_i: a_i,
                radius_j: inp.radius[j],
                velocity: inp.velocity[i] - v_j - DVec3::new(inp.flow_rate * branch.y, 0.0, 0.0),
                omega_i: inp.omega[i],
                omega_j: w_j,
                reduced_mass: 1.0 / (inp.inv_mass[i] + inp.inv_mass[j]),
            };
            let law = inp.laws.get(inp.species[i], inp.species[j]);
            let h = &mut history[local];
            let Some(pf) = law.interact(&kin, h, inp.dt) else {
                active[local] = false;
                continue;
            };
            active[local] = true;
            f_i += pf.force;
            t_i += pf.torque_i;
            if image.rotation.is_none() {
                force[j] -= pf.force;
                torque[j] += pf.torque_j;
            } else {
                force[j] -= image.vector_back(pf.force);
                torque[j] += image.vector_back(pf.torque_j);
            }
            if O::OBSERVES {
                obs.visit(&ContactView {
                    ids: [inp.id[i], inp.id[j]],
                    parts: [inp.part[i], inp.part[j]],
                    wall: None,
                    image,
                    position: r_i,
                    branch,
                    kinematics: &kin,
                    force: &pf,
                    law,
                    history: h,
                });
            }
        }
        force[i] += f_i;
        torque[i] += t_i;
    }
    obs
}
