//! `rheodem wet-study`: the wet split-bottom study over finished runs.

use anyhow::{Context, Result, bail};
use rheodem::io::atomic::write_atomic;
use std::path::{Path, PathBuf};

/// Runs `wet-study`: the runs found in `dirs` (each a run directory, or a directory of
/// them), their fits as markdown (at the band friction `mu` where one is held fixed), the
/// figures into `figures`.
pub fn run(dirs: &[PathBuf], figures: Option<&Path>, mu: Option<f64>) -> Result<()> {
    use rheodem::setups::wet_study::{WetRun, wet_study};
    if let Some(mu) = mu
        && !(mu.is_finite() && mu >= 0.0)
    {
        bail!("--mu {mu}: the band friction must be a finite number ≥ 0");
    }
    let mut runs = Vec::new();
    let mut left_out = Vec::new();
    for dir in dirs {
        let candidates: Vec<PathBuf> = if dir.join("summary.json").exists() {
            vec![dir.clone()]
        } else {
            let mut subs: Vec<PathBuf> = std::fs::read_dir(dir)
                .with_context(|| format!("cannot read {}", dir.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.join("summary.json").exists())
                .collect();
            subs.sort();
            subs
        };
        for c in candidates {
            match WetRun::read(&c) {
                Ok(r) => runs.push(r),
                Err(e) => left_out.push(e),
            }
        }
    }
    if runs.is_empty() {
        bail!(
            "no finished split-bottom run with band rheology in {}{}",
            dirs.iter()
                .map(|d| d.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
            if left_out.is_empty() {
                String::new()
            } else {
                format!(" ({})", left_out.join("; "))
            }
        );
    }
    let study =
        wet_study(&runs, mu).map_err(|e| anyhow::anyhow!("cannot draw the figures: {e}"))?;
    print!("{}", study.markdown);
    if !left_out.is_empty() {
        println!("\nLeft out:\n- {}", left_out.join("\n- "));
    }
    if let Some(out) = figures {
        std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
        for f in &study.figures {
            for (ext, bytes) in [("svg", f.svg.as_bytes()), ("png", f.png.as_slice())] {
                let file = out.join(format!("{}.{ext}", f.name));
                write_atomic(&file, bytes)
                    .with_context(|| format!("cannot write {}", file.display()))?;
            }
        }
        eprintln!("{} figures in {}", study.figures.len(), out.display());
    }
    Ok(())
}
