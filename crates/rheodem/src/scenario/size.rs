//! The size of a scenario before it is built: its particle count per group and the memory
//! the run will take (see [`crate::memory`]), so that an oversized scenario is refused,
//! naming the group that makes it large, before anything is allocated.

use super::spec::{ParticleGroup, Scenario};
use super::{ScenarioError, invalid};
use crate::memory::{self, Bytes};
use glam::DVec3;
use std::path::Path;

/// Spheres along the two edges of a lattice group of edge lengths `a`, `b` (m) and spacing
/// `h` (m).
pub(crate) fn lattice_counts(a: f64, b: f64, h: f64) -> (usize, usize) {
    ((a / h).floor() as usize + 1, (b / h).floor() as usize + 1)
}

/// Each particle group's key and the key that sets its size, with the number of spheres it
/// will hold (an upper bound read without building: a packing file's data lines; an
/// unreadable file or invalid values count as zero and are reported by the build).
pub fn group_sizes(s: &Scenario, base_dir: &Path) -> Vec<(String, u64)> {
    s.particles
        .iter()
        .enumerate()
        .map(|(k, g)| {
            let key = format!("particles[{k}]");
            match g {
                ParticleGroup::Explicit { spheres, .. } => {
                    (format!("{key}.spheres"), spheres.len() as u64)
                }
                ParticleGroup::Random { count, .. } => (format!("{key}.count"), *count as u64),
                ParticleGroup::File { path, .. } => {
                    let rows = std::fs::read_to_string(base_dir.join(path)).map_or(0, |t| {
                        t.lines()
                            .map(str::trim)
                            .filter(|l| !l.is_empty() && !l.starts_with('#'))
                            .count()
                    });
                    (format!("{key}.path"), rows as u64)
                }
                ParticleGroup::Lattice {
                    edge_a,
                    edge_b,
                    radius,
                    spacing,
                    ..
                } => {
                    let h = spacing.unwrap_or(2.0 * radius);
                    let (a, b) = (
                        DVec3::from_array(*edge_a).length(),
                        DVec3::from_array(*edge_b).length(),
                    );
                    let n = if h > 0.0 && h.is_finite() && a.is_finite() && b.is_finite() {
                        let (na, nb) = lattice_counts(a, b, h);
                        (na as u64).saturating_mul(nb as u64)
                    } else {
                        0
                    };
                    (format!("{key}.spacing"), n)
                }
            }
        })
        .collect()
}

/// The particle count and estimated peak memory (bytes) of the scenario on `threads`
/// worker threads; refused when the estimate exceeds `limit` bytes, naming the largest
/// group's key.
pub fn memory_estimate(
    s: &Scenario,
    base_dir: &Path,
    threads: usize,
    limit: Option<u64>,
) -> Result<(u64, u64), ScenarioError> {
    let sizes = group_sizes(s, base_dir);
    let total = sizes.iter().fold(0u64, |t, (_, n)| t.saturating_add(*n));
    let bytes = memory::estimate(total, threads);
    match (limit, sizes.iter().max_by_key(|(_, n)| *n)) {
        (Some(limit), Some((key, n))) if bytes > limit => Err(invalid(
            key,
            n,
            format!(
                "makes {total} particles in all, an estimated {} on {threads} threads, more \
                 than the memory limit of {} (the machine's physical memory unless \
                 --max-memory says otherwise): at most about {} particles fit",
                Bytes(bytes),
                Bytes(limit),
                memory::particles_within(limit, threads)
            ),
        )),
        _ => Ok((total, bytes)),
    }
}
