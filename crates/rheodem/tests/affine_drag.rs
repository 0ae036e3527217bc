//! Lees-Edwards shear with affine drag (docs/model.md §4.5), the dynamics of the source
//! papers' code: the stored velocities `c` exclude the mean flow and obey `dc/dt = F/m`, the
//! box moves every free particle by `(c + γ̇ (y − lo_y) x̂) dt`, the images carry no velocity
//! jump and contacts see `c_i − c_j` (the pair across the boundary against the same pair
//! inside is in `tests/lees_edwards.rs`). The invariants tested here:
//!
//! * **Rest relative to the flow.** A particle with `c = 0` and no contacts keeps `c = 0`
//!   and its `y`, and its `x` advances by exactly `γ̇ (y − lo_y) dt` per step.
//! * **Crossings.** A particle crossing `y = L_y` (or `y = 0`) re-enters at `y ∓ L_y`,
//!   `x ∓ s` with its velocity unchanged, and goes on along the same unwrapped path.
//! * **Momentum.** In a sheared dense box the total force vanishes to rounding and
//!   `Σ m c` is conserved to rounding (no kick, drag or crossing changes it); the box resists
//!   the shear as it does in the lab frame.

mod common;

use common::*;
use glam::DVec3;
use rheodem::Simulation;
use rheodem::bench::standard_problem;
use rheodem::contact::LawKind;
use rheodem::domain::{Domain, ShearDynamics};

/// Lower corner of the test box, off the origin (m).
const LO: DVec3 = DVec3::new(-0.004, 0.0015, -0.001);
/// Edges of the test box (m).
const SIZE: DVec3 = DVec3::new(0.020, 0.018, 0.022);
/// Shear rate (1/s): `γ̇ L_y = 0.09 m/s`.
const RATE: f64 = 5.0;

/// The sheared test box with affine drag.
fn dragged_box() -> Domain {
    let mut d = Domain::new(LO, LO + SIZE, [true; 3]).with_lees_edwards(RATE);
    if let Some(le) = d.as_lees_edwards_mut() {
        le.dynamics = ShearDynamics::AffineDrag;
    }
    d
}

/// `x` brought into `[lo_x, hi_x)` and `z` into `[lo_z, hi_z)`.
fn wrap_xz(d: &Domain, mut r: DVec3) -> DVec3 {
    let l = d.lengths();
    r.x = d.lo.x + (r.x - d.lo.x).rem_euclid(l.x);
    r.z = d.lo.z + (r.z - d.lo.z).rem_euclid(l.z);
    r
}

/// Distance along `x` modulo `L_x` (m).
fn x_distance(a: f64, b: f64, period: f64) -> f64 {
    let d = (a - b).rem_euclid(period);
    d.min(period - d)
}

/// Five spheres spread over the height (the lowest and highest within a radius of the
/// faces), at rest relative to the flow, no two in reach, over two wraps of the shift:
/// their velocity stays exactly zero, `y` unchanged, and `x = x_0 + k γ̇ (y − lo_y) dt`
/// modulo `L_x`. Tolerance `10⁻¹² L_x`: each of the ~10⁴ steps adds a rounding of
/// `ε L_x` to `x` (`10⁴ ε ≈ 2·10⁻¹²` at worst, `√10⁴ ε` typically).
#[test]
fn particles_at_rest_relative_to_the_flow_stay_so() {
    let domain = dragged_box();
    let a = A_REF;
    let heights = [
        0.6 * a,
        0.2 * SIZE.y,
        0.5 * SIZE.y,
        0.8 * SIZE.y,
        SIZE.y - 0.6 * a,
    ];
    let spheres: Vec<_> = heights
        .iter()
        .enumerate()
        .map(|(k, &h)| {
            let r = LO + DVec3::new((0.1 + 0.17 * k as f64) * SIZE.x, h, 0.5 * SIZE.z);
            sphere(r, DVec3::ZERO, a)
        })
        .collect();
    let law = frictional_law(0.8, 0.5);
    let dt = law
        .normal
        .contact_time(0.5 * mass(a), 0.5 * a)
        .expect("underdamped")
        / 50.0;
    let mut sim = simulation(&spheres, law, domain, vec![], DVec3::ZERO, dt);
    // Long enough for two wraps of the shift (at strains L_x/2L_y and 3L_x/2L_y).
    let steps = (1.6 * SIZE.x / (SIZE.y * RATE * dt)).ceil() as u64;
    let mut worst = 0.0f64;
    for k in 1..=steps {
        sim.step(k % 100 == 0).expect("step");
        for (id, s) in spheres.iter().enumerate() {
            let i = slot(&sim, id as u32);
            let (r, v) = (sim.particles.position[i], sim.particles.velocity[i]);
            assert_eq!(v, DVec3::ZERO, "sphere {id} gained a velocity at step {k}");
            assert_eq!(r.y, s.position.y, "sphere {id} moved in y at step {k}");
            assert_eq!(r.z, s.position.z);
            let expected = s.position.x + k as f64 * RATE * (s.position.y - LO.y) * dt;
            worst = worst.max(x_distance(r.x, expected, SIZE.x) / SIZE.x);
        }
    }
    let o = sim.observables();
    eprintln!(
        "{steps} steps, {} shift wraps: largest |Δx| = {worst:.2e} L_x; contacts {}, \
         granular temperature {:.1e} m²/s², lab kinetic energy {:.3e} J",
        sim.domain.image_epoch(),
        o.contacts,
        o.granular_temperature,
        o.kinetic_translational
    );
    assert!(
        sim.domain.image_epoch() >= 2,
        "the shift should have wrapped"
    );
    assert!(
        worst < 1e-12,
        "x drifted from the mean flow by {worst:.3e} L_x"
    );
    assert_eq!(o.contacts, 0);
    assert_eq!(o.granular_temperature, 0.0);
    // The kinetic energy is that of the motion in the lab, ½ Σ m (γ̇ (y − lo_y))².
    let lab: f64 = heights
        .iter()
        .map(|h| 0.5 * mass(a) * (RATE * h).powi(2))
        .sum();
    assert!((o.kinetic_translational / lab - 1.0).abs() < 1e-12);
}

/// The unwrapped path of a lone particle under affine drag from `r0` with velocity `c`
/// after `k` steps of `dt`: `y = y_0 + k c_y dt`, and `x` gains `c_x dt` plus the drag
/// `γ̇ (y_n − lo_y) dt` at each step's drifted height `y_n`.
fn unwrapped(r0: DVec3, c: DVec3, k: u64, dt: f64) -> DVec3 {
    let n = k as f64;
    let drag = RATE * dt * (n * (r0.y - LO.y) + c.y * dt * n * (n + 1.0) / 2.0);
    DVec3::new(
        r0.x + c.x * n * dt + drag,
        r0.y + c.y * n * dt,
        r0.z + c.z * n * dt,
    )
}

/// A lone particle crosses the top (bottom) face. Once a rebuild has wrapped it, it sits at
/// its unwrapped position mapped by `(∓s, ∓L_y, 0)` with the shift of the moment, and it
/// keeps that relation over the next 500 steps; its velocity never changes. Tolerance
/// `10⁻¹² L_x` (a rounding per step, as above).
#[test]
fn a_crossing_keeps_the_velocity_and_the_path() {
    for upwards in [true, false] {
        let domain = dragged_box();
        let a = A_REF;
        let r0 = if upwards {
            LO + DVec3::new(0.05 * SIZE.x, SIZE.y - 0.5 * a, 0.4 * SIZE.z)
        } else {
            LO + DVec3::new(0.95 * SIZE.x, 0.5 * a, 0.4 * SIZE.z)
        };
        let c = DVec3::new(0.01, if upwards { 0.03 } else { -0.03 }, -0.004);
        let law = normal_law(0.8);
        let dt = law
            .normal
            .contact_time(0.5 * mass(a), 0.5 * a)
            .expect("underdamped")
            / 50.0;
        let mut sim = simulation(&[sphere(r0, c, a)], law, domain, vec![], DVec3::ZERO, dt);
        let sign = if upwards { 1.0 } else { -1.0 };
        let (mut wrapped_at, mut worst) = (None, 0.0f64);
        for k in 1..=6000u64 {
            sim.step(false).expect("step");
            let (r, v) = (sim.particles.position[0], sim.particles.velocity[0]);
            assert_eq!(v, c, "the velocity changed at step {k}");
            let inside = r.y >= sim.domain.lo.y && r.y < sim.domain.hi.y;
            let path = unwrapped(r0, c, k, dt);
            let crossed = path.y >= sim.domain.hi.y || path.y < sim.domain.lo.y;
            if crossed && inside {
                let first = *wrapped_at.get_or_insert(k);
                let s = sim.domain.as_lees_edwards().expect("sheared").shift;
                let expected = wrap_xz(&sim.domain, path - sign * DVec3::new(s, SIZE.y, 0.0));
                let e = wrap_xz(&sim.domain, r) - expected;
                worst = worst.max(
                    x_distance(e.x, 0.0, SIZE.x)
                        .max(e.y.abs())
                        .max(x_distance(e.z, 0.0, SIZE.z))
                        / SIZE.x,
                );
                if k > first + 500 {
                    break;
                }
            } else if !crossed {
                let e = wrap_xz(&sim.domain, r) - wrap_xz(&sim.domain, path);
                worst = worst.max(x_distance(e.x, 0.0, SIZE.x).max(e.y.abs()) / SIZE.x);
            }
        }
        eprintln!(
            "{}: wrapped at step {wrapped_at:?}, largest deviation from the path {worst:.2e} L_x",
            if upwards { "up" } else { "down" }
        );
        assert!(wrapped_at.is_some(), "the particle never got wrapped");
        assert!(worst < 1e-12, "off the path by {worst:.3e} L_x");
    }
}

/// `Σ m c` over the free particles (kg m/s).
fn momentum(sim: &Simulation) -> DVec3 {
    let p = &sim.particles;
    (0..p.len()).map(|i| p.velocity[i] * p.mass[i]).sum()
}

/// The standard problem sheared with `dynamics` for `steps` steps; returns the simulation,
/// the largest `|Σ F| / Σ |F_i|`, the largest change of `Σ m c` relative to `M γ̇ L_y`
/// (`c` the velocity relative to the mean flow), and the mean `σ_xy` (Pa) of the second half.
fn sheared_standard_problem(dynamics: ShearDynamics, steps: u64) -> (Simulation, f64, f64, f64) {
    let mut sim = standard_problem(1.0, LawKind::None, 0.2);
    // The problem starts with the lab profile; re-express its velocities for the dynamics.
    let lab = sim.domain.clone();
    if let Some(le) = sim.domain.as_lees_edwards_mut() {
        le.dynamics = dynamics;
    }
    for i in 0..sim.particles.len() {
        let (r, v) = (sim.particles.position[i], sim.particles.velocity[i]);
        sim.particles.velocity[i] = sim.domain.stored_velocity(r, lab.peculiar_velocity(r, v));
    }
    let peculiar = |sim: &Simulation| -> DVec3 {
        let p = &sim.particles;
        (0..p.len())
            .map(|i| sim.domain.peculiar_velocity(p.position[i], p.velocity[i]) * p.mass[i])
            .sum()
    };
    let q0 = peculiar(&sim);
    let scale = sim.particles.mass.iter().sum::<f64>() * sim.domain.lengths().y;
    let (mut worst_f, mut worst_q, mut sigma, mut n) = (0.0f64, 0.0f64, 0.0, 0);
    for k in 1..=steps {
        let measure = k > steps / 2 && k % 10 == 0;
        sim.step(measure).expect("step");
        let total: DVec3 = sim.particles.force.iter().copied().sum();
        let scale_f: f64 = sim.particles.force.iter().map(|f| f.length()).sum();
        worst_f = worst_f.max(total.length() / scale_f);
        worst_q = worst_q.max((peculiar(&sim) - q0).length() / scale);
        if measure {
            sigma += sim.observables().stress[0][1];
            n += 1;
        }
    }
    (sim, worst_f, worst_q, sigma / n as f64)
}

/// The standard 4096-sphere problem (`φ = 0.62`, `γ̇ = 1`, model units) under affine drag
/// for 2000 steps (strain 0.64, past a wrap of the shift): `|Σ F| ≤ 10⁻¹² Σ |F_i|` and
/// `Σ m c` conserved to `10⁻¹²` of `M γ̇ L_y` (the reasoning of the lab-frame test in
/// `tests/lees_edwards.rs`, without the crossings' roundings). The packing resists the
/// shear: the mean `σ_xy` of the second half has the sign of the lab frame's, and the same
/// order of magnitude (within a factor 3: the two dynamics differ at this strain, which is
/// no steady state).
#[test]
fn total_force_vanishes_and_momentum_is_conserved() {
    let steps = 2000;
    let (sim, worst_f, worst_q, sigma) = sheared_standard_problem(ShearDynamics::AffineDrag, steps);
    let (_, _, _, sigma_lab) = sheared_standard_problem(ShearDynamics::Lab, steps);
    let o = sim.observables();
    eprintln!(
        "affine drag, {steps} steps ({} shift wraps): max |ΣF|/Σ|F_i| = {worst_f:.2e}, \
         max |ΔΣ m c|/(M γ̇ L_y) = {worst_q:.2e}; Z = {:.2}; σ_xy = {sigma:.4e} (lab frame \
         {sigma_lab:.4e}); Σ m c = {:?}",
        sim.domain.image_epoch(),
        o.coordination,
        momentum(&sim)
    );
    assert!(
        o.coordination > 3.0,
        "not a dense packing: Z = {}",
        o.coordination
    );
    assert!(
        sim.domain.image_epoch() >= 1,
        "the shift should have wrapped"
    );
    assert!(worst_f < 1e-12, "total force {worst_f:.3e} of Σ|F_i|");
    assert!(worst_q < 1e-12, "Σ m c changed by {worst_q:.3e}");
    assert!(
        sigma * sigma_lab > 0.0,
        "σ_xy {sigma:.3e} vs lab {sigma_lab:.3e}"
    );
    let ratio = sigma / sigma_lab;
    assert!((1.0 / 3.0..3.0).contains(&ratio), "σ_xy ratio {ratio:.3}");
}
