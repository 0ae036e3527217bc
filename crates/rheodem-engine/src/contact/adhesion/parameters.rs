//! The parameters of adhesive laws as scenario files, options and set-ups give them: a law
//! by name with its values ([`LawSpec`]), the parameters both linear laws share, and a
//! set-up's strength ([`Strength`]).

use super::super::parameters::{Bounds, LawError, Parameter, Parameters, Registered, Spec};
use super::{Adhesion, LawKind};

/// The parameters of a linear adhesive law (reversible or irreversible): `f_a^max` and
/// either the stiffness `k_c` or the range `f_a^max / k_c` (read by [`Parameters::linear`]).
pub const LINEAR_LAW_PARAMETERS: &[Parameter] = &[
    Parameter {
        key: "max_force",
        unit: "N",
        meaning: "maximum adhesive force f_a^max",
        bounds: Bounds::Positive,
        default: None,
        note: "",
        instead_of: None,
    },
    Parameter {
        key: "stiffness",
        unit: "N/m",
        meaning: "adhesive stiffness k_c of the separation branch (or give `range`)",
        bounds: Bounds::Positive,
        default: None,
        note: "",
        instead_of: None,
    },
    Parameter {
        key: "range",
        unit: "m",
        meaning: "separation f_a^max / k_c where the attraction ends (instead of `stiffness`)",
        bounds: Bounds::Positive,
        default: None,
        note: "",
        instead_of: Some("stiffness"),
    },
];

/// `f_max` and `k_c` of a linear law given `max_force` and one of `stiffness` (N/m) or
/// `range` (m, `k_c = f_max / range`).
pub fn linear_law(p: &Parameters<'_>) -> Result<(f64, f64), LawError> {
    p.check_keys()?;
    let f = p.require("max_force")?;
    let stiffness = p.get("stiffness")?;
    let range = p.get("range")?;
    match (stiffness, range) {
        (Some(_), Some(_)) => Err(LawError {
            key: String::new(),
            value: "stiffness and range".into(),
            reason: "give at most one of stiffness, range".into(),
        }),
        (Some(k), None) => Ok((f, k)),
        (None, Some(r)) => Ok((f, f / r)),
        (None, None) => Err(LawError {
            key: "stiffness".into(),
            value: "(missing)".into(),
            reason: "give `stiffness` (N/m) or `range` (m)".into(),
        }),
    }
}

/// A set-up's adhesive strength, from which each law derives its parameters
/// ([`super::AdhesiveLaw::at_strength`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Strength {
    /// `f_a^max` (N) of the mean pair (two particles of diameter `mean_diameter`).
    pub max_force: f64,
    /// Rupture distance (m) of a law with a range of its own.
    pub rupture_distance: f64,
    /// Normal contact stiffness `k_n` (N/m).
    pub normal_stiffness: f64,
    /// Mean particle diameter `d_p` (m).
    pub mean_diameter: f64,
}

/// An adhesive law by name with its parameters, as a scenario file or set-up writes it:
/// `{ law = "liquid_bridge", surface_tension = 0.02, contact_angle_deg = 20, volume = 75e-12 }`.
/// The name may be an alias; it is written back under the law's own name.
pub type LawSpec = Spec<LawKind>;

impl Spec<LawKind> {
    /// The law with its parameters checked.
    pub fn build(&self) -> Result<Adhesion, LawError> {
        self.law.build(&self.parameters())
    }
}

impl Registered for LawKind {
    const WHAT: &'static str = "adhesive law";
    const DEFAULT: Option<LawKind> = None;

    fn from_name(name: &str) -> Result<LawKind, String> {
        LawKind::from_name(name).map_err(|e| format!("{} {}", e.value, e.reason))
    }

    fn name(self) -> &'static str {
        LawKind::name(self)
    }

    fn parameters(self) -> &'static [Parameter] {
        self.info().parameters
    }
}
