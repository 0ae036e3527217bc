//! The wet split-bottom study of Roy et al. 2016 (docs/model.md §10.6): from a set of
//! finished split-bottom runs with band rheology, the relations between the microscopic
//! parameters (bridge volume through the rupture distance `S_c*`, surface tension through
//! `γ*`) and the macroscopic cohesion `c*` and torque `T*`, fitted as the papers do and set
//! beside their coefficients, with the papers' figures 8, 9, 11, 12 and 13.
//!
//! Scales: lengths by `d_p`, forces by `f_g = ρ_p (π/6) d_p³ g`, stresses by `f_g/d_p²`,
//! torques by `f_g d_p`. A run with the linear irreversible law counts with the surface
//! tension whose Willett bridge has its maximum force, `γ* = f_a^max* / (π cos θ)` with
//! `θ = 20°` (the papers' Eq. 23).

use super::phase_diagram::{Figure, Group, group_figure};
use super::split_bottom::{Groups, SplitBottomSpec};
use super::split_bottom_fields::BandSummary;
use crate::analysis::Estimate;
use crate::contact::LawKind;
use crate::fit::least_squares;
use crate::plot::Labels;
use serde::Deserialize;
use std::fmt::Write;
use std::path::Path;

/// The papers' coefficients (Roy et al. 2016, Sects. 3.1–3.2).
pub mod paper {
    /// Eq. 20: slope `a` of `c* − c*₀ = a S_c*` at `γ_s = 0.020 N/m`.
    pub const A_AT_0_020: f64 = 0.9805;
    /// Eq. 21: `ln c* = α ln γ* + k` at `V_b = 75 nl`.
    pub const ALPHA: f64 = 1.00;
    /// Eq. 21: the intercept `k`.
    pub const K: f64 = -0.4240;
    /// Eq. 23: slope `p` of `(c* − c*₀)/γ* = p S_c*`.
    pub const P: f64 = 2.1977;
    /// Eq. 28: slope `e` of `(c_eq* − c_eq,0*)/γ* = e S_c*`.
    pub const E: f64 = 2.0062;
    /// Fig. 11: intercept `t` of `T* = l γ* + t`.
    pub const T: f64 = 4.964e5;
    /// Fig. 5: `c*` at `V_b = 75 nl`, `γ_s = 0.020 N/m`.
    pub const C_75NL: f64 = 0.2655;
    /// Sect. 3.1: the band's `μ` for `γ_s` 0.020–0.060 N/m.
    pub const MU: f64 = 0.15;
}

/// The adhesion of a run, as the study groups it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Adhesion {
    /// Dry.
    Dry,
    /// Willett bridges of volume `volume` (m³) and surface tension `surface_tension` (N/m).
    Willett {
        /// `V_b` (m³).
        volume: f64,
        /// `γ_s` (N/m).
        surface_tension: f64,
    },
    /// Linear irreversible adhesion.
    Linear,
    /// Rabinovich bridges of volume `volume` (m³) and surface tension `surface_tension`
    /// (N/m), compared with Willett's of the same values (not part of the papers' fits).
    Rabinovich {
        /// `V_b` (m³).
        volume: f64,
        /// `γ_s` (N/m).
        surface_tension: f64,
    },
}

/// One finished run with band rheology, in the papers' scaled units.
#[derive(Clone, Debug, PartialEq)]
pub struct WetRun {
    /// The run directory's name.
    pub name: String,
    /// Its adhesion.
    pub adhesion: Adhesion,
    /// Rotation rate `Ω` (rad/s) and gravity `g` (m/s²): runs are compared at equal ones.
    pub omega_gravity: (f64, f64),
    /// How the cell differs from the default one (`d_p` 2.2 mm, `w` 2, the wall layer
    /// touching the mould), e.g. "d_p 2.333 mm"; empty for the default. Runs are compared
    /// in equal cells only.
    pub cell: String,
    /// `S_c* = S_c/d_p` (0 when dry).
    pub rupture: f64,
    /// `γ*` (0 when dry; the equivalent for the linear law).
    pub tension: f64,
    /// The band's friction `μ` and its standard error.
    pub mu: (f64, f64),
    /// `c* = c d_p²/f_g` and its standard error.
    pub cohesion: (f64, f64),
    /// `c_eq* = c_eq d_p²/f_g` from the torque (Eq. 27).
    pub cohesion_from_torque: f64,
    /// Wall torque `T* = T/(f_g d_p)` and its standard error.
    pub torque: (f64, f64),
    /// `T_macro* = M (μ P_avg + c) / (f_g d_p)` (Eq. 26).
    pub torque_macro: f64,
    /// Mean pressure of the fitted band points, `P_avg* = P_avg d_p²/f_g`.
    pub pressure: f64,
    /// The band's torque factor `M* = M/d_p³` (Eq. 26).
    pub torque_factor: f64,
    /// The settled state the run sheared from (`--from`), if any: runs from one settled
    /// state are paired wet against dry.
    pub from: Option<String>,
}

impl WetRun {
    /// The cohesion at a given friction `mu`: the band's line through its points' mean
    /// `(P_avg, τ_avg)` with slope `mu`, `c* + (μ − mu) P_avg*`. Fixing `μ` across runs
    /// takes out the trade-off of the two fitted coefficients; the standard error is the
    /// free fit's, an upper bound.
    pub fn cohesion_at(&self, mu: f64) -> (f64, f64) {
        (
            self.cohesion.0 + (self.mu.0 - mu) * self.pressure,
            self.cohesion.1,
        )
    }

    /// `c_eq* = T*/M* − μ P_avg*` (Eq. 27) at the friction `mu`: the cohesion the wall
    /// torque implies when the band's friction is `mu`.
    pub fn cohesion_from_torque_at(&self, mu: f64) -> f64 {
        self.torque.0 / self.torque_factor - mu * self.pressure
    }

    /// Whether `other` ran at the same `Ω` and `g` in the same cell.
    pub fn comparable(&self, other: &WetRun) -> bool {
        self.omega_gravity == other.omega_gravity && self.cell == other.cell
    }

    /// `Ω, g` and the cell, for a table.
    fn conditions(&self) -> String {
        let (w, g) = self.omega_gravity;
        if self.cell.is_empty() {
            format!("{w}, {g}")
        } else {
            format!("{w}, {g}, {}", self.cell)
        }
    }
}

/// How the cell of `spec` differs from the default one (empty if it does not).
fn cell_label(spec: &SplitBottomSpec) -> String {
    let base = SplitBottomSpec::default();
    let mut parts = Vec::new();
    if spec.diameter != base.diameter {
        parts.push(format!("d_p {:.4} mm", spec.diameter * 1e3));
    }
    if spec.w != base.w {
        parts.push(format!("w {}", spec.w));
    }
    if spec.wall_shell != base.wall_shell {
        parts.push(format!("wall shell {} d_p", spec.wall_shell));
    }
    parts.join(", ")
}

/// The parts of `summary.json` the study reads.
#[derive(Deserialize)]
struct RunSummary {
    spec: SplitBottomSpec,
    #[serde(default)]
    stage: Option<String>,
    #[serde(default)]
    from: Option<String>,
    groups: Groups,
    results: Option<TorqueResults>,
    band_rheology: Option<BandSummary>,
}

#[derive(Deserialize)]
struct TorqueResults {
    net_torque: Option<Estimate>,
}

impl WetRun {
    /// Reads the run in `dir` from its `summary.json`; the error says why it cannot count
    /// (unreadable, not finished with band rheology, no fit).
    pub fn read(dir: &Path) -> Result<WetRun, String> {
        let name = dir
            .file_name()
            .map_or_else(|| dir.display().to_string(), |n| n.to_string_lossy().into());
        WetRun::read_summary(&dir.join("summary.json"), &name)
    }

    /// Reads the run `name` from its summary `file` (a run's `summary.json`, or its copy in
    /// a study's archive).
    pub fn read_summary(file: &Path, name: &str) -> Result<WetRun, String> {
        let text = std::fs::read_to_string(file)
            .map_err(|e| format!("cannot read {}: {e}", file.display()))?;
        WetRun::from_summary(&text, name, &file.display().to_string())
    }

    /// [`WetRun::read_summary`] from the text of a summary; `origin` names it in errors.
    pub fn from_summary(text: &str, name: &str, origin: &str) -> Result<WetRun, String> {
        let name = name.to_string();
        let s: RunSummary = serde_json::from_str(text)
            .map_err(|e| format!("{origin} is not a split-bottom summary: {e}"))?;
        if let Some(stage) = s.stage.as_deref().filter(|&stage| stage != "done") {
            return Err(format!(
                "{name}: not finished (stage {stage}; its summary is a running one)"
            ));
        }
        let band = s
            .band_rheology
            .ok_or_else(|| format!("{name}: no band rheology (fields off, or not finished)"))?;
        let fit = band
            .fit
            .ok_or_else(|| format!("{name}: too few band points for τ = μ P + c"))?;
        let torque = s
            .results
            .and_then(|r| r.net_torque)
            .ok_or_else(|| format!("{name}: no wall torque"))?;
        let (d, fg) = (s.spec.diameter, s.groups.weight);
        let stress = d * d / fg;
        let law = &s.spec.cohesion;
        let value = |key: &str| {
            law.value(key)
                .ok_or_else(|| format!("{name}: law {} without its {key}", law.law))
        };
        let (adhesion, tension) = match law.law {
            LawKind::None => (Adhesion::Dry, 0.0),
            LawKind::LiquidBridge => (
                Adhesion::Willett {
                    volume: value("volume")?,
                    surface_tension: value("surface_tension")?,
                },
                s.groups.surface_tension_scaled,
            ),
            LawKind::Rabinovich => (
                Adhesion::Rabinovich {
                    volume: value("volume")?,
                    surface_tension: value("surface_tension")?,
                },
                s.groups.surface_tension_scaled,
            ),
            LawKind::LinearIrreversible => (
                Adhesion::Linear,
                value("max_force")? / fg / (std::f64::consts::PI * 20f64.to_radians().cos()),
            ),
            other => {
                return Err(format!(
                    "{name}: law {other} is not part of the wet study (dry, Willett, Rabinovich \
                     or linear irreversible)"
                ));
            }
        };
        Ok(WetRun {
            name,
            adhesion,
            omega_gravity: (s.spec.omega, s.spec.gravity),
            cell: cell_label(&s.spec),
            rupture: if adhesion == Adhesion::Dry {
                0.0
            } else {
                s.groups.rupture_scaled
            },
            tension,
            mu: (fit.slope, fit.slope_err),
            cohesion: (fit.intercept * stress, fit.intercept_err * stress),
            cohesion_from_torque: band.cohesion_from_torque.unwrap_or(f64::NAN) * stress,
            torque: (torque.mean / (fg * d), torque.error / (fg * d)),
            torque_macro: band.torque_macro.unwrap_or(f64::NAN) / (fg * d),
            pressure: band.pressure_avg * stress,
            torque_factor: band.torque_factor / (d * d * d),
            from: s.from,
        })
    }
}

/// A fitted straight line `y = slope x + intercept` (intercept 0 when forced through the
/// origin), with standard errors scaled by the scatter (`χ²_red`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    /// Slope and its standard error.
    pub slope: (f64, f64),
    /// Intercept and its standard error (`(0, 0)` through the origin).
    pub intercept: (f64, f64),
    /// Points fitted.
    pub points: usize,
    /// Largest absolute residual.
    pub max_residual: f64,
}

/// Weighted straight line through `(x, y, σ_y)`, through the origin or not; `None` when the
/// points do not determine it (too few, or no spread in `x`).
pub fn fit_line(points: &[(f64, f64, f64)], through_origin: bool) -> Option<Line> {
    let k = if through_origin { 1 } else { 2 };
    if through_origin && points.len() == 1 {
        // One point fixes a line through the origin: slope y/x, its error σ/x.
        let (x, y, sigma) = points[0];
        return (x != 0.0).then(|| Line {
            slope: (y / x, sigma / x.abs()),
            intercept: (0.0, 0.0),
            points: 1,
            max_residual: 0.0,
        });
    }
    if points.len() <= k {
        return None;
    }
    let y: Vec<f64> = points.iter().map(|p| p.1).collect();
    let sigma: Vec<f64> = points.iter().map(|p| p.2.max(1e-12)).collect();
    let model = |q: &[f64], i: usize| q[0] * points[i].0 + if k == 2 { q[1] } else { 0.0 };
    let start = if k == 2 { vec![1.0, 0.0] } else { vec![1.0] };
    let fit = least_squares(model, &y, &sigma, &start).ok()?;
    let max_residual = points
        .iter()
        .enumerate()
        .map(|(i, p)| (model(&fit.params, i) - p.1).abs())
        .fold(0.0, f64::max);
    Some(Line {
        slope: (fit.params[0], fit.errors[0]),
        intercept: if k == 2 {
            (fit.params[1], fit.errors[1])
        } else {
            (0.0, 0.0)
        },
        points: points.len(),
        max_residual,
    })
}

/// The Willett runs at one `(Ω, g)` and cell grouped by the value of `key`, ascending.
fn willett_groups(runs: &[WetRun], key: fn(f64, f64) -> f64) -> Vec<(f64, Vec<&WetRun>)> {
    let mut groups: Vec<(f64, Vec<&WetRun>)> = Vec::new();
    for r in runs {
        let Adhesion::Willett {
            volume,
            surface_tension,
        } = r.adhesion
        else {
            continue;
        };
        let value = key(volume, surface_tension);
        match groups
            .iter_mut()
            .find(|g| g.1[0].comparable(r) && g.0 == value)
        {
            Some(g) => g.1.push(r),
            None => groups.push((value, vec![r])),
        }
    }
    groups.sort_by(|a, b| a.0.total_cmp(&b.0));
    groups
}

/// A group of Willett runs at one surface tension for the figures of `c*` against
/// `S_c*`: `γ_s` (N/m), `γ*`, the friction held and the points `(S_c*, c* − c*₀, error)`.
struct AtFriction {
    gamma_s: f64,
    gamma: f64,
    mu: f64,
    points: Vec<(f64, f64, f64)>,
}

/// The study's fits and figures.
pub struct WetStudy {
    /// The report in Markdown.
    pub markdown: String,
    /// The figures.
    pub figures: Vec<Figure>,
}

/// Formats `(value, error)`.
fn pm((v, e): (f64, f64)) -> String {
    format!("{v:.3} ± {e:.3}")
}

/// The friction held fixed for the runs comparable with `run`: `mu` if given, else the
/// dry run's at the same `Ω`, `g` in the same cell, else the papers' 0.15.
fn friction(runs: &[WetRun], run: &WetRun, mu: Option<f64>) -> f64 {
    mu.unwrap_or_else(|| {
        runs.iter()
            .find(|r| r.adhesion == Adhesion::Dry && r.comparable(run))
            .map_or(paper::MU, |r| r.mu.0)
    })
}

/// Eq. 20 over a group of Willett runs at one surface tension: `y = c*₀ + a S_c*` with `y`
/// and its error from `value`. With a 0 nl run in the group, `c*₀` is its value (the
/// papers' definition) and the line goes through it, with the errors of both points added
/// in quadrature; otherwise `c*₀` is the fitted intercept.
fn rupture_line(members: &[&WetRun], value: impl Fn(&WetRun) -> (f64, f64)) -> Option<Line> {
    let zero = members.iter().find(|r| r.rupture == 0.0).map(|r| value(r));
    let pts: Vec<(f64, f64, f64)> = members
        .iter()
        .filter(|r| zero.is_none() || r.rupture > 0.0)
        .map(|r| {
            let (y, e) = value(r);
            match zero {
                Some((y0, e0)) => (r.rupture, y - y0, e.hypot(e0)),
                None => (r.rupture, y, e),
            }
        })
        .collect();
    let mut line = fit_line(&pts, zero.is_some())?;
    if let Some(z) = zero {
        line.intercept = z;
    }
    Some(line)
}

/// The wet–dry differences of runs sheared from one settled state at one `(Ω, g)`: the
/// torque's, `Δc* = ΔT*/M*` (the friction unchanged), and the band fits' at the dry run's
/// friction (or `mu`); then their mean over the realisations of each law, with the
/// standard error of the mean, against the papers' `c*` at 75 nl, 0.020 N/m.
fn wet_against_dry(md: &mut String, runs: &[WetRun], mu: Option<f64>) {
    let pairs: Vec<(&WetRun, &WetRun)> = runs
        .iter()
        .filter(|w| w.adhesion != Adhesion::Dry && w.from.is_some())
        .filter_map(|w| {
            runs.iter()
                .find(|d| d.adhesion == Adhesion::Dry && d.from == w.from && d.comparable(w))
                .map(|d| (w, d))
        })
        .collect();
    if pairs.is_empty() {
        return;
    }
    let _ = writeln!(
        md,
        "\n## Wet against dry from the same settled state\n\n\
         `Δc*` from the torque is `ΔT*/M*`, the friction unchanged; from the band fits it is \
         `c*(μ)` of the wet run less the dry run's, at the dry run's `μ`{}.\n\n\
         | wet run | dry run | Ω, g | ΔT* | Δc* from the torque | Δc* from the band fits |\n\
         |---|---|---|---|---|---|",
        mu.map_or(String::new(), |m| format!(" (here `--mu` {m})"))
    );
    let mut laws: Vec<(&WetRun, Vec<(f64, f64)>)> = Vec::new();
    for (w, d) in &pairs {
        let dt = (w.torque.0 - d.torque.0, w.torque.1.hypot(d.torque.1));
        let m = w.torque_factor;
        let from_torque = (dt.0 / m, dt.1 / m);
        let mu = mu.unwrap_or(d.mu.0);
        let (cw, ew) = w.cohesion_at(mu);
        let (cd, ed) = d.cohesion_at(mu);
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.4e} ± {:.1e} | {} | {} |",
            w.name,
            d.name,
            w.conditions(),
            dt.0,
            dt.1,
            pm(from_torque),
            pm((cw - cd, ew.hypot(ed)))
        );
        match laws
            .iter_mut()
            .find(|l| l.0.adhesion == w.adhesion && l.0.comparable(w))
        {
            Some(l) => l.1.push((from_torque.0, cw - cd)),
            None => laws.push((w, vec![(from_torque.0, cw - cd)])),
        }
    }
    let _ = writeln!(
        md,
        "\nOver the realisations (mean ± standard error of the mean; the papers' `c*` at \
         75 nl, 0.020 N/m: {}):\n\n\
         | adhesion | Ω, g | pairs | Δc* from the torque | Δc* from the band fits |\n\
         |---|---|---|---|---|",
        paper::C_75NL
    );
    for (run, values) in &laws {
        let name = match run.adhesion {
            Adhesion::Willett {
                volume,
                surface_tension,
            } => format!("Willett {} nl, {surface_tension} N/m", volume * 1e12),
            Adhesion::Rabinovich {
                volume,
                surface_tension,
            } => format!("Rabinovich {} nl, {surface_tension} N/m", volume * 1e12),
            Adhesion::Linear => "linear irreversible".into(),
            Adhesion::Dry => continue,
        };
        let column = |k: usize| {
            let x: Vec<f64> = values
                .iter()
                .map(|v| if k == 0 { v.0 } else { v.1 })
                .collect();
            match mean_and_error(&x) {
                Some(e) => pm(e),
                None => format!("{:.3}", x[0]),
            }
        };
        let _ = writeln!(
            md,
            "| {name} | {} | {} | {} | {} |",
            run.conditions(),
            values.len(),
            column(0),
            column(1)
        );
    }
}

/// The mean of `x` and its standard error, `None` for fewer than two values.
fn mean_and_error(x: &[f64]) -> Option<(f64, f64)> {
    let n = x.len();
    if n < 2 {
        return None;
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    Some((mean, (var / n as f64).sqrt()))
}

/// Fits the papers' relations to `runs` and draws their figures. `mu` fixes the band's
/// friction of every run for the comparisons at one friction (default: the dry run's at
/// the same `Ω`, `g`, else the papers' 0.15).
pub fn wet_study(runs: &[WetRun], mu: Option<f64>) -> Result<WetStudy, String> {
    let mut md = String::new();
    let mut figures = Vec::new();
    let _ = writeln!(
        md,
        "| run | adhesion | Ω (rad/s) | g (m/s²) | S_c* | γ* | μ | c* | c_eq* | T* | T_macro*/T* |\n\
         |---|---|---|---|---|---|---|---|---|---|---|"
    );
    for r in runs {
        let adhesion = match r.adhesion {
            Adhesion::Dry => "dry".to_string(),
            Adhesion::Willett {
                volume,
                surface_tension,
            } => format!("Willett {:.0} nl, {surface_tension} N/m", volume * 1e12),
            Adhesion::Rabinovich {
                volume,
                surface_tension,
            } => format!("Rabinovich {:.0} nl, {surface_tension} N/m", volume * 1e12),
            Adhesion::Linear => "linear irreversible".into(),
        };
        let _ = writeln!(
            md,
            "| {} | {adhesion} | {} | {} | {:.3} | {:.3} | {} | {} | {:.3} | {:.4e} ± {:.1e} | {:.3} |",
            r.name,
            r.omega_gravity.0,
            r.omega_gravity.1,
            r.rupture,
            r.tension,
            pm(r.mu),
            pm(r.cohesion),
            r.cohesion_from_torque,
            r.torque.0,
            r.torque.1,
            r.torque_macro / r.torque.0
        );
    }

    // Eq. 20 (Fig. 8a): c* = c*₀ + a S_c* at each surface tension.
    let _ = writeln!(
        md,
        "\n## Cohesion against the rupture distance (Eq. 20, Fig. 8a)\n\n\
         `c* = c*₀ + a S_c*` over the bridge volumes at one surface tension; the papers give \
         `a` = {} at 0.020 N/m. `c*₀` is the 0 nl run's (Willett's contact-only limit, as the \
         papers) when the group has one, the line's fitted intercept otherwise. Eq. 23's \
         `p = a/γ*`: papers {}. The band fits' own `μ`:\n\n\
         | γ_s (N/m) | Ω, g | volumes | c*₀ | a | max residual | p = a/γ* |\n\
         |---|---|---|---|---|---|---|",
        paper::A_AT_0_020,
        paper::P,
    );
    let mut rupture_groups = Vec::new();
    for (gamma_s, members) in willett_groups(runs, |_, s| s) {
        let at = members[0].conditions();
        let Some(line) = rupture_line(&members, |r| r.cohesion) else {
            let _ = writeln!(
                md,
                "| {gamma_s} | {at} | {} | (too few volumes to fit) ||||",
                members.len()
            );
            continue;
        };
        let gamma = members[0].tension;
        let _ = writeln!(
            md,
            "| {gamma_s} | {at} | {} | {} | {} | {:.3} | {:.2} |",
            members.len(),
            pm(line.intercept),
            pm(line.slope),
            line.max_residual,
            line.slope.0 / gamma,
        );
        rupture_groups.push((gamma_s, gamma, line, members));
    }
    // The same at one friction for all runs: the fitted μ falls with the volume, and c
    // rises with it in the free fits. Also c_eq* from the torque (Eq. 27) at that μ, and
    // Eq. 28's e.
    let _ = writeln!(
        md,
        "\nWith `μ` fixed for every run of a group ({}), `c*(μ) = c* + (μ_fit − μ) P_avg*`, \
         and `c_eq* = T*/M* − μ P_avg*` from the wall torque (Eq. 27); Eq. 28's \
         `e = slope/γ*`: papers {}:\n\n\
         | γ_s (N/m) | Ω, g | μ | volumes | c*₀ | a | max residual | p = a/γ* | c_eq*₀ | slope of c_eq* | e |\n\
         |---|---|---|---|---|---|---|---|---|---|---|",
        match mu {
            Some(mu) => format!("`--mu` {mu}"),
            None => format!(
                "the dry run's at the same `Ω`, `g`, else the papers' {}",
                paper::MU
            ),
        },
        paper::E
    );
    for (gamma_s, gamma, _, members) in &rupture_groups {
        let mu = friction(runs, members[0], mu);
        let at_mu = rupture_line(members, |r| r.cohesion_at(mu));
        let from_torque = rupture_line(members, |r| (r.cohesion_from_torque_at(mu), r.cohesion.1));
        if let (Some(line), Some(eq)) = (at_mu, from_torque) {
            let _ = writeln!(
                md,
                "| {gamma_s} | {} | {mu:.4} | {} | {} | {} | {:.3} | {:.2} | {:.3} | {:.3} | {:.2} |",
                members[0].conditions(),
                members.len(),
                pm(line.intercept),
                pm(line.slope),
                line.max_residual,
                line.slope.0 / gamma,
                eq.intercept.0,
                eq.slope.0,
                eq.slope.0 / gamma
            );
        }
    }
    // From the torque alone, the friction unchanged: a wet run's `Δc*` against the dry
    // run is `ΔT*/M*`, so `a` is the slope of `T*/M*` over the volumes, weighted by the
    // torque's errors (no friction is fitted or held).
    let _ = writeln!(
        md,
        "\nFrom the wall torque with the friction unchanged (a wet run's `Δc*` against the dry \
         run is `ΔT*/M*`), `T*/M* = c_T* + a S_c*`, weighted by the torques' errors:\n\n\
         | γ_s (N/m) | Ω, g | volumes | a | c_T* | max residual | χ²_red | p = a/γ* |\n\
         |---|---|---|---|---|---|---|---|"
    );
    for (gamma_s, gamma, _, members) in &rupture_groups {
        let pts: Vec<(f64, f64, f64)> = members
            .iter()
            .map(|r| {
                let m = r.torque_factor;
                (r.rupture, r.torque.0 / m, r.torque.1 / m)
            })
            .collect();
        if let Some(line) = fit_line(&pts, false) {
            let chi2: f64 = pts
                .iter()
                .map(|(x, y, e)| ((line.slope.0 * x + line.intercept.0 - y) / e).powi(2))
                .sum();
            let _ = writeln!(
                md,
                "| {gamma_s} | {} | {} | {} | {} | {:.3} | {:.2} | {:.2} |",
                members[0].conditions(),
                members.len(),
                pm(line.slope),
                pm(line.intercept),
                line.max_residual,
                chi2 / (pts.len() - 2) as f64,
                line.slope.0 / gamma,
            );
        }
    }
    wet_against_dry(&mut md, runs, mu);
    if !rupture_groups.is_empty() {
        let top = runs.iter().map(|r| r.rupture).fold(0.0, f64::max) * 1.05;
        // The figures show `c*` at the group's fixed friction, as the table at one friction
        // and the papers (their fits hold `μ` near 0.15): free fits trade `μ` against `c`.
        let at_friction: Vec<AtFriction> = rupture_groups
            .iter()
            .filter_map(|(gamma_s, gamma, _, members)| {
                let m = friction(runs, members[0], mu);
                let line = rupture_line(members, |r| r.cohesion_at(m))?;
                let points = members
                    .iter()
                    .map(|r| {
                        let (c, e) = r.cohesion_at(m);
                        (r.rupture, c - line.intercept.0, e)
                    })
                    .collect();
                Some(AtFriction {
                    gamma_s: *gamma_s,
                    gamma: *gamma,
                    mu: m,
                    points,
                })
            })
            .collect();
        let groups: Vec<Group> = at_friction
            .iter()
            .map(|g| Group {
                label: format!("γ_s = {} N/m, μ = {:.3}", g.gamma_s, g.mu),
                curve: if g.gamma_s == 0.02 {
                    vec![(0.0, 0.0), (top, paper::A_AT_0_020 * top)]
                } else {
                    Vec::new()
                },
                points: g.points.clone(),
            })
            .collect();
        figures.push(group_figure(
            "cstar-vs-rupture",
            &Labels {
                title: "c* − c*₀ at one friction against S_c* (Roy et al. 2016, Fig. 8a)",
                x: "rupture distance S_c* = S_c/d_p",
                y: "c* − c*₀ at μ fixed (c*₀: the 0 nl run, else the V_b → 0 limit)",
            },
            "Eq. 20 (a = 0.98)",
            &groups,
        )?);
        // Fig. 9: (c* − c*₀)/γ* against S_c*, every surface tension, Eq. 23.
        let groups: Vec<Group> = at_friction
            .iter()
            .map(|g| Group {
                label: format!("γ_s = {} N/m, μ = {:.3}", g.gamma_s, g.mu),
                curve: vec![(0.0, 0.0), (top, paper::P * top)],
                points: g
                    .points
                    .iter()
                    .map(|(x, y, e)| (*x, y / g.gamma, e / g.gamma))
                    .collect(),
            })
            .collect();
        figures.push(group_figure(
            "cstar-over-tension-vs-rupture",
            &Labels {
                title: "(c* − c*₀)/γ* at one friction against S_c* (Roy et al. 2016, Fig. 9)",
                x: "rupture distance S_c*",
                y: "(c* − c*₀)/γ* at μ fixed",
            },
            "Eq. 23 (p = 2.20)",
            &groups,
        )?);
    }

    // Eqs. 21–22 (Fig. 8b) and Fig. 11: c* and T* against γ* at one volume.
    let _ = writeln!(
        md,
        "\n## Cohesion and torque against the surface tension (Eqs. 21–22, Fig. 8b; Fig. 11)\n\n\
         `c* = b γ*` through the origin (papers `b = e^k` = {:.3}, `k` = {}), `ln c* = α ln γ* + k` \
         (papers `α` = {}), and `T* = l γ* + t` (papers `t` = {:.3e}).\n\n\
         | V_b (nl) | Ω, g | tensions | b | α | k | l | t |\n|---|---|---|---|---|---|---|---|",
        paper::K.exp(),
        paper::K,
        paper::ALPHA,
        paper::T
    );
    let mut tension_groups = Vec::new();
    for (volume, members) in willett_groups(runs, |v, _| v) {
        let at = members[0].conditions();
        let pts: Vec<(f64, f64, f64)> = members
            .iter()
            .map(|r| (r.tension, r.cohesion.0, r.cohesion.1))
            .collect();
        let logs: Vec<(f64, f64, f64)> = members
            .iter()
            .filter(|r| r.cohesion.0 > 0.0)
            .map(|r| {
                (
                    r.tension.ln(),
                    r.cohesion.0.ln(),
                    r.cohesion.1 / r.cohesion.0,
                )
            })
            .collect();
        let torques: Vec<(f64, f64, f64)> = members
            .iter()
            .map(|r| (r.tension, r.torque.0, r.torque.1))
            .collect();
        let nl = volume * 1e12;
        match (
            fit_line(&pts, true),
            fit_line(&logs, false),
            fit_line(&torques, false),
        ) {
            (Some(b), Some(log), Some(t)) => {
                let _ = writeln!(
                    md,
                    "| {nl:.0} | {at} | {} | {} | {} | {} | {:.3e} | {:.3e} |",
                    b.points,
                    pm(b.slope),
                    pm(log.slope),
                    pm(log.intercept),
                    t.slope.0,
                    t.intercept.0
                );
                tension_groups.push((nl, b, members));
            }
            _ => {
                let _ = writeln!(
                    md,
                    "| {nl:.0} | {at} | {} | (too few tensions to fit) |||||",
                    members.len()
                );
            }
        }
    }
    if !tension_groups.is_empty() {
        let top = runs.iter().map(|r| r.tension).fold(0.0, f64::max) * 1.05;
        let groups: Vec<Group> = tension_groups
            .iter()
            .map(|(nl, _, members)| Group {
                label: format!("V_b = {nl:.0} nl"),
                curve: vec![(0.0, 0.0), (top, paper::K.exp() * top)],
                points: members
                    .iter()
                    .map(|r| (r.tension, r.cohesion.0, r.cohesion.1))
                    .collect(),
            })
            .collect();
        figures.push(group_figure(
            "cstar-vs-tension",
            &Labels {
                title: "c* against γ* (Roy et al. 2016, Fig. 8b)",
                x: "surface tension γ* = γ_s d_p/f_g",
                y: "steady-state cohesion c*",
            },
            "Eq. 22 (b = 0.654)",
            &groups,
        )?);
        let groups: Vec<Group> = tension_groups
            .iter()
            .map(|(nl, _, members)| Group {
                label: format!("V_b = {nl:.0} nl"),
                curve: Vec::new(),
                points: members
                    .iter()
                    .map(|r| (r.tension, r.torque.0, r.torque.1))
                    .collect(),
            })
            .collect();
        figures.push(group_figure(
            "torque-vs-tension",
            &Labels {
                title: "Wall torque T* against γ* (Roy et al. 2016, Fig. 11)",
                x: "surface tension γ*",
                y: "T* = T/(f_g d_p)",
            },
            "",
            &groups,
        )?);
    }

    // Fig. 13: the macroscopic torque against the wall torque, every run.
    let top = runs.iter().map(|r| r.torque.0).fold(0.0, f64::max) * 1.05;
    let bottom = runs
        .iter()
        .map(|r| r.torque.0)
        .fold(f64::INFINITY, f64::min)
        * 0.95;
    if top > 0.0 {
        let ratios: Vec<f64> = runs.iter().map(|r| r.torque_macro / r.torque.0).collect();
        let (lo, hi) = ratios
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        let _ = writeln!(
            md,
            "\n## Macroscopic against wall torque (Eq. 26, Fig. 13)\n\n\
             `T_macro*/T*` ranges over {lo:.3}–{hi:.3} in {} runs (the papers show them equal).\n",
            runs.len()
        );
        let groups = [Group {
            label: "runs".into(),
            curve: vec![(bottom, bottom), (top, top)],
            points: runs
                .iter()
                .map(|r| (r.torque.0, r.torque_macro, 0.0))
                .collect(),
        }];
        figures.push(group_figure(
            "torque-macro-vs-wall",
            &Labels {
                title: "T_macro* against the wall torque T* (Roy et al. 2016, Fig. 13)",
                x: "wall torque T*",
                y: "T_macro* = M (μ P_avg + c)/(f_g d_p)",
            },
            "equality",
            &groups,
        )?);
    }
    Ok(WetStudy {
        markdown: md,
        figures,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(name: &str, volume_nl: f64, gamma_s: f64, c: f64, torque: f64) -> WetRun {
        WetRun {
            name: name.into(),
            adhesion: Adhesion::Willett {
                volume: volume_nl * 1e-12,
                surface_tension: gamma_s,
            },
            omega_gravity: (0.5, 9.81),
            cell: String::new(),
            rupture: 1.1745 * (volume_nl * 1e-12f64).cbrt() / 2.2e-3,
            tension: gamma_s * 2.2e-3 / 1.0939e-4,
            mu: (0.15, 0.002),
            cohesion: (c, 0.01),
            cohesion_from_torque: c,
            torque: (torque, 100.0),
            torque_macro: torque,
            pressure: 11.0,
            // T*/M* − 0.15 P* = c at the papers' friction.
            torque_factor: torque / (c + 0.15 * 11.0),
            from: Some("settled".into()),
        }
    }

    /// At a fixed friction the band line pivots about its points' mean `(P_avg*, τ_avg*)`.
    #[test]
    fn the_cohesion_at_another_friction_keeps_the_mean_point() {
        let mut r = run("r", 75.0, 0.02, 0.4, 6e5);
        r.mu = (0.14, 0.002);
        let tau = r.mu.0 * r.pressure + r.cohesion.0;
        let (c, e) = r.cohesion_at(0.16);
        assert!((0.16 * r.pressure + c - tau).abs() < 1e-12);
        assert!((c - 0.18).abs() < 1e-12 && e == r.cohesion.1);
    }

    #[test]
    fn lines_are_recovered_with_and_without_intercept() {
        let pts: Vec<(f64, f64, f64)> = (0..5)
            .map(|k| {
                let x = k as f64;
                (
                    x,
                    0.3 + 2.0 * x + if k % 2 == 0 { 0.01 } else { -0.01 },
                    0.01,
                )
            })
            .collect();
        let l = fit_line(&pts, false).expect("line");
        assert!((l.slope.0 - 2.0).abs() < 0.01 && (l.intercept.0 - 0.3).abs() < 0.02);
        assert!(l.slope.1 > 0.0 && l.max_residual < 0.02);
        let o = fit_line(&[(1.0, 2.0, 0.1), (2.0, 4.0, 0.1)], true).expect("through 0");
        assert!((o.slope.0 - 2.0).abs() < 1e-9 && o.intercept == (0.0, 0.0));
        assert!(fit_line(&[(1.0, 2.0, 0.1), (2.0, 4.0, 0.1)], false).is_none());
    }

    /// Runs made on the papers' relations give back their coefficients: `a` at 0.020 N/m,
    /// `b` at 75 nl, and `p = a/γ*`.
    #[test]
    fn the_papers_relations_are_recovered() {
        let c0 = 0.05;
        let mut runs = Vec::new();
        for (k, nl) in [14.0, 75.0, 200.0].into_iter().enumerate() {
            let mut r = run(&format!("v{k}"), nl, 0.02, 0.0, 6e5);
            r.cohesion.0 = c0 + paper::A_AT_0_020 * r.rupture;
            r.cohesion_from_torque = r.cohesion.0;
            runs.push(r);
        }
        for (k, g) in [0.04, 0.06].into_iter().enumerate() {
            let mut r = run(&format!("g{k}"), 75.0, g, 0.0, 6e5 + 1e5 * k as f64);
            r.cohesion.0 = paper::K.exp() * r.tension;
            r.cohesion_from_torque = r.cohesion.0;
            runs.push(r);
        }
        // The 75 nl, 0.020 N/m run on Eq. 22 as well: c0 + a S_c* = b γ* there.
        let study = wet_study(&runs, None).expect("study");
        let md = &study.markdown;
        assert!(
            md.contains("| 0.02 | 0.5, 9.81 | 3 | 0.050 ± 0.000 | 0.980 ± 0.000 | 0.000 | 2.44 |"),
            "{md}"
        );
        // With every μ at the papers' 0.15 (no dry run here), the fixed-μ fit is the same.
        assert!(
            md.contains("| 0.02 | 0.5, 9.81 | 0.1500 | 3 | 0.050 ± 0.000 | 0.980 ± 0.000 |"),
            "{md}"
        );
        // At 75 nl the 0.020 N/m run lies 3 % off Eq. 22 (c*₀ + a S_c* ≠ b γ* there).
        let b = md
            .lines()
            .find(|l| l.starts_with("| 75 | 0.5, 9.81 | 3 |"))
            .expect("the 75 nl row");
        assert!(b.contains("| 0.65"), "{b}");
        let names: Vec<&str> = study.figures.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "cstar-vs-rupture",
                "cstar-over-tension-vs-rupture",
                "cstar-vs-tension",
                "torque-vs-tension",
                "torque-macro-vs-wall"
            ]
        );
    }

    /// A 0 nl run is the papers' `c*₀`: the line goes through it, whatever the other
    /// volumes' intercept; `c_eq*` from the torque at the fixed friction gives Eq. 28's `e`.
    #[test]
    fn the_zero_volume_run_anchors_the_cohesion_line() {
        let mut runs = Vec::new();
        for (k, nl) in [0.0, 14.0, 75.0, 200.0].into_iter().enumerate() {
            let mut r = run(&format!("v{k}"), nl, 0.02, 0.0, 6e5);
            r.cohesion.0 = if nl == 0.0 {
                0.07
            } else {
                0.07 + 1.2 * r.rupture
            };
            r.torque_factor = r.torque.0 / (r.cohesion.0 + 0.15 * r.pressure);
            runs.push(r);
        }
        let md = wet_study(&runs, Some(0.15)).expect("study").markdown;
        let gamma = runs[0].tension;
        let free = format!(
            "| 0.02 | 0.5, 9.81 | 4 | 0.070 ± 0.010 | 1.200 ± 0.000 | 0.000 | {:.2} |",
            1.2 / gamma
        );
        assert!(md.contains(&free), "{md}");
        let fixed = format!(
            "| 0.02 | 0.5, 9.81 | 0.1500 | 4 | 0.070 ± 0.010 | 1.200 ± 0.000 | 0.000 | {:.2} | 0.070 | 1.200 | {:.2} |",
            1.2 / gamma,
            1.2 / gamma
        );
        assert!(md.contains(&fixed), "{md}");
        assert!(md.contains("`--mu` 0.15"), "{md}");
        // Torques on one line in `S_c*` at one torque factor: the torque's slope is `a`.
        for r in &mut runs {
            r.torque_factor = 2.9e5;
            r.torque.0 = r.torque_factor * (0.3 + 1.1 * r.rupture);
        }
        let md = wet_study(&runs, Some(0.15)).expect("study").markdown;
        let row = md
            .lines()
            .find(|l| l.starts_with("| 0.02 | 0.5, 9.81 | 4 | 1.100 ± "))
            .unwrap_or_else(|| panic!("no torque row: {md}"));
        assert!(
            row.contains("| 0.300 ± ") && row.contains("| 0.000 | 0.00 |"),
            "{row}"
        );
    }

    /// With the 0 nl run as the intercept, one more volume determines the slope `a`: the
    /// difference of the two `c*` over `S_c*`, with their combined error.
    #[test]
    fn two_volumes_with_the_zero_volume_run_give_the_slope() {
        let mut runs = Vec::new();
        for (k, nl) in [0.0, 75.0].into_iter().enumerate() {
            let mut r = run(&format!("v{k}"), nl, 0.02, 0.0, 6e5);
            r.cohesion = if nl == 0.0 {
                (0.07, 0.01)
            } else {
                (0.07 + 1.2 * r.rupture, 0.02)
            };
            r.torque_factor = r.torque.0 / (r.cohesion.0 + 0.15 * r.pressure);
            runs.push(r);
        }
        let md = wet_study(&runs, Some(0.15)).expect("study").markdown;
        let error = 0.01f64.hypot(0.02) / runs[1].rupture;
        let row = format!("| 0.02 | 0.5, 9.81 | 2 | 0.070 ± 0.010 | 1.200 ± {error:.3} | 0.000 |");
        assert!(md.contains(&row), "{row}\n{md}");
        assert!(!md.contains("too few volumes"), "{md}");
    }

    /// Wet runs pair with the dry run sheared from the same settled state in the same cell;
    /// `Δc*` from the torque is `ΔT*/M*`; realisations average, other cells stay apart.
    #[test]
    fn wet_runs_pair_with_the_dry_run_of_their_settled_state() {
        let mut runs = Vec::new();
        for (state, dry_t, wet_t) in [("s1", 5.7e5, 6.6e5), ("s2", 5.8e5, 6.6e5)] {
            let mut d = run(&format!("dry-{state}"), 0.0, 0.0, 0.0, dry_t);
            d.adhesion = Adhesion::Dry;
            d.from = Some(state.into());
            d.torque_factor = 3.0e5;
            let mut w = run(&format!("wet-{state}"), 75.0, 0.02, 0.3, wet_t);
            w.from = Some(state.into());
            w.torque_factor = 3.0e5;
            runs.extend([d, w]);
        }
        let mut other = run("wet-big", 75.0, 0.02, 0.3, 7.0e5);
        other.from = Some("s1".into());
        other.cell = "d_p 2.3333 mm".into();
        runs.push(other);
        let md = wet_study(&runs, None).expect("study").markdown;
        // (6.6e5 − 5.7e5)/3e5 = 0.3, (6.6e5 − 5.8e5)/3e5 = 0.267: mean 0.283 ± 0.017.
        assert!(
            md.contains("| wet-s1 | dry-s1 | 0.5, 9.81 | 9.0000e4"),
            "{md}"
        );
        assert!(md.contains("| 0.300 ± 0.000 |"), "{md}");
        assert!(
            md.contains("| Willett 75 nl, 0.02 N/m | 0.5, 9.81 | 2 | 0.283 ± 0.017 |"),
            "{md}"
        );
        assert!(!md.contains("| wet-big | dry-"), "{md}");
    }

    /// A running run's summary (written at each checkpoint) is left out, saying why; the
    /// same summary finished counts.
    #[test]
    fn a_running_summary_is_left_out() {
        let finished = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../validation/runs-split-bottom-rate/dry-omega0.5/summary.json"
        );
        let text = std::fs::read_to_string(finished).expect("a committed summary");
        assert!(WetRun::read_summary(Path::new(finished), "done").is_ok());
        let mut value: serde_json::Value = serde_json::from_str(&text).expect("json");
        value["stage"] = "shear".into();
        let dir = std::env::temp_dir().join(format!("rheodem-wet-running-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let running = dir.join("summary.json");
        std::fs::write(&running, value.to_string()).expect("write");
        let e = WetRun::read_summary(&running, "running").expect_err("running");
        assert!(e.contains("running: not finished (stage shear"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
