//! The three regimes of the `Δφ(μ_p, Bo)` phase diagram (Shi et al. 2020, Sect. 3.3;
//! docs/model.md §8.4): each `μ_p` column of measured `Δφ` classified, and the `μ_p` where
//! the regimes change, against the paper's `μ_p ≈ 0.027` and `≈ 0.40`.
//!
//! A column (one `μ_p`, `Bo > 0`) is in regime (i) when no `Δφ` is a significant dilation,
//! (iii) when the `Δφ` at the largest `Bo` is one, and (ii) otherwise: dilation at some `Bo`
//! and compression (or no significant change) again at the largest. "Significant" means
//! beyond [`SIGNIFICANCE`] standard errors. The boundary (i)/(ii) is where the most negative
//! `Δφ` of a column crosses zero, (ii)/(iii) where the `Δφ` at the largest `Bo` does (so it
//! depends on that `Bo`, as the paper notes), both linear in `μ_p` between neighbouring
//! columns.

use super::phase_diagram::DeltaPhi;
use crate::domain::ShearDynamics;
use crate::rheology::{PhiLaw, REGIME_I_MAX_MU_P, REGIME_II_MAX_MU_P, Regime};
use std::fmt::Write;

/// How many standard errors make a `Δφ` a significant compression or dilation.
pub const SIGNIFICANCE: f64 = 2.0;

/// A short label of a measured column's regime.
fn label(r: Regime) -> &'static str {
    match r {
        Regime::Compression => "(i) compression",
        Regime::Reentrant => "(ii) dilation, then compression",
        Regime::Dilation => "(iii) dilation",
    }
}

/// The regime of one column of `(Bo, Δφ, standard error)` with `Bo > 0`, in any order;
/// `None` when it is empty.
pub fn classify(column: &[(f64, f64, f64)]) -> Option<Regime> {
    let last = column.iter().max_by(|a, b| a.0.total_cmp(&b.0))?;
    let dilates = |&(_, v, e): &(f64, f64, f64)| v < -SIGNIFICANCE * e;
    Some(if !column.iter().any(dilates) {
        Regime::Compression
    } else if dilates(last) {
        Regime::Dilation
    } else {
        Regime::Reentrant
    })
}

/// The `μ_p` where `f` (one value per ascending `μ_p`) first changes sign, linear between
/// the two columns; `None` if it never does.
fn crossing(columns: &[(f64, f64)]) -> Option<f64> {
    columns.windows(2).find_map(|w| {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        ((y0 > 0.0) != (y1 > 0.0)).then(|| x0 + (x1 - x0) * y0 / (y0 - y1))
    })
}

/// The two boundaries of columns `(μ_p, [(Bo, Δφ)])` sorted by `μ_p`: where the most
/// negative `Δφ` crosses zero, and where the `Δφ` at `bond_max` does (columns without a
/// point at `bond_max` left out of the second).
fn boundaries(columns: &[(f64, Vec<(f64, f64)>)], bond_max: f64) -> (Option<f64>, Option<f64>) {
    let lowest: Vec<(f64, f64)> = columns
        .iter()
        .map(|(m, c)| (*m, c.iter().map(|p| p.1).fold(f64::INFINITY, f64::min)))
        .collect();
    let at_max: Vec<(f64, f64)> = columns
        .iter()
        .filter_map(|(m, c)| c.iter().find(|p| p.0 == bond_max).map(|p| (*m, p.1)))
        .collect();
    (crossing(&lowest), crossing(&at_max))
}

/// The law's boundaries (Eq. 16 with the coefficients of Eq. 1B) at `(I, p*)` over the
/// `bonds` given, on a grid of 1001 `μ_p` in `[0, 1]`.
pub fn law_boundaries(inertial: f64, softness: f64, bonds: &[f64]) -> (Option<f64>, Option<f64>) {
    let bond_max = bonds.iter().copied().fold(0.0, f64::max);
    let columns: Vec<(f64, Vec<(f64, f64)>)> = (0..=1000)
        .map(|k| {
            let mu_p = k as f64 / 1000.0;
            let law = PhiLaw::from_friction_dependence(mu_p);
            let col = bonds
                .iter()
                .map(|&bo| (bo, law.delta_phi(inertial, softness, bo)))
                .collect();
            (mu_p, col)
        })
        .collect();
    boundaries(&columns, bond_max)
}

fn show(b: Option<f64>) -> String {
    b.map_or_else(|| "not crossed".into(), |x| format!("{x:.3}"))
}

/// The regimes of measured `points` (as [`super::phase_diagram::delta_phi_points`] gives
/// them) as Markdown: per shear dynamics, a table of the columns (`Δφ` per `Bo` and the
/// regime), then the boundaries beside the law's at `(I, p*)` and the paper's.
pub fn regimes_markdown(points: &[DeltaPhi], inertial: f64, softness: f64) -> String {
    let mut md = String::new();
    let mut bonds: Vec<f64> = points
        .iter()
        .filter(|p| p.bond > 0.0)
        .map(|p| p.bond)
        .collect();
    bonds.sort_by(f64::total_cmp);
    bonds.dedup();
    let Some(&bond_max) = bonds.last() else {
        return "No cohesive point with a cohesionless partner yet.\n".into();
    };
    let law = law_boundaries(inertial, softness, &bonds);
    for dynamics in ShearDynamics::ALL {
        let mut mus: Vec<f64> = points
            .iter()
            .filter(|p| p.dynamics == dynamics && p.bond > 0.0)
            .map(|p| p.mu_p)
            .collect();
        mus.sort_by(f64::total_cmp);
        mus.dedup();
        if mus.is_empty() {
            continue;
        }
        let _ = writeln!(md, "### Shear dynamics: {dynamics}\n");
        let _ = write!(md, "| μ_p |");
        for b in &bonds {
            let _ = write!(md, " Δφ at Bo = {b} |");
        }
        let _ = writeln!(md, " regime |");
        let _ = writeln!(md, "|---|{}---|", "---|".repeat(bonds.len()));
        let mut columns = Vec::new();
        for &mu_p in &mus {
            let col: Vec<(f64, f64, f64)> = points
                .iter()
                .filter(|p| p.dynamics == dynamics && p.mu_p == mu_p && p.bond > 0.0)
                .map(|p| (p.bond, p.value, p.error))
                .collect();
            let _ = write!(md, "| {mu_p} |");
            for b in &bonds {
                match col.iter().find(|p| p.0 == *b) {
                    Some(p) => {
                        let _ = write!(md, " {:+.4} ± {:.4} |", p.1, p.2);
                    }
                    None => md += " – |",
                }
            }
            let complete = col.len() == bonds.len();
            let regime = classify(&col).expect("column has a cohesive point");
            let _ = writeln!(
                md,
                " {}{} |",
                label(regime),
                if complete { "" } else { " (so far)" }
            );
            if complete {
                columns.push((mu_p, col.iter().map(|p| (p.0, p.1)).collect()));
            }
        }
        let ours = boundaries(&columns, bond_max);
        let _ = writeln!(
            md,
            "\nBoundaries (complete columns only; Bo up to {bond_max}): (i)/(ii) at μ_p = {}, \
             (ii)/(iii) at μ_p = {}; the law (Eq. 16 with Eq. 1B) over the same Bo: {} and {}; \
             the paper's data: {} and {}.\n",
            show(ours.0),
            show(ours.1),
            show(law.0),
            show(law.1),
            REGIME_I_MAX_MU_P,
            REGIME_II_MAX_MU_P
        );
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_are_classified_by_their_significant_signs() {
        // Compression throughout, and a dilation within the noise: (i).
        let c = [
            (1.0, 0.002, 0.001),
            (3.0, -0.001, 0.001),
            (5.0, 0.03, 0.001),
        ];
        assert_eq!(classify(&c), Some(Regime::Compression));
        // Dilation, then compression at the largest Bo: (ii).
        let c = [
            (1.0, -0.02, 0.001),
            (3.0, -0.01, 0.001),
            (5.0, 0.004, 0.001),
        ];
        assert_eq!(classify(&c), Some(Regime::Reentrant));
        // Dilation, then no significant change at the largest Bo: still (ii).
        let c = [(5.0, 0.0005, 0.001), (1.0, -0.02, 0.001)];
        assert_eq!(classify(&c), Some(Regime::Reentrant));
        // Dilation up to the largest Bo: (iii).
        let c = [(1.0, -0.02, 0.001), (5.0, -0.01, 0.001)];
        assert_eq!(classify(&c), Some(Regime::Dilation));
        assert_eq!(classify(&[]), None);
    }

    #[test]
    fn a_boundary_lies_where_the_interpolated_column_value_is_zero() {
        let x = crossing(&[(0.0, 0.01), (0.1, 0.03), (0.3, -0.01)]).expect("crossed");
        assert!((x - 0.25).abs() < 1e-12, "{x}");
        assert_eq!(crossing(&[(0.0, -0.01), (1.0, -0.02)]), None);
        // The lowest Δφ crosses between 0.1 and 0.2, the one at Bo = 5 between 0.2 and 0.4.
        let cols = vec![
            (0.1, vec![(1.0, 0.01), (5.0, 0.05)]),
            (0.2, vec![(1.0, -0.01), (5.0, 0.02)]),
            (0.4, vec![(1.0, -0.03), (5.0, -0.02)]),
        ];
        let (a, b) = boundaries(&cols, 5.0);
        assert!((a.expect("crossed") - 0.15).abs() < 1e-12);
        assert!((b.expect("crossed") - 0.3).abs() < 1e-12);
    }

    /// The law's own map at the paper's `I = 0.02`, `p* = 0.01` over `Bo` = 1 … 5 turns
    /// from (i) to (ii) near the paper's `μ_p ≈ 0.027` (at 0.049), but never reaches (iii):
    /// the law over-predicts `φ` at large `Bo` (the paper says so of its Fig. 10), so its `Δφ`
    /// at `Bo = 5` stays positive up to `μ_p = 1`, where the data dilate beyond `μ_p ≈ 0.40`.
    #[test]
    fn the_law_turns_to_regime_ii_but_not_to_iii() {
        let (a, b) = law_boundaries(0.02, 0.01, &[1.0, 2.0, 3.0, 4.0, 5.0]);
        let a = a.expect("(i)/(ii)");
        assert!((0.02..0.08).contains(&a), "{a}");
        assert_eq!(b, None);
    }
}
