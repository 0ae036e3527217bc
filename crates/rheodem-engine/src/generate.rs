//! Particle generation: polydisperse radii and random non-overlapping placement.

use crate::domain::Domain;
use glam::DVec3;
use rand::RngExt;
use rand_xoshiro::Xoshiro256PlusPlus;
use rustc_hash::FxHashMap;

/// Random generator of the project: fixed by the scenario seed.
pub type Rng = Xoshiro256PlusPlus;

/// Volume fraction above which random sequential insertion is refused: it stalls near
/// `φ ≈ 0.35–0.4`, so denser packings must be compressed from a looser one.
pub const MAX_INSERTION_FRACTION: f64 = 0.35;

/// `count` radii drawn uniformly in `[r_min, w·r_min]` with `r_min = d_p / (1 + w)`, so that
/// the mean diameter of the distribution is `d_p` (m). Sorted from largest to smallest,
/// which helps insertion.
pub fn polydisperse_radii(rng: &mut Rng, count: usize, mean_diameter: f64, w: f64) -> Vec<f64> {
    let r_min = mean_diameter / (1.0 + w);
    let mut radii: Vec<f64> = (0..count)
        .map(|_| {
            if w > 1.0 {
                rng.random_range(r_min..w * r_min)
            } else {
                r_min
            }
        })
        .collect();
    radii.sort_by(|a, b| b.total_cmp(a));
    radii
}

/// Something a new sphere must not overlap: a sphere, or the positive side of a plane.
#[derive(Clone, Copy, Debug)]
pub enum Obstacle {
    /// A sphere: centre (m), radius (m).
    Sphere(DVec3, f64),
    /// A plane through a point with a unit normal towards the free side.
    Plane(DVec3, DVec3),
}

/// Places spheres of the given radii at uniformly random positions in `domain`, each
/// without overlap with the obstacles or the spheres already placed (periodic axes use the
/// nearest image; along other axes the sphere stays inside the box). Gives up after
/// `attempts_per_sphere` failures for one sphere and returns how many it placed.
pub fn insert_random(
    rng: &mut Rng,
    radii: &[f64],
    domain: &Domain,
    obstacles: &[Obstacle],
    attempts_per_sphere: usize,
) -> Result<Vec<DVec3>, usize> {
    let l = domain.lengths();
    let r_max = radii
        .iter()
        .copied()
        .chain(obstacles.iter().filter_map(|o| match o {
            Obstacle::Sphere(_, r) => Some(*r),
            Obstacle::Plane(..) => None,
        }))
        .fold(0.0, f64::max);
    let cell = (2.0 * r_max).max(1e-300);
    let dims: [i64; 3] = std::array::from_fn(|a| ((l[a] / cell).floor() as i64).clamp(1, 1 << 20));
    let key = |r: DVec3| -> [i64; 3] {
        std::array::from_fn(|a| {
            (((r[a] - domain.lo[a]) / l[a] * dims[a] as f64).floor() as i64).clamp(0, dims[a] - 1)
        })
    };
    let mut grid: FxHashMap<[i64; 3], Vec<(DVec3, f64)>> = FxHashMap::default();
    let mut planes = Vec::new();
    for o in obstacles {
        match *o {
            Obstacle::Sphere(c, r) => {
                let (mut c, mut v, mut w) = (c, DVec3::ZERO, DVec3::ZERO);
                domain.wrap(&mut c, &mut v, &mut w);
                grid.entry(key(c)).or_default().push((c, r));
            }
            Obstacle::Plane(p, n) => planes.push((p, n)),
        }
    }
    let min_image = |mut d: DVec3| {
        for a in 0..3 {
            if domain.periodic[a] {
                d[a] -= l[a] * (d[a] / l[a]).round();
            }
        }
        d
    };
    let mut placed = Vec::with_capacity(radii.len());
    for &a in radii {
        let mut ok = None;
        for _ in 0..attempts_per_sphere {
            let c = DVec3::from_array(std::array::from_fn(|k| {
                if domain.periodic[k] {
                    domain.lo[k] + rng.random::<f64>() * l[k]
                } else {
                    let span = (l[k] - 2.0 * a).max(0.0);
                    domain.lo[k] + a + rng.random::<f64>() * span
                }
            }));
            if planes.iter().any(|(p, n)| (c - *p).dot(*n) < a) {
                continue;
            }
            let kc = key(c);
            let mut free = true;
            'search: for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let mut k = [kc[0] + dx, kc[1] + dy, kc[2] + dz];
                        for ax in 0..3 {
                            if domain.periodic[ax] {
                                k[ax] = k[ax].rem_euclid(dims[ax]);
                            }
                        }
                        if let Some(list) = grid.get(&k) {
                            for (q, b) in list {
                                if min_image(c - *q).length_squared() < (a + b) * (a + b) {
                                    free = false;
                                    break 'search;
                                }
                            }
                        }
                    }
                }
            }
            if free {
                ok = Some(c);
                break;
            }
        }
        let Some(c) = ok else {
            return Err(placed.len());
        };
        grid.entry(key(c)).or_default().push((c, a));
        placed.push(c);
    }
    Ok(placed)
}

/// Normally distributed vector with standard deviation `sigma` per component.
pub fn gaussian_vector(rng: &mut Rng, sigma: f64) -> DVec3 {
    if sigma == 0.0 {
        return DVec3::ZERO;
    }
    let dist = rand_distr::Normal::new(0.0, sigma).expect("finite non-negative sigma");
    DVec3::new(rng.sample(dist), rng.sample(dist), rng.sample(dist))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn radii_have_requested_mean_and_width() {
        let mut rng = Rng::seed_from_u64(3);
        let r = polydisperse_radii(&mut rng, 20000, 2.0, 3.0);
        let mean_d = 2.0 * r.iter().sum::<f64>() / r.len() as f64;
        assert!((mean_d - 2.0).abs() < 0.01, "mean diameter {mean_d}");
        let (lo, hi) = (r[r.len() - 1], r[0]);
        assert!(lo >= 0.5 && hi <= 1.5 && hi / lo > 2.9);
    }

    #[test]
    fn inserted_spheres_do_not_overlap_across_periodic_faces() {
        let mut rng = Rng::seed_from_u64(9);
        let d = Domain::new(DVec3::ZERO, DVec3::splat(10.0), [true, true, false]);
        let radii = polydisperse_radii(&mut rng, 300, 1.0, 2.0);
        let pos = insert_random(&mut rng, &radii, &d, &[], 1000).expect("loose enough");
        for i in 0..pos.len() {
            assert!(pos[i].z >= radii[i] && pos[i].z <= 10.0 - radii[i]);
            for j in 0..i {
                let mut dr = pos[i] - pos[j];
                dr.x -= 10.0 * (dr.x / 10.0).round();
                dr.y -= 10.0 * (dr.y / 10.0).round();
                assert!(dr.length() >= radii[i] + radii[j]);
            }
        }
    }
}
