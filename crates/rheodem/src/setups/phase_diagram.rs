//! The relative dilation `Δφ = φ(Bo) − φ(0)` over `(μ_p, Bo)` (Shi et al. 2020, Sect. 3.3,
//! Figs. 9–11; docs/model.md §8.4): measured points from a sweep, the map interpolated from
//! them and from the laws, the compression/dilation boundary `Δφ = 0`, and the figures.

use super::sweep::PointResult;
use crate::domain::ShearDynamics;
use crate::plot::{HeatMap, Labels, Markers, Series, plot_png, plot_svg};
use crate::rheology::PhiLaw;
use rustc_hash::FxHashMap;

/// One measured `Δφ`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeltaPhi {
    /// Shear dynamics of both runs.
    pub dynamics: ShearDynamics,
    /// Interparticle friction.
    pub mu_p: f64,
    /// Bond number of the cohesive run.
    pub bond: f64,
    /// `φ(Bo) − φ(0)`.
    pub value: f64,
    /// Standard error, the two runs' errors combined in quadrature.
    pub error: f64,
}

/// Of the runs with a steady-state average, the one averaged over the most strain for each
/// state point (shear dynamics, `μ_p`, `I`, `p*`, `Bo`, cohesion, size and polydispersity);
/// the first of equals. In the order first met.
pub fn longest_runs<'a>(results: impl Iterator<Item = &'a PointResult>) -> Vec<&'a PointResult> {
    let window = |r: &PointResult| r.spec.strain - r.spec.transient_strain;
    let mut best: Vec<&PointResult> = Vec::new();
    for r in results.filter(|r| r.steady_state.is_some()) {
        let same = |c: &&PointResult| {
            let (a, b) = (&c.spec, &r.spec);
            a.shear_dynamics == b.shear_dynamics
                && a.mu_p == b.mu_p
                && a.inertial == b.inertial
                && a.softness == b.softness
                && a.bond == b.bond
                && a.cohesion == b.cohesion
                && a.particles == b.particles
                && a.polydispersity == b.polydispersity
        };
        match best.iter_mut().find(|c| same(c)) {
            Some(c) if window(c) < window(r) => *c = r,
            Some(_) => {}
            None => best.push(r),
        }
    }
    best
}

/// `Δφ` of every point of `results` with a steady-state average at `(I, p*)` =
/// `(inertial, softness)` (nominal controls) that has a cohesionless partner with the same
/// `μ_p`, dynamics, size and polydispersity; the partner itself gives `Δφ = 0`. Points
/// whose window failed the halves test are included, as in the validation table, which
/// flags them. Where several runs share a point the one averaged over the most strain is
/// used.
pub fn delta_phi_points(results: &[PointResult], inertial: f64, softness: f64) -> Vec<DeltaPhi> {
    let best = longest_runs(
        results
            .iter()
            .filter(|r| r.spec.inertial == inertial && r.spec.softness == softness),
    );
    let mut out = Vec::new();
    for r in &best {
        let reference = best.iter().find(|q| {
            q.spec.bond == 0.0
                && q.spec.shear_dynamics == r.spec.shear_dynamics
                && q.spec.mu_p == r.spec.mu_p
                && q.spec.particles == r.spec.particles
                && q.spec.polydispersity == r.spec.polydispersity
        });
        let (Some(q), Some(a)) = (reference, r.steady_state.as_ref()) else {
            continue;
        };
        let b = q.steady_state.as_ref().expect("filtered");
        let (fa, fb) = (a.volume_fraction, b.volume_fraction);
        out.push(DeltaPhi {
            dynamics: r.spec.shear_dynamics,
            mu_p: r.spec.mu_p,
            bond: r.spec.bond,
            value: fa.mean - fb.mean,
            error: if r.spec.bond == 0.0 {
                0.0
            } else {
                fa.error.hypot(fb.error)
            },
        });
    }
    out.sort_by(|a, b| a.mu_p.total_cmp(&b.mu_p).then(a.bond.total_cmp(&b.bond)));
    out
}

/// A scalar on a regular grid: `values[ix + xs.len() * iy]`, `xs` = `μ_p`, `ys` = `Bo`.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// `μ_p` of the columns, ascending and evenly spaced.
    pub xs: Vec<f64>,
    /// `Bo` of the rows, ascending and evenly spaced.
    pub ys: Vec<f64>,
    /// The values, row by row.
    pub values: Vec<f64>,
}

/// `n` evenly spaced values from `a` to `b`.
fn spaced(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| a + (b - a) * k as f64 / (n - 1) as f64)
        .collect()
}

/// `Δφ` of the laws (Eq. 16 with the coefficients of Eq. 1B, Table 8) at `(I, p*)` on an
/// `nx × ny` grid over `0 ≤ μ_p ≤ 1`, `0 ≤ Bo ≤ 5`.
pub fn law_grid(inertial: f64, softness: f64, nx: usize, ny: usize) -> Grid {
    let (xs, ys) = (spaced(0.0, 1.0, nx), spaced(0.0, 5.0, ny));
    let values = ys
        .iter()
        .flat_map(|&bo| {
            xs.iter().map(move |&mu_p| {
                PhiLaw::from_friction_dependence(mu_p).delta_phi(inertial, softness, bo)
            })
        })
        .collect();
    Grid { xs, ys, values }
}

/// Bilinear interpolation of `(μ_p, Bo, value)` points that fill a rectilinear grid (every
/// combination of their distinct `μ_p` and `Bo`, spacings free) onto an `nx × ny` regular
/// grid over the same extent. The error names a missing combination.
pub fn interpolate(points: &[(f64, f64, f64)], nx: usize, ny: usize) -> Result<Grid, String> {
    let distinct = |f: fn(&(f64, f64, f64)) -> f64| {
        let mut v: Vec<f64> = points.iter().map(f).collect();
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    };
    let (gx, gy) = (distinct(|p| p.0), distinct(|p| p.1));
    if gx.len() < 2 || gy.len() < 2 {
        return Err(format!(
            "{} μ_p and {} Bo values: a map needs at least 2 of each",
            gx.len(),
            gy.len()
        ));
    }
    let mut at = FxHashMap::default();
    for &(x, y, v) in points {
        at.insert((x.to_bits(), y.to_bits()), v);
    }
    let value = |i: usize, j: usize| {
        at.get(&(gx[i].to_bits(), gy[j].to_bits()))
            .copied()
            .ok_or_else(|| format!("no point at μ_p = {}, Bo = {}", gx[i], gy[j]))
    };
    let cell = |g: &[f64], t: f64| {
        let k = g.partition_point(|&v| v <= t).clamp(1, g.len() - 1) - 1;
        (k, ((t - g[k]) / (g[k + 1] - g[k])).clamp(0.0, 1.0))
    };
    let (xs, ys) = (
        spaced(gx[0], gx[gx.len() - 1], nx),
        spaced(gy[0], gy[gy.len() - 1], ny),
    );
    let mut values = Vec::with_capacity(nx * ny);
    for &y in &ys {
        let (j, v) = cell(&gy, y);
        for &x in &xs {
            let (i, u) = cell(&gx, x);
            let f = (1.0 - u) * (1.0 - v) * value(i, j)?
                + u * (1.0 - v) * value(i + 1, j)?
                + u * v * value(i + 1, j + 1)?
                + (1.0 - u) * v * value(i, j + 1)?;
            values.push(f);
        }
    }
    Ok(Grid { xs, ys, values })
}

/// The line `value = 0` of a grid by marching squares, as one curve whose branches are
/// separated by NaN points (the form [`HeatMap`] overlays take). Saddle cells are resolved
/// by the mean of their corners.
pub fn zero_contour(g: &Grid) -> Vec<(f64, f64)> {
    let nx = g.xs.len();
    let v = |i: usize, j: usize| g.values[i + nx * j];
    // The crossing on the edge between two grid nodes, keyed by the nodes so that the two
    // cells sharing an edge produce the same point.
    let crossing = |a: (usize, usize), b: (usize, usize)| -> Option<(f64, f64)> {
        let (a, b) = if (a.1, a.0) < (b.1, b.0) {
            (a, b)
        } else {
            (b, a)
        };
        let (fa, fb) = (v(a.0, a.1), v(b.0, b.1));
        // Zero counts as positive, so a node exactly on the line is crossed only once.
        if !(fa.is_finite() && fb.is_finite()) || (fa >= 0.0) == (fb >= 0.0) {
            return None;
        }
        let t = fa / (fa - fb);
        let (xa, ya, xb, yb) = (g.xs[a.0], g.ys[a.1], g.xs[b.0], g.ys[b.1]);
        Some((xa + t * (xb - xa), ya + t * (yb - ya)))
    };
    let mut segments: Vec<[(f64, f64); 2]> = Vec::new();
    for j in 0..g.ys.len().saturating_sub(1) {
        for i in 0..nx.saturating_sub(1) {
            let corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let hits: Vec<(f64, f64)> = (0..4)
                .filter_map(|e| crossing(corners[e], corners[(e + 1) % 4]))
                .collect();
            match hits.len() {
                2 => segments.push([hits[0], hits[1]]),
                4 => {
                    let mean = corners.iter().map(|c| v(c.0, c.1)).sum::<f64>() / 4.0;
                    // The corner (i, j) joins the centre when they share a sign.
                    if (mean >= 0.0) == (v(i, j) >= 0.0) {
                        segments.push([hits[0], hits[1]]);
                        segments.push([hits[2], hits[3]]);
                    } else {
                        segments.push([hits[1], hits[2]]);
                        segments.push([hits[3], hits[0]]);
                    }
                }
                _ => {}
            }
        }
    }
    segments.retain(|[a, b]| a != b);
    chain(segments)
}

/// Joins segments that share end points into polylines, separated by NaN points.
fn chain(mut segments: Vec<[(f64, f64); 2]>) -> Vec<(f64, f64)> {
    let key = |p: (f64, f64)| (p.0.to_bits(), p.1.to_bits());
    let mut out = Vec::new();
    while let Some([a, b]) = segments.pop() {
        let mut line = std::collections::VecDeque::from([a, b]);
        loop {
            let (front, back) = (key(line[0]), key(line[line.len() - 1]));
            let Some(k) = segments.iter().position(|s| {
                [key(s[0]), key(s[1])]
                    .iter()
                    .any(|e| *e == front || *e == back)
            }) else {
                break;
            };
            let [p, q] = segments.swap_remove(k);
            if key(p) == back {
                line.push_back(q);
            } else if key(q) == back {
                line.push_back(p);
            } else if key(p) == front {
                line.push_front(q);
            } else {
                line.push_front(p);
            }
        }
        if !out.is_empty() {
            out.push((f64::NAN, f64::NAN));
        }
        out.extend(line);
    }
    out
}

/// An image in both formats.
pub struct Figure {
    /// File stem.
    pub name: String,
    /// SVG document.
    pub svg: String,
    /// PNG image.
    pub png: Vec<u8>,
}

/// Measured points and the law's curve for one group (one `μ_p`, say), drawn in one colour.
#[derive(Clone, Debug, Default)]
pub struct Group {
    /// Legend label of the measured points; the curve's is `"<law>, <label>"`.
    pub label: String,
    /// The law's curve `(x, y)`; empty for none (the group keeps its colour).
    pub curve: Vec<(f64, f64)>,
    /// Measured `(x, y, standard error of y)`.
    pub points: Vec<(f64, f64, f64)>,
}

/// A line plot of groups: group `k`'s curve (labelled `"<law>, <label>"`) and points share
/// colour `k`.
pub fn group_figure(
    name: &str,
    axes: &Labels<'_>,
    law: &str,
    groups: &[Group],
) -> Result<Figure, String> {
    let curve_labels: Vec<String> = groups
        .iter()
        .map(|g| format!("{law}, {}", g.label))
        .collect();
    let series: Vec<Series> = groups
        .iter()
        .zip(&curve_labels)
        .map(|(g, label)| Series {
            dashed_as: None,
            label,
            points: &g.curve,
        })
        .collect();
    let markers: Vec<Markers> = groups
        .iter()
        .map(|g| Markers {
            label: &g.label,
            points: &g.points,
        })
        .collect();
    Ok(Figure {
        name: name.into(),
        svg: plot_svg(axes, &series, &markers)?,
        png: plot_png(axes, &series, &markers)?,
    })
}

/// The map of `grid` with its `Δφ = 0` line (leaving out leading rows that are zero
/// throughout, the reference `Bo = 0`).
pub fn phase_map_figure(name: &str, title: &str, grid: &Grid) -> Result<Figure, String> {
    // The reference row Bo = 0 is Δφ = 0 by definition: leave it out of the boundary.
    let nx = grid.xs.len();
    let skip = grid
        .ys
        .iter()
        .enumerate()
        .take_while(|(j, _)| grid.values[j * nx..(j + 1) * nx].iter().all(|&v| v == 0.0))
        .count();
    let boundary = zero_contour(&Grid {
        xs: grid.xs.clone(),
        ys: grid.ys[skip..].to_vec(),
        values: grid.values[skip * nx..].to_vec(),
    });
    let overlays = [Series {
        dashed_as: None,
        label: "Δφ = 0: the boundary between relative compression and dilation",
        points: &boundary,
    }];
    let map = HeatMap {
        title,
        x: "interparticle friction μ_p",
        y: "Bond number Bo",
        value: "Δφ = φ(Bo) − φ(0)",
        xs: &grid.xs,
        ys: &grid.ys,
        values: &grid.values,
        overlays: if boundary.is_empty() { &[] } else { &overlays },
    };
    Ok(Figure {
        name: name.into(),
        svg: map.to_svg()?,
        png: map.to_png()?,
    })
}

/// The `Δφ` figures of a set of measured points (Shi et al. 2020, Figs. 10–11): `Δφ`
/// against `Bo` per `μ_p` with the law's curves, one figure per shear dynamics present;
/// and, where the points fill a grid of at least 2 × 2, the interpolated map with its
/// boundary. Always the law's own map at the same `(I, p*)`.
pub fn delta_phi_figures(
    points: &[DeltaPhi],
    inertial: f64,
    softness: f64,
) -> Result<Vec<Figure>, String> {
    let mut out = vec![phase_map_figure(
        "phase-diagram-law",
        &format!("Δφ of Eq. 16 with Eq. 1B, I = {inertial}, p* = {softness}"),
        &law_grid(inertial, softness, 101, 101),
    )?];
    for dynamics in ShearDynamics::ALL {
        let ours: Vec<&DeltaPhi> = points.iter().filter(|p| p.dynamics == dynamics).collect();
        if ours.is_empty() {
            continue;
        }
        let mut frictions: Vec<f64> = ours.iter().map(|p| p.mu_p).collect();
        frictions.dedup();
        let groups: Vec<Group> = frictions
            .iter()
            .map(|&m| {
                let law =
                    PhiLaw::for_mu_p(m).unwrap_or_else(|| PhiLaw::from_friction_dependence(m));
                Group {
                    label: format!("μ_p = {m}"),
                    curve: (0..=50)
                        .map(|k| {
                            let bo = 0.1 * k as f64;
                            (bo, law.delta_phi(inertial, softness, bo))
                        })
                        .collect(),
                    points: ours
                        .iter()
                        .filter(|p| p.mu_p == m)
                        .map(|p| (p.bond, p.value, p.error))
                        .collect(),
                }
            })
            .collect();
        let title = format!("Δφ against Bo, {dynamics}, I = {inertial}, p* = {softness}");
        let axes = Labels {
            title: &title,
            x: "Bond number Bo",
            y: "Δφ = φ(Bo) − φ(0)",
        };
        out.push(group_figure(
            &format!("delta-phi-vs-bo-{dynamics}"),
            &axes,
            "Eq. 16",
            &groups,
        )?);
        let triples: Vec<(f64, f64, f64)> =
            ours.iter().map(|p| (p.mu_p, p.bond, p.value)).collect();
        if let Ok(grid) = interpolate(&triples, 101, 101) {
            out.push(phase_map_figure(
                &format!("phase-diagram-{dynamics}"),
                &format!("Measured Δφ, {dynamics}, I = {inertial}, p* = {softness}"),
                &grid,
            )?);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::setups::sweep::synthetic_result;

    /// `Δφ` pairs each cohesive point with the cohesionless run of the same dynamics, `μ_p`,
    /// size and polydispersity; of two runs of one point the longer counts; the standard
    /// errors combine in quadrature; a point without a partner, or at another state, is
    /// left out.
    #[test]
    fn delta_phi_pairs_each_point_with_its_cohesionless_partner() {
        let at = |extra: &str, phi: f64, err: f64| {
            synthetic_result(
                &format!("inertial = 0.02\nsoftness = 0.01\n{extra}"),
                phi,
                err,
            )
        };
        let wet = "cohesion = \"reversible\"\n";
        let results = vec![
            at("mu_p = 0.3", 0.620, 0.0003),
            at(&format!("mu_p = 0.3\nbond = 2.0\n{wet}"), 0.610, 0.0004),
            // A longer run of the same point: it counts, not the one above.
            at(
                &format!("mu_p = 0.3\nbond = 2.0\nstrain = 40.0\n{wet}"),
                0.605,
                0.0004,
            ),
            // Affine drag has its own partner.
            at(
                "mu_p = 0.3\nshear_dynamics = \"affine-drag\"",
                0.630,
                0.0003,
            ),
            at(
                &format!("mu_p = 0.3\nbond = 2.0\nshear_dynamics = \"affine-drag\"\n{wet}"),
                0.640,
                0.0004,
            ),
            // No partner at μ_p = 0.5 (its reference has another size).
            at(&format!("mu_p = 0.5\nbond = 1.0\n{wet}"), 0.6, 0.001),
            at("mu_p = 0.5\nparticles = 2048", 0.6, 0.001),
            // Another state.
            synthetic_result(
                &format!("mu_p = 0.3\nbond = 4.0\ninertial = 0.05\nsoftness = 0.01\n{wet}"),
                0.5,
                0.001,
            ),
        ];
        let d = delta_phi_points(&results, 0.02, 0.01);
        let lab: Vec<&DeltaPhi> = d
            .iter()
            .filter(|p| p.dynamics == ShearDynamics::Lab && p.mu_p == 0.3)
            .collect();
        assert_eq!(lab.len(), 2, "{d:?}");
        assert_eq!((lab[0].bond, lab[0].value, lab[0].error), (0.0, 0.0, 0.0));
        assert!((lab[1].value - (0.605 - 0.620)).abs() < 1e-12);
        assert!((lab[1].error - 0.0005).abs() < 1e-12, "{}", lab[1].error);
        let affine: Vec<&DeltaPhi> = d
            .iter()
            .filter(|p| p.dynamics == ShearDynamics::AffineDrag && p.bond > 0.0)
            .collect();
        assert_eq!(affine.len(), 1);
        assert!((affine[0].value - 0.010).abs() < 1e-12);
        assert!(
            d.iter().all(|p| p.mu_p == 0.3 || p.bond == 0.0),
            "the μ_p = 0.5 point has no partner: {d:?}"
        );
        assert!(d.iter().all(|p| p.bond != 4.0));
    }

    /// A plane `v = x − 0.3 − 0.1 y` is reproduced exactly by bilinear interpolation, and
    /// its zero line is the straight line `x = 0.3 + 0.1 y`.
    #[test]
    fn interpolation_and_contour_of_a_plane() {
        let f = |x: f64, y: f64| x - 0.3 - 0.1 * y;
        let mut pts = Vec::new();
        for &x in &[0.0, 0.1, 0.4, 1.0] {
            for &y in &[0.0, 1.0, 2.5, 5.0] {
                pts.push((x, y, f(x, y)));
            }
        }
        let g = interpolate(&pts, 21, 11).expect("full grid");
        for (k, v) in g.values.iter().enumerate() {
            let (x, y) = (g.xs[k % 21], g.ys[k / 21]);
            assert!((v - f(x, y)).abs() < 1e-12);
        }
        let line = zero_contour(&g);
        assert!(line.len() >= 10);
        assert!(line.iter().all(|p| p.0.is_finite()), "one branch");
        for &(x, y) in &line {
            assert!((x - 0.3 - 0.1 * y).abs() < 1e-12, "({x}, {y})");
        }
        pts.pop();
        let e = interpolate(&pts, 5, 5).expect_err("a hole");
        assert!(e.contains("μ_p = 1") && e.contains("Bo = 5"), "{e}");
    }

    /// A circle `x² + y² = r²` inside the grid: one closed branch, every point on it within
    /// the interpolation error of a grid of spacing `h` (`h²/(8 r)` for the curvature `1/r`).
    #[test]
    fn contour_of_a_circle_is_one_closed_branch() {
        let n = 41;
        let xs = spaced(-1.0, 1.0, n);
        let ys = xs.clone();
        let r = 0.6;
        let values = ys
            .iter()
            .flat_map(|&y| xs.iter().map(move |&x| x * x + y * y - r * r))
            .collect();
        let line = zero_contour(&Grid { xs, ys, values });
        let h = 2.0 / (n - 1) as f64;
        assert!(line.iter().all(|p| p.0.is_finite()), "one branch");
        assert_eq!(line.first(), line.last(), "closed");
        for &(x, y) in &line {
            assert!(((x * x + y * y).sqrt() - r).abs() < h * h / (8.0 * r) + 1e-12);
        }
    }

    /// The laws' map at the phase diagram's state: compression (Δφ > 0) at μ_p = 0 for every
    /// Bo > 0, dilation at μ_p = 0.5, Bo = 1, and a boundary between them.
    #[test]
    fn the_laws_map_has_both_signs_and_a_boundary() {
        let g = law_grid(0.02, 0.01, 51, 51);
        let at = |mu_p: f64, bo: f64| {
            let i = (mu_p * 50.0).round() as usize;
            let j = (bo * 10.0).round() as usize;
            g.values[i + 51 * j]
        };
        assert_eq!(at(0.3, 0.0), 0.0);
        assert!(at(0.0, 2.0) > 0.0);
        assert!(at(0.5, 1.0) < 0.0);
        assert!(!zero_contour(&g).is_empty());
        let fig = phase_map_figure("law", "laws", &g).expect("renders");
        assert!(fig.svg.contains("Δφ = 0"));
        assert!(fig.png.starts_with(b"\x89PNG"));
    }
}
