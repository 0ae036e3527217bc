//! Observables of a small hand-built configuration, against values counted by hand.

mod common;

use common::*;
use glam::DVec3;

/// A chain of three touching spheres and one isolated sphere: 2 contacts among 4 particles.
#[test]
fn coordination_with_and_without_rattlers() {
    let a = 1.0e-3;
    let overlap = 1.0e-6;
    let spheres = [
        sphere(DVec3::new(0.0, 0.0, 0.0), DVec3::ZERO, a),
        sphere(DVec3::new(2.0 * a - overlap, 0.0, 0.0), DVec3::ZERO, a),
        sphere(
            DVec3::new(4.0 * a - 2.0 * overlap, 0.0, 0.0),
            DVec3::ZERO,
            a,
        ),
        sphere(DVec3::new(0.0, 5.0 * a, 0.0), DVec3::ZERO, a),
    ];
    let law = normal_law(0.8);
    let t_c = law.normal.contact_time(1e-6, 5.0e-4).expect("underdamped");
    let mut sim = simulation(
        &spheres,
        law,
        open_box(0.05),
        vec![],
        DVec3::ZERO,
        t_c / 50.0,
    );
    sim.step(true).expect("step");
    let o = sim.observables();
    assert_eq!(o.contacts, 2);
    // Z = 2 N_c / N = 4 / 4; without rattlers only the middle sphere (2 contacts) remains.
    assert_eq!(o.coordination, 1.0);
    assert_eq!(o.coordination_without_rattlers, 2.0);
    // Two compressed contacts along x: σ_xx > 0 (compression positive), no shear.
    assert!(o.stress[0][0] > 0.0);
    assert!(o.stress[0][1].abs() < 1e-12 * o.stress[0][0]);
    // Elastic energy ½ k_n δ² per contact (the overlap barely changed in one step).
    let expected = 2.0 * 0.5 * KN * overlap * overlap;
    assert!(
        (o.elastic_energy / expected - 1.0).abs() < 1e-2,
        "{} vs {expected}",
        o.elastic_energy
    );
}
