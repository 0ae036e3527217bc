//! The stress tensor in full (PHYSICS §5), against a hand computation:
//!
//! `σ = (1/V) [ Σ_i m_i v'_i ⊗ v'_i + Σ_pairs f_ij ⊗ l_ij ]`, compression positive,
//! `f_ij` the total force on `i` (normal, tangential, adhesive), `l_ij = r_i − r_j` through
//! the nearest periodic image, `(row k, column l) = f_k l_l`, every interacting pair once,
//! including non-touching adhesive pairs.
//!
//! The configurations are built by hand; the expected forces come from the closed-form
//! contact law evaluated in this file (linear spring–dashpot normal force with the
//! restitution damping `γ_n = −2 ln e sqrt(m_ij k_n / (π² + ln² e))`, the first step of the
//! tangential spring `f_t = −(k_t dt + γ_t) v_t` capped at `μ f_rep`, reversible adhesion
//! `−f_max` in contact and `k_c S − f_max` apart), never from the library's helpers.
//!
//! The state is the one `Simulation::new` leaves: its force evaluation is the first, so
//! every contact history is zero and the tangential spring has been stretched once.

use glam::{DMat3, DVec3};
use rheodem::Simulation;
use rheodem::contact::Reversible;
use rheodem::contact::{
    Adhesion, ContactLaw, ContactTable, Damping, LinearNormal, Resistance, Spring,
};
use rheodem::domain::Domain;
use rheodem::forces::{ForceScratch, pair_forces};
use rheodem::measure::{ContactSums, kinetic_stress_sum};
use rheodem::neighbor::NeighborList;
use rheodem::particles::{Motion, Particles, Sphere};
use rheodem::team::Team;
use rheodem::walls::Wall;
use std::f64::consts::PI;

/// Density (kg/m³).
const RHO: f64 = 2000.0;
/// Normal stiffness (N/m) and restitution coefficient.
const KN: f64 = 100.0;
const E: f64 = 0.7;
/// `k_t / k_n = γ_t / γ_n`: the paper's `2/7`.
const RATIO_T: f64 = 2.0 / 7.0;
/// Coulomb coefficient (static = dynamic).
const MU: f64 = 0.4;
/// Reversible adhesion: `f_max` (N) and `k_c` (N/m); range `δ_a = f_max/k_c = 50 µm`.
const F_MAX: f64 = 5.0e-4;
const K_C: f64 = 10.0;
/// Time step (s): enters the first stretch of the tangential spring, `ξ = v_t dt`.
const DT: f64 = 2.0e-5;

/// The law of every pair in these tests, built from the constants above.
fn law(adhesive: bool) -> ContactLaw {
    let ln_e = E.ln();
    let per_sqrt_mass = -2.0 * ln_e * (KN / (PI * PI + ln_e * ln_e)).sqrt();
    let damping = Damping {
        per_sqrt_mass,
        ..Damping::NONE
    };
    ContactLaw {
        normal: LinearNormal {
            stiffness: KN,
            damping,
        }
        .into(),
        tangential: Resistance {
            stiffness: RATIO_T * KN,
            damping: damping.scaled(RATIO_T),
            mu_static: MU,
            mu_dynamic: MU,
        }
        .into(),
        rolling: Spring::NONE,
        torsion: Spring::NONE,
        adhesion: if adhesive {
            Adhesion::Reversible(Reversible {
                max_force: F_MAX,
                stiffness: K_C,
            })
        } else {
            Adhesion::None
        },
    }
}

/// A body as the closed form sees it: a free or prescribed sphere, or a planar wall.
#[derive(Clone, Copy, Debug)]
struct Body {
    r: DVec3,
    v: DVec3,
    w: DVec3,
    /// Radius (m); `∞` for a planar wall.
    a: f64,
    /// Mass (kg); `∞` for a prescribed particle or a wall.
    m: f64,
}

fn mass(a: f64) -> f64 {
    RHO * 4.0 / 3.0 * PI * a.powi(3)
}

/// What the closed form predicts for one pair.
#[derive(Clone, Copy, Debug, Default)]
struct Expected {
    /// Force on `i` (N).
    force: DVec3,
    /// Whether the pair interacts, touches, slides.
    interacts: bool,
    touching: bool,
    sliding: bool,
    /// Stored energy (J): springs plus the adhesive potential.
    energy: f64,
}

/// The first force evaluation of the pair `(i, j)` with branch vector `l = r_i − r_j`
/// (nearest image; for a planar wall `n · gap`) and unit normal `n = l/|l|`, overlap `δ`.
fn closed_form(i: &Body, j: &Body, l: DVec3, overlap: f64, adhesive: bool) -> Expected {
    let n = l.normalize();
    let delta_a = F_MAX / K_C;
    if overlap < 0.0 {
        let s = -overlap;
        if adhesive && s < delta_a {
            return Expected {
                force: n * (K_C * s - F_MAX),
                interacts: true,
                // ∫_s^{δ_a} (k_c S − f_max) dS = −½ k_c (δ_a − s)².
                energy: -0.5 * K_C * (delta_a - s).powi(2),
                ..Expected::default()
            };
        }
        return Expected::default();
    }
    // Reduced mass: a prescribed partner or a wall is infinitely heavy.
    let m_ij = if j.m.is_finite() {
        i.m * j.m / (i.m + j.m)
    } else {
        i.m
    };
    let ln_e = E.ln();
    let gamma_n = -2.0 * ln_e * (m_ij * KN / (PI * PI + ln_e * ln_e)).sqrt();
    let gamma_t = RATIO_T * gamma_n;
    let k_t = RATIO_T * KN;
    let v_rel = i.v - j.v;
    let overlap_rate = -v_rel.dot(n);
    let f_rep = KN * overlap + gamma_n * overlap_rate;
    // Contact point in the middle of the overlap: lever arms a − δ/2 (a wall has no spin).
    let spin = if j.a.is_finite() {
        (i.a - 0.5 * overlap) * i.w + (j.a - 0.5 * overlap) * j.w
    } else {
        (i.a - 0.5 * overlap) * i.w
    };
    let v_c = v_rel - spin.cross(n);
    let v_t = v_c - n * n.dot(v_c);
    let trial = -(k_t * DT + gamma_t) * v_t;
    let limit = MU * f_rep.abs();
    let (f_t, xi, sliding) = if trial.length() > limit {
        let f = trial * (limit / trial.length());
        (f, -(f + gamma_t * v_t) / k_t, true)
    } else {
        (trial, v_t * DT, false)
    };
    let f_adh = if adhesive { -F_MAX } else { 0.0 };
    let adhesive_energy = if adhesive {
        -0.5 * K_C * delta_a * delta_a - F_MAX * overlap
    } else {
        0.0
    };
    Expected {
        force: n * (f_rep + f_adh) + f_t,
        interacts: true,
        touching: overlap > 0.0,
        sliding,
        energy: 0.5 * KN * overlap * overlap + 0.5 * k_t * xi.length_squared() + adhesive_energy,
    }
}

/// `a ⊗ b`, entry `(k, l) = a_k b_l`, written out (row-major).
fn outer(a: DVec3, b: DVec3) -> [[f64; 3]; 3] {
    let (a, b) = (a.to_array(), b.to_array());
    std::array::from_fn(|k| std::array::from_fn(|l| a[k] * b[l]))
}

fn add(s: &mut [[f64; 3]; 3], t: [[f64; 3]; 3], scale: f64) {
    for k in 0..3 {
        for l in 0..3 {
            s[k][l] += scale * t[k][l];
        }
    }
}

fn rows(m: DMat3) -> [[f64; 3]; 3] {
    std::array::from_fn(|k| std::array::from_fn(|l| m.col(l)[k]))
}

/// Largest entry difference relative to the largest entry of `want`.
fn rel_diff(got: &[[f64; 3]; 3], want: &[[f64; 3]; 3]) -> f64 {
    let scale = want.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    let diff = got
        .iter()
        .flatten()
        .zip(want.iter().flatten())
        .fold(0.0f64, |m, (g, w)| m.max((g - w).abs()));
    diff / scale
}

/// The contact sums of one measuring force evaluation over a fresh neighbour list (skin
/// 0.2 mm, interaction `range` in m).
fn measured_pairs(
    particles: &mut Particles,
    domain: &Domain,
    law: ContactLaw,
    range: f64,
) -> ContactSums {
    let team = Team::new(rayon::current_num_threads());
    let mut list = NeighborList::new(0.2e-3, range);
    list.build(particles, domain, &team, range).expect("list");
    pair_forces::<ContactSums>(
        particles,
        &mut list,
        &ContactTable::uniform(1, law),
        &domain.image_transforms(),
        None,
        DT,
        &mut ForceScratch::default(),
        &team,
    )
}

fn sphere(r: DVec3, v: DVec3, w: DVec3, a: f64, motion: Motion) -> Sphere {
    Sphere {
        position: r,
        velocity: v,
        angular_velocity: w,
        radius: a,
        species: 0,
        motion,
    }
}

/// Nearest image of `d` through the periodic axes of a box of edges `l`.
fn nearest_image(mut d: DVec3, l: DVec3, periodic: [bool; 3]) -> DVec3 {
    for k in 0..3 {
        if periodic[k] {
            d[k] -= l[k] * (d[k] / l[k]).round();
        }
    }
    d
}

/// Seven free spheres in a triply periodic box with `lo ≠ 0`: a touching pair inside the
/// box (A–B, oblique normal, every velocity and spin non-zero), a touching pair across the
/// `x` boundary (C–D, sliding: its tangential trial force exceeds `μ f_rep`), an adhesive
/// pair apart across the `y` *and* `z` boundaries (E–F, at `S = 0.4 δ_a`), and a lone moving
/// sphere G. The reported `σ`, its kinetic part (`kinetic_stress_sum / V`) and its contact
/// part (the `ContactSums` of `pair_forces`) agree entry by entry with the hand sums over
/// all pairs within range through the nearest image, to `10⁻¹²` of the largest entry: both
/// sides add the same few products in a different order, so only rounding (~10⁻¹⁶) may
/// differ. The counts (2 contacts, 1 sliding, 1 attracting pair apart) and the elastic
/// energy (springs plus adhesive potential) are checked too.
///
/// Velocities are chosen so that the kinetic part is of the same order as the contact part
/// (neither hides the other), and the tangential forces make the contact part
/// asymmetric, so that a transposed `f ⊗ l` would fail.
#[test]
fn full_tensor_of_a_hand_built_periodic_configuration() {
    let lo = DVec3::new(-2.0e-3, 1.0e-3, 0.5e-3);
    let size = DVec3::splat(12.0e-3);
    let periodic = [true; 3];
    let domain = Domain::new(lo, lo + size, periodic);
    let delta_a = F_MAX / K_C;

    let u1 = DVec3::new(1.0, 0.4, -0.3).normalize();
    let u2 = DVec3::new(1.0, 0.2, 0.1).normalize();
    let u3 = DVec3::new(0.1, 1.0, 0.8).normalize();
    let (a_a, a_b, a_c, a_d, a_e, a_f, a_g) =
        (1.0e-3, 0.8e-3, 1.1e-3, 0.9e-3, 1.0e-3, 0.75e-3, 1.2e-3);
    let r_a = lo + DVec3::new(4.0e-3, 6.0e-3, 6.0e-3);
    let r_b = r_a - u1 * (a_a + a_b - 3.0e-5);
    let r_c = lo + DVec3::new(0.4e-3, 2.5e-3, 9.0e-3);
    // D's image one box to the left (−L_x) touches C.
    let r_d = r_c - u2 * (a_c + a_d - 2.0e-5) + DVec3::new(size.x, 0.0, 0.0);
    let r_e = lo + DVec3::new(8.0e-3, 0.3e-3, 0.2e-3);
    // F's image one box down in y and z lies 0.4 δ_a beyond contact with E.
    let r_f = r_e - u3 * (a_e + a_f + 0.4 * delta_a) + DVec3::new(0.0, size.y, size.z);
    let r_g = lo + DVec3::new(9.5e-3, 8.5e-3, 3.0e-3);
    let free = Motion::Free;
    let spheres = [
        sphere(
            r_a,
            DVec3::new(0.3, -0.1, 0.2),
            DVec3::new(10.0, -5.0, 20.0),
            a_a,
            free,
        ),
        sphere(
            r_b,
            DVec3::new(0.1, -0.05, 0.25),
            DVec3::new(-15.0, 3.0, 7.0),
            a_b,
            free,
        ),
        sphere(
            r_c,
            DVec3::new(0.02, 0.3, -0.1),
            DVec3::new(2.0, 0.0, -30.0),
            a_c,
            free,
        ),
        sphere(
            r_d,
            DVec3::new(0.03, -0.25, 0.2),
            DVec3::new(0.0, 12.0, 4.0),
            a_d,
            free,
        ),
        sphere(
            r_e,
            DVec3::new(-0.3, 0.1, 0.4),
            DVec3::new(1.0, 1.0, 1.0),
            a_e,
            free,
        ),
        sphere(r_f, DVec3::new(0.2, 0.3, -0.1), DVec3::ZERO, a_f, free),
        sphere(
            r_g,
            DVec3::new(-0.2, 0.3, 0.15),
            DVec3::new(0.0, 0.0, 50.0),
            a_g,
            free,
        ),
    ];
    for s in &spheres {
        for k in 0..3 {
            assert!(s.position[k] >= lo[k] && s.position[k] < lo[k] + size[k]);
        }
    }
    let volume = size.x * size.y * size.z;

    // The hand sums, over every pair, through the nearest image.
    let bodies: Vec<Body> = spheres
        .iter()
        .map(|s| Body {
            r: s.position,
            v: s.velocity,
            w: s.angular_velocity,
            a: s.radius,
            m: mass(s.radius),
        })
        .collect();
    let mut kinetic = [[0.0; 3]; 3];
    for b in &bodies {
        add(&mut kinetic, outer(b.v * b.m, b.v), 1.0 / volume);
    }
    let mut contact = [[0.0; 3]; 3];
    let (mut contacts, mut sliding, mut apart, mut energy) = (0, 0, 0, 0.0);
    for i in 0..bodies.len() {
        for j in i + 1..bodies.len() {
            let (bi, bj) = (&bodies[i], &bodies[j]);
            let l = nearest_image(bi.r - bj.r, size, periodic);
            let e = closed_form(bi, bj, l, bi.a + bj.a - l.length(), true);
            if e.interacts {
                add(&mut contact, outer(e.force, l), 1.0 / volume);
                contacts += usize::from(e.touching);
                sliding += usize::from(e.sliding);
                apart += usize::from(!e.touching);
                energy += e.energy;
            }
        }
    }
    // The set-up is what it claims: two touching pairs, one of them sliding, one adhesive
    // pair apart.
    assert_eq!((contacts, sliding, apart), (2, 1, 1));
    let mut total = kinetic;
    add(&mut total, contact, 1.0);
    // Neither part is negligible, and the contact part is not symmetric.
    let norm = |s: &[[f64; 3]; 3]| s.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(norm(&kinetic) > 0.2 * norm(&contact) && norm(&contact) > 0.2 * norm(&kinetic));
    assert!((contact[0][1] - contact[1][0]).abs() > 1e-3 * norm(&contact));

    let law = law(true);
    let mut particles = Particles::default();
    for s in &spheres {
        particles.push(*s, RHO);
    }
    let sim = Simulation::new(
        particles.clone(),
        domain.clone(),
        ContactTable::uniform(1, law),
        Vec::new(),
        DVec3::ZERO,
        DT,
        0.2e-3,
    )
    .expect("valid set-up");
    let o = sim.observables();
    let d = rel_diff(&o.stress, &total);
    assert!(d < 1e-12, "σ: {:?} vs {total:?} ({d:e})", o.stress);
    assert!(o.mean_stress() > 0.0, "compression positive");
    let d = rel_diff(
        &rows(kinetic_stress_sum(&sim.particles, &sim.domain) / volume),
        &kinetic,
    );
    assert!(d < 1e-12, "kinetic part ({d:e})");
    assert_eq!(o.contacts, 2);
    assert_eq!(o.sliding_fraction, 0.5);
    assert_eq!(o.bridges_per_particle, 1.0 / 7.0);
    assert!(
        ((o.elastic_energy - energy) / energy).abs() < 1e-12,
        "energy {} vs {energy}",
        o.elastic_energy
    );

    // The contact part alone, from the pair loop's own sums.
    let sums = measured_pairs(&mut particles, &domain, law, law.range());
    let d = rel_diff(&rows(sums.stress_sum / volume), &contact);
    assert!(d < 1e-12, "contact part ({d:e})");
    assert_eq!(
        (sums.contacts, sums.sliding, sums.attracting_apart),
        (2, 1, 1)
    );
}

/// Walls' share of the stress, by the documented convention (`ContactSums::stress_sum`,
/// `Observables::stress`): contacts of free particles with wall particles (fixed or
/// rotating) enter `Σ f ⊗ l` with `l = r_i − r_j`, those with a planar wall with `l` from
/// the foot of the centre on the plane to the centre (`l = n · gap`); the kinetic sum runs
/// over free particles only (a rotating wall particle's velocity is not agitation); two
/// prescribed particles never interact (their overlap here adds nothing); the volume is the
/// box's.
///
/// Set-up, in a box periodic in `x` and `y`: free sphere S1 rests on a planar floor
/// (normal `+z`) and touches a fixed wall particle W at an oblique angle; free sphere S2
/// touches a rotating wall particle R (its velocity `Ω × (r − c)` and spin `Ω` enter the
/// damping and the tangential force) and a tilted planar wall near the top; a second fixed
/// particle W2 overlaps R. The reported tensor matches the hand sum to `10⁻¹²` of its largest
/// entry (rounding only), and so do its kinetic part and the pair loop's contact part;
/// the hand sum without the walls' terms differs from it by far more than that, so the
/// test tells the conventions apart.
#[test]
fn walls_share_of_the_stress() {
    let lo = DVec3::new(0.0, 0.0, 0.0);
    let size = DVec3::new(10.0e-3, 10.0e-3, 12.0e-3);
    let periodic = [true, true, false];
    let domain = Domain::new(lo, lo + size, periodic);

    let floor_point = DVec3::new(0.0, 0.0, 0.0);
    let floor_n = DVec3::Z;
    let lid_n = DVec3::new(0.3, -0.2, -1.0).normalize();

    let (a1, a2, a_w, a_r) = (1.0e-3, 0.9e-3, 0.8e-3, 1.1e-3);
    let r1 = DVec3::new(3.0e-3, 4.0e-3, a1 - 1.5e-5);
    let u_w = DVec3::new(-0.6, 0.5, 0.4).normalize();
    let r_w = r1 - u_w * (a1 + a_w - 2.5e-5);
    let r2 = DVec3::new(7.0e-3, 6.5e-3, 9.0e-3);
    let u_r = DVec3::new(0.2, -0.9, -0.5).normalize();
    let r_r = r2 - u_r * (a2 + a_r - 1.8e-5);
    // A second fixed particle W2 overlapping R by 0.1 mm, out of S2's reach.
    let a_w2 = 0.7e-3;
    let r_w2 = r_r + DVec3::X * (a_r + a_w2 - 1.0e-4);
    // The tilted lid: S2's centre at a gap of 0.98 a2 from its plane.
    let lid_point = r2 - lid_n * (0.98 * a2);
    let center = DVec3::new(6.0e-3, 2.0e-3, 5.0e-3);
    let axis = DVec3::new(0.3, 0.4, 1.0).normalize();
    let omega = 40.0;
    let rotating = Motion::Rotating {
        center,
        axis,
        omega,
    };
    let v_r = (axis * omega).cross(r_r - center);
    let spheres = [
        sphere(
            r1,
            DVec3::new(0.12, -0.05, -0.08),
            DVec3::new(5.0, 8.0, -3.0),
            a1,
            Motion::Free,
        ),
        sphere(
            r2,
            DVec3::new(-0.1, 0.15, 0.07),
            DVec3::new(-6.0, 2.0, 9.0),
            a2,
            Motion::Free,
        ),
        sphere(r_w, DVec3::ZERO, DVec3::ZERO, a_w, Motion::Fixed),
        // Velocity and spin are set by the motion law at construction.
        sphere(r_r, DVec3::ZERO, DVec3::ZERO, a_r, rotating),
        sphere(r_w2, DVec3::ZERO, DVec3::ZERO, a_w2, Motion::Fixed),
    ];
    assert!(
        (r_w2 - r_r).length() < a_w2 + a_r,
        "W2 and R overlap: a pair that must not count"
    );
    assert!(
        (r_w2 - r2).length() > a_w2 + a2 + 0.5e-3,
        "W2 does not touch S2"
    );
    for s in &spheres {
        for k in 0..3 {
            assert!(s.position[k] > lo[k] && s.position[k] < lo[k] + size[k]);
        }
    }
    let volume = size.x * size.y * size.z;

    let b1 = Body {
        r: r1,
        v: spheres[0].velocity,
        w: spheres[0].angular_velocity,
        a: a1,
        m: mass(a1),
    };
    let b2 = Body {
        r: r2,
        v: spheres[1].velocity,
        w: spheres[1].angular_velocity,
        a: a2,
        m: mass(a2),
    };
    let bw = Body {
        r: r_w,
        v: DVec3::ZERO,
        w: DVec3::ZERO,
        a: a_w,
        m: f64::INFINITY,
    };
    let br = Body {
        r: r_r,
        v: v_r,
        w: axis * omega,
        a: a_r,
        m: f64::INFINITY,
    };
    let plane = |point: DVec3| Body {
        r: point,
        v: DVec3::ZERO,
        w: DVec3::ZERO,
        a: f64::INFINITY,
        m: f64::INFINITY,
    };

    let mut kinetic = [[0.0; 3]; 3];
    for b in [&b1, &b2] {
        add(&mut kinetic, outer(b.v * b.m, b.v), 1.0 / volume);
    }
    let mut particle_walls = [[0.0; 3]; 3];
    for (b, wall) in [(&b1, &bw), (&b2, &br)] {
        let l = b.r - wall.r;
        let e = closed_form(b, wall, l, b.a + wall.a - l.length(), false);
        assert!(e.touching);
        add(&mut particle_walls, outer(e.force, l), 1.0 / volume);
    }
    let mut planes = [[0.0; 3]; 3];
    for (b, point, n) in [(&b1, floor_point, floor_n), (&b2, lid_point, lid_n)] {
        let gap = (b.r - point).dot(n);
        let l = n * gap;
        let e = closed_form(b, &plane(point), l, b.a - gap, false);
        assert!(e.touching);
        add(&mut planes, outer(e.force, l), 1.0 / volume);
    }
    let mut contact = particle_walls;
    add(&mut contact, planes, 1.0);
    let mut total = kinetic;
    add(&mut total, contact, 1.0);

    let law = law(false);
    let mut particles = Particles::default();
    for s in &spheres {
        particles.push(*s, RHO);
    }
    let walls = vec![
        Wall::plane(floor_point, floor_n, 0),
        Wall::plane(lid_point, lid_n, 0),
    ];
    let sim = Simulation::new(
        particles.clone(),
        domain.clone(),
        ContactTable::uniform(1, law),
        walls.clone(),
        DVec3::ZERO,
        DT,
        0.2e-3,
    )
    .expect("valid set-up");
    let o = sim.observables();
    let d = rel_diff(&o.stress, &total);
    assert!(d < 1e-12, "σ: {:?} vs {total:?} ({d:e})", o.stress);
    let d = rel_diff(
        &rows(kinetic_stress_sum(&sim.particles, &sim.domain) / volume),
        &kinetic,
    );
    assert!(d < 1e-12, "kinetic part ({d:e})");
    // Four contacts: S1–floor, S1–W, S2–R, S2–lid (not W2–R).
    assert_eq!(o.contacts, 4);
    let v_free = 4.0 / 3.0 * PI * (a1.powi(3) + a2.powi(3));
    assert!((o.volume_fraction / (v_free / volume) - 1.0).abs() < 1e-14);

    // The conventions are distinguishable at this tolerance: leaving out either wall
    // share, or counting R's motion as agitation, changes σ by far more than 10⁻¹².
    let mut without_planes = kinetic;
    add(&mut without_planes, particle_walls, 1.0);
    assert!(rel_diff(&o.stress, &without_planes) > 1e-3);
    let mut without_particles = kinetic;
    add(&mut without_particles, planes, 1.0);
    assert!(rel_diff(&o.stress, &without_particles) > 1e-3);
    let mut with_r_kinetic = total;
    add(
        &mut with_r_kinetic,
        outer(v_r * mass(a_r), v_r),
        1.0 / volume,
    );
    assert!(rel_diff(&o.stress, &with_r_kinetic) > 1e-3);

    // The contact part alone: the pair loop (particle walls) plus the planar walls' sums.
    let mut particles = sim.particles.clone();
    let mut sums = measured_pairs(&mut particles, &domain, law, 0.0);
    let d = rel_diff(&rows(sums.stress_sum / volume), &particle_walls);
    assert!(d < 1e-12, "particle-wall part ({d:e})");
    for (k, mut w) in walls.into_iter().enumerate() {
        w.apply(
            k as u32,
            &mut particles,
            &ContactTable::uniform(1, law),
            DT,
            &mut sums,
        );
    }
    let d = rel_diff(&rows(sums.stress_sum / volume), &contact);
    assert!(d < 1e-12, "contact part ({d:e})");
}
