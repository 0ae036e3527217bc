//! The state of a split-bottom run, serialised whole as its checkpoint: the simulation,
//! the stage, the time series and the profiles and fields averaged so far; and the
//! measurements of the cell (the row of the time series with its wall torques, the
//! surface height, the steady-state results over the averaging window).

use super::spec::{Geometry, SplitBottomSpec};
use crate::Simulation;
use crate::analysis::{Estimate, block_average};
use crate::band::{AzimuthalProfile, ErfFit, surface_height};
use crate::cg::CgSums;
use crate::run::RunError;
use crate::scenario::invalid;
use crate::stage::EndCondition;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Wall parts of the cell, in part-number order.
pub const PARTS: [&str; 5] = [
    "inner-wall",
    "inner-bottom",
    "outer-bottom",
    "outer-wall",
    "backstops",
];
pub(super) const INNER_WALL: u16 = 0;
pub(super) const INNER_BOTTOM: u16 = 1;
pub(super) const OUTER_BOTTOM: u16 = 2;
pub(super) const OUTER_WALL: u16 = 3;
pub(super) const BACKSTOPS: u16 = 4;

/// Names of the velocity-profile slabs.
pub const SLABS: [&str; 3] = ["bottom", "middle", "surface"];

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

/// The state of a split-bottom run: serialised whole as its checkpoint (and as
/// `settled.bin` at the end of settling).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SplitBottomState {
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
}

/// Cylindrical radius of `r` about `z` (m).
pub(super) fn rho(r: DVec3) -> f64 {
    r.x.hypot(r.y)
}

/// The three slabs `(z_lo, z_hi)` of the velocity profiles for a surface at `h` (m):
/// 2 `d_p` thick, centred at `2 d_p` (bottom), `h/2` (middle) and `h − 2 d_p` (surface).
pub(super) fn slabs(h: f64, d: f64) -> [(f64, f64); 3] {
    [
        (d, 3.0 * d),
        (0.5 * h - d, 0.5 * h + d),
        (h - 3.0 * d, h - d),
    ]
}

impl SplitBottomState {
    /// Steps of the shear stage.
    pub fn shear_steps(&self) -> u64 {
        (self.spec.duration / self.simulation.dt).round().max(1.0) as u64
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

    /// Steps between samples of the fields, `cg_every / dt` rounded (at least 1); `None`
    /// without fields.
    pub(super) fn cg_steps(&self) -> Option<u64> {
        (self.spec.cg_every > 0.0)
            .then(|| ((self.spec.cg_every / self.simulation.dt).round() as u64).max(1))
    }

    pub(super) fn surface_height(&self) -> f64 {
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

    pub(super) fn sample_profiles(&mut self) -> Result<(), RunError> {
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
    pub(super) fn row(&self) -> Row {
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
}
