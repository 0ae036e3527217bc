//! # rheodem
//!
//! A discrete-element (DEM) simulator for polydisperse soft spheres with linear visco-elastic
//! frictional contacts, and the rheology tools built on it. The engine (particles, contact
//! laws, boundaries, neighbours, the pair loop, integration, observers, the step) is the
//! crate `rheodem-engine`, re-exported here under the same module names; this crate adds
//! scenario files, run directories and checkpoints, coarse-graining, analysis and fits, the
//! set-ups and studies, figures and the results database. All quantities are SI unless a
//! doc comment says otherwise.
//!
//! # Quick start
//!
//! A scenario (the format of [`scenario::spec`]) is parsed with
//! [`Scenario::from_toml`](scenario::Scenario::from_toml) and assembled into a
//! [`Simulation`] by [`scenario::build`]; [`Simulation::step`] advances it. Here one sphere
//! falls freely under gravity, and velocity Verlet reproduces `z = z₀ − ½ g t²` and
//! `v = −g t` exactly for a constant force (up to rounding):
//!
//! ```
//! use rheodem::scenario::{Scenario, build};
//!
//! let text = r#"
//!     gravity = [0.0, 0.0, -9.81]
//!     [domain]
//!     size = [0.1, 0.1, 0.1]
//!     [[species]]
//!     name = "glass"
//!     density = 2000.0
//!     [[contact]]
//!     normal = { stiffness = 100.0, restitution = 0.8 }
//!     [[particles]]
//!     kind = "explicit"
//!     species = "glass"
//!     spheres = [{ radius = 1.1e-3, position = [0.05, 0.05, 0.09] }]
//!     [run]
//!     steps = 200
//! "#;
//! let scenario = Scenario::from_toml(text)?;
//! let built = build(&scenario, std::path::Path::new("."))?;
//! let mut sim = built.simulation;
//! assert_eq!(built.resolved.free_particles, 1);
//! // The default time step: 1/50 of the shortest contact time.
//! assert!((sim.dt * 50.0 / built.resolved.contact_time - 1.0).abs() < 1e-12);
//! for _ in 0..built.resolved.steps {
//!     sim.step(false)?;
//! }
//! let t = 200.0 * sim.dt;
//! assert!((sim.time - t).abs() < 1e-12 * t);
//! let z = sim.particles.position[0].z;
//! assert!((z - (0.09 - 0.5 * 9.81 * t * t)).abs() < 1e-12);
//! assert!((sim.particles.velocity[0].z + 9.81 * t).abs() < 1e-12);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod analysis;
pub mod band;
pub mod bench;
pub mod cg;
pub mod driver;
pub mod fit;
pub mod io;
pub mod plot;
pub mod rheology;
pub mod run;
pub mod scenario;
pub mod setups;

// The engine (its own crate, `rheodem-engine`), under the same paths as before it moved.
pub use rheodem_engine::{
    Simulation, contact, domain, forces, generate, integrate, measure, memory, neighbor, observe,
    particles, prune, sanity, simulation, stage, stress_control, team, timestep, walls,
};

/// Version of the program, recorded in every output; checkpoints resume only under the
/// same version.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// Git commit the program was built from (`+dirty` with uncommitted changes), recorded in
/// every output for provenance.
pub const COMMIT: &str = env!("RHEODEM_COMMIT");
