//! `rheodem predict`: the fitted laws of Shi et al. 2020 at one state point.

use anyhow::Result;
use clap::Args;
use rheodem::rheology::predict::predict;

/// The state point and output format.
#[derive(Args)]
pub struct PredictArgs {
    /// Interparticle friction μ_p (0 or more).
    #[arg(long, allow_negative_numbers = true)]
    mu_p: f64,
    /// Inertial number I (positive).
    #[arg(long, allow_negative_numbers = true)]
    inertial: f64,
    /// Softness p* (0 or more).
    #[arg(long, allow_negative_numbers = true)]
    softness: f64,
    /// Bond number Bo (0 or more; default 0).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    bond: f64,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// Runs `rheodem predict`.
pub fn run(a: &PredictArgs) -> Result<()> {
    let r = predict(a.mu_p, a.inertial, a.softness, a.bond).map_err(anyhow::Error::msg)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&r)?);
        return Ok(());
    }
    println!(
        "Shi et al. 2020 at μ_p = {}, I = {}, p* = {}, Bo = {}:",
        r.mu_p, r.inertial, r.softness, r.bond
    );
    if let Some(v) = &r.phi_table {
        println!("  φ  = {:.4}   ({})", v.value, v.source);
    }
    println!(
        "  φ  = {:.4}   ({})",
        r.phi_friction_law.value, r.phi_friction_law.source
    );
    let word = if r.delta_phi.value > 0.0 {
        "relative compression"
    } else if r.delta_phi.value < 0.0 {
        "relative dilation"
    } else {
        "no change"
    };
    println!(
        "  Δφ = {:+.4}  ({}; {word})",
        r.delta_phi.value, r.delta_phi.source
    );
    if let Some(v) = &r.mu {
        println!("  μ  = {:.4}   ({})", v.value, v.source);
    }
    println!("  {} (Sect. 3.3, Fig. 11)", r.regime_description);
    for w in &r.warnings {
        println!("  note: {w}");
    }
    Ok(())
}
