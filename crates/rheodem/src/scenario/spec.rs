//! The scenario file format (TOML, SI units). Every table rejects unknown keys.
//!
//! ```toml
//! seed = 7
//! [domain]                      # box [lo, lo + size], periodic per axis
//! size = [0.02, 0.02, 0.02]
//! periodic = [true, true, true]
//! [[species]]
//! name = "glass"
//! density = 2000.0
//! [[contact]]                   # no `species` key: the default for every pair
//! normal = { stiffness = 100.0, restitution = 0.8 }
//! friction = { stiffness_ratio = 0.2857, damping_ratio = 0.2857, mu = 0.5 }
//! [[particles]]
//! kind = "random"
//! species = "glass"
//! count = 400
//! mean_diameter = 2.2e-3
//! polydispersity = 2.0
//! [preparation]
//! volume_fraction = 0.6
//! [run]
//! duration = 0.05
//! ```

pub use crate::contact::{LawSpec, NormalSpec};
use crate::domain::ShearDynamics;
use serde::{Deserialize, Serialize};

/// A whole scenario.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Free-text title of the run.
    #[serde(default)]
    pub title: Option<String>,
    /// Seed of every random choice (particle sizes, positions, velocities).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// The box.
    pub domain: DomainSpec,
    /// Particle species (materials).
    pub species: Vec<SpeciesSpec>,
    /// Contact laws: one without `species` is the default, others override a pair.
    #[serde(rename = "contact")]
    pub contacts: Vec<ContactSpec>,
    /// Particle groups, added in order.
    #[serde(default)]
    pub particles: Vec<ParticleGroup>,
    /// Infinite planar walls.
    #[serde(default, rename = "wall")]
    pub walls: Vec<WallSpec>,
    /// Gravitational acceleration (m/s²).
    #[serde(default, deserialize_with = "three")]
    pub gravity: [f64; 3],
    /// Optional compression of a loose packing before the run.
    #[serde(default)]
    pub preparation: Option<PreparationSpec>,
    /// Run length and time step.
    pub run: RunSpec,
    /// Output cadence.
    #[serde(default)]
    pub output: OutputSpec,
    /// Neighbour-list settings.
    #[serde(default)]
    pub neighbor: NeighborSpec,
    /// Control of `σ_yy` through `L_y` (needs `domain.shear_rate`).
    #[serde(default)]
    pub stress_control: Option<StressControlSpec>,
    /// Coarse-grained fields averaged over the run (periodic boxes).
    #[serde(default)]
    pub fields: Option<FieldsSpec>,
}

/// Coarse-grained fields of a periodic box, averaged on the fly over the time-series rows
/// from `start` on (docs/coarse-graining.md §7): written as `fields.csv` and `fields.vti`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FieldsSpec {
    /// `"slabs"` (averaged over planes normal to `axis`) or `"cartesian"`.
    #[serde(default)]
    pub grid: FieldGrid,
    /// The axis normal to the slabs, `"x"`, `"y"` (default, the shear gradient) or `"z"`.
    #[serde(default = "default_axis")]
    pub axis: String,
    /// Cells: one count for slabs, three (`x`, `y`, `z`) for a Cartesian grid.
    pub bins: Vec<usize>,
    /// Kernel shape, `"lucy"` (default) or `"gaussian"`.
    #[serde(default = "default_kernel")]
    pub kernel: crate::cg::KernelShape,
    /// Kernel width `w` (m), about a particle diameter.
    pub width: f64,
    /// Time from which the rows are averaged (s); default 0.
    #[serde(default)]
    pub start: f64,
    /// Particle-scale constants for the local `I`, `p*` and `Bo`; without them those
    /// fields are `NaN`.
    #[serde(default)]
    pub material: Option<crate::cg::Material>,
    /// Whether every sample's particles, contacts and box are also stored under
    /// `fields/`, so that `rheodem cg` can coarse-grain the run again with another kernel,
    /// width or grid (about 0.3 kB per particle and per sample); default false.
    #[serde(default)]
    pub records: bool,
}

/// The grid of [`FieldsSpec`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FieldGrid {
    /// Slabs normal to one axis.
    #[default]
    Slabs,
    /// Cells of a Cartesian grid over the box.
    Cartesian,
}

fn default_axis() -> String {
    "y".into()
}

fn default_kernel() -> crate::cg::KernelShape {
    crate::cg::KernelShape::Lucy
}

/// Proportional control of `σ_yy` (docs/model.md §5):
/// `L̇_y/L_y = (σ_yy − target)/(modulus · time)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StressControlSpec {
    /// Target `σ_yy` (Pa), positive.
    pub target: f64,
    /// Contact modulus `k_n / d_p` (Pa).
    pub modulus: f64,
    /// Relaxation time `τ` (s).
    pub time: f64,
}

fn default_seed() -> u64 {
    1
}

/// The simulation box.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DomainSpec {
    /// Lower corner (m); default the origin.
    #[serde(default, deserialize_with = "three")]
    pub lo: [f64; 3],
    /// Edge lengths (m). May be omitted when a packing file gives its box edge.
    #[serde(default, deserialize_with = "three_opt")]
    pub size: Option<[f64; 3]>,
    /// Periodicity of `x`, `y`, `z`.
    #[serde(default, deserialize_with = "three")]
    pub periodic: [bool; 3],
    /// Lees-Edwards shear rate `γ̇` (1/s): shear along `x`, gradient `y`, switched on after
    /// the preparation with the affine profile `v_x += γ̇ (y − lo_y)` (in the lab frame;
    /// under affine drag the box moves the particles with it) (needs `x`, `y` periodic).
    #[serde(default)]
    pub shear_rate: Option<f64>,
    /// The dynamics of the sheared box (docs/model.md §4.3–4.5): `"lab"` (the default),
    /// `"peculiar-contacts"` or `"affine-drag"`. The older boolean key `peculiar_contacts`
    /// is read as `"peculiar-contacts"` (true) or `"lab"` (false).
    #[serde(default, alias = "peculiar_contacts")]
    pub shear_dynamics: ShearDynamics,
}

/// A material.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpeciesSpec {
    /// Name used to refer to it.
    pub name: String,
    /// Density (kg/m³), positive.
    pub density: f64,
    /// Young's modulus `E` (Pa), which a `hertz` normal law takes where it gives none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub youngs_modulus: Option<f64>,
    /// Poisson's ratio `ν`, which a `hertz` normal law takes where it gives none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub poisson_ratio: Option<f64>,
    /// Restitution coefficient `e`, which a `hertz` normal law takes where it gives none
    /// (a pair of species mixes `√(e_i e_j)`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub restitution: Option<f64>,
}

/// The contact law of a species pair (or the default one).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// The pair this law applies to; omitted for the default law.
    #[serde(default)]
    pub species: Option<[String; 2]>,
    /// Normal force.
    pub normal: NormalSpec,
    /// Sliding friction; omitted for frictionless contacts.
    #[serde(default)]
    pub friction: Option<ResistanceSpec>,
    /// Rolling resistance; omitted for none.
    #[serde(default)]
    pub rolling: Option<ResistanceSpec>,
    /// Torsion resistance; omitted for none.
    #[serde(default)]
    pub torsion: Option<ResistanceSpec>,
    /// Adhesive law by name with its parameters (docs/model.md §2.4–2.6); omitted for
    /// none.
    #[serde(default)]
    pub adhesion: Option<LawSpec>,
}

/// A spring with history (friction, rolling, torsion): its law's name from the registry
/// (`law`, default `linear`, the spring–dashpot–Coulomb resistance) and that law's keys.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ResistanceSpec {
    /// The spring law's name (`linear`, the default; see `rheodem contact laws`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub law: Option<String>,
    /// Spring stiffness (N/m); or give `stiffness_ratio`.
    #[serde(default)]
    pub stiffness: Option<f64>,
    /// Spring stiffness as a fraction of `k_n` (the paper: 2/7).
    #[serde(default)]
    pub stiffness_ratio: Option<f64>,
    /// Fixed dashpot coefficient (kg/s).
    #[serde(default)]
    pub damping: Option<f64>,
    /// Dashpot as a fraction of the normal damping (the paper: 2/7).
    #[serde(default)]
    pub damping_ratio: Option<f64>,
    /// Mass-proportional dashpot `γ̂ m_ij` (1/s).
    #[serde(default)]
    pub damping_per_mass: Option<f64>,
    /// Coulomb coefficient used for both static and dynamic limits.
    #[serde(default)]
    pub mu: Option<f64>,
    /// Static Coulomb coefficient (with `mu_dynamic`, instead of `mu`).
    #[serde(default)]
    pub mu_static: Option<f64>,
    /// Dynamic Coulomb coefficient (≤ `mu_static`).
    #[serde(default)]
    pub mu_dynamic: Option<f64>,
}

/// How a particle moves.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum MotionSpec {
    /// Integrated.
    #[default]
    Free,
    /// Never moves (wall particle).
    Fixed,
    /// Rotates rigidly (wall particle).
    Rotating {
        /// A point on the axis (m).
        #[serde(deserialize_with = "three")]
        center: [f64; 3],
        /// Axis direction (normalised on use).
        #[serde(deserialize_with = "three")]
        axis: [f64; 3],
        /// Angular velocity (rad/s).
        omega: f64,
    },
}

/// One explicitly given sphere.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereSpec {
    /// Radius (m), positive.
    pub radius: f64,
    /// Centre (m).
    #[serde(deserialize_with = "three")]
    pub position: [f64; 3],
    /// Velocity (m/s).
    #[serde(default, deserialize_with = "three")]
    pub velocity: [f64; 3],
    /// Angular velocity (rad/s).
    #[serde(default, deserialize_with = "three")]
    pub angular_velocity: [f64; 3],
}

/// A group of particles.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ParticleGroup {
    /// Spheres listed one by one.
    Explicit {
        /// Species name.
        species: String,
        /// Motion of every sphere of the group.
        #[serde(default)]
        motion: MotionSpec,
        /// The spheres.
        spheres: Vec<SphereSpec>,
    },
    /// `count` polydisperse spheres placed at random without overlap.
    Random {
        /// Species name.
        species: String,
        /// Number of spheres, ≥ 1.
        #[serde(deserialize_with = "whole_count")]
        count: usize,
        /// Mean diameter `d_p` (m).
        mean_diameter: f64,
        /// Width ratio `w = r_max / r_min` ≥ 1; radii uniform in `[r_min, w r_min]`.
        #[serde(default = "one")]
        polydispersity: f64,
        /// Standard deviation of each initial velocity component (m/s).
        #[serde(default)]
        velocity_spread: f64,
    },
    /// Spheres read from a file of `diameter x y z` rows (path relative to the scenario).
    File {
        /// Species name.
        species: String,
        /// Path of the packing file.
        path: String,
        /// Factor applied to every length of the file (e.g. 2.2e-3 for a file in diameters).
        #[serde(default = "one")]
        length_scale: f64,
        /// Motion of every sphere of the group.
        #[serde(default)]
        motion: MotionSpec,
    },
    /// A rough wall: a square lattice of equal spheres covering the parallelogram
    /// `origin + s·edge_a + t·edge_b`, `s, t ∈ [0, 1]`.
    Lattice {
        /// Species name.
        species: String,
        /// Corner of the parallelogram (m).
        #[serde(deserialize_with = "three")]
        origin: [f64; 3],
        /// First edge (m).
        #[serde(deserialize_with = "three")]
        edge_a: [f64; 3],
        /// Second edge (m).
        #[serde(deserialize_with = "three")]
        edge_b: [f64; 3],
        /// Sphere radius (m).
        radius: f64,
        /// Centre-to-centre spacing (m); default one diameter.
        #[serde(default)]
        spacing: Option<f64>,
        /// Motion of every sphere (default fixed).
        #[serde(default = "fixed")]
        motion: MotionSpec,
    },
}

fn one() -> f64 {
    1.0
}

fn fixed() -> MotionSpec {
    MotionSpec::Fixed
}

/// An infinite planar wall.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallSpec {
    /// A point on the plane (m).
    #[serde(deserialize_with = "three")]
    pub point: [f64; 3],
    /// Normal pointing towards the particles (normalised on use).
    #[serde(deserialize_with = "three")]
    pub normal: [f64; 3],
    /// Species of the wall material.
    pub species: String,
}

/// Isotropic compression of a periodic packing before the run: the box shrinks affinely
/// (frictionless contacts meanwhile) until the target is reached, then the packing relaxes
/// with the scenario's contact laws.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PreparationSpec {
    /// Target volume fraction (0, 0.74).
    #[serde(default)]
    pub volume_fraction: Option<f64>,
    /// Target mean stress `tr σ / 3` (Pa).
    #[serde(default)]
    pub pressure: Option<f64>,
    /// Compression strain per contact time `t_c` (default 2·10⁻³).
    #[serde(default)]
    pub strain_per_contact_time: Option<f64>,
    /// Relaxation after compression, in contact times `t_c` (default 200).
    #[serde(default)]
    pub relax_contact_times: Option<f64>,
}

/// Run length and time step. Give exactly one of `duration` and `steps`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSpec {
    /// Simulated time (s).
    #[serde(default)]
    pub duration: Option<f64>,
    /// Number of steps.
    #[serde(default)]
    pub steps: Option<u64>,
    /// Time step (s); at most `t_c / 10`. Default `t_c · dt_fraction`.
    #[serde(default)]
    pub dt: Option<f64>,
    /// Time step as a fraction of the shortest contact time (default 1/50, at most 1/10).
    #[serde(default)]
    pub dt_fraction: Option<f64>,
    /// Largest displacement of a free particle per step, relative to the mean flow, as a
    /// fraction of the smallest radius (default 0.2); the run stops beyond it.
    #[serde(default)]
    pub max_displacement: Option<f64>,
    /// Largest overlap of a contact as a fraction of the pair's smaller radius (default
    /// 1); the run stops beyond it.
    #[serde(default)]
    pub max_overlap: Option<f64>,
}

/// How often to write each output, as a count over the run (at least 1 each).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Rows of the time series (default 200).
    #[serde(default = "default_rows")]
    pub timeseries_rows: u64,
    /// VTK snapshots (default 20; 0 for none).
    #[serde(default = "default_snapshots")]
    pub snapshots: u64,
    /// Checkpoints (default 10; 0 for none but the final one).
    #[serde(default = "default_checkpoints")]
    pub checkpoints: u64,
}

fn default_rows() -> u64 {
    200
}
fn default_snapshots() -> u64 {
    20
}
fn default_checkpoints() -> u64 {
    10
}

impl Default for OutputSpec {
    fn default() -> Self {
        OutputSpec {
            timeseries_rows: default_rows(),
            snapshots: default_snapshots(),
            checkpoints: default_checkpoints(),
        }
    }
}

/// Neighbour-list settings.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NeighborSpec {
    /// Verlet skin (m); default 0.2 × the smallest particle diameter.
    #[serde(default)]
    pub skin: Option<f64>,
}

/// Deserialises exactly three components: serde's fixed-size arrays stop reading after the
/// third and would silently drop a fourth (`size = [0.02, 0.02, 0.02, 0.02]`).
fn three<'de, D, T>(d: D) -> Result<[T; 3], D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    let v = Vec::<T>::deserialize(d)?;
    let n = v.len();
    v.try_into()
        .map_err(|_| serde::de::Error::invalid_length(n, &"exactly 3 components"))
}

/// Deserialises a count of spheres, with an error that names the key: inside a tagged
/// group the parser's own message would point at the `[[particles]]` header instead.
fn whole_count<'de, D>(d: D) -> Result<usize, D::Error>
where
    D: serde::Deserializer<'de>,
{
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Written {
        Integer(i64),
        Float(f64),
        Other(toml::Value),
    }
    let v = match Written::deserialize(d)? {
        Written::Integer(n) => n as f64,
        Written::Float(x) => x,
        Written::Other(other) => {
            return Err(serde::de::Error::custom(format!(
                "`count` = {other}: must be a whole number of spheres, at least 1"
            )));
        }
    };
    // Zero and too large counts are refused by the build, which names the full key.
    if v.fract() == 0.0 && v >= 0.0 && v <= usize::MAX as f64 {
        Ok(v as usize)
    } else {
        Err(serde::de::Error::custom(format!(
            "`count` = {v}: must be a whole number of spheres, at least 1"
        )))
    }
}

/// [`three`] for an optional value.
fn three_opt<'de, D, T>(d: D) -> Result<Option<[T; 3]>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    #[derive(Deserialize)]
    #[serde(bound = "T: Deserialize<'de>")]
    struct Three<T>(#[serde(deserialize_with = "three")] [T; 3]);
    Ok(Option::<Three<T>>::deserialize(d)?.map(|t| t.0))
}
