//! The tables of Shi et al. 2020 shipped with the library (`data/shi2020/*.csv`, compiled in),
//! parsed once on first use.

use super::{CohesionFactor, FrictionDependence, MuLaw, PhiLaw, SetUp};
use serde::Deserialize;
use std::sync::LazyLock;

const TABLE3: &str = include_str!("../../data/shi2020/table3.csv");
const TABLE5: &str = include_str!("../../data/shi2020/table5.csv");
const TABLE7: &str = include_str!("../../data/shi2020/table7.csv");
const TABLE8: &str = include_str!("../../data/shi2020/table8.csv");

/// Rows of a shipped table (lines starting with `#` are comments).
fn rows<T: for<'de> Deserialize<'de>>(name: &str, text: &str) -> Vec<T> {
    csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .from_reader(text.as_bytes())
        .deserialize()
        .enumerate()
        .map(|(k, r)| r.unwrap_or_else(|e| panic!("shipped table {name}, row {}: {e}", k + 1)))
        .collect()
}

#[derive(Deserialize)]
struct Table3Row {
    mu_p: f64,
    phi_0: f64,
    #[serde(rename = "I_phi")]
    i_phi: f64,
    p_phi: f64,
}

#[derive(Deserialize)]
struct Table5Row {
    mu_p: f64,
    p1: f64,
    p2: f64,
    p3: f64,
    p4: f64,
}

#[derive(Deserialize)]
struct Table7Row {
    mu_p: f64,
    setup: String,
    mu_0: f64,
    mu_inf: f64,
    #[serde(rename = "I_mu")]
    i_mu: f64,
    p_mu: f64,
    alpha_1: Option<f64>,
    beta_1: Option<f64>,
    a_here: Option<f64>,
    a_ref52: Option<f64>,
}

#[derive(Deserialize)]
struct Table8Row {
    coefficient: String,
    #[serde(rename = "Q_inf")]
    q_inf: f64,
    #[serde(rename = "Q_0")]
    q_0: f64,
    mu_p0: f64,
    rms: f64,
}

static PHI_LAWS: LazyLock<Vec<PhiLaw>> = LazyLock::new(|| {
    let t3: Vec<Table3Row> = rows("table3.csv", TABLE3);
    let t5: Vec<Table5Row> = rows("table5.csv", TABLE5);
    assert_eq!(t3.len(), t5.len(), "tables 3 and 5 list the same μ_p");
    t3.iter()
        .zip(&t5)
        .map(|(a, b)| {
            assert_eq!(a.mu_p, b.mu_p, "tables 3 and 5 list the same μ_p");
            PhiLaw {
                mu_p: a.mu_p,
                phi_0: a.phi_0,
                i_phi: a.i_phi,
                p_phi: a.p_phi,
                gc: [b.p1, b.p2, b.p3, b.p4],
            }
        })
        .collect()
});

static MU_LAWS: LazyLock<Vec<MuLaw>> = LazyLock::new(|| {
    rows::<Table7Row>("table7.csv", TABLE7)
        .into_iter()
        .map(|r| {
            let (setup, cohesion) = match (r.setup.as_str(), r.alpha_1, r.beta_1, r.a_ref52) {
                ("SS", Some(alpha), Some(beta), _) => {
                    (SetUp::SimpleShear, CohesionFactor::Power { alpha, beta })
                }
                ("SB", None, None, Some(slope)) => {
                    (SetUp::SplitBottom, CohesionFactor::Linear { slope })
                }
                (s, ..) => panic!("table7.csv: row μ_p = {} ({s}) is incomplete", r.mu_p),
            };
            MuLaw {
                mu_p: r.mu_p,
                setup,
                mu_0: r.mu_0,
                mu_inf: r.mu_inf,
                i_mu: r.i_mu,
                p_mu: r.p_mu,
                cohesion,
                linear_slope: r.a_here,
            }
        })
        .collect()
});

/// The coefficient names of Table 8, in the order [`PhiLaw::from_friction_dependence`]
/// reads them.
const TABLE8_ORDER: [&str; 7] = ["phi_0", "I_phi", "p_phi", "p1", "p2", "p3", "p4"];

static FRICTION_DEPENDENCES: LazyLock<Vec<FrictionDependence>> = LazyLock::new(|| {
    let t8: Vec<Table8Row> = rows("table8.csv", TABLE8);
    TABLE8_ORDER
        .iter()
        .map(|&name| {
            let r = t8
                .iter()
                .find(|r| r.coefficient == name)
                .unwrap_or_else(|| panic!("table8.csv has no row {name}"));
            FrictionDependence {
                coefficient: name,
                q_inf: r.q_inf,
                q_0: r.q_0,
                mu_p0: r.mu_p0,
                rms: r.rms,
            }
        })
        .collect()
});

/// Shi et al. 2020, Table 3 (`μ_p, φ_0, I_φ, p*_φ`) joined with Table 5 (`p₁ … p₄`), simple
/// shear, in increasing `μ_p`.
pub fn phi_laws() -> &'static [PhiLaw] {
    &PHI_LAWS
}

/// Shi et al. 2020, Table 7: the simple-shear rows (`μ_p` = 0, 0.01, 0.5) and the
/// split-bottom row (`μ_p` = 0.01).
pub fn mu_laws() -> &'static [MuLaw] {
    &MU_LAWS
}

/// Shi et al. 2020, Table 8: the friction dependence (Eq. 1B) of `φ_0, I_φ, p*_φ, p₁ … p₄`,
/// in that order.
pub fn friction_dependences() -> &'static [FrictionDependence] {
    &FRICTION_DEPENDENCES
}
