//! Hertz–Mindlin contacts against their closed forms (docs/model.md §2.10): the duration
//! of a Hertzian collision, the restitution of Tsuji's dashpot at every impact speed,
//! Mindlin's tangential force at fixed and shrinking overlap, energy conservation without
//! damping, and the scenario keys that mix two materials per pair.

mod common;

use common::*;
use glam::DVec3;
use rheodem::contact::normal::hertz::{HERTZ_TIME_FACTOR, HertzNormal, Material};
use rheodem::contact::spring::Mindlin;
use rheodem::contact::{Adhesion, ContactHistory, ContactLaw, NormalModel, PairKinematics, Spring};
use rheodem::scenario::Scenario;
use std::time::Instant;

/// A soft "glass": with `ρ = 2000 kg/m³` and `a = 1.1 mm`, a collision at 0.1 m/s
/// overlaps by about 1 % of the radius.
const SOFT: Material = Material {
    youngs_modulus: 2.0e7,
    poisson_ratio: 0.3,
};

/// Frictionless Hertz with restitution `e`.
fn hertz_law(e: f64) -> ContactLaw {
    ContactLaw {
        normal: HertzNormal::between(&SOFT, &SOFT, e, 1.0).into(),
        tangential: Spring::NONE,
        rolling: Spring::NONE,
        torsion: Spring::NONE,
        adhesion: Adhesion::None,
    }
}

/// A head-on collision of two spheres of radius `A_REF` at relative speed `v0` with `dt`
/// a `1/steps` of the undamped collision time at that speed: returns
/// `(restitution, contact time, undamped closed-form contact time)`.
fn collide(e: f64, v0: f64, steps: f64) -> (f64, f64, f64) {
    let law = hertz_law(e);
    let hertz = *law.normal.hertz().expect("hertz");
    let (m_ij, r_ij) = (0.5 * mass(A_REF), 0.5 * A_REF);
    let e_star = hertz.effective_modulus;
    let t_c = HERTZ_TIME_FACTOR * (m_ij * m_ij / (r_ij * e_star * e_star * v0)).powf(0.2);
    let dt = t_c / steps;
    // Start 2 steps apart, so that the contact starts within the run's first steps.
    let gap = 2.0 * v0 * dt;
    let s1 = sphere(
        DVec3::new(-(A_REF + gap / 2.0), 0.0, 0.0),
        DVec3::X * (v0 / 2.0),
        A_REF,
    );
    let s2 = sphere(
        DVec3::new(A_REF + gap / 2.0, 0.0, 0.0),
        DVec3::X * (-v0 / 2.0),
        A_REF,
    );
    let mut sim = simulation(&[s1, s2], law, open_box(0.1), vec![], DVec3::ZERO, dt);
    let overlap = |sim: &rheodem::Simulation| {
        let (i, j) = (slot(sim, 0), slot(sim, 1));
        2.0 * A_REF - (sim.particles.position[i] - sim.particles.position[j]).length()
    };
    let rel_v = |sim: &rheodem::Simulation| {
        let (i, j) = (slot(sim, 0), slot(sim, 1));
        (sim.particles.velocity[i] - sim.particles.velocity[j]).x
    };
    let (mut prev, mut start, mut end) = (overlap(&sim), None, None);
    for _ in 0..(10.0 * steps) as usize {
        sim.step(false).expect("step");
        let now = overlap(&sim);
        let t_prev = sim.time - dt;
        if prev <= 0.0 && now > 0.0 && start.is_none() {
            start = Some(t_prev + dt * (-prev) / (now - prev));
        }
        if prev > 0.0 && now <= 0.0 && start.is_some() {
            end = Some(t_prev + dt * prev / (prev - now));
            break;
        }
        prev = now;
    }
    sim.step(false).expect("step");
    (
        -rel_v(&sim) / v0,
        end.expect("contact ended") - start.expect("contact started"),
        t_c,
    )
}

/// An undamped Hertzian collision lasts `t_c = 2.868 (m*²/(R* E*² v))^{1/5}` and restitutes
/// fully, from 1 mm/s to 10 m/s (four decades of speed, a factor 6 in `t_c`).
///
/// At `t_c/400` the Verlet contact time is within 2·10⁻⁴ of the closed form and the
/// restitution within 10⁻⁵ of 1 (measured: 3·10⁻⁵ and 2·10⁻⁷ at every speed); the
/// bounds leave a factor 5 over the measured values for a changed rounding.
#[test]
fn an_undamped_hertzian_collision_lasts_the_closed_form_time() {
    for v0 in [1.0e-3, 1.0e-2, 0.1, 1.0, 10.0] {
        let (e, t, t_c) = collide(1.0, v0, 400.0);
        eprintln!("v = {v0} m/s: t_c = {t:.6e} s (closed form {t_c:.6e}), e = {e:.8}");
        assert!(
            (t / t_c - 1.0).abs() < 2e-4,
            "v = {v0}: t = {t}, closed form {t_c}"
        );
        assert!((e - 1.0).abs() < 1e-5, "v = {v0}: e = {e}");
    }
}

/// Tsuji's dashpot `η = α(e) √(2 m* (4/3) E* a)` gives a restitution independent of the
/// impact speed: over four decades of speed the measured `e` varies by less than 10⁻⁴.
///
/// Against the target `e`, the restitution misses by the error of Tsuji's polynomial fit
/// `α(e)`: integrating the dimensionless oscillator with RK4 to convergence gives
/// +0.11 % at 0.95, +0.02 % at 0.9, −0.01 % at 0.7 and −0.02 % at 0.5 and 0.3, and the
/// engine's Verlet collisions at `t_c/400` the same to 10⁻⁴. Bound: 0.2 %.
/// (With `m*` in place of `2 m*`, as LAMMPS's `damping tsuji` writes it, the same fit
/// restitutes 0.965, 0.928, 0.778 and 0.616.)
#[test]
fn tsuji_damping_restitutes_the_same_at_every_speed() {
    for target in [0.95, 0.9, 0.7, 0.5, 0.3] {
        let measured: Vec<f64> = [1.0e-3, 1.0e-2, 0.1, 1.0, 10.0]
            .iter()
            .map(|&v0| collide(target, v0, 400.0).0)
            .collect();
        let (lo, hi) = measured
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &e| {
                (lo.min(e), hi.max(e))
            });
        eprintln!(
            "e = {target}: measured {lo:.5}–{hi:.5} ({:+.2} % of the target)",
            100.0 * (0.5 * (lo + hi) / target - 1.0)
        );
        assert!(
            hi - lo < 1e-4,
            "e = {target}: spread {lo}–{hi} over the speeds"
        );
        assert!(
            ((lo + hi) / 2.0 / target - 1.0).abs() < 2e-3,
            "e = {target}: measured {lo}–{hi}"
        );
    }
}

/// Hertz with Mindlin's spring, `μ = 0.5`.
fn hertz_mindlin(mu: f64) -> (ContactLaw, HertzNormal) {
    let hertz = HertzNormal::between(&SOFT, &SOFT, 1.0, 1.0);
    let law = ContactLaw {
        normal: hertz.into(),
        tangential: Mindlin {
            effective_shear_modulus: hertz.effective_shear_modulus,
            dashpot: 0.0,
            mu_static: mu,
            mu_dynamic: mu,
        }
        .into(),
        rolling: Spring::NONE,
        torsion: Spring::NONE,
        adhesion: Adhesion::None,
    };
    (law, hertz)
}

/// Two spheres of radius `A_REF` at overlap `δ`, `i` sliding past `j` at `v` along x.
fn sliding_pair(overlap: f64, v: f64) -> PairKinematics {
    PairKinematics {
        normal: DVec3::Z,
        overlap,
        radius_i: A_REF,
        radius_j: A_REF,
        velocity: DVec3::X * v,
        omega_i: DVec3::ZERO,
        omega_j: DVec3::ZERO,
        reduced_mass: 0.5 * mass(A_REF),
    }
}

/// Mindlin's tangential force at fixed overlap is `min(8 G* a |ξ|, μ f_n)` with `ξ` the
/// sliding distance; when the overlap then shrinks at rest, the displacement is rescaled by
/// `a/a_prev`, so the force falls as `a²`: `8 G* a₂ (a₂/a₁) ξ₁`; sliding on, it slips at
/// `μ f_n(δ₂)`. Exact to rounding (10⁻¹²).
#[test]
fn mindlin_follows_its_closed_form_and_rescales_as_the_contact_shrinks() {
    let (law, hertz) = hertz_mindlin(0.5);
    let g = hertz.effective_shear_modulus;
    let (r_ij, d1, v, dt) = (0.5 * A_REF, 1.0e-5, 1.0e-2, 1.0e-6);
    let mut h = ContactHistory::default();
    let a1 = (r_ij * d1).sqrt();
    let f_n1 = hertz.elastic_force(d1, r_ij);
    let mut xi = 0.0;
    let mut slipped_at = None;
    for step in 1..=2000 {
        let f = law.evaluate(&sliding_pair(d1, v), &mut h, dt);
        xi += v * dt;
        let expected = (8.0 * g * a1 * xi).min(0.5 * f_n1);
        assert!(
            (-f.force.x - expected).abs() < 1e-12 * f_n1,
            "step {step}: f_t = {}, closed form {expected}",
            -f.force.x
        );
        if f.sliding && slipped_at.is_none() {
            slipped_at = Some(step);
        }
    }
    // The spring reached the limit at ξ = μ f_n / (8 G* a).
    let xi_limit = 0.5 * f_n1 / (8.0 * g * a1);
    let first = slipped_at.expect("the contact slides") as f64;
    assert!(
        (first - 1.0 - xi_limit / (v * dt)).abs() <= 1.0,
        "slipped at step {first}"
    );

    // Back below the limit at half the stretch: undo half of it, then unload at rest.
    let mut h = ContactHistory::default();
    for _ in 0..300 {
        law.evaluate(&sliding_pair(d1, v), &mut h, dt);
    }
    let xi1 = 300.0 * v * dt;
    assert!(8.0 * g * a1 * xi1 < 0.5 * f_n1, "still below the limit");
    let d2 = 0.64 * d1; // a₂ = 0.8 a₁
    let a2 = (r_ij * d2).sqrt();
    let f = law.evaluate(&sliding_pair(d2, 0.0), &mut h, dt);
    let expected = 8.0 * g * a2 * (a2 / a1) * xi1;
    assert!(
        (-f.force.x / expected - 1.0).abs() < 1e-12,
        "unloaded: f_t = {}, closed form {expected}",
        -f.force.x
    );
    assert!((h.sliding_state - a2).abs() < 1e-15 * a2, "the state is a₂");
    // Reloading to δ₁ keeps the rescaled displacement: the force grows only as a.
    let f = law.evaluate(&sliding_pair(d1, 0.0), &mut h, dt);
    let expected = 8.0 * g * a1 * (a2 / a1) * xi1;
    assert!((-f.force.x / expected - 1.0).abs() < 1e-12, "reloaded");
    // Sliding on at δ₂ ends at μ f_n(δ₂).
    let f_n2 = hertz.elastic_force(d2, r_ij);
    let mut last = 0.0;
    for _ in 0..3000 {
        last = -law.evaluate(&sliding_pair(d2, v), &mut h, dt).force.x;
    }
    assert!(
        (last / (0.5 * f_n2) - 1.0).abs() < 1e-12,
        "slides at {last}, μ f_n = {}",
        0.5 * f_n2
    );
}

/// A contact that opens forgets its Mindlin state, and one that closes again starts from
/// zero: no stale `a_prev` rescales a new contact.
#[test]
fn an_opened_contact_forgets_its_mindlin_state() {
    let (law, _) = hertz_mindlin(0.5);
    let mut h = ContactHistory::default();
    for _ in 0..10 {
        law.interact(&sliding_pair(1.0e-5, 1.0e-3), &mut h, 1.0e-6);
    }
    assert!(h.sliding_state > 0.0 && h.tangential.length() > 0.0);
    assert!(
        law.interact(&sliding_pair(-1.0e-6, 1.0e-3), &mut h, 1.0e-6)
            .is_none()
    );
    assert_eq!(h, ContactHistory::default());
}

/// Total energy of an undamped, frictionless Hertzian packing where contacts form and
/// break all the time, as in the linear law's test (conservation.rs): 256 spheres at
/// `φ = 0.6`, random velocities σ = 0.1 m/s, 4·10⁴ steps at `t_c(1 m/s)/50` (about
/// `t_c(0.1 m/s)/80`), energy sampled every 100 steps.
///
/// Hertz's force and stiffness both start at zero when a contact forms, so a contact
/// event has no kink of the force as the linear law's has: measured mean `Z` = 0.62,
/// drift −1.1·10⁻⁵ of the mean energy, RMS fluctuation 8·10⁻⁶. Criterion: 10⁻⁴, as for
/// the linear law's compressed packing.
#[test]
fn an_undamped_hertzian_packing_conserves_energy() {
    let law = hertz_law(1.0);
    let (spheres, domain) = fcc_packing(4, 0.6, 1.2, 0.1, 0.0, 11);
    let a_min = spheres
        .iter()
        .map(|s| s.radius)
        .fold(f64::INFINITY, f64::min);
    let dt = law
        .normal
        .contact_time(0.5 * mass(a_min), 0.5 * a_min)
        .expect("elastic")
        / 50.0;
    let mut sim = simulation(&spheres, law, domain, vec![], DVec3::ZERO, dt);
    let clock = Instant::now();
    let (drift, rms, z) = energy_drift(&mut sim, 40_000, 100);
    eprintln!(
        "hertz energy: {:.1} s, mean Z = {z:.2}, relative drift {drift:.3e}, RMS {rms:.3e}",
        clock.elapsed().as_secs_f64()
    );
    assert!(z > 0.3, "too few contacts: Z = {z}");
    assert!(
        drift.abs() < 1e-4,
        "energy drift {drift:.3e} of the mean energy"
    );
}

/// A scenario's hertz law takes each species' `youngs_modulus`, `poisson_ratio` and
/// `restitution` where it gives none and mixes them per pair:
/// `1/E* = Σ (1 − ν²)/E`, `1/G* = Σ 2(2 − ν)(1 + ν)/E`, `e = √(e_i e_j)`; Mindlin's spring
/// takes `G*` of its pair.
#[test]
fn a_scenario_mixes_two_materials_per_pair() {
    let toml = |normal: &str, friction: &str| {
        format!(
            r#"
            [domain]
            size = [0.02, 0.02, 0.02]
            periodic = [true, true, true]
            [[species]]
            name = "glass"
            density = 2500.0
            youngs_modulus = 6.3e10
            poisson_ratio = 0.22
            restitution = 0.9
            [[species]]
            name = "steel"
            density = 7800.0
            youngs_modulus = 2.0e11
            poisson_ratio = 0.3
            restitution = 0.6
            [[contact]]
            normal = {normal}
            friction = {friction}
            [run]
            duration = 0.001
            "#
        )
    };
    let scenario = |normal: &str, friction: &str| -> Result<_, String> {
        let s: Scenario = toml::from_str(&toml(normal, friction)).map_err(|e| e.to_string())?;
        rheodem::scenario::contact_table(&s).map_err(|e| e.to_string())
    };
    let table = scenario(
        r#"{ law = "hertz", impact_speed = 0.5 }"#,
        r#"{ law = "mindlin", mu = 0.4 }"#,
    )
    .expect("valid");
    let glass = Material {
        youngs_modulus: 6.3e10,
        poisson_ratio: 0.22,
    };
    let steel = Material {
        youngs_modulus: 2.0e11,
        poisson_ratio: 0.3,
    };
    let mixed = table.get(0, 1);
    let hertz = mixed.normal.hertz().expect("hertz");
    let e_star = 1.0 / ((1.0 - 0.22f64.powi(2)) / 6.3e10 + (1.0 - 0.09) / 2.0e11);
    let g_star = 1.0 / (2.0 * 1.78 * 1.22 / 6.3e10 + 2.0 * 1.7 * 1.3 / 2.0e11);
    assert!((hertz.effective_modulus / e_star - 1.0).abs() < 1e-14);
    assert!((hertz.effective_shear_modulus / g_star - 1.0).abs() < 1e-14);
    assert!((hertz.restitution - (0.9f64 * 0.6).sqrt()).abs() < 1e-15);
    assert_eq!(hertz.impact_speed, 0.5);
    assert_eq!(
        *hertz,
        HertzNormal::between(&glass, &steel, (0.9f64 * 0.6).sqrt(), 0.5)
    );
    match mixed.tangential {
        Spring::Mindlin(m) => assert_eq!(m.effective_shear_modulus, hertz.effective_shear_modulus),
        other => panic!("not mindlin: {other:?}"),
    }
    let like = table.get(1, 1).normal.hertz().expect("hertz");
    assert_eq!(*like, HertzNormal::between(&steel, &steel, 0.6, 0.5));
    assert_eq!(like.restitution(1.0), Some(0.6));

    // The law's own keys take precedence over the species'.
    let own = scenario(
        r#"{ law = "hertz", restitution = 0.8 }"#,
        r#"{ mu = 0.4, stiffness = 1e3 }"#,
    )
    .expect("valid");
    assert_eq!(
        own.get(0, 1).normal.hertz().expect("hertz").restitution,
        0.8
    );

    // Errors name the key and what is allowed.
    let e = scenario(
        r#"{ law = "hertz" }"#,
        r#"{ mu = 0.4, stiffness_ratio = 0.3 }"#,
    )
    .expect_err("no linear stiffness to take a ratio of");
    assert!(e.contains("contact[0].friction.stiffness_ratio"), "{e}");
    let e = scenario(
        r#"{ law = "linear", stiffness = 100.0 }"#,
        r#"{ law = "mindlin", mu = 0.4 }"#,
    )
    .expect_err("mindlin needs hertz");
    assert!(e.contains("friction.law") && e.contains("hertz"), "{e}");
    let e = scenario(
        r#"{ law = "hertz", poisson_ratio = 0.7 }"#,
        r#"{ law = "mindlin", mu = 0.4 }"#,
    )
    .expect_err("ν out of range");
    assert!(
        e.contains("contact[0].normal.poisson_ratio") && e.contains("(-1, 0.5]"),
        "{e}"
    );
    let e = scenario(
        r#"{ law = "hertz" }"#,
        r#"{ law = "mindlin", mu = 0.4, stiffness = 5.0 }"#,
    )
    .expect_err("mindlin takes no stiffness");
    assert!(e.contains("friction.stiffness"), "{e}");
}
