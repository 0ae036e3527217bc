//! The contacts of the current state as a table (a computed copy: contact forces are not
//! stored between steps).
//!
//! The forces are evaluated again on a copy of the simulation, at the positions of the
//! current state and at the velocities its last force evaluation saw (velocity Verlet's
//! half-step velocities, recovered by undoing the step's closing half kick), with a time
//! step of zero so that every spring keeps the history the step left it. They are those of
//! the step up to rounding: the contact forces on each particle add up, with gravity, to
//! its `forces` row.

use glam::DVec3;
use numpy::PyArray1;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rheodem::Simulation;
use rheodem::measure::Observables;
use rheodem::observe::{ContactObserver, ContactView};
use rheodem::team::Team;

/// Every interacting pair of one force evaluation, column by column.
#[derive(Default)]
pub struct ContactTable {
    i: Vec<u32>,
    j: Vec<u32>,
    wall: Vec<bool>,
    overlap: Vec<f64>,
    branch: Vec<DVec3>,
    normal: Vec<DVec3>,
    force: Vec<DVec3>,
    force_on_j: Vec<DVec3>,
    bridge: Vec<bool>,
}

impl ContactObserver for ContactTable {
    fn visit(&mut self, c: &ContactView<'_>) {
        self.i.push(c.ids[0]);
        self.j.push(c.ids[1]);
        self.wall.push(c.wall.is_some());
        self.overlap.push(c.kinematics.overlap);
        self.branch.push(c.branch);
        self.normal.push(c.kinematics.normal);
        self.force.push(c.force.force);
        self.force_on_j.push(c.force_on_j());
        self.bridge.push(c.history.bridge);
    }

    fn merge(&mut self, other: Self) {
        self.i.extend(other.i);
        self.j.extend(other.j);
        self.wall.extend(other.wall);
        self.overlap.extend(other.overlap);
        self.branch.extend(other.branch);
        self.normal.extend(other.normal);
        self.force.extend(other.force);
        self.force_on_j.extend(other.force_on_j);
        self.bridge.extend(other.bridge);
    }
}

/// A copy of `sim` at the velocities of its last force evaluation, with a time step of
/// zero, on which the forces can be evaluated again (see the module documentation).
/// `ends_a_step`: whether the state is the end of a step (its closing half kick applied
/// after the forces), rather than freshly assembled (forces at the current velocities).
fn probe(sim: &Simulation, ends_a_step: bool) -> Simulation {
    let mut probe = sim.clone();
    if ends_a_step {
        rheodem::integrate::kick(&mut probe.particles, -0.5 * probe.dt, &Team::new(1));
    }
    probe.dt = 0.0;
    probe
}

/// The contacts of `sim`'s current state (see the module documentation and [`probe`]),
/// evaluated in the caller's thread pool.
pub fn evaluate(sim: &Simulation, ends_a_step: bool) -> ContactTable {
    probe(sim, ends_a_step).compute_forces_with::<ContactTable>()
}

/// The observables of `sim`'s current state: the contact parts measured on the probe, the
/// kinetic parts at the state's own velocities.
pub fn observables(sim: &Simulation, ends_a_step: bool) -> Observables {
    let mut probe = probe(sim, ends_a_step);
    probe.compute_forces(true);
    probe.particles.velocity.clone_from(&sim.particles.velocity);
    probe
        .particles
        .angular_velocity
        .clone_from(&sim.particles.angular_velocity);
    probe.observables()
}

fn vectors<'py>(py: Python<'py>, v: &[DVec3]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = v.iter().flat_map(|x| x.to_array()).collect();
    // The shape holds the length exactly.
    Array2::from_shape_vec((v.len(), 3), flat).map_or_else(
        |_| PyArray2::zeros(py, (0, 3), false),
        |a| a.into_pyarray(py),
    )
}

impl ContactTable {
    /// The table as a dict of NumPy arrays (the columns of docs/python.md).
    pub fn into_dict(self, py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
        let d = PyDict::new(py);
        let normal_force: Vec<DVec3> = self
            .force
            .iter()
            .zip(&self.normal)
            .map(|(f, n)| f.dot(*n) * *n)
            .collect();
        let tangential_force: Vec<DVec3> = self
            .force
            .iter()
            .zip(&normal_force)
            .map(|(f, fnorm)| *f - *fnorm)
            .collect();
        d.set_item("i", PyArray1::from_vec(py, self.i))?;
        d.set_item("j", PyArray1::from_vec(py, self.j))?;
        d.set_item("wall", PyArray1::from_vec(py, self.wall))?;
        d.set_item("overlap", PyArray1::from_vec(py, self.overlap))?;
        d.set_item("branch", vectors(py, &self.branch))?;
        d.set_item("normal", vectors(py, &self.normal))?;
        d.set_item("force", vectors(py, &self.force))?;
        d.set_item("normal_force", vectors(py, &normal_force))?;
        d.set_item("tangential_force", vectors(py, &tangential_force))?;
        d.set_item("force_on_j", vectors(py, &self.force_on_j))?;
        d.set_item("bridge", PyArray1::from_vec(py, self.bridge))?;
        Ok(d)
    }
}
