//! `rheodem cg`: the coarse-grained fields of a split-bottom run from its stored snapshots,
//! or of a periodic-box run (a scenario, the shear box) from its stored samples.

use anyhow::{Context, Result};
use clap::Args;
use rheodem::cg::KernelShape;
use rheodem::cg::periodic::axis_index;
use rheodem::run::{samples, write_fields};
use rheodem::scenario::spec::FieldGrid;
use rheodem::setups::split_bottom_fields::{
    FieldSettings, export_mercury, offline_fields, read_run, write_outputs,
};
use std::path::{Path, PathBuf};

/// Arguments of `cg`.
#[derive(Args)]
pub struct CgArgs {
    /// The run directory: a split-bottom run (its checkpoint and snapshot files are read),
    /// or a scenario or shear-box run that stored its fields' samples (`records = true` in
    /// `[fields]`, the shear box's `--cg-records`). Nothing in it is changed.
    dir: PathBuf,
    /// Kernel (default: the run's `cg_kernel`).
    #[arg(long, value_enum)]
    kernel: Option<KernelArg>,
    /// Kernel width in particle diameters (default: the run's). For a box run the diameter is
    /// `fields.material.diameter`, or else the mean diameter of its particles.
    #[arg(long)]
    width: Option<f64>,
    /// Grid spacing in particle diameters (default: the run's; a box run's cell counts are
    /// then the box's lengths over it, rounded).
    #[arg(long)]
    spacing: Option<f64>,
    /// Worker threads (default: all cores).
    #[arg(long, short)]
    threads: Option<usize>,
    /// Where to write fields.csv and fields.vti (default: DIR/cg).
    #[arg(long, short)]
    out: Option<PathBuf>,
    /// Also write the snapshots of the averaging window (a box run: the samples from its
    /// `start`) in MercuryDPM's formats (mercury.data and mercury.fstat in the output
    /// directory), for MercuryCG.
    #[arg(long)]
    mercury: bool,
}

/// Kernel shapes.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum KernelArg {
    /// Gaussian cut at three widths.
    Gaussian,
    /// Lucy's quartic polynomial.
    Lucy,
}

impl KernelArg {
    fn shape(self) -> KernelShape {
        match self {
            KernelArg::Gaussian => KernelShape::Gaussian,
            KernelArg::Lucy => KernelShape::Lucy,
        }
    }
}

/// Runs `rheodem cg`.
pub fn run(args: CgArgs) -> Result<()> {
    let (pool, _) = crate::pool(args.threads)?;
    if !args.dir.join("split-bottom.toml").exists() && args.dir.join("scenario.toml").exists() {
        return pool.install(|| box_run(&args));
    }
    let run = read_run(&args.dir)
        .with_context(|| format!("cannot read the run in {}", args.dir.display()))?;
    // The run's own settings, each overridden by its option.
    let mut s = FieldSettings::of(&run.spec);
    if let Some(k) = args.kernel {
        s.kernel = k.shape();
    }
    s.width = args.width.unwrap_or(s.width);
    s.spacing = args.spacing.unwrap_or(s.spacing);
    let sums = pool.install(|| offline_fields(&args.dir, &run, s))?;
    let out = args.out.unwrap_or_else(|| args.dir.join("cg"));
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    let band = write_outputs(&run, &sums, &out)?;
    println!(
        "{} snapshots in the averaging window coarse-grained onto {} points: {}",
        sums.snapshots,
        sums.grid.len(),
        out.join("fields.csv").display()
    );
    if let (Some(fit), Some(c_star)) = (band.fit, band.cohesion_scaled) {
        println!(
            "band: {} points above P = {:.3} Pa: τ = μ P + c with μ = {:.4} ± {:.4}, \
             c = {:.3} ± {:.3} Pa (c* = {:.4}); macroscopic torque {:.4e} N m",
            fit.points,
            band.pressure_min,
            fit.slope,
            fit.slope_err,
            fit.intercept,
            fit.intercept_err,
            c_star,
            band.torque_macro.unwrap_or(f64::NAN)
        );
    }
    if args.mercury {
        let n = export_mercury(&args.dir, &run, &out)?;
        println!(
            "{n} snapshots in MercuryDPM's formats: {} and {}",
            out.join("mercury.data").display(),
            out.join("mercury.fstat").display()
        );
    }
    Ok(())
}

/// `rheodem cg` for a periodic-box run: its fields again from its stored samples.
fn box_run(args: &CgArgs) -> Result<()> {
    let dir: &Path = &args.dir;
    let run = samples::read_run(dir)
        .with_context(|| format!("cannot read the run in {}", dir.display()))?;
    let Some(mut spec) = run.fields.as_ref().map(|f| f.spec.clone()) else {
        anyhow::bail!(
            "{}: the run has no [fields], so it stored no samples to coarse-grain",
            dir.display()
        );
    };
    let p = &run.simulation.particles;
    let diameter = spec.material.as_ref().map_or_else(
        || 2.0 * p.radius.iter().sum::<f64>() / p.len().max(1) as f64,
        |m| m.diameter,
    );
    if let Some(k) = args.kernel {
        spec.kernel = k.shape();
    }
    if let Some(w) = args.width {
        anyhow::ensure!(
            w.is_finite() && w > 0.0,
            "--width {w}: must be a positive number of particle diameters"
        );
        spec.width = w * diameter;
    }
    if let Some(h) = args.spacing {
        anyhow::ensure!(
            h.is_finite() && h > 0.0,
            "--spacing {h}: must be a positive number of particle diameters"
        );
        let l = run.simulation.domain.lengths();
        let cells = |len: f64| ((len / (h * diameter)).round() as usize).max(1);
        spec.bins = match spec.grid {
            FieldGrid::Slabs => {
                let axis = axis_index(&spec.axis).context("the run's fields.axis")?;
                vec![cells(l[axis])]
            }
            FieldGrid::Cartesian => vec![cells(l.x), cells(l.y), cells(l.z)],
        };
    }
    let fields = samples::offline_fields(dir, &run, &spec)?;
    let out = args.out.clone().unwrap_or_else(|| dir.join("cg"));
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    write_fields(&fields, &out)?;
    let sums = fields.sums.as_ref().expect("at least one sample");
    println!(
        "{} samples from t = {} s coarse-grained onto {} points ({:?} kernel, width {:.4} m): {}",
        sums.snapshots,
        spec.start,
        sums.grid.len(),
        spec.kernel,
        spec.width,
        out.join("fields.csv").display()
    );
    if args.mercury {
        let n = samples::export_mercury(dir, &run, spec.start, &out)?;
        println!(
            "{n} samples in MercuryDPM's formats: {} and {}",
            out.join("mercury.data").display(),
            out.join("mercury.fstat").display()
        );
    }
    Ok(())
}
