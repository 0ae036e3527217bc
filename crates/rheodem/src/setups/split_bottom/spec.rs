//! What a split-bottom run is given: the spec (every key with its default, in SI units),
//! its checks, the resolved geometry of the cell, its dimensionless groups and the loose
//! random filling of the mould.

use crate::cg::KernelShape;
use crate::contact::{ContactLaw, Damping, LawKind, LawSpec, LinearNormal, Resistance, Spring};
use crate::generate::Rng;
use crate::memory::{self, Bytes};
use crate::neighbor::min_wedge_angle;
use crate::scenario::{ScenarioError, invalid, law_error};
use crate::setups::schema::{SetUpSchema, check_table, table_of};
use glam::{DMat3, DVec3};
use rand::RngExt;
use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

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
    pub cohesion: LawSpec,
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
            cohesion: LawSpec::default(),
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

/// Largest number of particles a cell may hold (the limit of scenario files).
const MAX_PARTICLES: usize = 50_000_000;

/// Volume fraction assumed for the settled packing when counting the particles to insert.
const SETTLED_FRACTION: f64 = 0.62;
/// Volume fraction of the loose random filling.
const FILL_FRACTION: f64 = 0.25;

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
        let mut spec: SplitBottomSpec = serde_path_to_error::deserialize(toml::Value::Table(table))
            .map_err(|e| ScenarioError::Parse(format!("key `{}`: {}", e.path(), e.inner())))?;
        // The law's defaults written out as for a config file (a Willett table without
        // its contact angle or volume), so that a study point and a config agree.
        spec.cohesion = crate::setups::law_options::cohesion(spec.cohesion, &Vec::new())?;
        Ok(spec)
    }

    /// The spec as TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }

    /// The contact law of every pair (particles and walls).
    ///
    /// # Errors
    /// [`ScenarioError`] naming the `cohesion` parameter its law refuses.
    pub fn law(&self) -> Result<ContactLaw, ScenarioError> {
        let damping = Damping {
            fixed: self.damping,
            ..Damping::NONE
        };
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
                stiffness: self.stiffness_ratio * self.stiffness,
                damping: damping.scaled(self.damping_ratio),
                mu_static: self.friction,
                mu_dynamic: self.friction,
            }
            .into(),
            rolling: Spring::NONE,
            torsion: Spring::NONE,
            adhesion,
        })
    }

    /// Checks the adhesive law's values, and that its interaction range (the rupture
    /// distance `S_c`) stays below the mean diameter `d` (m): a longer range lets a bridge
    /// reach past a particle's neighbours, outside the laws' validity (docs/model.md §2.5).
    fn check_cohesion(&self, d: f64) -> Result<(), ScenarioError> {
        // The values against the bounds the law declares in the registry.
        let range = self.law()?.range();
        // The key that sets the range: the bridge volume, or the linear laws' stiffness
        // (or the range given instead of it).
        let Some(range_key) = ["volume", "stiffness", "range"]
            .into_iter()
            .find_map(|k| self.cohesion.value(k).map(|v| (format!("cohesion.{k}"), v)))
        else {
            return Ok(());
        };
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
        check_table(Self::FIELDS, &table_of(self))?;
        let (scale, d) = (self.scale, self.diameter);
        self.check_cohesion(d)?;
        if self.average_from >= self.duration {
            return Err(invalid(
                "average_from",
                self.average_from,
                format!("must be in [0, duration = {})", self.duration),
            ));
        }
        let inner = self.inner_radius * scale;
        let outer = self.outer_radius * scale;
        let split = self.split_radius * scale;
        let height = self.height * scale;
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
        let range = self.law()?.range();
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
        let surface_tension = match self.cohesion.law {
            LawKind::LiquidBridge | LawKind::Rabinovich => {
                self.cohesion.value("surface_tension").unwrap_or(0.0)
            }
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

/// The mean of `r³` over radii uniform in `[r1, r2]` (m³).
pub(crate) fn mean_radius_cubed(r1: f64, r2: f64) -> f64 {
    if r2 > r1 {
        (r2.powi(4) - r1.powi(4)) / (4.0 * (r2 - r1))
    } else {
        r1.powi(3)
    }
}

/// Places spheres of `radii` (largest first) at random in the mould, without overlap with
/// each other (through the wedge's images too) or the mould walls.
pub(super) fn fill(
    rng: &mut Rng,
    radii: &[f64],
    g: &Geometry,
) -> Result<Vec<DVec3>, ScenarioError> {
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
