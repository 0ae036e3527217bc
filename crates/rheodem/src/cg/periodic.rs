//! Fields of a periodic box sampled on the fly by a run (`[fields]` of a scenario;
//! docs/coarse-graining.md §7): slabs or a Cartesian grid over the box, velocities in the
//! lab frame whatever the shear dynamics, Lees-Edwards images with their shift and
//! velocity jump, and the sums kept in the run's checkpoint.

use super::{
    CgError, CgSums, ContactRecord, FieldPoint, Grid, Kernel, ParticleRecord, Snapshot, fields,
    images_for,
};
use crate::domain::{Domain, ShearDynamics};
use crate::scenario::spec::{FieldGrid, FieldsSpec};
use crate::scenario::{ScenarioError, invalid};
use crate::simulation::Simulation;
use serde::{Deserialize, Serialize};

/// The on-the-fly fields of a run: the checked settings and, from the first sample on,
/// the sums over the grid that the box had then.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BoxFields {
    /// The settings.
    pub spec: FieldsSpec,
    /// The sums; `None` before the first sample.
    pub sums: Option<CgSums>,
}

/// The axis index of `"x"`, `"y"` or `"z"` (as `fields.axis` names it).
pub fn axis_index(name: &str) -> Option<usize> {
    ["x", "y", "z"].iter().position(|&a| a == name)
}

impl BoxFields {
    /// Checks `spec` and starts without sums.
    ///
    /// # Errors
    /// [`ScenarioError::Invalid`] naming the `fields.*` key out of range.
    pub fn new(spec: &FieldsSpec) -> Result<BoxFields, ScenarioError> {
        if axis_index(&spec.axis).is_none() {
            return Err(invalid(
                "fields.axis",
                &spec.axis,
                "must be \"x\", \"y\" or \"z\"",
            ));
        }
        let wanted = match spec.grid {
            FieldGrid::Slabs => 1,
            FieldGrid::Cartesian => 3,
        };
        if spec.bins.len() != wanted || spec.bins.contains(&0) {
            return Err(invalid(
                "fields.bins",
                format!("{:?}", spec.bins),
                format!(
                    "must be {wanted} positive cell count(s) for grid = \"{}\"",
                    match spec.grid {
                        FieldGrid::Slabs => "slabs",
                        FieldGrid::Cartesian => "cartesian",
                    }
                ),
            ));
        }
        Kernel::new(spec.kernel, spec.width)
            .map_err(|e| invalid("fields.width", spec.width, e.to_string()))?;
        if !(spec.start.is_finite() && spec.start >= 0.0) {
            return Err(invalid(
                "fields.start",
                spec.start,
                "must be a finite time ≥ 0 (s)",
            ));
        }
        if let Some(m) = &spec.material {
            for (key, v, zero_ok) in [
                ("fields.material.diameter", m.diameter, false),
                (
                    "fields.material.particle_density",
                    m.particle_density,
                    false,
                ),
                ("fields.material.stiffness", m.stiffness, false),
                ("fields.material.max_adhesion", m.max_adhesion, true),
            ] {
                if !(v.is_finite() && (v > 0.0 || (zero_ok && v == 0.0))) {
                    return Err(invalid(
                        key,
                        v,
                        if zero_ok {
                            "must be a finite number ≥ 0"
                        } else {
                            "must be a positive finite number"
                        },
                    ));
                }
            }
        }
        Ok(BoxFields {
            spec: spec.clone(),
            sums: None,
        })
    }

    /// Whether a measured state at `time` (s) is to be sampled.
    pub fn wants(&self, time: f64) -> bool {
        time >= self.spec.start
    }

    /// The grid over the current box of `domain`.
    ///
    /// # Errors
    /// [`CgError::Invalid`] for a grid too large.
    pub fn grid(&self, domain: &Domain) -> Result<Grid, CgError> {
        let grid = match self.spec.grid {
            FieldGrid::Slabs => {
                let axis = axis_index(&self.spec.axis).expect("checked");
                let l = domain.lengths();
                Grid::Slab {
                    axis,
                    lo: domain.lo[axis],
                    hi: domain.hi[axis],
                    bins: self.spec.bins[0],
                    area: l.x * l.y * l.z / l[axis],
                }
            }
            FieldGrid::Cartesian => Grid::Cartesian {
                lo: domain.lo,
                hi: domain.hi,
                bins: [self.spec.bins[0], self.spec.bins[1], self.spec.bins[2]],
            },
        };
        grid.validate()?;
        Ok(grid)
    }

    /// Adds a sample: the lab view of a measured state with that step's `contacts`. The
    /// grid is the box's at the first sample; a box that changes size later (stress
    /// control) is still covered through its periodic images.
    ///
    /// # Errors
    /// [`CgError::Invalid`] for a grid too large.
    pub fn add(&mut self, view: &LabView, contacts: &[ContactRecord]) -> Result<(), CgError> {
        if self.sums.is_none() {
            self.sums = Some(CgSums::new(self.grid(&view.domain)?)?);
        }
        let kernel = Kernel::new(self.spec.kernel, self.spec.width)?;
        let sums = self.sums.as_mut().expect("made");
        let snap = snapshot(view, contacts, &sums.grid);
        sums.add_snapshot(&kernel, &snap);
        Ok(())
    }

    /// The time-averaged fields, once there is a sample.
    pub fn points(&self) -> Option<(&Grid, Vec<FieldPoint>)> {
        let sums = self.sums.as_ref()?;
        Some((&sums.grid, fields(sums, self.spec.material.as_ref())))
    }
}

/// A state of a periodic box as its fields see it, the same in every shear dynamics: the
/// time (s), the box with lab-frame Lees-Edwards boundaries, and the particles with
/// lab-frame velocities (under affine drag the stored ones exclude the mean flow, which is
/// added back). This is what a sample stores (see [`crate::cg::samples`]).
#[derive(Clone, Debug, PartialEq)]
pub struct LabView {
    /// Step of the state.
    pub step: u64,
    /// Time (s).
    pub time: f64,
    /// The box, its Lees-Edwards boundaries (if any) in the lab frame.
    pub domain: Domain,
    /// The particles, velocities in the lab frame (m/s).
    pub particles: Vec<ParticleRecord>,
}

impl LabView {
    /// The lab view of `sim`.
    pub fn of(sim: &Simulation) -> LabView {
        let mut domain = sim.domain.clone();
        let mut particles = ParticleRecord::all(&sim.particles);
        for r in &mut particles {
            r.velocity = sim.domain.lab_velocity(r.position, r.velocity);
        }
        if let Some(le) = domain.as_lees_edwards_mut() {
            le.dynamics = ShearDynamics::Lab;
        }
        LabView {
            step: sim.step,
            time: sim.time,
            domain,
            particles,
        }
    }
}

/// The snapshot of `view` for `grid`, with images that carry the lab frame's Lees-Edwards
/// velocity jump, so that the velocity field is continuous through the sheared boundary.
pub fn snapshot(view: &LabView, contacts: &[ContactRecord], grid: &Grid) -> Snapshot {
    Snapshot::assemble(
        view.time,
        &view.particles,
        contacts,
        images_for(&view.domain, grid),
    )
}
