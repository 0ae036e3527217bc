//! The stages of a split-bottom run on the staged run driver: fill, settle (ending in the
//! frozen rough walls and `settled.bin`), shear; the operations each step triggers (rows,
//! profile and field samples, snapshots, checkpoints).

use super::fields::{self as cell_fields, FieldSettings};
use super::spec::{Geometry, SplitBottomSpec, TimeStepRule, fill};
use super::state::{
    BACKSTOPS, INNER_BOTTOM, INNER_WALL, OUTER_BOTTOM, OUTER_WALL, PARTS, SettleReport,
    SplitBottomState, Stage, rho, slabs,
};
use crate::Simulation;
use crate::band::AzimuthalProfile;
use crate::cg::{CgSums, ContactRecord};
use crate::contact::{ContactLaw, ContactTable};
use crate::domain::Domain;
use crate::driver::{Driver, Every, Progress, Session, SetUp, StepNeeds};
use crate::generate::{Rng, polydisperse_radii};
use crate::io::atomic::write_atomic;
use crate::io::made_by::Maker;
use crate::io::vtk;
use crate::particles::{Motion, Particles, Sphere};
use crate::run::{RunError, io_err, read_checkpoint};
use crate::scenario::invalid;
use crate::stage::Verdict;
use crate::timestep::shortest_contact_time;
use crate::walls::{Wall, WallShape};
use glam::DVec3;
use rand::SeedableRng;
use std::f64::consts::PI;
use std::path::Path;

/// A split-bottom run in its directory, on the staged run driver.
pub type SplitBottomRun = Driver<SplitBottomState>;

impl Driver<SplitBottomState> {
    /// Builds the filled cell (stage settle) in the new run directory `dir` (refusing one
    /// that holds a run unless `force`), writes the spec and the first checkpoint.
    ///
    /// # Errors
    /// [`RunError`] for an invalid spec, a directory that holds a run or is busy, or a
    /// file not written.
    pub fn start(
        spec: SplitBottomSpec,
        dir: &Path,
        force: bool,
    ) -> Result<SplitBottomRun, RunError> {
        let geometry = spec.geometry()?;
        Driver::create(dir, force, |session| {
            SplitBottomState::filled(spec, geometry, session)
        })
    }

    /// A new run in `dir` that starts shearing from the settled state of the run directory
    /// `settled_dir`, with the shear parameters of `spec` (`omega`, `duration`,
    /// `average_from`, `rows`, `snapshots`, `checkpoints`, `cohesion`); the geometry and
    /// particle parameters must match the settled run's.
    pub fn from_settled(
        spec: SplitBottomSpec,
        settled_dir: &Path,
        dir: &Path,
        force: bool,
    ) -> Result<SplitBottomRun, RunError> {
        let geometry = spec.geometry()?;
        let source: SplitBottomState = read_checkpoint(&settled_dir.join("settled.bin"))?;
        let same = |key: &str, a: f64, b: f64| {
            if a == b {
                Ok(())
            } else {
                Err(RunError::Scenario(invalid(
                    key,
                    a,
                    format!("must equal the settled run's value {b} to start from it"),
                )))
            }
        };
        let (s, o) = (&spec, &source.spec);
        for (key, a, b) in [
            ("inner_radius", s.inner_radius, o.inner_radius),
            ("outer_radius", s.outer_radius, o.outer_radius),
            ("split_radius", s.split_radius, o.split_radius),
            ("height", s.height, o.height),
            ("wedge_deg", s.wedge_deg, o.wedge_deg),
            ("scale", s.scale, o.scale),
            ("diameter", s.diameter, o.diameter),
            ("w", s.w, o.w),
            ("density", s.density, o.density),
            ("gravity", s.gravity, o.gravity),
            ("seed", s.seed as f64, o.seed as f64),
            ("wall_shell", s.wall_shell, o.wall_shell),
        ] {
            same(key, a, b)?;
        }
        if s.time_step != o.time_step {
            return Err(RunError::Scenario(invalid(
                "time_step",
                format!("{:?}", s.time_step),
                format!(
                    "must equal the settled run's rule ({:?}): its time step is kept",
                    o.time_step
                ),
            )));
        }
        let from = settled_dir.display().to_string();
        Driver::create(dir, force, |session| {
            let mut state = SplitBottomState {
                spec,
                geometry,
                from: Some(from),
                snapshots: Vec::new(),
                wall_seconds: 0.0,
                first_step: source.simulation.step,
                fields: None,
                ..source
            };
            state.begin_shear()?;
            state.write_spec(session.dir)?;
            Ok(state)
        })
    }
}

impl SplitBottomState {
    /// The filled cell of [`SplitBottomRun::start`], its spec written into the run
    /// directory.
    fn filled(
        spec: SplitBottomSpec,
        geometry: Geometry,
        session: &Session<'_>,
    ) -> Result<SplitBottomState, RunError> {
        let mut rng = Rng::seed_from_u64(spec.seed);
        let radii = polydisperse_radii(&mut rng, geometry.count, spec.diameter, spec.w);
        let centres = fill(&mut rng, &radii, &geometry)?;
        let mut particles = Particles::default();
        for (c, a) in centres.into_iter().zip(radii) {
            let sphere = Sphere {
                position: c,
                velocity: DVec3::ZERO,
                angular_velocity: DVec3::ZERO,
                radius: a,
                species: 0,
                motion: Motion::Free,
            };
            particles.push(sphere, spec.density);
        }
        let law = spec.law()?;
        let mut laws = ContactTable::uniform(1, law);
        let walls = backstops(&geometry);
        let dt = time_step(&spec, &particles, &laws, &walls)?;
        laws.map(|l| scale_damping(l, spec.settle_damping));
        let g = &geometry;
        let domain = Domain::wedge(
            g.angle,
            g.mould_inner + g.radii[0],
            g.mould_outer,
            g.floor,
            g.fill_top,
        );
        let skin = spec.skin * spec.diameter;
        let mut simulation = Simulation::new(
            particles,
            domain,
            laws,
            walls,
            DVec3::new(0.0, 0.0, -spec.gravity),
            dt,
            skin,
        )
        .map_err(RunError::Neighbor)?;
        simulation.parts = PARTS.iter().map(|s| s.to_string()).collect();
        let state = SplitBottomState {
            spec,
            geometry,
            stage: Stage::Settle,
            simulation,
            rows: Vec::new(),
            profiles: Vec::new(),
            settled: None,
            shear_start: None,
            snapshots: Vec::new(),
            wall_seconds: 0.0,
            from: None,
            first_step: 0,
            fields: None,
        };
        state.write_spec(session.dir)?;
        Ok(state)
    }

    /// Freezes the layer of particles touching each mould wall, and those whose centres lie
    /// in the wall shell (`wall_shell`), into the rough walls.
    fn freeze_walls(&mut self, kinetic_ratio: f64, criterion_met: bool) -> Result<(), RunError> {
        let g = self.geometry.clone();
        let shell = self.spec.wall_shell * self.spec.diameter;
        let p = &mut self.simulation.particles;
        let touch = 0.1 * g.radii[0];
        let mut counts = [0usize; 4];
        for i in 0..p.len() {
            if !p.motion[i].is_free() {
                continue;
            }
            let (r, a) = (p.position[i], p.radius[i]);
            let part = if r.z - a - g.floor < touch || r.z < shell {
                if rho(r) < g.split_radius {
                    INNER_BOTTOM
                } else {
                    OUTER_BOTTOM
                }
            } else if rho(r) - a - g.mould_inner < touch || rho(r) < g.inner_radius + shell {
                INNER_WALL
            } else if g.mould_outer - rho(r) - a < touch || rho(r) > g.outer_radius - shell {
                OUTER_WALL
            } else {
                continue;
            };
            counts[part as usize] += 1;
            p.prescribe(i, Motion::Fixed, part);
        }
        // Pairs of two wall particles leave the list.
        self.simulation.rebuild_neighbors()?;
        let free = self.simulation.particles.free_count();
        self.settled = Some(SettleReport {
            time: self.simulation.time,
            kinetic_ratio,
            criterion_met,
            free,
            wall_particles: counts,
            surface_height: self.surface_height(),
        });
        Ok(())
    }

    /// Starts the shear stage: the laws of the spec (no extra damping), the outer parts
    /// rotating at `Ω`, empty profiles.
    fn begin_shear(&mut self) -> Result<(), RunError> {
        let law = self.spec.law()?;
        let sim = &mut self.simulation;
        sim.laws = ContactTable::uniform(1, law);
        if law.range() > sim.neighbors.range {
            sim.neighbors.range = law.range();
        }
        sim.neighbors.skin = self.spec.skin * self.spec.diameter;
        close_bottom(&self.geometry, sim);
        for i in 0..sim.particles.len() {
            let part = sim.particles.part[i];
            if part == OUTER_BOTTOM || part == OUTER_WALL {
                sim.particles.motion[i] = Motion::Rotating {
                    center: DVec3::ZERO,
                    axis: DVec3::Z,
                    omega: self.spec.omega,
                };
            }
        }
        sim.rebuild_neighbors()?;
        sim.compute_forces(true);
        self.shear_start = Some((sim.time, sim.step));
        self.stage = Stage::Shear;
        let h = self
            .settled
            .as_ref()
            .map_or(self.geometry.height, |s| s.surface_height);
        let d = self.spec.diameter;
        let g = &self.geometry;
        let bins = (((g.outer_radius - g.inner_radius) / (0.5 * d)).round() as usize).max(4);
        self.profiles = slabs(h, d)
            .iter()
            .map(|&(lo, hi)| AzimuthalProfile::new(g.inner_radius, g.outer_radius, bins, lo, hi))
            .collect::<Result<_, _>>()
            .map_err(|e| RunError::Scenario(invalid("height", h, e.to_string())))?;
        self.fields = if self.spec.cg_every > 0.0 {
            Some(CgSums::new(FieldSettings::of(&self.spec).grid(self)?)?)
        } else {
            None
        };
        Ok(())
    }

    fn write_spec(&self, dir: &Path) -> Result<(), RunError> {
        let path = dir.join("split-bottom.toml");
        let header = format!(
            "# rheodem {} (commit {}) — split-bottom cell as run, every default written out\n",
            crate::VERSION,
            crate::COMMIT
        );
        write_atomic(&path, (header + &self.spec.to_toml()).as_bytes())
            .map_err(io_err("write", &path))?;
        let snapshots = dir.join("snapshots");
        std::fs::create_dir_all(&snapshots).map_err(io_err("create the directory", &snapshots))
    }

    /// Adds the current state, with the contacts of its last step, to the fields.
    fn sample_fields(&mut self, contacts: &[ContactRecord]) -> Result<(), RunError> {
        let kernel = FieldSettings::of(&self.spec).kernel(self.spec.diameter)?;
        let snap = cell_fields::snapshot(self, contacts);
        if let Some(sums) = &mut self.fields {
            sums.add_snapshot(&kernel, &snap);
        }
        Ok(())
    }

    fn snapshot(&mut self, dir: &Path, contacts: &[ContactRecord]) -> Result<(), RunError> {
        let p = &self.simulation.particles;
        let v_phi: Vec<f64> = (0..p.len())
            .map(|i| {
                let (r, v) = (p.position[i], p.velocity[i]);
                let rr = rho(r);
                if rr > 0.0 {
                    (r.x * v.y - r.y * v.x) / rr
                } else {
                    0.0
                }
            })
            .collect();
        let name = format!("snapshot-{:06}.vtp", self.snapshots.len());
        let path = dir.join("snapshots").join(&name);
        write_atomic(&path, vtk::particles_vtp(p, &[("v_phi", v_phi)]).as_bytes())
            .map_err(io_err("write", &path))?;
        let vtp = format!("snapshots/{name}");
        cell_fields::write_records(self, contacts, dir, &vtp)?;
        self.snapshots.push((self.simulation.time, vtp));
        let path = dir.join("snapshots.pvd");
        write_atomic(&path, vtk::collection_pvd(&self.snapshots).as_bytes())
            .map_err(io_err("write", &path))
    }

    /// Steps between the checks of the settle stage's end (5 ms of simulated time).
    fn settle_check(&self) -> u64 {
        ((0.005 / self.simulation.dt).round() as u64).max(1)
    }

    /// The operations of shear step `next` (counted from the start of shear), whose end is
    /// at `time`: `(measure, snapshot, sample the fields)`.
    fn shear_operations(&self, next: u64, time: f64) -> (bool, bool, bool) {
        let (t0, _) = self.shear_start.unwrap_or((0.0, 0));
        let total = self.shear_steps();
        let rows = Every(total.checked_div(self.spec.rows).unwrap_or(0).max(1));
        let measure = rows.fires(next) || next == total;
        let snapshot = Every(total.checked_div(self.spec.snapshots).unwrap_or(0)).fires(next);
        let in_window = time - t0 >= self.spec.average_from;
        let sample = in_window
            && self.fields.is_some()
            && self.cg_steps().is_some_and(|k| next.is_multiple_of(k));
        (measure, snapshot, sample)
    }

    /// The operations of the settle step just taken: a row every check, the end of
    /// settling (freezing the walls, saving `settled.bin`, starting the shear); returns
    /// whether a checkpoint is due.
    fn after_settle_step(&mut self, session: &mut Session<'_>) -> Result<bool, RunError> {
        let check = self.settle_check();
        let step = self.simulation.step;
        if !step.is_multiple_of(check) {
            return Ok(false);
        }
        let end = self.settle_end();
        let row = self.row();
        // Translational energy only: without torsion resistance a particle spinning about
        // its contact normal is never slowed down, so the rotational energy of a settled
        // bed need not vanish. Against the springs' energy alone: with a cohesive law the
        // elastic energy holds the negative adhesive potential and may be below zero.
        let springs = self.simulation.contact_summary().spring_energy;
        let energies = (row.kinetic_translational, springs);
        session.sane(&self.simulation)?;
        self.rows.push(row);
        let verdict = end.verdict(step, self.simulation.time, Some(energies));
        if verdict == Verdict::Continue {
            return Ok(step.is_multiple_of(20 * check));
        }
        let ratio = energies.0 / energies.1.max(f64::MIN_POSITIVE);
        self.freeze_walls(ratio, verdict == Verdict::Met)?;
        self.wall_seconds += session.lap();
        session.save_state("settled.bin", self)?;
        self.begin_shear()?;
        Ok(true)
    }

    /// The operations of the shear step just taken (`contacts`: its records, when asked
    /// for): field samples, rows with profile samples, snapshots, the end of shear;
    /// returns whether a checkpoint is due.
    fn after_shear_step(
        &mut self,
        session: &mut Session<'_>,
        contacts: Option<&[ContactRecord]>,
    ) -> Result<bool, RunError> {
        let (t0, s0) = self.shear_start.unwrap_or((0.0, 0));
        let total = self.shear_steps();
        let next = self.simulation.step - s0;
        let (measure, snapshot, sample) = self.shear_operations(next, self.simulation.time);
        let contacts = contacts.unwrap_or_default();
        if sample {
            self.sample_fields(contacts)?;
        }
        if measure {
            session.sane(&self.simulation)?;
            let row = self.row();
            if self.simulation.time - t0 >= self.spec.average_from {
                self.sample_profiles()?;
            }
            self.rows.push(row);
        }
        if snapshot {
            self.snapshot(session.dir, contacts)?;
        }
        if next == total {
            self.stage = Stage::Done;
        }
        let checkpoints = Every(total.checked_div(self.spec.checkpoints).unwrap_or(0));
        Ok(next == total || checkpoints.fires(next))
    }
}

impl SetUp for SplitBottomState {
    const MAKER: Maker = Maker::SplitBottom;

    fn simulation(&self) -> &Simulation {
        &self.simulation
    }

    fn simulation_mut(&mut self) -> &mut Simulation {
        &mut self.simulation
    }

    fn is_complete(&self) -> bool {
        self.stage == Stage::Done
    }

    fn progress(&self) -> Progress {
        match self.stage {
            Stage::Settle => Progress {
                stage: "settle",
                done: self.simulation.step,
                total: self.settle_end().max_steps(self.simulation.dt),
            },
            Stage::Shear | Stage::Done => Progress {
                stage: "shear",
                done: self.simulation.step - self.shear_start.map_or(0, |s| s.1),
                total: self.shear_steps(),
            },
        }
    }

    fn needs(&self) -> StepNeeds {
        let sim = &self.simulation;
        match self.stage {
            Stage::Settle => StepNeeds {
                measure: (sim.step + 1).is_multiple_of(self.settle_check()),
                contacts: false,
            },
            Stage::Shear | Stage::Done => {
                let next = sim.step + 1 - self.shear_start.map_or(0, |s| s.1);
                let (measure, snapshot, sample) = self.shear_operations(next, sim.time + sim.dt);
                // Steps whose contacts are coarse-grained or stored keep their records.
                StepNeeds {
                    measure,
                    contacts: snapshot || sample,
                }
            }
        }
    }

    fn after_step(
        &mut self,
        session: &mut Session<'_>,
        contacts: Option<&[ContactRecord]>,
    ) -> Result<bool, RunError> {
        match self.stage {
            Stage::Settle => self.after_settle_step(session),
            Stage::Shear | Stage::Done => self.after_shear_step(session, contacts),
        }
    }

    fn wall_seconds_mut(&mut self) -> &mut f64 {
        &mut self.wall_seconds
    }

    fn write_outputs(&self, dir: &Path) -> Result<serde_json::Value, RunError> {
        self.write_files(dir)
    }

    fn summary(&self) -> serde_json::Value {
        let band = self
            .fields
            .as_ref()
            .filter(|s| s.snapshots > 0)
            .map(|sums| cell_fields::band_rheology(self, sums));
        self.summary_with(band.as_ref())
    }
}

/// Closes the rough bottom for the shear. Where the rotating and the fixed bottom slide
/// past each other at `R_s`, gaps open between their particles. A free grain on the mould
/// floor could sink through such a gap below the wall particles' centres, and the closing
/// gap would then crush it between a moving and a fixed wall particle. So the floor
/// backstop rises from the mould floor to `floor + r_min`, the centres of the smallest
/// bottom particles, and the free grains that lie lower (in the bottom layer's hollows)
/// join the bottom wall on their side of `R_s`. With radii at most twice `r_min`, a free
/// grain's centre then stays at or above the bottom particles' centres, so their contacts
/// push it up and out.
fn close_bottom(g: &Geometry, sim: &mut Simulation) {
    let height = g.floor + g.radii[0];
    let p = &mut sim.particles;
    for i in 0..p.len() {
        if p.motion[i].is_free() && p.position[i].z - p.radius[i] < height {
            let part = if rho(p.position[i]) < g.split_radius {
                INNER_BOTTOM
            } else {
                OUTER_BOTTOM
            };
            p.prescribe(i, Motion::Fixed, part);
        }
    }
    for w in &mut sim.walls {
        if let (BACKSTOPS, WallShape::Plane { point, .. }) = (w.part, &mut w.shape) {
            point.z = height;
        }
    }
}

/// The smooth mould walls that stay as backstops.
fn backstops(g: &Geometry) -> Vec<Wall> {
    let mut walls = vec![
        Wall::plane(DVec3::new(0.0, 0.0, g.floor), DVec3::Z, 0),
        Wall::cylinder(DVec3::ZERO, DVec3::Z, g.mould_inner, false, 0),
        Wall::cylinder(DVec3::ZERO, DVec3::Z, g.mould_outer, true, 0),
    ];
    for w in &mut walls {
        w.part = BACKSTOPS;
    }
    walls
}

fn scale_damping(l: &mut ContactLaw, factor: f64) {
    l.normal = l.normal.damping_scaled(factor);
    l.tangential = l.tangential.damping_scaled(factor);
}

/// The time step of the rule (s).
fn time_step(
    spec: &SplitBottomSpec,
    particles: &Particles,
    laws: &ContactTable,
    walls: &[Wall],
) -> Result<f64, RunError> {
    let t_c = match spec.time_step {
        TimeStepRule::Shortest => shortest_contact_time(particles, laws, walls)
            .map_err(|e| RunError::Scenario(invalid("stiffness", spec.stiffness, e.to_string())))?,
        TimeStepRule::MeanPair => {
            let m = spec.density * PI / 6.0 * spec.diameter.powi(3);
            laws.get(0, 0)
                .normal
                .contact_time(0.5 * m, 0.25 * spec.diameter)
                .ok_or_else(|| {
                    RunError::Scenario(invalid(
                        "damping",
                        spec.damping,
                        "overdamps the mean pair: no contact time",
                    ))
                })?
        }
    };
    Ok(t_c / 50.0)
}
