//! Force–overlap curves: drives one pair through a prescribed overlap history, quasi-statically
//! (relative velocity zero, so dashpots do not act), and records the normal force.

use super::{ContactHistory, ContactLaw, PairKinematics};
use glam::DVec3;
use serde::Serialize;

/// One point of a force–overlap curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CurvePoint {
    /// Overlap `δ` (m); negative for a gap.
    pub overlap: f64,
    /// Net normal force on the first particle along the normal (N, positive repulsive).
    pub normal_force: f64,
    /// Its repulsive part `k_n δ` (N).
    pub repulsive: f64,
    /// Its adhesive part (N, ≤ 0).
    pub adhesive: f64,
    /// Whether an irreversible bridge exists after this point.
    pub bridge: bool,
}

/// Overlaps from `from` to `to` (m) in `n ≥ 1` equal steps, `to` included, `from` not.
pub fn ramp(from: f64, to: f64, n: usize) -> impl Iterator<Item = f64> {
    let n = n.max(1);
    (1..=n).map(move |k| from + (to - from) * k as f64 / n as f64)
}

/// The standard cycle: approach from a gap `start_gap` (m, > 0) to `max_overlap` (m),
/// separate to `end_gap` (m), approach again to `max_overlap`, `n` points per leg.
pub fn standard_cycle(start_gap: f64, max_overlap: f64, end_gap: f64, n: usize) -> Vec<f64> {
    let mut path = vec![-start_gap];
    path.extend(ramp(-start_gap, max_overlap, n));
    path.extend(ramp(max_overlap, -end_gap, n));
    path.extend(ramp(-end_gap, max_overlap, n));
    path
}

/// Drives a pair of radii `a_i`, `a_j` (m; `a_j = ∞` for a planar wall) through the given
/// overlaps with the law `law`, starting with no history.
pub fn drive(law: &ContactLaw, a_i: f64, a_j: f64, overlaps: &[f64]) -> Vec<CurvePoint> {
    let mut h = ContactHistory::default();
    overlaps
        .iter()
        .map(|&overlap| {
            let k = PairKinematics {
                normal: DVec3::X,
                overlap,
                radius_i: a_i,
                radius_j: a_j,
                velocity: DVec3::ZERO,
                omega_i: DVec3::ZERO,
                omega_j: DVec3::ZERO,
                reduced_mass: 1.0,
            };
            let f = law.interact(&k, &mut h, 0.0).unwrap_or_default();
            CurvePoint {
                overlap,
                normal_force: f.repulsive + f.adhesive,
                repulsive: f.repulsive,
                adhesive: f.adhesive,
                bridge: h.bridge,
            }
        })
        .collect()
}
