//! The laws at one state point, with their sources and the regime (`rheodem predict`).

use super::{MuLaw, PhiLaw, Regime, SetUp, mu_laws};
use serde::Serialize;

/// One predicted quantity with where its coefficients come from.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Value {
    /// The value (dimensionless).
    pub value: f64,
    /// The equation and table it comes from.
    pub source: String,
}

/// The laws of Shi et al. 2020 evaluated at one state point.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Prediction {
    /// Interparticle friction `μ_p`.
    pub mu_p: f64,
    /// Inertial number `I`.
    pub inertial: f64,
    /// Softness `p*`.
    pub softness: f64,
    /// Bond number `Bo`.
    pub bond: f64,
    /// `φ` from the tabulated row (Tables 3 and 5), where `μ_p` has one.
    pub phi_table: Option<Value>,
    /// `φ` from the friction dependence of the coefficients (Eq. 1B, Table 8).
    pub phi_friction_law: Value,
    /// `Δφ = φ(Bo) − φ(0)`, from the tabulated row where there is one, else from Eq. 1B.
    pub delta_phi: Value,
    /// `μ` from Table 7, where `μ_p` has a simple-shear row.
    pub mu: Option<Value>,
    /// The regime of the phase diagram `μ_p` falls in.
    pub regime: Regime,
    /// Its description.
    pub regime_description: &'static str,
    /// Where the state point leaves the range the laws were fitted on.
    pub warnings: Vec<String>,
}

fn check(name: &str, v: f64, positive: bool) -> Result<(), String> {
    let ok = v.is_finite() && if positive { v > 0.0 } else { v >= 0.0 };
    if !ok {
        let range = if positive { "> 0" } else { ">= 0" };
        return Err(format!("{name} = {v}: must be a finite number {range}"));
    }
    Ok(())
}

/// The laws at `(μ_p, I, p*, Bo)`; an error names an argument outside its range
/// (`μ_p, p*, Bo ≥ 0`, `I > 0`, all finite).
pub fn predict(mu_p: f64, inertial: f64, softness: f64, bond: f64) -> Result<Prediction, String> {
    check("mu_p", mu_p, false)?;
    check("inertial", inertial, true)?;
    check("softness", softness, false)?;
    check("bond", bond, false)?;
    let (i, p, bo) = (inertial, softness, bond);
    let table = PhiLaw::for_mu_p(mu_p);
    let fitted = PhiLaw::from_friction_dependence(mu_p);
    let phi_table = table.map(|l| Value {
        value: l.phi(i, p, bo),
        source: format!("Eq. 16 with Tables 3 and 5, row μ_p = {}", l.mu_p),
    });
    let phi_friction_law = Value {
        value: fitted.phi(i, p, bo),
        source: "Eq. 16 with the coefficients of Eq. 1B, Table 8".into(),
    };
    let (law, which) = match table {
        Some(l) => (l, "Tables 3 and 5"),
        None => (fitted, "Eq. 1B, Table 8"),
    };
    let delta_phi = Value {
        value: law.delta_phi(i, p, bo),
        source: format!("Eq. 17 with {which}"),
    };
    let mu = MuLaw::for_mu_p(mu_p).map(|l| Value {
        value: l.mu(i, p, bo),
        source: format!("Eq. 1A with Table 7, simple-shear row μ_p = {}", l.mu_p),
    });
    let mut warnings = Vec::new();
    if i >= 0.25 {
        warnings.push(format!(
            "I = {i} ≥ 0.25: outside the range φ was fitted on (I < 0.25)"
        ));
    }
    if p >= 0.03 {
        warnings.push(format!(
            "p* = {p} ≥ 0.03: outside the range φ was fitted on (p* < 0.03)"
        ));
    }
    if mu.is_some() && !(0.005 < i && i < 0.5) {
        warnings.push(format!(
            "I = {i}: outside the range μ was fitted on (0.005 < I < 0.5)"
        ));
    }
    if mu.is_some() && p >= 0.1 {
        warnings.push(format!(
            "p* = {p} ≥ 0.1: outside the range μ was fitted on (p* < 0.1)"
        ));
    }
    if bo > 5.0 {
        warnings.push(format!(
            "Bo = {bo} > 5: beyond the data the laws were fitted on (Bo ≤ 5)"
        ));
    }
    if let Some(l) = MuLaw::for_mu_p(mu_p)
        && (1.0 + bo) * p >= l.p_mu
    {
        warnings.push(format!(
            "(1 + Bo) p* = {} ≥ p*_μ = {}: the softening factor of μ is not positive",
            (1.0 + bo) * p,
            l.p_mu
        ));
    }
    if mu_p > 1.0 {
        warnings.push(format!(
            "μ_p = {} > 1: beyond the paper's range 0 ≤ μ_p ≤ 1",
            mu_p
        ));
    }
    if mu.is_none() {
        let rows: Vec<String> = mu_laws()
            .iter()
            .filter(|l| l.setup == SetUp::SimpleShear)
            .map(|l| l.mu_p.to_string())
            .collect();
        warnings.push(format!(
            "no μ: Table 7 has simple-shear rows for μ_p = {} only",
            rows.join(", ")
        ));
    }
    let regime = Regime::of(mu_p);
    Ok(Prediction {
        mu_p,
        inertial: i,
        softness: p,
        bond: bo,
        phi_table,
        phi_friction_law,
        delta_phi,
        mu,
        regime,
        regime_description: regime.describe(),
        warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tabulated_point_uses_the_rows_and_warns_of_nothing() {
        let p = predict(0.5, 0.02, 0.01, 4.0).expect("valid");
        let row = PhiLaw::for_mu_p(0.5).expect("tabulated");
        assert_eq!(
            p.phi_table.as_ref().map(|v| v.value),
            Some(row.phi(0.02, 0.01, 4.0))
        );
        assert_eq!(p.delta_phi.value, row.delta_phi(0.02, 0.01, 4.0));
        let mu = MuLaw::for_mu_p(0.5).expect("tabulated").mu(0.02, 0.01, 4.0);
        assert_eq!(p.mu.as_ref().map(|v| v.value), Some(mu));
        assert_eq!(p.regime, Regime::Dilation);
        assert!(p.warnings.is_empty(), "{:?}", p.warnings);
    }

    #[test]
    fn untabulated_point_uses_the_friction_law_and_says_what_is_missing() {
        let p = predict(0.25, 0.3, 0.04, 6.0).expect("valid");
        assert!(p.phi_table.is_none() && p.mu.is_none());
        let law = PhiLaw::from_friction_dependence(0.25);
        assert_eq!(p.delta_phi.value, law.delta_phi(0.3, 0.04, 6.0));
        assert_eq!(p.regime, Regime::Reentrant);
        let all = p.warnings.join("\n");
        for needle in ["I = 0.3", "p* = 0.04", "Bo = 6", "no μ"] {
            assert!(all.contains(needle), "{needle} missing from {all}");
        }
    }

    #[test]
    fn bad_arguments_are_named() {
        for (args, name) in [
            ((-0.1, 0.02, 0.01, 0.0), "mu_p"),
            ((0.1, 0.0, 0.01, 0.0), "inertial"),
            ((0.1, 0.02, f64::NAN, 0.0), "softness"),
            ((0.1, 0.02, 0.01, -1.0), "bond"),
        ] {
            let e = predict(args.0, args.1, args.2, args.3).expect_err("invalid");
            assert!(e.starts_with(name), "{e}");
        }
    }
}
