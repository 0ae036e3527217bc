//! The stress-controlled simple shear box, the "rheometer" (docs/model.md §6; Shi et al.
//! 2020, Sect. 2.1.1): N polydisperse spheres in a Lees-Edwards box sheared at `γ̇` along `x` with
//! gradient `y`, `σ_yy` held at `p` by letting `L_y` breathe.
//!
//! The user gives the dimensionless controls (docs/model.md §6.2) — `μ_p`, `I`, `p*`, `Bo`, the
//! cohesion law — and optionally the material; this module derives `p = p* k_n / d_p`,
//! `γ̇ = I sqrt(p/ρ_p) / d_p`, `f_a^max = Bo p d_p²` and writes an ordinary
//! [`Scenario`] (so runs, checkpoints and outputs are those of any scenario).
//!
//! Preparation: the particles are inserted at random at φ ≈ 0.3 in a cubic periodic box,
//! compressed isotropically (frictionless, non-cohesive) until the mean stress reaches `p`,
//! relaxed for 50 contact times with the full contact law, then sheared from the affine
//! profile `v_x = γ̇ (y − lo_y)` under σ_yy control.

use crate::analysis::{Estimate, block_average, halves_agree};
use crate::cg::{FieldPoint, KernelShape, Material};
use crate::contact::{LawKind, LawSpec, NormalKind, Strength};
use crate::domain::ShearDynamics;
use crate::measure::Observables;
use crate::scenario::spec::*;
use crate::scenario::{ScenarioError, invalid};
use crate::setups::schema::{
    Field, Range, SetUpSchema, Values, check_table, given, overlay, table_of,
};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

fn default_range() -> f64 {
    0.225
}
fn default_diameter() -> f64 {
    2.2e-3
}
fn default_density() -> f64 {
    2000.0
}
fn default_stiffness() -> f64 {
    100.0
}
fn default_restitution() -> f64 {
    0.8
}
fn default_w() -> f64 {
    3.0
}
fn default_particles() -> usize {
    4096
}
fn default_strain() -> f64 {
    20.0
}
fn default_transient() -> f64 {
    5.0
}
fn default_control() -> f64 {
    40.0
}
fn default_seed() -> u64 {
    1
}
fn default_rows() -> f64 {
    50.0
}
fn default_snapshots() -> u64 {
    10
}
fn default_checkpoints() -> u64 {
    40
}
fn default_plastic_ratio() -> f64 {
    5.0
}
fn default_plasticity_depth() -> f64 {
    0.05
}

/// The normal law of a shear-box point.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoxNormal {
    /// The linear spring and dashpot `k_n δ + γ_n δ̇` (the papers').
    #[default]
    Linear,
    /// Luding's elasto-plastic law loading along `k_n` (docs/model.md §2.9), whose adhesive
    /// branch carries the point's cohesion.
    Luding,
}

/// A shear-box point: dimensionless controls and material.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShearBoxSpec {
    /// Particle friction coefficient `μ_p` (`μ_s = μ_d`), in [0, 10].
    pub mu_p: f64,
    /// Inertial number `I = γ̇ d_p / sqrt(p/ρ_p)`, in (0, 2].
    pub inertial: f64,
    /// Softness `p* = p d_p / k_n`, in (0, 0.2].
    pub softness: f64,
    /// Bond number `Bo = f_a^max / (p d_p²)`, in [0, 100].
    #[serde(default)]
    pub bond: f64,
    /// Adhesive law, by its registered name (`none`, `reversible`, `liquid_bridge`,
    /// `linear_irreversible`, …), at the point's strength: `f_a^max = Bo p d_p²` for the
    /// mean pair, rupture at `range · d_p`, `k_c^a = k_n` (ignored when `bond = 0`).
    #[serde(default)]
    pub cohesion: LawKind,
    /// Rupture distance of the irreversible laws in mean diameters, `S_c / d_p` (default
    /// 0.225, i.e. 75 nl at 2.2 mm).
    #[serde(default = "default_range")]
    pub range: f64,
    /// Mean diameter `d_p` (m).
    #[serde(default = "default_diameter")]
    pub diameter: f64,
    /// Density `ρ_p` (kg/m³).
    #[serde(default = "default_density")]
    pub density: f64,
    /// Normal stiffness `k_n` (N/m).
    #[serde(default = "default_stiffness")]
    pub stiffness: f64,
    /// Restitution coefficient `e`.
    #[serde(default = "default_restitution")]
    pub restitution: f64,
    /// Polydispersity `w = r_max / r_min`.
    #[serde(default = "default_w")]
    pub polydispersity: f64,
    /// Number of particles.
    #[serde(default = "default_particles")]
    pub particles: usize,
    /// Total shear strain `γ̇ T`.
    #[serde(default = "default_strain")]
    pub strain: f64,
    /// Strain before averaging starts.
    #[serde(default = "default_transient")]
    pub transient_strain: f64,
    /// Relaxation time of the `σ_yy` control in units of `t_k = sqrt(ρ_p d_p³ / k_n)`.
    #[serde(default = "default_control")]
    pub control_time: f64,
    /// Seed.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Time-series rows per unit strain.
    #[serde(default = "default_rows")]
    pub rows_per_strain: f64,
    /// VTK snapshots over the run.
    #[serde(default = "default_snapshots")]
    pub snapshots: u64,
    /// Checkpoints over the run.
    #[serde(default = "default_checkpoints")]
    pub checkpoints: u64,
    /// Shear dynamics (docs/model.md §4.3–4.5): `"lab"` (default), `"peculiar-contacts"`
    /// (lab dynamics, contacts without the mean-flow difference) or `"affine-drag"` (the
    /// source papers' code). The older boolean `peculiar_contacts` reads as the first two.
    #[serde(default, alias = "peculiar_contacts")]
    pub shear_dynamics: ShearDynamics,
    /// Slabs along `y` (the shear gradient) of the coarse-grained fields averaged over the
    /// steady-state window, written as `fields.csv` and `fields.vti`; 0 (default) for none.
    #[serde(default)]
    pub cg_slabs: usize,
    /// Kernel of the fields, `"lucy"` (default) or `"gaussian"`.
    #[serde(default = "default_cg_kernel")]
    pub cg_kernel: KernelShape,
    /// Kernel width of the fields in mean diameters (default 1).
    #[serde(default = "default_cg_width")]
    pub cg_width: f64,
    /// Whether the fields' samples are also stored (particles, contacts and box, under
    /// `fields/`) for `rheodem cg` to coarse-grain again; needs `cg_slabs` > 0.
    #[serde(default)]
    pub cg_records: bool,
    /// Normal law: `"linear"` (default) or `"luding"`, Luding's elasto-plastic law loading
    /// along `k_n`; with `Bo > 0` its adhesive stiffness `k_c` is set so that a contact
    /// loaded to the plastic limit pulls off with `f_a^max = Bo p d_p²` (the mean pair), and
    /// `cohesion` stays `none`.
    #[serde(default)]
    pub normal_law: BoxNormal,
    /// Luding's largest unloading stiffness in units of `k_n`, `k_p/k_n` (default 5).
    #[serde(default = "default_plastic_ratio")]
    pub plastic_ratio: f64,
    /// Luding's plasticity depth `φ_f` (default 0.05).
    #[serde(default = "default_plasticity_depth")]
    pub plasticity_depth: f64,
}

fn default_cg_kernel() -> KernelShape {
    KernelShape::Lucy
}

fn default_cg_width() -> f64 {
    1.0
}

impl SetUpSchema for ShearBoxSpec {
    const NAME: &'static str = "shear-box";
    const SUMMARY: &'static str = "Stress-controlled simple shear box at given (μ_p, I, p*, Bo): \
        steady-state φ, μ, Z, σ (Shi et al. 2020).";
    const FIELDS: &'static [Field] = &[
        Field::number(
            "mu_p",
            "",
            "Particle friction μ_p",
            Range::Closed(0.0, 10.0),
        )
        .required(),
        Field::number(
            "inertial",
            "",
            "Inertial number I = γ̇ d_p / sqrt(p/ρ_p)",
            Range::AboveUpTo(0.0, 2.0),
        )
        .required(),
        Field::number(
            "softness",
            "",
            "Softness p* = p d_p / k_n",
            Range::AboveUpTo(0.0, 0.2),
        )
        .required(),
        Field::number(
            "bond",
            "",
            "Bond number Bo = f_a^max / (p d_p²)",
            Range::Closed(0.0, 100.0),
        ),
        Field::adhesive_law(
            "cohesion",
            "Adhesive law at the point's strength (f_a^max = Bo p d_p², k_c = k_n), needed when Bo > 0",
        ),
        Field::number(
            "range",
            "",
            "Rupture distance of the irreversible laws S_c/d_p",
            Range::AboveUpTo(0.0, 2.0),
        ),
        Field::number("diameter", "m", "Mean diameter d_p", Range::Above(0.0)),
        Field::number("density", "kg/m³", "Density ρ_p", Range::Above(0.0)),
        Field::number(
            "stiffness",
            "N/m",
            "Normal stiffness k_n",
            Range::Above(0.0),
        ),
        Field::number(
            "restitution",
            "",
            "Restitution coefficient e",
            Range::AboveUpTo(0.0, 1.0),
        ),
        Field::number(
            "polydispersity",
            "",
            "Polydispersity w = r_max/r_min",
            Range::Closed(1.0, 20.0),
        ),
        Field::count(
            "particles",
            "Number of particles N",
            Range::Closed(16.0, 1e7),
        ),
        Field::number(
            "strain",
            "",
            "Total shear strain",
            Range::AboveUpTo(0.0, 1e6),
        ),
        Field::number(
            "transient_strain",
            "",
            "Strain before averaging",
            Range::AtLeast(0.0),
        )
        .note(", below the total strain"),
        Field::number(
            "control_time",
            "",
            "Relaxation time of the σ_yy control in units of t_k = sqrt(ρ_p d_p³/k_n)",
            Range::AboveUpTo(0.0, 1e6),
        ),
        Field::count("seed", "Seed of the random packing", Range::AtLeast(0.0))
            .note(" (at most 2⁶³ − 1, the range a TOML file holds)"),
        Field::number(
            "rows_per_strain",
            "",
            "Time-series rows per unit strain",
            Range::AboveUpTo(0.0, 1e6),
        ),
        Field::count(
            "snapshots",
            "VTK snapshots over the run",
            Range::AtLeast(0.0),
        ),
        Field::count(
            "checkpoints",
            "Checkpoints over the run",
            Range::AtLeast(0.0),
        ),
        Field::choice(
            "shear_dynamics",
            "Shear dynamics (docs/model.md §4.3–4.5; peculiar-contacts: lab dynamics, contacts \
             without the mean-flow difference; affine-drag: the source papers' code)",
            &["lab", "peculiar-contacts", "affine-drag"],
        ),
        Field::count(
            "cg_slabs",
            "Slabs along y of the coarse-grained fields averaged over the steady window \
             (fields.csv, fields.vti)",
            Range::Closed(0.0, 1e5),
        )
        .note("; 0 for none"),
        Field::choice("cg_kernel", "Kernel of the fields", &["lucy", "gaussian"]),
        Field::number(
            "cg_width",
            "",
            "Kernel width of the fields in mean diameters",
            Range::AboveUpTo(0.0, 10.0),
        ),
        Field::switch(
            "cg_records",
            "Also store the fields' samples (particles, contacts, box under fields/) for \
             `rheodem cg` to coarse-grain the run again; needs cg_slabs > 0",
        ),
        Field::choice(
            "normal_law",
            "Normal law (luding: elasto-plastic, loading along k_n; with Bo > 0 its \
             adhesive branch pulls a contact loaded to the plastic limit off with \
             f_a^max = Bo p d_p², and cohesion stays none)",
            &["linear", "luding"],
        ),
        Field::number(
            "plastic_ratio",
            "",
            "Luding's largest unloading stiffness k_p/k_n",
            Range::AboveUpTo(1.0, 1000.0),
        ),
        Field::number(
            "plasticity_depth",
            "",
            "Luding's plasticity depth φ_f",
            Range::AboveUpTo(0.0, 1.0),
        ),
    ];

    fn defaults() -> toml::Table {
        // The defaults are serde's: a spec with only the required controls given.
        let controls: toml::Table = [("mu_p", 0.5), ("inertial", 0.1), ("softness", 0.01)]
            .into_iter()
            .map(|(k, v)| (k.to_string(), toml::Value::Float(v)))
            .collect();
        let required = ShearBoxSpec::from_table(controls).expect("the three controls make a spec");
        let mut t = table_of(&required);
        for f in Self::FIELDS.iter().filter(|f| f.required) {
            t.remove(f.key);
        }
        t
    }

    /// The config file (`base`) must be valid on its own: an option overriding a bad value
    /// does not hide it (its values are checked, completed by the options only where it
    /// has none).
    fn from_values(mut base: toml::Table, values: &Values) -> Result<ShearBoxSpec, ScenarioError> {
        if given(values, "shear_dynamics").is_some() {
            // The parameter replaces the older spelling of a config file.
            base.remove("peculiar_contacts");
        }
        let parse = |t: toml::Table| {
            ShearBoxSpec::from_table(t).map_err(|e| ScenarioError::Parse(e.to_string()))
        };
        let options = overlay(Self::FIELDS, toml::Table::new(), values)?;
        if !base.is_empty() {
            let mut probe = base.clone();
            for (k, v) in &options {
                probe.entry(k.clone()).or_insert_with(|| v.clone());
            }
            parse(probe)?.derive()?;
        }
        base.extend(options);
        let spec = parse(base)?;
        spec.derive()?;
        Ok(spec)
    }
}

/// SI values derived from a [`ShearBoxSpec`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Derived {
    /// Target `σ_yy = p` (Pa).
    pub pressure: f64,
    /// Shear rate `γ̇` (1/s).
    pub shear_rate: f64,
    /// Maximum adhesive force `f_a^max` (N).
    pub max_force: f64,
    /// Rupture distance `S_c` (m) of the irreversible laws.
    pub rupture_distance: f64,
    /// `t_k = sqrt(ρ d³/k_n)` (s).
    pub stiffness_time: f64,
    /// `t_p = d sqrt(ρ/p)` (s).
    pub pressure_time: f64,
    /// Run duration (s).
    pub duration: f64,
}

/// Smallest and largest radius (m) of the distribution with mean diameter `d` (m) and
/// polydispersity `w` (radii uniform in `[d/(1+w), w d/(1+w)]`, as
/// [`crate::generate::polydisperse_radii`] draws them).
fn radius_bounds(d: f64, w: f64) -> (f64, f64) {
    (d / (1.0 + w), w * d / (1.0 + w))
}

/// Mean cubed radius (m³) of that distribution.
fn mean_radius_cubed(d: f64, w: f64) -> f64 {
    let (r1, r2) = radius_bounds(d, w);
    if r2 > r1 {
        (r2.powi(4) - r1.powi(4)) / (4.0 * (r2 - r1))
    } else {
        r1.powi(3)
    }
}

impl ShearBoxSpec {
    /// A spec from a TOML table (a config file, a sweep point, command-line overrides);
    /// the error names the offending key.
    pub fn from_table(table: toml::Table) -> Result<ShearBoxSpec, toml::de::Error> {
        toml::Value::Table(table).try_into()
    }

    /// Validates the controls and derives the SI values.
    ///
    /// `p = p* k_n / d_p`, `γ̇ = I sqrt(p / ρ_p) / d_p`, `f_a^max = Bo p d_p²`:
    ///
    /// ```
    /// use rheodem::setups::shear_box::ShearBoxSpec;
    ///
    /// let spec: ShearBoxSpec = toml::from_str(
    ///     "mu_p = 0.5\ninertial = 0.02\nsoftness = 0.01\nbond = 1.0\ncohesion = \"reversible\"",
    /// )?;
    /// let dv = spec.derive()?;
    /// let (d, rho, k_n) = (2.2e-3, 2000.0, 100.0); // the seeds' material, the defaults
    /// let p = 0.01 * k_n / d;
    /// assert!((dv.pressure / p - 1.0).abs() < 1e-14);
    /// assert!((dv.shear_rate / (0.02 * (p / rho).sqrt() / d) - 1.0).abs() < 1e-14);
    /// assert!((dv.max_force / (1.0 * p * d * d) - 1.0).abs() < 1e-14);
    /// assert!((dv.duration * dv.shear_rate / spec.strain - 1.0).abs() < 1e-14);
    /// // Out-of-range controls are refused with the key.
    /// let bad = ShearBoxSpec { inertial: 3.0, ..spec };
    /// assert!(bad.derive().unwrap_err().to_string().contains("inertial"));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn derive(&self) -> Result<Derived, ScenarioError> {
        check_table(Self::FIELDS, &table_of(self))?;
        let (i, ps, bo, range) = (self.inertial, self.softness, self.bond, self.range);
        let (d, rho, k, strain) = (self.diameter, self.density, self.stiffness, self.strain);
        if self.transient_strain >= strain {
            return Err(invalid(
                "transient_strain",
                self.transient_strain,
                format!("must lie in [0, strain = {strain})"),
            ));
        }
        if self.cg_records && self.cg_slabs == 0 {
            return Err(invalid(
                "cg_records",
                true,
                "stores the fields' samples: it needs cg_slabs > 0",
            ));
        }
        match self.normal_law {
            BoxNormal::Linear if bo > 0.0 && self.cohesion == LawKind::None => {
                return Err(invalid(
                    "cohesion",
                    "\"none\"",
                    "a positive bond number needs a cohesion law (reversible, liquid_bridge, linear_irreversible), or normal_law = \"luding\"",
                ));
            }
            BoxNormal::Luding if self.cohesion != LawKind::None => {
                return Err(invalid(
                    "cohesion",
                    format!("\"{}\"", self.cohesion),
                    "with normal_law = \"luding\" the law's own adhesive branch carries Bo: leave cohesion = none",
                ));
            }
            _ => {}
        }
        // Lees-Edwards needs the sheared box at least three neighbour cells wide; a cell
        // holds the largest pair plus the attraction range and the skin (0.1 d_p). The
        // box edge is estimated at φ = 0.75, above every steady state of Shi et al. 2020.
        let (_, r_max) = radius_bounds(d, self.polydispersity);
        let reach = if self.cohesion.forms_bridges() {
            range * d
        } else {
            0.0
        };
        let cell = 2.0 * r_max + reach + 0.1 * d;
        let per_particle = 4.0 / 3.0 * PI * mean_radius_cubed(d, self.polydispersity) / 0.75;
        let fewest = ((3.0 * cell).powi(3) / per_particle).ceil();
        if (self.particles as f64) < fewest {
            return Err(invalid(
                "particles",
                self.particles,
                format!(
                    "must be at least {fewest} with polydispersity {} and this cohesion range: \
                     the sheared box must stay three neighbour cells (largest pair + range + \
                     skin) wide",
                    self.polydispersity
                ),
            ));
        }
        let p = ps * k / d;
        let shear_rate = i * (p / rho).sqrt() / d;
        if self.normal_law == BoxNormal::Luding {
            self.luding_adhesive_stiffness(bo * p * d * d)?;
        }
        Ok(Derived {
            pressure: p,
            shear_rate,
            max_force: bo * p * d * d,
            rupture_distance: range * d,
            stiffness_time: (rho * d.powi(3) / k).sqrt(),
            pressure_time: d * (rho / p).sqrt(),
            duration: strain / shear_rate,
        })
    }

    /// Luding's adhesive stiffness `k_c` (N/m) that pulls a contact of the mean pair
    /// (`r = d_p/2`) loaded to the plastic limit off with `f` (N): at the limit the
    /// unloading line has slope `k_p` and meets the adhesive branch at
    /// `f = k_c (k_p − k_1) δ_max^p/(k_p + k_c)` with `(k_p − k_1) δ_max^p = k_p φ_f r`, so
    /// `k_c = f k_p/(k_p φ_f r − f)`; an error when `f` is beyond what any `k_c` gives.
    pub fn luding_adhesive_stiffness(&self, f: f64) -> Result<f64, ScenarioError> {
        let k_p = self.plastic_ratio * self.stiffness;
        let reach = k_p * self.plasticity_depth * 0.5 * self.diameter;
        if f >= reach {
            return Err(invalid(
                "bond",
                self.bond,
                format!(
                    "Luding's law pulls off with less than k_p φ_f d_p/2 = {reach:.4e} N; \
                     Bo p d_p² = {f:.4e} N needs a larger plastic_ratio or plasticity_depth"
                ),
            ));
        }
        Ok(f * k_p / (reach - f))
    }

    /// The scenario that runs this point.
    pub fn scenario(&self) -> Result<Scenario, ScenarioError> {
        let dv = self.derive()?;
        let d = self.diameter;
        let w = self.polydispersity;
        let solid = self.particles as f64 * 4.0 / 3.0 * PI * mean_radius_cubed(d, w);
        // The random insertion accepts at most φ = 0.35 of the radii actually drawn; their
        // volume scatters about `solid` by ~1.1/sqrt(N) relative at w = 20, so small boxes
        // start looser (φ = 0.2 keeps N = 16 below the limit at 2.7 standard deviations).
        let loose = if self.particles >= 1000 { 0.3 } else { 0.2 };
        let edge = (solid / loose).cbrt();
        // The law at the point's strength: `f_a^max = Bo p d_p²` for the mean pair, the
        // rupture distance `range · d_p`, `k_c^a = k_n` (Shi et al. 2020).
        let strength = Strength {
            max_force: dv.max_force,
            rupture_distance: dv.rupture_distance,
            normal_stiffness: self.stiffness,
            mean_diameter: d,
        };
        let adhesion = (self.bond > 0.0 && self.normal_law == BoxNormal::Linear)
            .then(|| LawSpec::new(self.cohesion, self.cohesion.at_strength(&strength)));
        let normal = match self.normal_law {
            BoxNormal::Linear => NormalSpec::new(
                NormalKind::Linear,
                [
                    ("stiffness", self.stiffness),
                    ("restitution", self.restitution),
                ],
            ),
            BoxNormal::Luding => NormalSpec::new(
                NormalKind::Luding,
                [
                    ("stiffness", self.stiffness),
                    ("max_stiffness", self.plastic_ratio * self.stiffness),
                    (
                        "adhesive_stiffness",
                        self.luding_adhesive_stiffness(dv.max_force)?,
                    ),
                    ("plasticity_depth", self.plasticity_depth),
                    ("restitution", self.restitution),
                ],
            ),
        };
        let friction = (self.mu_p > 0.0).then(|| ResistanceSpec {
            law: None,
            stiffness: None,
            stiffness_ratio: Some(2.0 / 7.0),
            damping: None,
            damping_ratio: Some(2.0 / 7.0),
            damping_per_mass: None,
            mu: Some(self.mu_p),
            mu_static: None,
            mu_dynamic: None,
        });
        let rows = (self.rows_per_strain * self.strain).ceil().max(1.0) as u64;
        Ok(Scenario {
            title: Some(format!(
                "shear box: mu_p = {}, I = {}, p* = {}, Bo = {} ({:?}, {:?} normal law), w = {}, N = {}",
                self.mu_p,
                self.inertial,
                self.softness,
                self.bond,
                self.cohesion,
                self.normal_law,
                w,
                self.particles
            )),
            seed: self.seed,
            domain: DomainSpec {
                lo: [0.0; 3],
                size: Some([edge; 3]),
                periodic: [true; 3],
                shear_rate: Some(dv.shear_rate),
                shear_dynamics: self.shear_dynamics,
            },
            species: vec![SpeciesSpec {
                name: "grain".into(),
                density: self.density,
                youngs_modulus: None,
                poisson_ratio: None,
                restitution: None,
            }],
            contacts: vec![ContactSpec {
                species: None,
                normal,
                friction,
                rolling: None,
                torsion: None,
                adhesion,
            }],
            particles: vec![ParticleGroup::Random {
                species: "grain".into(),
                count: self.particles,
                mean_diameter: d,
                polydispersity: w,
                velocity_spread: 0.0,
            }],
            walls: Vec::new(),
            gravity: [0.0; 3],
            preparation: Some(PreparationSpec {
                volume_fraction: None,
                pressure: Some(dv.pressure),
                strain_per_contact_time: None,
                relax_contact_times: Some(50.0),
            }),
            run: RunSpec {
                duration: Some(dv.duration),
                steps: None,
                dt: None,
                dt_fraction: None,
                max_displacement: None,
                max_overlap: None,
            },
            output: OutputSpec {
                timeseries_rows: rows,
                snapshots: self.snapshots,
                checkpoints: self.checkpoints,
            },
            neighbor: NeighborSpec::default(),
            stress_control: Some(StressControlSpec {
                target: dv.pressure,
                modulus: self.stiffness / d,
                time: self.control_time * dv.stiffness_time,
            }),
            fields: (self.cg_slabs > 0).then(|| FieldsSpec {
                grid: FieldGrid::Slabs,
                axis: "y".into(),
                bins: vec![self.cg_slabs],
                kernel: self.cg_kernel,
                width: self.cg_width * d,
                start: self.transient_strain / dv.shear_rate,
                material: Some(Material {
                    diameter: d,
                    particle_density: self.density,
                    stiffness: self.stiffness,
                    max_adhesion: dv.max_force,
                }),
                records: self.cg_records,
            }),
        })
    }
}

/// Steady-state averages of a shear-box run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SteadyState {
    /// Whether the averaging window looks stationary (see [`steady_state`]).
    pub steady: bool,
    /// Why not, when not.
    pub note: String,
    /// Strain window averaged over.
    pub strain_window: [f64; 2],
    /// Volume fraction φ.
    pub volume_fraction: Estimate,
    /// Macroscopic friction `μ = |σ_xy| / σ_yy`.
    pub friction: Estimate,
    /// Coordination number `Z`.
    pub coordination: Estimate,
    /// Coordination number without rattlers.
    #[serde(default)]
    pub coordination_without_rattlers: Option<Estimate>,
    /// `σ_yy` (Pa).
    pub sigma_yy: Estimate,
    /// `|σ_xy|` (Pa).
    pub shear_stress: Estimate,
    /// Mean stress `tr σ / 3` (Pa).
    pub mean_stress: Estimate,
    /// Granular temperature (m²/s²).
    pub granular_temperature: Estimate,
    /// Fraction of sliding contacts.
    pub sliding_fraction: Estimate,
    /// Open bridges (attracting pairs apart) per particle.
    pub bridges_per_particle: Estimate,
    /// `I` from the measured `σ_yy`.
    pub inertial_measured: f64,
    /// `p*` from the measured `σ_yy`.
    pub softness_measured: f64,
    /// `Bo` from the measured `σ_yy`.
    pub bond_measured: f64,
    /// How evenly the slabs of the fields (`cg_slabs`) shared the shear over the window;
    /// absent without fields.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slab_rates: Option<SlabRates>,
}

/// The local strain rate of the slabs of a run's time-averaged fields, in units of the
/// imposed `γ̇`: 1 in every slab for homogeneous shear, spread out when the shear
/// localises (docs/model.md §6.1).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SlabRates {
    /// Number of slabs.
    pub slabs: usize,
    /// Smallest local rate over `γ̇`.
    pub min: f64,
    /// Largest local rate over `γ̇`.
    pub max: f64,
    /// Root-mean-square deviation of the local rates from `γ̇`, over `γ̇`.
    pub rms_deviation: f64,
}

impl SlabRates {
    /// The spread of `points`' strain rates (1/s) about `shear_rate` (1/s); `None` without
    /// points or with a non-finite rate.
    pub fn of(points: &[FieldPoint], shear_rate: f64) -> Option<SlabRates> {
        let rates: Vec<f64> = points.iter().map(|p| p.strain_rate / shear_rate).collect();
        if rates.is_empty() || rates.iter().any(|r| !r.is_finite()) {
            return None;
        }
        let n = rates.len() as f64;
        Some(SlabRates {
            slabs: rates.len(),
            min: rates.iter().copied().fold(f64::INFINITY, f64::min),
            max: rates.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            rms_deviation: (rates.iter().map(|r| (r - 1.0).powi(2)).sum::<f64>() / n).sqrt(),
        })
    }
}

/// Averages the rows past `transient_strain` (the strain of a row is `γ̇ t`). Steady when
/// at least 2 strain units are averaged and, for both φ and μ, the two halves of the window
/// agree within three combined standard errors (or within 0.2 % for φ and 2 % for μ).
pub fn steady_state(
    rows: &[Observables],
    spec: &ShearBoxSpec,
    dv: &Derived,
) -> Option<SteadyState> {
    let window: Vec<&Observables> = rows
        .iter()
        .filter(|o| o.time * dv.shear_rate >= spec.transient_strain)
        .collect();
    if window.len() < 8 {
        return None;
    }
    let series =
        |f: &dyn Fn(&Observables) -> f64| window.iter().map(|o| f(o)).collect::<Vec<f64>>();
    let phi = series(&|o| o.volume_fraction);
    let mu = series(&|o| {
        if o.stress[1][1] != 0.0 {
            o.stress[0][1].abs() / o.stress[1][1]
        } else {
            0.0
        }
    });
    let est = |x: &[f64]| block_average(x).expect("window has ≥ 8 rows");
    let first = window[0].time * dv.shear_rate;
    let last = window[window.len() - 1].time * dv.shear_rate;
    let sigma_yy = est(&series(&|o| o.stress[1][1]));
    let mut notes = Vec::new();
    if last - first < 2.0 {
        notes.push(format!(
            "only {:.2} strain units past the transient",
            last - first
        ));
    }
    if !halves_agree(&phi, 2e-3) {
        notes.push("volume fraction still drifting".to_string());
    }
    if !halves_agree(&mu, 2e-2) {
        notes.push("macroscopic friction still drifting".to_string());
    }
    let p = sigma_yy.mean;
    if p <= 0.0 {
        notes.push("mean σ_yy not compressive: I and Bo not measurable (reported as 0)".into());
    }
    Some(SteadyState {
        steady: notes.is_empty(),
        note: notes.join("; "),
        strain_window: [first, last],
        volume_fraction: est(&phi),
        friction: est(&mu),
        coordination: est(&series(&|o| o.coordination)),
        coordination_without_rattlers: block_average(&series(&|o| o.coordination_without_rattlers)),
        sigma_yy,
        shear_stress: est(&series(&|o| o.stress[0][1].abs())),
        mean_stress: est(&series(&|o| o.mean_stress())),
        granular_temperature: est(&series(&|o| o.granular_temperature)),
        sliding_fraction: est(&series(&|o| o.sliding_fraction)),
        bridges_per_particle: est(&series(&|o| o.bridges_per_particle)),
        inertial_measured: if p > 0.0 {
            dv.shear_rate * spec.diameter / (p / spec.density).sqrt()
        } else {
            0.0
        },
        softness_measured: p * spec.diameter / spec.stiffness,
        bond_measured: if p > 0.0 {
            dv.max_force / (p * spec.diameter * spec.diameter)
        } else {
            0.0
        },
        slab_rates: None,
    })
}
