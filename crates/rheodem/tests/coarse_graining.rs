//! Coarse-graining against closed forms and independent computations: a lattice gives the
//! density and an isotropic stress, a linear velocity field its strain rate, a rigid
//! rotation none; mass and contact stress integrate to the particle sums; the axisymmetric
//! grid equals a brute-force azimuthal average of the three-dimensional fields.

use glam::DVec3;
use rheodem::cg::snapshot::{Body, Segment};
use rheodem::cg::{CgSums, FieldPoint, Grid, Kernel, KernelShape, Snapshot, fields, images_for};
use rheodem::domain::Domain;
use std::f64::consts::{PI, TAU};

const MASS: f64 = 2.0e-3;

fn body(position: DVec3, velocity: DVec3) -> Body {
    Body {
        position,
        velocity,
        mass: MASS,
        volume: 0.5,
        contacts: 6,
        bridges: 1,
    }
}

/// A simple cubic lattice of spacing 1 filling `[0, n)³`, with velocities `v(r)`.
fn lattice(n: usize, v: impl Fn(DVec3) -> DVec3) -> Vec<Body> {
    let mut out = Vec::new();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let r = DVec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5);
                out.push(body(r, v(r)));
            }
        }
    }
    out
}

fn coarse_grain(grid: Grid, kernel: &Kernel, snap: &Snapshot) -> Vec<FieldPoint> {
    let mut sums = CgSums::new(grid).expect("valid grid");
    sums.add_snapshot(kernel, snap);
    fields(&sums, None)
}

/// A lattice sums a kernel to its integral only up to the kernel's lack of smoothness: the
/// Gaussian's step of e^{−4.5} of its peak at the cut-off leaves 10⁻⁴–2·10⁻³ of the value at
/// points on the lattice planes (measured for widths of 0.8–2 spacings) and 5·10⁻³ at
/// points midway between them (width 1.5); Lucy's polynomial, smooth to the second
/// derivative, 10⁻⁶–10⁻⁴. At the width used here (1.5 spacings) the tolerances are:
fn lattice_tol(shape: KernelShape) -> f64 {
    match shape {
        KernelShape::Gaussian => 6e-3,
        KernelShape::Lucy => 1e-4,
    }
}

/// The kernel width of the lattice tests, in lattice spacings.
const WIDTH: f64 = 1.5;

#[test]
fn a_periodic_lattice_has_uniform_density_and_isotropic_stress() {
    let n = 8;
    let domain = Domain::new(DVec3::ZERO, DVec3::splat(n as f64), [true; 3]);
    let grid = Grid::Cartesian {
        lo: DVec3::ZERO,
        hi: DVec3::splat(n as f64),
        bins: [4, 4, 4],
    };
    let bodies = lattice(n, |_| DVec3::ZERO);
    // Each particle pushed away from its neighbour below along each axis with force 3 N.
    let f = 3.0;
    let segments = bodies
        .iter()
        .flat_map(|b| {
            [DVec3::X, DVec3::Y, DVec3::Z].map(|e| Segment {
                from: b.position - e,
                to: b.position,
                force: f * e,
            })
        })
        .collect();
    let snap = Snapshot {
        time: 0.0,
        bodies,
        segments,
        images: images_for(&domain, &grid),
    };
    assert_eq!(snap.images.len(), 26);
    for shape in [KernelShape::Gaussian, KernelShape::Lucy] {
        let tol = lattice_tol(shape);
        let kernel = Kernel::new(shape, WIDTH).expect("valid");
        for p in coarse_grain(grid.clone(), &kernel, &snap) {
            assert!(
                (p.density / MASS - 1.0).abs() < tol,
                "{shape:?} ρ = {}",
                p.density
            );
            assert!((p.volume_fraction / 0.5 - 1.0).abs() < tol);
            // Per-particle counts are ratios of two sums with the same lattice error.
            assert!((p.coordination - 6.0).abs() < 1e-12);
            assert!((p.bridges_per_particle - 1.0).abs() < 1e-12);
            // σ = f ⊗ l per particle volume along each axis: P = f/a², τ = 0.
            assert!(
                (p.pressure / f - 1.0).abs() < tol,
                "{shape:?} P = {}",
                p.pressure
            );
            assert!(p.shear_stress < tol * f, "{shape:?} τ = {}", p.shear_stress);
            assert!(p.kinetic_stress.iter().all(|s| s.abs() < 1e-12));
        }
    }
}

#[test]
fn simple_shear_gives_its_strain_rate_on_cartesian_and_slab_grids() {
    // v_x = γ̇ (y − y₀) across a Lees-Edwards box: the images carry the velocity jump, so
    // the velocity is linear through the boundary.
    let (n, rate) = (8, 0.7);
    let domain =
        Domain::new(DVec3::ZERO, DVec3::splat(n as f64), [true; 3]).with_lees_edwards(rate);
    let bodies = lattice(n, |r| DVec3::new(rate * r.y, 0.0, 0.0));
    // Points on the lattice's planes: the kernel-weighted mean height of the particles
    // around a point is then the point's own by symmetry, and the velocity exact.
    let grids = [
        Grid::Cartesian {
            lo: DVec3::ZERO,
            hi: DVec3::splat(n as f64),
            bins: [4, 8, 4],
        },
        Grid::Slab {
            axis: 1,
            lo: 0.0,
            hi: n as f64,
            bins: 8,
            area: (n * n) as f64,
        },
    ];
    for shape in [KernelShape::Gaussian, KernelShape::Lucy] {
        let kernel = Kernel::new(shape, WIDTH).expect("valid");
        // The kernel's standard deviation along an axis (0.958 w for the Gaussian cut at
        // three widths).
        let sd = match shape {
            KernelShape::Gaussian => 0.958_029 * WIDTH,
            KernelShape::Lucy => WIDTH,
        };
        for grid in &grids {
            let snap = Snapshot {
                time: 0.0,
                bodies: bodies.clone(),
                segments: Vec::new(),
                images: images_for(&domain, grid),
            };
            let points = coarse_grain(grid.clone(), &kernel, &snap);
            let y_axis = grid
                .axis_names()
                .iter()
                .position(|&a| a == "y")
                .expect("a y axis");
            for p in &points {
                let y = p.coordinates[y_axis];
                let v = p.velocity[0];
                assert!(
                    (v - rate * y).abs() < 1e-9 * rate,
                    "{shape:?} {grid:?}: {v} at {y}"
                );
                assert!(
                    (p.strain_rate / rate - 1.0).abs() < 1e-9,
                    "γ̇ = {}",
                    p.strain_rate
                );
                // The kinetic stress of a smoothed linear field is the velocity variance
                // under the kernel, ρ γ̇² ⟨(y − Y)²⟩ = ρ γ̇² sd² (to the lattice's error,
                // larger for this second moment).
                let expected = p.density * rate * rate * sd * sd;
                let got = p.kinetic_stress[0];
                let tol = 10.0 * lattice_tol(shape);
                assert!(
                    (got / expected - 1.0).abs() < tol,
                    "{shape:?} σ_k,xx {got} vs {expected}"
                );
                assert!(p.kinetic_stress[4].abs() < 1e-12);
            }
        }
    }
}

#[test]
fn a_rigid_rotation_has_no_strain_rate_on_the_axisymmetric_grid() {
    let omega = 1.3;
    let (n, c) = (24, 12.0);
    // A lattice cylinder of radius 11 about the axis through (12, 12).
    let bodies: Vec<Body> = lattice(n, |_| DVec3::ZERO)
        .into_iter()
        .map(|b| {
            let r = b.position - DVec3::new(c, c, 0.0);
            body(r, DVec3::new(-omega * r.y, omega * r.x, 0.0))
        })
        .filter(|b| b.position.truncate().length() < 11.0)
        .collect();
    let grid = Grid::Axisymmetric {
        r: [3.0, 6.0],
        z: [8.0, 16.0],
        bins: [6, 8],
        angle: TAU,
    };
    let kernel = Kernel::new(KernelShape::Lucy, WIDTH).expect("valid");
    let snap = Snapshot {
        time: 0.0,
        bodies,
        segments: Vec::new(),
        images: Vec::new(),
    };
    let tol = lattice_tol(KernelShape::Lucy);
    for p in coarse_grain(grid, &kernel, &snap) {
        let r = p.coordinates[0];
        assert!((p.density / MASS - 1.0).abs() < tol, "ρ = {}", p.density);
        assert!(
            (p.velocity[1] / (omega * r) - 1.0).abs() < tol,
            "v_φ at r = {r}"
        );
        assert!(p.velocity[0].abs() < tol * omega && p.velocity[2].abs() < 1e-12);
        // The lattice's error in the velocity over a grid spacing, against Ω for the
        // velocity gradient itself.
        assert!(
            p.strain_rate < 10.0 * tol * omega,
            "γ̇ = {} at r = {r}",
            p.strain_rate
        );
    }
}

/// A deterministic scatter of `n` points in `[lo, hi]`.
fn scatter(n: usize, lo: DVec3, hi: DVec3, seed: u64) -> Vec<DVec3> {
    let mut state = seed;
    let mut next = move || {
        // A 64-bit linear congruential generator, plenty for test positions.
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| lo + (hi - lo) * DVec3::new(next(), next(), next()))
        .collect()
}

fn scattered_snapshot(lo: DVec3, hi: DVec3) -> Snapshot {
    let points = scatter(60, lo, hi, 7);
    let bodies = points
        .iter()
        .map(|&r| body(r, DVec3::new(r.y, -r.z, 0.3 * r.x)))
        .collect();
    let segments = points
        .windows(2)
        .map(|w| {
            let l = (w[1] - w[0]).normalize() * 0.9;
            Segment {
                from: w[1] - l,
                to: w[1],
                force: DVec3::new(l.x + 0.2, 0.5 * l.y, l.z - 0.1),
            }
        })
        .collect();
    Snapshot {
        time: 0.0,
        bodies,
        segments,
        images: Vec::new(),
    }
}

fn integrate(grid: &Grid, points: &[FieldPoint], q: impl Fn(&FieldPoint) -> f64) -> f64 {
    points
        .iter()
        .enumerate()
        .map(|(k, p)| q(p) * grid.cell_volume(k))
        .sum()
}

#[test]
fn mass_and_contact_stress_integrate_to_the_particle_sums() {
    let (lo, hi) = (DVec3::splat(0.0), DVec3::new(6.0, 5.0, 4.0));
    let snap = scattered_snapshot(lo, hi);
    let mass: f64 = snap.bodies.iter().map(|b| b.mass).sum();
    let mut fl = [0.0; 9];
    for s in &snap.segments {
        let l = s.to - s.from;
        for a in 0..9 {
            fl[a] += s.force[a / 3] * l[a % 3];
        }
    }
    let w = 1.0;
    // The midpoint rule on a grid of spacing w/4 over the whole support. Lucy's kernel is
    // smooth at its cut-off and the sums agree to 10⁻⁶; the Gaussian's step of e^{−4.5} of
    // its peak at the cut-off leaves an error of about that step times the cells it cuts,
    // 10⁻³ here.
    for (shape, tol) in [(KernelShape::Lucy, 1e-6), (KernelShape::Gaussian, 2e-3)] {
        let kernel = Kernel::new(shape, w).expect("valid");
        let margin = kernel.cutoff() + 1.0;
        let span = hi - lo + DVec3::splat(2.0 * margin);
        let bins = (span * 4.0 / w).ceil().as_uvec3();
        let grid = Grid::Cartesian {
            lo: lo - DVec3::splat(margin),
            hi: hi + DVec3::splat(margin),
            bins: [bins.x as usize, bins.y as usize, bins.z as usize],
        };
        let points = coarse_grain(grid.clone(), &kernel, &snap);
        let m = integrate(&grid, &points, |p| p.density);
        assert!(
            (m / mass - 1.0).abs() < tol,
            "{shape:?}: ∫ρ = {m}, Σm = {mass}"
        );
        let scale = fl.iter().map(|x| x.abs()).fold(0.0, f64::max);
        for (a, want) in fl.iter().enumerate() {
            let s = integrate(&grid, &points, |p| p.contact_stress[a]);
            assert!(
                (s - want).abs() < tol * scale,
                "{shape:?} [{a}]: {s} vs {want}"
            );
        }

        // The same on the axisymmetric grid about an axis through the middle of the cloud.
        let centre = DVec3::new(3.0, 2.5, 0.0);
        let moved = Snapshot {
            bodies: snap
                .bodies
                .iter()
                .map(|b| Body {
                    position: b.position - centre,
                    ..*b
                })
                .collect(),
            segments: Vec::new(),
            ..snap.clone()
        };
        // On the (r, z) grid the weight r of the volume element makes the midpoint rule's
        // error h²/24 · ∂(rρ)/∂r at the axis, which does not vanish: halving h must cut the
        // error four-fold, and Richardson's extrapolation (4 I_{h/2} − I_h)/3 removes it.
        let rz = |refine: f64| {
            let h = w / 4.0 / refine;
            let grid = Grid::Axisymmetric {
                r: [0.0, 4.0 + margin],
                z: [lo.z - margin, hi.z + margin],
                bins: [
                    ((4.0 + margin) / h).round() as usize,
                    (span.z / h).round() as usize,
                ],
                angle: TAU,
            };
            let points = coarse_grain(grid.clone(), &kernel, &moved);
            integrate(&grid, &points, |p| p.density)
        };
        let (coarse, fine) = (rz(1.0), rz(2.0));
        if shape == KernelShape::Lucy {
            let extrapolated = (4.0 * fine - coarse) / 3.0;
            assert!(
                (extrapolated / mass - 1.0).abs() < tol,
                "(r, z): ∫ρ = {coarse}, {fine} → {extrapolated}, Σm = {mass}"
            );
            let ratio = (coarse - mass) / (fine - mass);
            assert!((ratio - 4.0).abs() < 0.2, "error ratio {ratio}");
        } else {
            assert!(
                (fine / mass - 1.0).abs() < tol,
                "(r, z): ∫ρ = {fine}, Σm = {mass}"
            );
        }
    }
}

/// The brute-force azimuthal average at `(r, z)` of the fields of the full ring, from the
/// three-dimensional kernel at 4 000 azimuths (the integrand is smooth and periodic, so the
/// midpoint rule converges fast): `[ρ, j_r, j_φ, j_z, σ_c (9)]` in the local cylindrical
/// components, the contact stress by a 64-point midpoint rule along each segment.
fn ring_average(kernel: &Kernel, snap: &Snapshot, r: f64, z: f64) -> [f64; 13] {
    let n = 4_000;
    let c = kernel.cutoff();
    let mut out = [0.0; 13];
    for k in 0..n {
        let t = (k as f64 + 0.5) * TAU / n as f64;
        let (s, co) = t.sin_cos();
        let x = DVec3::new(r * co, r * s, z);
        let e = [DVec3::new(co, s, 0.0), DVec3::new(-s, co, 0.0), DVec3::Z];
        for b in &snap.bodies {
            let w = kernel.value((x - b.position).length_squared()) / n as f64;
            out[0] += b.mass * w;
            for a in 0..3 {
                out[1 + a] += b.mass * b.velocity.dot(e[a]) * w;
            }
        }
        for g in &snap.segments {
            let l = g.to - g.from;
            if (x - 0.5 * (g.from + g.to)).length() > c + 0.5 * l.length() {
                continue;
            }
            let m = 64;
            let spread: f64 = (0..m)
                .map(|i| {
                    let p = g.from + l * ((i as f64 + 0.5) / m as f64);
                    kernel.value((x - p).length_squared()) / m as f64
                })
                .sum::<f64>()
                / n as f64;
            for a in 0..3 {
                for b in 0..3 {
                    out[4 + 3 * a + b] += g.force.dot(e[a]) * l.dot(e[b]) * spread;
                }
            }
        }
    }
    out
}

#[test]
fn the_axisymmetric_grid_equals_the_azimuthal_average_of_the_full_ring() {
    // A wedge of 60° with its particles and contacts; its five rotated copies make the
    // full ring. The (r, z) grid sees only the wedge, with angle π/3.
    let angle = PI / 3.0;
    let wedge: Vec<DVec3> = scatter(400, DVec3::new(2.0, 0.0, 0.0), DVec3::new(6.0, 4.0, 3.0), 3)
        .into_iter()
        .filter(|p| {
            let phi = p.y.atan2(p.x);
            (0.0..angle).contains(&phi) && p.truncate().length() < 6.0
        })
        .collect();
    let bodies: Vec<Body> = wedge
        .iter()
        .map(|&p| body(p, DVec3::new(0.2 * p.z, 0.1 * p.x, -0.3 * p.y)))
        .collect();
    let segments: Vec<Segment> = wedge
        .windows(2)
        .map(|w| Segment {
            from: w[1] - (w[1] - w[0]).normalize() * 0.8,
            to: w[1],
            force: DVec3::new(0.3, -0.7, 0.4),
        })
        .collect();
    let snap = Snapshot {
        time: 0.0,
        bodies,
        segments,
        images: Vec::new(),
    };
    let mut full = Snapshot::default();
    for k in 0..6 {
        let m = glam::DMat3::from_rotation_z(k as f64 * angle);
        full.bodies.extend(snap.bodies.iter().map(|b| Body {
            position: m * b.position,
            velocity: m * b.velocity,
            ..*b
        }));
        full.segments.extend(snap.segments.iter().map(|s| Segment {
            from: m * s.from,
            to: m * s.to,
            force: m * s.force,
        }));
    }
    let kernel = Kernel::new(KernelShape::Lucy, 0.8).expect("valid");
    let grid = Grid::Axisymmetric {
        r: [3.0, 5.0],
        z: [1.0, 2.0],
        bins: [2, 2],
        angle,
    };
    let mut sums = CgSums::new(grid.clone()).expect("valid");
    sums.add_snapshot(&kernel, &snap);
    for (k, got) in sums.mean().iter().enumerate() {
        let x = grid.coordinates(k);
        let (r, z) = (x[0], x[1]);
        let want = ring_average(&kernel, &full, r, z);
        let check = |name: &str, got: f64, want: f64, scale: f64, tol: f64| {
            assert!(
                (got - want).abs() <= tol * scale,
                "{name} at ({r}, {z}): (r, z) grid {got}, ring average {want}"
            );
        };
        // The ring quadrature of 8 nodes against 4 000 azimuths: 10⁻⁶ of the value.
        check("ρ", got.mass, want[0], want[0], 1e-6);
        let scale = got.momentum.iter().map(|x| x.abs()).fold(0.0, f64::max);
        for c in 0..3 {
            check("momentum", got.momentum[c], want[1 + c], scale, 1e-6);
        }
        // The segment rule (a few Gauss nodes) against the fine midpoint rule: 10⁻³.
        let scale = got.contact.iter().map(|x| x.abs()).fold(0.0, f64::max);
        for a in 0..9 {
            check("contact stress", got.contact[a], want[4 + a], scale, 1e-3);
        }
    }
}
