//! Binary collisions against the closed forms of docs/model.md §2.2–2.3 and §3.

mod common;

use common::*;
use glam::DVec3;
use rheodem::contact::Reversible;
use rheodem::particles::Motion;
use std::f64::consts::PI;

/// Result of one head-on collision.
struct Outcome {
    restitution: f64,
    contact_time: f64,
}

/// Runs a head-on collision of spheres of radii `a1`, `a2` (the second fixed if `wall`) at
/// relative speed `v0`, with time step `t_c / steps_per_contact`.
fn head_on(e: f64, a1: f64, a2: f64, wall: bool, steps_per_contact: f64) -> (Outcome, f64, f64) {
    let v0 = 0.05;
    let gap = 0.002 * (a1 + a2);
    let mut s1 = sphere(
        DVec3::new(-(a1 + gap / 2.0), 0.0, 0.0),
        DVec3::new(v0 / 2.0, 0.0, 0.0),
        a1,
    );
    let mut s2 = sphere(
        DVec3::new(a2 + gap / 2.0, 0.0, 0.0),
        DVec3::new(-v0 / 2.0, 0.0, 0.0),
        a2,
    );
    if wall {
        s1.velocity.x = v0;
        s2.velocity = DVec3::ZERO;
        s2.motion = Motion::Fixed;
    }
    let law = normal_law(e);
    let m1 = RHO * 4.0 / 3.0 * PI * a1.powi(3);
    let m2 = RHO * 4.0 / 3.0 * PI * a2.powi(3);
    let m_ij = if wall { m1 } else { m1 * m2 / (m1 + m2) };
    let t_c = law.normal.contact_time(m_ij, 5.0e-4).expect("underdamped");
    let dt = t_c / steps_per_contact;
    let mut sim = simulation(&[s1, s2], law, open_box(0.1), vec![], DVec3::ZERO, dt);

    let overlap = |sim: &rheodem::Simulation| {
        let (i, j) = (slot(sim, 0), slot(sim, 1));
        a1 + a2 - (sim.particles.position[i] - sim.particles.position[j]).length()
    };
    let rel_v = |sim: &rheodem::Simulation| {
        let (i, j) = (slot(sim, 0), slot(sim, 1));
        (sim.particles.velocity[i] - sim.particles.velocity[j]).x
    };
    let v_before = rel_v(&sim);
    let mut prev = overlap(&sim);
    let mut t_start = None;
    let mut t_end = None;
    for _ in 0..(20.0 * steps_per_contact) as usize {
        sim.step(false).expect("step");
        let now = overlap(&sim);
        let t_prev = sim.time - dt;
        if prev <= 0.0 && now > 0.0 && t_start.is_none() {
            t_start = Some(t_prev + dt * (-prev) / (now - prev));
        }
        if prev > 0.0 && now <= 0.0 && t_start.is_some() {
            t_end = Some(t_prev + dt * prev / (prev - now));
            break;
        }
        prev = now;
    }
    // A few more steps to leave the contact entirely (forces are zero once δ ≤ 0).
    sim.step(false).expect("step");
    let outcome = Outcome {
        restitution: -rel_v(&sim) / v_before,
        contact_time: t_end.expect("contact ended") - t_start.expect("contact started"),
    };
    (
        outcome,
        t_c,
        law.normal.restitution(m_ij).expect("underdamped"),
    )
}

fn check(e: f64, a1: f64, a2: f64, wall: bool, steps: f64, tol: f64) {
    let (got, t_c, e_exact) = head_on(e, a1, a2, wall, steps);
    assert!((e_exact - e).abs() < 1e-12);
    let de = (got.restitution - e).abs() / e;
    let dt = (got.contact_time - t_c).abs() / t_c;
    assert!(
        de < tol && dt < tol,
        "e={e} a=({a1},{a2}) wall={wall} t_c/{steps}: restitution {} (err {:.3}%), contact time {} vs {} (err {:.3}%)",
        got.restitution,
        100.0 * de,
        got.contact_time,
        t_c,
        100.0 * dt
    );
}

const A: f64 = 1.1e-3;

#[test]
fn restitution_and_contact_time_fine_step() {
    for &e in &[0.5, 0.8, 0.95] {
        check(e, A, A, false, 200.0, 0.005);
        check(e, A, 0.5 * A, false, 200.0, 0.005);
        check(e, A, 1.7 * A, true, 200.0, 0.005);
    }
}

#[test]
fn restitution_and_contact_time_default_step() {
    for &e in &[0.5, 0.8, 0.95] {
        check(e, A, A, false, 50.0, 0.03);
        check(e, A, 0.5 * A, false, 50.0, 0.03);
        check(e, A, 1.7 * A, true, 50.0, 0.03);
    }
}

/// Contact history is keyed by particle identity: rebuilding the neighbour list (which
/// re-sorts the particles) in the middle of a frictional contact changes nothing.
#[test]
fn history_survives_rebuilds_and_resorting() {
    let a = A;
    let make = || {
        let s1 = sphere(DVec3::new(0.0, 0.0, 0.0), DVec3::new(0.0, 0.0, 0.0), a);
        // Just touching, held together by adhesion, sliding and rolling sideways: a lasting
        // frictional contact whose springs carry history.
        let mut s2 = sphere(
            DVec3::new(1.8 * a - 1e-6, 0.0, 0.0),
            DVec3::new(0.0, 2e-4, 0.0),
            0.8 * a,
        );
        s2.angular_velocity = DVec3::new(0.0, 0.0, 3.0);
        let mut law = frictional_law(0.8, 0.5);
        law.adhesion = rheodem::contact::Adhesion::Reversible(Reversible {
            max_force: 1e-4,
            stiffness: 100.0,
        });
        let t_c = law.normal.contact_time(1e-6, 5.0e-4).expect("underdamped");
        simulation(
            &[s2, s1],
            law,
            open_box(0.1),
            vec![],
            DVec3::ZERO,
            t_c / 200.0,
        )
    };
    let mut quiet = make();
    let mut rebuilt = make();
    for k in 0..400 {
        quiet.step(k == 399).expect("step");
        rebuilt.step(false).expect("step");
        if k % 7 == 0 {
            rebuilt.rebuild_neighbors().expect("rebuild");
        }
    }
    assert!(rebuilt.neighbors.builds > 50);
    assert_eq!(
        quiet.observables().contacts,
        1,
        "the pair must stay in contact"
    );
    for id in 0..2 {
        let (i, j) = (slot(&quiet, id), slot(&rebuilt, id));
        assert_eq!(quiet.particles.position[i], rebuilt.particles.position[j]);
        assert_eq!(
            quiet.particles.angular_velocity[i],
            rebuilt.particles.angular_velocity[j]
        );
    }
}
