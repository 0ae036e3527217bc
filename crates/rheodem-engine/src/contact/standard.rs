//! The contact laws of the standard throughput problem (BENCHMARKS.md; the problem itself
//! is built by the `rheodem` crate's `bench` module), in model units: the frictional law
//! and its cohesive variants. The force loop's tests use them too.

use super::{Adhesion, ContactLaw, Damping, NormalLaw, Resistance};

/// The bench's contact law: `k_n = 10⁴`, `k_t = 2/7 k_n`, `γ_n = 27.6941 m_ij`, no
/// tangential damping, `μ = 0.5`.
pub fn bench_law() -> ContactLaw {
    ContactLaw {
        normal: NormalLaw {
            stiffness: 1.0e4,
            damping: Damping {
                per_mass: 27.6941,
                ..Damping::NONE
            },
        },
        tangential: Resistance {
            stiffness: 2857.142857,
            damping: Damping::NONE,
            mu_static: 0.5,
            mu_dynamic: 0.5,
        },
        rolling: Resistance::NONE,
        torsion: Resistance::NONE,
        adhesion: Adhesion::None,
    }
}

/// Cohesion variants of the standard problem (their cost targets are in BENCHMARKS.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchCohesion {
    /// The plain frictional law.
    None,
    /// Reversible adhesion, `f_a^max = p d² = 185` (`Bo ≈ 1` at the steady mean stress
    /// `p ≈ 185`, `d = 1`), `k_c = k_n`.
    Reversible,
    /// Willett bridges with the same `f_a^max` for the mean pair (`r = 0.5`, `θ = 20°`) and
    /// `S_c = 0.225 d`.
    LiquidBridge,
}

/// `f_a^max` of the cohesive variants (model units).
const BENCH_MAX_FORCE: f64 = 185.0;

impl BenchCohesion {
    /// The adhesive law of the variant.
    pub fn adhesion(self) -> Adhesion {
        match self {
            BenchCohesion::None => Adhesion::None,
            BenchCohesion::Reversible => Adhesion::Reversible {
                max_force: BENCH_MAX_FORCE,
                stiffness: 1.0e4,
            },
            BenchCohesion::LiquidBridge => {
                let theta = 20f64.to_radians();
                Adhesion::LiquidBridge {
                    surface_tension: BENCH_MAX_FORCE
                        / (2.0 * std::f64::consts::PI * 0.5 * theta.cos()),
                    contact_angle: theta,
                    volume: (0.225 / (1.0 + 0.5 * theta)).powi(3),
                }
            }
        }
    }
}
