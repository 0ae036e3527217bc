//! The split-bottom ring shear cell (docs/model.md §10): an angular-periodic wedge of an
//! annulus between a fixed inner and a rotating outer cylinder, whose bottom is split at
//! `R_s` (inside fixed, outside rotating with the outer cylinder), filled with grains to a
//! free surface under gravity.
//!
//! A run passes through stages, each ending in a checkpoint:
//! 1. **fill** — `N` spheres are placed at random without overlap in a mould slightly
//!    larger than the cell (smooth cylinders at `R_i − d_p/2`, `R_o + d_p/2`, a smooth floor
//!    at `z = −d_p/2`), loosely, up to about twice the filling height;
//! 2. **settle** — they fall under gravity with the damping multiplied by
//!    `settle_damping` until the translational kinetic energy is below
//!    `settle_kinetic_ratio` times the energy of the contact springs (the repulsive elastic
//!    energy, without the negative adhesive potential of a cohesive law, so that the test
//!    means "at rest" under any law); then the layer of particles touching each mould wall is frozen into
//!    the rough walls: inner cylinder and inner bottom (`r < R_s`) fixed, outer cylinder and
//!    outer bottom rotating. The smooth mould walls stay as backstops. The state is saved as
//!    `settled.bin`, from which any number of shear runs can start (`from_settled`);
//! 3. **shear** — the rotating parts turn at `Ω`; the wall torques, kinetic energy, contacts
//!    and surface height are recorded, and the azimuthal velocity profile is averaged in
//!    three horizontal slabs over the averaging window and fitted with an error function.

use super::split_bottom_fields::{self as cell_fields, FieldSettings};
use crate::Simulation;
use crate::analysis::{Estimate, block_average};
use crate::band::{AzimuthalProfile, ErfFit, erf_profile, surface_height};
use crate::cg::{CgSums, ContactRecord, ContactRecords, KernelShape};
use crate::contact::{
    Adhesion, ContactLaw, ContactTable, Damping, LawKind, LawSpec, NormalLaw, Resistance,
};
use crate::domain::Domain;
use crate::generate::{Rng, polydisperse_radii};
use crate::io::atomic::write_atomic;
use crate::io::lock::DirLock;
use crate::io::made_by::{self, Maker};
use crate::io::vtk;
use crate::memory::{self, Bytes};
use crate::neighbor::min_wedge_angle;
use crate::particles::{Motion, Particles, Sphere};
use crate::plot::{Labels, Markers, Series, plot_svg};
use crate::run::{RunError, io_err, lock, read_checkpoint, write_checkpoint};
use crate::scenario::{ScenarioError, invalid, law_error};
use crate::stage::{EndCondition, Verdict};
use crate::timestep::shortest_contact_time;
use crate::walls::{Wall, WallShape};
use glam::{DMat3, DVec3};
use rand::{RngExt, SeedableRng};
use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// The adhesive law between all particles (and at the walls).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "law", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Cohesion {
    /// Dry, non-cohesive.
    #[default]
    Dry,
    /// Willett liquid bridges (docs/model.md §2.5).
    Willett {
        /// Surface tension `γ_s` (N/m).
        surface_tension: f64,
        /// Bridge volume `V_b` (m³).
        volume: f64,
        /// Contact angle `θ` (degrees).
        #[serde(default = "default_contact_angle")]
        contact_angle_deg: f64,
    },
    /// Linear irreversible adhesion (docs/model.md §2.6).
    Linear {
        /// Maximum adhesive force `f_a^max` (N).
        max_force: f64,
        /// Stiffness `k_c` of the separation branch (N/m).
        stiffness: f64,
    },
}

fn default_contact_angle() -> f64 {
    20.0
}

/// How the time step is chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TimeStepRule {
    /// The engine's default: 1/50 of the shortest contact time (lightest pair).
    #[default]
    Shortest,
    /// The source papers' code: 1/50 of the contact time of the mean pair (diameter `d_p`).
    MeanPair,
}

/// Everything a split-bottom run needs, SI units; the defaults are the cell of Shi et al.
/// 2020 and Roy et al. 2016 (docs/model.md §10) with a faster rotation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SplitBottomSpec {
    /// Inner cylinder radius `R_i` (m).
    pub inner_radius: f64,
    /// Outer cylinder radius `R_o` (m).
    pub outer_radius: f64,
    /// Radius `R_s` of the split in the bottom (m).
    pub split_radius: f64,
    /// Filling height `H` aimed at after settling (m).
    pub height: f64,
    /// Wedge angle `Φ` (degrees), in `(0, 180]`.
    pub wedge_deg: f64,
    /// Factor on the cell's lengths (`R_i`, `R_o`, `R_s`, `H`), not on the particles.
    pub scale: f64,
    /// Mean particle diameter `d_p` (m).
    pub diameter: f64,
    /// Polydispersity `w = d_max / d_min` (uniform radii).
    pub w: f64,
    /// Particle density `ρ_p` (kg/m³).
    pub density: f64,
    /// Normal stiffness `k_n` (N/m).
    pub stiffness: f64,
    /// Normal damping `γ_n` (kg/s), fixed.
    pub damping: f64,
    /// Sliding friction coefficient `μ_p`.
    pub friction: f64,
    /// `k_t / k_n`.
    pub stiffness_ratio: f64,
    /// `γ_t / γ_n`.
    pub damping_ratio: f64,
    /// The adhesive law.
    pub cohesion: Cohesion,
    /// Angular velocity `Ω` of the outer parts (rad/s).
    pub omega: f64,
    /// Gravitational acceleration `g` (m/s²), along `−z`.
    pub gravity: f64,
    /// Time-step rule.
    pub time_step: TimeStepRule,
    /// Factor on every damping coefficient while settling.
    pub settle_damping: f64,
    /// Settling ends when the translational kinetic energy is below this fraction of the
    /// energy of the contact springs (the repulsive elastic energy, adhesion left out).
    pub settle_kinetic_ratio: f64,
    /// Settling ends at this time (s) even if the kinetic criterion is not met (reported).
    pub settle_max_time: f64,
    /// Shear duration (s).
    pub duration: f64,
    /// Start of the averaging window, in seconds after the start of shear.
    pub average_from: f64,
    /// Time-series rows over the shear stage.
    pub rows: u64,
    /// Snapshots over the shear stage (0 for none).
    pub snapshots: u64,
    /// Checkpoints over the shear stage (besides the final one).
    pub checkpoints: u64,
    /// Thickness of the frozen wall shell in units of `d_p`: besides the layer touching the
    /// mould, the particles whose centres lie within this distance inside the cell's walls
    /// (`R_i`, `R_o` and the floor `z = 0`) become wall particles; 0: that layer alone.
    /// The source papers' public driver freezes 2.2 radii, 1.1 here.
    pub wall_shell: f64,
    /// Verlet skin in units of `d_p`.
    pub skin: f64,
    /// Random seed of the filling.
    pub seed: u64,
    /// Coarse-graining kernel of the fields (docs/coarse-graining.md).
    pub cg_kernel: KernelShape,
    /// Kernel width `w` in units of `d_p`.
    pub cg_width: f64,
    /// Spacing of the `(r, z)` grid of the fields in units of `d_p`.
    pub cg_spacing: f64,
    /// Time between the samples of the fields in the averaging window (s); 0 for no
    /// fields.
    pub cg_every: f64,
}

impl Default for SplitBottomSpec {
    fn default() -> Self {
        SplitBottomSpec {
            inner_radius: 0.0147,
            outer_radius: 0.110,
            split_radius: 0.085,
            height: 0.040,
            wedge_deg: 30.0,
            scale: 1.0,
            diameter: 2.2e-3,
            w: 2.0,
            density: 2000.0,
            stiffness: 100.0,
            damping: 0.002,
            friction: 0.01,
            stiffness_ratio: 2.0 / 7.0,
            damping_ratio: 2.0 / 7.0,
            cohesion: Cohesion::Dry,
            omega: 0.5,
            gravity: 9.81,
            time_step: TimeStepRule::Shortest,
            settle_damping: 10.0,
            settle_kinetic_ratio: 1e-4,
            settle_max_time: 2.0,
            duration: 4.0,
            average_from: 2.0,
            rows: 200,
            snapshots: 4,
            checkpoints: 8,
            wall_shell: 0.0,
            skin: 0.1,
            seed: 1,
            cg_kernel: KernelShape::Lucy,
            cg_width: 1.0,
            cg_spacing: 0.5,
            cg_every: 0.1,
        }
    }
}

/// Wall parts of the cell, in part-number order.
pub const PARTS: [&str; 5] = [
    "inner-wall",
    "inner-bottom",
    "outer-bottom",
    "outer-wall",
    "backstops",
];
const INNER_WALL: u16 = 0;
const INNER_BOTTOM: u16 = 1;
const OUTER_BOTTOM: u16 = 2;
const OUTER_WALL: u16 = 3;
const BACKSTOPS: u16 = 4;

/// Records a failure in the run directory's `summary.json`: the last summary written (or a
/// new one for `spec`) with `"status": "failed"`, the error and where it happened
/// (`failed_at`).
fn record_failure(
    dir: &Path,
    spec: &SplitBottomSpec,
    failed_at: serde_json::Value,
    error: &RunError,
) -> Result<(), RunError> {
    let path = dir.join("summary.json");
    let mut summary = std::fs::read_to_string(&path)
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .filter(|v| v.is_object())
        .unwrap_or_else(|| {
            serde_json::json!({
                "program": "rheodem split-bottom",
                "version": crate::VERSION,
                "commit": crate::COMMIT,
                "seed": spec.seed,
                "spec": spec,
            })
        });
    summary["status"] = "failed".into();
    summary["error"] = error.to_string().into();
    summary["failed_at"] = failed_at;
    let text = serde_json::to_string_pretty(&summary).unwrap_or_default();
    write_atomic(&path, text.as_bytes()).map_err(io_err("write", &path))
}

/// Marks `dir` as a split-bottom run directory ([`made_by`]).
fn mark_split_bottom(dir: &Path) -> Result<(), RunError> {
    made_by::mark(dir, Maker::SplitBottom).map_err(io_err("write", &dir.join(made_by::FILE)))
}

/// Largest number of particles a cell may hold (the limit of scenario files).
const MAX_PARTICLES: usize = 50_000_000;

/// Volume fraction assumed for the settled packing when counting the particles to insert.
const SETTLED_FRACTION: f64 = 0.62;
/// Volume fraction of the loose random filling.
const FILL_FRACTION: f64 = 0.25;
/// Names of the velocity-profile slabs.
pub const SLABS: [&str; 3] = ["bottom", "middle", "surface"];

/// The cell's resolved geometry (m, rad).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Geometry {
    /// `R_i` after scaling.
    pub inner_radius: f64,
    /// `R_o` after scaling.
    pub outer_radius: f64,
    /// `R_s` after scaling.
    pub split_radius: f64,
    /// `H` after scaling.
    pub height: f64,
    /// Wedge angle `Φ` (rad).
    pub angle: f64,
    /// Radius of the inner mould cylinder (backstop), `R_i − d_p/2`.
    pub mould_inner: f64,
    /// Radius of the outer mould cylinder (backstop), `R_o + d_p/2`.
    pub mould_outer: f64,
    /// Height of the mould floor (backstop), `−d_p/2`.
    pub floor: f64,
    /// Smallest and largest particle radius.
    pub radii: [f64; 2],
    /// Particles inserted (free and future wall particles).
    pub count: usize,
    /// Top of the loose filling.
    pub fill_top: f64,
    /// Rupture distance of the adhesive law (0 if none).
    pub range: f64,
}

/// The stage a run is in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Stage {
    /// Falling and settling under gravity.
    Settle,
    /// Rotating.
    Shear,
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
    /// Rotation angle of the outer parts since the start of shear (rad).
    pub angle: f64,
    /// Kinetic energy of the free particles, translational + rotational (J).
    pub kinetic_energy: f64,
    /// Its translational part (J).
    #[serde(default)]
    pub kinetic_translational: f64,
    /// Elastic energy of the contacts (J).
    pub elastic_energy: f64,
    /// Contacts with overlap.
    pub contacts: u64,
    /// Coordination number `2 N_c / N` over free particles.
    pub coordination: f64,
    /// Attracting pairs apart (open bridges) per free particle.
    pub bridges_per_particle: f64,
    /// Height of the free surface (m), see `band::surface_height`.
    pub surface_height: f64,
    /// Torque about `z` on each part from the grains, scaled to the full ring (N m).
    pub torque: [f64; 5],
    /// The source papers' net torque (Roy et al. 2016, Eq. 24), full ring (N m):
    /// torque on the fixed parts minus torque on the rotating parts.
    pub net_torque: f64,
}

/// What settling reached.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SettleReport {
    /// Time at the end of settling (s).
    pub time: f64,
    /// Translational `E_kin / E_springs` at the end (`E_springs` the energy of the contact
    /// springs, without the adhesive potential).
    pub kinetic_ratio: f64,
    /// Whether the kinetic criterion was met (rather than the time limit).
    pub criterion_met: bool,
    /// Free particles left.
    pub free: usize,
    /// Wall particles per part.
    pub wall_particles: [usize; 4],
    /// Height of the free surface (m).
    pub surface_height: f64,
}

impl SettleReport {
    /// A warning when settling ended on its time limit rather than its criterion (`None`
    /// when the criterion was met), naming the keys that control it.
    pub fn limit_notice(&self, spec: &SplitBottomSpec) -> Option<String> {
        (!self.criterion_met).then(|| {
            format!(
                "settling ended at its time limit settle_max_time = {} s without reaching \
                 settle_kinetic_ratio = {:e} (E_kin/E_springs = {:.3e} at t = {:.3} s): the \
                 bed is still moving; raise settle_max_time or settle_damping",
                spec.settle_max_time, spec.settle_kinetic_ratio, self.kinetic_ratio, self.time
            )
        })
    }
}

/// Steady-state results of the shear stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShearResults {
    /// Averaging window (s after the start of shear).
    pub window: [f64; 2],
    /// Torque on each part, full ring (N m).
    pub torque: Vec<Option<Estimate>>,
    /// Net torque of Roy et al. 2016 Eq. 24, full ring (N m).
    pub net_torque: Option<Estimate>,
    /// The net torque in units of `f_g d_p`.
    pub net_torque_scaled: Option<f64>,
    /// Sum of the torques on all parts (≈ 0 in steady state), full ring (N m).
    pub balance: Option<Estimate>,
    /// Error-function fit of `v_φ/(Ω r)` per slab (bottom, middle, surface).
    pub band: Vec<SlabFit>,
}

/// The band fit in one slab.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SlabFit {
    /// Slab name.
    pub slab: String,
    /// Slab heights (m).
    pub z: [f64; 2],
    /// The fit, or why it failed.
    pub fit: Result<ErfFit, String>,
}

/// Dimensionless groups and scales of the run (docs/model.md §10.3).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Groups {
    /// Weight of a mean particle `f_g = ρ_p (π/6) d_p³ g` (N).
    pub weight: f64,
    /// Surface tension `γ* = γ_s d_p / f_g` (0 when dry).
    pub surface_tension_scaled: f64,
    /// Rupture distance `S_c* = S_c / d_p`.
    pub rupture_scaled: f64,
    /// Speed of the outer wall `Ω R_o` (m/s).
    pub wall_speed: f64,
    /// Estimated pressure at mid-height `ρ_p φ g H/2` (Pa).
    pub pressure_estimate: f64,
    /// Estimated inertial number in the band, `(Ω R_s / W) d_p / sqrt(P/ρ_p)`, `W = 5 d_p`.
    pub inertial_estimate: f64,
    /// Estimated softness `P d_p / k_n`.
    pub softness_estimate: f64,
    /// Time step (s) and the rule used.
    pub dt: f64,
}

/// A split-bottom run: serialised whole as its checkpoint.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SplitBottomRun {
    /// The spec as run.
    pub spec: SplitBottomSpec,
    /// Resolved geometry.
    pub geometry: Geometry,
    /// Current stage.
    pub stage: Stage,
    /// The simulation state.
    pub simulation: Simulation,
    /// Time-series rows so far.
    pub rows: Vec<Row>,
    /// Velocity profiles of the averaging window, per slab.
    pub profiles: Vec<AzimuthalProfile>,
    /// End of settling, once reached.
    pub settled: Option<SettleReport>,
    /// Time and step at the start of shear.
    pub shear_start: Option<(f64, u64)>,
    /// Snapshots so far: `(time, file name)`.
    pub snapshots: Vec<(f64, String)>,
    /// Wall-clock seconds spent stepping.
    pub wall_seconds: f64,
    /// Where the settled state came from, if this run started from one.
    pub from: Option<String>,
    /// The step this run started at (non-zero for a run from a settled state); the
    /// throughput counts the steps since.
    #[serde(default)]
    pub first_step: u64,
    /// Kernel sums of the coarse-grained fields over the averaging window so far (none
    /// before shear, or with `cg_every = 0`).
    #[serde(default)]
    pub fields: Option<CgSums>,
    #[serde(skip)]
    lock: Option<Arc<DirLock>>,
}

fn positive(key: &str, v: f64) -> Result<f64, ScenarioError> {
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(invalid(key, v, "must be a positive number"))
    }
}

fn non_negative(key: &str, v: f64) -> Result<f64, ScenarioError> {
    if v >= 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(invalid(key, v, "must be zero or positive"))
    }
}

impl SplitBottomSpec {
    /// Parses a spec from TOML (keys as the fields; omitted keys take the defaults).
    pub fn from_toml(text: &str) -> Result<SplitBottomSpec, ScenarioError> {
        let de =
            toml::Deserializer::parse(text).map_err(|e| ScenarioError::Parse(e.to_string()))?;
        serde_path_to_error::deserialize(de).map_err(|e| {
            ScenarioError::Parse(format!(
                "split-bottom spec, key `{}`: {}",
                e.path(),
                e.inner()
            ))
        })
    }

    /// A spec from a TOML table (a study point); the error names the offending key's path
    /// in the table.
    pub fn from_table(table: toml::Table) -> Result<SplitBottomSpec, ScenarioError> {
        serde_path_to_error::deserialize(toml::Value::Table(table))
            .map_err(|e| ScenarioError::Parse(format!("key `{}`: {}", e.path(), e.inner())))
    }

    /// The spec as TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }

    /// The contact law of every pair (particles and walls).
    pub fn law(&self) -> ContactLaw {
        let damping = Damping {
            fixed: self.damping,
            ..Damping::NONE
        };
        let adhesion = match self.cohesion {
            Cohesion::Dry => Adhesion::None,
            Cohesion::Willett {
                surface_tension,
                volume,
                contact_angle_deg,
            } => Adhesion::LiquidBridge(crate::contact::LiquidBridge {
                surface_tension,
                contact_angle: contact_angle_deg.to_radians(),
                volume,
            }),
            Cohesion::Linear {
                max_force,
                stiffness,
            } => Adhesion::LinearIrreversible(crate::contact::LinearIrreversible {
                max_force,
                stiffness,
            }),
        };
        ContactLaw {
            normal: NormalLaw {
                stiffness: self.stiffness,
                damping,
            },
            tangential: Resistance {
                stiffness: self.stiffness_ratio * self.stiffness,
                damping: damping.scaled(self.damping_ratio),
                mu_static: self.friction,
                mu_dynamic: self.friction,
            },
            rolling: Resistance::NONE,
            torsion: Resistance::NONE,
            adhesion,
        }
    }

    /// The adhesive law by its registered name with its parameters, as the engine's
    /// registry checks and builds it.
    pub fn law_spec(&self) -> LawSpec {
        match self.cohesion {
            Cohesion::Dry => LawSpec::default(),
            Cohesion::Willett {
                surface_tension,
                volume,
                contact_angle_deg,
            } => LawSpec::new(
                LawKind::LiquidBridge,
                [
                    ("surface_tension", surface_tension),
                    ("contact_angle_deg", contact_angle_deg),
                    ("volume", volume),
                ],
            ),
            Cohesion::Linear {
                max_force,
                stiffness,
            } => LawSpec::new(
                LawKind::LinearIrreversible,
                [("max_force", max_force), ("stiffness", stiffness)],
            ),
        }
    }

    /// Checks the adhesive law's values, and that its interaction range (the rupture
    /// distance `S_c`) stays below the mean diameter `d` (m): a longer range lets a bridge
    /// reach past a particle's neighbours, outside the laws' validity (docs/model.md §2.5).
    fn check_cohesion(&self, d: f64) -> Result<(), ScenarioError> {
        let range_key = match self.cohesion {
            Cohesion::Dry => return Ok(()),
            Cohesion::Willett { volume, .. } => ("cohesion.volume", volume),
            Cohesion::Linear { stiffness, .. } => ("cohesion.stiffness", stiffness),
        };
        // The values against the bounds the law declares in the registry.
        self.law_spec()
            .build()
            .map_err(|e| law_error("cohesion", e))?;
        let range = self.law().range();
        if !(range.is_finite() && range <= d) {
            return Err(invalid(
                range_key.0,
                range_key.1,
                format!(
                    "gives an interaction range S_c = {range:.3e} m beyond the mean diameter \
                     d_p = {d:.3e} m (the law is meant for bridges shorter than a particle)"
                ),
            ));
        }
        Ok(())
    }

    /// Checks every value and resolves the geometry; errors name the key and the range.
    pub fn geometry(&self) -> Result<Geometry, ScenarioError> {
        let scale = positive("scale", self.scale)?;
        let d = positive("diameter", self.diameter)?;
        if !(self.w >= 1.0 && self.w.is_finite()) {
            return Err(invalid("w", self.w, "must be at least 1 (d_max / d_min)"));
        }
        positive("density", self.density)?;
        positive("stiffness", self.stiffness)?;
        non_negative("damping", self.damping)?;
        non_negative("friction", self.friction)?;
        non_negative("stiffness_ratio", self.stiffness_ratio)?;
        non_negative("damping_ratio", self.damping_ratio)?;
        non_negative("omega", self.omega)?;
        non_negative("gravity", self.gravity)?;
        positive("settle_damping", self.settle_damping)?;
        positive("skin", self.skin)?;
        if !(self.wall_shell.is_finite() && (0.0..=5.0).contains(&self.wall_shell)) {
            return Err(invalid(
                "wall_shell",
                self.wall_shell,
                "must lie in [0, 5] particle diameters",
            ));
        }
        positive("cg_width", self.cg_width)?;
        positive("cg_spacing", self.cg_spacing)?;
        non_negative("cg_every", self.cg_every)?;
        positive("settle_kinetic_ratio", self.settle_kinetic_ratio)?;
        positive("settle_max_time", self.settle_max_time)?;
        positive("duration", self.duration)?;
        self.check_cohesion(d)?;
        if !(self.average_from >= 0.0 && self.average_from < self.duration) {
            return Err(invalid(
                "average_from",
                self.average_from,
                format!("must be in [0, duration = {})", self.duration),
            ));
        }
        if self.rows < 2 {
            return Err(invalid("rows", self.rows, "must be at least 2"));
        }
        let inner = positive("inner_radius", self.inner_radius)? * scale;
        let outer = positive("outer_radius", self.outer_radius)? * scale;
        let split = positive("split_radius", self.split_radius)? * scale;
        let height = positive("height", self.height)? * scale;
        if split <= inner {
            return Err(invalid(
                "split_radius",
                self.split_radius,
                format!("must exceed inner_radius = {}", self.inner_radius),
            ));
        }
        if outer <= split {
            return Err(invalid(
                "outer_radius",
                self.outer_radius,
                format!("must exceed split_radius = {}", self.split_radius),
            ));
        }
        if !(self.wedge_deg > 0.0 && self.wedge_deg <= 180.0) {
            return Err(invalid("wedge_deg", self.wedge_deg, "must be in (0, 180]"));
        }
        let (r_min, r_max) = (d / (1.0 + self.w), self.w * d / (1.0 + self.w));
        if outer - split < 2.0 * d || split - inner < 2.0 * d || height < 2.0 * d {
            return Err(invalid(
                "scale",
                self.scale,
                format!(
                    "leaves the cell (R_s − R_i = {:.3e} m, R_o − R_s = {:.3e} m, H = {:.3e} m) \
                     narrower than two particle diameters ({:.3e} m): the scale must be at \
                     least {:.4}",
                    split - inner,
                    outer - split,
                    height,
                    2.0 * d,
                    scale * 2.0 * d / (split - inner).min(outer - split).min(height)
                ),
            ));
        }
        let range = self.law().range();
        let mould_inner = inner - 0.5 * d;
        let mould_outer = outer + 0.5 * d;
        let floor = -0.5 * d;
        let angle = self.wedge_deg.to_radians();
        // No particle may reach its own image across the wedge (docs/model.md §4.6).
        let reach = 2.0 * r_max + range;
        let closest = mould_inner + r_min;
        match min_wedge_angle(closest, reach) {
            Some(min) if angle >= min => {}
            min => {
                return Err(invalid(
                    "wedge_deg",
                    self.wedge_deg,
                    match min {
                        Some(m) => format!(
                            "is too narrow at the inner wall (radius {closest:.4e} m) for \
                             particles of diameter up to {:.4e} m with interaction range \
                             {range:.3e} m: it must be at least {:.4}°",
                            2.0 * r_max,
                            m.to_degrees()
                        ),
                        None => "no wedge fits: the inner radius is too small".into(),
                    },
                ));
            }
        }
        let area = 0.5 * angle * (mould_outer.powi(2) - mould_inner.powi(2));
        let mean_volume = 4.0 / 3.0 * PI * mean_radius_cubed(r_min, r_max);
        let count = (SETTLED_FRACTION * area * (height + 0.5 * d) / mean_volume).round();
        if count > MAX_PARTICLES as f64 {
            return Err(invalid(
                "scale",
                self.scale,
                format!(
                    "gives {count:.3e} particles, more than the {MAX_PARTICLES} a cell may hold: \
                     the scale must be at most about {:.3}",
                    self.scale * (MAX_PARTICLES as f64 / count).cbrt()
                ),
            ));
        }
        let count = count as usize;
        let fill_top = floor + count as f64 * mean_volume / (FILL_FRACTION * area) + 2.0 * r_max;
        Ok(Geometry {
            inner_radius: inner,
            outer_radius: outer,
            split_radius: split,
            height,
            angle,
            mould_inner,
            mould_outer,
            floor,
            radii: [r_min, r_max],
            count,
            fill_top,
            range,
        })
    }

    /// The particle count and the estimated peak memory (bytes) of the cell on `threads`
    /// worker threads, known before anything is allocated; refused (naming `scale`) when
    /// the estimate exceeds `limit` bytes, with the largest scale that fits.
    pub fn memory_estimate(
        &self,
        threads: usize,
        limit: Option<u64>,
    ) -> Result<(usize, u64), ScenarioError> {
        let count = self.geometry()?.count;
        let bytes = memory::estimate(count as u64, threads);
        match limit {
            Some(limit) if bytes > limit => {
                let fits = memory::particles_within(limit, threads) as f64;
                Err(invalid(
                    "scale",
                    self.scale,
                    format!(
                        "gives {count} particles, an estimated {} on {threads} threads, more \
                         than the memory limit of {} (the machine's physical memory unless \
                         --max-memory says otherwise): the scale must be at most about {:.3}",
                        Bytes(bytes),
                        Bytes(limit),
                        self.scale * (fits / count as f64).cbrt()
                    ),
                ))
            }
            _ => Ok((count, bytes)),
        }
    }

    /// Dimensionless groups for the time step `dt` (s).
    pub fn groups(&self, g: &Geometry, dt: f64) -> Groups {
        let weight = self.density * PI / 6.0 * self.diameter.powi(3) * self.gravity;
        let surface_tension = match self.cohesion {
            Cohesion::Willett {
                surface_tension, ..
            } => surface_tension,
            _ => 0.0,
        };
        let pressure = self.density * SETTLED_FRACTION * self.gravity * 0.5 * g.height;
        let rate = self.omega * g.split_radius / (5.0 * self.diameter);
        let speed = (pressure / self.density).sqrt();
        Groups {
            weight,
            surface_tension_scaled: if weight > 0.0 {
                surface_tension * self.diameter / weight
            } else {
                0.0
            },
            rupture_scaled: g.range / self.diameter,
            wall_speed: self.omega * g.outer_radius,
            pressure_estimate: pressure,
            inertial_estimate: if speed > 0.0 {
                rate * self.diameter / speed
            } else {
                f64::INFINITY
            },
            softness_estimate: pressure * self.diameter / self.stiffness,
            dt,
        }
    }
}

fn mean_radius_cubed(r1: f64, r2: f64) -> f64 {
    if r2 > r1 {
        (r2.powi(4) - r1.powi(4)) / (4.0 * (r2 - r1))
    } else {
        r1.powi(3)
    }
}

/// Places spheres of `radii` (largest first) at random in the mould, without overlap with
/// each other (through the wedge's images too) or the mould walls.
fn fill(rng: &mut Rng, radii: &[f64], g: &Geometry) -> Result<Vec<DVec3>, ScenarioError> {
    let cell = 2.0 * g.radii[1];
    let key = |r: DVec3| -> [i64; 3] { std::array::from_fn(|a| (r[a] / cell).floor() as i64) };
    let mut grid: FxHashMap<[i64; 3], Vec<(DVec3, f64)>> = FxHashMap::default();
    let images = [
        DMat3::IDENTITY,
        DMat3::from_rotation_z(g.angle),
        DMat3::from_rotation_z(-g.angle),
    ];
    let mut placed = Vec::with_capacity(radii.len());
    for (k, &a) in radii.iter().enumerate() {
        let (lo, hi) = ((g.mould_inner + a).powi(2), (g.mould_outer - a).powi(2));
        let mut found = None;
        for _ in 0..10_000 {
            let rho = rng.random_range(lo..hi).sqrt();
            let phi = rng.random_range(0.0..g.angle);
            let z = rng.random_range(g.floor + a..g.fill_top - a);
            let c = DVec3::new(rho * phi.cos(), rho * phi.sin(), z);
            let free = images.iter().all(|m| {
                let q = *m * c;
                let base = key(q);
                (-1..=1).all(|dx| {
                    (-1..=1).all(|dy| {
                        (-1..=1).all(|dz| {
                            grid.get(&[base[0] + dx, base[1] + dy, base[2] + dz])
                                .is_none_or(|v| v.iter().all(|(p, b)| (*p - q).length() >= a + b))
                        })
                    })
                })
            });
            if free {
                found = Some(c);
                break;
            }
        }
        let Some(c) = found else {
            return Err(invalid(
                "height",
                g.height,
                format!(
                    "the loose filling could not place particle {k} of {} without overlap",
                    radii.len()
                ),
            ));
        };
        grid.entry(key(c)).or_default().push((c, a));
        placed.push(c);
    }
    Ok(placed)
}

/// Cylindrical radius of `r` about `z` (m).
fn rho(r: DVec3) -> f64 {
    r.x.hypot(r.y)
}

impl SplitBottomRun {
    /// Builds the filled cell (stage settle) in the new run directory `dir` (refusing one
    /// that holds a run unless `force`), writes the spec and the first checkpoint.
    pub fn start(
        spec: SplitBottomSpec,
        dir: &Path,
        force: bool,
    ) -> Result<SplitBottomRun, RunError> {
        let geometry = spec.geometry()?;
        let existed = dir.exists();
        let lock = lock(dir)?;
        if dir.join("checkpoint.bin").exists() && !force {
            return Err(RunError::Exists(dir.to_path_buf()));
        }
        mark_split_bottom(dir)?;
        match SplitBottomRun::fill_cell(spec.clone(), geometry, lock, dir) {
            Err(e) if !existed => {
                let _ = std::fs::remove_dir_all(dir);
                Err(e)
            }
            Err(e) => {
                // The error itself matters more than a summary that cannot be written.
                let _ = record_failure(dir, &spec, "fill".into(), &e);
                Err(e)
            }
            other => other,
        }
    }

    /// The filled cell of [`SplitBottomRun::start`] in the locked directory `dir`.
    fn fill_cell(
        spec: SplitBottomSpec,
        geometry: Geometry,
        lock: Arc<DirLock>,
        dir: &Path,
    ) -> Result<SplitBottomRun, RunError> {
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
        let law = spec.law();
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
        let mut run = SplitBottomRun {
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
            lock: Some(lock),
        };
        run.write_spec(dir)?;
        run.checkpoint(dir)?;
        Ok(run)
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
        let source: SplitBottomRun = read_checkpoint(&settled_dir.join("settled.bin"))?;
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
        let lock = lock(dir)?;
        if dir.join("checkpoint.bin").exists() && !force {
            return Err(RunError::Exists(dir.to_path_buf()));
        }
        mark_split_bottom(dir)?;
        let mut run = SplitBottomRun {
            spec,
            geometry,
            lock: Some(lock),
            from: Some(settled_dir.display().to_string()),
            snapshots: Vec::new(),
            wall_seconds: 0.0,
            first_step: source.simulation.step,
            fields: None,
            ..source
        };
        let begun = run
            .begin_shear()
            .and_then(|()| run.write_spec(dir))
            .and_then(|()| run.checkpoint(dir));
        if let Err(e) = begun {
            let _ = run.write_failure(dir, &e);
            return Err(e);
        }
        Ok(run)
    }

    /// Loads the checkpoint of the run directory `dir` (locking it).
    pub fn resume(dir: &Path) -> Result<SplitBottomRun, RunError> {
        let lock = lock(dir)?;
        let mut run: SplitBottomRun = read_checkpoint(&dir.join("checkpoint.bin"))?;
        run.lock = Some(lock);
        Ok(run)
    }

    /// Steps of the shear stage.
    pub fn shear_steps(&self) -> u64 {
        (self.spec.duration / self.simulation.dt).round().max(1.0) as u64
    }

    /// Runs the remaining stages, reporting `(stage, done, total)` progress (steps of the
    /// stage; the settle stage's total is its step limit).
    pub fn advance(
        &mut self,
        dir: &Path,
        mut progress: impl FnMut(Stage, u64, u64),
    ) -> Result<(), RunError> {
        self.advance_until(dir, u64::MAX, &mut progress)
    }

    /// Like [`SplitBottomRun::advance`] but stops after step `stop` (to test resumption).
    pub fn advance_until(
        &mut self,
        dir: &Path,
        stop: u64,
        progress: &mut dyn FnMut(Stage, u64, u64),
    ) -> Result<(), RunError> {
        self.run_steps(dir, stop, false, progress)
    }

    /// Runs the current stage to its end (settle: its criterion or its time limit, see
    /// [`SplitBottomRun::settled`]; shear: its duration, with the outputs written), so that
    /// a caller can report between stages.
    pub fn advance_stage(
        &mut self,
        dir: &Path,
        progress: &mut dyn FnMut(Stage, u64, u64),
    ) -> Result<(), RunError> {
        self.run_steps(dir, u64::MAX, true, progress)
    }

    /// Steps until step `stop`, the run's end, or (`one_stage`) the end of the current
    /// stage; on an error the summary says "failed" and why.
    fn run_steps(
        &mut self,
        dir: &Path,
        stop: u64,
        one_stage: bool,
        progress: &mut dyn FnMut(Stage, u64, u64),
    ) -> Result<(), RunError> {
        let outcome = self.steps(dir, stop, one_stage, progress);
        if let Err(e) = &outcome {
            // The error itself matters more than a summary that cannot be written.
            let _ = self.write_failure(dir, e);
        }
        outcome
    }

    /// Records a failure in `summary.json` (see [`record_failure`]).
    fn write_failure(&self, dir: &Path, error: &RunError) -> Result<(), RunError> {
        let at = serde_json::json!({
            "stage": self.stage,
            "time": self.simulation.time,
            "steps": self.simulation.step,
        });
        record_failure(dir, &self.spec, at, error)
    }

    fn steps(
        &mut self,
        dir: &Path,
        stop: u64,
        one_stage: bool,
        progress: &mut dyn FnMut(Stage, u64, u64),
    ) -> Result<(), RunError> {
        let dt = self.simulation.dt;
        let mut clock = Instant::now();
        let first = self.stage;
        while self.simulation.step < stop && !(one_stage && self.stage != first) {
            match self.stage {
                Stage::Settle => {
                    let check = ((0.005 / dt).round() as u64).max(1);
                    let end = self.settle_end();
                    let limit = end.max_steps(dt);
                    let next = self.simulation.step + 1;
                    let measure = next.is_multiple_of(check);
                    self.simulation.step(measure)?;
                    progress(Stage::Settle, next, limit);
                    if measure {
                        let row = self.row();
                        // Translational energy only: without torsion resistance a particle
                        // spinning about its contact normal is never slowed down, so the
                        // rotational energy of a settled bed need not vanish. Against the
                        // springs' energy alone: with a cohesive law the elastic energy
                        // holds the negative adhesive potential and may be below zero.
                        let springs = self.simulation.contact_summary().spring_energy;
                        let energies = (row.kinetic_translational, springs);
                        self.sane()?;
                        self.rows.push(row);
                        let verdict = end.verdict(next, self.simulation.time, Some(energies));
                        if verdict != Verdict::Continue {
                            let ratio = energies.0 / energies.1.max(f64::MIN_POSITIVE);
                            self.freeze_walls(ratio, verdict == Verdict::Met)?;
                            self.wall_seconds += clock.elapsed().as_secs_f64();
                            clock = Instant::now();
                            write_checkpoint(&dir.join("settled.bin"), &*self)?;
                            self.begin_shear()?;
                            self.checkpoint(dir)?;
                        } else if next.is_multiple_of(20 * check) {
                            self.checkpoint(dir)?;
                        }
                    }
                }
                Stage::Shear => {
                    let (t0, s0) = self.shear_start.unwrap_or((0.0, 0));
                    let total = self.shear_steps();
                    let next = self.simulation.step + 1 - s0;
                    let row_every = (total / self.spec.rows).max(1);
                    let measure = next.is_multiple_of(row_every) || next == total;
                    let snap_every = total.checked_div(self.spec.snapshots).unwrap_or(0);
                    let snap_now = snap_every > 0 && next.is_multiple_of(snap_every);
                    let in_window = self.simulation.time + dt - t0 >= self.spec.average_from;
                    let cg_now = in_window
                        && self.fields.is_some()
                        && self.cg_steps().is_some_and(|k| next.is_multiple_of(k));
                    // Steps whose contacts are coarse-grained or stored keep their records.
                    let contacts = if cg_now || snap_now {
                        Some(self.simulation.step_with::<ContactRecords>()?.0)
                    } else {
                        self.simulation.step(measure)?;
                        None
                    };
                    if cg_now {
                        self.sample_fields(contacts.as_deref().unwrap_or_default())?;
                    }
                    if measure {
                        self.sane()?;
                        let row = self.row();
                        if self.simulation.time - t0 >= self.spec.average_from {
                            self.sample_profiles()?;
                        }
                        self.rows.push(row);
                    }
                    if snap_now {
                        self.snapshot(dir, contacts.as_deref().unwrap_or_default())?;
                    }
                    let ck_every = total.checked_div(self.spec.checkpoints).unwrap_or(0);
                    if next == total {
                        self.stage = Stage::Done;
                    }
                    if next == total || (ck_every > 0 && next.is_multiple_of(ck_every)) {
                        self.wall_seconds += clock.elapsed().as_secs_f64();
                        clock = Instant::now();
                        self.checkpoint(dir)?;
                    }
                    progress(Stage::Shear, next, total);
                }
                Stage::Done => break,
            }
        }
        self.wall_seconds += clock.elapsed().as_secs_f64();
        if self.stage == Stage::Done {
            self.write_outputs(dir)?;
        }
        Ok(())
    }

    /// The settle stage's end: the kinetic criterion, no sooner than the time of a free fall
    /// from the top of the filling, at the latest `settle_max_time`.
    pub fn settle_end(&self) -> EndCondition {
        let fall = (2.0 * (self.geometry.fill_top - self.geometry.floor)
            / self.spec.gravity.max(1e-9))
        .sqrt();
        EndCondition::KineticBelow {
            ratio: self.spec.settle_kinetic_ratio,
            min_time: fall,
            max_time: self.spec.settle_max_time,
        }
    }

    fn sane(&self) -> Result<(), RunError> {
        self.simulation
            .check_sanity()
            .map_err(|cause| RunError::Unstable {
                step: self.simulation.step,
                time: self.simulation.time,
                cause,
                checkpoint: None,
            })
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
        let law = self.spec.law();
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

    fn surface_height(&self) -> f64 {
        let p = &self.simulation.particles;
        let g = &self.geometry;
        let d = self.spec.diameter;
        surface_height(
            &p.position,
            &p.radius,
            |i| p.motion[i].is_free(),
            g.inner_radius + d,
            g.outer_radius - d,
            2.0 * d,
        )
        .unwrap_or(0.0)
    }

    fn sample_profiles(&mut self) -> Result<(), RunError> {
        let p = &self.simulation.particles;
        if self.spec.omega == 0.0 {
            return Ok(());
        }
        for profile in &mut self.profiles {
            profile
                .add_sample(
                    &p.position,
                    &p.velocity,
                    |i| p.motion[i].is_free(),
                    self.spec.omega,
                )
                .map_err(|e| {
                    RunError::Scenario(invalid("omega", self.spec.omega, e.to_string()))
                })?;
        }
        Ok(())
    }

    /// The row of the current (just measured) state.
    fn row(&self) -> Row {
        let sim = &self.simulation;
        let (kinetic_translational, kinetic_rotational) = sim.kinetic_energies();
        let c = sim.contact_summary();
        let ring = 2.0 * PI / self.geometry.angle;
        let mut torque = [0.0; 5];
        for (t, load) in torque.iter_mut().zip(sim.part_loads()) {
            *t = ring * load.torque_about(DVec3::ZERO, DVec3::Z);
        }
        let angle = self
            .shear_start
            .map_or(0.0, |(t0, _)| self.spec.omega * (sim.time - t0));
        Row {
            time: sim.time,
            stage: self.stage,
            angle,
            kinetic_energy: kinetic_translational + kinetic_rotational,
            kinetic_translational,
            elastic_energy: c.elastic_energy,
            contacts: c.contacts,
            coordination: c.coordination,
            bridges_per_particle: c.bridges_per_particle,
            surface_height: self.surface_height(),
            net_torque: torque[INNER_WALL as usize] + torque[INNER_BOTTOM as usize]
                - torque[OUTER_BOTTOM as usize]
                - torque[OUTER_WALL as usize],
            torque,
        }
    }

    /// Steady-state results over the averaging window.
    pub fn results(&self) -> ShearResults {
        let t0 = self.shear_start.map_or(0.0, |s| s.0);
        let window: Vec<&Row> = self
            .rows
            .iter()
            .filter(|r| r.stage != Stage::Settle && r.time - t0 >= self.spec.average_from)
            .collect();
        let series = |f: &dyn Fn(&Row) -> f64| {
            block_average(&window.iter().map(|r| f(r)).collect::<Vec<_>>())
        };
        let h = self
            .settled
            .as_ref()
            .map_or(self.geometry.height, |s| s.surface_height);
        let d = self.spec.diameter;
        let net = series(&|r| r.net_torque);
        let weight = self.spec.groups(&self.geometry, self.simulation.dt).weight;
        ShearResults {
            window: [self.spec.average_from, self.spec.duration],
            torque: (0..PARTS.len()).map(|k| series(&|r| r.torque[k])).collect(),
            net_torque_scaled: net.map(|e| e.mean / (weight * d)),
            net_torque: net,
            balance: series(&|r| r.torque.iter().sum()),
            band: self
                .profiles
                .iter()
                .zip(SLABS)
                .zip(slabs(h, d))
                .map(|((p, name), z)| SlabFit {
                    slab: name.to_string(),
                    z: [z.0, z.1],
                    fit: p.fit(4, 0.02).map_err(|e| e.to_string()),
                })
                .collect(),
        }
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

    fn checkpoint(&mut self, dir: &Path) -> Result<(), RunError> {
        write_checkpoint(&dir.join("checkpoint.bin"), &*self)?;
        self.write_outputs(dir)
    }

    /// Steps between samples of the fields, `cg_every / dt` rounded (at least 1); `None`
    /// without fields.
    fn cg_steps(&self) -> Option<u64> {
        (self.spec.cg_every > 0.0)
            .then(|| ((self.spec.cg_every / self.simulation.dt).round() as u64).max(1))
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

    /// Writes the time series, band profiles and summary.
    pub fn write_outputs(&self, dir: &Path) -> Result<(), RunError> {
        let mut csv = String::from(
            "time,stage,angle,kinetic_energy,elastic_energy,contacts,coordination,\
             bridges_per_particle,surface_height,torque_inner_wall,torque_inner_bottom,\
             torque_outer_bottom,torque_outer_wall,torque_backstops,net_torque\n",
        );
        for r in &self.rows {
            let stage = match r.stage {
                Stage::Settle => "settle",
                _ => "shear",
            };
            csv.push_str(&format!(
                "{:e},{stage},{:e},{:e},{:e},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}\n",
                r.time,
                r.angle,
                r.kinetic_energy,
                r.elastic_energy,
                r.contacts,
                r.coordination,
                r.bridges_per_particle,
                r.surface_height,
                r.torque[0],
                r.torque[1],
                r.torque[2],
                r.torque[3],
                r.torque[4],
                r.net_torque
            ));
        }
        let path = dir.join("timeseries.csv");
        write_atomic(&path, csv.as_bytes()).map_err(io_err("write", &path))?;

        let mut band = String::from("slab,z_lo,z_hi,r,ratio,stderr,count\n");
        for (p, name) in self.profiles.iter().zip(SLABS) {
            let (lo, hi) = p.slab();
            for b in p.bins() {
                band.push_str(&format!(
                    "{name},{lo:e},{hi:e},{:e},{:e},{:e},{}\n",
                    b.r, b.mean, b.stderr, b.count
                ));
            }
        }
        let path = dir.join("band.csv");
        write_atomic(&path, band.as_bytes()).map_err(io_err("write", &path))?;
        let band = match self.fields.as_ref().filter(|s| s.snapshots > 0) {
            Some(sums) => Some(cell_fields::write_outputs(self, sums, dir)?),
            None => None,
        };

        let summary = serde_json::json!({
            "program": "rheodem split-bottom",
            "version": crate::VERSION,
            "commit": crate::COMMIT,
            "seed": self.spec.seed,
            "status": if self.stage == Stage::Done { "completed" } else { "running" },
            "stage": self.stage,
            "from": self.from,
            "time": self.simulation.time,
            "steps": self.simulation.step,
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
            "groups": self.spec.groups(&self.geometry, self.simulation.dt),
            "time_step_rule": self.spec.time_step,
            "parts": PARTS,
            "settled": self.settled,
            "results": (self.stage != Stage::Settle).then(|| self.results()),
            "fields": self.fields.as_ref().map(|f| serde_json::json!({
                "samples": f.snapshots,
                "grid": f.grid,
                "kernel": self.spec.cg_kernel,
                "width": self.spec.cg_width * self.spec.diameter,
            })),
            "band_rheology": band.as_ref().map(|b| cell_fields::BandSummary::new(
                b,
                self.results().net_torque.map(|e| e.mean),
            )),
        });
        let path = dir.join("summary.json");
        let text = serde_json::to_string_pretty(&summary).unwrap_or_default();
        write_atomic(&path, text.as_bytes()).map_err(io_err("write", &path))?;
        if self.stage == Stage::Done {
            self.write_figures(dir)?;
        }
        Ok(())
    }

    /// `torque.svg`: the torques against the rotation angle (Roy et al. 2016, Fig. 10);
    /// `band.svg`: the velocity profiles with their fits.
    fn write_figures(&self, dir: &Path) -> Result<(), RunError> {
        let shear: Vec<&Row> = self
            .rows
            .iter()
            .filter(|r| r.stage != Stage::Settle)
            .collect();
        let curve = |f: &dyn Fn(&Row) -> f64| -> Vec<(f64, f64)> {
            shear.iter().map(|r| (r.angle, f(r))).collect()
        };
        let net = curve(&|r| r.net_torque);
        let drive = curve(&|r| -(r.torque[OUTER_BOTTOM as usize] + r.torque[OUTER_WALL as usize]));
        let balance = curve(&|r| r.torque.iter().sum());
        let svg = plot_svg(
            &Labels {
                title: "Wall torque, full ring",
                x: "rotation angle (rad)",
                y: "torque (N m)",
            },
            &[
                Series {
                    dashed_as: None,
                    label: "net (fixed − rotating parts)",
                    points: &net,
                },
                Series {
                    dashed_as: None,
                    label: "drive (−rotating parts)",
                    points: &drive,
                },
                Series {
                    dashed_as: None,
                    label: "balance (all parts)",
                    points: &balance,
                },
            ],
            &[],
        )
        .map_err(|e| RunError::Scenario(invalid("figure", "torque.svg", e)))?;
        let path = dir.join("torque.svg");
        write_atomic(&path, svg.as_bytes()).map_err(io_err("write", &path))?;

        let results = self.results();
        let mut measured = Vec::new();
        let mut fitted = Vec::new();
        for p in &self.profiles {
            let bins = p.bins();
            measured.push(
                bins.iter()
                    .filter(|b| b.count > 1)
                    .map(|b| (b.r, b.mean, b.stderr))
                    .collect::<Vec<_>>(),
            );
        }
        for fit in &results.band {
            let points = match &fit.fit {
                Ok(f) => {
                    let (lo, hi) = (self.geometry.inner_radius, self.geometry.outer_radius);
                    (0..=100)
                        .map(|k| {
                            let r = lo + (hi - lo) * k as f64 / 100.0;
                            (r, erf_profile(r, f.centre, f.width))
                        })
                        .collect()
                }
                Err(_) => Vec::new(),
            };
            fitted.push(points);
        }
        let names: Vec<String> = SLABS.iter().map(|s| format!("{s} slab, fit")).collect();
        let series: Vec<Series<'_>> = fitted
            .iter()
            .zip(&names)
            .map(|(p, n)| Series {
                dashed_as: None,
                label: n,
                points: p,
            })
            .collect();
        let markers: Vec<Markers<'_>> = measured
            .iter()
            .zip(SLABS)
            .map(|(p, n)| Markers {
                label: n,
                points: p,
            })
            .collect();
        let svg = plot_svg(
            &Labels {
                title: "Azimuthal velocity of the grains",
                x: "r (m)",
                y: "v_φ / (Ω r)",
            },
            &series,
            &markers,
        )
        .map_err(|e| RunError::Scenario(invalid("figure", "band.svg", e)))?;
        let path = dir.join("band.svg");
        write_atomic(&path, svg.as_bytes()).map_err(io_err("write", &path))
    }
}

/// The three slabs `(z_lo, z_hi)` of the velocity profiles for a surface at `h` (m):
/// 2 `d_p` thick, centred at `2 d_p` (bottom), `h/2` (middle) and `h − 2 d_p` (surface).
fn slabs(h: f64, d: f64) -> [(f64, f64); 3] {
    [
        (d, 3.0 * d),
        (0.5 * h - d, 0.5 * h + d),
        (h - 3.0 * d, h - d),
    ]
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
    l.normal.damping = l.normal.damping.scaled(factor);
    l.tangential.damping = l.tangential.damping.scaled(factor);
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
            laws.get(0, 0).normal.contact_time(0.5 * m).ok_or_else(|| {
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
