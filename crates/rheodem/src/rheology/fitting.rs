//! Fits of the laws of Shi et al. 2020 to measured steady states (docs/model.md §8.6), with
//! the paper's fit ranges as defaults, and the fitted coefficients laid out like the paper's
//! Tables 3, 5, 7 and 8, side by side with its values.
//!
//! The fits go in the paper's order: at one `μ_p`, the cohesionless points fix `φ_0, I_φ,
//! p*_φ` (Eq. 13) and `μ_0, μ_∞, I_μ, p*_μ` (Eq. 1A at `Bo = 0`); with those held, the
//! cohesive points fix `p₁ … p₄` (Eq. 15) and `α₁, β₁`; across `μ_p`, each coefficient
//! follows Eq. 1B. Every fit weights the points by their standard errors and reports the
//! standard errors of its parameters and its RMS residual ([`crate::fit`]).

use super::{CohesionFactor, MuLaw, PhiLaw, SetUp, mu_laws, phi_laws};
use crate::fit::{Fit, FitError, least_squares};
use serde::Serialize;
use std::fmt::Write;

/// A measured steady state, as the fits need it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MeasuredPoint {
    /// Interparticle friction `μ_p`.
    pub mu_p: f64,
    /// Inertial number `I` (from the measured pressure).
    pub inertial: f64,
    /// Softness `p*` (from the measured pressure).
    pub softness: f64,
    /// Bond number `Bo` (from the measured pressure).
    pub bond: f64,
    /// Volume fraction `φ`: mean and standard error.
    pub phi: (f64, f64),
    /// Macroscopic friction `μ`: mean and standard error.
    pub mu: (f64, f64),
}

/// Where the points used by a fit must lie (Shi et al. 2020, Sects. 3.1 and Appendix 1).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FitRange {
    /// Smallest `φ` (exclusive).
    pub phi_min: f64,
    /// Smallest `I` (exclusive; 0 for none).
    pub inertial_min: f64,
    /// Largest `I` (exclusive).
    pub inertial_max: f64,
    /// Largest `p*` (exclusive).
    pub softness_max: f64,
}

impl FitRange {
    /// The range of the volume-fraction fits: `φ > 0.5`, `I < 0.25`, `p* < 0.03`.
    pub const PHI: FitRange = FitRange {
        phi_min: 0.5,
        inertial_min: 0.0,
        inertial_max: 0.25,
        softness_max: 0.03,
    };
    /// The range of the friction fits: `φ > 0.5`, `0.005 < I < 0.5`, `p* < 0.1`.
    pub const MU: FitRange = FitRange {
        phi_min: 0.5,
        inertial_min: 0.005,
        inertial_max: 0.5,
        softness_max: 0.1,
    };

    /// Whether `p` lies inside the range.
    pub fn contains(&self, p: &MeasuredPoint) -> bool {
        p.phi.0 > self.phi_min
            && p.inertial > self.inertial_min
            && p.inertial < self.inertial_max
            && p.softness < self.softness_max
    }
}

/// A fitted set of named coefficients.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CoefficientFit {
    /// Interparticle friction of the points.
    pub mu_p: f64,
    /// The coefficients' names, in the order of `fit.params`.
    pub names: Vec<&'static str>,
    /// The fit.
    pub fit: Fit,
}

/// Smallest standard error a point is given (a point averaged without scatter must not
/// take all the weight).
const SIGMA_FLOOR: f64 = 1e-6;

fn selected<'a>(
    points: &'a [MeasuredPoint],
    range: &FitRange,
    cohesive: bool,
) -> Vec<&'a MeasuredPoint> {
    points
        .iter()
        .filter(|p| range.contains(p) && (cohesive || p.bond == 0.0))
        .collect()
}

/// The tabulated row of a table nearest to `mu_p` (the fits' starting point).
fn nearest<T: Copy>(rows: &[T], mu_p: f64, key: impl Fn(&T) -> f64) -> T {
    *rows
        .iter()
        .min_by(|a, b| (key(a) - mu_p).abs().total_cmp(&(key(b) - mu_p).abs()))
        .expect("shipped tables are not empty")
}

/// `φ_0, I_φ, p*_φ` (Eq. 13) from the cohesionless points in `range`, all at one `μ_p`.
pub fn fit_phi_law(points: &[MeasuredPoint], range: &FitRange) -> Result<CoefficientFit, FitError> {
    let pts = selected(points, range, false);
    let mu_p = pts.first().map_or(0.0, |p| p.mu_p);
    let start = nearest(phi_laws(), mu_p, |l| l.mu_p);
    let y: Vec<f64> = pts.iter().map(|p| p.phi.0).collect();
    let s: Vec<f64> = pts.iter().map(|p| p.phi.1.max(SIGMA_FLOOR)).collect();
    let fit = least_squares(
        |q, i| q[0] * (1.0 - pts[i].inertial / q[1]) * (1.0 + pts[i].softness / q[2]),
        &y,
        &s,
        &[start.phi_0, start.i_phi, start.p_phi],
    )?;
    Ok(CoefficientFit {
        mu_p,
        names: vec!["phi_0", "I_phi", "p_phi"],
        fit,
    })
}

/// The volume-fraction law at `mu_p` for a sweep too narrow in `(I, p*)` to fit Eq. 13 (a
/// phase diagram at one `I` and `p*`): `I_φ` and `p*_φ` held at Table 3's row nearest to
/// `mu_p`, and `φ_0` the error-weighted mean of `φ / ((1 − I/I_φ)(1 + p*/p*_φ))` over the
/// cohesionless points in `range`, so that the law passes through them. An error if no
/// cohesionless point is in range.
pub fn anchor_phi_0(
    points: &[MeasuredPoint],
    range: &FitRange,
    mu_p: f64,
) -> Result<AnchoredPhiLaw, FitError> {
    let held = nearest(phi_laws(), mu_p, |l| l.mu_p);
    let (mut sum_w, mut sum_wx) = (0.0, 0.0);
    for p in selected(points, range, false) {
        let shape = (1.0 - p.inertial / held.i_phi) * (1.0 + p.softness / held.p_phi);
        let sigma = p.phi.1.max(SIGMA_FLOOR) / shape;
        let w = 1.0 / (sigma * sigma);
        sum_w += w;
        sum_wx += w * p.phi.0 / shape;
    }
    if sum_w == 0.0 {
        return Err(FitError::NoPointInRange {
            what: "cohesionless (Bo = 0)",
        });
    }
    Ok(AnchoredPhiLaw {
        law: PhiLaw {
            mu_p,
            phi_0: sum_wx / sum_w,
            gc: [0.0; 4],
            ..held
        },
        phi_0_error: sum_w.powf(-0.5),
        table_mu_p: held.mu_p,
    })
}

/// Eq. 13 anchored at the cohesionless points ([`anchor_phi_0`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnchoredPhiLaw {
    /// The law: `φ_0` estimated, `I_φ` and `p*_φ` from Table 3, `g_c = 1`.
    pub law: PhiLaw,
    /// Standard error of `φ_0`.
    pub phi_0_error: f64,
    /// The `μ_p` of the Table 3 row that `I_φ` and `p*_φ` come from.
    pub table_mu_p: f64,
}

/// `p₁ … p₄` of `g_c` (Eq. 15) from the cohesive points in `range`, with `φ_0, I_φ, p*_φ`
/// held at `base` (a point at `Bo = 0` has `g_c = 1` whatever `p₁ … p₄` are, so it says
/// nothing about them and does not count towards the points the fit needs).
pub fn fit_cohesion_factor(
    points: &[MeasuredPoint],
    range: &FitRange,
    base: &PhiLaw,
) -> Result<CoefficientFit, FitError> {
    let pts: Vec<&MeasuredPoint> = selected(points, range, true)
        .into_iter()
        .filter(|p| p.bond > 0.0)
        .collect();
    let y: Vec<f64> = pts.iter().map(|p| p.phi.0).collect();
    let s: Vec<f64> = pts.iter().map(|p| p.phi.1.max(SIGMA_FLOOR)).collect();
    let model = |q: &[f64], i: usize| {
        let law = PhiLaw {
            gc: [q[0], q[1], q[2], q[3]],
            ..*base
        };
        let p = pts[i];
        law.phi(p.inertial, p.softness, p.bond)
    };
    let fit = least_squares(
        model,
        &y,
        &s,
        &nearest(phi_laws(), base.mu_p, |l| l.mu_p).gc,
    )?;
    Ok(CoefficientFit {
        mu_p: base.mu_p,
        names: vec!["p1", "p2", "p3", "p4"],
        fit,
    })
}

/// `μ_0, μ_∞, I_μ, p*_μ` (Eq. 1A at `Bo = 0`) from the cohesionless points in `range`.
pub fn fit_mu_law(points: &[MeasuredPoint], range: &FitRange) -> Result<CoefficientFit, FitError> {
    let pts = selected(points, range, false);
    let mu_p = pts.first().map_or(0.0, |p| p.mu_p);
    let simple: Vec<MuLaw> = mu_laws()
        .iter()
        .copied()
        .filter(|l| l.setup == SetUp::SimpleShear)
        .collect();
    let start = nearest(&simple, mu_p, |l| l.mu_p);
    let y: Vec<f64> = pts.iter().map(|p| p.mu.0).collect();
    let s: Vec<f64> = pts.iter().map(|p| p.mu.1.max(SIGMA_FLOOR)).collect();
    let model = |q: &[f64], i: usize| {
        let law = MuLaw {
            mu_0: q[0],
            mu_inf: q[1],
            i_mu: q[2],
            p_mu: q[3],
            cohesion: CohesionFactor::Linear { slope: 0.0 },
            ..start
        };
        law.mu(pts[i].inertial, pts[i].softness, 0.0)
    };
    let fit = least_squares(
        model,
        &y,
        &s,
        &[start.mu_0, start.mu_inf, start.i_mu, start.p_mu],
    )?;
    Ok(CoefficientFit {
        mu_p,
        names: vec!["mu_0", "mu_inf", "I_mu", "p_mu"],
        fit,
    })
}

/// `α₁, β₁` of `f_Bo = 1 + α₁ Bo^β₁` from every point in `range`, with the rest of Eq. 1A
/// held at `base`.
pub fn fit_mu_cohesion(
    points: &[MeasuredPoint],
    range: &FitRange,
    base: &MuLaw,
) -> Result<CoefficientFit, FitError> {
    let pts = selected(points, range, true);
    let y: Vec<f64> = pts.iter().map(|p| p.mu.0).collect();
    let s: Vec<f64> = pts.iter().map(|p| p.mu.1.max(SIGMA_FLOOR)).collect();
    let model = |q: &[f64], i: usize| {
        let law = MuLaw {
            cohesion: CohesionFactor::Power {
                alpha: q[0],
                beta: q[1],
            },
            ..*base
        };
        law.mu(pts[i].inertial, pts[i].softness, pts[i].bond)
    };
    let fit = least_squares(model, &y, &s, &[0.4, 1.5])?;
    Ok(CoefficientFit {
        mu_p: base.mu_p,
        names: vec!["alpha_1", "beta_1"],
        fit,
    })
}

/// `Q_∞, Q_0, μ_p⁰` of Eq. 1B from a coefficient's values `q` (standard errors `sigma`) at
/// the frictions `mu_p`.
pub fn fit_friction_dependence(mu_p: &[f64], q: &[f64], sigma: &[f64]) -> Result<Fit, FitError> {
    let (lo, hi) = mu_p.iter().zip(q).fold(
        ((f64::INFINITY, 0.0), (f64::NEG_INFINITY, 0.0)),
        |(lo, hi), (&m, &v)| {
            (
                if m < lo.0 { (m, v) } else { lo },
                if m > hi.0 { (m, v) } else { hi },
            )
        },
    );
    let s: Vec<f64> = sigma.iter().map(|s| s.max(SIGMA_FLOOR)).collect();
    least_squares(
        |c, i| c[0] + (c[1] - c[0]) * (-mu_p[i] / c[2]).exp(),
        q,
        &s,
        &[hi.1, lo.1, 0.3],
    )
}

/// `value ± error` with as many decimals as the error's first two significant digits need.
pub fn with_error(value: f64, error: f64) -> String {
    let decimals = if error > 0.0 && error.is_finite() {
        (1.0 - error.log10().floor()).clamp(1.0, 8.0) as usize
    } else {
        4
    };
    format!("{value:.decimals$} ± {error:.decimals$}")
}

/// A markdown table of fitted coefficients (one row per fit, `label` naming the rows'
/// source) with the paper's values (`paper(μ_p)`, one per name, where it has a row) below
/// each fitted row.
pub fn coefficient_table(
    title: &str,
    label: &str,
    fits: &[CoefficientFit],
    paper: impl Fn(f64) -> Option<Vec<f64>>,
) -> String {
    let mut s = String::new();
    let Some(first) = fits.first() else {
        let _ = writeln!(s, "{title}: no fit.");
        return s;
    };
    let _ = writeln!(s, "{title}\n");
    let _ = write!(s, "| μ_p | source |");
    for n in &first.names {
        let _ = write!(s, " {n} |");
    }
    let _ = writeln!(s, " points | RMS residual | χ²_red |");
    let _ = write!(s, "|---|---|");
    for _ in &first.names {
        let _ = write!(s, "---|");
    }
    let _ = writeln!(s, "---|---|---|");
    for f in fits {
        let _ = write!(s, "| {} | {label} |", f.mu_p);
        for (v, e) in f.fit.params.iter().zip(&f.fit.errors) {
            let _ = write!(s, " {} |", with_error(*v, *e));
        }
        let _ = writeln!(
            s,
            " {} | {:.2e} | {:.2} |",
            f.fit.points, f.fit.rms, f.fit.reduced_chi2
        );
        if let Some(values) = paper(f.mu_p) {
            let _ = write!(s, "| {} | Shi et al. 2020 |", f.mu_p);
            for v in values {
                let _ = write!(s, " {v} |");
            }
            let _ = writeln!(s, " | | |");
        }
    }
    s
}

/// The paper's Table 3 values at `μ_p`, if tabulated.
pub fn paper_table3(mu_p: f64) -> Option<Vec<f64>> {
    PhiLaw::for_mu_p(mu_p).map(|l| vec![l.phi_0, l.i_phi, l.p_phi])
}

/// The paper's Table 5 values at `μ_p`, if tabulated.
pub fn paper_table5(mu_p: f64) -> Option<Vec<f64>> {
    PhiLaw::for_mu_p(mu_p).map(|l| l.gc.to_vec())
}

/// The paper's Table 7 values (`μ_0, μ_∞, I_μ, p*_μ`) at `μ_p`, simple shear, if tabulated.
pub fn paper_table7(mu_p: f64) -> Option<Vec<f64>> {
    MuLaw::for_mu_p(mu_p).map(|l| vec![l.mu_0, l.mu_inf, l.i_mu, l.p_mu])
}

/// The paper's Table 7 cohesion values (`α₁, β₁`) at `μ_p`, simple shear, if tabulated.
pub fn paper_table7_cohesion(mu_p: f64) -> Option<Vec<f64>> {
    MuLaw::for_mu_p(mu_p).and_then(|l| match l.cohesion {
        CohesionFactor::Power { alpha, beta } => Some(vec![alpha, beta]),
        CohesionFactor::Linear { .. } => None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// Points on the μ_p = 0.3 laws at a grid of `(I, p*, Bo)` with noise of the size the
    /// shear box measures (`φ` ± 0.0003, `μ` ± 0.003).
    fn synthetic(seed: u64, truth_phi: &PhiLaw, truth_mu: &MuLaw) -> Vec<MeasuredPoint> {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
        let (n_phi, n_mu) = (
            Normal::new(0.0, 3e-4).expect("σ"),
            Normal::new(0.0, 3e-3).expect("σ"),
        );
        let mut out = Vec::new();
        for &i in &[0.005, 0.01, 0.02, 0.05, 0.1, 0.2] {
            for &p in &[0.002, 0.005, 0.01, 0.02] {
                for &bo in &[0.0, 0.5, 1.0, 2.0, 3.0, 4.0, 5.0] {
                    out.push(MeasuredPoint {
                        mu_p: truth_phi.mu_p,
                        inertial: i,
                        softness: p,
                        bond: bo,
                        phi: (truth_phi.phi(i, p, bo) + n_phi.sample(&mut rng), 3e-4),
                        mu: (truth_mu.mu(i, p, bo) + n_mu.sample(&mut rng), 3e-3),
                    });
                }
            }
        }
        out
    }

    /// Every fit recovers the coefficients the data were made with, within 3 of its standard
    /// errors (a 0.3 % chance each for a Gaussian estimate), and its RMS residual is the
    /// noise's.
    #[test]
    fn fits_recover_known_coefficients() {
        let truth_phi = PhiLaw {
            mu_p: 0.3,
            ..PhiLaw::for_mu_p(0.3).expect("tabulated")
        };
        let truth_mu = MuLaw {
            mu_p: 0.3,
            ..MuLaw::for_mu_p(0.5).expect("tabulated")
        };
        let pts = synthetic(5, &truth_phi, &truth_mu);
        let check = |f: &CoefficientFit, truth: &[f64]| {
            for (k, t) in truth.iter().enumerate() {
                let (v, e) = (f.fit.params[k], f.fit.errors[k]);
                assert!((v - t).abs() < 3.0 * e, "{}: {v} ± {e} vs {t}", f.names[k]);
            }
        };
        let phi = fit_phi_law(&pts, &FitRange::PHI).expect("φ fit");
        check(&phi, &[truth_phi.phi_0, truth_phi.i_phi, truth_phi.p_phi]);
        assert!(
            (phi.fit.rms / 3e-4 - 1.0).abs() < 0.3,
            "rms {}",
            phi.fit.rms
        );
        // 6 I values below 0.25, 4 p* values below 0.03, Bo = 0.
        assert_eq!(phi.fit.points, 24);
        let base = PhiLaw {
            phi_0: phi.fit.params[0],
            i_phi: phi.fit.params[1],
            p_phi: phi.fit.params[2],
            ..truth_phi
        };
        let gc = fit_cohesion_factor(&pts, &FitRange::PHI, &base).expect("g_c fit");
        check(&gc, &truth_phi.gc);
        let mu = fit_mu_law(&pts, &FitRange::MU).expect("μ fit");
        check(
            &mu,
            &[truth_mu.mu_0, truth_mu.mu_inf, truth_mu.i_mu, truth_mu.p_mu],
        );
        let CohesionFactor::Power { alpha, beta } = truth_mu.cohesion else {
            panic!("simple-shear row");
        };
        let coh = fit_mu_cohesion(&pts, &FitRange::MU, &truth_mu).expect("α, β fit");
        check(&coh, &[alpha, beta]);
        // The table puts the paper's row under the fitted one.
        let table = coefficient_table("Table 3", "fit", &[phi], paper_table3);
        assert!(
            table.contains("| 0.3 | Shi et al. 2020 | 0.61 | 5.166 | 0.283 |"),
            "{table}"
        );
    }

    /// A phase-diagram column (one `I`, `p*`; `Bo` = 0 … 5): `φ_0` anchored at the `Bo = 0`
    /// point and `g_c` fitted over the rest recover the law the data were made with.
    #[test]
    fn one_state_point_column_recovers_phi_0_and_g_c() {
        let truth = PhiLaw::for_mu_p(0.3).expect("tabulated");
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(11);
        let noise = Normal::new(0.0, 3e-4).expect("σ");
        let pts: Vec<MeasuredPoint> = (0..=10)
            .map(|k| {
                let bo = 0.5 * k as f64;
                MeasuredPoint {
                    mu_p: 0.3,
                    inertial: 0.02,
                    softness: 0.01,
                    bond: bo,
                    phi: (truth.phi(0.02, 0.01, bo) + noise.sample(&mut rng), 3e-4),
                    mu: (0.4, 3e-3),
                }
            })
            .collect();
        assert!(fit_phi_law(&pts, &FitRange::PHI).is_err(), "one (I, p*)");
        let anchored = anchor_phi_0(&pts, &FitRange::PHI, 0.3).expect("a Bo = 0 point");
        assert_eq!(anchored.table_mu_p, 0.3);
        let (v, e) = (anchored.law.phi_0, anchored.phi_0_error);
        assert!((v - truth.phi_0).abs() < 3.0 * e, "{v} ± {e}");
        let gc = fit_cohesion_factor(&pts, &FitRange::PHI, &anchored.law).expect("g_c");
        assert_eq!(gc.fit.points, 10, "the Bo = 0 point does not count");
        for (k, t) in truth.gc.iter().enumerate() {
            let (v, e) = (gc.fit.params[k], gc.fit.errors[k]);
            assert!((v - t).abs() < 3.0 * e, "{}: {v} ± {e} vs {t}", gc.names[k]);
        }
        let none = anchor_phi_0(&pts[1..], &FitRange::PHI, 0.3).expect_err("no Bo = 0");
        assert!(none.to_string().contains("cohesionless"), "{none}");
    }

    #[test]
    fn friction_dependence_recovers_table_8() {
        let row = super::super::friction_dependences()[0];
        let mu_p = [0.0, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0];
        let q: Vec<f64> = mu_p.iter().map(|&m| row.at(m)).collect();
        let fit = fit_friction_dependence(&mu_p, &q, &[1e-4; 8]).expect("fits");
        for (v, t) in fit.params.iter().zip([row.q_inf, row.q_0, row.mu_p0]) {
            assert!((v - t).abs() < 1e-6 * t.abs().max(1.0), "{v} vs {t}");
        }
    }

    #[test]
    fn points_outside_the_range_are_left_out() {
        let p = |i, s, phi| MeasuredPoint {
            mu_p: 0.01,
            inertial: i,
            softness: s,
            bond: 0.0,
            phi: (phi, 1e-3),
            mu: (0.3, 1e-3),
        };
        assert!(FitRange::PHI.contains(&p(0.1, 0.01, 0.6)));
        assert!(!FitRange::PHI.contains(&p(0.3, 0.01, 0.6)));
        assert!(!FitRange::PHI.contains(&p(0.1, 0.05, 0.6)));
        assert!(!FitRange::PHI.contains(&p(0.1, 0.01, 0.45)));
        assert!(!FitRange::MU.contains(&p(0.004, 0.01, 0.6)));
        assert!(FitRange::MU.contains(&p(0.3, 0.05, 0.6)));
        let e = fit_phi_law(&[p(0.1, 0.01, 0.6), p(0.3, 0.01, 0.6)], &FitRange::PHI)
            .expect_err("one point in range");
        assert!(
            matches!(
                e,
                FitError::TooFewPoints {
                    points: 1,
                    params: 3
                }
            ),
            "{e}"
        );
    }
}
