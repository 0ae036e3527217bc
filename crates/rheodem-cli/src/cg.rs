//! `rheodem cg`: the coarse-grained fields of a split-bottom run from its stored snapshots.

use anyhow::{Context, Result};
use clap::Args;
use rheodem::cg::KernelShape;
use rheodem::setups::split_bottom_fields::{
    FieldSettings, export_mercury, offline_fields, read_run, write_outputs,
};
use std::path::PathBuf;

/// Arguments of `cg`.
#[derive(Args)]
pub struct CgArgs {
    /// The split-bottom run directory (its checkpoint and snapshot files are read, not changed).
    dir: PathBuf,
    /// Kernel (default: the run's `cg_kernel`).
    #[arg(long, value_enum)]
    kernel: Option<KernelArg>,
    /// Kernel width in particle diameters (default: the run's `cg_width`).
    #[arg(long)]
    width: Option<f64>,
    /// Grid spacing in particle diameters (default: the run's `cg_spacing`).
    #[arg(long)]
    spacing: Option<f64>,
    /// Worker threads (default: all cores).
    #[arg(long, short)]
    threads: Option<usize>,
    /// Where to write fields.csv and fields.vti (default: DIR/cg).
    #[arg(long, short)]
    out: Option<PathBuf>,
    /// Also write the snapshots of the averaging window in MercuryDPM's formats
    /// (mercury.data and mercury.fstat in the output directory), for MercuryCG.
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

/// Runs `rheodem cg`.
pub fn run(args: CgArgs) -> Result<()> {
    let (pool, _) = crate::pool(args.threads)?;
    let run = read_run(&args.dir)
        .with_context(|| format!("cannot read the run in {}", args.dir.display()))?;
    // The run's own settings, each overridden by its option.
    let mut s = FieldSettings::of(&run.spec);
    if let Some(k) = args.kernel {
        s.kernel = match k {
            KernelArg::Gaussian => KernelShape::Gaussian,
            KernelArg::Lucy => KernelShape::Lucy,
        };
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
