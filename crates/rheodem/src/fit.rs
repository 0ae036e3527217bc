//! Weighted nonlinear least squares for any model with a few parameters (Levenberg–Marquardt,
//! the `levenberg-marquardt` crate), with parameter uncertainties and residual statistics.
//! The rheology laws are fitted with it (`rheology::fitting`).
//!
//! The model is a function `f(params, i)` giving the prediction for data point `i`; the
//! Jacobian is taken by central differences. At the optimum the covariance of the
//! parameters is `C = (Jᵀ W J)⁻¹ · χ²_red`, with `W = diag(1/σ_i²)` and
//! `χ²_red = χ² / (n − k)`: the standard errors reflect the observed scatter about the fit,
//! as `scipy.optimize.curve_fit` does by default. Only the relative weights of the `σ_i`
//! therefore matter.

use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::storage::Owned;
use nalgebra::{DMatrix, DVector, Dyn};
use serde::Serialize;

/// Why a fit failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FitError {
    /// Fewer data points than parameters plus one.
    #[error("{points} point(s) for {params} parameter(s): at least {} are needed", params + 1)]
    TooFewPoints {
        /// Points given.
        points: usize,
        /// Parameters fitted.
        params: usize,
    },
    /// No point of the kind a closed-form estimate needs lies inside the fit range.
    #[error("no {what} point inside the fit range")]
    NoPointInRange {
        /// The kind of point needed.
        what: &'static str,
    },
    /// The data and their standard errors differ in length.
    #[error("{values} values but {sigmas} standard errors")]
    LengthMismatch {
        /// Values given.
        values: usize,
        /// Standard errors given.
        sigmas: usize,
    },
    /// A value, standard error or initial parameter is not finite, or a standard error is not
    /// positive.
    #[error("{what} {index} is {value}: must be finite{}", if *what == "standard error" { " and positive" } else { "" })]
    BadInput {
        /// Which input.
        what: &'static str,
        /// Its index.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// The minimisation gave non-finite parameters, or the covariance is singular (a
    /// parameter the data do not determine).
    #[error("the fit diverged: {0}")]
    Diverged(String),
}

/// The result of [`least_squares`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fit {
    /// Best parameters.
    pub params: Vec<f64>,
    /// Their standard errors, `sqrt(C_jj)`.
    pub errors: Vec<f64>,
    /// Covariance matrix `C` (row-major, `k × k`).
    pub covariance: Vec<Vec<f64>>,
    /// Root-mean-square residual `sqrt(Σ (y_i − f_i)² / n)` (units of `y`).
    pub rms: f64,
    /// `χ² / (n − k)` with the given standard errors.
    pub reduced_chi2: f64,
    /// Number of data points `n`.
    pub points: usize,
    /// Whether the minimiser reported convergence.
    pub converged: bool,
}

struct Problem<'a, M> {
    model: &'a M,
    y: &'a [f64],
    sigma: &'a [f64],
    p: DVector<f64>,
}

impl<M: Fn(&[f64], usize) -> f64> Problem<'_, M> {
    fn jacobian_at(&self, p: &DVector<f64>) -> DMatrix<f64> {
        let (n, k) = (self.y.len(), p.len());
        let mut j = DMatrix::zeros(n, k);
        let mut q = p.as_slice().to_vec();
        for c in 0..k {
            // Central differences, step ∛ε relative (absolute near zero).
            let h = 6e-6 * p[c].abs().max(1e-4);
            q[c] = p[c] + h;
            let up: Vec<f64> = (0..n).map(|i| (self.model)(&q, i)).collect();
            q[c] = p[c] - h;
            for (i, u) in up.into_iter().enumerate() {
                j[(i, c)] = (u - (self.model)(&q, i)) / (2.0 * h) / self.sigma[i];
            }
            q[c] = p[c];
        }
        j
    }
}

impl<M: Fn(&[f64], usize) -> f64> LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_, M> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, p: &DVector<f64>) {
        self.p.copy_from(p);
    }

    fn params(&self) -> DVector<f64> {
        self.p.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        let p = self.p.as_slice();
        let r = DVector::from_iterator(
            self.y.len(),
            (0..self.y.len()).map(|i| ((self.model)(p, i) - self.y[i]) / self.sigma[i]),
        );
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let j = self.jacobian_at(&self.p);
        j.iter().all(|v| v.is_finite()).then_some(j)
    }
}

/// Fits the parameters of `model(params, i)` (the prediction for point `i`) to the values
/// `y` with standard errors `sigma`, starting from `initial`.
///
/// ```
/// use rheodem::fit::least_squares;
/// // y = a exp(−b x) through three exact points: a = 2, b = 0.5.
/// let x = [0.0f64, 1.0, 2.0, 3.0];
/// let y: Vec<f64> = x.iter().map(|x| 2.0 * (-0.5 * x).exp()).collect();
/// let fit = least_squares(|p, i| p[0] * (-p[1] * x[i]).exp(), &y, &[0.01; 4], &[1.0, 1.0])?;
/// assert!((fit.params[0] - 2.0).abs() < 1e-8 && (fit.params[1] - 0.5).abs() < 1e-8);
/// # Ok::<(), rheodem::fit::FitError>(())
/// ```
pub fn least_squares<M: Fn(&[f64], usize) -> f64>(
    model: M,
    y: &[f64],
    sigma: &[f64],
    initial: &[f64],
) -> Result<Fit, FitError> {
    let (n, k) = (y.len(), initial.len());
    if sigma.len() != n {
        return Err(FitError::LengthMismatch {
            values: n,
            sigmas: sigma.len(),
        });
    }
    if n <= k {
        return Err(FitError::TooFewPoints {
            points: n,
            params: k,
        });
    }
    let bad = |what, index, value| Err(FitError::BadInput { what, index, value });
    for (i, &v) in y.iter().enumerate() {
        if !v.is_finite() {
            return bad("value", i, v);
        }
    }
    for (i, &s) in sigma.iter().enumerate() {
        if !(s.is_finite() && s > 0.0) {
            return bad("standard error", i, s);
        }
    }
    for (i, &p) in initial.iter().enumerate() {
        if !p.is_finite() {
            return bad("initial parameter", i, p);
        }
    }
    let problem = Problem {
        model: &model,
        y,
        sigma,
        p: DVector::from_column_slice(initial),
    };
    let (problem, report) = LevenbergMarquardt::new()
        .with_patience(500)
        .minimize(problem);
    let p = problem.p.clone();
    if !p.iter().all(|v| v.is_finite()) {
        return Err(FitError::Diverged(format!(
            "non-finite parameters ({:?})",
            report.termination
        )));
    }
    let (mut chi2, mut sq) = (0.0, 0.0);
    for i in 0..n {
        let d = y[i] - model(p.as_slice(), i);
        sq += d * d;
        chi2 += (d / sigma[i]).powi(2);
    }
    if !chi2.is_finite() {
        return Err(FitError::Diverged(
            "non-finite residuals at the optimum".into(),
        ));
    }
    let j = problem.jacobian_at(&p);
    let jtj = j.transpose() * &j;
    let inverse = jtj
        .clone()
        .try_inverse()
        .filter(|c| c.iter().all(|v| v.is_finite()) && (0..k).all(|d| c[(d, d)] > 0.0))
        .ok_or_else(|| {
            FitError::Diverged(format!(
                "singular covariance at {:?}: the data do not determine every parameter",
                p.as_slice()
            ))
        })?;
    // A near-singular JᵀWJ inverts to garbage: check that it really is the inverse.
    let residual = (&jtj * &inverse - DMatrix::<f64>::identity(k, k))
        .abs()
        .max();
    if residual > 1e-6 {
        return Err(FitError::Diverged(format!(
            "ill-conditioned covariance (‖JᵀJ C − 1‖ = {residual:.1e}) at {:?}: the data barely \
             determine the parameters",
            p.as_slice()
        )));
    }
    let reduced_chi2 = chi2 / (n - k) as f64;
    let covariance: Vec<Vec<f64>> = (0..k)
        .map(|r| (0..k).map(|c| inverse[(r, c)] * reduced_chi2).collect())
        .collect();
    Ok(Fit {
        params: p.as_slice().to_vec(),
        errors: (0..k).map(|d| covariance[d][d].sqrt()).collect(),
        covariance,
        rms: (sq / n as f64).sqrt(),
        reduced_chi2,
        points: n,
        converged: report.termination.was_successful(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// A straight line against the closed-form weighted least squares.
    #[test]
    fn line_matches_the_closed_form() {
        let x = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
        let y = [0.9, 3.2, 4.8, 7.1, 9.2, 10.7];
        let fit =
            least_squares(|p, i| p[0] + p[1] * x[i], &y, &[1.0; 6], &[0.0, 0.0]).expect("fits");
        let n = x.len() as f64;
        let (sx, sy) = (x.iter().sum::<f64>(), y.iter().sum::<f64>());
        let sxx: f64 = x.iter().map(|v| v * v).sum();
        let sxy: f64 = x.iter().zip(&y).map(|(a, b)| a * b).sum();
        let slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
        let intercept = (sy - slope * sx) / n;
        assert!((fit.params[1] - slope).abs() < 1e-9 && (fit.params[0] - intercept).abs() < 1e-9);
        // Standard error of the slope: sqrt(s² n / (n Σx² − (Σx)²)), s² = χ²/(n − 2).
        let s2: f64 = x
            .iter()
            .zip(&y)
            .map(|(a, b)| (b - intercept - slope * a).powi(2))
            .sum::<f64>()
            / (n - 2.0);
        let e_slope = (s2 * n / (n * sxx - sx * sx)).sqrt();
        assert!((fit.errors[1] / e_slope - 1.0).abs() < 1e-6);
        assert!((fit.reduced_chi2 - s2).abs() < 1e-9);
    }

    /// An exponential decay with Gaussian noise of known σ, 400 times: each parameter's
    /// 1σ interval covers the truth in 68 % of the fits. With 400 draws the binomial spread
    /// of the rate is 2.3 %; the bounds 60–76 % are 3.4 spreads wide on each side.
    #[test]
    fn uncertainties_cover_the_truth_at_the_stated_rate() {
        let x: Vec<f64> = (0..30).map(|k| 0.1 * k as f64).collect();
        let truth = [2.0, 0.7];
        let noise = Normal::new(0.0, 0.02).expect("normal");
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(11);
        let trials = 400;
        let mut covered = [0usize; 2];
        for _ in 0..trials {
            let y: Vec<f64> = x
                .iter()
                .map(|&v| truth[0] * (-truth[1] * v).exp() + noise.sample(&mut rng))
                .collect();
            let fit = least_squares(
                |p, i| p[0] * (-p[1] * x[i]).exp(),
                &y,
                &vec![0.02; x.len()],
                &[1.0, 1.0],
            )
            .expect("fits");
            for k in 0..2 {
                if (fit.params[k] - truth[k]).abs() <= fit.errors[k] {
                    covered[k] += 1;
                }
            }
        }
        for (k, c) in covered.iter().enumerate() {
            let rate = *c as f64 / trials as f64;
            assert!(
                (0.60..=0.76).contains(&rate),
                "parameter {k}: covered {rate:.3}"
            );
        }
    }

    #[test]
    fn bad_input_and_undetermined_parameters_are_refused() {
        let y = [1.0, 2.0, 3.0];
        let e = least_squares(|p, _| p[0], &y, &[1.0; 2], &[0.0]).expect_err("lengths");
        assert_eq!(
            e,
            FitError::LengthMismatch {
                values: 3,
                sigmas: 2
            }
        );
        let e = least_squares(
            |p, i| p[0] + p[1] * i as f64 + p[2],
            &y,
            &[1.0; 3],
            &[0.0; 3],
        )
        .expect_err("too few");
        assert!(matches!(
            e,
            FitError::TooFewPoints {
                points: 3,
                params: 3
            }
        ));
        let e = least_squares(|p, _| p[0], &[1.0, f64::NAN], &[1.0; 2], &[0.0]).expect_err("NaN");
        assert!(e.to_string().contains("value 1 is NaN"), "{e}");
        let e = least_squares(|p, _| p[0], &y, &[1.0, 0.0, 1.0], &[0.0]).expect_err("σ = 0");
        assert!(e.to_string().contains("standard error 1"), "{e}");
        // Two parameters that enter only as their sum are not determined separately.
        let e = least_squares(|p, i| (p[0] + p[1]) * i as f64, &y, &[1.0; 3], &[0.5, 0.5])
            .expect_err("degenerate");
        assert!(matches!(e, FitError::Diverged(_)), "{e}");
    }
}
