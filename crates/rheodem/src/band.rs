//! A first look at the shear band of the split-bottom ring shear cell (docs/model.md §10,
//! docs/split-bottom-band.md).
//!
//! Three tools, all in SI units and all about the `z` axis through the origin (shift the
//! positions first if the cell's axis is elsewhere):
//!
//! - [`AzimuthalProfile`] bins the normalised azimuthal velocity `ω = v_φ / (Ω r)` of the
//!   particles of one horizontal slab over the cylindrical radius `r`, accumulating over
//!   snapshots (and over runs, with [`AzimuthalProfile::merge`]).
//! - [`fit_erf`] fits the universal profile `ω(r) = ½ [1 + erf((r − R_c) / W)]`
//!   (Fenistein & van Hecke 2003) by weighted nonlinear least squares, giving the band centre
//!   `R_c` and width `W` with their standard errors; `σ = W / √2` is the width in the
//!   convention `erf((r − R_c) / (√2 σ))`, the standard deviation of the Gaussian strain-rate
//!   profile `∂ω/∂r`.
//! - [`surface_height`] measures the height of the free surface, so that a profile can be
//!   taken at the top of the layer and the filling height `H` of a run is known.

use glam::DVec3;
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::storage::Owned;
use nalgebra::{DVector, Dyn, Matrix2, OMatrix, U2, Vector2};
use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};

/// The largest number of radial bins an [`AzimuthalProfile`] accepts.
pub const MAX_BINS: usize = 1 << 20;

/// Errors of the shear-band analysis.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BandError {
    /// The binning of a profile is not usable (bounds not finite or not increasing, no bins,
    /// too many bins, a negative inner radius, or inconsistent stored arrays).
    #[error("invalid profile binning: {0}")]
    InvalidBinning(String),
    /// Two profiles with different binning cannot be merged.
    #[error("the profiles have different binning and cannot be merged")]
    IncompatibleProfiles,
    /// The angular velocity `Ω` is zero or not finite, so `v_φ / (Ω r)` is undefined.
    #[error("the angular velocity Ω must be finite and non-zero, got {0} rad/s")]
    InvalidOmega(f64),
    /// Arrays that describe the same particles or points have different lengths.
    #[error("length mismatch: {what} ({a} vs {b})")]
    LengthMismatch {
        /// What was compared.
        what: &'static str,
        /// First length.
        a: usize,
        /// Second length.
        b: usize,
    },
    /// A selected particle has a non-finite position or velocity.
    #[error("particle {0} has a non-finite position or velocity")]
    NonFiniteParticle(usize),
    /// The fit needs at least three points (two parameters and one degree of freedom).
    #[error("the fit needs at least 3 points, got {0}")]
    TooFewPoints(usize),
    /// A data point is not finite (`r`, `y` or `σ`).
    #[error("point {0} is not finite (r, y or sigma)")]
    NonFiniteData(usize),
    /// A point's uncertainty is not positive.
    #[error("point {index} has a non-positive uncertainty sigma = {sigma}")]
    NonPositiveSigma {
        /// Index of the point.
        index: usize,
        /// Its uncertainty.
        sigma: f64,
    },
    /// The data never cross ½: the band centre lies outside the radial range covered.
    #[error(
        "the profile never crosses 0.5 within r = [{r_min}, {r_max}] m: the band lies outside the range"
    )]
    NoCrossing {
        /// Smallest radius of the data (m).
        r_min: f64,
        /// Largest radius of the data (m).
        r_max: f64,
    },
    /// The minimisation ran away or left the parameters undetermined.
    #[error("the erf fit diverged: {0}")]
    Diverged(String),
}

/// One radial bin of an [`AzimuthalProfile`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ProfileBin {
    /// Centre of the bin (m).
    pub r: f64,
    /// Mean of `v_φ / (Ω r)` over the samples in the bin (dimensionless); NaN when empty.
    pub mean: f64,
    /// Standard error of the mean, `s / √n` with the sample standard deviation `s`
    /// (dimensionless); NaN with fewer than 2 samples. It treats every sample as
    /// independent, which the same particle seen in successive snapshots is not: with
    /// correlated snapshots it underestimates the error.
    pub stderr: f64,
    /// Number of samples (particle × snapshot) in the bin.
    pub count: u64,
}

/// The binned normalised azimuthal velocity `v_φ / (Ω r)` of the particles of one horizontal
/// slab `z_lo ≤ z < z_hi` (m), over `bins` equal radial bins covering `r_lo ≤ r < r_hi` (m),
/// where `r = sqrt(x² + y²)` and `v_φ = (x v_y − y v_x) / r` about the `z` axis through the
/// origin.
///
/// Each bin keeps the number of samples, their sum and their sum of squares, so profiles
/// accumulate over snapshots, merge across runs, and serialise (serde) into a checkpoint.
/// The average is over particles (number-weighted), not mass-weighted. A particle in rigid
/// rotation with the outer part of the cell contributes 1, one at rest 0.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "ProfileState")]
pub struct AzimuthalProfile {
    r_lo: f64,
    r_hi: f64,
    z_lo: f64,
    z_hi: f64,
    count: Vec<u64>,
    sum: Vec<f64>,
    sum_sq: Vec<f64>,
    snapshots: u64,
}

/// The serialised form of [`AzimuthalProfile`], checked on the way in.
#[derive(Deserialize)]
struct ProfileState {
    r_lo: f64,
    r_hi: f64,
    z_lo: f64,
    z_hi: f64,
    count: Vec<u64>,
    sum: Vec<f64>,
    sum_sq: Vec<f64>,
    snapshots: u64,
}

impl TryFrom<ProfileState> for AzimuthalProfile {
    type Error = BandError;

    fn try_from(s: ProfileState) -> Result<Self, BandError> {
        check_binning(s.r_lo, s.r_hi, s.count.len(), s.z_lo, s.z_hi)?;
        if s.sum.len() != s.count.len() || s.sum_sq.len() != s.count.len() {
            return Err(BandError::InvalidBinning(format!(
                "stored arrays differ in length ({}, {}, {})",
                s.count.len(),
                s.sum.len(),
                s.sum_sq.len()
            )));
        }
        if s.sum.iter().chain(&s.sum_sq).any(|v| !v.is_finite()) {
            return Err(BandError::InvalidBinning(
                "stored sums are not finite".into(),
            ));
        }
        Ok(Self {
            r_lo: s.r_lo,
            r_hi: s.r_hi,
            z_lo: s.z_lo,
            z_hi: s.z_hi,
            count: s.count,
            sum: s.sum,
            sum_sq: s.sum_sq,
            snapshots: s.snapshots,
        })
    }
}

fn check_binning(r_lo: f64, r_hi: f64, bins: usize, z_lo: f64, z_hi: f64) -> Result<(), BandError> {
    let bad = |m: String| Err(BandError::InvalidBinning(m));
    if ![r_lo, r_hi, z_lo, z_hi].iter().all(|v| v.is_finite()) {
        return bad(format!(
            "bounds must be finite: r = [{r_lo}, {r_hi}), z = [{z_lo}, {z_hi})"
        ));
    }
    if r_lo < 0.0 || r_hi <= r_lo {
        return bad(format!("need 0 ≤ r_lo < r_hi, got [{r_lo}, {r_hi}) m"));
    }
    if z_hi <= z_lo {
        return bad(format!("need z_lo < z_hi, got [{z_lo}, {z_hi}) m"));
    }
    if bins == 0 || bins > MAX_BINS {
        return bad(format!("need 1 to {MAX_BINS} bins, got {bins}"));
    }
    Ok(())
}

impl AzimuthalProfile {
    /// An empty profile with `bins` radial bins over `r_lo ≤ r < r_hi` (m) for the slab
    /// `z_lo ≤ z < z_hi` (m). Errors unless the bounds are finite, `0 ≤ r_lo < r_hi`,
    /// `z_lo < z_hi` and `1 ≤ bins ≤` [`MAX_BINS`].
    pub fn new(r_lo: f64, r_hi: f64, bins: usize, z_lo: f64, z_hi: f64) -> Result<Self, BandError> {
        check_binning(r_lo, r_hi, bins, z_lo, z_hi)?;
        Ok(Self {
            r_lo,
            r_hi,
            z_lo,
            z_hi,
            count: vec![0; bins],
            sum: vec![0.0; bins],
            sum_sq: vec![0.0; bins],
            snapshots: 0,
        })
    }

    /// Radial range `(r_lo, r_hi)` (m).
    pub fn radial_range(&self) -> (f64, f64) {
        (self.r_lo, self.r_hi)
    }

    /// Height range of the slab `(z_lo, z_hi)` (m).
    pub fn slab(&self) -> (f64, f64) {
        (self.z_lo, self.z_hi)
    }

    /// Number of radial bins.
    pub fn bin_count(&self) -> usize {
        self.count.len()
    }

    /// Number of snapshots accumulated (calls of [`add_sample`](Self::add_sample), summed
    /// over merged profiles).
    pub fn snapshots(&self) -> u64 {
        self.snapshots
    }

    /// Total number of samples over all bins.
    pub fn samples(&self) -> u64 {
        self.count.iter().sum()
    }

    /// Accumulates one snapshot: every particle `i` with `include(i)` whose position lies in
    /// the slab and in the radial range adds `v_φ / (Ω r)` to its bin. `positions` (m) and
    /// `velocities` (m/s) are indexed alike; `omega` (rad/s) is the angular velocity of the
    /// rotating part of the cell. A particle exactly on the axis (`r = 0`) is skipped.
    ///
    /// Returns the number of particles accumulated. Errors, leaving the profile unchanged,
    /// when the slices differ in length, when `Ω` is zero or not finite, or when a selected
    /// particle has a non-finite position or velocity.
    pub fn add_sample(
        &mut self,
        positions: &[DVec3],
        velocities: &[DVec3],
        include: impl Fn(usize) -> bool,
        omega: f64,
    ) -> Result<usize, BandError> {
        if positions.len() != velocities.len() {
            return Err(BandError::LengthMismatch {
                what: "positions vs velocities",
                a: positions.len(),
                b: velocities.len(),
            });
        }
        if !omega.is_finite() || omega == 0.0 {
            return Err(BandError::InvalidOmega(omega));
        }
        let bins = self.count.len();
        let dr = (self.r_hi - self.r_lo) / bins as f64;
        let mut hits: Vec<(usize, f64)> = Vec::new();
        for (i, (p, v)) in positions.iter().zip(velocities).enumerate() {
            if !include(i) {
                continue;
            }
            if !p.is_finite() || !v.is_finite() {
                return Err(BandError::NonFiniteParticle(i));
            }
            if p.z < self.z_lo || p.z >= self.z_hi {
                continue;
            }
            let r2 = p.x * p.x + p.y * p.y;
            let r = r2.sqrt();
            if r < self.r_lo || r >= self.r_hi || r2 == 0.0 {
                continue;
            }
            let k = (((r - self.r_lo) / dr) as usize).min(bins - 1);
            let ratio = (p.x * v.y - p.y * v.x) / (omega * r2);
            if !ratio.is_finite() {
                return Err(BandError::NonFiniteParticle(i));
            }
            hits.push((k, ratio));
        }
        for &(k, ratio) in &hits {
            self.count[k] += 1;
            self.sum[k] += ratio;
            self.sum_sq[k] += ratio * ratio;
        }
        self.snapshots += 1;
        Ok(hits.len())
    }

    /// Adds the samples of `other`, which must have exactly the same binning and slab.
    pub fn merge(&mut self, other: &AzimuthalProfile) -> Result<(), BandError> {
        let same = self.r_lo == other.r_lo
            && self.r_hi == other.r_hi
            && self.z_lo == other.z_lo
            && self.z_hi == other.z_hi
            && self.count.len() == other.count.len();
        if !same {
            return Err(BandError::IncompatibleProfiles);
        }
        for k in 0..self.count.len() {
            self.count[k] += other.count[k];
            self.sum[k] += other.sum[k];
            self.sum_sq[k] += other.sum_sq[k];
        }
        self.snapshots += other.snapshots;
        Ok(())
    }

    /// The bins, from the innermost out: centre radius (m), mean ratio, its standard error
    /// and the number of samples (see [`ProfileBin`] for empty and single-sample bins).
    pub fn bins(&self) -> Vec<ProfileBin> {
        let bins = self.count.len();
        let dr = (self.r_hi - self.r_lo) / bins as f64;
        (0..bins)
            .map(|k| {
                let n = self.count[k];
                let nf = n as f64;
                let (mean, stderr) = match n {
                    0 => (f64::NAN, f64::NAN),
                    1 => (self.sum[k], f64::NAN),
                    _ => {
                        let mean = self.sum[k] / nf;
                        let var = ((self.sum_sq[k] - nf * mean * mean) / (nf - 1.0)).max(0.0);
                        (mean, (var / nf).sqrt())
                    }
                };
                ProfileBin {
                    r: self.r_lo + (k as f64 + 0.5) * dr,
                    mean,
                    stderr,
                    count: n,
                }
            })
            .collect()
    }

    /// Fits [`fit_erf`] to the bins holding at least `min_count` samples (at least 2), each
    /// weighted by its standard error raised to at least `sigma_floor` (> 0; it keeps bins
    /// in rigid rotation or at rest, whose scatter is zero, from taking infinite weight).
    /// Errors as [`fit_erf`], and with [`BandError::NonPositiveSigma`] (index 0) when
    /// `sigma_floor` is not positive and finite.
    pub fn fit(&self, min_count: u64, sigma_floor: f64) -> Result<ErfFit, BandError> {
        if !(sigma_floor > 0.0 && sigma_floor.is_finite()) {
            return Err(BandError::NonPositiveSigma {
                index: 0,
                sigma: sigma_floor,
            });
        }
        let min_count = min_count.max(2);
        let (mut r, mut y, mut s) = (Vec::new(), Vec::new(), Vec::new());
        for b in self.bins().into_iter().filter(|b| b.count >= min_count) {
            r.push(b.r);
            y.push(b.mean);
            s.push(b.stderr.max(sigma_floor));
        }
        fit_erf(&r, &y, &s)
    }
}

/// The universal split-bottom profile `½ [1 + erf((r − centre) / width)]` at radius `r`
/// (all lengths in m; `width` is `W`, not `σ = W / √2`).
pub fn erf_profile(r: f64, centre: f64, width: f64) -> f64 {
    0.5 * (1.0 + libm::erf((r - centre) / width))
}

/// Result of [`fit_erf`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErfFit {
    /// Band centre `R_c` (m): where the profile is ½.
    pub centre: f64,
    /// Standard error of `R_c` (m).
    pub centre_err: f64,
    /// Band width `W` (m) in the convention `erf((r − R_c) / W)` of Fenistein & van Hecke.
    pub width: f64,
    /// Standard error of `W` (m).
    pub width_err: f64,
    /// `σ = W / √2` (m): the width in the convention `erf((r − R_c) / (√2 σ))`, the standard
    /// deviation of the Gaussian `∂ω/∂r`.
    pub sigma: f64,
    /// Standard error of `σ` (m).
    pub sigma_err: f64,
    /// Root-mean-square of the unweighted residuals `y − model` (dimensionless).
    pub rms_residual: f64,
    /// `χ² / (n − 2)` with `χ² = Σ ((y − model) / σ_i)²`.
    pub reduced_chi2: f64,
    /// Number of points fitted.
    pub points: usize,
    /// Whether Levenberg–Marquardt stopped on a convergence criterion rather than on its
    /// evaluation limit.
    pub converged: bool,
}

/// The weighted least-squares problem of [`fit_erf`]; parameters `(R_c, ln W)`, so that the
/// width stays positive.
struct ErfProblem<'a> {
    r: &'a [f64],
    y: &'a [f64],
    sigma: &'a [f64],
    p: Vector2<f64>,
}

const FRAC_1_SQRT_PI: f64 = 0.564_189_583_547_756_3;

impl ErfProblem<'_> {
    /// `(∂f/∂R_c, ∂f/∂W)` of the model at point `i` (unweighted).
    fn gradient(&self, i: usize, centre: f64, width: f64) -> (f64, f64) {
        let u = (self.r[i] - centre) / width;
        let g = FRAC_1_SQRT_PI * (-u * u).exp() / width;
        (-g, -g * u)
    }
}

impl LeastSquaresProblem<f64, Dyn, U2> for ErfProblem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, U2>;
    type ParameterStorage = Owned<f64, U2>;

    fn set_params(&mut self, p: &Vector2<f64>) {
        self.p.copy_from(p);
    }

    fn params(&self) -> Vector2<f64> {
        self.p
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        let (c, w) = (self.p[0], self.p[1].exp());
        Some(DVector::from_iterator(
            self.r.len(),
            (0..self.r.len()).map(|i| (erf_profile(self.r[i], c, w) - self.y[i]) / self.sigma[i]),
        ))
    }

    fn jacobian(&self) -> Option<OMatrix<f64, Dyn, U2>> {
        let (c, w) = (self.p[0], self.p[1].exp());
        Some(OMatrix::<f64, Dyn, U2>::from_fn(self.r.len(), |i, j| {
            let (dc, dw) = self.gradient(i, c, w);
            // ∂f/∂(ln W) = W ∂f/∂W.
            (if j == 0 { dc } else { w * dw }) / self.sigma[i]
        }))
    }
}

/// Median of the radii where the piecewise-linear interpolation of the points (sorted by
/// `r`) crosses `level`.
fn crossing(order: &[usize], r: &[f64], y: &[f64], level: f64) -> Option<f64> {
    let mut at: Vec<f64> = Vec::new();
    for pair in order.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let (da, db) = (y[a] - level, y[b] - level);
        if da == 0.0 {
            at.push(r[a]);
        } else if da * db < 0.0 {
            at.push(r[a] + (r[b] - r[a]) * da / (da - db));
        }
    }
    if let Some(&last) = order.last()
        && y[last] == level
    {
        at.push(r[last]);
    }
    if at.is_empty() {
        return None;
    }
    at.sort_by(f64::total_cmp);
    let m = at.len();
    Some(if m % 2 == 1 {
        at[m / 2]
    } else {
        0.5 * (at[m / 2 - 1] + at[m / 2])
    })
}

/// Weighted nonlinear least-squares fit of `y(r) = ½ [1 + erf((r − R_c) / W)]` with the
/// parameters `R_c` and `W > 0` to the points `(r_i, y_i)` (m, dimensionless) with standard
/// errors `sigma_i` (dimensionless), by Levenberg–Marquardt (the `levenberg-marquardt`
/// crate).
///
/// The data must rise from 0 at small `r` to 1 at large `r` (the outer part of the cell
/// turns). The initial guess takes `R_c` where the data cross ½ (linear interpolation; the
/// median crossing when noise makes several) and `W = (r₈₄ − r₁₆) / √2` from the radii
/// where they cross `Φ(∓1) ≈ 0.16, 0.84` (the span is `2σ`).
///
/// The standard errors come from the covariance `(Jᵀ W J)⁻¹` at the optimum (`J` the
/// Jacobian of the model in `(R_c, W)`, `W = diag(1/σ_i²)`) scaled by the reduced `χ²`, so
/// they reflect the observed scatter about the fit; only the relative weights of the
/// `sigma_i` matter.
///
/// Errors: fewer than 3 points, slices of different lengths, non-finite data, a
/// non-positive `sigma_i`, no crossing of ½ (the band lies outside the range), and a
/// diverged fit (non-finite parameters, a centre or width far beyond the data range, fewer
/// than two points within `2W` of the centre, as when the band is much narrower than the
/// point spacing, or a singular covariance).
pub fn fit_erf(r: &[f64], y: &[f64], sigma: &[f64]) -> Result<ErfFit, BandError> {
    let n = r.len();
    for (what, len) in [("r vs y", y.len()), ("r vs sigma", sigma.len())] {
        if len != n {
            return Err(BandError::LengthMismatch { what, a: n, b: len });
        }
    }
    if n < 3 {
        return Err(BandError::TooFewPoints(n));
    }
    for i in 0..n {
        if !(r[i].is_finite() && y[i].is_finite() && sigma[i].is_finite()) {
            return Err(BandError::NonFiniteData(i));
        }
        if sigma[i] <= 0.0 {
            return Err(BandError::NonPositiveSigma {
                index: i,
                sigma: sigma[i],
            });
        }
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| r[a].total_cmp(&r[b]));
    let r_min = r[order[0]];
    let r_max = r[order[n - 1]];
    let span = r_max - r_min;
    let c0 = crossing(&order, r, y, 0.5).ok_or(BandError::NoCrossing { r_min, r_max })?;
    const LOW: f64 = 0.158_655_253_931_457_05; // Φ(−1)
    let lo = crossing(&order, r, y, LOW);
    let hi = crossing(&order, r, y, 1.0 - LOW);
    let w0 = match (lo, hi) {
        (Some(a), Some(b)) if b > a => (b - a) / std::f64::consts::SQRT_2,
        (Some(a), None) if a < c0 => (c0 - a) * std::f64::consts::SQRT_2,
        (None, Some(b)) if b > c0 => (b - c0) * std::f64::consts::SQRT_2,
        _ => 0.25 * span,
    };
    if !(w0 > 0.0 && w0.is_finite()) {
        return Err(BandError::Diverged(format!(
            "no usable initial width (data span {span} m)"
        )));
    }
    let problem = ErfProblem {
        r,
        y,
        sigma,
        p: Vector2::new(c0, w0.ln()),
    };
    let (problem, report) = LevenbergMarquardt::new()
        .with_patience(200)
        .minimize(problem);
    let centre = problem.p[0];
    let width = problem.p[1].exp();
    if !(centre.is_finite() && width.is_finite() && width > 0.0) {
        return Err(BandError::Diverged(format!(
            "non-finite parameters ({:?})",
            report.termination
        )));
    }
    if (centre - 0.5 * (r_min + r_max)).abs() > 10.0 * span || width > 100.0 * span {
        return Err(BandError::Diverged(format!(
            "R_c = {centre} m, W = {width} m, far beyond the data r = [{r_min}, {r_max}] m"
        )));
    }
    let informative = r
        .iter()
        .filter(|&&x| ((x - centre) / width).abs() < 2.0)
        .count();
    if informative < 2 {
        return Err(BandError::Diverged(format!(
            "W = {width} m is not resolved: {informative} point(s) within 2W of R_c = {centre} m"
        )));
    }
    let mut jtj = Matrix2::<f64>::zeros();
    let (mut chi2, mut sq) = (0.0, 0.0);
    for i in 0..n {
        let (dc, dw) = problem.gradient(i, centre, width);
        let g = Vector2::new(dc, dw) / sigma[i];
        jtj += g * g.transpose();
        let d = y[i] - erf_profile(r[i], centre, width);
        sq += d * d;
        chi2 += (d / sigma[i]) * (d / sigma[i]);
    }
    let det = jtj[(0, 0)] * jtj[(1, 1)] - jtj[(0, 1)] * jtj[(1, 0)];
    let scale = jtj[(0, 0)] * jtj[(1, 1)];
    let cov = match jtj.try_inverse() {
        Some(inv) if det > 1e-12 * scale && inv.iter().all(|v| v.is_finite()) => inv,
        _ => {
            return Err(BandError::Diverged(format!(
                "singular covariance at R_c = {centre} m, W = {width} m: the width is not resolved by the points"
            )));
        }
    };
    let reduced_chi2 = chi2 / (n - 2) as f64;
    let centre_err = (cov[(0, 0)] * reduced_chi2).max(0.0).sqrt();
    let width_err = (cov[(1, 1)] * reduced_chi2).max(0.0).sqrt();
    Ok(ErfFit {
        centre,
        centre_err,
        width,
        width_err,
        sigma: width / std::f64::consts::SQRT_2,
        sigma_err: width_err / std::f64::consts::SQRT_2,
        rms_residual: (sq / n as f64).sqrt(),
        reduced_chi2,
        points: n,
        converged: report.termination.was_successful(),
    })
}

/// Height (m) of the free surface of the particles `i` with `include(i)` whose cylindrical
/// radius `r = sqrt(x² + y²)` lies in `r_lo ≤ r < r_hi` (m).
///
/// The annulus is divided into columns of about `column × column` (m²) in `(r, φ)`: `n_r =
/// max(1, round((r_hi − r_lo) / column))` rings of equal width, and in ring `k`, of mid radius
/// `r_k`, `max(1, round(2π r_k / column))` equal sectors of the full turn. In each column the
/// top of the highest particle, `z + a` (centre height plus radius), is taken; the surface
/// height is the mean of these tops over the columns that hold at least one particle, so a
/// packing that fills only a wedge of the ring is measured over the wedge alone.
///
/// The column should be one to a few particle diameters: smaller columns leave holes between
/// the top grains (biasing the mean low by up to about a radius), larger ones pick the
/// highest grain of a rough surface (biasing it high). Particles with a non-finite position
/// or radius are skipped.
///
/// `None` when no particle qualifies, when `positions` and `radii` differ in length, or when
/// the arguments are not usable (non-finite, `r_lo < 0`, `r_hi ≤ r_lo` or `column ≤ 0`).
pub fn surface_height(
    positions: &[DVec3],
    radii: &[f64],
    include: impl Fn(usize) -> bool,
    r_lo: f64,
    r_hi: f64,
    column: f64,
) -> Option<f64> {
    if positions.len() != radii.len()
        || ![r_lo, r_hi, column].iter().all(|v| v.is_finite())
        || r_lo < 0.0
        || r_hi <= r_lo
        || column <= 0.0
    {
        return None;
    }
    let rings = ((r_hi - r_lo) / column).round().max(1.0);
    let dr = (r_hi - r_lo) / rings;
    let rings = rings as usize;
    let mut tops: FxHashMap<(usize, usize), f64> = FxHashMap::default();
    for (i, (p, &a)) in positions.iter().zip(radii).enumerate() {
        if !include(i) || !p.is_finite() || !a.is_finite() {
            continue;
        }
        let r = p.x.hypot(p.y);
        if r < r_lo || r >= r_hi {
            continue;
        }
        let k = (((r - r_lo) / dr) as usize).min(rings - 1);
        let r_mid = r_lo + (k as f64 + 0.5) * dr;
        let sectors = (std::f64::consts::TAU * r_mid / column).round().max(1.0);
        let phi = p.y.atan2(p.x).rem_euclid(std::f64::consts::TAU);
        let s = ((phi / std::f64::consts::TAU * sectors) as usize).min(sectors as usize - 1);
        let top = p.z + a;
        tops.entry((k, s))
            .and_modify(|t| *t = t.max(top))
            .or_insert(top);
    }
    mean_top(&tops)
}

/// Height (m) of the free surface of the particles `i` with `include(i)` in a box periodic
/// along `x` and `y`, lower corner `lo` and edges `lengths` (m), measured as
/// [`surface_height`] measures it in an annulus: the box is divided into `n_x × n_y`
/// columns of about `column × column` (m², `n = max(1, round(L / column))` per axis, particle
/// positions wrapped into the box), the top `z + a` of the highest particle of each column
/// is taken, and the surface height is the mean of these tops over the columns that hold a
/// particle.
///
/// `None` when no particle qualifies, when `positions` and `radii` differ in length, or when
/// the lengths or the column are not positive and finite.
pub fn surface_height_box(
    positions: &[DVec3],
    radii: &[f64],
    include: impl Fn(usize) -> bool,
    lo: DVec3,
    lengths: DVec3,
    column: f64,
) -> Option<f64> {
    if positions.len() != radii.len()
        || ![lengths.x, lengths.y, column]
            .iter()
            .all(|v| v.is_finite() && *v > 0.0)
    {
        return None;
    }
    let n = |l: f64| (l / column).round().max(1.0);
    let (nx, ny) = (n(lengths.x), n(lengths.y));
    let bin = |x: f64, lo: f64, l: f64, n: f64| {
        (((x - lo).rem_euclid(l) / l * n) as usize).min(n as usize - 1)
    };
    let mut tops: FxHashMap<(usize, usize), f64> = FxHashMap::default();
    for (i, (p, &a)) in positions.iter().zip(radii).enumerate() {
        if !include(i) || !p.is_finite() || !a.is_finite() {
            continue;
        }
        let key = (bin(p.x, lo.x, lengths.x, nx), bin(p.y, lo.y, lengths.y, ny));
        let top = p.z + a;
        tops.entry(key)
            .and_modify(|t| *t = t.max(top))
            .or_insert(top);
    }
    mean_top(&tops)
}

/// The mean of the columns' tops (m); `None` without a column.
fn mean_top(tops: &FxHashMap<(usize, usize), f64>) -> Option<f64> {
    (!tops.is_empty()).then(|| tops.values().sum::<f64>() / tops.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_distr::{Distribution, StandardNormal};

    type Rng = rand_xoshiro::Xoshiro256PlusPlus;

    /// Radii evenly spread over `[r0, r1]`.
    fn grid(r0: f64, r1: f64, n: usize) -> Vec<f64> {
        (0..n)
            .map(|k| r0 + (r1 - r0) * k as f64 / (n - 1) as f64)
            .collect()
    }

    #[test]
    fn noiseless_fit_recovers_the_parameters() {
        // A band of the size of the source papers' cell: R_c = 70 mm, W = 8 mm, data over
        // 20–110 mm, the points not in order and with uneven weights.
        let (c, w) = (0.070, 0.008);
        let mut r = grid(0.020, 0.110, 46);
        r.reverse();
        r.swap(3, 30);
        let y: Vec<f64> = r.iter().map(|&x| erf_profile(x, c, w)).collect();
        let s: Vec<f64> = (0..r.len())
            .map(|k| 0.01 * (1.0 + (k % 3) as f64))
            .collect();
        let fit = fit_erf(&r, &y, &s).expect("fit");
        assert!(fit.converged);
        assert!((fit.centre - c).abs() < 1e-8, "{fit:?}");
        assert!((fit.width - w).abs() < 1e-8, "{fit:?}");
        assert!((fit.sigma - w / std::f64::consts::SQRT_2).abs() < 1e-8);
        assert!(fit.rms_residual < 1e-10, "{fit:?}");
        assert!(fit.centre_err < 1e-8 && fit.width_err < 1e-8, "{fit:?}");
        assert_eq!(fit.points, 46);
    }

    #[test]
    fn noiseless_fit_of_a_band_partly_outside_the_range() {
        // Only the inner half of the band is covered: no 84 % crossing for the guess.
        let (c, w) = (0.080, 0.010);
        let r = grid(0.040, 0.082, 22);
        let y: Vec<f64> = r.iter().map(|&x| erf_profile(x, c, w)).collect();
        let fit = fit_erf(&r, &y, &vec![0.02; r.len()]).expect("fit");
        assert!((fit.centre - c).abs() < 1e-8, "{fit:?}");
        assert!((fit.width - w).abs() < 1e-8, "{fit:?}");
    }

    #[test]
    fn noisy_fit_is_within_three_standard_errors() {
        let (c, w) = (0.065, 0.012);
        let r = grid(0.015, 0.110, 60);
        for seed in 0..8 {
            let mut rng = Rng::seed_from_u64(100 + seed);
            let s: Vec<f64> = r.iter().map(|_| rng.random_range(0.01..0.04)).collect();
            let y: Vec<f64> = r
                .iter()
                .zip(&s)
                .map(|(&x, &e)| {
                    let z: f64 = StandardNormal.sample(&mut rng);
                    erf_profile(x, c, w) + e * z
                })
                .collect();
            let fit = fit_erf(&r, &y, &s).expect("fit");
            assert!(fit.converged, "{fit:?}");
            assert!(fit.centre_err > 0.0 && fit.width_err > 0.0);
            assert!(
                (fit.centre - c).abs() < 3.0 * fit.centre_err,
                "seed {seed}: {fit:?}"
            );
            assert!(
                (fit.width - w).abs() < 3.0 * fit.width_err,
                "seed {seed}: {fit:?}"
            );
            // With the true uncertainties the reduced χ² is of order 1.
            assert!(fit.reduced_chi2 > 0.5 && fit.reduced_chi2 < 1.6, "{fit:?}");
        }
    }

    #[test]
    fn fit_rejects_bad_input() {
        let r = [0.01, 0.02, 0.03, 0.04];
        let y = [0.0, 0.2, 0.8, 1.0];
        let s = [0.05; 4];
        assert_eq!(
            fit_erf(&r[..2], &y[..2], &s[..2]),
            Err(BandError::TooFewPoints(2))
        );
        assert_eq!(fit_erf(&[], &[], &[]), Err(BandError::TooFewPoints(0)));
        assert!(matches!(
            fit_erf(&r, &y[..3], &s),
            Err(BandError::LengthMismatch { .. })
        ));
        let mut bad = y;
        bad[1] = f64::NAN;
        assert_eq!(fit_erf(&r, &bad, &s), Err(BandError::NonFiniteData(1)));
        let mut bad_r = r;
        bad_r[3] = f64::INFINITY;
        assert_eq!(fit_erf(&bad_r, &y, &s), Err(BandError::NonFiniteData(3)));
        let mut bad_s = s;
        bad_s[2] = 0.0;
        assert!(matches!(
            fit_erf(&r, &y, &bad_s),
            Err(BandError::NonPositiveSigma { index: 2, .. })
        ));
        // The whole range turns with the outer part: the band lies further in.
        assert!(matches!(
            fit_erf(&r, &[0.7, 0.8, 0.9, 1.0], &s),
            Err(BandError::NoCrossing { .. })
        ));
        // At rest everywhere: the band lies further out.
        assert!(matches!(
            fit_erf(&r, &[0.0; 4], &s),
            Err(BandError::NoCrossing { .. })
        ));
    }

    #[test]
    fn a_step_between_two_points_does_not_resolve_the_width() {
        let r = grid(0.01, 0.06, 6);
        let y = [0.0, 0.0, 0.0, 1.0, 1.0, 1.0];
        let e = fit_erf(&r, &y, &[0.01; 6]).expect_err("unresolved width");
        assert!(matches!(e, BandError::Diverged(_)), "{e:?}");
    }

    /// Particles spread uniformly over an annulus and a height range.
    fn cloud(rng: &mut Rng, n: usize, r: (f64, f64), z: (f64, f64)) -> Vec<DVec3> {
        (0..n)
            .map(|_| {
                let rr = rng.random_range(r.0..r.1);
                let phi = rng.random_range(0.0..std::f64::consts::TAU);
                DVec3::new(rr * phi.cos(), rr * phi.sin(), rng.random_range(z.0..z.1))
            })
            .collect()
    }

    #[test]
    fn rigid_rotation_gives_one_and_rest_gives_zero() {
        let mut rng = Rng::seed_from_u64(1);
        let pos = cloud(&mut rng, 4000, (0.015, 0.110), (0.0, 0.04));
        for omega in [0.0628, -2.5] {
            let rotating: Vec<DVec3> = pos
                .iter()
                .map(|p| DVec3::new(-omega * p.y, omega * p.x, rng.random_range(-1e-3..1e-3)))
                .collect();
            let mut prof = AzimuthalProfile::new(0.015, 0.110, 19, 0.0, 0.04).expect("binning");
            assert_eq!(prof.add_sample(&pos, &rotating, |_| true, omega), Ok(4000));
            for b in prof.bins() {
                assert!(b.count > 100, "{b:?}");
                assert!((b.mean - 1.0).abs() < 1e-12, "{b:?}");
                assert!(b.stderr < 1e-6, "{b:?}");
            }
            let mut rest = AzimuthalProfile::new(0.015, 0.110, 19, 0.0, 0.04).expect("binning");
            let still = vec![DVec3::new(0.0, 0.0, 0.3); pos.len()];
            rest.add_sample(&pos, &still, |_| true, omega)
                .expect("sample");
            assert!(rest.bins().iter().all(|b| b.mean == 0.0 && b.stderr == 0.0));
            assert_eq!(rest.snapshots(), 1);
        }
    }

    #[test]
    fn bin_centres_and_statistics() {
        let mut prof = AzimuthalProfile::new(0.01, 0.05, 4, -1.0, 1.0).expect("binning");
        // Two particles on the x axis in bin 1 (r = 0.02–0.03) with ratios 0.5 and 1.5, one in
        // bin 3 on the y axis with ratio 2.
        let pos = [
            DVec3::new(0.025, 0.0, 0.0),
            DVec3::new(0.025, 0.0, 0.0),
            DVec3::new(0.0, 0.045, 0.0),
        ];
        let omega = 2.0;
        let vel = [
            DVec3::new(0.0, 0.5 * omega * 0.025, 0.0),
            DVec3::new(0.0, 1.5 * omega * 0.025, 0.0),
            DVec3::new(-2.0 * omega * 0.045, 0.0, 0.0),
        ];
        assert_eq!(prof.add_sample(&pos, &vel, |_| true, omega), Ok(3));
        let b = prof.bins();
        let centres: Vec<f64> = b.iter().map(|b| b.r).collect();
        for (c, e) in centres.iter().zip([0.015, 0.025, 0.035, 0.045]) {
            assert!((c - e).abs() < 1e-15);
        }
        assert_eq!(b[0].count, 0);
        assert!(b[0].mean.is_nan() && b[0].stderr.is_nan());
        assert_eq!(b[1].count, 2);
        assert!((b[1].mean - 1.0).abs() < 1e-12);
        // s = 1/√2, stderr = s/√2 = 0.5.
        assert!((b[1].stderr - 0.5).abs() < 1e-12, "{:?}", b[1]);
        assert_eq!(b[3].count, 1);
        assert!((b[3].mean - 2.0).abs() < 1e-12 && b[3].stderr.is_nan());
    }

    #[test]
    fn slab_range_and_include_select_particles() {
        let omega = 1.0;
        let pos = [
            DVec3::new(0.055, 0.0, 0.015),    // in
            DVec3::new(0.055, 0.0, 0.020),    // z = z_hi: out
            DVec3::new(0.055, 0.0, 0.010),    // z = z_lo: in
            DVec3::new(0.055, 0.0, 0.005),    // below: out
            DVec3::new(0.20, 0.0, 0.015),     // r ≥ r_hi: out
            DVec3::new(0.001, 0.0, 0.015),    // r < r_lo: out
            DVec3::new(0.0, -0.06, 0.012),    // in, but excluded by `include`
            DVec3::new(f64::NAN, 0.0, 0.015), // excluded by `include`, never read
        ];
        let vel: Vec<DVec3> = pos
            .iter()
            .map(|p| DVec3::new(-omega * p.y, omega * p.x, 0.0))
            .collect();
        let mut prof = AzimuthalProfile::new(0.01, 0.10, 9, 0.010, 0.020).expect("binning");
        let n = prof
            .add_sample(&pos, &vel, |i| i < 6, omega)
            .expect("sample");
        assert_eq!(n, 2);
        assert_eq!(prof.samples(), 2);
        assert_eq!(prof.bins()[4].count, 2);
        // Including the NaN particle is an error and leaves the profile as it was.
        let before = prof.clone();
        assert_eq!(
            prof.add_sample(&pos, &vel, |_| true, omega),
            Err(BandError::NonFiniteParticle(7))
        );
        assert_eq!(prof, before);
    }

    #[test]
    fn profile_rejects_bad_input() {
        assert!(AzimuthalProfile::new(0.02, 0.01, 4, 0.0, 1.0).is_err());
        assert!(AzimuthalProfile::new(-0.01, 0.01, 4, 0.0, 1.0).is_err());
        assert!(AzimuthalProfile::new(0.0, 0.01, 0, 0.0, 1.0).is_err());
        assert!(AzimuthalProfile::new(0.0, 0.01, MAX_BINS + 1, 0.0, 1.0).is_err());
        assert!(AzimuthalProfile::new(0.0, 0.01, 4, 1.0, 1.0).is_err());
        assert!(AzimuthalProfile::new(0.0, f64::NAN, 4, 0.0, 1.0).is_err());
        let mut prof = AzimuthalProfile::new(0.0, 0.1, 4, 0.0, 1.0).expect("binning");
        let p = [DVec3::new(0.05, 0.0, 0.5)];
        let v = [DVec3::ZERO];
        assert!(matches!(
            prof.add_sample(&p, &[], |_| true, 1.0),
            Err(BandError::LengthMismatch { .. })
        ));
        assert_eq!(
            prof.add_sample(&p, &v, |_| true, 0.0),
            Err(BandError::InvalidOmega(0.0))
        );
        assert!(prof.add_sample(&p, &v, |_| true, f64::NAN).is_err());
        assert_eq!(prof.samples(), 0);
        assert_eq!(prof.snapshots(), 0);
        let other = AzimuthalProfile::new(0.0, 0.1, 5, 0.0, 1.0).expect("binning");
        assert_eq!(prof.merge(&other), Err(BandError::IncompatibleProfiles));
        assert!(prof.fit(2, 0.0).is_err());
    }

    #[test]
    fn merge_equals_accumulating_together_and_serde_round_trips() {
        let mut rng = Rng::seed_from_u64(2);
        let omega = 0.5;
        let new = || AzimuthalProfile::new(0.01, 0.1, 12, 0.0, 0.03).expect("binning");
        let (mut a, mut b, mut both) = (new(), new(), new());
        for k in 0..4 {
            let pos = cloud(&mut rng, 500, (0.0, 0.12), (-0.01, 0.04));
            let vel: Vec<DVec3> = pos
                .iter()
                .map(|_| {
                    DVec3::new(
                        rng.random_range(-0.05..0.05),
                        rng.random_range(-0.05..0.05),
                        0.0,
                    )
                })
                .collect();
            let half = if k % 2 == 0 { &mut a } else { &mut b };
            half.add_sample(&pos, &vel, |_| true, omega)
                .expect("sample");
            both.add_sample(&pos, &vel, |_| true, omega)
                .expect("sample");
        }
        a.merge(&b).expect("same binning");
        assert_eq!(a.snapshots(), 4);
        assert_eq!(a.samples(), both.samples());
        for (x, y) in a.bins().iter().zip(both.bins()) {
            assert_eq!(x.count, y.count);
            assert!((x.mean - y.mean).abs() < 1e-12);
            assert!((x.stderr - y.stderr).abs() < 1e-12);
        }
        let text = serde_json::to_string(&a).expect("serialise");
        let back: AzimuthalProfile = serde_json::from_str(&text).expect("deserialise");
        assert_eq!(back, a);
        let broken = text.replacen("\"count\":[", "\"count\":[1,", 1);
        assert!(serde_json::from_str::<AzimuthalProfile>(&broken).is_err());
    }

    #[test]
    fn profile_of_an_erf_flow_fits_back() {
        // Particles moving with ω(r) = ½[1 + erf((r − R_c)/W)] plus noise: the binned profile
        // fits back to R_c and W.
        let (c, w, omega) = (0.060, 0.010, 0.3);
        let mut rng = Rng::seed_from_u64(3);
        let mut prof = AzimuthalProfile::new(0.015, 0.110, 38, 0.02, 0.04).expect("binning");
        for _ in 0..5 {
            let pos = cloud(&mut rng, 3000, (0.015, 0.110), (0.0, 0.05));
            let vel: Vec<DVec3> = pos
                .iter()
                .map(|p| {
                    let r = p.x.hypot(p.y);
                    let z: f64 = StandardNormal.sample(&mut rng);
                    let ratio = erf_profile(r, c, w) + 0.05 * z;
                    let v_phi = ratio * omega * r;
                    DVec3::new(-v_phi * p.y / r, v_phi * p.x / r, 0.0)
                })
                .collect();
            prof.add_sample(&pos, &vel, |_| true, omega)
                .expect("sample");
        }
        let fit = prof.fit(5, 1e-3).expect("fit");
        assert!(fit.converged);
        assert!((fit.centre - c).abs() < 3.0 * fit.centre_err, "{fit:?}");
        assert!((fit.width - w).abs() < 3.0 * fit.width_err, "{fit:?}");
        assert!(fit.centre_err < 5e-4 && fit.width_err < 1e-3, "{fit:?}");
    }

    #[test]
    fn surface_of_a_lattice() {
        // A simple cubic lattice of spheres of radius a (spacing 2a) filling x, y ∈ [−L, L]
        // and five layers with centres at z = a, 3a, …, 9a: the surface is at 10a.
        let a = 1.1e-3;
        let m = 60;
        let mut pos = Vec::new();
        for i in -m..=m {
            for j in -m..=m {
                for l in 0..5 {
                    pos.push(DVec3::new(
                        2.0 * a * i as f64,
                        2.0 * a * j as f64,
                        a + 2.0 * a * l as f64,
                    ));
                }
            }
        }
        let radii = vec![a; pos.len()];
        let h = surface_height(&pos, &radii, |_| true, 0.02, 0.12, 4.0 * a).expect("surface");
        assert!((h - 10.0 * a).abs() < 1e-12, "{h}");
        // One particle higher: only its column rises, by 2a, so the mean rises by 2a/columns.
        let mut raised = pos.clone();
        raised.push(DVec3::new(0.05, 0.0, 11.0 * a));
        let mut radii2 = radii.clone();
        radii2.push(a);
        let h2 = surface_height(&raised, &radii2, |_| true, 0.02, 0.12, 4.0 * a).expect("surface");
        assert!(h2 > h && h2 - h < 2.0 * a * 0.01, "{h} {h2}");
        // ... unless it is excluded.
        let last = raised.len() - 1;
        let h3 =
            surface_height(&raised, &radii2, |i| i != last, 0.02, 0.12, 4.0 * a).expect("surface");
        assert_eq!(h3, h);
        // A 30° wedge of the same lattice: only its columns count.
        let wedge = |i: usize| {
            let p = pos[i];
            let phi = p.y.atan2(p.x);
            (0.0..std::f64::consts::FRAC_PI_6).contains(&phi)
        };
        let hw = surface_height(&pos, &radii, wedge, 0.02, 0.12, 4.0 * a).expect("surface");
        assert!((hw - 10.0 * a).abs() < 1e-12, "{hw}");
        // Excluding the top layer lowers the surface by 2a.
        let below = |i: usize| i % 5 != 4;
        let hb = surface_height(&pos, &radii, below, 0.02, 0.12, 4.0 * a).expect("surface");
        assert!((hb - 8.0 * a).abs() < 1e-12, "{hb}");
    }

    #[test]
    fn surface_height_of_nothing_or_bad_arguments_is_none() {
        let pos = [DVec3::new(0.05, 0.0, 0.01)];
        let a = [1e-3];
        assert!(surface_height(&pos, &a, |_| true, 0.02, 0.1, 4e-3).is_some());
        assert_eq!(surface_height(&pos, &a, |_| false, 0.02, 0.1, 4e-3), None);
        assert_eq!(surface_height(&pos, &a, |_| true, 0.06, 0.1, 4e-3), None);
        assert_eq!(surface_height(&pos, &[], |_| true, 0.02, 0.1, 4e-3), None);
        assert_eq!(surface_height(&pos, &a, |_| true, 0.02, 0.1, 0.0), None);
        assert_eq!(surface_height(&pos, &a, |_| true, 0.1, 0.02, 4e-3), None);
        assert_eq!(
            surface_height(&pos, &a, |_| true, 0.02, f64::NAN, 4e-3),
            None
        );
        assert_eq!(surface_height(&[], &[], |_| true, 0.02, 0.1, 4e-3), None);
    }

    /// In a periodic box: a flat layer of spheres on a grid gives its top; positions
    /// outside the box wrap into its columns; a grain sitting higher in one of four columns
    /// raises the mean by a quarter of its excess; bad arguments give none.
    #[test]
    fn surface_height_of_a_periodic_layer_is_its_mean_column_top() {
        let (lo, l) = (DVec3::new(0.0, 0.0, 0.0), DVec3::new(4.0, 4.0, 0.0));
        let mut pos: Vec<DVec3> = (0..4)
            .flat_map(|i| (0..4).map(move |j| DVec3::new(i as f64 + 0.5, j as f64 + 0.5, 1.0)))
            .collect();
        let mut a = vec![0.5; pos.len()];
        let h = |p: &[DVec3], a: &[f64]| surface_height_box(p, a, |_| true, lo, l, 2.0);
        assert_eq!(h(&pos, &a), Some(1.5));
        // The same layer shifted by whole box lengths: the same columns.
        let shifted: Vec<DVec3> = pos
            .iter()
            .map(|p| *p + DVec3::new(-4.0, 8.0, 0.0))
            .collect();
        assert_eq!(h(&shifted, &a), Some(1.5));
        pos.push(DVec3::new(0.5, 0.5, 3.0));
        a.push(0.5);
        assert_eq!(h(&pos, &a), Some(1.5 + 2.0 / 4.0));
        assert_eq!(surface_height_box(&pos, &a, |_| false, lo, l, 2.0), None);
        assert_eq!(
            surface_height_box(&pos, &a[1..], |_| true, lo, l, 2.0),
            None
        );
        assert_eq!(surface_height_box(&pos, &a, |_| true, lo, l, 0.0), None);
        assert_eq!(
            surface_height_box(&pos, &a, |_| true, lo, DVec3::ZERO, 2.0),
            None
        );
    }
}
