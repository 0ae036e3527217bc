//! The rheology laws fitted by Shi et al. 2020 (docs/model.md §8) with the paper's
//! coefficients, for comparing simulations against them.
//!
//! Volume fraction (Shi et al. 2020, Eqs. 13–16):
//! `φ(I, p*, Bo) = φ_0 (1 − I/I_φ) (1 + (1+Bo) p*/p*_φ) g_c(Bo)`,
//! `g_c = 1 + p₁ Bo + p₂ Bo² + p₃ Bo³ + p₄ Bo⁴`.
//! Macroscopic friction (Shi et al. 2020, Eq. 1A):
//! `μ = μ_0 (1 + (μ_∞/μ_0 − 1)/(1 + I_μ/I)) (1 − sqrt((1+Bo) p*/p*_μ)) (1 + α₁ Bo^β₁)`.

use serde::Serialize;

/// Coefficients of the volume-fraction law for one `μ_p` (Shi et al. 2020, Tables 3 and 5).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PhiLaw {
    /// Interparticle friction coefficient `μ_p` the row belongs to (dimensionless).
    pub mu_p: f64,
    /// `φ_0`: volume fraction of the quasi-static, rigid, cohesionless limit.
    pub phi_0: f64,
    /// `I_φ`: inertial number over which `φ` falls linearly (dimensionless).
    pub i_phi: f64,
    /// `p*_φ`: softness over which `φ` grows linearly (dimensionless).
    pub p_phi: f64,
    /// `p₁ … p₄`: polynomial coefficients of the cohesion factor `g_c(Bo)`.
    pub gc: [f64; 4],
}

/// Coefficients of the friction law for one `μ_p` (Shi et al. 2020, Table 7, simple-shear
/// rows).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MuLaw {
    /// Interparticle friction coefficient `μ_p` the row belongs to (dimensionless).
    pub mu_p: f64,
    /// `μ_0`: macroscopic friction of the quasi-static, rigid, cohesionless limit.
    pub mu_0: f64,
    /// `μ_∞`: macroscopic friction approached at large inertial number.
    pub mu_inf: f64,
    /// `I_μ`: inertial number of the crossover from `μ_0` to `μ_∞`.
    pub i_mu: f64,
    /// `p*_μ`: softness scale of the softening factor; the law applies for
    /// `(1 + Bo) p* < p*_μ` only.
    pub p_mu: f64,
    /// `α₁`: amplitude of the cohesion factor `1 + α₁ Bo^β₁`.
    pub alpha: f64,
    /// `β₁`: exponent of the cohesion factor.
    pub beta: f64,
}

/// Shi et al. 2020, Table 3 (`μ_p, φ_0, I_φ, p*_φ`) joined with Table 5 (`p₁ … p₄`), simple
/// shear.
pub const PHI_LAWS: [PhiLaw; 11] = [
    PhiLaw {
        mu_p: 0.00,
        phi_0: 0.656,
        i_phi: 1.960,
        p_phi: 0.271,
        gc: [-0.0175, -0.0060, 0.0029, -0.0003],
    },
    PhiLaw {
        mu_p: 0.01,
        phi_0: 0.653,
        i_phi: 2.246,
        p_phi: 0.272,
        gc: [-0.0237, -0.0056, 0.0034, -0.0004],
    },
    PhiLaw {
        mu_p: 0.05,
        phi_0: 0.643,
        i_phi: 3.171,
        p_phi: 0.274,
        gc: [-0.0394, 0.0030, 0.0015, 0.0002],
    },
    PhiLaw {
        mu_p: 0.10,
        phi_0: 0.634,
        i_phi: 3.959,
        p_phi: 0.276,
        gc: [-0.0564, 0.0134, -0.0011, 0.00003],
    },
    PhiLaw {
        mu_p: 0.20,
        phi_0: 0.619,
        i_phi: 4.806,
        p_phi: 0.280,
        gc: [-0.0845, 0.0310, -0.0058, 0.0005],
    },
    PhiLaw {
        mu_p: 0.30,
        phi_0: 0.610,
        i_phi: 5.166,
        p_phi: 0.283,
        gc: [-0.1091, 0.0480, -0.0107, 0.0010],
    },
    PhiLaw {
        mu_p: 0.40,
        phi_0: 0.603,
        i_phi: 5.319,
        p_phi: 0.285,
        gc: [-0.1195, 0.0542, -0.0125, 0.0011],
    },
    PhiLaw {
        mu_p: 0.50,
        phi_0: 0.595,
        i_phi: 5.383,
        p_phi: 0.287,
        gc: [-0.1359, 0.0668, -0.0162, 0.0015],
    },
    PhiLaw {
        mu_p: 0.70,
        phi_0: 0.591,
        i_phi: 5.422,
        p_phi: 0.291,
        gc: [-0.1516, 0.0779, -0.0195, 0.0018],
    },
    PhiLaw {
        mu_p: 0.90,
        phi_0: 0.585,
        i_phi: 5.429,
        p_phi: 0.293,
        gc: [-0.1494, 0.0733, -0.0176, 0.0016],
    },
    PhiLaw {
        mu_p: 1.00,
        phi_0: 0.583,
        i_phi: 5.430,
        p_phi: 0.293,
        gc: [-0.1511, 0.0746, -0.0181, 0.0017],
    },
];

/// Shi et al. 2020, Table 7, simple-shear rows (`μ_p` = 0, 0.01, 0.5).
pub const MU_LAWS: [MuLaw; 3] = [
    MuLaw {
        mu_p: 0.00,
        mu_0: 0.1432,
        mu_inf: 0.3281,
        i_mu: 0.0645,
        p_mu: 0.4222,
        alpha: 0.3136,
        beta: 1.6475,
    },
    MuLaw {
        mu_p: 0.01,
        mu_0: 0.1645,
        mu_inf: 0.3499,
        i_mu: 0.0818,
        p_mu: 0.4950,
        alpha: 0.4490,
        beta: 1.5218,
    },
    MuLaw {
        mu_p: 0.50,
        mu_0: 0.3530,
        mu_inf: 0.7148,
        i_mu: 0.7184,
        p_mu: 0.3905,
        alpha: 0.2551,
        beta: 1.5125,
    },
];

impl PhiLaw {
    /// The paper's row for `μ_p` (exact match within 1e-9), if tabulated.
    pub fn for_mu_p(mu_p: f64) -> Option<PhiLaw> {
        PHI_LAWS
            .iter()
            .copied()
            .find(|l| (l.mu_p - mu_p).abs() < 1e-9)
    }

    /// Cohesive correction `g_c(Bo)`.
    pub fn g_c(&self, bond: f64) -> f64 {
        let [p1, p2, p3, p4] = self.gc;
        1.0 + bond * (p1 + bond * (p2 + bond * (p3 + bond * p4)))
    }

    /// `φ(I, p*, Bo)` (Shi et al. 2020, Eq. 16).
    pub fn phi(&self, inertial: f64, softness: f64, bond: f64) -> f64 {
        self.phi_0
            * (1.0 - inertial / self.i_phi)
            * (1.0 + (1.0 + bond) * softness / self.p_phi)
            * self.g_c(bond)
    }
}

impl MuLaw {
    /// The paper's row for `μ_p` (exact match within 1e-9), if tabulated.
    pub fn for_mu_p(mu_p: f64) -> Option<MuLaw> {
        MU_LAWS
            .iter()
            .copied()
            .find(|l| (l.mu_p - mu_p).abs() < 1e-9)
    }

    /// `μ(I, p*, Bo)` (Shi et al. 2020, Eq. 1A), dimensionless. Meaningful for
    /// `(1 + Bo) p* < p*_μ`; beyond it the softening factor, and the result, turn negative.
    pub fn mu(&self, inertial: f64, softness: f64, bond: f64) -> f64 {
        let f_i = 1.0 + (self.mu_inf / self.mu_0 - 1.0) / (1.0 + self.i_mu / inertial);
        let f_p = 1.0 - ((1.0 + bond) * softness / self.p_mu).sqrt();
        let f_c = 1.0 + self.alpha * bond.powf(self.beta);
        self.mu_0 * f_i * f_p * f_c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_points() {
        // μ_p = 0.5, I = 0.02, p* = 0.01: 0.595 (1 − 0.02/5.383)(1 + 0.01/0.287).
        let phi = PhiLaw::for_mu_p(0.5)
            .expect("tabulated")
            .phi(0.02, 0.01, 0.0);
        assert!((phi - 0.595 * (1.0 - 0.02 / 5.383) * (1.0 + 0.01 / 0.287)).abs() < 1e-15);
        assert!((phi - 0.61342).abs() < 1e-4);
        let g = PhiLaw::for_mu_p(0.01).expect("tabulated").g_c(2.0);
        assert!((g - (1.0 - 0.0474 - 0.0224 + 0.0272 - 0.0064)).abs() < 1e-12);
        let mu = MuLaw::for_mu_p(0.01)
            .expect("tabulated")
            .mu(0.02, 0.01, 0.0);
        assert!((mu - 0.1724).abs() < 1e-3, "{mu}");
    }
}
