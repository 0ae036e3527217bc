//! Inclined chute flow, the classic μ(I) rheometer (docs/model.md §12; Silbert et al.
//! 2001, GDR MiDi 2004): a layer of grains of height `h` on a rough base of frozen grains,
//! periodic along the flow `x` and across it `y`, under gravity tilted by `θ` about `y`,
//! `g = g (sin θ, 0, −cos θ)`; dry or with any registered adhesive law.
//!
//! A run passes through stages on the staged run driver ([`crate::driver`]):
//! 1. **fill** — `N` spheres (polydisperse, mean diameter `d_p`) are placed at random
//!    without overlap, loosely, above a smooth floor at `z = 0`;
//! 2. **settle** — they fall under vertical gravity, the damping multiplied by
//!    `settle_damping`, until the translational kinetic energy is below
//!    `settle_kinetic_ratio` times the springs' energy; the grains whose centres lie below
//!    `base_thickness · d_p` then freeze into the rough base (the floor stays as a
//!    backstop). The state is saved as `settled.bin`, from which runs at other angles,
//!    frictions or laws start (`from`);
//! 3. **tilt and flow** — gravity turns at once to the angle `θ`, the contact laws lose the
//!    settling damping, and the layer flows for `duration`; the kinetic energy, flow rate,
//!    mean velocity and surface height are recorded, and from `average_from` on the
//!    profiles along `z` are coarse-grained in slabs (`φ`, `v_x`, `σ`, `γ̇`, and from them
//!    `μ = |σ_xz|/σ_zz`, `I = γ̇ d_p/√(σ_zz/ρ_p)`, `p* = σ_zz d_p/k_n`, `Bo`), with error bars
//!    from [`BLOCKS`] consecutive blocks of the window.
//!
//! The summary holds the steady-state verdict, the bulk averages (the slabs more than
//! `bulk_margin · d_p` from the base and the surface), the force balance of steady uniform
//! flow (`σ_xz/σ_zz = tan θ`, `σ_zz(z) = ρ_p g cos θ ∫_z φ dz'`) and the fit of Bagnold's
//! velocity profile.

use crate::Simulation;
use crate::analysis::{Estimate, block_average, halves_agree};
use crate::band::surface_height_box;
use crate::cg::periodic::{LabView, snapshot};
use crate::cg::{CgSums, ContactRecord, FieldPoint, Grid, Kernel, KernelShape, Material, fields};
use crate::contact::{
    ContactLaw, ContactTable, Damping, LawSpec, LinearNormal, Resistance, Spring,
};
use crate::domain::Domain;
use crate::driver::{Driver, Every, Progress, Session, SetUp, StepNeeds};
use crate::generate::{Rng, insert_random, polydisperse_radii};
use crate::io::atomic::write_atomic;
use crate::io::made_by::{self, Maker};
use crate::io::vtk;
use crate::particles::{Motion, Particles, Sphere};
use crate::plot::{Labels, Markers, Series, plot_svg};
use crate::run::{RunError, io_err, read_checkpoint};
use crate::scenario::{ScenarioError, invalid, law_error};
use crate::setups::law_options::{cohesion, fields_with_law, law_name};
use crate::setups::results_db::ResultsDb;
use crate::setups::runner::{Event, Experiment, Finished, RunOptions};
use crate::setups::schema::{
    Field, Range, SetUpSchema, Values, check_table, overlay, spec_changes, table_of,
};
use crate::setups::split_bottom::spec::mean_radius_cubed;
use crate::setups::studied::Studied;
use crate::setups::study::{Report, StudySpec};
use crate::setups::sweep::{PointStatus, SweepSpec, point_tables};
use crate::stage::{EndCondition, Verdict};
use crate::timestep::shortest_contact_time;
use crate::walls::Wall;
use glam::DVec3;
use rand::SeedableRng;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Everything a chute run needs; lengths of the layer in mean diameters, the rest in SI
/// units. The defaults are the shear box's grains (docs/model.md §6) on a 10 × 10 `d_p`
/// chute, 20 `d_p` deep, at 24°.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ChuteSpec {
    /// Inclination `θ` (degrees).
    pub angle_deg: f64,
    /// Height `h` of the layer above the base, aimed at after settling, in `d_p`.
    pub height: f64,
    /// Length of the periodic box along the flow `x`, in `d_p`.
    pub length: f64,
    /// Width of the periodic box across the flow `y`, in `d_p`.
    pub width: f64,
    /// Grains whose centres lie below this height above the floor freeze into the rough
    /// base, in `d_p`.
    pub base_thickness: f64,
    /// Mean particle diameter `d_p` (m).
    pub diameter: f64,
    /// Polydispersity `w = r_max / r_min` (uniform radii).
    pub polydispersity: f64,
    /// Particle density `ρ_p` (kg/m³).
    pub density: f64,
    /// Normal stiffness `k_n` (N/m).
    pub stiffness: f64,
    /// Restitution coefficient `e` of a pair (its damping `γ_n` from `k_n` and the pair's
    /// reduced mass); `γ_t/γ_n = k_t/k_n = 2/7`.
    pub restitution: f64,
    /// Sliding friction coefficient `μ_p`.
    pub friction: f64,
    /// The adhesive law.
    pub cohesion: LawSpec,
    /// Gravitational acceleration `g` (m/s²).
    pub gravity: f64,
    /// Factor on every damping coefficient while settling.
    pub settle_damping: f64,
    /// Settling ends when the translational kinetic energy is below this fraction of the
    /// contact springs' energy.
    pub settle_kinetic_ratio: f64,
    /// Settling ends at this time (s) even if the kinetic criterion is not met (reported).
    pub settle_max_time: f64,
    /// Flow duration after the tilt (s).
    pub duration: f64,
    /// Start of the averaging window, in seconds after the tilt.
    pub average_from: f64,
    /// Slabs within this distance of the base top and of the surface are left out of the
    /// bulk averages, in `d_p`.
    pub bulk_margin: f64,
    /// Time-series rows over the flow.
    pub rows: u64,
    /// Snapshots over the flow (0 for none).
    pub snapshots: u64,
    /// Checkpoints over the flow (besides the final one).
    pub checkpoints: u64,
    /// Verlet skin in units of `d_p`.
    pub skin: f64,
    /// Random seed of the filling.
    pub seed: u64,
    /// Coarse-graining kernel of the profiles.
    pub cg_kernel: KernelShape,
    /// Kernel width `w` in units of `d_p`.
    pub cg_width: f64,
    /// Spacing of the slabs along `z` in units of `d_p`.
    pub cg_spacing: f64,
    /// Time between the profiles' samples in the averaging window (s).
    pub cg_every: f64,
}

impl Default for ChuteSpec {
    fn default() -> Self {
        ChuteSpec {
            angle_deg: 24.0,
            height: 20.0,
            length: 10.0,
            width: 10.0,
            base_thickness: 1.0,
            diameter: 2.2e-3,
            polydispersity: 1.5,
            density: 2000.0,
            stiffness: 100.0,
            restitution: 0.8,
            friction: 0.5,
            cohesion: LawSpec::default(),
            gravity: 9.81,
            settle_damping: 10.0,
            settle_kinetic_ratio: 1e-4,
            settle_max_time: 2.0,
            duration: 6.0,
            average_from: 3.0,
            bulk_margin: 4.0,
            rows: 300,
            snapshots: 4,
            checkpoints: 8,
            skin: 0.1,
            seed: 1,
            cg_kernel: KernelShape::Lucy,
            cg_width: 1.0,
            cg_spacing: 0.5,
            cg_every: 0.02,
        }
    }
}

/// Blocks of the averaging window whose profiles give the error bars.
pub const BLOCKS: usize = 8;

/// Volume fraction assumed for the settled layer when counting the particles to insert.
const SETTLED_FRACTION: f64 = 0.6;
/// Volume fraction of the loose random filling.
const FILL_FRACTION: f64 = 0.25;
/// Largest number of particles a chute may hold.
const MAX_PARTICLES: usize = 50_000_000;
/// Part number of the frozen base.
const BASE: u16 = 0;
/// Part number of the smooth floor under the base.
const FLOOR: u16 = 1;

/// The chute's resolved geometry (m).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Geometry {
    /// Box length along the flow `L_x`.
    pub length: f64,
    /// Box width across the flow `L_y`.
    pub width: f64,
    /// Height below which settled grains freeze into the base.
    pub base: f64,
    /// Top of the loose filling (and of the box's cell grid; grains above it still
    /// interact).
    pub fill_top: f64,
    /// Particles inserted (free and future base).
    pub count: usize,
    /// Smallest and largest particle radius.
    pub radii: [f64; 2],
    /// Interaction range of the adhesive law beyond contact (0 if none).
    pub range: f64,
}

impl ChuteSpec {
    /// A spec from a TOML table (a study point, a config); the error names the key.
    ///
    /// # Errors
    /// [`ScenarioError::Parse`] naming the offending key.
    pub fn from_table(table: toml::Table) -> Result<ChuteSpec, ScenarioError> {
        let mut spec: ChuteSpec = serde_path_to_error::deserialize(toml::Value::Table(table))
            .map_err(|e| ScenarioError::Parse(format!("key `{}`: {}", e.path(), e.inner())))?;
        spec.cohesion = cohesion(spec.cohesion, &Vec::new())?;
        Ok(spec)
    }

    /// The spec as TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }

    /// The contact law of every pair (grains, base and floor): a linear spring and dashpot
    /// of restitution `e`, a tangential spring and dashpot at 2/7 of the normal ones with
    /// Coulomb's limit `μ_p`, and the adhesive law.
    ///
    /// # Errors
    /// [`ScenarioError`] naming the `cohesion` parameter its law refuses.
    pub fn law(&self) -> Result<ContactLaw, ScenarioError> {
        let damping = Damping::from_restitution(self.restitution, self.stiffness);
        let adhesion = self
            .cohesion
            .build()
            .map_err(|e| law_error("cohesion", e))?;
        Ok(ContactLaw {
            normal: LinearNormal {
                stiffness: self.stiffness,
                damping,
            }
            .into(),
            tangential: Resistance {
                stiffness: 2.0 / 7.0 * self.stiffness,
                damping: damping.scaled(2.0 / 7.0),
                mu_static: self.friction,
                mu_dynamic: self.friction,
            }
            .into(),
            rolling: Spring::NONE,
            torsion: Spring::NONE,
            adhesion,
        })
    }

    /// Weight of a particle of the mean diameter, `m g` (N).
    pub fn weight(&self) -> f64 {
        self.density * PI / 6.0 * self.diameter.powi(3) * self.gravity
    }

    /// The largest adhesive force of a pair of mean particles, `f_a^max` (N); 0 when dry.
    ///
    /// # Errors
    /// As [`ChuteSpec::law`].
    pub fn max_adhesion(&self) -> Result<f64, ScenarioError> {
        let a = 0.5 * self.diameter;
        Ok(self.law()?.adhesion.max_force(a, a))
    }

    /// Checks every value and resolves the geometry; errors name the key and the range.
    ///
    /// # Errors
    /// [`ScenarioError::Invalid`] naming the key out of range.
    pub fn geometry(&self) -> Result<Geometry, ScenarioError> {
        check_table(Self::FIELDS, &table_of(self))?;
        let d = self.diameter;
        if self.average_from >= self.duration {
            return Err(invalid(
                "average_from",
                self.average_from,
                format!("must be in [0, duration = {})", self.duration),
            ));
        }
        let range = self.law()?.range();
        if !(range.is_finite() && range <= d) {
            return Err(invalid(
                "law",
                format!("\"{}\"", self.cohesion.law),
                format!(
                    "gives an interaction range S_c = {range:.3e} m beyond the mean diameter \
                     d_p = {d:.3e} m (the laws are meant for bridges shorter than a particle)"
                ),
            ));
        }
        let w = self.polydispersity;
        let (r_min, r_max) = (d / (1.0 + w), w * d / (1.0 + w));
        // The periodic axes must hold three neighbour cells (docs/model.md §4.1).
        let cutoff = 2.0 * r_max + range + self.skin * d;
        for (key, l) in [("length", self.length), ("width", self.width)] {
            if l * d < 3.0 * cutoff {
                return Err(invalid(
                    key,
                    l,
                    format!(
                        "must be at least {:.3} d_p: three neighbour cells of 2 r_max + range + \
                         skin = {cutoff:.3e} m",
                        3.0 * cutoff / d
                    ),
                ));
            }
        }
        let (length, width) = (self.length * d, self.width * d);
        let area = length * width;
        let mean_volume = 4.0 / 3.0 * PI * mean_radius_cubed(r_min, r_max);
        let column = (self.height + self.base_thickness) * d;
        let count = (SETTLED_FRACTION * area * column / mean_volume).round();
        if count > MAX_PARTICLES as f64 {
            return Err(invalid(
                "height",
                self.height,
                format!(
                    "gives {count:.3e} particles with length and width, more than the \
                     {MAX_PARTICLES} a chute may hold"
                ),
            ));
        }
        let count = count as usize;
        let fill_top = count as f64 * mean_volume / (FILL_FRACTION * area) + 2.0 * r_max;
        Ok(Geometry {
            length,
            width,
            base: self.base_thickness * d,
            fill_top,
            count,
            radii: [r_min, r_max],
            range,
        })
    }
}

impl SetUpSchema for ChuteSpec {
    const NAME: &'static str = "chute";
    const SUMMARY: &'static str = "Inclined chute flow on a rough base: fill, settle, tilt, \
        flow; depth profiles of φ, v, σ, μ and I, the force balance and Bagnold's profile \
        (Silbert et al. 2001).";
    const FIELDS: &'static [Field] = fields_with_law!([
        Field::number(
            "angle_deg",
            "degrees",
            "Inclination θ of the chute",
            Range::Closed(0.0, 60.0),
        ),
        Field::number(
            "height",
            "d_p",
            "Height h of the layer above the base, aimed at after settling",
            Range::Closed(2.0, 1000.0),
        ),
        Field::number("mu_p", "", "Particle friction μ_p", Range::AtLeast(0.0))
            .stored_as("friction"),
    ]; [
        Field::number("duration", "s", "Flow duration after the tilt", Range::Above(0.0)),
        Field::number(
            "average_from",
            "s",
            "Start of the averaging window after the tilt",
            Range::AtLeast(0.0),
        )
        .note(", below the duration"),
        Field::number(
            "length",
            "d_p",
            "Length of the periodic box along the flow",
            Range::Above(0.0),
        )
        .note(", at least three neighbour cells"),
        Field::number(
            "width",
            "d_p",
            "Width of the periodic box across the flow",
            Range::Above(0.0),
        )
        .note(", at least three neighbour cells"),
        Field::number(
            "base_thickness",
            "d_p",
            "Grains whose centres lie below this height freeze into the rough base",
            Range::Closed(0.1, 10.0),
        ),
        Field::number(
            "diameter",
            "m",
            "Mean particle diameter d_p",
            Range::Above(0.0),
        ),
        Field::number(
            "polydispersity",
            "",
            "Polydispersity w = r_max/r_min (uniform radii)",
            Range::Closed(1.0, 10.0),
        ),
        Field::number(
            "density",
            "kg/m³",
            "Particle density ρ_p",
            Range::Above(0.0),
        ),
        Field::number(
            "stiffness",
            "N/m",
            "Normal stiffness k_n",
            Range::Above(0.0),
        ),
        Field::number(
            "restitution",
            "",
            "Restitution coefficient e of a pair",
            Range::AboveUpTo(0.0, 1.0),
        ),
        Field::number("gravity", "m/s²", "Gravity g", Range::Above(0.0)),
        Field::number(
            "settle_damping",
            "",
            "Factor on every damping coefficient while settling",
            Range::Above(0.0),
        ),
        Field::number(
            "settle_kinetic_ratio",
            "",
            "Settling ends when the kinetic energy is below this fraction of the contact \
             springs' energy",
            Range::Above(0.0),
        ),
        Field::number(
            "settle_max_time",
            "s",
            "Settling ends at this time even if the kinetic criterion is not met",
            Range::Above(0.0),
        ),
        Field::number(
            "bulk_margin",
            "d_p",
            "Slabs this close to the base or the surface are left out of the bulk averages",
            Range::AtLeast(0.0),
        ),
        Field::count("rows", "Time-series rows over the flow", Range::AtLeast(2.0)),
        Field::count(
            "snapshots",
            "Snapshots over the flow (0 for none)",
            Range::AtLeast(0.0),
        ),
        Field::count(
            "checkpoints",
            "Checkpoints over the flow besides the final one",
            Range::AtLeast(0.0),
        ),
        Field::number("skin", "d_p", "Verlet skin", Range::Above(0.0)),
        Field::count("seed", "Random seed of the filling", Range::AtLeast(0.0)),
        Field::choice(
            "cg_kernel",
            "Coarse-graining kernel of the profiles",
            &["lucy", "gaussian"],
        ),
        Field::number("cg_width", "d_p", "Kernel width", Range::Above(0.0)),
        Field::number(
            "cg_spacing",
            "d_p",
            "Spacing of the slabs along z",
            Range::Above(0.0),
        ),
        Field::number(
            "cg_every",
            "s",
            "Time between the profiles' samples in the averaging window",
            Range::Above(0.0),
        ),
    ]);

    fn defaults() -> toml::Table {
        table_of(&ChuteSpec::default())
    }

    fn from_values(base: toml::Table, values: &Values) -> Result<ChuteSpec, ScenarioError> {
        let table = overlay(Self::FIELDS, base, values)?;
        let mut s = ChuteSpec::from_table(table)?;
        s.cohesion = cohesion(s.cohesion, values)?;
        s.geometry()?;
        Ok(s)
    }
}

/// The stage a run is in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Stage {
    /// Falling and settling under vertical gravity.
    Settle,
    /// Flowing down the tilted chute.
    Flow,
    /// Finished.
    Done,
}

/// One row of the time series.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Time since the start of the filling (s).
    pub time: f64,
    /// Stage of the row.
    pub stage: Stage,
    /// Kinetic energy of the free particles, translational + rotational (J).
    pub kinetic_energy: f64,
    /// Its translational part (J).
    pub kinetic_translational: f64,
    /// Flow rate per unit width `Q = Σ V_i v_x,i / L_x` (m²/s).
    pub flow_rate: f64,
    /// Mass-averaged velocity along the flow `Σ m_i v_x,i / Σ m_i` (m/s).
    pub mean_velocity: f64,
    /// Height of the free surface above the floor (m), see [`surface_height_box`].
    pub surface_height: f64,
    /// Contacts with overlap.
    pub contacts: u64,
    /// Coordination number `2 N_c / N` over free particles.
    pub coordination: f64,
    /// Attracting pairs apart (open bridges) per free particle.
    pub bridges_per_particle: f64,
}

/// What settling reached.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SettleReport {
    /// Time at the end of settling (s).
    pub time: f64,
    /// Translational `E_kin / E_springs` at the end.
    pub kinetic_ratio: f64,
    /// Whether the kinetic criterion was met (rather than the time limit).
    pub criterion_met: bool,
    /// Free particles left.
    pub free: usize,
    /// Particles frozen into the base.
    pub base_particles: usize,
    /// Height of the base's top above the floor (m), measured as the surface.
    pub base_top: f64,
    /// Height of the free surface above the floor (m).
    pub surface_height: f64,
}

/// The state of a chute run: serialised whole as its checkpoint (and as `settled.bin` at
/// the end of settling).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ChuteState {
    /// The spec as run.
    pub spec: ChuteSpec,
    /// Resolved geometry.
    pub geometry: Geometry,
    /// Current stage.
    pub stage: Stage,
    /// The simulation state.
    pub simulation: Simulation,
    /// Time-series rows so far.
    pub rows: Vec<Row>,
    /// End of settling, once reached.
    pub settled: Option<SettleReport>,
    /// Time and step of the tilt.
    pub flow_start: Option<(f64, u64)>,
    /// Kernel sums of the profiles over the averaging window so far.
    pub fields: Option<CgSums>,
    /// The same sums per block of the window ([`BLOCKS`]), for the error bars.
    pub blocks: Vec<CgSums>,
    /// Snapshots so far: `(time, file name)`.
    pub snapshots: Vec<(f64, String)>,
    /// Wall-clock seconds spent stepping.
    pub wall_seconds: f64,
    /// The settled run this one started from, if any.
    pub from: Option<String>,
    /// The step this run started at (the throughput counts the steps since).
    pub first_step: u64,
}

/// A chute run in its directory, on the staged run driver.
pub type ChuteRun = Driver<ChuteState>;

impl ChuteState {
    /// The filled chute (stage settle), its spec written into the run directory.
    fn filled(
        spec: ChuteSpec,
        geometry: Geometry,
        session: &Session<'_>,
    ) -> Result<ChuteState, RunError> {
        let mut rng = Rng::seed_from_u64(spec.seed);
        let g = &geometry;
        let radii = polydisperse_radii(&mut rng, g.count, spec.diameter, spec.polydispersity);
        let mould = Domain::new(
            DVec3::ZERO,
            DVec3::new(g.length, g.width, g.fill_top),
            [true, true, false],
        );
        let centres = insert_random(&mut rng, &radii, &mould, &[], 10_000).map_err(|placed| {
            RunError::Scenario(invalid(
                "height",
                spec.height,
                format!(
                    "the loose filling could place only {placed} of {} particles",
                    g.count
                ),
            ))
        })?;
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
        let mut laws = ContactTable::uniform(1, spec.law()?);
        let mut floor = Wall::plane(DVec3::ZERO, DVec3::Z, 0);
        floor.part = FLOOR;
        let walls = vec![floor];
        let t_c = shortest_contact_time(&particles, &laws, &walls).map_err(|e| {
            RunError::Scenario(invalid("restitution", spec.restitution, e.to_string()))
        })?;
        laws.map(|l| {
            l.normal = l.normal.damping_scaled(spec.settle_damping);
            l.tangential = l.tangential.damping_scaled(spec.settle_damping);
        });
        let mut simulation = Simulation::new(
            particles,
            mould,
            laws,
            walls,
            DVec3::new(0.0, 0.0, -spec.gravity),
            t_c / 50.0,
            spec.skin * spec.diameter,
        )
        .map_err(RunError::Neighbor)?;
        simulation.parts = vec!["base".into(), "floor".into()];
        let state = ChuteState {
            spec,
            geometry,
            stage: Stage::Settle,
            simulation,
            rows: Vec::new(),
            settled: None,
            flow_start: None,
            fields: None,
            blocks: Vec::new(),
            snapshots: Vec::new(),
            wall_seconds: 0.0,
            from: None,
            first_step: 0,
        };
        state.write_spec(session.dir)?;
        Ok(state)
    }

    fn write_spec(&self, dir: &Path) -> Result<(), RunError> {
        let path = dir.join("chute.toml");
        let header = format!(
            "# rheodem {} (commit {}) — chute as run, every default written out\n",
            crate::VERSION,
            crate::COMMIT
        );
        write_atomic(&path, (header + &self.spec.to_toml()).as_bytes())
            .map_err(io_err("write", &path))?;
        let snapshots = dir.join("snapshots");
        std::fs::create_dir_all(&snapshots).map_err(io_err("create the directory", &snapshots))
    }

    /// Height of the top of the particles with `include(i)` (m), [`surface_height_box`]
    /// over columns of 2 `d_p`.
    fn top_of(&self, include: impl Fn(usize) -> bool) -> f64 {
        let p = &self.simulation.particles;
        let g = &self.geometry;
        surface_height_box(
            &p.position,
            &p.radius,
            include,
            DVec3::ZERO,
            DVec3::new(g.length, g.width, 0.0),
            2.0 * self.spec.diameter,
        )
        .unwrap_or(0.0)
    }

    fn surface_height(&self) -> f64 {
        let p = &self.simulation.particles;
        self.top_of(|i| p.motion[i].is_free())
    }

    /// The row of the current (just measured) state.
    fn row(&self) -> Row {
        let sim = &self.simulation;
        let p = &sim.particles;
        let (kinetic_translational, kinetic_rotational) = sim.kinetic_energies();
        let c = sim.contact_summary();
        let (mut volume_flux, mut momentum, mut mass) = (0.0, 0.0, 0.0);
        for i in (0..p.len()).filter(|&i| p.motion[i].is_free()) {
            let v = p.velocity[i].x;
            volume_flux += 4.0 / 3.0 * PI * p.radius[i].powi(3) * v;
            momentum += p.mass[i] * v;
            mass += p.mass[i];
        }
        Row {
            time: sim.time,
            stage: self.stage,
            kinetic_energy: kinetic_translational + kinetic_rotational,
            kinetic_translational,
            flow_rate: volume_flux / self.geometry.length,
            mean_velocity: if mass > 0.0 { momentum / mass } else { 0.0 },
            surface_height: self.surface_height(),
            contacts: c.contacts,
            coordination: c.coordination,
            bridges_per_particle: c.bridges_per_particle,
        }
    }

    /// Steps of the flow stage.
    pub fn flow_steps(&self) -> u64 {
        (self.spec.duration / self.simulation.dt).round().max(1.0) as u64
    }

    /// The settle stage's end: the kinetic criterion, no sooner than the time of a free fall
    /// from the top of the filling, at the latest `settle_max_time`.
    pub fn settle_end(&self) -> EndCondition {
        EndCondition::KineticBelow {
            ratio: self.spec.settle_kinetic_ratio,
            min_time: (2.0 * self.geometry.fill_top / self.spec.gravity).sqrt(),
            max_time: self.spec.settle_max_time,
        }
    }

    /// Steps between the checks of the settle stage's end (5 ms of simulated time).
    fn settle_check(&self) -> u64 {
        ((0.005 / self.simulation.dt).round() as u64).max(1)
    }

    /// Freezes the grains below the base height into the rough base.
    fn freeze_base(&mut self, kinetic_ratio: f64, criterion_met: bool) -> Result<(), RunError> {
        let base = self.geometry.base;
        let p = &mut self.simulation.particles;
        let mut frozen = 0;
        for i in 0..p.len() {
            if p.motion[i].is_free() && p.position[i].z < base {
                p.prescribe(i, Motion::Fixed, BASE);
                frozen += 1;
            }
        }
        // Pairs of two base particles leave the list.
        self.simulation.rebuild_neighbors()?;
        let p = &self.simulation.particles;
        self.settled = Some(SettleReport {
            time: self.simulation.time,
            kinetic_ratio,
            criterion_met,
            free: p.free_count(),
            base_particles: frozen,
            base_top: self.top_of(|i| !p.motion[i].is_free()),
            surface_height: self.surface_height(),
        });
        Ok(())
    }

    /// Tilts the chute: the laws of the spec (no settling damping), gravity at `θ`, empty
    /// profiles over slabs from the floor to well above the surface.
    fn begin_flow(&mut self) -> Result<(), RunError> {
        let law = self.spec.law()?;
        let sim = &mut self.simulation;
        sim.laws = ContactTable::uniform(1, law);
        if law.range() > sim.neighbors.range {
            sim.neighbors.range = law.range();
        }
        sim.neighbors.skin = self.spec.skin * self.spec.diameter;
        let theta = self.spec.angle_deg.to_radians();
        sim.gravity = self.spec.gravity * DVec3::new(theta.sin(), 0.0, -theta.cos());
        sim.rebuild_neighbors()?;
        sim.compute_forces(true);
        self.flow_start = Some((sim.time, sim.step));
        self.stage = Stage::Flow;
        let grid = self.grid()?;
        self.fields = Some(CgSums::new(grid.clone())?);
        self.blocks = (0..BLOCKS)
            .map(|_| CgSums::new(grid.clone()))
            .collect::<Result<_, _>>()?;
        Ok(())
    }

    /// Slabs along `z` from the floor to the settled surface plus a quarter of the layer
    /// and two diameters (room for the dilated flowing layer).
    fn grid(&self) -> Result<Grid, RunError> {
        let d = self.spec.diameter;
        let surface = self
            .settled
            .as_ref()
            .map_or(self.geometry.fill_top, |s| s.surface_height);
        let hi = 1.25 * surface + 2.0 * d;
        let bins = ((hi / (self.spec.cg_spacing * d)).round() as usize).max(2);
        let grid = Grid::Slab {
            axis: 2,
            lo: 0.0,
            hi,
            bins,
            area: self.geometry.length * self.geometry.width,
        };
        grid.validate()?;
        Ok(grid)
    }

    fn kernel(&self) -> Result<Kernel, RunError> {
        Ok(Kernel::new(
            self.spec.cg_kernel,
            self.spec.cg_width * self.spec.diameter,
        )?)
    }

    /// Adds the current state, with the contacts of its last step, to the profiles and to
    /// the block of the window it falls in.
    fn sample_fields(&mut self, contacts: &[ContactRecord]) -> Result<(), RunError> {
        let kernel = self.kernel()?;
        let t0 = self.flow_start.map_or(0.0, |s| s.0);
        let window = self.spec.duration - self.spec.average_from;
        let into = (self.simulation.time - t0 - self.spec.average_from) / window;
        let block = ((into * BLOCKS as f64) as usize).min(BLOCKS - 1);
        let view = LabView::of(&self.simulation);
        if let Some(sums) = &mut self.fields {
            let snap = snapshot(&view, contacts, &sums.grid);
            sums.add_snapshot(&kernel, &snap);
            if let Some(b) = self.blocks.get_mut(block) {
                b.add_snapshot(&kernel, &snap);
            }
        }
        Ok(())
    }

    fn snapshot(&mut self, dir: &Path) -> Result<(), RunError> {
        let p = &self.simulation.particles;
        let v_x: Vec<f64> = p.velocity.iter().map(|v| v.x).collect();
        let name = format!("snapshot-{:06}.vtp", self.snapshots.len());
        let path = dir.join("snapshots").join(&name);
        write_atomic(&path, vtk::particles_vtp(p, &[("v_x", v_x)]).as_bytes())
            .map_err(io_err("write", &path))?;
        self.snapshots
            .push((self.simulation.time, format!("snapshots/{name}")));
        let path = dir.join("snapshots.pvd");
        write_atomic(&path, vtk::collection_pvd(&self.snapshots).as_bytes())
            .map_err(io_err("write", &path))
    }

    /// The operations of flow step `next` (counted from the tilt), whose end is at `time`:
    /// `(measure, snapshot, sample the profiles)`.
    fn flow_operations(&self, next: u64, time: f64) -> (bool, bool, bool) {
        let (t0, _) = self.flow_start.unwrap_or((0.0, 0));
        let total = self.flow_steps();
        let rows = Every(total.checked_div(self.spec.rows).unwrap_or(0).max(1));
        let measure = rows.fires(next) || next == total;
        let snapshot = Every(total.checked_div(self.spec.snapshots).unwrap_or(0)).fires(next);
        let every = ((self.spec.cg_every / self.simulation.dt).round() as u64).max(1);
        let sample = time - t0 >= self.spec.average_from && next.is_multiple_of(every);
        (measure, snapshot, sample)
    }

    fn after_settle_step(&mut self, session: &mut Session<'_>) -> Result<bool, RunError> {
        let check = self.settle_check();
        let step = self.simulation.step;
        if !step.is_multiple_of(check) {
            return Ok(false);
        }
        let end = self.settle_end();
        let row = self.row();
        // As in the split-bottom cell: the translational energy against the springs'
        // energy alone (a cohesive law's potential may make the elastic energy negative).
        let springs = self.simulation.contact_summary().spring_energy;
        let energies = (row.kinetic_translational, springs);
        session.sane(&self.simulation)?;
        self.rows.push(row);
        let verdict = end.verdict(step, self.simulation.time, Some(energies));
        if verdict == Verdict::Continue {
            return Ok(step.is_multiple_of(20 * check));
        }
        let ratio = energies.0 / energies.1.max(f64::MIN_POSITIVE);
        self.freeze_base(ratio, verdict == Verdict::Met)?;
        self.wall_seconds += session.lap();
        session.save_state("settled.bin", self)?;
        self.begin_flow()?;
        Ok(true)
    }

    fn after_flow_step(
        &mut self,
        session: &mut Session<'_>,
        contacts: Option<&[ContactRecord]>,
    ) -> Result<bool, RunError> {
        let (_, s0) = self.flow_start.unwrap_or((0.0, 0));
        let total = self.flow_steps();
        let next = self.simulation.step - s0;
        let (measure, snapshot, sample) = self.flow_operations(next, self.simulation.time);
        if sample {
            self.sample_fields(contacts.unwrap_or_default())?;
        }
        if measure {
            session.sane(&self.simulation)?;
            let row = self.row();
            self.rows.push(row);
        }
        if snapshot {
            self.snapshot(session.dir)?;
        }
        if next == total {
            self.stage = Stage::Done;
        }
        let checkpoints = Every(total.checked_div(self.spec.checkpoints).unwrap_or(0));
        Ok(next == total || checkpoints.fires(next))
    }
}

impl SetUp for ChuteState {
    const MAKER: Maker = Maker::Chute;

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
            Stage::Flow | Stage::Done => Progress {
                stage: "flow",
                done: self.simulation.step - self.flow_start.map_or(0, |s| s.1),
                total: self.flow_steps(),
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
            Stage::Flow | Stage::Done => {
                let next = sim.step + 1 - self.flow_start.map_or(0, |s| s.1);
                let (measure, _, sample) = self.flow_operations(next, sim.time + sim.dt);
                StepNeeds {
                    measure: measure || sample,
                    contacts: sample,
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
            Stage::Flow | Stage::Done => self.after_flow_step(session, contacts),
        }
    }

    fn wall_seconds_mut(&mut self) -> &mut f64 {
        &mut self.wall_seconds
    }

    fn write_outputs(&self, dir: &Path) -> Result<serde_json::Value, RunError> {
        let mut csv = String::from(
            "time,stage,kinetic_energy,flow_rate,mean_velocity,surface_height,contacts,\
             coordination,bridges_per_particle\n",
        );
        for r in &self.rows {
            let _ = writeln!(
                csv,
                "{:e},{},{:e},{:e},{:e},{:e},{},{:e},{:e}",
                r.time,
                if r.stage == Stage::Settle {
                    "settle"
                } else {
                    "flow"
                },
                r.kinetic_energy,
                r.flow_rate,
                r.mean_velocity,
                r.surface_height,
                r.contacts,
                r.coordination,
                r.bridges_per_particle
            );
        }
        let path = dir.join("timeseries.csv");
        write_atomic(&path, csv.as_bytes()).map_err(io_err("write", &path))?;
        let results = self.results()?;
        if let Some(r) = &results {
            let path = dir.join("profiles.csv");
            write_atomic(&path, profiles_csv(&r.profiles).as_bytes())
                .map_err(io_err("write", &path))?;
            if self.stage == Stage::Done {
                self.write_figures(dir, r)?;
            }
        }
        Ok(self.summary_with(results.as_ref()))
    }

    fn summary(&self) -> serde_json::Value {
        self.summary_with(self.results().ok().flatten().as_ref())
    }
}

/// The profiles at one height, averaged over the window; `*_error` the standard error
/// from the [`BLOCKS`] blocks (NaN where a block lacks the point).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ProfilePoint {
    /// Height above the floor (m).
    pub z: f64,
    /// Volume fraction `φ`.
    pub volume_fraction: f64,
    /// Its error.
    pub volume_fraction_error: f64,
    /// Velocity along the flow `v_x` (m/s).
    pub velocity: f64,
    /// Its error.
    pub velocity_error: f64,
    /// Shear stress `σ_xz` (Pa, compression positive).
    pub shear_stress: f64,
    /// Normal stress `σ_zz` (Pa, compression positive).
    pub normal_stress: f64,
    /// The normal stress of the weight above, `ρ_p g cos θ ∫_z^∞ φ dz'` (Pa).
    pub weight_above: f64,
    /// Shear rate `γ̇` (1/s), the coarse-grained strain rate's magnitude.
    pub shear_rate: f64,
    /// Friction `μ = |σ_xz| / σ_zz`.
    pub friction: f64,
    /// Its error.
    pub friction_error: f64,
    /// Inertial number `I = γ̇ d_p / √(σ_zz/ρ_p)`.
    pub inertial_number: f64,
    /// Its error.
    pub inertial_number_error: f64,
    /// Softness `p* = σ_zz d_p / k_n`.
    pub softness: f64,
    /// Bond number `Bo = f_a^max / (σ_zz d_p²)` (0 when dry).
    pub bond_number: f64,
}

/// Values over the bulk slabs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bulk {
    /// The bulk's heights above the floor (m).
    pub z: [f64; 2],
    /// Slabs in it.
    pub slabs: usize,
    /// Friction `μ`, averaged over the slabs (error from the blocks).
    pub friction: Option<Estimate>,
    /// Inertial number `I`.
    pub inertial_number: Option<Estimate>,
    /// Volume fraction `φ`.
    pub volume_fraction: Option<Estimate>,
    /// `p*` at mid-depth (the slab nearest the middle of the layer).
    pub softness_mid: f64,
    /// `Bo` at mid-depth.
    pub bond_mid: f64,
    /// `σ_zz` over the weight above, averaged over the slabs.
    pub normal_stress_ratio: Option<Estimate>,
    /// The largest `|μ − tan θ|` over the slabs in units of each slab's error.
    pub friction_worst_sigma: f64,
    /// The largest `|σ_zz / weight above − 1|` over the slabs.
    pub normal_stress_worst: f64,
}

/// Bagnold's profile fitted to the bulk: `v(ζ) = v_0 + A (H^{3/2} − (H − ζ)^{3/2})`, `ζ`
/// the height above the base top and `H` the flowing depth (surface minus base top).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BagnoldFit {
    /// Flowing depth `H` (m).
    pub depth: f64,
    /// Velocity offset `v_0` (m/s).
    pub offset: f64,
    /// Amplitude `A` (m^{-1/2} s^{-1}).
    pub amplitude: f64,
    /// Root-mean-square residual over the bulk slabs (m/s).
    pub rms_residual: f64,
    /// The residual over the largest fitted velocity.
    pub relative_residual: f64,
}

/// The results of the averaging window.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChuteResults {
    /// Averaging window (s after the tilt).
    pub window: [f64; 2],
    /// `tan θ`, the friction that steady uniform flow must show at every depth.
    pub tan_theta: f64,
    /// Kinetic energy of the window (J).
    pub kinetic_energy: Option<Estimate>,
    /// Flow rate per unit width (m²/s).
    pub flow_rate: Option<Estimate>,
    /// Surface height above the floor (m).
    pub surface_height: Option<Estimate>,
    /// Whether the window is steady: the two halves of the kinetic energy and of the flow
    /// rate agree (within 3 errors or 5 %).
    pub steady: bool,
    /// Profile samples in the window.
    pub samples: u64,
    /// The bulk.
    pub bulk: Option<Bulk>,
    /// Bagnold's profile, or why it was not fitted.
    pub bagnold: Result<BagnoldFit, String>,
    /// The profiles.
    pub profiles: Vec<ProfilePoint>,
}

/// The mean and standard error over the blocks that have a value; NaN error with fewer
/// than two.
fn over_blocks(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    let n = v.len() as f64;
    if v.len() < 2 {
        return (v.first().copied().unwrap_or(f64::NAN), f64::NAN);
    }
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

impl ChuteState {
    fn material(&self) -> Result<Material, RunError> {
        Ok(Material {
            diameter: self.spec.diameter,
            particle_density: self.spec.density,
            stiffness: self.spec.stiffness,
            max_adhesion: self.spec.max_adhesion()?,
        })
    }

    /// The profile values of one set of sums: `(z, φ, v_x, σ_xz, σ_zz, γ̇, μ, I)` per slab.
    fn raw_profile(&self, sums: &CgSums) -> Result<Vec<[f64; 8]>, RunError> {
        let material = self.material()?;
        let (d, rho) = (self.spec.diameter, self.spec.density);
        Ok(fields(sums, Some(&material))
            .iter()
            .map(|f: &FieldPoint| {
                let (xz, zz) = (f.stress[2], f.stress[8]);
                let rate = f.strain_rate;
                [
                    f.coordinates[0],
                    f.volume_fraction,
                    f.velocity[0],
                    xz,
                    zz,
                    rate,
                    xz.abs() / zz,
                    rate * d / (zz / rho).sqrt(),
                ]
            })
            .collect())
    }

    /// The results of the window, once it has a sample.
    ///
    /// # Errors
    /// [`RunError::Scenario`] when the law cannot be built (a corrupt state).
    pub fn results(&self) -> Result<Option<ChuteResults>, RunError> {
        let Some(sums) = self.fields.as_ref().filter(|s| s.snapshots > 0) else {
            return Ok(None);
        };
        let spec = &self.spec;
        let (d, theta) = (spec.diameter, spec.angle_deg.to_radians());
        let max_adhesion = spec.max_adhesion()?;
        let total = self.raw_profile(sums)?;
        let blocks: Vec<Vec<[f64; 8]>> = self
            .blocks
            .iter()
            .filter(|b| b.snapshots > 0)
            .map(|b| self.raw_profile(b))
            .collect::<Result<_, _>>()?;
        let error = |j: usize, k: usize| over_blocks(blocks.iter().map(|b| b[j][k])).1;
        // The weight above each slab centre: half its own slab, all slabs above.
        let dz = sums.grid.spacing()[0];
        let load = spec.density * spec.gravity * theta.cos();
        let mut above = 0.0;
        let mut weight = vec![0.0; total.len()];
        for j in (0..total.len()).rev() {
            let phi = total[j][1].max(0.0);
            weight[j] = load * (above + 0.5 * phi * dz);
            above += phi * dz;
        }
        let profiles: Vec<ProfilePoint> = total
            .iter()
            .enumerate()
            .map(|(j, t)| ProfilePoint {
                z: t[0],
                volume_fraction: t[1],
                volume_fraction_error: error(j, 1),
                velocity: t[2],
                velocity_error: error(j, 2),
                shear_stress: t[3],
                normal_stress: t[4],
                weight_above: weight[j],
                shear_rate: t[5],
                friction: t[6],
                friction_error: error(j, 6),
                inertial_number: t[7],
                inertial_number_error: error(j, 7),
                softness: t[4] * d / spec.stiffness,
                bond_number: if max_adhesion > 0.0 {
                    max_adhesion / (t[4] * d * d)
                } else {
                    0.0
                },
            })
            .collect();
        let t0 = self.flow_start.map_or(0.0, |s| s.0);
        let window: Vec<&Row> = self
            .rows
            .iter()
            .filter(|r| r.stage != Stage::Settle && r.time - t0 >= spec.average_from)
            .collect();
        let series = |f: &dyn Fn(&Row) -> f64| window.iter().map(|r| f(r)).collect::<Vec<_>>();
        let (energy, flow, surface) = (
            series(&|r| r.kinetic_energy),
            series(&|r| r.flow_rate),
            series(&|r| r.surface_height),
        );
        let surface_height = block_average(&surface);
        let base_top = self.settled.as_ref().map_or(0.0, |s| s.base_top);
        let top = surface_height.map_or(base_top, |e| e.mean);
        let margin = spec.bulk_margin * d;
        let bulk_range = [base_top + margin, top - margin];
        let in_bulk: Vec<usize> = (0..profiles.len())
            .filter(|&j| (bulk_range[0]..=bulk_range[1]).contains(&profiles[j].z))
            .collect();
        let bulk = (!in_bulk.is_empty()).then(|| {
            let mean_over = |b: &[[f64; 8]], k: usize| {
                in_bulk.iter().map(|&j| b[j][k]).sum::<f64>() / in_bulk.len() as f64
            };
            let estimate = |k: usize| {
                let (_, error) = over_blocks(blocks.iter().map(|b| mean_over(b, k)));
                Some(Estimate {
                    mean: mean_over(&total, k),
                    error,
                    samples: blocks.len(),
                })
            };
            let ratio = |b: &[[f64; 8]]| {
                in_bulk.iter().map(|&j| b[j][4] / weight[j]).sum::<f64>() / in_bulk.len() as f64
            };
            let mid = 0.5 * (base_top + top);
            let nearest = in_bulk
                .iter()
                .copied()
                .min_by(|&a, &b| {
                    (profiles[a].z - mid)
                        .abs()
                        .total_cmp(&(profiles[b].z - mid).abs())
                })
                .unwrap_or(in_bulk[0]);
            Bulk {
                z: bulk_range,
                slabs: in_bulk.len(),
                friction: estimate(6),
                inertial_number: estimate(7),
                volume_fraction: estimate(1),
                softness_mid: profiles[nearest].softness,
                bond_mid: profiles[nearest].bond_number,
                normal_stress_ratio: Some(Estimate {
                    mean: ratio(&total),
                    error: over_blocks(blocks.iter().map(|b| ratio(b))).1,
                    samples: blocks.len(),
                }),
                friction_worst_sigma: in_bulk
                    .iter()
                    .map(|&j| {
                        (profiles[j].friction - theta.tan()).abs() / profiles[j].friction_error
                    })
                    .fold(0.0, f64::max),
                normal_stress_worst: in_bulk
                    .iter()
                    .map(|&j| (profiles[j].normal_stress / weight[j] - 1.0).abs())
                    .fold(0.0, f64::max),
            }
        });
        let points: Vec<(f64, f64)> = in_bulk
            .iter()
            .map(|&j| (profiles[j].z - base_top, profiles[j].velocity))
            .collect();
        Ok(Some(ChuteResults {
            window: [spec.average_from, spec.duration],
            tan_theta: theta.tan(),
            kinetic_energy: block_average(&energy),
            flow_rate: block_average(&flow),
            surface_height,
            steady: halves_agree(&energy, 0.05) && halves_agree(&flow, 0.05),
            samples: sums.snapshots,
            bulk,
            bagnold: fit_bagnold(&points, top - base_top),
            profiles,
        }))
    }

    fn summary_with(&self, results: Option<&ChuteResults>) -> serde_json::Value {
        let weight = self.spec.weight();
        serde_json::json!({
            "program": "rheodem chute",
            "seed": self.spec.seed,
            "stage": self.stage,
            "from": self.from,
            "time": self.simulation.time,
            "steps": self.simulation.step,
            "dt": self.simulation.dt,
            "wall_seconds": self.wall_seconds,
            "particles": self.simulation.particles.len(),
            "free_particles": self.simulation.particles.free_count(),
            "particle_steps_per_second": if self.wall_seconds > 0.0 {
                let steps = self.simulation.step - self.first_step;
                self.simulation.particles.len() as f64 * steps as f64 / self.wall_seconds
            } else { 0.0 },
            "threads": rayon::current_num_threads(),
            "spec": self.spec,
            "geometry": self.geometry,
            "weight": weight,
            "cohesion_ratio": self.spec.max_adhesion().map(|f| f / weight).unwrap_or(f64::NAN),
            "settled": self.settled,
            "steady": results.map(|r| r.steady),
            "results": results,
        })
    }

    /// `flow.svg` (mean velocity and flow rate against time), `velocity.svg` (the velocity
    /// profile with Bagnold's fit), `friction.svg` (`μ(z)` beside `tan θ`) and
    /// `volume-fraction.svg`.
    fn write_figures(&self, dir: &Path, r: &ChuteResults) -> Result<(), RunError> {
        let t0 = self.flow_start.map_or(0.0, |s| s.0);
        let flow: Vec<(f64, f64)> = self
            .rows
            .iter()
            .filter(|r| r.stage != Stage::Settle)
            .map(|r| (r.time - t0, r.mean_velocity))
            .collect();
        let base_top = self.settled.as_ref().map_or(0.0, |s| s.base_top);
        let d = self.spec.diameter;
        let filled: Vec<&ProfilePoint> = r
            .profiles
            .iter()
            .filter(|p| p.z > base_top && p.volume_fraction > 0.05)
            .collect();
        let depth = |p: &ProfilePoint| (p.z - base_top) / d;
        let velocity: Vec<(f64, f64, f64)> = filled
            .iter()
            .map(|p| (depth(p), p.velocity, p.velocity_error))
            .collect();
        let fitted: Vec<(f64, f64)> = match &r.bagnold {
            Ok(f) => (0..=50)
                .map(|k| {
                    let zeta = f.depth * k as f64 / 50.0;
                    (zeta / d, f.at(zeta))
                })
                .collect(),
            Err(_) => Vec::new(),
        };
        let friction: Vec<(f64, f64, f64)> = filled
            .iter()
            .map(|p| (depth(p), p.friction, p.friction_error))
            .collect();
        let top = filled.last().map_or(1.0, |p| depth(p));
        let tan = [(0.0, r.tan_theta), (top, r.tan_theta)];
        let phi: Vec<(f64, f64, f64)> = filled
            .iter()
            .map(|p| (depth(p), p.volume_fraction, p.volume_fraction_error))
            .collect();
        let figures = [
            (
                "flow.svg",
                Labels {
                    title: "Mean velocity along the chute",
                    x: "time after the tilt (s)",
                    y: "v (m/s)",
                },
                vec![Series {
                    label: "mass-averaged v_x",
                    points: &flow,
                    dashed_as: None,
                }],
                Vec::new(),
            ),
            (
                "velocity.svg",
                Labels {
                    title: "Velocity profile",
                    x: "height above the base (d_p)",
                    y: "v_x (m/s)",
                },
                vec![Series {
                    label: "Bagnold fit (bulk)",
                    points: &fitted,
                    dashed_as: None,
                }],
                vec![Markers {
                    label: "coarse-grained",
                    points: &velocity,
                }],
            ),
            (
                "friction.svg",
                Labels {
                    title: "Friction |σ_xz|/σ_zz",
                    x: "height above the base (d_p)",
                    y: "μ",
                },
                vec![Series {
                    label: "tan θ",
                    points: &tan,
                    dashed_as: None,
                }],
                vec![Markers {
                    label: "coarse-grained",
                    points: &friction,
                }],
            ),
            (
                "volume-fraction.svg",
                Labels {
                    title: "Volume fraction",
                    x: "height above the base (d_p)",
                    y: "φ",
                },
                Vec::new(),
                vec![Markers {
                    label: "coarse-grained",
                    points: &phi,
                }],
            ),
        ];
        for (name, labels, series, markers) in figures {
            let svg = plot_svg(&labels, &series, &markers)
                .map_err(|e| RunError::Scenario(invalid("figure", name, e)))?;
            let path = dir.join(name);
            write_atomic(&path, svg.as_bytes()).map_err(io_err("write", &path))?;
        }
        Ok(())
    }
}

impl BagnoldFit {
    /// The fitted velocity at height `zeta` above the base top (m/s).
    pub fn at(&self, zeta: f64) -> f64 {
        let h = self.depth;
        self.offset + self.amplitude * (h.powf(1.5) - (h - zeta).max(0.0).powf(1.5))
    }
}

/// Fits Bagnold's profile to `(ζ, v)` points (heights above the base top, m; velocities,
/// m/s) for the flowing depth `depth` (m): linear least squares in `v_0` and `A`.
///
/// # Errors
/// A message with fewer than three points or a depth that is not positive.
pub fn fit_bagnold(points: &[(f64, f64)], depth: f64) -> Result<BagnoldFit, String> {
    if points.len() < 3 || !(depth.is_finite() && depth > 0.0) {
        return Err(format!(
            "{} bulk points over a depth of {depth:.3e} m: too few to fit",
            points.len()
        ));
    }
    let shape = |zeta: f64| depth.powf(1.5) - (depth - zeta).max(0.0).powf(1.5);
    let n = points.len() as f64;
    let (sx, sy) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), &(z, v)| (a + shape(z), b + v));
    let (mx, my) = (sx / n, sy / n);
    let (sxx, sxy) = points.iter().fold((0.0, 0.0), |(a, b), &(z, v)| {
        let x = shape(z) - mx;
        (a + x * x, b + x * (v - my))
    });
    if sxx <= 0.0 {
        return Err("the bulk points lie at one height".into());
    }
    let amplitude = sxy / sxx;
    let fit = BagnoldFit {
        depth,
        offset: my - amplitude * mx,
        amplitude,
        rms_residual: 0.0,
        relative_residual: 0.0,
    };
    let rms = (points
        .iter()
        .map(|&(z, v)| (v - fit.at(z)).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    let largest = points
        .iter()
        .map(|&(z, _)| fit.at(z).abs())
        .fold(0.0, f64::max);
    Ok(BagnoldFit {
        rms_residual: rms,
        relative_residual: rms / largest,
        ..fit
    })
}

fn profiles_csv(profiles: &[ProfilePoint]) -> String {
    let mut csv = String::from(
        "z,volume_fraction,volume_fraction_error,velocity,velocity_error,shear_stress,\
         normal_stress,weight_above,shear_rate,friction,friction_error,inertial_number,\
         inertial_number_error,softness,bond_number\n",
    );
    for p in profiles {
        let _ = writeln!(
            csv,
            "{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
            p.z,
            p.volume_fraction,
            p.volume_fraction_error,
            p.velocity,
            p.velocity_error,
            p.shear_stress,
            p.normal_stress,
            p.weight_above,
            p.shear_rate,
            p.friction,
            p.friction_error,
            p.inertial_number,
            p.inertial_number_error,
            p.softness,
            p.bond_number
        );
    }
    csv
}

impl Driver<ChuteState> {
    /// Opens `dir` for `spec` (and `from`, the settled chute to tilt): resumes the run
    /// there if it has the same settings, refuses one of other settings (naming each
    /// changed key), starts a new one otherwise (with `force`, always).
    ///
    /// # Errors
    /// [`RunError`] for a directory made by another command, a run of other settings, a
    /// settled state of another chute, or a file not read or written.
    pub fn open(
        spec: ChuteSpec,
        dir: &Path,
        from: Option<&Path>,
        force: bool,
    ) -> Result<ChuteRun, RunError> {
        if !force {
            made_by::expect(dir, Maker::Chute).map_err(RunError::OtherCommand)?;
            if dir.join("checkpoint.bin").exists() {
                let run = ChuteRun::resume(dir)?;
                let asked = from.map(|p| p.display().to_string());
                let mut changes = spec_changes(&run.spec, &spec);
                if run.from != asked {
                    changes.push(format!(
                        "from: {} → {}",
                        run.from.as_deref().unwrap_or("(none)"),
                        asked.as_deref().unwrap_or("(none)")
                    ));
                }
                if !changes.is_empty() {
                    return Err(RunError::Changed {
                        dir: dir.to_path_buf(),
                        changes,
                    });
                }
                return Ok(run);
            }
        }
        let geometry = spec.geometry()?;
        match from {
            None => Driver::create(dir, force, |session| {
                ChuteState::filled(spec, geometry, session)
            }),
            Some(settled) => {
                let source: ChuteState = read_checkpoint(&settled.join("settled.bin"))?;
                let (s, o) = (&spec, &source.spec);
                for (key, a, b) in [
                    ("height", s.height, o.height),
                    ("length", s.length, o.length),
                    ("width", s.width, o.width),
                    ("base_thickness", s.base_thickness, o.base_thickness),
                    ("diameter", s.diameter, o.diameter),
                    ("polydispersity", s.polydispersity, o.polydispersity),
                    ("density", s.density, o.density),
                    ("stiffness", s.stiffness, o.stiffness),
                    ("gravity", s.gravity, o.gravity),
                    ("seed", s.seed as f64, o.seed as f64),
                ] {
                    if a != b {
                        return Err(RunError::Scenario(invalid(
                            key,
                            a,
                            format!("must equal the settled chute's value {b} to start from it"),
                        )));
                    }
                }
                let from = settled.display().to_string();
                Driver::create(dir, force, |session| {
                    let mut state = ChuteState {
                        spec,
                        geometry,
                        from: Some(from),
                        snapshots: Vec::new(),
                        wall_seconds: 0.0,
                        first_step: source.simulation.step,
                        ..source
                    };
                    state.begin_flow()?;
                    state.write_spec(session.dir)?;
                    Ok(state)
                })
            }
        }
    }
}

impl Experiment for ChuteSpec {
    const FROM: Option<&'static str> = Some(
        "Tilt the settled layer of this earlier chute run directory (same layer and grains) \
         instead of filling a new one.",
    );

    const ESTIMATES_MEMORY: bool = false;

    fn run(
        self,
        options: &RunOptions<'_>,
        events: &mut dyn FnMut(Event<'_>),
    ) -> Result<Finished, RunError> {
        let dir = options.dir;
        let mut run = ChuteRun::open(self, dir, options.from, options.force)?;
        events(Event::Note(&format!(
            "chute: {} particles at θ = {}°, dt = {:.3e} s, outputs in {}",
            run.simulation.particles.len(),
            run.spec.angle_deg,
            run.simulation.dt,
            dir.display()
        )));
        events(Event::Particles(run.simulation.particles.len()));
        let mut warnings = Vec::new();
        loop {
            let stage = run.stage;
            run.advance_stage(dir, &mut |p| events(Event::Progress(p)))?;
            if stage == Stage::Settle
                && let Some(s) = run.settled.as_ref().filter(|s| !s.criterion_met)
            {
                let notice = format!(
                    "settling ended at its time limit settle_max_time = {} s with E_kin/E_springs \
                     = {:.3e}: the layer was still moving when it was tilted; raise \
                     settle_max_time or settle_damping",
                    run.spec.settle_max_time, s.kinetic_ratio
                );
                events(Event::Warning(&notice));
                warnings.push(notice);
            }
            if run.stage == Stage::Done {
                break;
            }
        }
        let results = run.results()?;
        if results.as_ref().is_some_and(|r| !r.steady) {
            warnings.push(
                "the flow is not steady in the averaging window (its halves differ in kinetic \
                 energy or flow rate): the angle may be above the steady range, or the run \
                 too short"
                    .into(),
            );
        }
        let summary = crate::driver::read_summary(dir)?;
        Ok(Finished {
            summary,
            report: report(&run, results.as_ref(), dir),
            warnings,
        })
    }
}

fn show(e: Option<Estimate>) -> String {
    e.map_or("n/a".into(), |e| format!("{:.4} ± {:.4}", e.mean, e.error))
}

/// The finished run in words: the flow, the bulk, the force balance, Bagnold's fit.
fn report(run: &ChuteRun, results: Option<&ChuteResults>, dir: &Path) -> String {
    let mut text = String::new();
    let _ = writeln!(
        text,
        "done: t = {:.3} s, {:.0} s wall, θ = {}°",
        run.simulation.time, run.wall_seconds, run.spec.angle_deg
    );
    if let Some(r) = results {
        let _ = writeln!(
            text,
            "  flow rate {} m²/s, surface at {} m, {}",
            show(r.flow_rate),
            show(r.surface_height),
            if r.steady { "steady" } else { "NOT steady" }
        );
        if let Some(b) = &r.bulk {
            let _ = writeln!(
                text,
                "  bulk ({} slabs): μ = {} (tan θ = {:.4}), I = {}, φ = {}; mid-depth p* = \
                 {:.3e}, Bo = {:.3}",
                b.slabs,
                show(b.friction),
                r.tan_theta,
                show(b.inertial_number),
                show(b.volume_fraction),
                b.softness_mid,
                b.bond_mid
            );
            let _ = writeln!(
                text,
                "  force balance: σ_zz / weight above = {}, worst slab {:.3}; worst |μ − tan θ| \
                 {:.2} errors",
                show(b.normal_stress_ratio),
                b.normal_stress_worst,
                b.friction_worst_sigma
            );
        }
        let _ = match &r.bagnold {
            Ok(f) => writeln!(
                text,
                "  Bagnold: v = {:.4} + {:.4e} (H^1.5 − (H − ζ)^1.5), H = {:.3e} m, rms residual \
                 {:.2} % of the largest velocity",
                f.offset,
                f.amplitude,
                f.depth,
                100.0 * f.relative_residual
            ),
            Err(e) => writeln!(text, "  Bagnold: no fit ({e})"),
        };
    }
    let _ = writeln!(text, "outputs in {}", dir.display());
    text
}

/// The name of a study point's directory from its controls:
/// `<law>-theta<θ>-h<h>-mu<μ_p>-s<seed>`.
pub fn point_name(spec: &ChuteSpec) -> String {
    format!(
        "{}-theta{}-h{}-mu{}-s{}",
        law_name(&spec.cohesion),
        spec.angle_deg,
        spec.height,
        spec.friction,
        spec.seed
    )
}

/// The spec and stage a `summary.json` (or its archived copy) records.
fn recorded(file: &Path) -> Option<(ChuteSpec, Stage)> {
    let text = std::fs::read_to_string(file).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    Some((
        serde_json::from_value(v.get("spec")?.clone()).ok()?,
        serde_json::from_value(v.get("stage")?.clone()).ok()?,
    ))
}

impl Studied for ChuteSpec {
    fn points(variant: &SweepSpec) -> Result<Vec<(String, Self)>, ScenarioError> {
        ChuteSpec::from_table(variant.base.clone())
            .map_err(|e| ScenarioError::Parse(format!("[base]: {e}")))?;
        let mut out: Vec<(String, ChuteSpec)> = Vec::new();
        for (k, t) in point_tables(&variant.base, &variant.grid, &variant.point)?
            .into_iter()
            .enumerate()
        {
            let spec = ChuteSpec::from_table(t)
                .and_then(|s| s.geometry().map(|_| s))
                .map_err(|e| ScenarioError::Parse(format!("study point {k}: {e}")))?;
            let name = point_name(&spec);
            if out.iter().any(|(n, _)| *n == name) {
                return Err(ScenarioError::Parse(format!(
                    "study point {k} ({name}) duplicates an earlier point"
                )));
            }
            out.push((name, spec));
        }
        Ok(out)
    }

    fn status(&self, name: &str, dir: &Path, archive: Option<&Path>) -> PointStatus<PathBuf> {
        let finished = |file: PathBuf| {
            recorded(&file)
                .is_some_and(|(s, stage)| s == *self && stage == Stage::Done)
                .then_some(file)
        };
        if let Some(file) = archive.and_then(|a| finished(a.join(format!("{name}.json")))) {
            return PointStatus::Finished(file);
        }
        if let Some(file) = finished(dir.join("summary.json")) {
            return PointStatus::Finished(file);
        }
        if !dir.join("checkpoint.bin").exists() {
            return PointStatus::Waiting;
        }
        match crate::io::lock::DirLock::try_acquire(dir) {
            Err(crate::io::lock::LockError::Busy(_)) => PointStatus::Running(0.0),
            _ => PointStatus::Stopped(0.0),
        }
    }

    fn archive(archive: &Path, name: &str, result: &Path) -> Result<(), String> {
        std::fs::create_dir_all(archive).map_err(|e| format!("{}: {e}", archive.display()))?;
        let text = std::fs::read(result).map_err(|e| format!("{}: {e}", result.display()))?;
        let file = archive.join(format!("{name}.json"));
        write_atomic(&file, &text).map_err(|e| format!("{}: {e}", file.display()))
    }

    fn store(db: &mut ResultsDb, study: &str, name: &str, result: &Path) -> Result<(), String> {
        let text =
            std::fs::read_to_string(result).map_err(|e| format!("{}: {e}", result.display()))?;
        let v: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| format!("{}: {e}", result.display()))?;
        let spec = v.get("spec").cloned().unwrap_or_default();
        db.insert_run(study, Self::NAME, name, &spec, &text)
            .map_err(|e| e.to_string())
    }

    fn report(
        study: &StudySpec,
        variant: &str,
        total: usize,
        finished: &[(String, PathBuf)],
    ) -> Result<Report, String> {
        let mut md = crate::setups::study::header(study, variant, finished.len(), total);
        let _ = writeln!(
            md,
            "| point | θ (°) | tan θ | μ (bulk) | I (bulk) | φ (bulk) | p* (mid) | Bo (mid) | steady |\n|---|---|---|---|---|---|---|---|---|"
        );
        for (name, file) in finished {
            let Ok(text) = std::fs::read_to_string(file) else {
                let _ = writeln!(md, "| {name} | unreadable: {} |", file.display());
                continue;
            };
            let Ok(s) = serde_json::from_str::<serde_json::Value>(&text) else {
                continue;
            };
            let r: Option<ChuteResults> = serde_json::from_value(s["results"].clone()).ok();
            let spec: Option<ChuteSpec> = serde_json::from_value(s["spec"].clone()).ok();
            let (Some(r), Some(spec)) = (r, spec) else {
                let _ = writeln!(md, "| {name} | no results |");
                continue;
            };
            let b = r.bulk.as_ref();
            let _ = writeln!(
                md,
                "| {name} | {} | {:.4} | {} | {} | {} | {} | {} | {} |",
                spec.angle_deg,
                r.tan_theta,
                show(b.and_then(|b| b.friction)),
                show(b.and_then(|b| b.inertial_number)),
                show(b.and_then(|b| b.volume_fraction)),
                b.map_or("n/a".into(), |b| format!("{:.3e}", b.softness_mid)),
                b.map_or("n/a".into(), |b| format!("{:.3}", b.bond_mid)),
                if r.steady { "yes" } else { "no" }
            );
        }
        Ok(Report {
            markdown: md,
            figures: Vec::new(),
        })
    }

    fn outcome(name: &str, result: &Path) -> String {
        let bulk = std::fs::read_to_string(result)
            .ok()
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
            .and_then(|s| serde_json::from_value::<ChuteResults>(s["results"].clone()).ok())
            .and_then(|r| r.bulk);
        match bulk {
            Some(b) => format!(
                "{name}: μ = {}, I = {}, φ = {}",
                show(b.friction),
                show(b.inertial_number),
                show(b.volume_fraction)
            ),
            None => format!("{name}: finished (no bulk results)"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bagnold's profile is recovered exactly from points on it, and a straight profile
    /// leaves a residual.
    #[test]
    fn bagnold_fit_recovers_its_own_profile() {
        let depth = 0.04;
        let exact = BagnoldFit {
            depth,
            offset: 0.05,
            amplitude: 120.0,
            rms_residual: 0.0,
            relative_residual: 0.0,
        };
        let points: Vec<(f64, f64)> = (1..20)
            .map(|k| {
                let z = depth * k as f64 / 20.0;
                (z, exact.at(z))
            })
            .collect();
        let fit = fit_bagnold(&points, depth).expect("a fit");
        assert!((fit.offset - 0.05).abs() < 1e-12, "{fit:?}");
        assert!((fit.amplitude - 120.0).abs() < 1e-9, "{fit:?}");
        assert!(fit.rms_residual < 1e-12);
        let line: Vec<(f64, f64)> = (1..20).map(|k| (k as f64 * 0.002, k as f64)).collect();
        assert!(fit_bagnold(&line, depth).expect("a fit").relative_residual > 1e-3);
        assert!(fit_bagnold(&points[..2], depth).is_err());
        assert!(fit_bagnold(&points, 0.0).is_err());
    }

    /// The block errors: mean and standard error of the finite values.
    #[test]
    fn block_errors_skip_missing_values() {
        let (m, e) = over_blocks([1.0, 2.0, 3.0, f64::NAN].into_iter());
        assert_eq!(m, 2.0);
        assert!((e - (1.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert!(over_blocks([1.0].into_iter()).1.is_nan());
    }

    /// Bad values name their key and range; the count of particles follows the layer.
    #[test]
    fn the_spec_checks_name_the_key() {
        let g = ChuteSpec::default().geometry().expect("the defaults");
        // 10 × 10 × 21 d_p at φ = 0.6 of spheres of mean diameter d_p (w = 1.5).
        assert!((2000..3000).contains(&g.count), "{}", g.count);
        let e = ChuteSpec {
            length: 2.0,
            ..ChuteSpec::default()
        }
        .geometry()
        .expect_err("too short")
        .to_string();
        assert!(
            e.contains("`length`") && e.contains("three neighbour cells"),
            "{e}"
        );
        let e = ChuteSpec {
            average_from: 7.0,
            ..ChuteSpec::default()
        }
        .geometry()
        .expect_err("window")
        .to_string();
        assert!(e.contains("`average_from`"), "{e}");
        let e = ChuteSpec {
            angle_deg: 70.0,
            ..ChuteSpec::default()
        }
        .geometry()
        .expect_err("steep")
        .to_string();
        assert!(e.contains("`angle_deg`"), "{e}");
    }
}
