//! Continuum fields from time-averaged coarse-graining sums (docs/coarse-graining.md §4):
//! density, volume fraction, velocity, kinetic and contact stress, pressure, shear stress,
//! strain rate, and the local dimensionless numbers of the rheology (`I`, `p*`, `Bo`, `μ`),
//! coordination and bridges per particle.

use super::grid::Grid;
use super::sums::{CgSums, PointSums};

/// Particle-scale constants that make the local dimensionless numbers.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Material {
    /// Mean particle diameter `d_p` (m).
    pub diameter: f64,
    /// Particle material density `ρ_p` (kg/m³).
    pub particle_density: f64,
    /// Normal contact stiffness `k_n` (N/m).
    pub stiffness: f64,
    /// Largest adhesive force of a pair `f_a^max` (N); zero without cohesion.
    pub max_adhesion: f64,
}

/// The fields at one grid point. Vectors and tensors are in the grid's components
/// (Cartesian, or `(r, φ, z)`), tensors row-major; stresses are positive in compression.
/// Quantities that need a density, a pressure or neighbours with a velocity are `NaN`
/// where those are missing.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldPoint {
    /// Coordinates of the point along the grid's axes (m).
    pub coordinates: Vec<f64>,
    /// Mass density `ρ = Σ m ψ` (kg/m³).
    pub density: f64,
    /// Volume fraction `φ = Σ V ψ`.
    pub volume_fraction: f64,
    /// Velocity `V = Σ m v ψ / ρ` (m/s).
    pub velocity: [f64; 3],
    /// Kinetic stress `Σ m v ⊗ v ψ − ρ V ⊗ V` (Pa).
    pub kinetic_stress: [f64; 9],
    /// Contact stress `Σ f ⊗ l ∫ψ ds` (Pa).
    pub contact_stress: [f64; 9],
    /// Total stress `σ`, kinetic plus contact (Pa).
    pub stress: [f64; 9],
    /// Pressure `P = tr σ / 3` (Pa).
    pub pressure: f64,
    /// Shear stress `τ = √(½ s : s)` (Pa), `s` the deviator of the symmetric part of `σ`.
    pub shear_stress: f64,
    /// The shear stress resolved on the flow (Pa): `√(σ_rφ² + σ_φz²)` on the axisymmetric
    /// grid (azimuthal flow), `|σ_xy|` otherwise (flow along `x`, gradient along `y`), from
    /// the symmetric part.
    pub resolved_shear_stress: f64,
    /// Strain rate `γ̇ = √(2 D' : D')` (1/s), `D'` the deviator of the strain-rate tensor of
    /// `V` (so that simple shear `v_x = γ̇ y` gives `γ̇`; the Frobenius norm of `D` is `γ̇/2`).
    pub strain_rate: f64,
    /// Macroscopic friction `μ = τ / P`.
    pub friction: f64,
    /// Inertial number `I = γ̇ d_p / √(P / ρ_p)`.
    pub inertial_number: f64,
    /// Softness `p* = P d_p / k_n`.
    pub softness: f64,
    /// Bond number `Bo = f_a^max / (P d_p²)`.
    pub bond_number: f64,
    /// Touching contacts per particle `Σ c ψ / Σ ψ` (walls included).
    pub coordination: f64,
    /// Attracting pairs apart (open bridges) per particle.
    pub bridges_per_particle: f64,
}

/// A point counts as filled when its mass density exceeds this fraction of the largest.
const FILLED: f64 = 1e-6;

/// The fields at every point of `sums`' grid from their time average.
pub fn fields(sums: &CgSums, material: Option<&Material>) -> Vec<FieldPoint> {
    let grid = &sums.grid;
    let mean = sums.mean();
    let top = mean.iter().map(|p| p.mass).fold(0.0, f64::max);
    let filled: Vec<bool> = mean.iter().map(|p| p.mass > FILLED * top).collect();
    let velocity: Vec<[f64; 3]> = mean
        .iter()
        .zip(&filled)
        .map(|(p, &f)| {
            if f {
                p.momentum.map(|m| m / p.mass)
            } else {
                [f64::NAN; 3]
            }
        })
        .collect();
    (0..grid.len())
        .map(|k| point(grid, k, &mean[k], &velocity, &filled, material))
        .collect()
}

fn point(
    grid: &Grid,
    k: usize,
    p: &PointSums,
    velocity: &[[f64; 3]],
    filled: &[bool],
    material: Option<&Material>,
) -> FieldPoint {
    let v = velocity[k];
    let kinetic: [f64; 9] = if filled[k] {
        std::array::from_fn(|a| p.kinetic[a] - p.mass * v[a / 3] * v[a % 3])
    } else {
        [0.0; 9]
    };
    let stress: [f64; 9] = std::array::from_fn(|a| kinetic[a] + p.contact[a]);
    let pressure = (stress[0] + stress[4] + stress[8]) / 3.0;
    let sym = |a: usize, b: usize| 0.5 * (stress[a * 3 + b] + stress[b * 3 + a]);
    let mut dev2 = 0.0;
    for a in 0..3 {
        for b in 0..3 {
            let s = sym(a, b) - if a == b { pressure } else { 0.0 };
            dev2 += s * s;
        }
    }
    let shear_stress = (0.5 * dev2).sqrt();
    let resolved_shear_stress = match grid {
        Grid::Axisymmetric { .. } => sym(0, 1).hypot(sym(1, 2)),
        _ => sym(0, 1).abs(),
    };
    let strain_rate = strain_rate(grid, k, velocity, filled);
    let (inertial_number, softness, bond_number) = match material {
        Some(m) if pressure > 0.0 => (
            strain_rate * m.diameter / (pressure / m.particle_density).sqrt(),
            pressure * m.diameter / m.stiffness,
            m.max_adhesion / (pressure * m.diameter * m.diameter),
        ),
        _ => (f64::NAN, f64::NAN, f64::NAN),
    };
    let per_particle = |x: f64| {
        if p.number > 0.0 {
            x / p.number
        } else {
            f64::NAN
        }
    };
    FieldPoint {
        coordinates: grid.coordinates(k),
        density: p.mass,
        volume_fraction: p.volume,
        velocity: v,
        kinetic_stress: kinetic,
        contact_stress: p.contact,
        stress,
        pressure,
        shear_stress,
        resolved_shear_stress,
        strain_rate,
        friction: if pressure > 0.0 {
            shear_stress / pressure
        } else {
            f64::NAN
        },
        inertial_number,
        softness,
        bond_number,
        coordination: per_particle(p.contacts),
        bridges_per_particle: per_particle(p.bridges),
    }
}

/// `∂V_c/∂x_a` at point `k` by finite differences along grid axis `a`: central between two
/// filled neighbours, one-sided with one, `NaN` with none.
fn derivative(grid: &Grid, k: usize, a: usize, velocity: &[[f64; 3]], filled: &[bool]) -> [f64; 3] {
    let ax = grid.axes();
    let idx = ax.indices(k);
    let at = |i: usize| {
        let mut j = idx;
        j[a] = i;
        ax.index(&j)
    };
    let i = idx[a];
    let up = (i + 1 < ax.n[a]).then(|| at(i + 1)).filter(|&j| filled[j]);
    let down = i.checked_sub(1).map(at).filter(|&j| filled[j]);
    let h = ax.h[a];
    let diff = |j1: usize, j0: usize, span: f64| -> [f64; 3] {
        std::array::from_fn(|c| (velocity[j1][c] - velocity[j0][c]) / span)
    };
    match (down, up, filled[k]) {
        (Some(d), Some(u), _) => diff(u, d, 2.0 * h),
        (None, Some(u), true) => diff(u, k, h),
        (Some(d), None, true) => diff(k, d, h),
        _ => [f64::NAN; 3],
    }
}

/// `γ̇ = √(2 D' : D')` at point `k` (see [`FieldPoint::strain_rate`]).
fn strain_rate(grid: &Grid, k: usize, velocity: &[[f64; 3]], filled: &[bool]) -> f64 {
    if !filled[k] {
        return f64::NAN;
    }
    // d[a][c] = ∂V_c / ∂(grid axis a).
    let count = grid.axes().count;
    let d: Vec<[f64; 3]> = (0..count)
        .map(|a| derivative(grid, k, a, velocity, filled))
        .collect();
    let v = velocity[k];
    // Velocity gradient G[c][b] = ∂V_c/∂x_b in the grid's components.
    let mut g = [[0.0; 3]; 3];
    match grid {
        Grid::Cartesian { .. } => {
            for (b, db) in d.iter().enumerate() {
                for c in 0..3 {
                    g[c][b] = db[c];
                }
            }
        }
        Grid::Slab { axis, .. } => {
            for c in 0..3 {
                g[c][*axis] = d[0][c];
            }
        }
        Grid::Axisymmetric { .. } => {
            // Cylindrical components of ∇V for V(r, z): the (·)φ column holds the terms of
            // the curved basis, (∂/∂φ = 0): G_rφ = −V_φ/r, G_φφ = V_r/r.
            let r = grid.coordinates(k)[0];
            let (dr, dz) = (d[0], d[1]);
            g[0][0] = dr[0];
            g[0][1] = -v[1] / r;
            g[0][2] = dz[0];
            g[1][0] = dr[1];
            g[1][1] = v[0] / r;
            g[1][2] = dz[1];
            g[2][0] = dr[2];
            g[2][2] = dz[2];
        }
    }
    let trace = (g[0][0] + g[1][1] + g[2][2]) / 3.0;
    let sum: f64 = (0..9)
        .map(|k| {
            let (a, b) = (k / 3, k % 3);
            let s = 0.5 * (g[a][b] + g[b][a]) - if a == b { trace } else { 0.0 };
            s * s
        })
        .sum();
    (2.0 * sum).sqrt()
}
