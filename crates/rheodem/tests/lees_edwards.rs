//! Lees-Edwards boundaries in the lab-frame convention (docs/model.md §4.3).
//!
//! Shear along `x`, gradient along `y`. Velocities are full (lab) velocities; the image of a
//! particle across `y = L_y` sits `s` further along `x` and moves `γ̇ L_y` faster along `x`,
//! with `s = ∫ γ̇ L_y dt` (mod `L_x`). The invariants tested here:
//!
//! * **Homogeneity.** A pair in contact across the moving boundary feels exactly the force
//!   and torques of the same pair placed inside the box with the same relative position and
//!   relative velocity (the image's velocity shift `+γ̇ L_y` included), for a frictional,
//!   damped law with rolling and torsion, and for a damped normal law alone, both for grains
//!   moving with the mean flow (relative velocity across the boundary small) and for grains
//!   at rest in the lab (relative velocity `−γ̇ L_y`); over a whole collision with list
//!   rebuilds and a crossing in between; in each of the three shear dynamics: the lab
//!   frame, peculiar contacts (docs/model.md §4.4: contacts subtract `γ̇ l_y x̂`, `l` the
//!   branch vector through the image) and affine drag (§4.5: stored velocities exclude the
//!   mean flow, the image carries no velocity jump, the box moves the particles with the
//!   flow). `tests/affine_drag.rs` tests the rest of affine drag.
//! * **Newton's third law.** The total force on the free particles of a sheared dense box is
//!   zero to rounding; `Σ m (v_x − γ̇ (y − lo_y))`, `Σ m v_y`, `Σ m v_z` are conserved to
//!   rounding (the plain `Σ m v_x` jumps by `m γ̇ L_y` at every crossing; that is no error).
//! * **Crossings.** A particle leaving through `y = L_y` re-enters at `y − L_y`, `x − s`,
//!   `v_x − γ̇ L_y` (and the reverse); its velocity relative to the mean flow is unchanged.
//! * **Shift under a breathing box.** With `L_y` rescaled every step (stress control),
//!   `s(t) = ∫ γ̇ L_y dt` mod `L_x`, with no jumps other than `±L_x` wraps.
//! * **Neighbour list.** In a sheared, stress-controlled dense packing every pair in contact
//!   is in the list, with the right image, at every step; the list is rebuilt far less
//!   often than a lab-frame displacement criterion would.

mod common;

use common::*;
use glam::DVec3;
use rheodem::Simulation;
use rheodem::bench::standard_problem;
use rheodem::contact::LawKind;
use rheodem::contact::{ContactHistory, ContactLaw, PairKinematics, Resistance};
use rheodem::domain::{Domain, ShearDynamics};
use rheodem::measure::kinetic_stress_sum;
use rheodem::particles::Sphere;
use rheodem::stress_control::StressControl;
use std::collections::HashSet;
use std::time::Instant;

/// Lower corner of the test boxes, off the origin so that every use of `lo` is exercised (m).
const LO: DVec3 = DVec3::new(-0.004, 0.0015, -0.001);
/// Edges of the test boxes (m): non-cubic, 8–10 mean diameters.
const SIZE: DVec3 = DVec3::new(0.020, 0.018, 0.022);
/// Shear rate of the test boxes (1/s): `γ̇ L_y = 0.09 m/s`.
const RATE: f64 = 5.0;

/// The test box, sheared until the shift is `fraction · L_x` (brought into
/// `[−L_x/2, L_x/2)`), through the domain's own clock.
fn sheared_box(fraction: f64) -> Domain {
    let mut d = Domain::new(LO, LO + SIZE, [true; 3]).with_lees_edwards(RATE);
    let t = fraction * SIZE.x / (RATE * SIZE.y);
    for _ in 0..16 {
        d.advance(t / 16.0);
    }
    d
}

fn shift(d: &Domain) -> f64 {
    d.as_lees_edwards().expect("Lees-Edwards box").shift
}

/// `x` brought into `[lo, hi)` along `x` and `z`.
fn wrap_xz(d: &Domain, mut r: DVec3) -> DVec3 {
    let l = d.lengths();
    r.x -= l.x * ((r.x - d.lo.x) / l.x).floor();
    r.z -= l.z * ((r.z - d.lo.z) / l.z).floor();
    r
}

/// The paper's frictional law with rolling and torsion resistance on as well.
fn full_law(e: f64, mu: f64) -> ContactLaw {
    let mut law = frictional_law(e, mu);
    let r = Resistance {
        mu_static: 0.1,
        mu_dynamic: 0.1,
        ..*law.tangential.linear().expect("a linear sliding spring")
    };
    law.rolling = r.into();
    law.torsion = r.into();
    law
}

fn contact_time(law: &ContactLaw, a: f64) -> f64 {
    law.normal
        .contact_time(0.5 * mass(a), 0.5 * a)
        .expect("underdamped")
}

// ---------------------------------------------------------------------------------------
// 1. A pair across the moving boundary ≡ the same pair inside the box.
// ---------------------------------------------------------------------------------------

/// How the two grains move before the contact.
#[derive(Clone, Copy, Debug)]
enum Motion {
    /// With the mean flow at their positions plus a small perturbation: the relative
    /// velocity across the boundary is small (`γ̇ l_y` plus the perturbations).
    MeanFlow,
    /// At rest in the lab plus the perturbation: across the boundary the relative velocity
    /// is `−γ̇ L_y` (the image moves `γ̇ L_y` faster).
    LabRest,
}

/// Where the pair sits.
#[derive(Clone, Copy, Debug)]
enum Placement {
    /// Mid-way along `x` and `z`.
    Middle,
    /// `i` near `lo_x`: the partner's image is also across the `x` faces (after the shift).
    AcrossX,
    /// `i` just above `lo_z` and the partner across the `z` faces: the partner then sorts
    /// into a later cell than `i`, so the half list holds the pair from the top particle
    /// (image offset `c_y = +1`, the other cases give `c_y = −1`).
    AcrossZ,
}

/// One pair set-up: `i` just below the top face, `j`'s image above it.
struct PairSetUp {
    across: [Sphere; 2],
    inside: [Sphere; 2],
}

/// Builds the pair in `domain`: `i` at `y = hi_y − 0.01 a_i`, the branch vector
/// `r_i − r_j' = (a_i + a_j − δ) n` (`n_y < 0`: `j`'s image `r_j' = r_j + (s, L_y, 0)` lies
/// above the top face), and the same pair centred in the box with the same relative
/// velocity `v_i − (v_j + γ̇ L_y x̂)` (in the lab; stored velocities follow the domain's
/// shear dynamics, and under affine drag the image's stored velocity has no jump).
fn pair_set_up(domain: &Domain, motion: Motion, seed: u64, place: Placement) -> PairSetUp {
    let mut rng = rng(seed);
    let (a_i, a_j) = (A_REF * 1.13, A_REF * 0.91);
    let (x_fraction, z_offset, n_z) = match place {
        Placement::Middle => (0.5, 0.31 * domain.lengths().z, -0.45),
        Placement::AcrossX => (0.02, 0.31 * domain.lengths().z, -0.45),
        Placement::AcrossZ => (0.5, 0.05 * a_i, 0.45),
    };
    let n = DVec3::new(0.35, -0.8, n_z).normalize();
    let delta = 0.01 * (a_i + a_j);
    let b = n * (a_i + a_j - delta);
    let l = domain.lengths();
    let s = shift(domain);
    let r_i = DVec3::new(
        domain.lo.x + x_fraction * l.x,
        domain.hi.y - 0.01 * a_i,
        domain.lo.z + z_offset,
    );
    let image_j = r_i - b;
    assert!(
        image_j.y > domain.hi.y,
        "the partner's image must lie above the box"
    );
    let r_j = wrap_xz(domain, image_j - DVec3::new(s, l.y, 0.0));
    // Perturbations: approach along n (so that the pair collides), a little sideways slip,
    // an upward drift of i (it crosses the top face during the collision), and spins.
    let u_i = DVec3::new(0.004, 0.012, -0.003) + random_vec(&mut rng, 0.002);
    let u_j = u_i + n * 0.02 + random_vec(&mut rng, 0.003);
    let (v_i, v_j) = match motion {
        Motion::MeanFlow => (
            domain.stored_velocity(r_i, u_i),
            domain.stored_velocity(r_j, u_j),
        ),
        Motion::LabRest => (
            domain.stored_velocity(r_i, u_i - domain.mean_flow(r_i)),
            domain.stored_velocity(r_j, u_j - domain.mean_flow(r_j)),
        ),
    };
    let w_i = random_vec(&mut rng, 20.0);
    let w_j = random_vec(&mut rng, 20.0);
    let mk = |r, v, w, a| {
        let mut s = sphere(r, v, a);
        s.angular_velocity = w;
        s
    };
    let jump = if domain.drags_affinely() {
        0.0
    } else {
        RATE * l.y
    };
    let image_velocity = v_j + DVec3::new(jump, 0.0, 0.0);
    let centre = domain.lo + 0.5 * l;
    PairSetUp {
        across: [mk(r_i, v_i, w_i, a_i), mk(r_j, v_j, w_j, a_j)],
        inside: [
            mk(centre + 0.5 * b, v_i, w_i, a_i),
            mk(centre - 0.5 * b, image_velocity, w_j, a_j),
        ],
    }
}

/// Force on id 0 and torques on ids 0 and 1, initially and after each of `steps` steps;
/// the list is rebuilt by hand every `rebuild_every` steps (wrapping the particles and
/// re-deriving image codes). Also returns the image offsets `c_y` the pair was seen with.
fn pair_record(
    law: ContactLaw,
    domain: Domain,
    spheres: &[Sphere; 2],
    dt: f64,
    steps: usize,
    rebuild_every: usize,
) -> (Vec<[DVec3; 3]>, HashSet<i32>) {
    let mut sim = simulation(spheres, law, domain, vec![], DVec3::ZERO, dt);
    let mut seen = HashSet::new();
    let mut record = |sim: &mut Simulation, out: &mut Vec<[DVec3; 3]>| {
        let (i, j) = (slot(sim, 0), slot(sim, 1));
        out.push([
            sim.particles.force[i],
            sim.particles.torque[i],
            sim.particles.torque[j],
        ]);
        let list = sim.neighbors.slices();
        for &c in list.image {
            seen.insert(rheodem::domain::image_offsets(c)[1]);
        }
    };
    let mut out = Vec::new();
    record(&mut sim, &mut out);
    for k in 1..=steps {
        sim.step(false).expect("step");
        if k % rebuild_every == 0 {
            sim.rebuild_neighbors().expect("rebuild");
        }
        record(&mut sim, &mut out);
    }
    (out, seen)
}

/// Largest difference of two records relative to the largest force (forces) and the
/// largest torque (torques).
fn record_error(a: &[[DVec3; 3]], b: &[[DVec3; 3]]) -> (f64, f64, f64, f64) {
    let f_max = b.iter().map(|r| r[0].length()).fold(0.0, f64::max);
    let t_max = b
        .iter()
        .map(|r| r[1].length().max(r[2].length()))
        .fold(0.0, f64::max);
    let (mut ef, mut et) = (0.0f64, 0.0f64);
    for (x, y) in a.iter().zip(b) {
        ef = ef.max((x[0] - y[0]).length() / f_max);
        et = et.max((x[1] - y[1]).length().max((x[2] - y[2]).length()) / t_max);
    }
    (ef, et, f_max, t_max)
}

/// The first force evaluation across the boundary equals the inside one to rounding, and
/// so does the whole collision (200 steps, about 4 contact times, with list rebuilds every
/// 10 steps and `i` crossing the top face half-way).
///
/// Tolerances. Positions are stored to `ε L ≈ 4·10⁻¹⁸ m` (`L ≈ 0.02 m`), against an overlap
/// of order `δ = 5·10⁻⁵ m`: the overlap of the two set-ups agrees to `~10⁻¹³` relative, the
/// relative velocity to `ε γ̇ L_y / |v_rel| ≈ 10⁻¹⁵`. The first evaluation is compared at
/// `10⁻¹²` of the force (torque). Along the collision the rounding of `r += v dt` (different
/// absolute positions and speeds in the two set-ups) accumulates over 200 steps to
/// `~√200 ε L ≈ 6·10⁻¹⁷ m`, i.e. `k_n · 6·10⁻¹⁷ ≈ 10⁻¹⁴ N` against forces of `~5·10⁻³ N`;
/// and a wrong image velocity would change the force by tens of percent. The trajectory is
/// compared at `10⁻⁹` of the largest force (torque).
#[test]
fn pair_across_moving_boundary_matches_pair_inside() {
    let laws = [
        ("frictional, damped, rolling + torsion", full_law(0.8, 0.5)),
        ("frictionless, damped", normal_law(0.8)),
    ];
    let mut worst = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut codes = HashSet::new();
    for ((name, law), dynamics) in laws
        .into_iter()
        .flat_map(|l| ShearDynamics::ALL.map(|d| (l, d)))
    {
        let dt = contact_time(&law, A_REF) / 50.0;
        for (k, fraction) in [0.37, 0.8].into_iter().enumerate() {
            let mut domain = sheared_box(fraction);
            if let Some(le) = domain.as_lees_edwards_mut() {
                le.dynamics = dynamics;
            }
            for motion in [Motion::MeanFlow, Motion::LabRest] {
                for (m, place) in [Placement::Middle, Placement::AcrossX, Placement::AcrossZ]
                    .into_iter()
                    .enumerate()
                {
                    let seed = 17 + 4 * k as u64 + m as u64;
                    let set = pair_set_up(&domain, motion, seed, place);
                    let (across, seen) = pair_record(law, domain.clone(), &set.across, dt, 200, 10);
                    let (inside, _) = pair_record(law, domain.clone(), &set.inside, dt, 200, 10);
                    codes.extend(seen);
                    let (f0, t0, fm, tm) = record_error(&across[..1], &inside[..1]);
                    let (ef, et, _, _) = record_error(&across, &inside);
                    eprintln!(
                        "[{name}, {dynamics}] s = {:+.3} L_x, {motion:?}, {place:?}: \
                         first evaluation |ΔF|/F = {f0:.2e}, |ΔT|/T = {t0:.2e}; \
                         200 steps |ΔF|/F_max = {ef:.2e}, |ΔT|/T_max = {et:.2e} \
                         (F_max = {fm:.3e} N, T_max = {tm:.3e} N m)",
                        shift(&domain) / SIZE.x
                    );
                    assert!(fm > 0.0, "the pair must be in contact");
                    assert!(
                        f0 < 1e-12 && t0 < 1e-12,
                        "first evaluation differs: force {f0:.3e}, torque {t0:.3e}"
                    );
                    assert!(
                        ef < 1e-9 && et < 1e-9,
                        "collision differs: force {ef:.3e}, torque {et:.3e}"
                    );
                    worst = (
                        worst.0.max(f0),
                        worst.1.max(t0),
                        worst.2.max(ef),
                        worst.3.max(et),
                    );
                }
            }
        }
    }
    eprintln!(
        "worst: first evaluation {:.2e} (force), {:.2e} (torque); collision {:.2e}, {:.2e}; \
         image offsets c_y seen: {codes:?}",
        worst.0, worst.1, worst.2, worst.3
    );
    // Both orders of the pair in the half list (image above and below) were exercised.
    assert!(
        codes.contains(&1) && codes.contains(&-1),
        "image offsets seen: {codes:?}"
    );
}

/// The test above can tell the right image velocity from a wrong one: with the image moving
/// `γ̇ L_y` slower instead of faster (the sign error of a peer code), or with no velocity
/// shift at all, the first force differs by a large fraction.
#[test]
fn wrong_image_velocity_would_be_detected() {
    let law = full_law(0.8, 0.5);
    let dt = contact_time(&law, A_REF) / 50.0;
    let domain = sheared_box(0.37);
    let u = RATE * domain.lengths().y;
    for motion in [Motion::MeanFlow, Motion::LabRest] {
        let set = pair_set_up(&domain, motion, 3, Placement::Middle);
        let sim = simulation(&set.across, law, domain.clone(), vec![], DVec3::ZERO, dt);
        let f_sim = sim.particles.force[slot(&sim, 0)];
        let [si, sj] = set.inside;
        let force_with = |v_j: DVec3| {
            let branch = si.position - sj.position;
            let kin = PairKinematics {
                normal: branch.normalize(),
                overlap: si.radius + sj.radius - branch.length(),
                radius_i: si.radius,
                radius_j: sj.radius,
                velocity: si.velocity - v_j,
                omega_i: si.angular_velocity,
                omega_j: sj.angular_velocity,
                reduced_mass: 1.0 / (1.0 / mass(si.radius) + 1.0 / mass(sj.radius)),
            };
            law.evaluate(&kin, &mut ContactHistory::default(), dt).force
        };
        let right = force_with(sj.velocity);
        let flipped = force_with(sj.velocity - DVec3::new(2.0 * u, 0.0, 0.0));
        let unshifted = force_with(sj.velocity - DVec3::new(u, 0.0, 0.0));
        let rel = |f: DVec3| (f - right).length() / right.length();
        eprintln!(
            "{motion:?}: simulation vs closed pair kernel {:.2e}; a flipped image velocity \
             changes the force by {:.1} %, no image velocity by {:.1} %",
            rel(f_sim),
            100.0 * rel(flipped),
            100.0 * rel(unshifted)
        );
        assert!(rel(f_sim) < 1e-12);
        assert!(rel(flipped) > 0.05 && rel(unshifted) > 0.05);
    }
}

// ---------------------------------------------------------------------------------------
// 2. Newton's third law and the conserved momenta of a sheared dense box.
// ---------------------------------------------------------------------------------------

/// `(Σ m (v_x − γ̇ (y − lo_y)), Σ m v_y, Σ m v_z)`: the momentum relative to the mean flow.
fn peculiar_momentum(sim: &Simulation) -> DVec3 {
    let p = &sim.particles;
    (0..p.len())
        .map(|i| (p.velocity[i] - sim.domain.mean_flow(p.position[i])) * p.mass[i])
        .sum()
}

/// Lab-frame displacement bookkeeping of the usual rule "rebuild once the two largest
/// displacements since the last build add up to the skin" (LAMMPS's skin/2 rule), applied
/// to the lab-frame motion `Σ v dt`, which counts the mean flow.
struct LabFrameRule {
    skin: f64,
    moved: Vec<DVec3>,
    builds: u64,
}

impl LabFrameRule {
    fn new(n: usize, skin: f64) -> LabFrameRule {
        LabFrameRule {
            skin,
            moved: vec![DVec3::ZERO; n],
            builds: 0,
        }
    }

    /// Adds the motion of one step (end-of-step velocities of `sim`, over `dt`).
    fn advance(&mut self, sim: &Simulation) {
        let (mut first, mut second) = (0.0f64, 0.0f64);
        for (slot, v) in sim.particles.velocity.iter().enumerate() {
            let m = &mut self.moved[sim.particles.id[slot] as usize];
            *m += *v * sim.dt;
            let d = m.length();
            if d > second {
                if d > first {
                    second = first;
                    first = d;
                } else {
                    second = d;
                }
            }
        }
        if first + second >= self.skin {
            self.builds += 1;
            self.moved.iter_mut().for_each(|m| *m = DVec3::ZERO);
        }
    }
}

/// The standard 4096-sphere problem (`φ = 0.62`, Hooke + friction, `γ̇ = 1`, model units)
/// sheared for 2000 steps (strain 0.64, past the first wrap of the shift at 0.5), by which
/// time a contact network has built up: at every step `|Σ F| ≤ 10⁻¹² Σ |F_i|`. Each pair
/// adds `+f` and `−f` to its two particles; the sum carries only the rounding of ~10⁵
/// additions, `~√(10⁵) ε f_c`, far below `Σ |F_i|`, which is of order `N f_c` (`f_c` a
/// typical contact force). The peculiar momentum `Σ m (v − γ̇ (y − lo_y) x̂)` is conserved
/// to `10⁻¹²` of `M γ̇ L_y` (`M` the total mass): the kicks add `Σ F dt/2 = 0`, the drift
/// changes `Σ m γ̇ y` by `γ̇ dt Σ m v_y = 0`, and a crossing changes `v_x` and `γ̇ y` by the
/// same `γ̇ L_y` (a rounding of `ε m γ̇ L_y` each). The list is rebuilt at least 3 times
/// less often than the lab-frame rule would on the same trajectory.
#[test]
fn total_force_vanishes_and_peculiar_momentum_is_conserved() {
    let clock = Instant::now();
    let mut sim = standard_problem(1.0, LawKind::None, 0.2);
    let steps = 2000;
    let q0 = peculiar_momentum(&sim);
    let total_mass: f64 = sim.particles.mass.iter().sum();
    let scale = total_mass * 1.0 * sim.domain.lengths().y;
    let px = |sim: &Simulation| -> f64 {
        (0..sim.particles.len())
            .map(|i| sim.particles.mass[i] * sim.particles.velocity[i].x)
            .sum()
    };
    let px0 = px(&sim);
    let builds0 = sim.neighbors.builds;
    let mut lab = LabFrameRule::new(sim.particles.len(), sim.neighbors.skin);
    let (mut worst_f, mut worst_q) = (0.0f64, 0.0f64);
    for k in 1..=steps {
        sim.step(k == steps).expect("step");
        let total: DVec3 = sim.particles.force.iter().copied().sum();
        let scale_f: f64 = sim.particles.force.iter().map(|f| f.length()).sum();
        worst_f = worst_f.max(total.length() / scale_f);
        worst_q = worst_q.max((peculiar_momentum(&sim) - q0).length() / scale);
        lab.advance(&sim);
    }
    let obs = sim.observables();
    let builds = sim.neighbors.builds - builds0;
    eprintln!(
        "bench problem, {steps} steps in {:.1} s ({} shift wraps): max |ΣF|/Σ|F_i| = \
         {worst_f:.2e}, max |ΔQ|/(M γ̇ L_y) = {worst_q:.2e}; plain Σ m v_x moved by {:.3e} \
         (crossings, expected); p = {:.1}, Z = {:.2}; list builds {builds} vs {} by the \
         lab-frame rule",
        clock.elapsed().as_secs_f64(),
        sim.domain.image_epoch(),
        px(&sim) - px0,
        obs.mean_stress(),
        obs.coordination,
        lab.builds
    );
    assert!(
        obs.coordination > 3.0,
        "not a dense packing: Z = {}",
        obs.coordination
    );
    assert!(
        sim.domain.image_epoch() >= 1,
        "the shift should have wrapped"
    );
    assert!(worst_f < 1e-12, "total force {worst_f:.3e} of Σ|F_i|");
    assert!(
        worst_q < 1e-12,
        "peculiar momentum changed by {worst_q:.3e}"
    );
    assert!(
        3 * builds <= lab.builds,
        "{builds} builds vs {} lab-frame",
        lab.builds
    );
}

// ---------------------------------------------------------------------------------------
// 3. Crossings.
// ---------------------------------------------------------------------------------------

/// `Domain::wrap` directly: up through the top (also with an `x` wrap), down through the
/// bottom, two periods at once, a negative shift, and a particle inside (untouched).
/// Compared at `10⁻¹⁵ L` (positions) and `10⁻¹⁴ γ̇ L_y` (velocities): a few roundings.
#[test]
fn wrap_maps_position_and_velocity_of_a_crossing() {
    for fraction in [0.37, 0.8] {
        let d = sheared_box(fraction);
        let (l, s) = (d.lengths(), shift(&d));
        let u = RATE * l.y;
        let v0 = DVec3::new(0.05, 0.01, -0.02);
        let cases = [
            // (position, periods k crossed upwards)
            (
                DVec3::new(d.lo.x + 0.6 * l.x, d.hi.y + 2e-4, d.lo.z + 0.3 * l.z),
                1.0,
            ),
            (
                DVec3::new(d.lo.x + 0.01 * l.x, d.hi.y + 1e-6, d.lo.z + 0.3 * l.z),
                1.0,
            ),
            (
                DVec3::new(d.lo.x + 0.97 * l.x, d.lo.y - 3e-4, d.lo.z + 0.9 * l.z),
                -1.0,
            ),
            (
                DVec3::new(d.lo.x + 0.5 * l.x, d.hi.y + l.y + 1e-4, d.lo.z + 0.5 * l.z),
                2.0,
            ),
            (
                DVec3::new(d.lo.x + 0.5 * l.x, d.lo.y + 0.5 * l.y, d.lo.z + 0.5 * l.z),
                0.0,
            ),
        ];
        for (r0, k) in cases {
            let (mut r, mut v, mut w) = (r0, v0, DVec3::ZERO);
            d.wrap(&mut r, &mut v, &mut w);
            let expected = wrap_xz(&d, DVec3::new(r0.x - k * s, r0.y - k * l.y, r0.z));
            let v_expected = DVec3::new(v0.x - k * u, v0.y, v0.z);
            let peculiar_before = v0 - d.mean_flow(r0);
            let peculiar_after = v - d.mean_flow(r);
            eprintln!(
                "s = {:+.3} L_x, k = {k}: Δr = {:.1e} m, Δv = {:.1e} m/s, Δv' = {:.1e} m/s",
                s / l.x,
                (r - expected).length(),
                (v - v_expected).length(),
                (peculiar_after - peculiar_before).length()
            );
            assert!(r.y >= d.lo.y && r.y < d.hi.y && r.x >= d.lo.x && r.x < d.hi.x);
            assert!(
                (r - expected).length() < 1e-15 * l.x.max(l.y),
                "{r} vs {expected}"
            );
            assert!((v - v_expected).length() < 1e-14 * u, "{v} vs {v_expected}");
            assert!((peculiar_after - peculiar_before).length() < 1e-14 * u);
        }
    }
}

/// A lone particle in a simulation crosses the top (bottom) face: it stays outside the box
/// until the next list rebuild, which maps it to `y ∓ L_y`, `x ∓ s` (with the shift of that
/// moment), `v_x ∓ γ̇ L_y`; its velocity relative to the mean flow is the same before and
/// after, and afterwards it keeps moving with the new velocity. No forces act, so the
/// unwrapped motion is `r_0 + v_0 t` exactly up to rounding (`10⁻¹² L`).
#[test]
fn lone_particle_crosses_in_a_simulation() {
    for upwards in [true, false] {
        let domain = sheared_box(0.45);
        let l = domain.lengths();
        let u = RATE * l.y;
        let a = A_REF;
        let r0 = if upwards {
            DVec3::new(LO.x + 0.05 * l.x, domain.hi.y - 0.5 * a, LO.z + 0.4 * l.z)
        } else {
            DVec3::new(LO.x + 0.95 * l.x, domain.lo.y + 0.5 * a, LO.z + 0.4 * l.z)
        };
        let vy = if upwards { 0.03 } else { -0.03 };
        let v0 = domain.mean_flow(r0) + DVec3::new(0.01, vy, -0.004);
        let law = normal_law(0.8);
        let dt = contact_time(&law, a) / 50.0;
        let mut sim = simulation(&[sphere(r0, v0, a)], law, domain, vec![], DVec3::ZERO, dt);
        let builds0 = sim.neighbors.builds;
        let mut crossed_at = None;
        let mut wrapped = false;
        for k in 1..=5000 {
            let before = sim.neighbors.builds;
            sim.step(false).expect("step");
            let (r, v) = (sim.particles.position[0], sim.particles.velocity[0]);
            let t = sim.time;
            // Where the particle would be without any wrapping (no forces act).
            let unwrapped = r0 + v0 * t;
            if crossed_at.is_none()
                && (unwrapped.y >= sim.domain.hi.y || unwrapped.y < sim.domain.lo.y)
            {
                crossed_at = Some(k);
            }
            let Some(k_cross) = crossed_at else {
                // Until it crosses, its lab velocity is untouched and y follows r_0 + v_0 t.
                assert!((v - v0).length() < 1e-14 * u);
                assert!((r.y - unwrapped.y).abs() < 1e-12 * l.y);
                continue;
            };
            if sim.neighbors.builds == before {
                // Crossed but not rebuilt yet: still outside, velocity untouched.
                assert!(r.y >= sim.domain.hi.y || r.y < sim.domain.lo.y);
                assert!((v - v0).length() < 1e-14 * u);
                continue;
            }
            // Rebuilt after the crossing: the particle is wrapped with the current shift.
            let s = shift(&sim.domain);
            let sign = if upwards { 1.0 } else { -1.0 };
            let expected = wrap_xz(&sim.domain, unwrapped - sign * DVec3::new(s, l.y, 0.0));
            let v_expected = v0 - sign * DVec3::new(u, 0.0, 0.0);
            // Relative to the mean flow, before (unwrapped) and after (wrapped).
            let peculiar0 = v0 - sim.domain.mean_flow(unwrapped);
            let peculiar = v - sim.domain.mean_flow(r);
            eprintln!(
                "{}: crossed at step {k_cross}, wrapped at step {k} (rebuild {}): \
                 Δr = {:.1e} m, Δv = {:.1e} m/s, Δv' = {:.1e} m/s",
                if upwards { "up" } else { "down" },
                sim.neighbors.builds - builds0,
                (r - expected).length(),
                (v - v_expected).length(),
                (peculiar - peculiar0).length()
            );
            assert!(
                r.y >= sim.domain.lo.y && r.y < sim.domain.hi.y,
                "not brought back"
            );
            assert!((r - expected).length() < 1e-12 * l.x, "{r} vs {expected}");
            assert!((v - v_expected).length() < 1e-12 * u, "{v} vs {v_expected}");
            assert!((peculiar - peculiar0).length() < 1e-12 * u);
            // It keeps moving with the new velocity.
            for _ in 0..20 {
                sim.step(false).expect("step");
            }
            let moved = sim.particles.position[0];
            let straight = r + v * (20.0 * dt);
            assert!(
                (wrap_xz(&sim.domain, moved) - wrap_xz(&sim.domain, straight)).length()
                    < 1e-12 * l.x
            );
            assert!((sim.particles.velocity[0] - v_expected).length() < 1e-12 * u);
            wrapped = true;
            break;
        }
        assert!(wrapped, "the particle never crossed and got wrapped");
    }
}

// ---------------------------------------------------------------------------------------
// 4. The shift while L_y changes.
// ---------------------------------------------------------------------------------------

/// Distance of `x` from the nearest multiple of `period`.
fn modulo_distance(x: f64, period: f64) -> f64 {
    (x - period * (x / period).round()).abs()
}

/// `Domain::advance` followed by `scale_y` every step, as under stress control, with `L_y`
/// breathing by ±30 % (`ln L_y = ln L_0 + 0.3 sin(2π k/3000)`) over 20 000 steps
/// (≈ 12 wraps of the shift): `s` equals the reference `Σ γ̇ L_y(k) dt` (same `L_y`
/// sequence, not wrapped) modulo `L_x` to `10⁻¹² L_x` (rounding of 2·10⁴ additions to a sum
/// of ~0.25 m is ~10⁻¹⁴ m); each step changes `s` by exactly `γ̇ L_y dt` or by that minus
/// `L_x` (to `10⁻¹² L_x`), and only the latter steps count a wrap. The naive `γ̇ L_y t`
/// would be off by a large fraction of `L_x`.
#[test]
fn shift_integrates_breathing_box_height() {
    let mut d = Domain::new(LO, LO + SIZE, [true; 3]).with_lees_edwards(7.0);
    let dt = 1e-4;
    let lx = SIZE.x;
    let (mut reference, mut naive_worst, mut worst, mut step_worst) = (0.0, 0.0f64, 0.0f64, 0.0f64);
    let mut wraps_seen = 0;
    let steps = 20_000;
    let log_l = |k: usize| 0.3 * (2.0 * std::f64::consts::PI * k as f64 / 3000.0).sin();
    let (mut no_pos, mut no_vel): (Vec<DVec3>, Vec<DVec3>) = (Vec::new(), Vec::new());
    let (mut l_min, mut l_max) = (f64::INFINITY, 0.0f64);
    for k in 0..steps {
        let ly = d.lengths().y;
        l_min = l_min.min(ly);
        l_max = l_max.max(ly);
        let s_before = shift(&d);
        let wraps_before = d.as_lees_edwards().map_or(0, |le| le.wraps);
        d.advance(dt);
        d.scale_y((log_l(k + 1) - log_l(k)).exp(), &mut no_pos, &mut no_vel);
        let increment = 7.0 * ly * dt;
        reference += increment;
        let s = shift(&d);
        assert!((-0.5 * lx..0.5 * lx).contains(&s), "shift {s} out of range");
        let jump = s - s_before;
        let wrapped = d.as_lees_edwards().map_or(0, |le| le.wraps) > wraps_before;
        if wrapped {
            wraps_seen += 1;
            step_worst = step_worst.max((jump - (increment - lx)).abs());
        } else {
            step_worst = step_worst.max((jump - increment).abs());
        }
        worst = worst.max(modulo_distance(s - reference, lx));
        naive_worst = naive_worst.max(modulo_distance(
            s - 7.0 * d.lengths().y * dt * (k + 1) as f64,
            lx,
        ));
    }
    eprintln!(
        "breathing box, L_y in [{:.4}, {:.4}] m, {steps} steps, {wraps_seen} wraps: \
         |s − ∫γ̇L_y dt| mod L_x ≤ {:.2e} L_x, per-step increment error ≤ {:.2e} L_x; \
         naive γ̇ L_y t would be off by up to {:.3} L_x",
        l_min,
        l_max,
        worst / lx,
        step_worst / lx,
        naive_worst / lx
    );
    assert!(wraps_seen >= 10);
    assert_eq!(d.as_lees_edwards().map_or(0, |le| le.wraps), wraps_seen);
    assert!(worst < 1e-12 * lx);
    assert!(step_worst < 1e-12 * lx);
    assert!(
        naive_worst > 0.05 * lx,
        "the check would not see the naive formula"
    );
}

/// The same through a stress-controlled simulation: a dense FCC packing (256 spheres,
/// `w = 1.2`) sheared with `σ_yy` held at a target well below its initial stress, so that the
/// control dilates `L_y` at its strain cap at first. Every step
/// `ln(L_y'/L_y) = clamp((σ_yy − σ_0) dt / (M τ), ±cap)` with `σ_yy` the value of the
/// previous force evaluation (to `10⁻¹²` of the cap), and the shift equals the reference
/// `Σ γ̇ L_y dt` (the `L_y` at the start of each step) modulo `L_x` to `10⁻¹² L_x`. Also
/// `Simulation::sigma_yy` equals the measured `σ_yy` of the observables to `10⁻¹²` once both
/// use the same velocities (`sigma_yy` is taken with the forces, before the closing half
/// kick; the observables after it — they differ by ~10⁻⁵ relative, an `O(dt)` difference of
/// the kinetic part).
#[test]
fn shift_and_stress_control_in_a_simulation() {
    let (mut spheres, domain) = fcc_packing(4, 0.60, 1.2, 0.01, 0.0, 5);
    let rate = 20.0;
    for s in &mut spheres {
        s.velocity.x += rate * (s.position.y - domain.lo.y);
    }
    let law = frictional_law(0.8, 0.5);
    let a_min = spheres
        .iter()
        .map(|s| s.radius)
        .fold(f64::INFINITY, f64::min);
    let dt = contact_time(&law, a_min) / 50.0;
    let mut sim = simulation(
        &spheres,
        law,
        domain.with_lees_edwards(rate),
        vec![],
        DVec3::ZERO,
        dt,
    );
    let d = 2.0 * A_REF;
    let t_k = (RHO * d.powi(3) / KN).sqrt();
    let control = StressControl {
        target: 0.005 * KN / d,
        modulus: KN / d,
        time: 10.0 * t_k,
        max_strain_per_step: 2e-5,
    };
    sim.set_stress_control(control);
    let lx = sim.domain.lengths().x;
    let ly0 = sim.domain.lengths().y;
    let mut reference = 0.0;
    let (mut worst_s, mut worst_law, mut worst_sigma) = (0.0f64, 0.0f64, 0.0f64);
    let (mut capped, mut free) = (0, 0);
    for k in 1..=3000 {
        let ly = sim.domain.lengths().y;
        let sigma = sim.sigma_yy;
        let measure = k % 100 == 0;
        sim.step(measure).expect("step");
        reference += rate * ly * dt;
        worst_s = worst_s.max(modulo_distance(shift(&sim.domain) - reference, lx));
        let strain = ((sigma - control.target) * dt / (control.modulus * control.time))
            .clamp(-control.max_strain_per_step, control.max_strain_per_step);
        if strain.abs() == control.max_strain_per_step {
            capped += 1;
        } else {
            free += 1;
        }
        let applied = sim.domain.lengths().y / ly - 1.0;
        worst_law = worst_law.max((applied - strain).abs() / control.max_strain_per_step);
        if measure {
            // `sigma_yy` is evaluated with the forces, i.e. with the velocities before the
            // closing half kick; the observables use the end-of-step velocities. Undo the
            // half kick and compare the same quantity.
            let obs = sim.observables();
            let volume = sim.domain.volume();
            let k_end = kinetic_stress_sum(&sim.particles, &sim.domain).y_axis.y;
            let contact = obs.stress[1][1] * volume - k_end;
            let mut half = sim.particles.clone();
            for i in 0..half.len() {
                let kick = half.force[i] * (half.inv_mass[i] * 0.5 * dt);
                half.velocity[i] -= kick;
            }
            let k_half = kinetic_stress_sum(&half, &sim.domain).y_axis.y;
            let expected = (k_half + contact) / volume;
            worst_sigma = worst_sigma.max((sim.sigma_yy - expected).abs() / expected.abs());
        }
    }
    eprintln!(
        "stress-controlled shear, 3000 steps: L_y {:.3e} → {:.3e} m ({capped} capped, {free} \
         proportional steps), σ_yy = {:.1} Pa vs target {:.1} Pa; |s − ∫γ̇L_y dt| mod L_x ≤ \
         {:.2e} L_x; control law error ≤ {:.2e} of the cap; σ_yy vs observables ≤ {:.2e}",
        ly0,
        sim.domain.lengths().y,
        sim.sigma_yy,
        control.target,
        worst_s / lx,
        worst_law,
        worst_sigma
    );
    assert!(
        capped > 0 && free > 0,
        "both regimes of the control should occur"
    );
    assert!(
        (sim.domain.lengths().y / ly0 - 1.0).abs() > 0.01,
        "L_y hardly changed"
    );
    assert!(worst_s < 1e-12 * lx);
    assert!(worst_law < 1e-9);
    assert!(worst_sigma < 1e-12);
}

// ---------------------------------------------------------------------------------------
// 5. Neighbour list under shear.
// ---------------------------------------------------------------------------------------

/// Minimum-image separation `r_i − r_j` through the Lees-Edwards images (brute force over
/// `c_y ∈ {−1, 0, 1}`, then the nearest `x` and `z` images).
fn min_image(d: &Domain, ri: DVec3, rj: DVec3) -> DVec3 {
    let l = d.lengths();
    let s = d.as_lees_edwards().map_or(0.0, |le| le.shift);
    let mut best = DVec3::splat(f64::INFINITY);
    for cy in -1..=1 {
        let c = cy as f64;
        let mut b = ri - rj - DVec3::new(c * s, c * l.y, 0.0);
        b.x -= l.x * (b.x / l.x).round();
        b.z -= l.z * (b.z / l.z).round();
        if b.length_squared() < best.length_squared() {
            best = b;
        }
    }
    best
}

/// Outcome of one brute-force check of the list.
#[derive(Default)]
struct ListCheck {
    contacts: usize,
    missing: usize,
    wrong_image: usize,
    /// Smallest `|r_ij| − (a_i + a_j)` over pairs *not* in the list (m).
    margin: f64,
}

/// Checks every pair of `sim` by brute force: each pair with `|r_ij| < a_i + a_j` must be
/// in the list, and the list's image must give the minimum-image separation (to
/// `10⁻¹² L`).
fn check_list(sim: &mut Simulation) -> ListCheck {
    let images = sim.domain.image_transforms();
    let p = &sim.particles;
    let list = sim.neighbors.slices();
    let mut listed = std::collections::HashMap::new();
    for i in 0..p.len() {
        for k in list.offsets[i] as usize..list.offsets[i + 1] as usize {
            let j = list.partner[k] as usize;
            let b = p.position[i] - images[list.image[k] as usize].position(p.position[j]);
            let key = (p.id[i].min(p.id[j]), p.id[i].max(p.id[j]));
            listed.insert(key, b.length());
        }
    }
    let mut out = ListCheck {
        margin: f64::INFINITY,
        ..ListCheck::default()
    };
    let tol = 1e-12 * sim.domain.lengths().max_element();
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            let b = min_image(&sim.domain, p.position[i], p.position[j]).length();
            let sum = p.radius[i] + p.radius[j];
            let key = (p.id[i].min(p.id[j]), p.id[i].max(p.id[j]));
            match listed.get(&key) {
                Some(&lb) => {
                    if b < sum {
                        out.contacts += 1;
                        if (lb - b).abs() > tol {
                            out.wrong_image += 1;
                        }
                    }
                }
                None => {
                    out.margin = out.margin.min(b - sum);
                    if b < sum {
                        out.contacts += 1;
                        out.missing += 1;
                    }
                }
            }
        }
    }
    out
}

/// A sheared, stress-controlled dense packing (256 spheres, `w = 1.5`, frictional, `γ̇`
/// giving a strain of 0.6 over 4000 steps, `L_y` breathing under `σ_yy` control) is checked
/// against brute force after every step: no pair in contact is missing from the list, every
/// listed contact uses the minimum image, and the contact count of the force loop equals
/// the brute-force count. The shift starts at `L_x/4` (one lattice cell, so the FCC lattice
/// stays consistent across the boundary) and wraps at strain 0.25.
///
/// Rebuilds: this box is only ~6 diameters high, so the mean-flow speed at the faces is only
/// a few times the non-affine velocity fluctuations and the affine criterion saves less than
/// in a large box (the 4096-sphere test above: see its numbers); required here is only
/// fewer builds than the lab-frame rule on the same trajectory.
#[test]
fn neighbour_list_is_complete_under_shear() {
    let clock = Instant::now();
    let (mut spheres, domain) = fcc_packing(4, 0.60, 1.5, 0.02, 0.0, 9);
    let law = frictional_law(0.8, 0.5);
    let a_min = spheres
        .iter()
        .map(|s| s.radius)
        .fold(f64::INFINITY, f64::min);
    let dt = contact_time(&law, a_min) / 50.0;
    let steps = 4000;
    let rate = 0.6 / (steps as f64 * dt);
    for s in &mut spheres {
        s.velocity.x += rate * (s.position.y - domain.lo.y);
    }
    let mut domain = domain.with_lees_edwards(rate);
    let shift = 0.25 * domain.hi.x - 0.25 * domain.lo.x;
    if let Some(le) = domain.as_lees_edwards_mut() {
        le.shift = shift;
    }
    let mut sim = simulation(&spheres, law, domain, vec![], DVec3::ZERO, dt);
    let d = 2.0 * A_REF;
    sim.set_stress_control(StressControl {
        target: 0.01 * KN / d,
        modulus: KN / d,
        time: 10.0 * (RHO * d.powi(3) / KN).sqrt(),
        max_strain_per_step: 1e-4,
    });
    let n = sim.particles.len();
    let skin = sim.neighbors.skin;
    let builds0 = sim.neighbors.builds;
    let mut lab = LabFrameRule::new(n, skin);
    let mut contacts_total = 0usize;
    let mut min_margin = f64::INFINITY;
    let mut ly_range = (f64::INFINITY, 0.0f64);
    for k in 1..=steps {
        sim.step(true).expect("step");
        let check = check_list(&mut sim);
        assert_eq!(
            check.missing, 0,
            "step {k}: {} contacts missing from the list",
            check.missing
        );
        assert_eq!(
            check.wrong_image, 0,
            "step {k}: {} contacts with a wrong image",
            check.wrong_image
        );
        let obs = sim.observables();
        assert_eq!(
            obs.contacts as usize, check.contacts,
            "step {k}: contact count"
        );
        contacts_total += check.contacts;
        min_margin = min_margin.min(check.margin);
        let ly = sim.domain.lengths().y;
        ly_range = (ly_range.0.min(ly), ly_range.1.max(ly));
        lab.advance(&sim);
    }
    let builds = sim.neighbors.builds - builds0;
    let wraps = sim.domain.image_epoch();
    eprintln!(
        "sheared packing: {n} spheres, {steps} steps, strain {:.2}, L_y in [{:.4e}, {:.4e}] m, \
         {wraps} shift wraps, mean {:.2} contacts/step, closest unlisted pair {:.3} skin from \
         contact; list builds: {builds} (one every {:.0} steps); lab-frame rule: {} builds; \
         {:.1} s",
        rate * steps as f64 * dt,
        ly_range.0,
        ly_range.1,
        contacts_total as f64 / steps as f64,
        min_margin / skin,
        steps as f64 / builds as f64,
        lab.builds,
        clock.elapsed().as_secs_f64()
    );
    assert!(wraps >= 1, "the shift should wrap at least once");
    assert!(contacts_total > steps * n, "not a dense packing");
    assert!(
        builds < lab.builds,
        "{builds} builds vs {} lab-frame",
        lab.builds
    );
}

/// Pure compression along `y` (no shear, grains at rest, so the motion is entirely affine)
/// of two spheres of radius `a` that start just outside the list cutoff `2a + skin`,
/// separated along `y`, compressed by `10⁻⁴` per step (the stress control's strain cap).
/// The list must hold the pair before they touch, at the latest once the affine strain
/// reaches `skin / (2a + skin)` (9.1 % here): a pair outside the list at the last build can
/// close its gap once `‖A‖ (r_c + skin) ≥ skin` (`r_c = 2 a_max + range`), since
/// `|(I + A) r_0| ≥ (1 − ‖A‖) |r_0|` and `|r_0| ≥ r_c + skin`.
#[test]
fn neighbour_list_is_complete_under_pure_compression() {
    let a = A_REF;
    let law = normal_law(0.8);
    let dt = contact_time(&law, a) / 50.0;
    let domain = Domain::new(LO, LO + SIZE, [true; 3]).with_lees_edwards(0.0);
    let centre = LO + 0.5 * SIZE;
    let skin = 0.2 * a; // as set by common::simulation
    let gap = (2.0 * a + skin) * (1.0 + 1e-6);
    let spheres = [
        sphere(centre + DVec3::new(0.0, 0.5 * gap, 0.0), DVec3::ZERO, a),
        sphere(centre - DVec3::new(0.0, 0.5 * gap, 0.0), DVec3::ZERO, a),
    ];
    let mut sim = simulation(&spheres, law, domain, vec![], DVec3::ZERO, dt);
    assert_eq!(sim.neighbors.len(), 0, "the pair starts outside the list");
    let (mut first_contact, mut first_missed, mut worst_missed) = (None, None, 0.0f64);
    let mut listed_at = None;
    for k in 1..=1500 {
        let mut pos = std::mem::take(&mut sim.particles.position);
        let mut vel = std::mem::take(&mut sim.particles.velocity);
        sim.domain.scale_y(1.0 - 1e-4, &mut pos, &mut vel);
        sim.particles.position = pos;
        sim.particles.velocity = vel;
        sim.refresh_neighbors().expect("rebuild");
        sim.compute_forces(true);
        let strain = 1.0 - sim.domain.lengths().y / SIZE.y;
        let check = check_list(&mut sim);
        if check.contacts > 0 && first_contact.is_none() {
            first_contact = Some((k, strain));
        }
        if check.missing > 0 {
            first_missed.get_or_insert((k, strain));
            worst_missed = worst_missed.max(-check.margin);
        }
        if listed_at.is_none() && !sim.neighbors.is_empty() {
            listed_at = Some((k, strain));
        }
    }
    eprintln!(
        "pure y-compression: first touch at (step, strain) {first_contact:?}; pair listed from \
         {listed_at:?}; missed contacts from {first_missed:?}, worst missed overlap {:.3e} m \
         ({:.2} % of the diameter)",
        worst_missed,
        100.0 * worst_missed / (2.0 * a)
    );
    assert!(first_contact.is_some(), "the pair never touched");
    assert!(
        first_missed.is_none(),
        "contacts missing from the list from (step, strain) {first_missed:?} until the list \
         was rebuilt at {listed_at:?}: overlap up to {worst_missed:.3e} m unseen"
    );
}

/// Under peculiar contacts the pair loop subtracts the boundary's mean-flow difference
/// `L b` from a contact's relative velocity (docs/model.md §4.4). Two touching spheres that
/// both move with the mean flow, stacked along the gradient `y`, then have no relative
/// sliding velocity: their sliding spring stays at zero after one evaluation and the
/// force is the normal spring alone. In the lab frame the same pair slides at `γ̇ d` along
/// `x`, and its spring loads to `γ̇ d dt`. The gradient itself is checked against the mean
/// flow: `L b = v̄(r + b) − v̄(r)`.
#[test]
fn peculiar_contacts_subtract_the_boundarys_mean_flow() {
    use rheodem::contact::{ContactTable, Damping, LinearNormal, Spring};
    use rheodem::forces::{ForceScratch, pair_forces};
    use rheodem::neighbor::NeighborList;
    use rheodem::particles::{Motion, Particles};
    use rheodem::team::Team;
    let (rate, a, overlap, dt) = (3.0, 1.0e-3, 1.0e-5, 1.0e-6);
    let edge = 12.0 * a;
    let mut domain =
        Domain::new(DVec3::ZERO, DVec3::splat(edge), [true; 3]).with_lees_edwards(rate);
    assert_eq!(domain.contact_velocity_gradient(), None, "the lab frame");
    domain.as_lees_edwards_mut().expect("sheared").dynamics = ShearDynamics::PeculiarContacts;
    let gradient = domain
        .contact_velocity_gradient()
        .expect("peculiar contacts subtract the mean flow");
    for (r, b) in [
        (
            DVec3::new(1e-3, 2e-3, 3e-3),
            DVec3::new(0.4e-3, 1.3e-3, -0.2e-3),
        ),
        (
            DVec3::new(5e-3, 7e-3, 1e-3),
            DVec3::new(-1e-3, -2.5e-3, 0.7e-3),
        ),
    ] {
        let expected = domain.mean_flow(r + b) - domain.mean_flow(r);
        assert!((gradient * b - expected).length() < 1e-15, "{b}");
    }
    let law = ContactLaw {
        normal: LinearNormal {
            stiffness: 100.0,
            damping: Damping::NONE,
        }
        .into(),
        tangential: Resistance {
            stiffness: 40.0,
            damping: Damping::NONE,
            mu_static: 10.0,
            mu_dynamic: 10.0,
        }
        .into(),
        rolling: Spring::NONE,
        torsion: Spring::NONE,
        adhesion: rheodem::contact::Adhesion::None,
    };
    let sliding_spring = |mean_flow| {
        let mut p = Particles::default();
        let d = 2.0 * a - overlap;
        for y in [4.0 * a, 4.0 * a + d] {
            let r = DVec3::new(6.0 * a, y, 6.0 * a);
            p.push(
                Sphere {
                    position: r,
                    velocity: domain.mean_flow(r),
                    angular_velocity: DVec3::ZERO,
                    radius: a,
                    species: 0,
                    motion: Motion::Free,
                },
                2500.0,
            );
        }
        let team = Team::new(1);
        let mut list = NeighborList::new(0.2 * a, 0.0);
        list.build(&mut p, &domain, &team, 0.0).expect("list");
        pair_forces::<()>(
            &mut p,
            &mut list,
            &ContactTable::uniform(1, law),
            &domain.image_transforms(),
            mean_flow,
            dt,
            &mut ForceScratch::default(),
            &team,
        );
        // The upper sphere (larger y) is pushed up by k_n δ and dragged back along x by the
        // sliding spring k_t ξ (ξ = the sliding displacement over one step).
        let upper = if p.position[0].y > p.position[1].y {
            0
        } else {
            1
        };
        (p.force[upper], 100.0 * overlap)
    };
    // The lab frame's spring force, and the rounding left of it when the mean flow's
    // difference is subtracted (`γ̇ y₁ − γ̇ y₂` against `γ̇ (y₁ − y₂)`: a few ulps).
    let slid = rate * (2.0 * a - overlap) * dt;
    let (f, normal) = sliding_spring(Some(gradient));
    assert!((f.y - normal).abs() < 1e-12 * normal, "{f}");
    assert!(
        f.x.abs() < 1e-9 * 40.0 * slid,
        "no sliding relative to the mean flow: {f}"
    );
    let (f, normal) = sliding_spring(None);
    assert!((f.y - normal).abs() < 1e-12 * normal, "{f}");
    assert!(
        (f.x + 40.0 * slid).abs() < 1e-9 * 40.0 * slid,
        "the lab frame slides at γ̇ d: {f} against {}",
        -40.0 * slid
    );
}
