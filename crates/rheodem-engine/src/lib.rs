//! # rheodem-engine
//!
//! The discrete-element engine of rheodem: polydisperse soft spheres ([`particles`]), their
//! contact laws ([`contact`]: linear visco-elastic frictional contacts with rolling and
//! torsion resistance, reversible adhesion, Willett liquid bridges, the linear irreversible
//! law), the boundaries ([`domain`]: periodic, Lees-Edwards, the angular-periodic wedge;
//! [`walls`]), neighbour lists ([`neighbor`]), the pair loop ([`forces`]), velocity-Verlet
//! integration ([`integrate`]), per-contact observers ([`observe`], [`measure`]) and the
//! time step ([`Simulation::step`]). All quantities are SI unless a doc comment says
//! otherwise.
//!
//! The engine reads no files and draws nothing: scenario files, run directories,
//! checkpoints on disk, coarse-graining, fits, figures and the results database belong to
//! the `rheodem` crate built on it, which re-exports these modules under the same names.
//!
//! A sphere falling freely under gravity: velocity Verlet reproduces `z = z₀ − ½ g t²`
//! exactly for a constant force (up to rounding).
//!
//! ```
//! use glam::DVec3;
//! use rheodem_engine::Simulation;
//! use rheodem_engine::contact::{Adhesion, ContactLaw, ContactTable, Damping, LinearNormal, Spring};
//! use rheodem_engine::domain::Domain;
//! use rheodem_engine::particles::{Motion, Particles, Sphere};
//!
//! let mut particles = Particles::default();
//! let sphere = Sphere {
//!     position: DVec3::new(0.05, 0.05, 0.09),
//!     velocity: DVec3::ZERO,
//!     angular_velocity: DVec3::ZERO,
//!     radius: 1.1e-3,
//!     species: 0,
//!     motion: Motion::Free,
//! };
//! particles.push(sphere, 2000.0);
//! let law = ContactLaw {
//!     normal: LinearNormal { stiffness: 100.0, damping: Damping::NONE }.into(),
//!     tangential: Spring::NONE,
//!     rolling: Spring::NONE,
//!     torsion: Spring::NONE,
//!     adhesion: Adhesion::None,
//! };
//! let domain = Domain::new(DVec3::ZERO, DVec3::splat(0.1), [false; 3]);
//! let (gravity, dt) = (DVec3::new(0.0, 0.0, -9.81), 1e-5);
//! let mut sim =
//!     Simulation::new(particles, domain, ContactTable::uniform(1, law), Vec::new(), gravity, dt, 1e-4)?;
//! for _ in 0..200 {
//!     sim.step(false)?;
//! }
//! let t = 200.0 * dt;
//! let z = sim.particles.position[0].z;
//! assert!((z - (0.09 - 0.5 * 9.81 * t * t)).abs() < 1e-12);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod cell_walk;
pub mod contact;
mod displacement;
pub mod domain;
pub mod forces;
pub mod generate;
mod halo;
pub mod integrate;
pub mod measure;
pub mod memory;
pub mod neighbor;
pub mod observe;
pub mod particles;
pub mod prune;
pub mod sanity;
pub mod simulation;
pub mod stage;
pub mod stress_control;
pub mod team;
pub mod timestep;
pub mod walls;

pub use simulation::Simulation;
