//! Read-only NumPy views of the particle arrays, without copies, and the rule that keeps
//! them sound.
//!
//! A view's memory is the simulation's own array. The simulation notes every array it has
//! lent; before anything changes its arrays (a step, a run) it hands each lent array that a
//! view still uses to that view's [`Buffer`] and goes on with a copy. A view therefore
//! always shows the state at the step it was taken: two reads within a step share their
//! memory, and a view held across a step keeps the earlier values (the simulation has moved
//! on in new memory). A step after which no view of an array is alive copies nothing. While
//! the memory is still the simulation's, a view's buffer keeps the simulation object alive;
//! the simulation holds its lent slots weakly, so no cycle forms.

use glam::DVec3;
use numpy::ndarray::{ArrayView1, ArrayView2};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rheodem::particles::Particles;
use std::sync::{Arc, Mutex, PoisonError, Weak};

/// A particle array that can be viewed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Field {
    /// Centre positions (m), (N, 3).
    Position,
    /// Velocities (m/s), (N, 3).
    Velocity,
    /// Angular velocities (rad/s), (N, 3).
    AngularVelocity,
    /// Total forces of the last evaluation (N), (N, 3).
    Force,
    /// Total torques of the last evaluation (N m), (N, 3).
    Torque,
    /// Radii (m), (N,).
    Radius,
    /// Masses (kg), (N,).
    Mass,
    /// Permanent particle ids, (N,) `uint32`.
    Id,
    /// Wall part of each particle, (N,) `uint16`.
    Part,
    /// Species index, (N,) `uint16`.
    Species,
}

/// An array handed over by the simulation: held (never read again from Rust) so that the
/// views of it stay valid.
#[allow(dead_code)]
enum Owned {
    Vectors(Vec<DVec3>),
    Reals(Vec<f64>),
    Ids(Vec<u32>),
    Small(Vec<u16>),
}

/// Whose memory a view shows.
#[allow(dead_code)]
enum Holder {
    /// The simulation's (the Python object, kept alive while the view lives).
    Simulation(Py<PyAny>),
    /// An array the simulation handed over.
    Array(Owned),
}

/// What the [`Buffer`]s of one lent array share.
struct Slot(Mutex<Holder>);

/// The base object of a view (`view.base`): keeps the viewed memory alive. Not made from
/// Python.
#[pyclass(module = "rheodem._rheodem", frozen)]
pub struct Buffer {
    _slot: Arc<Slot>,
}

/// The arrays a simulation has lent, each with the slot its views share (held weakly: a
/// slot lives as long as a view of it).
#[derive(Default)]
pub struct Lent(Vec<(Field, Weak<Slot>)>);

impl Field {
    /// The array of `self` in `p`, replaced there by a copy.
    fn take(self, p: &mut Particles) -> Owned {
        fn swap<T: Clone>(v: &mut Vec<T>) -> Vec<T> {
            let copy = v.clone();
            std::mem::replace(v, copy)
        }
        match self {
            Field::Position => Owned::Vectors(swap(&mut p.position)),
            Field::Velocity => Owned::Vectors(swap(&mut p.velocity)),
            Field::AngularVelocity => Owned::Vectors(swap(&mut p.angular_velocity)),
            Field::Force => Owned::Vectors(swap(&mut p.force)),
            Field::Torque => Owned::Vectors(swap(&mut p.torque)),
            Field::Radius => Owned::Reals(swap(&mut p.radius)),
            Field::Mass => Owned::Reals(swap(&mut p.mass)),
            Field::Id => Owned::Ids(swap(&mut p.id)),
            Field::Part => Owned::Small(swap(&mut p.part)),
            Field::Species => Owned::Small(swap(&mut p.species)),
        }
    }
}

impl Lent {
    /// Hands every lent array that a view still uses to its buffer, leaving a copy in `p`;
    /// forgets the rest. Called before anything changes `p`.
    pub fn release(&mut self, p: &mut Particles) {
        for (field, slot) in self.0.drain(..) {
            if let Some(slot) = slot.upgrade() {
                let owned = field.take(p);
                // The simulation object is let go with it.
                *slot.0.lock().unwrap_or_else(PoisonError::into_inner) = Holder::Array(owned);
            }
        }
    }

    /// The slot of `field`'s current memory, made (holding `owner`) if no live view
    /// shares it.
    fn slot(&mut self, field: Field, owner: Py<PyAny>) -> Arc<Slot> {
        self.0.retain(|(_, s)| s.strong_count() > 0);
        if let Some(s) = self
            .0
            .iter()
            .find(|(f, _)| *f == field)
            .and_then(|(_, s)| s.upgrade())
        {
            return s;
        }
        let s = Arc::new(Slot(Mutex::new(Holder::Simulation(owner))));
        self.0.push((field, Arc::downgrade(&s)));
        s
    }
}

/// A read-only NumPy view of `field` of `p`, whose base keeps `owner` (the Python
/// simulation object) alive while the memory is the simulation's.
pub fn view<'py>(
    py: Python<'py>,
    p: &Particles,
    lent: &mut Lent,
    field: Field,
    owner: Py<PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let base = Bound::new(
        py,
        Buffer {
            _slot: lent.slot(field, owner),
        },
    )?
    .into_any();
    // SAFETY: each array's memory stays where it is while `base` lives: the simulation
    // never reallocates or frees a lent array (it hands it to the slot first, see
    // `Lent::release`), and the slot keeps the simulation alive meanwhile. `DVec3` is three
    // `f64` in a row (`repr(C)`), so N of them are an (N, 3) C-ordered `f64` array.
    let array = unsafe {
        match field {
            Field::Position
            | Field::Velocity
            | Field::AngularVelocity
            | Field::Force
            | Field::Torque => {
                let v = match field {
                    Field::Position => &p.position,
                    Field::Velocity => &p.velocity,
                    Field::AngularVelocity => &p.angular_velocity,
                    Field::Force => &p.force,
                    _ => &p.torque,
                };
                let a = ArrayView2::from_shape_ptr((v.len(), 3), v.as_ptr().cast::<f64>());
                PyArray2::borrow_from_array(&a, base).into_any()
            }
            Field::Radius | Field::Mass => {
                let v = if field == Field::Radius {
                    &p.radius
                } else {
                    &p.mass
                };
                PyArray1::borrow_from_array(&ArrayView1::from_shape_ptr(v.len(), v.as_ptr()), base)
                    .into_any()
            }
            Field::Id => PyArray1::borrow_from_array(
                &ArrayView1::from_shape_ptr(p.id.len(), p.id.as_ptr()),
                base,
            )
            .into_any(),
            Field::Part | Field::Species => {
                let v = if field == Field::Part {
                    &p.part
                } else {
                    &p.species
                };
                PyArray1::borrow_from_array(&ArrayView1::from_shape_ptr(v.len(), v.as_ptr()), base)
                    .into_any()
            }
        }
    };
    let flags = PyDict::new(py);
    flags.set_item("write", false)?;
    array.call_method("setflags", (), Some(&flags))?;
    Ok(array)
}
