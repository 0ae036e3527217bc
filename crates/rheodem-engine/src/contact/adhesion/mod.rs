//! Adhesive (cohesive) normal forces, added to the repulsive normal force (docs/model.md
//! §2.4–2.6), and the registry of adhesive laws.
//!
//! Forces are positive when repulsive, so every adhesive force here is ≤ 0. The separation
//! of two surfaces is `S = −δ` (m). Each law is one file implementing [`AdhesiveLaw`]:
//! its name and aliases, its parameters with units and allowed ranges, its constants
//! resolved once per run, and the force touching and apart in lanes ([`ResolvedLaw`]).
//! The [`adhesive_laws!`] line below registers them; it generates the [`Adhesion`] enum the
//! contact law stores, the [`ResolvedAdhesion`] enum the pair loop matches on (one
//! predictable branch per contact, no dynamic dispatch), the [`LawKind`] names every
//! scenario file, option and set-up accepts, and the list [`LAWS`]. No other file lists
//! the laws.
//!
//! Registered laws:
//! - [`Reversible`]: dry, van der Waals type; `−f_max` in contact, rising linearly to zero
//!   at `S = δ_a = f_max / k_c`, the same on approach and separation.
//! - [`LiquidBridge`]: wet, Willett's capillary force, formed at contact, ruptured past
//!   `S_c = (1 + θ/2) V_b^{1/3}`.
//! - [`LinearIrreversible`]: the bridge's loading path with a linear separation branch
//!   `−(f_max − k_c S)`, rupture at `S_c = f_max / k_c`.
//! - [`Rabinovich`]: wet, Rabinovich's capillary force of a fixed-volume bridge with its
//!   filling-angle term, formed at contact, ruptured past `S_c = (1 + θ/2) V_b^{1/3}`.
//!
//! Adding a law: write one file beside these with a parameter struct implementing
//! [`AdhesiveLaw`] and its resolved form implementing [`ResolvedLaw`], declare the module
//! below, and add one line to the `adhesive_laws!` invocation. Its per-contact state is the
//! bridge flag when [`AdhesiveLaw::FORMS_BRIDGES`] is set, none otherwise.

pub mod linear_irreversible;
pub mod parameters;
pub mod rabinovich;
pub mod reversible;
pub mod willett;

pub use super::parameters::{Bounds, LawError, Parameter, Parameters, Spec};
pub use linear_irreversible::LinearIrreversible;
pub use parameters::{LawSpec, Strength};
pub use rabinovich::Rabinovich;
pub use reversible::Reversible;
pub use willett::{LiquidBridge, willett_factor};

use super::lanes::Real;
use super::names;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::fmt::Debug;

/// An adhesive law as scenario files and set-ups give it: its parameters in SI units.
pub trait AdhesiveLaw: Copy + Debug + PartialEq + Serialize + DeserializeOwned {
    /// The name scenario files, options and results use (`snake_case`).
    const NAME: &'static str;
    /// Other spellings accepted for the name (kebab-case is always accepted too).
    const ALIASES: &'static [&'static str];
    /// One line saying what the law is, with its source.
    const SUMMARY: &'static str;
    /// The parameters a scenario file gives, in the order of the law's documentation.
    const PARAMETERS: &'static [Parameter];
    /// Whether a bridge forms at contact and outlives it until it ruptures (irreversible
    /// laws); such a law's per-contact state is the bridge flag.
    const FORMS_BRIDGES: bool;
    /// The law with its per-run constants computed, as the pair loop uses it.
    type Resolved: ResolvedLaw;

    /// The law from named parameter values (checked against [`Self::PARAMETERS`]).
    fn from_parameters(p: &Parameters<'_>) -> Result<Self, LawError>;

    /// The parameters (in the units of [`Self::PARAMETERS`]) that give the law at a
    /// set-up's strength: `f_a^max` of the mean pair and, for a law with a range of its
    /// own, the rupture distance.
    fn at_strength(s: &Strength) -> Vec<(&'static str, f64)>;

    /// The law with its constants resolved.
    fn resolve(&self) -> Self::Resolved;
}

/// An adhesive law with its per-run constants computed: what the pair loop evaluates.
/// `WALL` marks a sphere on a planar wall (`a_j` unused).
pub trait ResolvedLaw: Copy + Debug + PartialEq {
    /// Range of the attraction beyond contact (m).
    fn range(&self) -> f64;

    /// `f_a^max` (N) of a pair of radii `a_i`, `a_j` (m).
    fn max_force(&self, a_i: f64, a_j: f64) -> f64;

    /// Adhesive force (N, ≤ 0) of a touching pair, in lanes.
    fn contact_force_lanes<R: Real, const WALL: bool>(&self, a_i: R, a_j: R) -> R;

    /// Adhesive force (N, ≤ 0) at separation `s ≥ 0` (m), in lanes, and whether each
    /// bridge survives; `bridge` says which bridges exist (ignored by reversible laws).
    fn separated_force_lanes<R: Real, const WALL: bool>(
        &self,
        s: R,
        a_i: R,
        a_j: R,
        bridge: R::Mask,
    ) -> (R, R::Mask);

    /// `∫_s^{range} f_a dS` (J, ≤ 0) for `0 ≤ s < range`: the work the attraction still
    /// does before the pair is free.
    fn separation_energy(&self, s: f64, a_i: f64, a_j: f64) -> f64;
}

/// The radius `r = 2 a_i a_j / (a_i + a_j)` (m) of a pair (twice the reduced radius); for a
/// planar wall (`a_j = ∞`) it is `2 a_i`.
#[inline]
pub fn bridge_radius(a_i: f64, a_j: f64) -> f64 {
    if a_j.is_finite() {
        2.0 * a_i * a_j / (a_i + a_j)
    } else {
        2.0 * a_i
    }
}

/// [`bridge_radius`] in lanes; `WALL` for a sphere on a wall (`a_j` unused).
#[inline(always)]
pub fn bridge_radius_lanes<R: Real, const WALL: bool>(a_i: R, a_j: R) -> R {
    let two = R::splat(2.0);
    if WALL {
        two * a_i
    } else {
        two * a_i * a_j / (a_i + a_j)
    }
}

/// Facts about one registered law, for help texts and documentation.
#[derive(Clone, Copy, Debug)]
pub struct LawInfo {
    /// Its [`LawKind`].
    pub kind: LawKind,
    /// [`AdhesiveLaw::NAME`].
    pub name: &'static str,
    /// [`AdhesiveLaw::ALIASES`].
    pub aliases: &'static [&'static str],
    /// [`AdhesiveLaw::SUMMARY`].
    pub summary: &'static str,
    /// [`AdhesiveLaw::PARAMETERS`].
    pub parameters: &'static [Parameter],
    /// [`AdhesiveLaw::FORMS_BRIDGES`].
    pub forms_bridges: bool,
}

/// Generates, from one line per law, the enums and the list every part of rheodem takes
/// the adhesive laws from (see the module documentation).
macro_rules! adhesive_laws {
    ($($(#[$doc:meta])* $variant:ident => $law:ty),* $(,)?) => {
        /// An adhesive law: none, or one registered law with its parameters (SI units).
        #[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
        pub enum Adhesion {
            /// No adhesion.
            #[default]
            None,
            $($(#[$doc])* $variant($law),)*
        }

        /// An [`Adhesion`] law with its per-run constants computed (see
        /// [`Adhesion::resolve`]).
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum ResolvedAdhesion {
            /// No adhesion.
            None,
            $($(#[$doc])* $variant(<$law as AdhesiveLaw>::Resolved),)*
        }

        /// The name of an adhesive law, as scenario files, options, set-ups and results
        /// give it (`none`, or a registered law's [`AdhesiveLaw::NAME`]).
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
        pub enum LawKind {
            /// No adhesion (`none`, alias `dry`).
            #[default]
            None,
            $($(#[$doc])* $variant,)*
        }

        /// Every registered law, `none` first.
        pub const LAWS: &[LawInfo] = &[
            LawInfo {
                kind: LawKind::None,
                name: "none",
                aliases: &["dry"],
                summary: "No adhesion.",
                parameters: &[],
                forms_bridges: false,
            },
            $(LawInfo {
                kind: LawKind::$variant,
                name: <$law as AdhesiveLaw>::NAME,
                aliases: <$law as AdhesiveLaw>::ALIASES,
                summary: <$law as AdhesiveLaw>::SUMMARY,
                parameters: <$law as AdhesiveLaw>::PARAMETERS,
                forms_bridges: <$law as AdhesiveLaw>::FORMS_BRIDGES,
            },)*
        ];

        impl LawKind {
            /// The law built from named parameter values.
            pub fn build(self, p: &Parameters<'_>) -> Result<Adhesion, LawError> {
                Ok(match self {
                    LawKind::None => {
                        p.check_keys()?;
                        Adhesion::None
                    }
                    $(LawKind::$variant => Adhesion::$variant(<$law>::from_parameters(p)?),)*
                })
            }

            /// The parameters of the law at a set-up's strength (see
            /// [`AdhesiveLaw::at_strength`]); none for `none`.
            pub fn at_strength(self, s: &Strength) -> Vec<(&'static str, f64)> {
                match self {
                    LawKind::None => Vec::new(),
                    $(LawKind::$variant => <$law>::at_strength(s),)*
                }
            }
        }

        impl Adhesion {
            /// The law's name.
            pub fn kind(&self) -> LawKind {
                match self {
                    Adhesion::None => LawKind::None,
                    $(Adhesion::$variant(_) => LawKind::$variant,)*
                }
            }

            /// The law with its per-run constants computed (`2π γ_s cos θ`, the range,
            /// `1/V_b`), as the pair loop uses it.
            pub fn resolve(&self) -> ResolvedAdhesion {
                match self {
                    Adhesion::None => ResolvedAdhesion::None,
                    $(Adhesion::$variant(law) => ResolvedAdhesion::$variant(law.resolve()),)*
                }
            }
        }

        impl ResolvedAdhesion {
            /// Whether a bridge forms at contact (irreversible laws).
            #[inline(always)]
            pub fn needs_bridge(&self) -> bool {
                match self {
                    ResolvedAdhesion::None => false,
                    $(ResolvedAdhesion::$variant(_) => <$law as AdhesiveLaw>::FORMS_BRIDGES,)*
                }
            }

            /// Range of the attraction beyond contact (m); zero without adhesion.
            #[inline(always)]
            pub fn range(&self) -> f64 {
                match self {
                    ResolvedAdhesion::None => 0.0,
                    $(ResolvedAdhesion::$variant(law) => law.range(),)*
                }
            }

            /// `f_a^max` (N) of a pair of radii `a_i`, `a_j` (m).
            #[inline(always)]
            pub fn max_force(&self, a_i: f64, a_j: f64) -> f64 {
                match self {
                    ResolvedAdhesion::None => 0.0,
                    $(ResolvedAdhesion::$variant(law) => law.max_force(a_i, a_j),)*
                }
            }

            /// [`Adhesion::separation_energy`] (J) with the constants resolved.
            pub fn separation_energy(&self, s: f64, a_i: f64, a_j: f64) -> f64 {
                if s >= self.range() {
                    return 0.0;
                }
                match self {
                    ResolvedAdhesion::None => 0.0,
                    $(ResolvedAdhesion::$variant(law) => law.separation_energy(s, a_i, a_j),)*
                }
            }

            /// [`ResolvedAdhesion::contact_force`] in lanes, for two spheres or (`WALL`) a
            /// sphere on a wall (`a_j` unused).
            #[inline(always)]
            pub fn contact_force_lanes<R: Real, const WALL: bool>(&self, a_i: R, a_j: R) -> R {
                match self {
                    ResolvedAdhesion::None => R::splat(0.0),
                    $(ResolvedAdhesion::$variant(law) => {
                        law.contact_force_lanes::<R, WALL>(a_i, a_j)
                    })*
                }
            }

            /// [`ResolvedAdhesion::separated_force`] in lanes, for two spheres or (`WALL`) a
            /// sphere on a wall (`a_j` unused).
            #[inline(always)]
            pub fn separated_force_lanes<R: Real, const WALL: bool>(
                &self,
                s: R,
                a_i: R,
                a_j: R,
                bridge: R::Mask,
            ) -> (R, R::Mask) {
                match self {
                    ResolvedAdhesion::None => (R::splat(0.0), R::all(false)),
                    $(ResolvedAdhesion::$variant(law) => {
                        law.separated_force_lanes::<R, WALL>(s, a_i, a_j, bridge)
                    })*
                }
            }
        }
    };
}

adhesive_laws! {
    /// Reversible linear adhesion (Shi et al. 2020, Eq. 3).
    Reversible => Reversible,
    /// Irreversible Willett liquid bridge (Roy et al. 2016, Eqs. 10–15).
    LiquidBridge => LiquidBridge,
    /// Irreversible linear adhesion (Roy et al. 2016, Eqs. 16–17).
    LinearIrreversible => LinearIrreversible,
    /// Irreversible Rabinovich liquid bridge (Rabinovich et al. 2005; Lian et al. 1993).
    Rabinovich => Rabinovich,
}

impl LawKind {
    /// The facts the registry holds about this law.
    pub fn info(self) -> &'static LawInfo {
        LAWS.iter()
            .find(|l| l.kind == self)
            .expect("every LawKind is in LAWS")
    }

    /// The law's name (`snake_case`).
    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// Whether the law forms bridges at contact (irreversible laws).
    pub fn forms_bridges(self) -> bool {
        self.info().forms_bridges
    }

    /// The law from its name: the name itself, an alias, or either in kebab-case; an
    /// error lists the known names.
    pub fn from_name(name: &str) -> Result<LawKind, LawError> {
        LAWS.iter()
            .find(|l| names::spells(name, l.name, l.aliases))
            .map(|l| l.kind)
            .ok_or_else(|| LawError {
                key: "law".into(),
                value: format!("\"{name}\""),
                reason: format!("is not a known adhesive law; known: {}", LawKind::known()),
            })
    }

    /// The known names with their aliases, for messages: `none (dry), reversible, …`.
    pub fn known() -> String {
        LAWS.iter()
            .map(|l| names::with_aliases(l.name, l.aliases))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl std::fmt::Display for LawKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for LawKind {
    type Err = LawError;
    fn from_str(s: &str) -> Result<LawKind, LawError> {
        LawKind::from_name(s)
    }
}

impl Serialize for LawKind {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> Deserialize<'de> for LawKind {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<LawKind, D::Error> {
        let name = String::deserialize(d)?;
        LawKind::from_name(&name)
            .map_err(|e| serde::de::Error::custom(format!("{} {}", e.value, e.reason)))
    }
}

impl Adhesion {
    /// Whether the law has any adhesion.
    pub fn is_none(&self) -> bool {
        matches!(self, Adhesion::None)
    }

    /// Whether the law needs a bridge formed at contact (irreversible laws).
    #[inline]
    pub fn needs_bridge(&self) -> bool {
        self.kind().forms_bridges()
    }

    /// Range of the attraction beyond contact (m): `δ_a` or `S_c`; zero without adhesion.
    pub fn range(&self) -> f64 {
        self.resolve().range()
    }

    /// Maximum adhesive force `f_a^max` (N) of a pair of radii `a_i`, `a_j` (m).
    pub fn max_force(&self, a_i: f64, a_j: f64) -> f64 {
        self.resolve().max_force(a_i, a_j)
    }

    /// Adhesive force (N, ≤ 0) of a pair in contact (`δ ≥ 0`): `−f_a^max` for every law.
    pub fn contact_force(&self, a_i: f64, a_j: f64) -> f64 {
        -self.max_force(a_i, a_j)
    }

    /// Adhesive force (N, ≤ 0) of a pair separated by `s > 0` (m), and whether the
    /// bridge survives. `bridge` says whether an irreversible law's bridge exists.
    pub fn separated_force(&self, s: f64, a_i: f64, a_j: f64, bridge: bool) -> (f64, bool) {
        self.resolve().separated_force(s, a_i, a_j, bridge)
    }

    /// Work (J) the attraction still does before the pair is free, from separation `s ≥ 0`
    /// (m) with a live bridge: `∫_s^{range} f_a dS` (≤ 0). It is the adhesive potential
    /// energy of a pair at `s` relative to separated particles.
    pub fn separation_energy(&self, s: f64, a_i: f64, a_j: f64) -> f64 {
        self.resolve().separation_energy(s, a_i, a_j)
    }

    /// Adhesive potential energy (J) of a pair at overlap `δ` (m): the separation energy from
    /// contact plus `−f_max δ` inside the contact; zero for a pair without a bridge under an
    /// irreversible law.
    pub fn potential(&self, overlap: f64, a_i: f64, a_j: f64, bridge: bool) -> f64 {
        self.resolve().potential(overlap, a_i, a_j, bridge)
    }
}

impl ResolvedAdhesion {
    /// Whether there is no adhesion.
    #[inline(always)]
    pub fn is_none(&self) -> bool {
        matches!(self, ResolvedAdhesion::None)
    }

    /// [`Adhesion::potential`] (J) with the constants resolved.
    pub fn potential(&self, overlap: f64, a_i: f64, a_j: f64, bridge: bool) -> f64 {
        if self.is_none() || (self.needs_bridge() && !bridge) {
            return 0.0;
        }
        if overlap >= 0.0 {
            self.separation_energy(0.0, a_i, a_j) - self.max_force(a_i, a_j) * overlap
        } else {
            self.separation_energy(-overlap, a_i, a_j)
        }
    }

    /// Adhesive force (N, ≤ 0) in contact: `−f_a^max`.
    #[inline(always)]
    pub fn contact_force(&self, a_i: f64, a_j: f64) -> f64 {
        -self.max_force(a_i, a_j)
    }

    /// Adhesive force (N, ≤ 0) at separation `s > 0` (m), and whether the bridge survives;
    /// `bridge` says whether an irreversible law's bridge exists.
    #[inline(always)]
    pub fn separated_force(&self, s: f64, a_i: f64, a_j: f64, bridge: bool) -> (f64, bool) {
        if a_j.is_finite() {
            self.separated_force_lanes::<f64, false>(s, a_i, a_j, bridge)
        } else {
            self.separated_force_lanes::<f64, true>(s, a_i, a_j, bridge)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_and_alias_finds_its_law_and_nothing_else_does() {
        for law in LAWS {
            assert_eq!(LawKind::from_name(law.name).expect("name"), law.kind);
            assert_eq!(law.kind.name(), law.name);
            for alias in law.aliases {
                assert_eq!(LawKind::from_name(alias).expect("alias"), law.kind);
            }
            let kebab = law.name.replace('_', "-");
            assert_eq!(LawKind::from_name(&kebab).expect("kebab"), law.kind);
        }
        let names: Vec<&str> = LAWS
            .iter()
            .flat_map(|l| std::iter::once(l.name).chain(l.aliases.iter().copied()))
            .collect();
        let mut unique = names.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(
            unique.len(),
            names.len(),
            "a name is registered twice: {names:?}"
        );
        let e = LawKind::from_name("glue").expect_err("unknown");
        assert!(e.to_string().contains("glue") && e.to_string().contains("liquid_bridge"));
    }

    #[test]
    fn the_laws_serialise_as_before() {
        // The checkpoint (MessagePack) and JSON forms of version 0.2.0, when each law was
        // a struct variant of one enum: checkpoints written then still load.
        let laws = [
            (Adhesion::None, "\"None\"", "a44e6f6e65"),
            (
                Adhesion::Reversible(Reversible {
                    max_force: 1.5e-3,
                    stiffness: 100.0,
                }),
                r#"{"Reversible":{"max_force":0.0015,"stiffness":100.0}}"#,
                "81aa52657665727369626c6592cb3f589374bc6a7efacb4059000000000000",
            ),
            (
                Adhesion::LiquidBridge(LiquidBridge {
                    surface_tension: 0.02,
                    contact_angle: 0.25,
                    volume: 75e-12,
                }),
                r#"{"LiquidBridge":{"surface_tension":0.02,"contact_angle":0.25,"volume":7.5e-11}}"#,
                "81ac4c697175696442726964676593cb3f947ae147ae147bcb3fd0000000000000cb3dd49da7e361ce4c",
            ),
            (
                Adhesion::LinearIrreversible(LinearIrreversible {
                    max_force: 1.3e-4,
                    stiffness: 0.26,
                }),
                r#"{"LinearIrreversible":{"max_force":0.00013,"stiffness":0.26}}"#,
                "81b24c696e656172497272657665727369626c6592cb3f210a137f38c543cb3fd0a3d70a3d70a4",
            ),
        ];
        for (law, json, packed) in laws {
            assert_eq!(serde_json::to_string(&law).expect("json"), json);
            let bytes = rmp_serde::to_vec(&law).expect("msgpack");
            let hex: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
            assert_eq!(hex, packed);
            let back: Adhesion = rmp_serde::from_slice(&bytes).expect("reads back");
            assert_eq!(back, law);
        }
    }

    #[test]
    fn a_spec_builds_the_same_law_as_its_parameters_say() {
        let spec: LawSpec = serde_json::from_str(
            r#"{"law": "willett", "surface_tension": 0.02, "contact_angle_deg": 20, "volume": 7.5e-11}"#,
        )
        .expect("spec");
        let law = spec.build().expect("valid");
        assert_eq!(
            law,
            Adhesion::LiquidBridge(LiquidBridge {
                surface_tension: 0.02,
                contact_angle: 20f64.to_radians(),
                volume: 75e-12,
            })
        );
        // Written back under the law's own name, and read again to the same law.
        let text = serde_json::to_string(&spec).expect("writes");
        assert!(text.contains("\"law\":\"liquid_bridge\""), "{text}");
        let again: LawSpec = serde_json::from_str(&text).expect("reads");
        assert_eq!(again.build().expect("valid"), law);
    }
}
