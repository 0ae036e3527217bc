//! Figures of the volume fraction under reversible adhesion against the law of Shi et al.
//! 2020 (docs/model.md §8.7), one of each per shear dynamics present:
//!
//! - `phi-vs-bo-*`: `φ` against `Bo` per `μ_p` at the report's `(I, p*)`, with Eq. 16
//!   (the paper's Fig. 6);
//! - `gc-vs-bo-*`: the measured cohesion factor against `Bo` per `μ_p`, with Eq. 15 (Fig. 7);
//! - `phi-collapse-*`: `φ/(φ_0 g_I g_c)` against `(1 + Bo) p*`, every point, with the line
//!   `1 + (1 + Bo) p*/p*_φ` (Fig. 8);
//! - `delta-phi-vs-mu-p-*`: `Δφ` against `μ_p` per `Bo`, with Eq. 17 over Eq. 1B (Fig. 10b).
//!
//! The law of a `μ_p` is the paper's row in Tables 3 and 5 where there is one, and Eq. 1B
//! (Table 8) elsewhere. Points with a cohesion law other than reversible adhesion are left
//! out (the laws describe that one); of several runs of one state the longest counts.

use super::phase_diagram::{Figure, Group, delta_phi_points, group_figure, longest_runs};
use super::sweep::PointResult;
use crate::contact::LawKind;
use crate::domain::ShearDynamics;
use crate::plot::Labels;
use crate::rheology::PhiLaw;

/// The law of `μ_p`: the paper's row, or Eq. 1B.
fn law(mu_p: f64) -> PhiLaw {
    PhiLaw::for_mu_p(mu_p).unwrap_or_else(|| PhiLaw::from_friction_dependence(mu_p))
}

/// `n + 1` evenly spaced values from `a` to `b`.
fn span(a: f64, b: f64, n: usize) -> impl Iterator<Item = f64> {
    (0..=n).map(move |k| a + (b - a) * k as f64 / n as f64)
}

/// The distinct values of `f` over `runs`, ascending.
fn distinct(runs: &[&PointResult], f: fn(&PointResult) -> f64) -> Vec<f64> {
    let mut v: Vec<f64> = runs.iter().map(|r| f(r)).collect();
    v.sort_by(f64::total_cmp);
    v.dedup();
    v
}

/// The volume fraction of a run: mean and standard error (NaN without a steady state,
/// which [`longest_runs`] never passes on).
fn phi(r: &PointResult) -> (f64, f64) {
    r.steady_state.as_ref().map_or((f64::NAN, f64::NAN), |s| {
        (s.volume_fraction.mean, s.volume_fraction.error)
    })
}

/// The measured cohesion factor of `r` against its cohesionless partner `r0` (same state
/// otherwise): `g_c = [φ(Bo)/φ(0)] · (1 + p*/p*_φ)/(1 + (1 + Bo) p*/p*_φ)`, which divides out
/// `φ_0 g_I` and so any offset of the measured `φ_0` from the table's. Standard error from
/// both runs' in quadrature.
pub fn measured_g_c(r: &PointResult, r0: &PointResult) -> (f64, f64) {
    let l = law(r.spec.mu_p);
    let (p, bo) = (r.spec.softness, r.spec.bond);
    let ((a, ea), (b, eb)) = (phi(r), phi(r0));
    let g = a / b * (1.0 + p / l.p_phi) / (1.0 + (1.0 + bo) * p / l.p_phi);
    (g, g * (ea / a).hypot(eb / b))
}

/// The collapse ordinate of Fig. 8, `φ/(φ_0 (1 − I/I_φ) g_c(Bo))`, with its standard error.
pub fn collapsed_phi(r: &PointResult) -> (f64, f64) {
    let l = law(r.spec.mu_p);
    let scale = l.phi_0 * (1.0 - r.spec.inertial / l.i_phi) * l.g_c(r.spec.bond);
    let (m, e) = phi(r);
    (m / scale, e / scale)
}

/// The four figures for every shear dynamics present in `results`, at the state
/// `(inertial, softness)` for the three that need one.
pub fn cohesion_figures(
    results: &[PointResult],
    inertial: f64,
    softness: f64,
) -> Result<Vec<Figure>, String> {
    let mut out = Vec::new();
    let usable = |r: &&PointResult| r.spec.cohesion == LawKind::Reversible || r.spec.bond == 0.0;
    let deltas = delta_phi_points(
        &results.iter().filter(usable).cloned().collect::<Vec<_>>(),
        inertial,
        softness,
    );
    for dynamics in ShearDynamics::ALL {
        let runs = longest_runs(
            results
                .iter()
                .filter(usable)
                .filter(|r| r.spec.shear_dynamics == dynamics),
        );
        if runs.is_empty() {
            continue;
        }
        let at_state: Vec<&PointResult> = runs
            .iter()
            .copied()
            .filter(|r| r.spec.inertial == inertial && r.spec.softness == softness)
            .collect();
        let state = format!("{dynamics}, I = {inertial}, p* = {softness}");
        if at_state.iter().any(|r| r.spec.bond > 0.0) {
            out.push(phi_vs_bond(
                &at_state, inertial, softness, &state, dynamics,
            )?);
            out.push(gc_vs_bond(&at_state, &state, dynamics)?);
        }
        out.push(collapse(&runs, dynamics)?);
        let ours: Vec<_> = deltas
            .iter()
            .filter(|d| d.dynamics == dynamics && d.bond > 0.0)
            .collect();
        let mut bonds: Vec<f64> = ours.iter().map(|d| d.bond).collect();
        bonds.sort_by(f64::total_cmp);
        bonds.dedup();
        if !bonds.is_empty() {
            let groups: Vec<Group> = bonds
                .iter()
                .map(|&bo| Group {
                    label: format!("Bo = {bo}"),
                    curve: span(0.0, 1.0, 100)
                        .map(|m| (m, law(m).delta_phi(inertial, softness, bo)))
                        .collect(),
                    points: ours
                        .iter()
                        .filter(|d| d.bond == bo)
                        .map(|d| (d.mu_p, d.value, d.error))
                        .collect(),
                })
                .collect();
            let title = format!("Δφ against μ_p, {state}");
            let axes = Labels {
                title: &title,
                x: "interparticle friction μ_p",
                y: "Δφ = φ(Bo) − φ(0)",
            };
            out.push(group_figure(
                &format!("delta-phi-vs-mu-p-{dynamics}"),
                &axes,
                "Eq. 17 with Eq. 1B",
                &groups,
            )?);
        }
    }
    Ok(out)
}

/// `φ` against `Bo` per `μ_p` (Fig. 6).
fn phi_vs_bond(
    runs: &[&PointResult],
    inertial: f64,
    softness: f64,
    state: &str,
    dynamics: ShearDynamics,
) -> Result<Figure, String> {
    let groups: Vec<Group> = distinct(runs, |r| r.spec.mu_p)
        .into_iter()
        .map(|m| Group {
            label: format!("μ_p = {m}"),
            curve: span(0.0, 5.0, 50)
                .map(|bo| (bo, law(m).phi(inertial, softness, bo)))
                .collect(),
            points: runs
                .iter()
                .filter(|r| r.spec.mu_p == m)
                .map(|r| {
                    let (v, e) = phi(r);
                    (r.spec.bond, v, e)
                })
                .collect(),
        })
        .collect();
    let title = format!("φ against Bo, {state}");
    let axes = Labels {
        title: &title,
        x: "Bond number Bo",
        y: "volume fraction φ",
    };
    group_figure(&format!("phi-vs-bo-{dynamics}"), &axes, "Eq. 16", &groups)
}

/// The measured `g_c` against `Bo` per `μ_p` (Fig. 7); points need a cohesionless partner.
fn gc_vs_bond(
    runs: &[&PointResult],
    state: &str,
    dynamics: ShearDynamics,
) -> Result<Figure, String> {
    let partner = |r: &PointResult| {
        runs.iter().copied().find(|q| {
            q.spec.bond == 0.0
                && q.spec.mu_p == r.spec.mu_p
                && q.spec.particles == r.spec.particles
                && q.spec.polydispersity == r.spec.polydispersity
        })
    };
    let groups: Vec<Group> = distinct(runs, |r| r.spec.mu_p)
        .into_iter()
        .map(|m| Group {
            label: format!("μ_p = {m}"),
            curve: span(0.0, 5.0, 50).map(|bo| (bo, law(m).g_c(bo))).collect(),
            points: runs
                .iter()
                .filter(|r| r.spec.mu_p == m)
                .filter_map(|r| {
                    let (g, e) = measured_g_c(r, partner(r)?);
                    Some((r.spec.bond, g, e))
                })
                .collect(),
        })
        .collect();
    let title = format!("Cohesion factor g_c against Bo, {state}");
    let axes = Labels {
        title: &title,
        x: "Bond number Bo",
        y: "g_c = φ(Bo)/φ(0) · (1 + p*/p*_φ)/(1 + (1+Bo)p*/p*_φ)",
    };
    group_figure(&format!("gc-vs-bo-{dynamics}"), &axes, "Eq. 15", &groups)
}

/// `φ/(φ_0 g_I g_c)` against `(1 + Bo) p*`, every run (Fig. 8).
fn collapse(runs: &[&PointResult], dynamics: ShearDynamics) -> Result<Figure, String> {
    let x = |r: &PointResult| (1.0 + r.spec.bond) * r.spec.softness;
    let top = runs.iter().map(|r| x(r)).fold(0.0, f64::max);
    let groups: Vec<Group> = distinct(runs, |r| r.spec.mu_p)
        .into_iter()
        .map(|m| Group {
            label: format!("μ_p = {m}"),
            curve: span(0.0, top, 20)
                .map(|s| (s, 1.0 + s / law(m).p_phi))
                .collect(),
            points: runs
                .iter()
                .filter(|r| r.spec.mu_p == m)
                .map(|r| {
                    let (v, e) = collapsed_phi(r);
                    (x(r), v, e)
                })
                .collect(),
        })
        .collect();
    let title = format!("Collapse of φ onto the softness term, {dynamics}");
    let axes = Labels {
        title: &title,
        x: "(1 + Bo) p*",
        y: "φ / (φ_0 (1 − I/I_φ) g_c(Bo))",
    };
    group_figure(
        &format!("phi-collapse-{dynamics}"),
        &axes,
        "1 + (1+Bo)p*/p*_φ",
        &groups,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::setups::sweep::synthetic_result;

    /// A run at `(μ_p, I, p*, Bo)` whose φ is the law's times `factor`.
    fn run(mu_p: f64, inertial: f64, softness: f64, bond: f64, factor: f64) -> PointResult {
        let phi = law(mu_p).phi(inertial, softness, bond) * factor;
        synthetic_result(
            &format!(
                "mu_p = {mu_p}\ninertial = {inertial}\nsoftness = {softness}\nbond = {bond}\n\
                 cohesion = \"{}\"",
                if bond > 0.0 { "reversible" } else { "none" }
            ),
            phi,
            0.001,
        )
    }

    /// Points on the law give back `g_c` of Eq. 15 and the collapse line exactly, also when
    /// every `φ` is off by one factor (the measured `g_c` divides it out); the figures build.
    #[test]
    fn points_on_the_law_fall_on_its_curves() {
        for (mu_p, factor) in [(0.1, 1.0), (0.3, 0.98), (0.25, 1.01)] {
            let r0 = run(mu_p, 0.02, 0.01, 0.0, factor);
            for bo in [1.0, 3.0, 5.0] {
                let r = run(mu_p, 0.02, 0.01, bo, factor);
                let (g, e) = measured_g_c(&r, &r0);
                assert!((g - law(mu_p).g_c(bo)).abs() < 1e-12, "{mu_p} {bo}: {g}");
                assert!(e > 0.0 && e < 0.01);
                let (c, _) = collapsed_phi(&r);
                let line = 1.0 + (1.0 + bo) * 0.01 / law(mu_p).p_phi;
                assert!((c / factor - line).abs() < 1e-12, "{c} against {line}");
            }
        }
        let results: Vec<PointResult> = [0.0, 2.0, 4.0]
            .iter()
            .flat_map(|&bo| [run(0.1, 0.02, 0.01, bo, 1.0), run(0.3, 0.02, 0.01, bo, 1.0)])
            .chain([run(0.1, 0.05, 0.005, 0.0, 1.0)])
            .collect();
        let figs = cohesion_figures(&results, 0.02, 0.01).expect("figures");
        let names: Vec<&str> = figs.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "phi-vs-bo-lab",
                "gc-vs-bo-lab",
                "phi-collapse-lab",
                "delta-phi-vs-mu-p-lab"
            ]
        );
        assert!(figs.iter().all(|f| f.png.starts_with(b"\x89PNG")));
        // No cohesive point: only the collapse.
        let dry = [run(0.1, 0.05, 0.005, 0.0, 1.0)];
        let figs = cohesion_figures(&dry, 0.02, 0.01).expect("figures");
        assert_eq!(figs.len(), 1);
    }
}
