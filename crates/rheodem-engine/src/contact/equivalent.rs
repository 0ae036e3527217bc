//! The linear irreversible law equivalent to a liquid bridge (Willett's or Rabinovich's;
//! Roy et al. 2016, Sect. 4; docs/model.md §2.7): same maximum force and (a) the same
//! interaction distance, or (b) the same adhesive energy per contact
//! `E = ∫₀^{S_c} |f_a| dS`.

use super::adhesion::Adhesion;
use serde::Serialize;

/// The bridge's characteristics and the two equivalent linear stiffnesses.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Equivalent {
    /// Maximum adhesive force `f_a^max` (N).
    pub max_force: f64,
    /// Rupture distance `S_c` (m).
    pub rupture_distance: f64,
    /// Adhesive energy per contact `∫₀^{S_c} |f_a| dS` (J), by Simpson quadrature.
    pub energy: f64,
    /// `k_c = f_a^max / S_c` (N/m): same maximum force and interaction distance.
    pub equal_range_stiffness: f64,
    /// `k_c = (f_a^max)² / (2E)` (N/m): same maximum force and adhesive energy.
    pub equal_energy_stiffness: f64,
    /// Interaction distance `2E / f_a^max` (m) of the equal-energy law.
    pub equal_energy_range: f64,
}

/// Number of Simpson intervals over `[0, S_c]` (the integrand is smooth: error ~1e-14).
const INTERVALS: usize = 2000;

/// Equivalent linear laws of an adhesive law with a range (a liquid bridge) between
/// spheres of radii `a_i`, `a_j` (m). `None` when the law gives no attraction beyond
/// contact (zero volume or tension).
pub fn equivalent_linear(bridge: &Adhesion, a_i: f64, a_j: f64) -> Option<Equivalent> {
    let f_max = bridge.max_force(a_i, a_j);
    let s_c = bridge.range();
    if !(f_max > 0.0 && s_c > 0.0 && f_max.is_finite() && s_c.is_finite()) {
        return None;
    }
    let h = s_c / INTERVALS as f64;
    let f = |s: f64| -bridge.separated_force(s, a_i, a_j, true).0;
    let mut sum = f(0.0) + f(s_c);
    for k in 1..INTERVALS {
        sum += f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    let energy = sum * h / 3.0;
    Some(Equivalent {
        max_force: f_max,
        rupture_distance: s_c,
        energy,
        equal_range_stiffness: f_max / s_c,
        equal_energy_stiffness: f_max * f_max / (2.0 * energy),
        equal_energy_range: 2.0 * energy / f_max,
    })
}
