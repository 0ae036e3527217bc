//! Walls inside running simulations: a granular column settling on a planar floor (force
//! balance, the floor's share of the stress), rough walls of lattice spheres
//! (`kind = "lattice"`: geometry, a sphere resting on one), and wall particles in
//! prescribed rotation (`motion = { rotating = … }`) touched by a free particle.

mod common;

use common::*;
use glam::DVec3;
use rheodem::Simulation;
use rheodem::particles::Motion;
use rheodem::scenario::{Scenario, build};
use std::f64::consts::PI;
use std::path::Path;
use std::time::Instant;

/// Builds a scenario given as TOML text.
fn built(text: &str) -> rheodem::scenario::Built {
    let s = Scenario::from_toml(text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    build(&s, Path::new(".")).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// The force (N) that the planar wall `k` exerts on the free particles, evaluated on a
/// copy of the simulation (the wall's own contact history advances only in the copy; the
/// normal force does not depend on it).
fn wall_force(sim: &Simulation, k: usize) -> DVec3 {
    let mut copy = sim.clone();
    copy.particles
        .force
        .iter_mut()
        .for_each(|f| *f = DVec3::ZERO);
    let dt = copy.dt;
    let laws = copy.laws.clone();
    copy.walls[k].apply(k as u32, &mut copy.particles, &laws, dt, &mut ());
    copy.particles.force.iter().copied().sum()
}

/// Volume (m³) of the part of a sphere (centre height `zc`, radius `a`) inside the slab
/// `z1 ≤ z ≤ z2`: `π ∫ (a² − (z − zc)²) dz` over the overlap.
fn slab_volume(zc: f64, a: f64, z1: f64, z2: f64) -> f64 {
    let t1 = (z1 - zc).max(-a);
    let t2 = (z2 - zc).min(a);
    if t2 <= t1 {
        return 0.0;
    }
    let f = |t: f64| a * a * t - t * t * t / 3.0;
    PI * (f(t2) - f(t1))
}

// ---------------------------------------------------------------------------------------
// A column settling under gravity onto a planar floor.
// ---------------------------------------------------------------------------------------

/// 300 frictional spheres (`μ = 0.5`, `e = 0.3`, radii within ±10 % of 1.1 mm) start on a
/// jittered loose lattice above a planar floor at `z = 0` in a box periodic in `x` and `y`
/// (6 × 6 mean diameters), fall under `g = −9.81 ẑ` and settle until their kinetic energy
/// is below `2·10⁻⁶ M g d` (a mean speed of 2·10⁻³ sqrt(g d); what is left is mostly a few
/// surface spheres rolling, with no rolling resistance). Then:
///
/// - **Force balance**: the floor's normal force per area equals the weight per area
///   `M g / A` within 1 %. At rest this is exact (the pair forces cancel in pairs, so the
///   floor carries the whole weight); what is left is `Σ m a_z` of the residual motion,
///   measured at ≤ 0.2 % once the kinetic energy is this low (0.9 % at 5·10⁻⁶ M g d, on
///   the way down).
/// - **The floor's share of the stress**: for a packing at rest, summing `z_i` times the
///   force balance of every particle gives `Σ_pairs f_z l_z + Σ_floor f_z gap = g Σ m_i z_i`
///   exactly, the left side being `V σ_zz` (contact part) under the documented convention
///   (`l = r_i − r_j`; for a planar wall, from the foot on the wall to the centre). Checked
///   within 1 %; leaving the floor contacts out would miss it by their `Σ f_z gap ≈ M g a`,
///   i.e. by `a / z_cm ≈ 15 %`.
/// - **Hydrostatics**: the bottom pressure against `ρ_p φ g h`, `φ` the volume fraction
///   measured in the bulk of the column (exact sphere–slab volumes between `z = 2 d` and
///   `h − 2 d`) and `h` the mean height of the free surface (the highest sphere top in
///   each `d × d` column, averaged). Within 8 %: `ρ_p φ g h` would be exact for a uniform
///   slab of height `h`, and the column is not one — the layer against the floor is looser
///   than the bulk (no sphere reaches into the wall), and the mean top height overstates
///   the filled height by a fraction of a diameter; each is worth a few per cent of
///   `h ≈ 7.6 d` (measured together: `P / (ρ_p φ g h) = 0.97`).
#[test]
fn settled_column_is_carried_by_the_floor() {
    let start = Instant::now();
    let d = 2.0 * A_REF;
    let edge = 6.0 * d;
    let domain = rheodem::domain::Domain::new(
        DVec3::ZERO,
        DVec3::new(edge, edge, 60.0 * d),
        [true, true, false],
    );
    let mut rng = rng(11);
    let per_row = 5;
    let spacing = edge / per_row as f64;
    let mut spheres = Vec::new();
    'fill: for layer in 0.. {
        for ix in 0..per_row {
            for iy in 0..per_row {
                if spheres.len() == 300 {
                    break 'fill;
                }
                let a = A_REF * (0.9 + 0.2 * rand::RngExt::random_range(&mut rng, 0.0..1.0));
                let jitter = random_vec(&mut rng, 0.05 * d);
                let r = DVec3::new(
                    (ix as f64 + 0.5) * spacing,
                    (iy as f64 + 0.5) * spacing,
                    (layer as f64 + 0.6) * 1.2 * d,
                ) + DVec3::new(jitter.x, jitter.y, 0.0);
                spheres.push(sphere(r, DVec3::ZERO, a));
            }
        }
    }
    let law = frictional_law(0.3, 0.5);
    let m_min = mass(0.9 * A_REF);
    let t_c = law
        .normal
        .contact_time(0.5 * m_min, 0.45 * A_REF)
        .expect("underdamped");
    let g = 9.81;
    let mut sim = simulation(
        &spheres,
        law,
        domain,
        vec![(DVec3::ZERO, DVec3::Z)],
        DVec3::new(0.0, 0.0, -g),
        t_c / 25.0,
    );
    let total_mass: f64 = sim.particles.mass.iter().sum();
    let weight = total_mass * g;
    let mut settled = false;
    while sim.time < 2.0 {
        for _ in 0..999 {
            sim.step(false).expect("step");
        }
        sim.step(true).expect("step");
        let o = sim.observables();
        assert!(o.is_finite());
        if o.kinetic_translational + o.kinetic_rotational < 2e-6 * weight * d {
            settled = true;
            break;
        }
    }
    assert!(settled, "not at rest after {} s", sim.time);
    let p = &sim.particles;
    assert!(
        p.position.iter().zip(&p.radius).all(|(r, a)| r.z > 0.9 * a),
        "nobody fell through the floor"
    );

    // Force balance.
    let area = edge * edge;
    let floor = wall_force(&sim, 0);
    let bottom_pressure = floor.z / area;
    assert!(
        (bottom_pressure / (weight / area) - 1.0).abs() < 0.01,
        "floor {} N vs weight {weight} N",
        floor.z
    );

    // The floor's share of σ_zz: V σ_zz(contact) = g Σ m z.
    let o = sim.observables();
    let volume = sim.domain.volume();
    let kinetic = rheodem::measure::kinetic_stress_sum(p, &sim.domain);
    let virial = o.stress[2][2] * volume - kinetic.z_axis.z;
    let moment: f64 = g
        * (0..p.len())
            .map(|i| p.mass[i] * p.position[i].z)
            .sum::<f64>();
    assert!(
        (virial / moment - 1.0).abs() < 0.01,
        "V σ_zz = {virial} vs g Σ m z = {moment}"
    );

    // Hydrostatics.
    let cells = 6;
    let mut top = vec![0.0f64; cells * cells];
    for i in 0..p.len() {
        let cx = ((p.position[i].x / edge * cells as f64) as usize).min(cells - 1);
        let cy = ((p.position[i].y / edge * cells as f64) as usize).min(cells - 1);
        let t = &mut top[cx * cells + cy];
        *t = t.max(p.position[i].z + p.radius[i]);
    }
    let h = top.iter().sum::<f64>() / top.len() as f64;
    let (z1, z2) = (2.0 * d, h - 2.0 * d);
    assert!(z2 - z1 > 2.0 * d, "column too short: h = {h}");
    let solid: f64 = (0..p.len())
        .map(|i| slab_volume(p.position[i].z, p.radius[i], z1, z2))
        .sum();
    let phi = solid / (area * (z2 - z1));
    assert!(phi > 0.5 && phi < 0.66, "bulk φ = {phi}");
    let hydrostatic = RHO * phi * g * h;
    assert!(
        (bottom_pressure / hydrostatic - 1.0).abs() < 0.08,
        "P = {bottom_pressure} Pa vs ρ φ g h = {hydrostatic} Pa (φ = {phi}, h = {h})"
    );
    eprintln!(
        "settled at t = {:.3} s after {:.1} s wall: φ = {phi:.4}, h = {:.2} d, P/(ρφgh) = {:.4}, floor/weight = {:.6}",
        sim.time,
        start.elapsed().as_secs_f64(),
        h / d,
        bottom_pressure / hydrostatic,
        floor.z / weight
    );
}

// ---------------------------------------------------------------------------------------
// Lattice walls.
// ---------------------------------------------------------------------------------------

/// The spheres of a `kind = "lattice"` group: a rectangular patch tilted out of the
/// coordinate planes (`edge_a = 8.5 mm x̂`, `edge_b = 6 mm (ŷ + ẑ)`, `|edge_b| = 8.49 mm`)
/// with spacing 1.2 mm, and one with the default spacing (one diameter) and edges that
/// are not multiples of it (3.0 mm and 2.5 mm at 0.8 mm). The lattice holds
/// `(⌊|e_a|/h⌋ + 1)(⌊|e_b|/h⌋ + 1)` spheres (8 × 8 and 4 × 4) at
/// `origin + u h ê_a + v h ê_b`, all inside the parallelogram and covering it (one more
/// step along either edge would leave it), each with the group's radius and prescribed
/// (fixed by default, or the motion given), lattice neighbours exactly `h` apart. Positions
/// are compared to `10⁻¹²` of the box size (the same sum in another order).
#[test]
fn lattice_groups_have_the_documented_geometry() {
    let text = r#"
        [domain]
        size = [0.02, 0.02, 0.02]
        [[species]]
        name = "s"
        density = 2000.0
        [[contact]]
        normal = { stiffness = 100.0, restitution = 0.5 }
        [[particles]]
        kind = "lattice"
        species = "s"
        origin = [1.0e-3, 2.0e-3, 0.5e-3]
        edge_a = [8.5e-3, 0.0, 0.0]
        edge_b = [0.0, 6.0e-3, 6.0e-3]
        radius = 0.5e-3
        spacing = 1.2e-3
        motion = { rotating = { center = [0.0, 0.0, 0.0], axis = [0.0, 0.0, 1.0], omega = 0.0 } }
        [[particles]]
        kind = "lattice"
        species = "s"
        origin = [12.0e-3, 12.0e-3, 15.0e-3]
        edge_a = [0.0, 3.0e-3, 0.0]
        edge_b = [2.5e-3, 0.0, 0.0]
        radius = 0.4e-3
        [[particles]]
        kind = "explicit"
        species = "s"
        spheres = [{ radius = 1.0e-3, position = [15.0e-3, 5.0e-3, 5.0e-3] }]
        [run]
        steps = 1
    "#;
    let b = built(text);
    let p = &b.simulation.particles;
    assert_eq!(b.resolved.wall_particles, 64 + 16);
    assert_eq!(b.resolved.free_particles, 1);
    assert_eq!(p.len(), 81);
    let slot = p.slot_of();
    let groups = [
        (
            0usize,
            DVec3::new(1.0e-3, 2.0e-3, 0.5e-3),
            DVec3::new(8.5e-3, 0.0, 0.0),
            DVec3::new(0.0, 6.0e-3, 6.0e-3),
            0.5e-3,
            1.2e-3,
            (8usize, 8usize),
        ),
        (
            64,
            DVec3::new(12.0e-3, 12.0e-3, 15.0e-3),
            DVec3::new(0.0, 3.0e-3, 0.0),
            DVec3::new(2.5e-3, 0.0, 0.0),
            0.4e-3,
            0.8e-3,
            (4, 4),
        ),
    ];
    for (g, &(first, origin, ea, eb, radius, h, (na, nb))) in groups.iter().enumerate() {
        // The counts follow from the edges: na − 1 steps fit along ê_a, na do not.
        assert!((na - 1) as f64 * h <= ea.length() && na as f64 * h > ea.length());
        assert!((nb - 1) as f64 * h <= eb.length() && nb as f64 * h > eb.length());
        let (ua, ub) = (ea / ea.length(), eb / eb.length());
        let at = |u: usize, v: usize| {
            let id = first + u * nb + v;
            p.position[slot[id] as usize]
        };
        for u in 0..na {
            for v in 0..nb {
                let i = slot[first + u * nb + v] as usize;
                let want = origin + ua * (u as f64 * h) + ub * (v as f64 * h);
                assert!(
                    (p.position[i] - want).length() < 1e-12 * 0.02,
                    "group {g} ({u}, {v}): {} vs {want}",
                    p.position[i]
                );
                assert_eq!(p.radius[i], radius);
                assert!(!p.motion[i].is_free());
                if g == 1 {
                    assert_eq!(p.motion[i], Motion::Fixed, "default motion");
                }
                // Parallelogram coordinates (the edges are orthogonal): s, t ∈ [0, 1].
                let rel = p.position[i] - origin;
                let (s, t) = (
                    rel.dot(ea) / ea.length_squared(),
                    rel.dot(eb) / eb.length_squared(),
                );
                assert!((-1e-12..=1.0 + 1e-12).contains(&s) && (-1e-12..=1.0 + 1e-12).contains(&t));
                assert!(rel.dot(ea.cross(eb)).abs() < 1e-12 * 0.02 * ea.cross(eb).length());
                if u + 1 < na {
                    assert!(((at(u + 1, v) - at(u, v)).length() / h - 1.0).abs() < 1e-12);
                }
                if v + 1 < nb {
                    assert!(((at(u, v + 1) - at(u, v)).length() / h - 1.0).abs() < 1e-12);
                }
            }
        }
    }
}

/// Equilibrium overlap `δ` and height `z` (m) of a sphere of mass `m` and radius `R`
/// resting in the hollow of four lattice spheres of radius `a` whose centres lie a
/// horizontal distance `ρ` from it, with linear springs `k_n`: `4 k_n δ z / D = m g`,
/// `D = R + a − δ`, `z = sqrt(D² − ρ²)`. Solved by bisection.
fn hollow_equilibrium(m: f64, g: f64, big: f64, a: f64, rho: f64) -> (f64, f64) {
    let residual = |delta: f64| {
        let dd = big + a - delta;
        let z = (dd * dd - rho * rho).sqrt();
        4.0 * KN * delta * z / dd - m * g
    };
    let (mut lo, mut hi) = (0.0, 0.01 * big);
    assert!(residual(hi) > 0.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if residual(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let delta = 0.5 * (lo + hi);
    let dd = big + a - delta;
    (delta, (dd * dd - rho * rho).sqrt())
}

/// A free sphere (`R = 1.1 mm`) dropped from 0.1 R above its resting height onto a rough
/// floor of fixed lattice spheres (`a = 0.5 mm`, spacing 1.2 mm, centres at `z = 0`) comes
/// to rest in the hollow between four of them at the height of the closed-form balance
/// `4 k_n δ z/D = m g` (`D = R + a − δ`, `z = sqrt(D² − h²/2)`), within `10⁻⁶` of the
/// overlap `δ` (the damped oscillation, `e = 0.3`, has decayed far below that), stays on
/// the hollow's axis, feels a total force of zero to `10⁻⁶ m g` (the contacts carry its
/// weight), and each of the four lattice spheres pushes with `k_n δ`. Its contact stress
/// obeys `V σ_zz = Σ f_z l_z = m g z` (the lattice centres lie at `z = 0`), within `10⁻⁶`.
#[test]
fn sphere_rests_on_a_lattice_floor() {
    let (big, a, h): (f64, f64, f64) = (1.1e-3, 0.5e-3, 1.2e-3);
    let rho_h = h / 2f64.sqrt();
    let g = 9.81;
    let m = RHO * 4.0 / 3.0 * PI * big.powi(3);
    let (delta, z_eq) = hollow_equilibrium(m, g, big, a, rho_h);
    let text = format!(
        r#"
        gravity = [0.0, 0.0, -{g}]
        [domain]
        lo = [-0.01, -0.01, -0.002]
        size = [0.02, 0.02, 0.02]
        [[species]]
        name = "s"
        density = {RHO}
        [[contact]]
        normal = {{ stiffness = {KN}, restitution = 0.3 }}
        [[particles]]
        kind = "lattice"
        species = "s"
        origin = [{o}, {o}, 0.0]
        edge_a = [{e}, 0.0, 0.0]
        edge_b = [0.0, {e}, 0.0]
        radius = {a}
        spacing = {h}
        [[particles]]
        kind = "explicit"
        species = "s"
        spheres = [{{ radius = {big}, position = [0.0, 0.0, {z0}] }}]
        [run]
        steps = 1
        "#,
        o = -2.5 * h,
        e = 5.5 * h,
        z0 = z_eq + 0.1 * big,
    );
    let mut sim = built(&text).simulation;
    assert_eq!(sim.particles.len(), 37);
    let free = (0..37)
        .find(|&i| sim.particles.motion[i].is_free())
        .expect("one free sphere");
    let free_id = sim.particles.id[free];
    let steps = (0.1 / sim.dt) as usize;
    for _ in 0..steps {
        sim.step(false).expect("step");
    }
    sim.step(true).expect("step");
    let i = slot(&sim, free_id);
    let p = &sim.particles;
    let r = p.position[i];
    assert!(
        (r.z - z_eq).abs() < 1e-6 * delta,
        "z = {} vs {z_eq} (δ = {delta})",
        r.z
    );
    assert!(r.truncate().length() < 1e-6 * delta, "off axis: {r}");
    // The contacts carry the weight: the total force (contacts + gravity) vanishes.
    assert!(
        p.force[i].length() < 1e-6 * m * g,
        "net force {}",
        p.force[i]
    );
    let o = sim.observables();
    assert_eq!(o.contacts, 4);
    // Each of the four contacts pushes with k_n δ along its normal.
    let mut pushed = 0;
    for j in 0..p.len() {
        let l = r - p.position[j];
        if j != i && l.length() < big + a {
            let overlap = big + a - l.length();
            assert!(((KN * overlap) / (KN * delta) - 1.0).abs() < 1e-6);
            pushed += 1;
        }
    }
    assert_eq!(pushed, 4);
    let virial = o.stress[2][2] * sim.domain.volume();
    assert!(
        (virial / (m * g * z_eq) - 1.0).abs() < 1e-6,
        "V σ_zz = {virial} vs m g z = {}",
        m * g * z_eq
    );
}

// ---------------------------------------------------------------------------------------
// Rotating wall particles.
// ---------------------------------------------------------------------------------------

/// `r` rotated by `angle` about the unit `axis` through `center` (Rodrigues' formula).
fn rotated(r: DVec3, center: DVec3, axis: DVec3, angle: f64) -> DVec3 {
    let x = r - center;
    let (s, c) = angle.sin_cos();
    center + x * c + axis.cross(x) * s + axis * axis.dot(x) * (1.0 - c)
}

/// Six wall spheres on a ring (radius 4 mm, offset 1 mm along the axis from the centre)
/// rotate at `Ω = 30 rad/s` about the oblique axis `(1, 2, 2)/3` through
/// `c = (10, 10, 10) mm`; a free frictional sphere starts just touching one of them and is
/// knocked away. After every step, and while the free sphere is in contact, every wall
/// sphere is where the closed-form rotation puts it,
/// `c + R(Ω t)(r₀ − c)` (Rodrigues), within `10⁻¹¹` of the ring radius (the code composes
/// `t/dt` small rotations, each exact to a few `10⁻¹⁶`, so rounding accumulates to at most
/// ~`10⁻¹³` over the 1500 steps), moves with `Ω ẑ' × (r − c)` and spins with `Ω` (to
/// `10⁻¹²` of their size) — contact forces do not disturb it — while the free sphere, the
/// only free body, takes up momentum from the contact.
#[test]
fn rotating_wall_follows_its_rigid_rotation_while_touched() {
    let center = DVec3::splat(10.0e-3);
    let axis = DVec3::new(1.0, 2.0, 2.0) / 3.0;
    let omega = 30.0;
    // An orthonormal pair perpendicular to the axis.
    let e1 = DVec3::new(2.0, -1.0, 0.0).normalize();
    let e2 = axis.cross(e1);
    let (ring, a_w, a_f) = (4.0e-3, 0.8e-3, 1.0e-3);
    let starts: Vec<DVec3> = (0..6)
        .map(|k| {
            let phi = k as f64 * PI / 3.0;
            center + axis * 1.0e-3 + (e1 * phi.cos() + e2 * phi.sin()) * ring
        })
        .collect();
    // The free sphere sits just outside sphere 0 along its radial direction, overlapping it
    // by 1 µm, ahead of it in the sense of motion by a little so that it is pushed.
    let radial = (starts[0] - center - axis * axis.dot(starts[0] - center)).normalize();
    let tangent = axis.cross(radial);
    let dir = (radial + 0.5 * tangent).normalize();
    let free_start = starts[0] + dir * (a_w + a_f - 1.0e-6);
    let fmt = |r: DVec3| format!("[{:e}, {:e}, {:e}]", r.x, r.y, r.z);
    let wall_spheres = starts
        .iter()
        .map(|r| format!("{{ radius = {a_w:e}, position = {} }}", fmt(*r)))
        .collect::<Vec<_>>()
        .join(", ");
    let text = format!(
        r#"
        [domain]
        size = [0.02, 0.02, 0.02]
        [[species]]
        name = "s"
        density = 2000.0
        [[contact]]
        normal = {{ stiffness = 100.0, restitution = 0.7 }}
        friction = {{ stiffness_ratio = 0.2857, damping_ratio = 0.2857, mu = 0.5 }}
        [[particles]]
        kind = "explicit"
        species = "s"
        motion = {{ rotating = {{ center = {c}, axis = [1.0, 2.0, 2.0], omega = {omega} }} }}
        spheres = [{wall_spheres}]
        [[particles]]
        kind = "explicit"
        species = "s"
        spheres = [{{ radius = {a_f:e}, position = {f} }}]
        [run]
        steps = 1
        "#,
        c = fmt(center),
        f = fmt(free_start),
    );
    let mut sim = built(&text).simulation;
    let dt = sim.dt;
    let mut touched = 0;
    for n in 1..=1500u32 {
        sim.step(true).expect("step");
        let t = f64::from(n) * dt;
        let p = &sim.particles;
        let slots = p.slot_of();
        for (k, r0) in starts.iter().enumerate() {
            let i = slots[k] as usize;
            let want = rotated(*r0, center, axis, omega * t);
            assert!(
                (p.position[i] - want).length() < 1e-11 * ring,
                "step {n}, sphere {k}: {} vs {want}",
                p.position[i]
            );
            let v = (axis * omega).cross(want - center);
            assert!((p.velocity[i] - v).length() < 1e-12 * v.length().max(omega * ring));
            assert!((p.angular_velocity[i] - axis * omega).length() < 1e-12 * omega);
        }
        touched += usize::from(sim.observables().contacts > 0);
    }
    assert!(
        touched >= 5,
        "the free sphere touched the wall for {touched} steps"
    );
    let f = slot(&sim, 6);
    assert!(sim.particles.motion[f].is_free());
    let speed = sim.particles.velocity[f].length();
    assert!(
        speed > 1e-3 * omega * ring,
        "the free sphere was pushed: v = {speed}"
    );
}

/// A rotating wall sphere whose circle crosses a periodic boundary: the box is periodic in
/// `x` and `y` (20 mm), the axis is `ẑ` through `c = (19, 10, 10) mm`, the sphere starts
/// inside the box 3 mm from the axis at `x = 16 mm` and turns once, half of the turn
/// beyond `x = 20 mm`. Through the periodic boundaries it must be at `c + R(Ω t)(r₀ − c)`
/// up to whole box lengths (checked to `10⁻¹¹` of the radius after every step, as above).
///
/// Regression: the neighbour list wraps every particle into the box, prescribed ones
/// included, and `drift` used to rotate the wrapped position about the unwrapped `c`, so
/// from the first rebuild after the crossing the sphere ran on a circle of ~19 mm instead
/// of 3 mm (it failed at step 5161 of 11 600). The wrap now moves the axis with the
/// particle.
#[test]
fn rotating_wall_across_a_periodic_boundary() {
    let center = DVec3::new(19.0e-3, 10.0e-3, 10.0e-3);
    let r0 = center - DVec3::new(3.0e-3, 0.0, 0.0);
    let omega = 30.0;
    let text = format!(
        r#"
        [domain]
        size = [0.02, 0.02, 0.02]
        periodic = [true, true, false]
        [[species]]
        name = "s"
        density = 2000.0
        [[contact]]
        normal = {{ stiffness = 100.0, restitution = 0.7 }}
        [[particles]]
        kind = "explicit"
        species = "s"
        motion = {{ rotating = {{ center = [{cx:e}, {cy:e}, {cz:e}], axis = [0.0, 0.0, 1.0], omega = {omega} }} }}
        spheres = [{{ radius = 0.8e-3, position = [{x:e}, {y:e}, {z:e}] }}]
        [[particles]]
        kind = "explicit"
        species = "s"
        spheres = [{{ radius = 1.0e-3, position = [5.0e-3, 5.0e-3, 5.0e-3] }}]
        [run]
        steps = 1
        "#,
        cx = center.x,
        cy = center.y,
        cz = center.z,
        x = r0.x,
        y = r0.y,
        z = r0.z,
    );
    let mut sim = built(&text).simulation;
    let l = sim.domain.lengths();
    let turn = (2.0 * PI / omega / sim.dt).ceil() as u32;
    for n in 1..=turn {
        sim.step(false).expect("step");
        let want = rotated(r0, center, DVec3::Z, omega * f64::from(n) * sim.dt);
        let got = sim.particles.position[slot(&sim, 0)];
        let mut d = got - want;
        d.x -= l.x * (d.x / l.x).round();
        d.y -= l.y * (d.y / l.y).round();
        assert!(
            d.length() < 1e-11 * 3.0e-3,
            "step {n}: {got} is no image of {want}"
        );
    }
}
