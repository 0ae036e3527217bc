//! `rheodem contact …`: force–overlap curves and the equivalent linear model.

use crate::law_arg;
use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use rheodem::contact::adhesion::LAWS;
use rheodem::contact::adhesion::LiquidBridge;
use rheodem::contact::curve::{drive, standard_cycle};
use rheodem::contact::equivalent::equivalent_linear;
use rheodem::contact::names::with_aliases;
use rheodem::contact::parameters::Parameter;
use rheodem::contact::{
    Adhesion, ContactLaw, Damping, LawKind, LawSpec, LinearNormal, NORMAL_LAWS, SPRING_LAWS, Spring,
};
use rheodem::io::atomic::write_atomic;
use rheodem::plot::{Labels, Series, line_plot_svg};
use rheodem::scenario::{Scenario, contact_table};
use std::fmt::Write;
use std::path::PathBuf;

/// Contact-law tools.
#[derive(Subcommand)]
pub enum ContactCommand {
    /// Drive two particles through approach, separation past the range and a second
    /// approach; write the force–overlap curve as CSV and SVG.
    Curve(CurveArgs),
    /// The linear irreversible laws equivalent to a liquid bridge, Willett's or
    /// Rabinovich's (Roy et al. 2016, Sect. 4; docs/model.md §2.7).
    Equivalent(EquivalentArgs),
    /// Every registered contact law by sub-model (normal, springs, adhesion), with the names
    /// scenario files and options accept and the adhesive laws' parameters.
    Laws,
}

/// Arguments of `contact curve`.
#[derive(Args)]
#[command(allow_negative_numbers = true)]
pub struct CurveArgs {
    /// Take the law from this scenario file (with --pair); otherwise from the flags below.
    #[arg(long)]
    scenario: Option<PathBuf>,
    /// Species pair of the scenario, e.g. `glass,glass` (default: the first species twice).
    #[arg(long, value_delimiter = ',')]
    pair: Vec<String>,
    // Adhesive law (without --scenario); the help text lists the registered laws.
    #[arg(long, default_value = "liquid-bridge", value_parser = law_arg::law_kind,
          help = law_arg::law_help("Adhesive law (without --scenario)"))]
    law: LawKind,
    /// Normal stiffness k_n (N/m).
    #[arg(long, default_value_t = 100.0)]
    stiffness: f64,
    /// Maximum adhesive force f_a^max (N) of the linear laws.
    #[arg(long, default_value_t = 1.3e-4)]
    max_force: f64,
    /// Adhesive stiffness k_c (N/m) of the linear laws.
    #[arg(long, default_value_t = 100.0)]
    adhesive_stiffness: f64,
    /// Surface tension γ_s (N/m) of the liquid bridge.
    #[arg(long, default_value_t = 0.02)]
    surface_tension: f64,
    /// Contact angle θ (degrees) of the liquid bridge.
    #[arg(long, default_value_t = 20.0)]
    contact_angle_deg: f64,
    /// Bridge volume V_b (m³).
    #[arg(long, default_value_t = 75e-12)]
    volume: f64,
    /// Any parameter the law declares, as key=value in its units (repeatable; overrides
    /// the flags above), e.g. `--param range=1e-4`.
    #[arg(long = "param", value_parser = law_arg::law_parameter)]
    params: Vec<(String, f64)>,
    /// Radius of the first particle (m).
    #[arg(long, default_value_t = 1.1e-3)]
    radius_i: f64,
    /// Radius of the second particle (m).
    #[arg(long, default_value_t = 1.1e-3)]
    radius_j: f64,
    /// Largest overlap of the cycle (m); default: 3 f_a^max / k_n, or 1 % of the smaller radius.
    #[arg(long)]
    max_overlap: Option<f64>,
    /// Points per leg of the cycle.
    #[arg(long, default_value_t = 400)]
    points: usize,
    /// Output prefix: writes PREFIX.csv and PREFIX.svg.
    #[arg(long, short, default_value = "contact-curve")]
    out: PathBuf,
}

/// Arguments of `contact equivalent`.
#[derive(Args)]
#[command(allow_negative_numbers = true)]
pub struct EquivalentArgs {
    /// The bridge's law: liquid-bridge (Willett's) or rabinovich.
    #[arg(long, default_value = "liquid-bridge", value_parser = law_arg::law_kind)]
    law: LawKind,
    /// Surface tension γ_s (N/m).
    #[arg(long, default_value_t = 0.02)]
    surface_tension: f64,
    /// Contact angle θ (degrees).
    #[arg(long, default_value_t = 20.0)]
    contact_angle_deg: f64,
    /// Bridge volumes V_b in nanolitres (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = [0.0, 1.0, 2.0, 4.2, 8.0, 14.0, 20.0, 75.0, 140.0, 200.0])]
    volume_nl: Vec<f64>,
    /// Particle diameter (m); both particles unless --diameter-j is given.
    #[arg(long, default_value_t = 2.2e-3)]
    diameter: f64,
    /// Diameter of the second particle (m).
    #[arg(long)]
    diameter_j: Option<f64>,
}

/// Runs a `contact` subcommand.
pub fn run(cmd: ContactCommand) -> Result<()> {
    match cmd {
        ContactCommand::Curve(a) => curve(a),
        ContactCommand::Equivalent(a) => equivalent(a),
        ContactCommand::Laws => {
            print!("{}", laws());
            Ok(())
        }
    }
}

/// One registered law as `contact laws` lists it: name, aliases, summary, parameters.
type Listed = (
    &'static str,
    &'static [&'static str],
    &'static str,
    &'static [Parameter],
);

/// The registries' contents as `contact laws` prints them.
fn laws() -> String {
    let mut out = String::new();
    section(
        &mut out,
        "Normal laws (a scenario's contact.normal.law; default linear):",
        NORMAL_LAWS
            .iter()
            .map(|m| (m.name, m.aliases, m.summary, m.parameters)),
    );
    section(
        &mut out,
        "Spring laws (contact.friction.law, contact.rolling.law, contact.torsion.law; default linear):",
        SPRING_LAWS
            .iter()
            .map(|m| (m.name, m.aliases, m.summary, m.parameters)),
    );
    section(
        &mut out,
        "Adhesive laws (contact.adhesion.law, the set-ups' --cohesion or --law; default none):",
        LAWS.iter()
            .map(|l| (l.name, l.aliases, l.summary, l.parameters)),
    );
    out
}

/// Writes one registry's laws under `title`, each with its parameters and their units.
fn section(out: &mut String, title: &str, laws: impl Iterator<Item = Listed>) {
    let _ = writeln!(out, "{title}");
    for (name, aliases, summary, parameters) in laws {
        let named = with_aliases(name, aliases);
        if named.chars().count() < 28 {
            let _ = writeln!(out, "  {named:<28}{summary}");
        } else {
            let _ = writeln!(out, "  {named}\n  {:<28}{summary}", "");
        }
        for p in parameters {
            let unit = if p.unit.is_empty() {
                "dimensionless"
            } else {
                p.unit
            };
            let _ = writeln!(out, "      {:<24}{} ({unit})", p.key, p.meaning);
        }
    }
    let _ = writeln!(out);
}

fn flag_law(a: &CurveArgs) -> Result<ContactLaw> {
    let positive = |name: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            bail!("--{name} = {v}: must be a positive finite number")
        }
    };
    // The flags that name a parameter of the chosen law, then any --param.
    let flags = [
        ("max_force", "max-force", a.max_force),
        ("stiffness", "adhesive-stiffness", a.adhesive_stiffness),
        ("surface_tension", "surface-tension", a.surface_tension),
        (
            "contact_angle_deg",
            "contact-angle-deg",
            a.contact_angle_deg,
        ),
        ("volume", "volume", a.volume),
    ];
    let declared = a.law.info().parameters;
    let mut spec = LawSpec::new(
        a.law,
        flags
            .iter()
            .filter(|(key, _, _)| declared.iter().any(|p| p.key == *key))
            .map(|&(key, _, v)| (key, v)),
    );
    // A --param replaces the flag of its key, and of the key it is given instead of.
    for (key, v) in &a.params {
        if let Some(other) = declared
            .iter()
            .find(|p| p.key == key)
            .and_then(|p| p.instead_of)
        {
            spec.values.remove(other);
        }
        spec.values.insert(key.clone(), *v);
    }
    let adhesion = spec.build().map_err(|e| {
        let option = if e.key.is_empty() {
            format!("--law {}", a.law)
        } else {
            flags
                .iter()
                .find(|(key, _, _)| *key == e.key && !a.params.iter().any(|(k, _)| k == key))
                .map_or_else(
                    || format!("--param {}", e.key),
                    |(_, flag, _)| format!("--{flag}"),
                )
        };
        anyhow::anyhow!("{option} = {}: {}", e.value, e.reason)
    })?;
    Ok(ContactLaw {
        normal: LinearNormal {
            stiffness: positive("stiffness", a.stiffness)?,
            damping: Damping::NONE,
        }
        .into(),
        tangential: Spring::NONE,
        rolling: Spring::NONE,
        torsion: Spring::NONE,
        adhesion,
    })
}

fn curve(a: CurveArgs) -> Result<()> {
    let law = match &a.scenario {
        None => flag_law(&a)?,
        Some(path) => {
            let sc = Scenario::from_file(path)?;
            let table = contact_table(&sc)?;
            let index = |name: &str| {
                sc.species
                    .iter()
                    .position(|s| s.name == name)
                    .with_context(|| format!("--pair: no species \"{name}\" in {}", path.display()))
            };
            let (i, j) = match a.pair.as_slice() {
                [] => (0, 0),
                [x, y] => (index(x)?, index(y)?),
                other => bail!("--pair takes two species names, got {}", other.len()),
            };
            *table.get(i as u16, j as u16)
        }
    };
    for (name, r) in [("radius-i", a.radius_i), ("radius-j", a.radius_j)] {
        if !(r.is_finite() && r > 0.0) {
            bail!("--{name} = {r}: must be a positive finite number");
        }
    }
    let f_max = law.adhesion.max_force(a.radius_i, a.radius_j);
    let max_overlap = a.max_overlap.unwrap_or(if f_max > 0.0 {
        3.0 * f_max
            / law
                .normal
                .max_stiffness(a.radius_i * a.radius_j / (a.radius_i + a.radius_j))
    } else {
        0.01 * a.radius_i.min(a.radius_j)
    });
    let range = law.range();
    let gap = if range > 0.0 {
        1.3 * range
    } else {
        max_overlap
    };
    let path = standard_cycle(gap, max_overlap, gap, a.points.max(2));
    let curve = drive(&law, a.radius_i, a.radius_j, &path);

    let mut csv = String::from("leg,overlap_m,normal_force_N,repulsive_N,adhesive_N,bridge\n");
    let leg_len = a.points.max(2);
    let mut legs: [Vec<(f64, f64)>; 3] = Default::default();
    for (k, p) in curve.iter().enumerate() {
        let leg = if k == 0 {
            0
        } else {
            ((k - 1) / leg_len).min(2)
        };
        let _ = writeln!(
            csv,
            "{},{:e},{:e},{:e},{:e},{}",
            ["approach", "separation", "re-approach"][leg],
            p.overlap,
            p.normal_force,
            p.repulsive,
            p.adhesive,
            u8::from(p.bridge)
        );
        legs[leg].push((p.overlap * 1e3, p.normal_force * 1e3));
    }
    let csv_path = a.out.with_extension("csv");
    write_atomic(&csv_path, csv.as_bytes())
        .with_context(|| format!("writing {}", csv_path.display()))?;
    // Rabinovich's bridge is drawn beside Willett's of the same γ_s, θ and V_b.
    let willett: Vec<(f64, f64)> = match law.adhesion {
        Adhesion::Rabinovich(b) => {
            let mut beside = law;
            beside.adhesion = Adhesion::LiquidBridge(LiquidBridge {
                surface_tension: b.surface_tension,
                contact_angle: b.contact_angle,
                volume: b.volume,
            });
            drive(&beside, a.radius_i, a.radius_j, &path)
                .iter()
                .enumerate()
                .filter(|(k, _)| *k > leg_len && *k <= 2 * leg_len)
                .map(|(_, p)| (p.overlap * 1e3, p.normal_force * 1e3))
                .collect()
        }
        _ => Vec::new(),
    };
    let mut series = vec![
        Series {
            dashed_as: None,
            label: "first approach",
            points: &legs[0],
        },
        Series {
            dashed_as: None,
            label: "separation",
            points: &legs[1],
        },
        // Dashed: it retraces the first approach where the bridge holds, which would
        // hide it under a solid line.
        Series {
            dashed_as: Some(2),
            label: "second approach (dashed over the first)",
            points: &legs[2],
        },
    ];
    if !willett.is_empty() {
        series.push(Series {
            dashed_as: Some(1),
            label: "separation, Willett's bridge of the same γ_s, θ, V_b",
            points: &willett,
        });
    }
    let svg = line_plot_svg(
        &Labels {
            title: "normal force against overlap",
            x: "overlap δ (mm)",
            y: "normal force (mN)",
        },
        &series,
    )
    .map_err(|e| anyhow::anyhow!("plotting failed: {e}"))?;
    let svg_path = a.out.with_extension("svg");
    write_atomic(&svg_path, svg.as_bytes())
        .with_context(|| format!("writing {}", svg_path.display()))?;
    println!(
        "f_a^max = {f_max:.4e} N, range = {range:.4e} m; wrote {} and {}",
        csv_path.display(),
        svg_path.display()
    );
    Ok(())
}

fn equivalent(a: EquivalentArgs) -> Result<()> {
    let d_j = a.diameter_j.unwrap_or(a.diameter);
    if !(a.diameter > 0.0 && d_j > 0.0) {
        bail!("--diameter and --diameter-j must be positive");
    }
    if a.surface_tension.is_nan()
        || a.surface_tension < 0.0
        || !(0.0..90.0).contains(&a.contact_angle_deg)
    {
        bail!("--surface-tension must be ≥ 0 and --contact-angle-deg in [0, 90)");
    }
    let title = match a.law {
        LawKind::LiquidBridge => "Willett bridge",
        LawKind::Rabinovich => "Rabinovich bridge",
        other => bail!(
            "--law {other}: the linear equivalents are of a liquid bridge (liquid-bridge or rabinovich)"
        ),
    };
    println!(
        "{title}, γ_s = {} N/m, θ = {}°, d = {} / {} m (r = harmonic-mean radius)",
        a.surface_tension, a.contact_angle_deg, a.diameter, d_j
    );
    println!(
        "{:>8} {:>12} {:>12} {:>12} {:>16} {:>16}",
        "V_b (nl)", "f_max (N)", "S_c (m)", "E (J)", "k_c equal S_c", "k_c equal E"
    );
    for &v in &a.volume_nl {
        if !(v >= 0.0 && v.is_finite()) {
            bail!("--volume-nl = {v}: volumes must be finite and ≥ 0");
        }
        let bridge = if v == 0.0 && a.law == LawKind::Rabinovich {
            None
        } else {
            let spec = LawSpec::new(
                a.law,
                [
                    ("surface_tension", a.surface_tension),
                    ("contact_angle_deg", a.contact_angle_deg),
                    ("volume", v * 1e-12),
                ],
            );
            let law = spec.build().map_err(|e| {
                anyhow::anyhow!("--law {}: `{}` = {}: {}", a.law, e.key, e.value, e.reason)
            })?;
            equivalent_linear(&law, 0.5 * a.diameter, 0.5 * d_j)
        };
        match bridge {
            Some(e) => println!(
                "{v:>8} {:>12.4e} {:>12.4e} {:>12.4e} {:>12.4} N/m {:>12.4} N/m",
                e.max_force,
                e.rupture_distance,
                e.energy,
                e.equal_range_stiffness,
                e.equal_energy_stiffness
            ),
            None => println!(
                "{v:>8} {:>12} {:>12} {:>12} {:>16} {:>16}",
                "-", "0", "0", "∞", "∞"
            ),
        }
    }
    Ok(())
}
