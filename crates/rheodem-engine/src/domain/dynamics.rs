//! How a box with a mean flow moves its particles and what their stored velocities mean:
//! the three shear dynamics of the Lees-Edwards box (docs/model.md §4.3–4.5).

use serde::{Deserialize, Serialize};

/// How a Lees-Edwards box moves its particles and what their stored velocities mean
/// (docs/model.md §4.3–4.5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ShearDynamics {
    /// Lab frame (the default, §4.3): velocities are full velocities, `dv/dt = F/m`; images
    /// across `y` move `±γ̇ L_y` along `x`, and contacts see the full relative velocity.
    #[default]
    Lab,
    /// The lab-frame dynamics, but every contact subtracts the mean-flow difference
    /// `γ̇ l_y x̂` of its two particles from its relative velocity (§4.4), for comparison.
    PeculiarContacts,
    /// Affine drag (§4.5, the dynamics of the source papers' code): velocities `c` are
    /// relative to the mean flow and obey `dc/dt = F/m`; every free particle is moved by
    /// `(c + γ̇ (y − lo_y) x̂) dt`; images carry no velocity jump and contacts see
    /// `c_i − c_j`.
    AffineDrag,
}

impl ShearDynamics {
    /// Every option, in the order of the documentation.
    pub const ALL: [ShearDynamics; 3] = [
        ShearDynamics::Lab,
        ShearDynamics::PeculiarContacts,
        ShearDynamics::AffineDrag,
    ];

    /// The name used in scenario files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ShearDynamics::Lab => "lab",
            ShearDynamics::PeculiarContacts => "peculiar-contacts",
            ShearDynamics::AffineDrag => "affine-drag",
        }
    }
}

impl std::fmt::Display for ShearDynamics {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for ShearDynamics {
    type Err = String;

    fn from_str(s: &str) -> Result<ShearDynamics, String> {
        ShearDynamics::ALL
            .into_iter()
            .find(|d| d.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown shear dynamics {s:?}: expected lab, peculiar-contacts or affine-drag"
                )
            })
    }
}

/// Reads a name (`"affine-drag"`), or the boolean of the older key `peculiar_contacts`
/// (`true` = [`ShearDynamics::PeculiarContacts`], `false` = [`ShearDynamics::Lab`]), so that
/// files written before the three options existed still read the same.
impl<'de> Deserialize<'de> for ShearDynamics {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<ShearDynamics, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = ShearDynamics;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("\"lab\", \"peculiar-contacts\" or \"affine-drag\"")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<ShearDynamics, E> {
                v.parse().map_err(E::custom)
            }
            fn visit_bool<E: serde::de::Error>(self, v: bool) -> Result<ShearDynamics, E> {
                Ok(if v {
                    ShearDynamics::PeculiarContacts
                } else {
                    ShearDynamics::Lab
                })
            }
        }
        d.deserialize_any(Visitor)
    }
}
