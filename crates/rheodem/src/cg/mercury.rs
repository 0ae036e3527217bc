//! Snapshots in MercuryDPM's text formats, so that MercuryDPM's own coarse-graining tools
//! (MercuryCG) can cross-check the fields (docs/coarse-graining.md §8).
//!
//! - `.data`, format 14 (3-D), one block per time step: a line
//!   `N t x_min y_min z_min x_max y_max z_max`, then one line per particle,
//!   `x y z v_x v_y v_z r θ_x θ_y θ_z ω_x ω_y ω_z info`. Spheres carry no orientation here, so
//!   the three angles are 0; `info` is 0 for a free particle and 1 for a wall particle.
//! - `.fstat`, one block per time step: three header lines,
//!   `# t 0`, `# x_min y_min z_min x_max y_max z_max`, `# r_min r_max 0 0 0 0`, then one line
//!   per free side of each interacting pair,
//!   `t i j c_x c_y c_z δ δ_t f_n f_t n_x n_y n_z t_x t_y t_z`, where `i` is the particle the
//!   line belongs to (its index in the `.data` block), `j` its partner (`−k − 1` for analytic
//!   wall `k`), `c` the contact point in `i`'s frame, `δ` the overlap (negative for an open
//!   bridge), `n` the unit normal from the partner towards `i`, and `f_n n + f_t t` the force
//!   on `i`. The tangential spring `δ_t` is not recorded and is written as 0; MercuryCG's
//!   stress does not use it.

use super::CgError;
use super::snapshot::{ContactRecord, ParticleRecord};
use glam::DVec3;
use std::collections::HashMap;
use std::fmt::Write;

/// The box that holds every particle whole: the centres' range widened by the largest radius.
fn bounds(particles: &[ParticleRecord]) -> (DVec3, DVec3) {
    let r = particles.iter().map(|p| p.radius).fold(0.0, f64::max);
    let lo = particles
        .iter()
        .fold(DVec3::INFINITY, |a, p| a.min(p.position));
    let hi = particles
        .iter()
        .fold(DVec3::NEG_INFINITY, |a, p| a.max(p.position));
    (lo - DVec3::splat(r), hi + DVec3::splat(r))
}

fn vec3(v: DVec3) -> String {
    format!("{:e} {:e} {:e}", v.x, v.y, v.z)
}

/// Appends the `.data` block of one snapshot at `time` (s) to `out`.
///
/// # Errors
/// [`CgError::Invalid`] when there are no particles, or their angular velocities are unknown
/// (records read from a file written before they were recorded).
pub fn data_block(
    out: &mut String,
    time: f64,
    particles: &[ParticleRecord],
) -> Result<(), CgError> {
    if particles.is_empty() {
        return Err(CgError::Invalid(format!(
            "the snapshot at t = {time} s has no particles to export"
        )));
    }
    if particles.iter().any(|p| p.angular_velocity.is_nan()) {
        return Err(CgError::Invalid(format!(
            "the snapshot at t = {time} s has no angular velocities (written by an older \
             version): MercuryDPM's .data format needs them"
        )));
    }
    let (lo, hi) = bounds(particles);
    let _ = writeln!(
        out,
        "{} {time:e} {} {}",
        particles.len(),
        vec3(lo),
        vec3(hi)
    );
    for p in particles {
        let _ = writeln!(
            out,
            "{} {} {:e} 0 0 0 {} {}",
            vec3(p.position),
            vec3(p.velocity),
            p.radius,
            vec3(p.angular_velocity),
            u8::from(!p.free)
        );
    }
    Ok(())
}

/// One `.fstat` line: the force `force` on the particle of index `i` from partner `j`.
fn fstat_line(out: &mut String, time: f64, i: usize, j: i64, c: &ContactRecord, side: Side) {
    let (point, normal, force) = match side {
        Side::I => (c.point_i, c.branch.normalize_or_zero(), c.force_i),
        Side::J => (
            c.point_j,
            (c.centre_j - c.point_j).normalize_or_zero(),
            c.force_j,
        ),
    };
    let f_n = force.dot(normal);
    let tangential = force - f_n * normal;
    let f_t = tangential.length();
    let t = if f_t > 0.0 {
        tangential / f_t
    } else {
        DVec3::ZERO
    };
    let _ = writeln!(
        out,
        "{time:e} {i} {j} {} {:e} 0 {f_n:e} {f_t:e} {} {}",
        vec3(point),
        c.overlap,
        vec3(normal),
        vec3(t)
    );
}

#[derive(Clone, Copy)]
enum Side {
    I,
    J,
}

/// Appends the `.fstat` block of one snapshot at `time` (s) to `out`: a line for each free
/// side of each pair in `contacts`, with indices into `particles` (the order of the `.data`
/// block).
///
/// # Errors
/// [`CgError::Invalid`] when there are no particles, or a contact names a particle id that
/// is not among them.
pub fn fstat_block(
    out: &mut String,
    time: f64,
    particles: &[ParticleRecord],
    contacts: &[ContactRecord],
) -> Result<(), CgError> {
    if particles.is_empty() {
        return Err(CgError::Invalid(format!(
            "the snapshot at t = {time} s has no particles to export"
        )));
    }
    let index: HashMap<u32, usize> = particles
        .iter()
        .enumerate()
        .map(|(k, p)| (p.id, k))
        .collect();
    let find = |id: u32| {
        index.get(&id).copied().ok_or_else(|| {
            CgError::Invalid(format!(
                "a contact of the snapshot at t = {time} s names particle {id}, which it lacks"
            ))
        })
    };
    let (lo, hi) = bounds(particles);
    let (r_min, r_max) = particles.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.radius), b.max(p.radius))
    });
    let _ = writeln!(out, "# {time:e} 0");
    let _ = writeln!(out, "# {} {}", vec3(lo), vec3(hi));
    let _ = writeln!(out, "# {r_min:e} {r_max:e} 0 0 0 0");
    for c in contacts {
        let i = find(c.i)?;
        if c.wall {
            if particles[i].free {
                fstat_line(out, time, i, -i64::from(c.j) - 1, c, Side::I);
            }
            continue;
        }
        let j = find(c.j)?;
        if particles[i].free {
            fstat_line(out, time, i, j as i64, c, Side::I);
        }
        if particles[j].free {
            fstat_line(out, time, j, i as i64, c, Side::J);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn particle(id: u32, x: f64, free: bool) -> ParticleRecord {
        ParticleRecord {
            id,
            position: DVec3::new(x, 0.0, 0.0),
            velocity: DVec3::new(0.0, x, 0.0),
            radius: 0.5,
            mass: 1.0,
            free,
            angular_velocity: DVec3::new(0.0, 0.0, 2.0),
        }
    }

    /// The pair (`i`, `j`) at `x_i`, `x_j` (`x_i > x_j`) touching halfway, with force `f`
    /// on `i`.
    fn pair(i: u32, j: u32, xi: f64, xj: f64, f: DVec3) -> ContactRecord {
        let mid = DVec3::new(0.5 * (xi + xj), 0.0, 0.0);
        ContactRecord {
            i,
            j,
            wall: false,
            overlap: 1.0 - (xi - xj),
            centre_i: DVec3::new(xi, 0.0, 0.0),
            branch: DVec3::new(xi - xj, 0.0, 0.0),
            point_i: mid,
            force_i: f,
            centre_j: DVec3::new(xj, 0.0, 0.0),
            point_j: mid,
            force_j: -f,
        }
    }

    fn numbers(line: &str) -> Vec<f64> {
        line.split_whitespace()
            .map(|x| x.parse().expect("a number"))
            .collect()
    }

    #[test]
    fn each_free_side_gets_a_line_whose_force_is_the_recorded_one() {
        // Ids 7 (free), 3 (free), 9 (wall particle); 7–3 touch, 9–7 touch, 7 meets wall 0.
        let particles = [
            particle(7, 0.9, true),
            particle(3, 0.0, true),
            particle(9, 1.8, false),
        ];
        let f = DVec3::new(2.0, 0.5, -0.25);
        let mut wall = pair(7, 0, 0.9, 0.9, DVec3::new(0.0, 0.0, 3.0));
        wall.wall = true;
        wall.branch = DVec3::new(0.0, 0.0, 0.4);
        let contacts = [pair(7, 3, 0.9, 0.0, f), pair(9, 7, 1.8, 0.9, -f), wall];
        let mut out = String::new();
        fstat_block(&mut out, 0.25, &particles, &contacts).expect("export");
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(lines[0], "# 2.5e-1 0");
        assert_eq!(numbers(&lines[2][1..]), [0.5, 0.5, 0.0, 0.0, 0.0, 0.0]);
        // Two lines for 7–3, one for 9–7 (the wall particle has none), one for the wall.
        let rows: Vec<Vec<f64>> = lines[3..].iter().map(|l| numbers(l)).collect();
        assert_eq!(rows.len(), 4);
        let ids: Vec<(f64, f64)> = rows.iter().map(|r| (r[1], r[2])).collect();
        assert_eq!(ids, [(0.0, 1.0), (1.0, 0.0), (0.0, 2.0), (0.0, -1.0)]);
        let expected = [f, -f, f, DVec3::new(0.0, 0.0, 3.0)];
        for (r, want) in rows.iter().zip(expected) {
            let n = DVec3::new(r[10], r[11], r[12]);
            let t = DVec3::new(r[13], r[14], r[15]);
            assert!((n.length() - 1.0).abs() < 1e-15);
            assert!((r[8] * n + r[9] * t - want).length() < 1e-14, "{r:?}");
            assert!(r[9] >= 0.0 && r[0] == 0.25);
        }
        // The normal points from the partner towards the line's particle.
        assert_eq!((rows[0][10], rows[1][10]), (1.0, -1.0));
    }

    #[test]
    fn data_blocks_hold_every_particle_and_refuse_unknown_spins() {
        let particles = [particle(7, 0.9, true), particle(9, 1.8, false)];
        let mut out = String::new();
        data_block(&mut out, 1.0, &particles).expect("export");
        let lines: Vec<Vec<f64>> = out.lines().map(numbers).collect();
        assert_eq!(lines[0], [2.0, 1.0, 0.4, -0.5, -0.5, 2.3, 0.5, 0.5]);
        assert_eq!(lines[1].len(), 14);
        assert_eq!(
            &lines[2][..],
            &[
                1.8, 0.0, 0.0, 0.0, 1.8, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 1.0
            ]
        );
        let mut old = particles;
        old[1].angular_velocity = DVec3::NAN;
        let e = data_block(&mut String::new(), 1.0, &old).expect_err("no spins");
        assert!(e.to_string().contains("angular velocities"), "{e}");
        let e = fstat_block(
            &mut String::new(),
            1.0,
            &particles,
            &[pair(7, 4, 0.9, 0.0, DVec3::X)],
        )
        .expect_err("unknown id");
        assert!(e.to_string().contains("particle 4"), "{e}");
    }
}
