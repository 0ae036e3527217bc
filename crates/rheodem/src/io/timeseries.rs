//! The time series as CSV: one row per [`Observables`].

use crate::measure::Observables;
use std::fmt::Write;

/// Column names of the CSV, in order. Units: s, J, Pa.
pub const COLUMNS: [&str; 27] = [
    "time",
    "step",
    "kinetic_translational",
    "kinetic_rotational",
    "elastic_energy",
    "total_energy",
    "contacts",
    "coordination",
    "sliding_fraction",
    "volume_fraction",
    "mean_stress",
    "stress_xx",
    "stress_xy",
    "stress_xz",
    "stress_yx",
    "stress_yy",
    "stress_yz",
    "stress_zx",
    "stress_zy",
    "stress_zz",
    "mu_xy_yy",
    "box_x",
    "box_y",
    "box_z",
    "granular_temperature",
    "bridges_per_particle",
    "coordination_without_rattlers",
];

/// Renders the rows as CSV with a header line; `mu_xy_yy` is `|σ_xy| / σ_yy`.
pub fn to_csv(rows: &[Observables]) -> String {
    let mut out = COLUMNS.join(",");
    out.push('\n');
    for o in rows {
        let s = &o.stress;
        let mu = if s[1][1] != 0.0 {
            s[0][1].abs() / s[1][1]
        } else {
            0.0
        };
        let _ = write!(
            out,
            "{:e},{},{:e},{:e},{:e},{:e},{},{:e},{:e},{:e},{:e}",
            o.time,
            o.step,
            o.kinetic_translational,
            o.kinetic_rotational,
            o.elastic_energy,
            o.total_energy(),
            o.contacts,
            o.coordination,
            o.sliding_fraction,
            o.volume_fraction,
            o.mean_stress()
        );
        for row in s {
            for v in row {
                let _ = write!(out, ",{v:e}");
            }
        }
        let _ = writeln!(
            out,
            ",{mu:e},{:e},{:e},{:e},{:e},{:e},{:e}",
            o.box_size[0],
            o.box_size[1],
            o.box_size[2],
            o.granular_temperature,
            o.bridges_per_particle,
            o.coordination_without_rattlers
        );
    }
    out
}
