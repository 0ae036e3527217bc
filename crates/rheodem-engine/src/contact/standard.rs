//! The contact laws of the standard throughput problem (BENCHMARKS.md; the problem itself
//! is built by the `rheodem` crate's `bench` module), in model units: the frictional law
//! and its cohesive variants. The force loop's tests use them too.

use super::normal::hertz::{HertzNormal, Material};
use super::spring::Mindlin;
use super::{
    Adhesion, ContactLaw, Damping, LawKind, LawSpec, LinearNormal, LudingNormal, NormalKind,
    Resistance, Spring, Strength,
};

/// The bench's contact law: `k_n = 10⁴`, `k_t = 2/7 k_n`, `γ_n = 27.6941 m_ij`, no
/// tangential damping, `μ = 0.5`.
pub fn bench_law() -> ContactLaw {
    ContactLaw {
        normal: LinearNormal {
            stiffness: 1.0e4,
            damping: Damping {
                per_mass: 27.6941,
                ..Damping::NONE
            },
        }
        .into(),
        tangential: Resistance {
            stiffness: 2857.142857,
            damping: Damping::NONE,
            mu_static: 0.5,
            mu_dynamic: 0.5,
        }
        .into(),
        rolling: Spring::NONE,
        torsion: Spring::NONE,
        adhesion: Adhesion::None,
    }
}

/// The bench's law with the normal law `kind` in place of the linear one, for the cost of
/// each normal law on the same problem (model units):
/// - `linear`: [`bench_law`];
/// - `hertz`: Hertz with `E = 1.82·10⁵`, `ν = 0.3` (`E* = 10⁵`, whose contact stiffness
///   `(4/3) E* √(R* δ)` is the linear `k_n = 10⁴` at `δ ≈ 0.02 d`, the steady state's
///   typical overlap), Tsuji's dashpot for `e = 0.8` (the linear law's restitution) and
///   Mindlin's sliding spring with `μ = 0.5` and no tangential dashpot;
/// - `luding`: Luding's law loading along the linear `k_n = 10⁴` with `k_p = 5·10⁴`,
///   `φ_f = 0.05`, no adhesive branch, the linear law's dashpot and sliding spring.
pub fn bench_law_with(kind: NormalKind) -> ContactLaw {
    let base = bench_law();
    match kind {
        NormalKind::Linear => base,
        NormalKind::Hertz => {
            let material = Material {
                youngs_modulus: 1.82e5,
                poisson_ratio: 0.3,
            };
            let hertz = HertzNormal::between(&material, &material, 0.8, 1.0);
            ContactLaw {
                normal: hertz.into(),
                tangential: Mindlin {
                    effective_shear_modulus: hertz.effective_shear_modulus,
                    dashpot: 0.0,
                    mu_static: 0.5,
                    mu_dynamic: 0.5,
                }
                .into(),
                ..base
            }
        }
        NormalKind::Luding => ContactLaw {
            normal: LudingNormal {
                stiffness: 1.0e4,
                max_stiffness: 5.0e4,
                adhesive_stiffness: 0.0,
                plasticity_depth: 0.05,
                damping: Damping {
                    per_mass: 27.6941,
                    ..Damping::NONE
                },
            }
            .into(),
            ..base
        },
    }
}

/// The adhesive strength of the standard problem's cohesive variants (model units; their
/// cost targets are in BENCHMARKS.md): `f_a^max = p d² = 185` for the mean pair (`Bo ≈ 1`
/// at the steady mean stress `p ≈ 185`, `d = 1`), a rupture distance `0.225 d` for laws
/// with a range of their own, `k_c = k_n` for the reversible law.
pub const BENCH_STRENGTH: Strength = Strength {
    max_force: 185.0,
    rupture_distance: 0.225,
    normal_stiffness: 1.0e4,
    mean_diameter: 1.0,
};

/// The adhesive law `kind` at the bench's strength ([`BENCH_STRENGTH`]); no adhesion for
/// [`LawKind::None`].
pub fn bench_adhesion(kind: LawKind) -> Adhesion {
    LawSpec::new(kind, kind.at_strength(&BENCH_STRENGTH))
        .build()
        .expect("the bench strength is valid for every law")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::adhesion::LAWS;

    #[test]
    fn every_law_at_the_bench_strength_pulls_the_mean_pair_with_its_max_force() {
        for law in LAWS {
            let adhesion = bench_adhesion(law.kind);
            let expected = if law.kind == LawKind::None {
                0.0
            } else {
                185.0
            };
            assert!(
                (adhesion.max_force(0.5, 0.5) - expected).abs() < 1e-12,
                "{}",
                law.name
            );
        }
        // The bench's earlier constants, bit for bit.
        let theta = 20f64.to_radians();
        assert_eq!(
            bench_adhesion(LawKind::LiquidBridge),
            Adhesion::LiquidBridge(crate::contact::LiquidBridge {
                surface_tension: 185.0 / (2.0 * std::f64::consts::PI * 0.5 * theta.cos()),
                contact_angle: theta,
                volume: (0.225 / (1.0 + 0.5 * theta)).powi(3),
            })
        );
    }
}
