//! The laws of Shi et al. 2020 fitted to a sweep's finished shear-box points
//! (`rheodem fit`; docs/model.md §8.6): one group per `μ_p` and shear dynamics, the fits of
//! `rheology::fitting` in the paper's order, and the tables in the paper's layout.

use super::sweep::PointResult;
use crate::domain::ShearDynamics;
use crate::rheology::fitting::{
    CoefficientFit, FitRange, MeasuredPoint, anchor_phi_0, coefficient_table, fit_cohesion_factor,
    fit_friction_dependence, fit_mu_cohesion, fit_mu_law, fit_phi_law, paper_table3, paper_table5,
    paper_table7, paper_table7_cohesion, with_error,
};
use crate::rheology::{CohesionFactor, MuLaw, PhiLaw, SetUp, friction_dependences};
use std::fmt::Write;

/// The steady states of `results` as fit points, grouped by `(shear dynamics, μ_p)` in that
/// order. Points without a steady state are left out; where several runs share a state
/// point (same `μ_p, I, p*, Bo`, cohesion law, dynamics, size and polydispersity), the one
/// averaged over the most strain is kept.
pub fn fit_groups(results: &[PointResult]) -> Vec<(ShearDynamics, f64, Vec<MeasuredPoint>)> {
    let chosen = super::phase_diagram::longest_runs(results.iter());
    let mut groups: Vec<(ShearDynamics, f64, Vec<MeasuredPoint>)> = Vec::new();
    for r in chosen {
        let ss = r.steady_state.as_ref().expect("filtered");
        let point = MeasuredPoint {
            mu_p: r.spec.mu_p,
            inertial: ss.inertial_measured,
            softness: ss.softness_measured,
            bond: ss.bond_measured,
            phi: (ss.volume_fraction.mean, ss.volume_fraction.error),
            mu: (ss.friction.mean, ss.friction.error),
        };
        let key = (r.spec.shear_dynamics, r.spec.mu_p);
        match groups.iter_mut().find(|g| (g.0, g.1) == key) {
            Some(g) => g.2.push(point),
            None => groups.push((key.0, key.1, vec![point])),
        }
    }
    let rank = |d: ShearDynamics| ShearDynamics::ALL.iter().position(|&x| x == d);
    groups.sort_by(|a, b| rank(a.0).cmp(&rank(b.0)).then(a.1.total_cmp(&b.1)));
    groups
}

/// Fitted `φ` laws of one group, where its points determine them.
struct GroupFits {
    phi: Option<CoefficientFit>,
    gc: Option<CoefficientFit>,
    mu: Option<CoefficientFit>,
    mu_cohesion: Option<CoefficientFit>,
    /// Eq. 13 that `g_c` multiplies: fitted, or anchored at the `Bo = 0` points.
    phi_base: Option<PhiLaw>,
    /// Eq. 1A at `Bo = 0` as fitted.
    mu_base: Option<MuLaw>,
    /// Values a fit held because the points could not determine them, one line each.
    held: Vec<String>,
    /// Why a fit was not made, one line per fit.
    notes: Vec<String>,
}

fn fit_group(mu_p: f64, points: &[MeasuredPoint]) -> GroupFits {
    let mut notes = Vec::new();
    let mut keep = |what: &str, r: Result<CoefficientFit, crate::fit::FitError>| match r {
        Ok(f) => Some(f),
        Err(e) => {
            notes.push(format!("μ_p = {mu_p}, {what}: {e}"));
            None
        }
    };
    let phi_fit = fit_phi_law(points, &FitRange::PHI);
    let cohesive = points.iter().filter(|p| p.bond > 0.0).count();
    let mut held = Vec::new();
    // The law g_c multiplies: the fitted Eq. 13 where the points determine it, otherwise
    // (a sweep at one I and p*, as the phase diagram) anchored at the Bo = 0 point.
    let base = match &phi_fit {
        Ok(f) => Some(Ok(PhiLaw {
            mu_p,
            phi_0: f.fit.params[0],
            i_phi: f.fit.params[1],
            p_phi: f.fit.params[2],
            gc: [0.0; 4],
        })),
        Err(_) if cohesive > 0 => match anchor_phi_0(points, &FitRange::PHI, mu_p) {
            Ok(anchored) => {
                let law = anchored.law;
                held.push(format!(
                    "μ_p = {mu_p}: too few (I, p*) to fit Eq. 13, so g_c multiplies φ_0 = {} \
                     through the Bo = 0 point(s), with I_φ = {} and p*_φ = {} held at Table 3's \
                     row for μ_p = {}",
                    with_error(law.phi_0, anchored.phi_0_error),
                    law.i_phi,
                    law.p_phi,
                    anchored.table_mu_p
                ));
                Some(Ok(law))
            }
            Err(e) => Some(Err(e)),
        },
        Err(_) => None,
    };
    let phi = keep("φ_0, I_φ, p*_φ", phi_fit);
    let mut phi_base = None;
    let gc = match base {
        Some(Ok(base)) => {
            phi_base = Some(base);
            if cohesive > 0 {
                keep(
                    "p₁ … p₄",
                    fit_cohesion_factor(points, &FitRange::PHI, &base),
                )
            } else {
                None
            }
        }
        Some(Err(e)) => keep("p₁ … p₄", Err(e)),
        None => None,
    };
    let mu = keep("μ_0, μ_∞, I_μ, p*_μ", fit_mu_law(points, &FitRange::MU));
    let mu_base = mu.as_ref().map(|f| MuLaw {
        mu_p,
        setup: SetUp::SimpleShear,
        mu_0: f.fit.params[0],
        mu_inf: f.fit.params[1],
        i_mu: f.fit.params[2],
        p_mu: f.fit.params[3],
        cohesion: CohesionFactor::Linear { slope: 0.0 },
        linear_slope: None,
    });
    let mu_cohesion = match mu_base {
        Some(base) if cohesive > 0 => keep("α₁, β₁", fit_mu_cohesion(points, &FitRange::MU, &base)),
        _ => None,
    };
    GroupFits {
        phi,
        gc,
        mu,
        mu_cohesion,
        phi_base,
        mu_base,
        held,
        notes,
    }
}

/// The laws fitted to one group of points (one shear dynamics and `μ_p`), ready to draw.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FittedLaws {
    /// Shear dynamics of the points.
    pub dynamics: ShearDynamics,
    /// Interparticle friction of the points.
    pub mu_p: f64,
    /// Eq. 13 with the fitted `φ_0, I_φ, p*_φ` (`g_c = 1`), where fitted.
    pub phi: Option<PhiLaw>,
    /// Eq. 16: the law `g_c` was fitted on (fitted or anchored at `Bo = 0`) with the
    /// fitted `p₁ … p₄`, where fitted.
    pub phi_cohesive: Option<PhiLaw>,
    /// Eq. 1A at `Bo = 0` with the fitted `μ_0, μ_∞, I_μ, p*_μ`, where fitted.
    pub mu: Option<MuLaw>,
    /// Eq. 1A with the fitted cohesion factor `1 + α₁ Bo^β₁` as well, where fitted.
    pub mu_cohesive: Option<MuLaw>,
}

/// The fitted laws of every group of `results` ([`fit_groups`]), in the same order.
pub fn fitted_laws(results: &[PointResult]) -> Vec<FittedLaws> {
    fit_groups(results)
        .iter()
        .map(|(dynamics, mu_p, points)| {
            let f = fit_group(*mu_p, points);
            let phi_cohesive = match (f.phi_base, &f.gc) {
                (Some(base), Some(gc)) => Some(PhiLaw {
                    gc: [
                        gc.fit.params[0],
                        gc.fit.params[1],
                        gc.fit.params[2],
                        gc.fit.params[3],
                    ],
                    ..base
                }),
                _ => None,
            };
            let mu_cohesive = match (f.mu_base, &f.mu_cohesion) {
                (Some(base), Some(c)) => Some(MuLaw {
                    cohesion: CohesionFactor::Power {
                        alpha: c.fit.params[0],
                        beta: c.fit.params[1],
                    },
                    ..base
                }),
                _ => None,
            };
            FittedLaws {
                dynamics: *dynamics,
                mu_p: *mu_p,
                phi: f.phi.as_ref().and(f.phi_base),
                phi_cohesive,
                mu: f.mu_base,
                mu_cohesive,
            }
        })
        .collect()
}

/// The fitted coefficients of every group as markdown tables laid out like Shi et al.
/// 2020, Tables 3, 5, 7 and (with fits at three or more `μ_p`) 8, each fitted row followed
/// by the paper's row for the same `μ_p`; then the fits that could not be made, and why.
pub fn fit_tables(results: &[PointResult]) -> String {
    let mut s = String::new();
    let groups = fit_groups(results);
    if groups.is_empty() {
        return "No finished point with a steady state to fit.\n".into();
    }
    for dynamics in ShearDynamics::ALL {
        let fits: Vec<(f64, GroupFits)> = groups
            .iter()
            .filter(|g| g.0 == dynamics)
            .map(|g| (g.1, fit_group(g.1, &g.2)))
            .collect();
        if fits.is_empty() {
            continue;
        }
        let counts: Vec<String> = groups
            .iter()
            .filter(|g| g.0 == dynamics)
            .map(|g| format!("{} at μ_p = {}", g.2.len(), g.1))
            .collect();
        let _ = writeln!(
            s,
            "## Shear dynamics: {dynamics}\n\nPoints: {}. Fit ranges: φ > 0.5, I < 0.25, \
             p* < 0.03 (φ); φ > 0.5, 0.005 < I < 0.5, p* < 0.1 (μ).\n",
            counts.join(", ")
        );
        let label = format!("this work ({dynamics})");
        let collect = |pick: fn(&GroupFits) -> &Option<CoefficientFit>| -> Vec<CoefficientFit> {
            fits.iter().filter_map(|(_, f)| pick(f).clone()).collect()
        };
        let phi = collect(|f| &f.phi);
        s += &coefficient_table(
            "Volume fraction, Eq. 13 (Table 3)",
            &label,
            &phi,
            paper_table3,
        );
        s += "\n";
        s += &coefficient_table(
            "Cohesion factor g_c, Eq. 15 (Table 5)",
            &label,
            &collect(|f| &f.gc),
            paper_table5,
        );
        s += "\n";
        s += &coefficient_table(
            "Macroscopic friction, Eq. 1A at Bo = 0 (Table 7)",
            &label,
            &collect(|f| &f.mu),
            paper_table7,
        );
        s += "\n";
        s += &coefficient_table(
            "Cohesion factor of μ, f_Bo = 1 + α₁ Bo^β₁ (Table 7)",
            &label,
            &collect(|f| &f.mu_cohesion),
            paper_table7_cohesion,
        );
        s += "\n";
        if phi.len() >= 3 {
            s += &table8(&phi, &label);
            s += "\n";
        }
        s += &bullets("Held", fits.iter().flat_map(|(_, f)| &f.held));
        s += &bullets("Not fitted", fits.iter().flat_map(|(_, f)| &f.notes));
    }
    s
}

/// `title:` and one bullet per line of `lines`, then a blank line; nothing without lines.
fn bullets<'a>(title: &str, lines: impl Iterator<Item = &'a String>) -> String {
    let body: String = lines.map(|l| format!("- {l}\n")).collect();
    if body.is_empty() {
        String::new()
    } else {
        format!("{title}:\n{body}\n")
    }
}

/// Eq. 1B fitted to `φ_0, I_φ, p*_φ` across the groups, beside the paper's Table 8.
fn table8(phi: &[CoefficientFit], label: &str) -> String {
    let mut s = String::from(
        "Friction dependence, Eq. 1B (Table 8)\n\n| coefficient | source | Q_∞ | Q_0 | μ_p⁰ | RMS residual |\n|---|---|---|---|---|---|\n",
    );
    let mu_p: Vec<f64> = phi.iter().map(|f| f.mu_p).collect();
    for (k, paper) in friction_dependences().iter().take(3).enumerate() {
        let q: Vec<f64> = phi.iter().map(|f| f.fit.params[k]).collect();
        let e: Vec<f64> = phi.iter().map(|f| f.fit.errors[k]).collect();
        match fit_friction_dependence(&mu_p, &q, &e) {
            Ok(f) => {
                let _ = writeln!(
                    s,
                    "| {} | {label} | {:.4} ± {:.4} | {:.4} ± {:.4} | {:.4} ± {:.4} | {:.2e} |",
                    paper.coefficient,
                    f.params[0],
                    f.errors[0],
                    f.params[1],
                    f.errors[1],
                    f.params[2],
                    f.errors[2],
                    f.rms
                );
            }
            Err(e) => {
                let _ = writeln!(
                    s,
                    "| {} | {label} | not fitted: {e} | | | |",
                    paper.coefficient
                );
            }
        }
        let _ = writeln!(
            s,
            "| {} | Shi et al. 2020 | {} | {} | {} | {} |",
            paper.coefficient, paper.q_inf, paper.q_0, paper.mu_p0, paper.rms
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::setups::sweep::synthetic_result;

    /// Points on Eq. 16 at `μ_p = 0.01` (Tables 3 and 5), over `I` and `p*` at `Bo = 0` and
    /// over `Bo` = 1 … 5 at `I = 0.02`, `p* = 0.01`: the fitted laws give those `φ` back.
    #[test]
    fn fitted_laws_reproduce_the_points_they_were_fitted_on() {
        let truth = PhiLaw::for_mu_p(0.01).expect("tabulated");
        let point = |i: f64, p: f64, bo: f64| {
            synthetic_result(
                &format!(
                    "mu_p = 0.01\ninertial = {i}\nsoftness = {p}\nbond = {bo}\ncohesion = \"{}\"",
                    if bo > 0.0 { "reversible" } else { "none" }
                ),
                truth.phi(i, p, bo),
                1e-4,
            )
        };
        let mut results = Vec::new();
        for i in [0.005, 0.02, 0.05, 0.1] {
            for p in [0.002, 0.01, 0.02] {
                results.push(point(i, p, 0.0));
            }
        }
        for bo in [1.0, 2.0, 3.0, 4.0, 5.0] {
            results.push(point(0.02, 0.01, bo));
        }
        let laws = fitted_laws(&results);
        assert_eq!(laws.len(), 1);
        let (phi, cohesive) = (
            laws[0].phi.expect("Eq. 13 fitted"),
            laws[0].phi_cohesive.expect("g_c fitted"),
        );
        for i in [0.005, 0.05, 0.1] {
            let (a, b) = (phi.phi(i, 0.01, 0.0), truth.phi(i, 0.01, 0.0));
            assert!((a - b).abs() < 1e-6, "I = {i}: {a} vs {b}");
        }
        for bo in [1.0, 3.0, 5.0] {
            let (a, b) = (cohesive.phi(0.02, 0.01, bo), truth.phi(0.02, 0.01, bo));
            assert!((a - b).abs() < 1e-6, "Bo = {bo}: {a} vs {b}");
        }
    }
}
