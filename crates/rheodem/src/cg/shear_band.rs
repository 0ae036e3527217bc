//! The shear band in the coarse-grained fields of the split-bottom cell, and its local
//! rheology (docs/coarse-graining.md §6).
//!
//! Per height of the `(r, z)` grid: the largest strain rate and where it is, the band
//! centre and width from an error-function fit of `ω = V_φ / (Ω r)` and from a Gaussian fit
//! of `γ̇(r)` (both reported), and the centre region where `γ̇` exceeds a fraction (80 %,
//! Roy et al. 2016, Sect. 3.1) of that height's maximum. The points of the centre regions
//! are the band's rheology points, to which `τ = μ P + c` is fitted (Roy et al. 2016,
//! Eq. 18).

use super::fields::FieldPoint;
use super::grid::Grid;
use crate::band::{ErfFit, fit_erf};
use serde::{Deserialize, Serialize};

/// A Gaussian fit `γ̇(r) = A exp(−(r − R_c)² / 2σ²)` of a strain-rate profile.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GaussFit {
    /// Peak strain rate `A` (1/s).
    pub peak: f64,
    /// Centre `R_c` (m).
    pub centre: f64,
    /// Standard error of `R_c` (m).
    pub centre_err: f64,
    /// Standard deviation `σ` (m).
    pub sigma: f64,
    /// Standard error of `σ` (m).
    pub sigma_err: f64,
    /// Points fitted.
    pub points: usize,
}

/// The band at one height.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BandAtHeight {
    /// Height (m).
    pub z: f64,
    /// Largest strain rate at this height (1/s) and its radius (m).
    pub max_strain_rate: f64,
    /// Radius of the largest strain rate (m).
    pub r_at_max: f64,
    /// Radial extent `[r_lo, r_hi]` of the centre region (m).
    pub centre_region: [f64; 2],
    /// Error-function fit of `ω(r)`, or why it failed.
    pub erf: Result<ErfFit, String>,
    /// Gaussian fit of `γ̇(r)`, or why it failed.
    pub gauss: Result<GaussFit, String>,
}

/// Filled points of height row `iz`, with their indices, in order of `r`.
fn row<'a>(grid: &Grid, points: &'a [FieldPoint], iz: usize) -> Vec<&'a FieldPoint> {
    let ax = grid.axes();
    (0..ax.n[0])
        .map(|ir| &points[ax.index(&[ir, iz])])
        .filter(|p| p.density > 0.0 && p.strain_rate.is_finite() && p.velocity[1].is_finite())
        .collect()
}

/// The band at every height of an axisymmetric grid's fields, for the outer parts turning
/// at `omega` (rad/s); `fraction` of the largest strain rate bounds the centre region.
/// Heights with fewer than five filled points are left out.
pub fn band_by_height(
    grid: &Grid,
    points: &[FieldPoint],
    omega: f64,
    fraction: f64,
) -> Vec<BandAtHeight> {
    let ax = grid.axes();
    if !matches!(grid, Grid::Axisymmetric { .. }) {
        return Vec::new();
    }
    (0..ax.n[1])
        .filter_map(|iz| {
            let row = row(grid, points, iz);
            if row.len() < 5 {
                return None;
            }
            let top = row
                .iter()
                .max_by(|a, b| a.strain_rate.total_cmp(&b.strain_rate))?;
            let max = top.strain_rate;
            let inside: Vec<f64> = row
                .iter()
                .filter(|p| p.strain_rate >= fraction * max)
                .map(|p| p.coordinates[0])
                .collect();
            let r: Vec<f64> = row.iter().map(|p| p.coordinates[0]).collect();
            let omega_ratio: Vec<f64> = row
                .iter()
                .map(|p| p.velocity[1] / (omega * p.coordinates[0]))
                .collect();
            let rate: Vec<f64> = row.iter().map(|p| p.strain_rate).collect();
            Some(BandAtHeight {
                z: ax.point(1, iz),
                max_strain_rate: max,
                r_at_max: top.coordinates[0],
                centre_region: [
                    inside.iter().copied().fold(f64::INFINITY, f64::min),
                    inside.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                ],
                erf: fit_erf(&r, &omega_ratio, &vec![1.0; r.len()]).map_err(|e| e.to_string()),
                gauss: fit_gauss(&r, &rate),
            })
        })
        .collect()
}

/// A point of the band's local rheology, in SI units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RheologyPoint {
    /// Radius (m).
    pub r: f64,
    /// Height (m).
    pub z: f64,
    /// Inertial number.
    pub inertial_number: f64,
    /// Softness `p*`.
    pub softness: f64,
    /// Bond number.
    pub bond_number: f64,
    /// Volume fraction.
    pub volume_fraction: f64,
    /// Friction `μ = τ/P`.
    pub friction: f64,
    /// Shear stress (Pa).
    pub shear_stress: f64,
    /// Pressure (Pa).
    pub pressure: f64,
    /// Strain rate (1/s).
    pub strain_rate: f64,
    /// Coordination.
    pub coordination: f64,
}

/// The points of the centre regions of `bands` (see [`band_by_height`]).
pub fn band_points(
    grid: &Grid,
    points: &[FieldPoint],
    bands: &[BandAtHeight],
) -> Vec<RheologyPoint> {
    let ax = grid.axes();
    let mut out = Vec::new();
    for b in bands {
        let iz = ((b.z - ax.lo[1]) / ax.h[1]).floor() as usize;
        for p in row(grid, points, iz) {
            let r = p.coordinates[0];
            if r >= b.centre_region[0] && r <= b.centre_region[1] {
                out.push(RheologyPoint {
                    r,
                    z: b.z,
                    inertial_number: p.inertial_number,
                    softness: p.softness,
                    bond_number: p.bond_number,
                    volume_fraction: p.volume_fraction,
                    friction: p.friction,
                    shear_stress: p.shear_stress,
                    pressure: p.pressure,
                    strain_rate: p.strain_rate,
                    coordination: p.coordination,
                });
            }
        }
    }
    out
}

/// The straight line `τ = μ P + c` fitted by ordinary least squares.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LinearFit {
    /// Slope `μ`.
    pub slope: f64,
    /// Standard error of the slope.
    pub slope_err: f64,
    /// Intercept `c` (Pa).
    pub intercept: f64,
    /// Standard error of the intercept (Pa).
    pub intercept_err: f64,
    /// Root-mean-square residual (Pa).
    pub rms: f64,
    /// Points fitted.
    pub points: usize,
}

/// Fits `τ = μ P + c` to the rheology points with `P ≥ p_min` (Pa); standard errors from the
/// residual scatter. `None` with fewer than three points or no spread in `P`.
pub fn fit_friction_line(points: &[RheologyPoint], p_min: f64) -> Option<LinearFit> {
    let used: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.pressure >= p_min && p.shear_stress.is_finite() && p.pressure.is_finite())
        .map(|p| (p.pressure, p.shear_stress))
        .collect();
    let n = used.len();
    if n < 3 {
        return None;
    }
    let nf = n as f64;
    let mx = used.iter().map(|u| u.0).sum::<f64>() / nf;
    let my = used.iter().map(|u| u.1).sum::<f64>() / nf;
    let sxx: f64 = used.iter().map(|u| (u.0 - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let sxy: f64 = used.iter().map(|u| (u.0 - mx) * (u.1 - my)).sum();
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let ss: f64 = used
        .iter()
        .map(|u| (u.1 - intercept - slope * u.0).powi(2))
        .sum();
    let s2 = ss / (nf - 2.0);
    Some(LinearFit {
        slope,
        slope_err: (s2 / sxx).sqrt(),
        intercept,
        intercept_err: (s2 * (1.0 / nf + mx * mx / sxx)).sqrt(),
        rms: (ss / nf).sqrt(),
        points: n,
    })
}

/// Fits `γ̇(r) = A exp(−(r − R_c)²/2σ²)` by Levenberg–Marquardt ([`crate::fit::least_squares`]),
/// starting from the largest point and the spread of the profile about it; standard errors
/// from the covariance scaled by the residual variance.
///
/// # Errors
/// A message with fewer than four points, non-finite data, or a fit that does not converge
/// to a centre inside the data's range.
pub fn fit_gauss(r: &[f64], rate: &[f64]) -> Result<GaussFit, String> {
    let n = r.len();
    if n < 4 || rate.len() != n {
        return Err(format!("the Gaussian fit needs at least 4 points, got {n}"));
    }
    if r.iter().chain(rate).any(|x| !x.is_finite()) {
        return Err("the strain-rate profile has non-finite values".into());
    }
    let (k, &top) = rate
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .ok_or("no points")?;
    let total: f64 = rate.iter().map(|y| y.max(0.0)).sum();
    let spread = (rate
        .iter()
        .zip(r)
        .map(|(y, x)| y.max(0.0) * (x - r[k]).powi(2))
        .sum::<f64>()
        / total.max(f64::MIN_POSITIVE))
    .sqrt()
    .max(0.5 * (r[n - 1] - r[0]) / n as f64);
    // Parameters (A, R_c, ln σ), so that the width stays positive; unit weights, so the
    // standard errors are scaled by the residual variance.
    let model = |p: &[f64], i: usize| p[0] * (-0.5 * ((r[i] - p[1]) / p[2].exp()).powi(2)).exp();
    let fit = crate::fit::least_squares(model, rate, &vec![1.0; n], &[top, r[k], spread.ln()])
        .map_err(|e| format!("the Gaussian fit failed: {e}"))?;
    let (a, c, s) = (fit.params[0], fit.params[1], fit.params[2].exp());
    let (lo, hi) = (r[0].min(r[n - 1]), r[0].max(r[n - 1]));
    if !(fit.converged && a > 0.0 && c > lo && c < hi && s.is_finite()) {
        return Err(format!(
            "the Gaussian fit did not converge (A = {a}, R_c = {c}, σ = {s})"
        ));
    }
    Ok(GaussFit {
        peak: a,
        centre: c,
        centre_err: fit.errors[1],
        sigma: s,
        sigma_err: s * fit.errors[2],
        points: n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic noise in `[−1, 1]`.
    fn noise(k: usize) -> f64 {
        ((k as f64 * 12.9898).sin() * 43_758.545_3).fract() * 2.0 - 1.0
    }

    #[test]
    fn the_gaussian_fit_recovers_a_noisy_profile() {
        let (a, c, s) = (1.7, 0.072, 0.006);
        let r: Vec<f64> = (0..60).map(|k| 0.015 + k as f64 * 0.0015).collect();
        let y: Vec<f64> = r
            .iter()
            .enumerate()
            .map(|(k, x)| a * (-0.5 * ((x - c) / s).powi(2)).exp() + 0.02 * noise(k))
            .collect();
        let fit = fit_gauss(&r, &y).expect("fit");
        // Noise of 1 % of the peak: the centre within a few standard errors, and those
        // small against the width.
        assert!(
            (fit.centre - c).abs() < 4.0 * fit.centre_err + 1e-5,
            "{fit:?}"
        );
        assert!(
            (fit.sigma - s).abs() < 4.0 * fit.sigma_err + 1e-5,
            "{fit:?}"
        );
        assert!(fit.centre_err < 0.05 * s && (fit.peak / a - 1.0).abs() < 0.03);
    }

    #[test]
    fn the_friction_line_recovers_known_coefficients() {
        let (mu, c) = (0.15, 12.0);
        let points: Vec<RheologyPoint> = (0..40)
            .map(|k| {
                let p = 20.0 + 10.0 * k as f64;
                RheologyPoint {
                    r: 0.0,
                    z: 0.0,
                    inertial_number: 0.0,
                    softness: 0.0,
                    bond_number: 0.0,
                    volume_fraction: 0.0,
                    friction: 0.0,
                    shear_stress: mu * p + c + 0.5 * noise(k),
                    pressure: p,
                    strain_rate: 0.0,
                    coordination: 0.0,
                }
            })
            .collect();
        let fit = fit_friction_line(&points, 0.0).expect("fit");
        assert!((fit.slope - mu).abs() < 3.0 * fit.slope_err, "{fit:?}");
        assert!(
            (fit.intercept - c).abs() < 3.0 * fit.intercept_err,
            "{fit:?}"
        );
        assert!(fit.slope_err < 0.01 && fit.points == 40);
        // The cut-off leaves out the low pressures.
        assert_eq!(fit_friction_line(&points, 215.0).expect("fit").points, 20);
        assert!(fit_friction_line(&points[..2], 0.0).is_none());
    }
}
