//! Study files (docs/studies.md): a sweep of shear-box points (or of split-bottom cells,
//! `setup = "split-bottom"`) with a title, a results database, the state of its `Δφ`
//! figures and a `quick` variant, and the report built from its finished points (Markdown,
//! and HTML with the images embedded).
//!
//! ```toml
//! title = "Non-cohesive rheology at μ_p = 0.01"
//! out = "../runs/studies/noncohesive"       # relative to the study file
//! results = "results/noncohesive"           # archive of finished points (kept in git)
//! database = "../runs/studies/results.sqlite"
//! [report]
//! inertial = 0.02                           # the state of the Δφ figures
//! softness = 0.01
//! [base]                                    # as in a sweep file
//! mu_p = 0.01
//! softness = 0.01
//! [grid]
//! inertial = [0.01, 0.02, 0.05]
//! softness = [0.005, 0.01]
//! [quick]                                   # the quick variant: merged into base, and
//! base = { particles = 512, strain = 6.0, transient_strain = 2.0 }
//! grid = { inertial = [0.05, 0.1] }         # replacing grid and points where given
//! ```

use super::law_fits::fit_tables;
use super::phase_diagram::{Figure, delta_phi_figures, delta_phi_points};
use super::sweep::{PointResult, SweepSpec};
use crate::scenario::ScenarioError;
use base64::Engine;
use serde::Deserialize;
use std::fmt::Write;

/// The state `(I, p*)` at which the report draws `Δφ` (default the phase diagram's, 0.02
/// and 0.01).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReportSpec {
    /// Inertial number of the `Δφ` figures.
    #[serde(default = "default_inertial")]
    pub inertial: f64,
    /// Softness of the `Δφ` figures.
    #[serde(default = "default_softness")]
    pub softness: f64,
}

fn default_inertial() -> f64 {
    0.02
}

fn default_softness() -> f64 {
    0.01
}

impl Default for ReportSpec {
    fn default() -> ReportSpec {
        ReportSpec {
            inertial: default_inertial(),
            softness: default_softness(),
        }
    }
}

/// What the quick variant changes.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QuickSpec {
    /// Fields merged into `base` (smaller systems, shorter runs).
    #[serde(default)]
    pub base: toml::Table,
    /// A grid replacing the study's (when given).
    #[serde(default)]
    pub grid: Option<toml::Table>,
    /// Points replacing the study's (when given).
    #[serde(default)]
    pub point: Option<Vec<toml::Table>>,
}

fn default_setup() -> String {
    "shear-box".into()
}

/// A study file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudySpec {
    /// Title of the report.
    pub title: String,
    /// The registered set-up of every point (`shear-box`, the default, `split-bottom`, …;
    /// its points come from `setups::registry::study_points`).
    #[serde(default = "default_setup")]
    pub setup: String,
    /// Output directory (relative to the study file); the quick variant's gets `-quick`.
    pub out: String,
    /// Archive of finished points (relative to the study file), as in a sweep file.
    #[serde(default)]
    pub results: Option<String>,
    /// Results database (relative to the study file) that every finished point goes into.
    #[serde(default)]
    pub database: Option<String>,
    /// The report's settings.
    #[serde(default)]
    pub report: ReportSpec,
    /// Fields shared by every point.
    #[serde(default)]
    pub base: toml::Table,
    /// Cartesian product of value lists.
    #[serde(default)]
    pub grid: toml::Table,
    /// Individual points.
    #[serde(default)]
    pub point: Vec<toml::Table>,
    /// The quick variant, if the study has one.
    #[serde(default)]
    pub quick: Option<QuickSpec>,
}

impl StudySpec {
    /// Reads a study file's text; the error names the offending key. Its points are
    /// checked when they are expanded (`setups::registry::study_points`).
    pub fn from_toml(text: &str) -> Result<StudySpec, ScenarioError> {
        toml::from_str(text).map_err(|e| ScenarioError::Parse(e.to_string()))
    }

    /// The variant's output directory, archive and point tables, as a sweep file holds
    /// them (whatever the set-up; not expanded).
    pub fn variant(&self, quick: bool) -> Result<SweepSpec, ScenarioError> {
        let mut sweep = SweepSpec {
            out: Some(self.out.clone()),
            results: self.results.clone(),
            base: self.base.clone(),
            grid: self.grid.clone(),
            point: self.point.clone(),
        };
        if quick {
            let q = self
                .quick
                .as_ref()
                .ok_or_else(|| ScenarioError::Parse("the study has no [quick] variant".into()))?;
            sweep.out = Some(format!("{}-quick", self.out));
            sweep.results = None;
            sweep.base.extend(q.base.clone());
            if let Some(g) = &q.grid {
                sweep.grid = g.clone();
            }
            if let Some(p) = &q.point {
                sweep.point = p.clone();
            }
        }
        Ok(sweep)
    }
}

/// The report of a study: its Markdown text and its figures (file stem, SVG, PNG).
pub struct Report {
    /// The report in Markdown; the figures are linked as `<name>.png`.
    pub markdown: String,
    /// The figures.
    pub figures: Vec<Figure>,
}

/// The report's title and status line.
pub(crate) fn header(study: &StudySpec, variant: &str, done: usize, total: usize) -> String {
    format!(
        "# {}\n\nVariant: {variant}. {done} of {total} points finished. Generated by rheodem {}.\n\n",
        study.title,
        crate::VERSION
    )
}

/// The report's section of figures, each linked as `<name>.png`.
fn figure_links(figures: &[Figure]) -> String {
    let mut md = String::from("\n## Figures\n\n");
    for f in figures {
        let _ = writeln!(md, "![{0}]({0}.png)\n", f.name);
    }
    md
}

/// Builds the report of `study` from its finished points: status, the validation table
/// against the laws of Shi et al. 2020, the fitted coefficients beside the paper's
/// (Tables 3, 5, 7, 8), the regimes of the phase diagram where the study has `Δφ` points
/// at the report's `(I, p*)`, and the `Δφ` figures.
pub fn report(
    study: &StudySpec,
    variant: &str,
    total: usize,
    finished: &[PointResult],
) -> Result<Report, String> {
    let mut md = header(study, variant, finished.len(), total);
    let _ = writeln!(md, "## The points against the laws of Shi et al. 2020\n");
    md += &super::compare::comparison_markdown(finished);
    let _ = writeln!(md, "\n## Fitted coefficients\n");
    md += &fit_tables(finished);
    let (i, p) = (study.report.inertial, study.report.softness);
    let delta_phi = delta_phi_points(finished, i, p);
    if delta_phi.iter().any(|d| d.bond > 0.0) {
        let _ = writeln!(md, "\n## Regimes of Δφ(μ_p, Bo) at I = {i}, p* = {p}\n");
        md += &super::regimes::regimes_markdown(&delta_phi, i, p);
    }
    let mut figures = super::compare::comparison_figures(finished)?;
    figures.extend(delta_phi_figures(&delta_phi, i, p)?);
    figures.extend(super::cohesion_figures::cohesion_figures(finished, i, p)?);
    md += &figure_links(&figures);
    Ok(Report {
        markdown: md,
        figures,
    })
}

/// Builds the report of a split-bottom study from its finished runs (`(name,
/// summary.json)`): status, the runs and the fits of Roy et al. 2016 beside the papers'
/// coefficients ([`super::wet_study`]), and their figures.
pub fn split_bottom_report(
    study: &StudySpec,
    variant: &str,
    total: usize,
    finished: &[(String, std::path::PathBuf)],
) -> Result<Report, String> {
    let mut md = header(study, variant, finished.len(), total);
    let mut runs = Vec::new();
    for (name, file) in finished {
        match super::wet_study::WetRun::read_summary(file, name) {
            Ok(r) => runs.push(r),
            Err(e) => {
                let _ = writeln!(md, "- left out: {e}");
            }
        }
    }
    let mut figures = Vec::new();
    if !runs.is_empty() {
        let _ = writeln!(md, "## The runs and the relations of Roy et al. 2016\n");
        let wet = super::wet_study::wet_study(&runs, None)?;
        md += &wet.markdown;
        figures = wet.figures;
        md += &figure_links(&figures);
    }
    Ok(Report {
        markdown: md,
        figures,
    })
}

/// The report as one self-contained HTML page: the Markdown rendered (tables included)
/// with every figure embedded as a PNG data URI.
pub fn report_html(r: &Report, title: &str) -> String {
    use pulldown_cmark::{CowStr, Event, Options, Parser, Tag};
    let embed = |dest: &str| {
        r.figures
            .iter()
            .find(|f| format!("{}.png", f.name) == dest)
            .map(|f| {
                format!(
                    "data:image/png;base64,{}",
                    base64::engine::general_purpose::STANDARD.encode(&f.png)
                )
            })
    };
    let events = Parser::new_ext(&r.markdown, Options::ENABLE_TABLES).map(|e| match e {
        Event::Start(Tag::Image {
            link_type,
            dest_url,
            title,
            id,
        }) => {
            let dest_url = embed(&dest_url).map_or(dest_url, CowStr::from);
            Event::Start(Tag::Image {
                link_type,
                dest_url,
                title,
                id,
            })
        }
        e => e,
    });
    let mut body = String::new();
    pulldown_cmark::html::push_html(&mut body, events);
    let escaped = title
        .replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;");
    format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{escaped}</title>\n\
         <style>body{{font-family:sans-serif;max-width:1200px;margin:2em auto}}\
         table{{border-collapse:collapse;font-size:0.85em}}td,th{{border:1px solid #bbb;\
         padding:2px 6px}}img{{max-width:100%}}</style></head>\n<body>\n{body}</body></html>\n"
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::setups::sweep::expand;

    const STUDY: &str = r#"
title = "tiny"
out = "runs/tiny"
results = "results/tiny"
[base]
inertial = 0.05
softness = 0.01
particles = 4096
[grid]
mu_p = [0.01, 0.5]
[quick]
base = { particles = 256, strain = 2.0, transient_strain = 1.0 }
grid = { mu_p = [0.01] }
"#;

    #[test]
    fn the_quick_variant_is_smaller_and_kept_apart() {
        let s = StudySpec::from_toml(STUDY).expect("valid");
        let full = expand(&s.variant(false).expect("full")).expect("points");
        let quick = expand(&s.variant(true).expect("quick")).expect("points");
        assert_eq!((full.len(), quick.len()), (2, 1));
        assert_eq!(quick[0].1.particles, 256);
        assert_eq!(quick[0].1.strain, 2.0);
        let q = s.variant(true).expect("quick");
        assert_eq!(q.out.as_deref(), Some("runs/tiny-quick"));
        assert_eq!(q.results, None);
        let e = StudySpec::from_toml(&STUDY.replace("[quick]", "[quick]\nsize = 1"))
            .expect_err("unknown key");
        assert!(e.to_string().contains("size"), "{e}");
        let no_quick =
            StudySpec::from_toml(&STUDY[..STUDY.find("[quick]").expect("has")]).expect("valid");
        assert!(no_quick.variant(true).is_err());
    }

    #[test]
    fn an_empty_report_builds_and_embeds_its_figures() {
        let s = StudySpec::from_toml(STUDY).expect("valid");
        let r = report(&s, "full", 2, &[]).expect("report");
        assert!(r.markdown.starts_with("# tiny"));
        assert!(r.markdown.contains("0 of 2 points finished"));
        assert!(
            r.markdown
                .contains("![phase-diagram-law](phase-diagram-law.png)")
        );
        let html = report_html(&r, &s.title);
        assert!(html.contains("<h1>tiny</h1>"));
        assert!(
            html.contains("src=\"data:image/png;base64,iVBOR"),
            "PNG embedded"
        );
        assert!(!html.contains("src=\"phase-diagram-law.png\""));
    }
}
