//! The result of one finished shear-box point (of a sweep, a study or the archive) and the
//! results table over many points.

use super::shear_box::{Derived, ShearBoxSpec, SteadyState};
use serde::{Deserialize, Serialize};
use std::fmt::Write;
use std::path::Path;

/// Outcome of one point.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct PointResult {
    /// Directory name of the point.
    pub name: String,
    /// The point.
    pub spec: ShearBoxSpec,
    /// Derived SI values.
    pub derived: Derived,
    /// Steady-state averages (`None` if too few rows).
    pub steady_state: Option<SteadyState>,
    /// Wall-clock seconds of the run (all sessions).
    pub wall_seconds: f64,
    /// Git commit of the build that finished the point.
    #[serde(default)]
    pub commit: String,
}

impl PointResult {
    /// The point's steady state in words (as the command line prints it), and warnings
    /// when it did not reach one; `dir` is its run directory.
    pub fn report(&self, dir: &Path) -> (String, Vec<String>) {
        let mut text = String::new();
        let mut warnings = Vec::new();
        match &self.steady_state {
            Some(ss) => {
                let _ = writeln!(
                    text,
                    "steady state over strain {:.1}–{:.1}: φ = {:.5} ± {:.5}, μ = {:.4} ± {:.4}, Z = {:.3} ± {:.3}, σ_yy = {:.5e} ± {:.1e} Pa (target {:.5e}), P = tr σ/3 = {:.5e} Pa",
                    ss.strain_window[0],
                    ss.strain_window[1],
                    ss.volume_fraction.mean,
                    ss.volume_fraction.error,
                    ss.friction.mean,
                    ss.friction.error,
                    ss.coordination.mean,
                    ss.coordination.error,
                    ss.sigma_yy.mean,
                    ss.sigma_yy.error,
                    self.derived.pressure,
                    ss.mean_stress.mean
                );
                if let Some(s) = &ss.slab_rates {
                    let _ = writeln!(
                        text,
                        "local shear rate over γ̇ in {} slabs: {:.2}–{:.2}, rms deviation {:.2} (1 everywhere for homogeneous shear)",
                        s.slabs, s.min, s.max, s.rms_deviation
                    );
                }
                if !ss.steady {
                    warnings.push(format!(
                        "{} did NOT reach a steady state: {}",
                        dir.display(),
                        ss.note
                    ));
                }
            }
            None => warnings.push(format!(
                "{}: too few time-series rows past the transient to average",
                dir.display()
            )),
        }
        let _ = writeln!(text, "outputs in {}", dir.display());
        (text, warnings)
    }
}

/// The results table (CSV), one row per finished point.
pub fn results_csv(results: &[PointResult]) -> String {
    let mut s = String::from(
        "name,mu_p,inertial,softness,bond,cohesion,range,polydispersity,particles,seed,pressure_Pa,shear_rate_per_s,\
         steady,strain_from,strain_to,phi,phi_err,mu,mu_err,Z,Z_err,sigma_yy_Pa,sigma_yy_err,mean_stress_Pa,mean_stress_err,\
         granular_temperature,sliding_fraction,bridges_per_particle,I_measured,pstar_measured,Bo_measured,wall_seconds,note\n",
    );
    for r in results {
        let p = &r.spec;
        let _ = write!(
            s,
            "{},{},{},{},{},{:?},{},{},{},{},{:e},{:e},",
            r.name,
            p.mu_p,
            p.inertial,
            p.softness,
            p.bond,
            p.cohesion,
            p.range,
            p.polydispersity,
            p.particles,
            p.seed,
            r.derived.pressure,
            r.derived.shear_rate
        );
        match &r.steady_state {
            Some(ss) => {
                let _ = writeln!(
                    s,
                    "{},{:.3},{:.3},{:.6},{:.6},{:.5},{:.5},{:.4},{:.4},{:.6e},{:.3e},{:.6e},{:.3e},{:.4e},{:.5},{:.5},{:.5},{:.5},{:.5},{:.1},\"{}\"",
                    ss.steady,
                    ss.strain_window[0],
                    ss.strain_window[1],
                    ss.volume_fraction.mean,
                    ss.volume_fraction.error,
                    ss.friction.mean,
                    ss.friction.error,
                    ss.coordination.mean,
                    ss.coordination.error,
                    ss.sigma_yy.mean,
                    ss.sigma_yy.error,
                    ss.mean_stress.mean,
                    ss.mean_stress.error,
                    ss.granular_temperature.mean,
                    ss.sliding_fraction.mean,
                    ss.bridges_per_particle.mean,
                    ss.inertial_measured,
                    ss.softness_measured,
                    ss.bond_measured,
                    r.wall_seconds,
                    ss.note
                );
            }
            None => {
                // `steady`, 18 empty measurement fields, `wall_seconds`, `note`
                let _ = writeln!(
                    s,
                    "false{},{:.1},\"too few rows\"",
                    ",".repeat(18),
                    r.wall_seconds
                );
            }
        }
    }
    s
}
