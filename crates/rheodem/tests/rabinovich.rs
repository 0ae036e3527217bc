//! Rabinovich's liquid bridge through the pair kernel (docs/model.md §2.11): a
//! loading–unloading cycle's adhesive work against the integral of the paper's closed
//! form, no attraction before the first contact, and the contact value beside Willett's.

mod common;

use common::*;
use rheodem::contact::adhesion::{LiquidBridge, Rabinovich};
use rheodem::contact::curve::drive;
use rheodem::contact::{Adhesion, ContactLaw};
use std::f64::consts::PI;

const GAMMA: f64 = 0.02;
const VOLUME: f64 = 75e-12;

fn theta() -> f64 {
    20f64.to_radians()
}

/// Undamped frictionless linear spring (`k_n = KN`) with Rabinovich's bridge.
fn law() -> ContactLaw {
    let mut law = normal_law(1.0);
    law.adhesion = Adhesion::Rabinovich(Rabinovich {
        surface_tension: GAMMA,
        contact_angle: theta(),
        volume: VOLUME,
    });
    law
}

/// Rabinovich et al. 2005's force between spheres of pair radius `r` at separation `s > 0`,
/// as the paper writes it (immersion height, half-filling angle, two terms).
fn paper_force(s: f64, r: f64) -> f64 {
    let root = (1.0 + 2.0 * VOLUME / (PI * r * s * s)).sqrt();
    let d_sp = s / 2.0 * (root - 1.0);
    let alpha = (s / r * (root - 1.0)).sqrt();
    -2.0 * PI * r * GAMMA * theta().cos() / (1.0 + s / (2.0 * d_sp))
        - 2.0 * PI * GAMMA * r * alpha.sin() * (theta() + alpha).sin()
}

/// A contact loaded to `δ_max`, unloaded and pulled apart past rupture: the work
/// `∮ f dδ` of the undamped cycle is the adhesive energy `∫₀^{S_c} |f_a| dS` (the spring
/// and the constant contact attraction return what they took). Integrated by the
/// trapezoidal rule over 4·10⁴ points of the kernel's path, against Simpson's rule on the
/// paper's form over 2·10⁴ intervals (from `S = 10⁻⁹ S_c`, where the paper's form is
/// still finite): agreement to 10⁻⁶ (the trapezoidal error, measured 6·10⁻⁸).
#[test]
fn a_cycle_dissipates_the_integral_of_the_papers_force() {
    let law = law();
    let (a_i, a_j) = (A_REF, 0.7 * A_REF);
    let r = 2.0 * a_i * a_j / (a_i + a_j);
    let s_c = law.adhesion.range();
    assert!((s_c - (1.0 + theta() / 2.0) * VOLUME.cbrt()).abs() < 1e-18);
    let d_max = 2.0 * law.adhesion.max_force(a_i, a_j) / KN;
    let n = 20_000;
    // Approach from 1.2 S_c apart to δ_max through δ = 0 exactly, then apart to S_c
    // exactly, then beyond.
    let mut path: Vec<f64> = (0..=n)
        .map(|k| -1.2 * s_c + (1.2 * s_c + d_max) * k as f64 / n as f64)
        .collect();
    let contact = path
        .iter()
        .position(|&d| d >= 0.0)
        .expect("the approach reaches contact");
    path[contact] = 0.0;
    path.extend((1..=n).map(|k| d_max - (d_max + s_c) * k as f64 / n as f64));
    path.push(-1.5 * s_c);
    let curve = drive(&law, a_i, a_j, &path);
    // No attraction before the first contact, a bridge from it on, none after rupture.
    assert!(
        curve[..contact]
            .iter()
            .all(|p| p.normal_force == 0.0 && !p.bridge)
    );
    assert!(curve[contact].bridge);
    assert!(
        curve
            .last()
            .is_some_and(|p| !p.bridge && p.normal_force == 0.0)
    );
    let mut work = 0.0;
    for w in curve.windows(2) {
        // Across a change of the bridge the force is that of the side without one (zero).
        let (f0, f1) = if w[0].bridge == w[1].bridge {
            (w[0].normal_force, w[1].normal_force)
        } else {
            (0.0, 0.0)
        };
        work += 0.5 * (f0 + f1) * (w[1].overlap - w[0].overlap);
    }
    let m = 20_000;
    let (lo, h) = (1e-9 * s_c, (s_c - 1e-9 * s_c) / m as f64);
    let mut sum = -paper_force(lo, r) - paper_force(s_c, r);
    for k in 1..m {
        sum += -paper_force(lo + k as f64 * h, r) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    let energy = sum * h / 3.0;
    eprintln!("cycle work {work:.9e} J, ∫|f_a| dS = {energy:.9e} J");
    assert!((work / energy - 1.0).abs() < 1e-6, "{work} vs {energy}");
    // The law's own separation energy is the same integral.
    // (Simpson's rule starts at 10⁻⁹ S_c and misses about 10⁻⁹ of the integral.)
    let own = -law.adhesion.separation_energy(0.0, a_i, a_j);
    assert!((own / energy - 1.0).abs() < 1e-8, "{own} vs {energy}");
}

/// At contact Rabinovich's force is Willett's `2π r γ cos θ` plus the filling-angle term
/// `2π r γ sin α₀ sin(θ + α₀)`, `α₀ = (2 V/(π r³))^{1/4}`: +31.7 % at 75 nl between
/// 2.2 mm grains, +11.9 % at 4.2 nl. Apart, both decay over the same rupture distance.
#[test]
fn at_contact_the_filling_angle_term_adds_to_willetts_force() {
    for (volume, excess) in [(75e-12, 0.317), (4.2e-12, 0.119)] {
        let rabinovich = Adhesion::Rabinovich(Rabinovich {
            surface_tension: GAMMA,
            contact_angle: theta(),
            volume,
        });
        let willett = Adhesion::LiquidBridge(LiquidBridge {
            surface_tension: GAMMA,
            contact_angle: theta(),
            volume,
        });
        let ratio = rabinovich.max_force(A_REF, A_REF) / willett.max_force(A_REF, A_REF);
        eprintln!("V = {volume:e} m³: Rabinovich/Willett at contact = {ratio:.4}");
        assert!((ratio - 1.0 - excess).abs() < 1e-3, "V = {volume}: {ratio}");
        assert_eq!(rabinovich.range(), willett.range());
    }
}
