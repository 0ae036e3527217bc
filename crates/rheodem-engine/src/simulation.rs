//! The simulation state and its time step.
//!
//! [`Simulation`] holds everything a run depends on — particles (in their current sorted
//! order), box, contact laws, walls, neighbour list with contact history, time — so that
//! serialising it is a complete checkpoint and stepping it is a pure function of it.

use crate::contact::ContactTable;
use crate::domain::Domain;
use crate::forces::{ForceScratch, pair_forces};
use crate::integrate::{add_gravity, drift, kick, kick_drift};
use crate::measure::{
    ContactSummary, ContactSums, Observables, granular_temperature, kinetic_energies,
    kinetic_stress_sum, to_rows,
};
use crate::neighbor::{NeighborError, NeighborList};
use crate::observe::{ContactObserver, PartLoads, StressSum};
use crate::particles::{Particles, Sphere};
use crate::sanity::{self, DeepestContact, Instability, Limits};
use crate::stress_control::StressControl;
use crate::team::TeamSlot;
use crate::walls::Wall;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// A DEM simulation.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Simulation {
    /// The particles.
    pub particles: Particles,
    /// The box and its boundaries.
    pub domain: Domain,
    /// Contact laws per species pair.
    pub laws: ContactTable,
    /// Smooth analytic walls (planes, cylinders).
    pub walls: Vec<Wall>,
    /// Names of the wall parts, indexed by the part numbers of particles and walls.
    #[serde(default)]
    pub parts: Vec<String>,
    /// Verlet list and contact history.
    pub neighbors: NeighborList,
    /// Gravitational acceleration (m/s²).
    pub gravity: DVec3,
    /// Time step (s).
    pub dt: f64,
    /// Simulated time (s).
    pub time: f64,
    /// Steps taken.
    pub step: u64,
    /// Control of `σ_yy` through `L_y`, if any (Lees-Edwards shear box).
    pub stress_control: Option<StressControl>,
    /// `σ_yy` (Pa) of the last force evaluation under stress control: the controller's
    /// input for the next step, hence state (checkpointed), not an observation.
    pub sigma_yy: f64,
    /// Limits of a sane state (see [`crate::sanity`]).
    #[serde(default)]
    pub limits: Limits,
    /// Contact sums of the last measuring force evaluation and its step: an observation,
    /// not state, so not checkpointed (a resumed run measures again at its next measuring
    /// step; checkpoints that hold it still load, the field ignored).
    #[serde(skip)]
    measured: (u64, ContactSums),
    /// Loads on the wall parts at the last measuring force evaluation (an observation,
    /// not checkpointed).
    #[serde(skip)]
    part_loads: PartLoads,
    #[serde(skip)]
    scratch: ForceScratch,
    /// The threads that share the step's loops.
    #[serde(skip)]
    team: TeamSlot,
}

impl Simulation {
    /// Assembles a simulation and evaluates the initial forces. `skin` (m) is the Verlet
    /// skin; the list also keeps every pair within the laws' interaction range.
    ///
    /// Two spheres overlapping by `δ` at rest push each other apart with `k_n δ`, and the
    /// contact stress `σ = f ⊗ l / V` is `k_n δ (a_i + a_j − δ) / V` along the line of
    /// centres (compression positive):
    ///
    /// ```
    /// use glam::DVec3;
    /// use rheodem_engine::Simulation;
    /// use rheodem_engine::contact::{Adhesion, ContactLaw, ContactTable, Damping, LinearNormal, Spring};
    /// use rheodem_engine::domain::Domain;
    /// use rheodem_engine::particles::{Motion, Particles, Sphere};
    ///
    /// let (a, delta, k_n) = (1.0e-3, 1.0e-5, 100.0);
    /// let law = ContactLaw {
    ///     normal: LinearNormal { stiffness: k_n, damping: Damping::from_restitution(0.8, k_n) }.into(),
    ///     tangential: Spring::NONE,
    ///     rolling: Spring::NONE,
    ///     torsion: Spring::NONE,
    ///     adhesion: Adhesion::None,
    /// };
    /// let mut particles = Particles::default();
    /// for x in [0.0, 2.0 * a - delta] {
    ///     let sphere = Sphere {
    ///         position: DVec3::new(0.01 + x, 0.01, 0.01),
    ///         velocity: DVec3::ZERO,
    ///         angular_velocity: DVec3::ZERO,
    ///         radius: a,
    ///         species: 0,
    ///         motion: Motion::Free,
    ///     };
    ///     particles.push(sphere, 2000.0);
    /// }
    /// let domain = Domain::new(DVec3::ZERO, DVec3::splat(0.02), [false; 3]);
    /// let sim = Simulation::new(
    ///     particles,
    ///     domain,
    ///     ContactTable::uniform(1, law),
    ///     Vec::new(),
    ///     DVec3::ZERO,
    ///     1e-5,
    ///     0.2 * a,
    /// )?;
    /// let slots = sim.particles.slot_of();
    /// let f_left = sim.particles.force[slots[0] as usize];
    /// assert!((f_left - DVec3::new(-k_n * delta, 0.0, 0.0)).length() < 1e-12 * k_n * delta);
    /// let o = sim.observables();
    /// assert_eq!(o.contacts, 1);
    /// let sigma_xx = k_n * delta * (2.0 * a - delta) / 0.02f64.powi(3);
    /// assert!((o.stress[0][0] / sigma_xx - 1.0).abs() < 1e-12);
    /// assert_eq!(o.stress[1][1], 0.0);
    /// # Ok::<(), rheodem_engine::neighbor::NeighborError>(())
    /// ```
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        particles: Particles,
        domain: Domain,
        laws: ContactTable,
        walls: Vec<Wall>,
        gravity: DVec3,
        dt: f64,
        skin: f64,
    ) -> Result<Simulation, NeighborError> {
        let range = laws.max_range();
        let mut sim = Simulation {
            particles,
            domain,
            laws,
            walls,
            parts: Vec::new(),
            neighbors: NeighborList::new(skin, range),
            gravity,
            dt,
            time: 0.0,
            step: 0,
            stress_control: None,
            sigma_yy: 0.0,
            limits: Limits::default(),
            measured: (0, ContactSums::default()),
            part_loads: PartLoads::default(),
            scratch: ForceScratch::default(),
            team: TeamSlot::default(),
        };
        // Give prescribed particles the velocities of their motion law.
        drift(&mut sim.particles, 0.0, sim.team.get());
        sim.rebuild_neighbors()?;
        sim.compute_forces(true);
        Ok(sim)
    }

    /// Advances one velocity-Verlet step. With `measure`, the force evaluation also gathers
    /// the contact sums that [`Simulation::observables`] reports.
    pub fn step(&mut self, measure: bool) -> Result<(), NeighborError> {
        self.begin_step();
        self.refresh_neighbors()?;
        self.compute_forces(measure);
        self.end_step();
        Ok(())
    }

    /// First half of a step: half kick, drift (with the affine drag of the mean flow under
    /// [`crate::domain::ShearDynamics::AffineDrag`]), advance the clock.
    pub fn begin_step(&mut self) {
        kick_drift(&mut self.particles, 0.5 * self.dt, self.dt, self.team.get());
        let motion = &self.particles.motion;
        self.domain.drag_affinely(
            &mut self.particles.position,
            |i| motion[i].is_free(),
            self.dt,
        );
        self.domain.advance(self.dt);
        if let Some(control) = &self.stress_control {
            control.apply(
                self.sigma_yy,
                self.dt,
                &mut self.domain,
                &mut self.particles,
            );
        }
        self.time += self.dt;
        self.step += 1;
    }

    /// Last part of a step, after the forces: the second half kick.
    pub fn end_step(&mut self) {
        kick(&mut self.particles, 0.5 * self.dt, self.team.get());
    }

    /// Rebuilds the neighbour list if particles or images have moved far enough.
    pub fn refresh_neighbors(&mut self) -> Result<(), NeighborError> {
        if self.list_is_stale() {
            self.rebuild_neighbors()?;
        }
        Ok(())
    }

    /// Whether particles or images have moved far enough that the neighbour list must be
    /// rebuilt before the next force evaluation, or the laws need pairs it left out.
    pub fn list_is_stale(&mut self) -> bool {
        // The laws act on pairs without a bridge up to their free range.
        let unbridged_range = self.laws.free_range();
        let team = self.team.get();
        self.neighbors
            .needs_rebuild(&self.particles, &self.domain, team, unbridged_range)
    }

    /// How far beyond contact (m) a build of the neighbour list keeps pairs without a
    /// bridge: when the laws form bridges, only as far as the laws that act without one
    /// (reversible adhesion) reach; otherwise every pair within the list's range, so that
    /// the list serves any laws up to that range (the preparation compresses without
    /// adhesion, then switches it on without a rebuild). A list that left out pairs the
    /// laws need is rebuilt before the next step ([`Simulation::list_is_stale`]).
    fn unbridged_range(&self) -> f64 {
        if self.laws.forms_bridges() {
            self.laws.free_range()
        } else {
            f64::INFINITY
        }
    }

    /// Rebuilds the neighbour list now; walls rotate the history of particles that crossed
    /// a wedge face with them and renew their lists of particles within reach.
    pub fn rebuild_neighbors(&mut self) -> Result<(), NeighborError> {
        let unbridged_range = self.unbridged_range();
        let team = self.team.get();
        self.neighbors
            .build(&mut self.particles, &self.domain, team, unbridged_range)?;
        let reach = self.neighbors.range + self.neighbors.skin;
        for wall in &mut self.walls {
            for &(id, rotation) in self.neighbors.last_rotations() {
                wall.rotate_history(id, rotation);
            }
            wall.find_candidates(&self.particles, reach);
        }
        Ok(())
    }

    /// Inserts spheres of the given densities (kg/m³) during a run, each in wall part
    /// `part` (or [`crate::observe::NO_PART`]), and returns their ids. Call it between
    /// steps. Every existing contact keeps its springs and bridges, and the particles
    /// present keep the forces of the last step (rotated with those the rebuild wraps
    /// through a wedge face): evaluating them again would advance every spring a second
    /// time in the same step. The new particles enter the neighbour list and the walls at
    /// once; their forces, and the contacts they make, count from the next step (their
    /// first half kick sees no force).
    pub fn insert(&mut self, spheres: &[(Sphere, f64, u16)]) -> Result<Vec<u32>, NeighborError> {
        let first = self.particles.len() as u32;
        for &(s, density, part) in spheres {
            self.particles.push_in_part(s, density, part);
        }
        self.rebuild_neighbors()?;
        let slot = self.particles.slot_of();
        for &(id, m) in self.neighbors.last_rotations() {
            let i = slot[id as usize] as usize;
            self.particles.force[i] = m * self.particles.force[i];
            self.particles.torque[i] = m * self.particles.torque[i];
        }
        Ok((first..self.particles.len() as u32).collect())
    }

    /// Evaluates all forces and torques at the current positions and velocities, with
    /// every contact observable and the loads on the wall parts when `measure` (the
    /// contact stress alone is always summed under stress control, which needs `σ_yy`
    /// every step).
    pub fn compute_forces(&mut self, measure: bool) {
        if measure {
            self.compute_measured_forces::<()>();
        } else if self.stress_control.is_some() {
            let StressSum(sum) = self.compute_forces_with::<StressSum>();
            self.update_sigma_yy(sum);
        } else {
            self.compute_forces_with::<()>();
        }
    }

    /// The full measurement of [`Simulation::compute_forces`], with the contacts shown to
    /// an extra observer `O` as well, whose observations are returned.
    fn compute_measured_forces<O: ContactObserver>(&mut self) -> O {
        let ((sums, loads), extra) = self.compute_forces_with::<((ContactSums, PartLoads), O)>();
        self.measured = (self.step, sums);
        self.part_loads = loads;
        if self.stress_control.is_some() {
            self.update_sigma_yy(sums.stress_sum);
        }
        extra
    }

    /// One measured step ([`Simulation::step`] with `measure`) whose contacts an extra
    /// observer `O` also sees (contact records for coarse-graining and snapshots); returns
    /// its observations, taken at the positions the step ends at.
    pub fn step_with<O: ContactObserver>(&mut self) -> Result<O, NeighborError> {
        self.begin_step();
        self.refresh_neighbors()?;
        let extra = self.compute_measured_forces::<O>();
        self.end_step();
        Ok(extra)
    }

    /// Evaluates all forces and torques (pairs, walls, gravity), showing every interacting
    /// contact to a fresh observer `O`, and returns its observations. This is the hook for
    /// measurements defined outside the engine (contact snapshots, coarse-graining).
    pub fn compute_forces_with<O: ContactObserver>(&mut self) -> O {
        let images = self.domain.image_transforms();
        let flow = self.domain.contact_velocity_gradient();
        let team = self.team.get();
        let (p, nb, laws, dt, scratch) = (
            &mut self.particles,
            &mut self.neighbors,
            &self.laws,
            self.dt,
            &mut self.scratch,
        );
        let mut obs = pair_forces::<O>(p, nb, laws, &images, flow, dt, scratch, team);
        for (index, wall) in self.walls.iter_mut().enumerate() {
            wall.apply(
                index as u32,
                &mut self.particles,
                &self.laws,
                self.dt,
                &mut obs,
            );
        }
        add_gravity(&mut self.particles, self.gravity, self.team.get());
        obs
    }

    fn update_sigma_yy(&mut self, contact_sum: glam::DMat3) {
        let kinetic = kinetic_stress_sum(&self.particles, &self.domain);
        self.sigma_yy = (kinetic.y_axis.y + contact_sum.y_axis.y) / self.domain.volume();
    }

    /// Loads on the wall parts at the last measurement (index = part number; parts that
    /// had no contact may be missing at the end).
    pub fn part_loads(&self) -> &[crate::observe::PartLoad] {
        &self.part_loads.0
    }

    /// Switches on control of `σ_yy` (Lees-Edwards box), starting from the stress of the
    /// last full measurement.
    pub fn set_stress_control(&mut self, control: StressControl) {
        let kinetic = kinetic_stress_sum(&self.particles, &self.domain);
        self.sigma_yy =
            (kinetic.y_axis.y + self.measured.1.stress_sum.y_axis.y) / self.domain.volume();
        self.stress_control = Some(control);
    }

    /// Coordination number of the free particles that have at least 2 particle contacts
    /// (rattlers, with fewer, are left out): `Σ c_i / #{i : c_i ≥ 2}`.
    pub fn coordination_without_rattlers(&self) -> f64 {
        let counts = self.neighbors.contact_counts(&self.particles, &self.domain);
        let (mut sum, mut n) = (0u64, 0u64);
        for (i, &c) in counts.iter().enumerate() {
            if c >= 2 && self.particles.motion[i].is_free() {
                sum += u64::from(c);
                n += 1;
            }
        }
        if n > 0 { sum as f64 / n as f64 } else { 0.0 }
    }

    /// Checks that the state is still a meaningful DEM state (finite numbers, speeds and
    /// overlaps within [`Simulation::limits`]); overlaps are those of the last measurement
    /// if it was taken at the current step.
    pub fn check_sanity(&self) -> Result<(), Instability> {
        let deepest = (self.measured.0 == self.step).then_some(&self.measured.1.deepest);
        sanity::check(
            &self.particles,
            &self.domain,
            self.dt,
            &self.limits,
            deepest,
        )
    }

    /// The deepest contact of the last measurement (zero ratio if none).
    pub fn observables_deepest(&self) -> DeepestContact {
        self.measured.1.deepest
    }

    /// Step at which the contact sums of [`Simulation::observables`] were gathered.
    pub fn measured_step(&self) -> u64 {
        self.measured.0
    }

    /// The contact quantities of [`Simulation::observables`] (from the last step taken
    /// with `measure = true`), without the walk over the neighbour list that the
    /// coordination without rattlers takes.
    pub fn contact_summary(&self) -> ContactSummary {
        let sums = &self.measured.1;
        let free = self.particles.free_count().max(1) as f64;
        ContactSummary {
            elastic_energy: sums.elastic_energy,
            spring_energy: sums.spring_energy,
            contacts: sums.contacts,
            sliding_fraction: if sums.contacts > 0 {
                sums.sliding as f64 / sums.contacts as f64
            } else {
                0.0
            },
            coordination: 2.0 * sums.contacts as f64 / free,
            bridges_per_particle: sums.attracting_apart as f64 / free,
        }
    }

    /// Kinetic energies `(½ Σ m v², ½ Σ I ω²)` of the free particles (J) at the current
    /// state, as [`Simulation::observables`] reports them.
    pub fn kinetic_energies(&self) -> (f64, f64) {
        kinetic_energies(&self.particles, &self.domain)
    }

    /// The observables at the current state. Contact quantities come from the last step
    /// taken with `measure = true` (see [`Simulation::measured_step`]).
    pub fn observables(&self) -> Observables {
        let p = &self.particles;
        let (kt, kr) = kinetic_energies(p, &self.domain);
        let sums = &self.measured.1;
        let volume = self.domain.volume();
        let stress = (kinetic_stress_sum(p, &self.domain) + sums.stress_sum) / volume;
        let c = self.contact_summary();
        Observables {
            time: self.time,
            step: self.step,
            kinetic_translational: kt,
            kinetic_rotational: kr,
            elastic_energy: c.elastic_energy,
            contacts: c.contacts,
            sliding_fraction: c.sliding_fraction,
            coordination: c.coordination,
            coordination_without_rattlers: self.coordination_without_rattlers(),
            bridges_per_particle: c.bridges_per_particle,
            volume_fraction: p.free_volume() / volume,
            box_size: self.domain.lengths().to_array(),
            granular_temperature: granular_temperature(p, &self.domain),
            stress: to_rows(stress),
        }
    }
}
