//! The result of one finished shear-box point (of a sweep, a study or the archive) and the
//! results table over many points.

use super::shear_box::{Derived, ShearBoxSpec, SteadyState};
use serde::{Deserialize, Serialize};
use std::fmt::Write;

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
