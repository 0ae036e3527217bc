//! A species pair's contact law resolved once for the pair loop.
//!
//! [`ContactLaw`] is the law as stored and serialised: its parts say what they are
//! (`Adhesion::LiquidBridge(LiquidBridge { surface_tension, contact_angle, volume })`). The pair loop needs
//! other numbers: `2π γ_s cos θ`, the rupture distance `(1 + θ/2) V_b^{1/3}`, `1/V_b`, and
//! which parts act at all. A [`PairKernel`] holds them, derived from the law when a
//! [`super::ContactTable`] is built or changed and never serialised, so that nothing fixed
//! per run is recomputed or re-tested per contact. It is the single implementation of the
//! contact law: [`ContactLaw::interact`] resolves the law and calls it.

use super::adhesion::ResolvedAdhesion;
use super::lanes::{Real, V3};
use super::normal::{NormalForce, ResolvedNormal};
use super::spring::{Sliding, Spring};
use super::{ContactHistory, ContactLaw, PairForce, PairKinematics};

/// A species pair's contact law with every per-run constant resolved (see the module
/// documentation). Units as in [`ContactLaw`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairKernel {
    /// The normal law with its constants.
    normal: ResolvedNormal,
    /// Sliding resistance, used when `sliding` is set.
    tangential: Spring,
    /// Rolling resistance, used when `rolling_on` is set.
    rolling: Spring,
    /// Torsion resistance, used when `torsion_on` is set.
    torsion: Spring,
    /// Whether sliding friction acts at all.
    sliding: bool,
    /// Whether rolling resistance acts at all.
    rolling_on: bool,
    /// Whether torsion resistance acts at all.
    torsion_on: bool,
    /// The adhesive law with its constants.
    adhesion: ResolvedAdhesion,
}

impl PairKernel {
    /// Resolves `law`.
    pub fn new(law: &ContactLaw) -> PairKernel {
        PairKernel {
            normal: law.normal.resolve(),
            tangential: law.tangential,
            rolling: law.rolling,
            torsion: law.torsion,
            sliding: law.tangential.is_active(),
            rolling_on: law.rolling.is_active(),
            torsion_on: law.torsion.is_active(),
            adhesion: law.adhesion.resolve(),
        }
    }

    /// Interaction range beyond contact (m).
    #[inline(always)]
    pub fn range(&self) -> f64 {
        self.adhesion.range()
    }

    /// Whether the law acts on pairs apart (any adhesion).
    #[inline(always)]
    pub fn acts_apart(&self) -> bool {
        !self.adhesion.is_none()
    }

    /// Evaluates a pair at any overlap and advances its history over `dt` (s); `None` when
    /// the pair does not interact (its history is then reset). See [`ContactLaw::interact`].
    #[inline(always)]
    pub fn interact(
        &self,
        k: &PairKinematics,
        h: &mut ContactHistory,
        dt: f64,
    ) -> Option<PairForce> {
        if k.overlap >= 0.0 {
            Some(self.touching(k, h, dt))
        } else {
            self.apart(k, h)
        }
    }

    /// Evaluates a pair apart (`overlap < 0`): the springs relax and only the adhesive law
    /// (and its bridge) may act; `None` when the pair does not interact.
    #[inline(always)]
    pub fn apart(&self, k: &PairKinematics, h: &mut ContactHistory) -> Option<PairForce> {
        let bridge = h.bridge;
        *h = ContactHistory::default();
        if self.adhesion.is_none() {
            return None;
        }
        let (f_a, alive) = self
            .adhesion
            .separated_force(-k.overlap, k.radius_i, k.radius_j, bridge);
        h.bridge = alive;
        (f_a != 0.0).then(|| PairForce {
            force: k.normal * f_a,
            adhesive: f_a,
            ..PairForce::default()
        })
    }

    /// Evaluates a touching pair (`overlap ≥ 0`) and advances its history over `dt` (s).
    /// The Coulomb limits use the repulsive part `|k_n δ + γ_n δ̇|` alone.
    #[inline(always)]
    pub fn touching(&self, k: &PairKinematics, h: &mut ContactHistory, dt: f64) -> PairForce {
        let pair = Touch {
            normal: V3::from_glam(k.normal),
            overlap: k.overlap,
            radius_i: k.radius_i,
            radius_j: k.radius_j,
            velocity: V3::from_glam(k.velocity),
            omega_i: V3::from_glam(k.omega_i),
            omega_j: V3::from_glam(k.omega_j),
            reduced_mass: k.reduced_mass,
        };
        let mut springs = HistoryLanes {
            tangential: V3::from_glam(h.tangential),
            rolling: V3::from_glam(h.rolling),
            torsion: V3::from_glam(h.torsion),
            state: h.state,
            sliding_state: h.sliding_state,
        };
        let f = if k.radius_j.is_finite() {
            self.touching_lanes::<f64, false>(&pair, &mut springs, dt)
        } else {
            self.touching_lanes::<f64, true>(&pair, &mut springs, dt)
        };
        h.tangential = springs.tangential.to_glam();
        h.rolling = springs.rolling.to_glam();
        h.torsion = springs.torsion.to_glam();
        h.state = springs.state;
        h.sliding_state = springs.sliding_state;
        if self.needs_bridge() {
            h.bridge = true;
        }
        PairForce {
            force: f.force.to_glam(),
            torque_i: f.torque_i.to_glam(),
            torque_j: f.torque_j.to_glam(),
            repulsive: f.repulsive,
            adhesive: f.adhesive,
            sliding: f.sliding,
        }
    }

    /// [`PairKernel::apart`]'s adhesive force (N, ≤ 0) in lanes, at separation `s` (m), with
    /// whether each bridge survives; `bridge` says which bridges exist.
    #[inline(always)]
    pub fn apart_lanes<R: Real, const WALL: bool>(
        &self,
        s: R,
        radius_i: R,
        radius_j: R,
        bridge: R::Mask,
    ) -> (R, R::Mask) {
        self.adhesion
            .separated_force_lanes::<R, WALL>(s, radius_i, radius_j, bridge)
    }

    /// Elastic energy (J) stored in a pair at overlap `δ` (m, either sign) with history `h`:
    /// the springs' `½ k x²` while touching, plus the adhesive potential. See
    /// [`ContactLaw::elastic_energy`].
    pub fn elastic_energy(&self, overlap: f64, a_i: f64, a_j: f64, h: &ContactHistory) -> f64 {
        self.spring_energy(overlap, a_i, a_j, h)
            + self.adhesive_potential(overlap, a_i, a_j, h.bridge)
    }

    /// The adhesive potential (J, ≤ 0) of the pair at overlap `δ` (m) for radii `a_i`,
    /// `a_j` (m) and bridge flag `bridge`: the part of [`PairKernel::elastic_energy`] that
    /// is not in the springs.
    pub fn adhesive_potential(&self, overlap: f64, a_i: f64, a_j: f64, bridge: bool) -> f64 {
        self.adhesion.potential(overlap, a_i, a_j, bridge)
    }

    /// Energy (J, ≥ 0) of the pair's springs alone at overlap `δ` (m) between radii `a_i`,
    /// `a_j` (m) with history `h`: the normal law's energy and the three springs' while
    /// touching (`½ k_n δ² + ½ k_t |ξ_t|² + ½ k_r |ξ_r|² + ½ k_o |ξ_o|²` for linear laws),
    /// zero apart — the repulsive part of [`PairKernel::elastic_energy`], without the
    /// adhesive potential.
    pub fn spring_energy(&self, overlap: f64, a_i: f64, a_j: f64, h: &ContactHistory) -> f64 {
        if overlap > 0.0 {
            self.normal.energy(overlap, a_i, a_j, h.state)
                + self.tangential.energy(h.tangential, overlap, a_i, a_j)
                + self.rolling.energy(h.rolling, overlap, a_i, a_j)
                + self.torsion.energy(h.torsion, overlap, a_i, a_j)
        } else {
            0.0
        }
    }

    /// Whether a bridge forms at contact (irreversible adhesive laws).
    #[inline(always)]
    pub fn needs_bridge(&self) -> bool {
        self.adhesion.needs_bridge()
    }

    /// Whether the normal law keeps a per-contact state ([`NormalForce::KEEPS_STATE`]).
    #[inline(always)]
    pub fn keeps_state(&self) -> bool {
        self.normal.keeps_state()
    }

    /// Whether the sliding spring's law keeps a per-contact state
    /// ([`super::spring::SpringModel::KEEPS_STATE`]).
    #[inline(always)]
    pub fn sliding_keeps_state(&self) -> bool {
        self.sliding && self.tangential.keeps_state()
    }

    /// Whether the law has rolling or torsion resistance (springs beyond the sliding one).
    #[inline(always)]
    pub fn resists_rotation(&self) -> bool {
        self.rolling_on || self.torsion_on
    }

    /// [`PairKernel::touching`] in lanes, for pairs of spheres or (`WALL`) a sphere on a
    /// wall (`radius_j` then unused). The torques on `j` are zero against a wall.
    #[inline(always)]
    pub fn touching_lanes<R: Real, const WALL: bool>(
        &self,
        k: &Touch<R>,
        springs: &mut HistoryLanes<R>,
        dt: f64,
    ) -> TouchForce<R> {
        self.touching_lanes_with::<R, WALL, _, _>(&self.normal, &self.tangential, k, springs, dt)
    }

    /// The kernel's sliding spring (for [`Spring::with`]).
    #[inline(always)]
    pub fn tangential(&self) -> &Spring {
        &self.tangential
    }

    /// The kernel's normal law, resolved (for [`ResolvedNormal::with`]).
    #[inline(always)]
    pub fn normal(&self) -> &ResolvedNormal {
        &self.normal
    }

    /// [`PairKernel::touching_lanes`] with the kernel's normal law given as `normal` and its
    /// sliding spring as `sliding`, each its own type, so that the caller's code is compiled
    /// for those laws alone.
    #[inline(always)]
    pub fn touching_lanes_with<R: Real, const WALL: bool, N: NormalForce, T: Sliding>(
        &self,
        normal: &N,
        sliding: &T,
        k: &Touch<R>,
        springs: &mut HistoryLanes<R>,
        dt: f64,
    ) -> TouchForce<R> {
        let n = k.normal;
        let half = R::splat(0.5);
        let lever_i = k.radius_i - half * k.overlap;
        let lever_j = k.radius_j - half * k.overlap;
        let overlap_rate = -k.velocity.dot(n);
        let normal = normal.force_lanes::<R, WALL>(k, overlap_rate, &mut springs.state);
        let f_rep = normal.repulsive;
        let limit_ref = f_rep.abs();
        let mut f_a = self
            .adhesion
            .contact_force_lanes::<R, WALL>(k.radius_i, k.radius_j);
        if let Some(own) = normal.adhesive {
            f_a = f_a + own;
        }
        let mut out = TouchForce {
            force: n.scale(f_rep + f_a),
            torque_i: V3::zero(),
            torque_j: V3::zero(),
            repulsive: f_rep,
            adhesive: f_a,
            sliding: R::all(false),
        };

        if self.sliding {
            // Relative velocity of the two surfaces at the contact point (middle of the
            // overlap), in the tangent plane.
            let spin = if WALL {
                k.omega_i.scale(lever_i)
            } else {
                k.omega_i.scale(lever_i) + k.omega_j.scale(lever_j)
            };
            let v_contact = k.velocity - spin.cross(n);
            let v_t = v_contact - n.scale(n.dot(v_contact));
            let (f_t, slip) = sliding.slide(
                &mut springs.tangential,
                n,
                v_t,
                k,
                limit_ref,
                dt,
                &mut springs.sliding_state,
            );
            let arm = n.cross(f_t);
            out.force = out.force + f_t;
            out.torque_i = arm.scale(-lever_i);
            if !WALL {
                out.torque_j = arm.scale(-lever_j);
            }
            out.sliding = slip;
        }

        if self.rolling_on || self.torsion_on {
            let a_eff = if WALL {
                k.radius_i
            } else {
                k.radius_i * k.radius_j / (k.radius_i + k.radius_j)
            };
            let w_rel = k.omega_i - k.omega_j;
            if self.rolling_on {
                let v_r = w_rel.cross(n).scale(-a_eff);
                // A rolling spring keeps no state (scenarios refuse laws that would).
                let mut no_state = R::splat(0.0);
                let (f_r, _) = self.rolling.in_plane_lanes(
                    &mut springs.rolling,
                    n,
                    v_r,
                    k,
                    limit_ref,
                    dt,
                    &mut no_state,
                );
                let t = n.cross(f_r).scale(-a_eff);
                out.torque_i = out.torque_i + t;
                out.torque_j = out.torque_j - t;
            }
            if self.torsion_on {
                let v_o = n.scale(a_eff * w_rel.dot(n));
                let (f_o, _) =
                    self.torsion
                        .along_normal_lanes(&mut springs.torsion, n, v_o, k, limit_ref, dt);
                let t = f_o.scale(a_eff);
                out.torque_i = out.torque_i + t;
                out.torque_j = out.torque_j - t;
            }
        }
        out
    }
}

/// A touching pair as the kernel sees it from `i`, in lanes (units as in
/// [`PairKinematics`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Touch<R> {
    /// Unit normal from `j` to `i`.
    pub normal: V3<R>,
    /// Overlap `δ ≥ 0` (m).
    pub overlap: R,
    /// Radius of `i` (m).
    pub radius_i: R,
    /// Radius of `j` (m).
    pub radius_j: R,
    /// `v_i − v_j` (m/s).
    pub velocity: V3<R>,
    /// Angular velocity of `i` (rad/s).
    pub omega_i: V3<R>,
    /// Angular velocity of `j` (rad/s).
    pub omega_j: V3<R>,
    /// Reduced mass (kg).
    pub reduced_mass: R,
}

/// A touching contact's history in lanes: the three springs (m) and the laws' states
/// (see [`ContactHistory`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct HistoryLanes<R> {
    /// Sliding spring.
    pub tangential: V3<R>,
    /// Rolling spring.
    pub rolling: V3<R>,
    /// Torsion spring.
    pub torsion: V3<R>,
    /// The normal law's per-contact state (zero under a law that keeps none).
    pub state: R,
    /// The sliding spring law's per-contact state (zero under a law that keeps none).
    pub sliding_state: R,
}

/// What [`PairKernel::touching_lanes`] returns: forces and torques on `i` (N, N m), the
/// torque on `j`, the repulsive and adhesive normal forces (N) and whether the sliding
/// spring slipped.
#[derive(Clone, Copy, Debug)]
pub struct TouchForce<R: Real> {
    /// Force on `i`; `j` receives its negative.
    pub force: V3<R>,
    /// Torque on `i`.
    pub torque_i: V3<R>,
    /// Torque on `j`.
    pub torque_j: V3<R>,
    /// `k_n δ + γ_n δ̇`.
    pub repulsive: R,
    /// Adhesive normal force (≤ 0).
    pub adhesive: R,
    /// Whether the sliding spring slipped.
    pub sliding: R::Mask,
}
