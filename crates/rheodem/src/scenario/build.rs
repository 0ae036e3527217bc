//! Validation and assembly of a scenario into a simulation.

use super::prepare::{PreparationReport, Target, prepare};
use super::spec::*;
use super::{ScenarioError, invalid};
use crate::Simulation;
use crate::contact::adhesion::LawError;
use crate::contact::normal::hertz::{HertzNormal, Material, tsuji_alpha};
use crate::contact::parameters::Parameters;
use crate::contact::spring::Mindlin;
use crate::contact::{
    Adhesion, ContactLaw, ContactTable, Damping, LawSpec, LinearNormal, Normal, NormalKind,
    Resistance, Spring, SpringKind,
};
use crate::domain::{Domain, ShearDynamics};
use crate::generate::{
    MAX_INSERTION_FRACTION, Obstacle, Rng, gaussian_vector, insert_random, polydisperse_radii,
};
use crate::io::packing::parse_packing;
use crate::neighbor::NeighborError;
use crate::particles::{Motion, Particles, Sphere};
use crate::sanity::{DEFAULT_DISPLACEMENT, DEFAULT_OVERLAP, Instability, Limits};
use crate::stress_control::StressControl;
use crate::timestep::{DEFAULT_FRACTION, MAX_FRACTION, shortest_contact_time};
use crate::walls::Wall;
use glam::DVec3;
use rand::SeedableRng;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Values derived from a scenario, recorded in every output.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Resolved {
    /// Program version.
    pub version: String,
    /// Git commit of the build.
    #[serde(default)]
    pub commit: String,
    /// Seed of the run.
    pub seed: u64,
    /// Time step (s).
    pub dt: f64,
    /// Shortest binary contact time `t_c` (s).
    pub contact_time: f64,
    /// Steps of the run.
    pub steps: u64,
    /// Verlet skin (m).
    pub skin: f64,
    /// Free (integrated) particles.
    pub free_particles: usize,
    /// Prescribed (wall) particles.
    pub wall_particles: usize,
    /// Smallest and largest free-particle radius (m).
    pub radius_range: [f64; 2],
    /// Mean free-particle diameter (m).
    pub mean_diameter: f64,
    /// How the radii were drawn.
    pub radius_distribution: String,
    /// Volume fraction of the free particles in the box at the start of the run.
    pub volume_fraction: f64,
    /// Box edge lengths at the start of the run (m).
    pub box_size: [f64; 3],
    /// What the preparation did, if there was one (and it ran: `check` does not run it).
    pub preparation: Option<PreparationReport>,
    /// Doubtful but accepted input (deep initial overlaps, say).
    #[serde(default)]
    pub warnings: Vec<String>,
}

/// A scenario assembled into a simulation.
pub struct Built {
    /// The simulation, ready to step.
    pub simulation: Simulation,
    /// The derived values.
    pub resolved: Resolved,
}

fn positive(key: &str, v: f64) -> Result<f64, ScenarioError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(invalid(key, v, "must be a positive finite number"))
    }
}

fn non_negative(key: &str, v: f64) -> Result<f64, ScenarioError> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(invalid(key, v, "must be a finite number ≥ 0"))
    }
}

fn finite3(key: &str, v: [f64; 3]) -> Result<DVec3, ScenarioError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(DVec3::from_array(v))
    } else {
        Err(invalid(
            key,
            format!("{v:?}"),
            "all three components must be finite",
        ))
    }
}

fn unit3(key: &str, v: [f64; 3]) -> Result<DVec3, ScenarioError> {
    let d = finite3(key, v)?;
    if d.length() > 0.0 {
        Ok(d.normalize())
    } else {
        Err(invalid(key, format!("{v:?}"), "must be a non-zero vector"))
    }
}

fn at_most_one(key: &str, names: &[(&str, bool)]) -> Result<(), ScenarioError> {
    let given: Vec<&str> = names.iter().filter(|(_, g)| *g).map(|(n, _)| *n).collect();
    if given.len() > 1 {
        return Err(invalid(
            key,
            given.join(" and "),
            format!(
                "give at most one of {}",
                names.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
            ),
        ));
    }
    Ok(())
}

fn species_index(key: &str, name: &str, species: &[SpeciesSpec]) -> Result<u16, ScenarioError> {
    species
        .iter()
        .position(|s| s.name == name)
        .map(|i| i as u16)
        .ok_or_else(|| {
            invalid(
                key,
                format!("\"{name}\""),
                format!(
                    "must name a declared species ({})",
                    species
                        .iter()
                        .map(|s| format!("\"{}\"", s.name))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
        })
}

/// The normal law of `n` from the registry for a pair of species `a`, `b`: Hertz's law
/// takes the elastic constants and the restitution it omits from the two species.
fn normal_law(
    key: &str,
    n: &NormalSpec,
    a: &SpeciesSpec,
    b: &SpeciesSpec,
) -> Result<Normal, ScenarioError> {
    if n.law != NormalKind::Hertz {
        return n.build().map_err(|e| law_error(key, e));
    }
    n.parameters().check_keys().map_err(|e| law_error(key, e))?;
    let material = |sp: &SpeciesSpec| -> Result<Material, ScenarioError> {
        let mut values = n.values.clone();
        for (k, v) in [
            ("youngs_modulus", sp.youngs_modulus),
            ("poisson_ratio", sp.poisson_ratio),
        ] {
            match (values.contains_key(k), v) {
                (true, _) => {}
                (false, Some(v)) => {
                    values.insert(k.into(), v);
                }
                (false, None) => {
                    return Err(invalid(
                        format!("{key}.{k}"),
                        "(missing)",
                        format!(
                            "give it in the hertz law or as `{k}` of species \"{}\"",
                            sp.name
                        ),
                    ));
                }
            }
        }
        let p = Parameters::of("hertz", n.law.info().parameters, &values);
        HertzNormal::material(&p).map_err(|e| {
            if n.values.contains_key(&e.key) {
                law_error(key, e)
            } else {
                invalid(
                    format!("species \"{}\".{}", sp.name, e.key),
                    e.value,
                    e.reason,
                )
            }
        })
    };
    let restitution = match (n.value("restitution"), a.restitution, b.restitution) {
        (Some(e), _, _) => e,
        (None, Some(e_a), Some(e_b)) => (e_a * e_b).sqrt(),
        (None, Some(e), None) | (None, None, Some(e)) => e,
        (None, None, None) => 1.0,
    };
    let mut values = n.values.clone();
    values.insert("restitution".into(), restitution);
    let p = Parameters::of("hertz", n.law.info().parameters, &values);
    let checked = |k: &str| p.require(k).map_err(|e| law_error(key, e));
    Ok(HertzNormal::between(
        &material(a)?,
        &material(b)?,
        checked("restitution")?,
        checked("impact_speed")?,
    )
    .into())
}

/// A spring of the contact (`role`: friction, rolling or torsion): none when not given,
/// else the registry's law named by `law` (the linear spring–dashpot–Coulomb law by
/// default) from its keys; ratios are taken of the normal law's linear reference.
fn spring(
    key: &str,
    role: &str,
    r: &Option<ResistanceSpec>,
    normal: &Normal,
) -> Result<Spring, ScenarioError> {
    let Some(r) = r else {
        return Ok(Spring::NONE);
    };
    let kind = match &r.law {
        None => SpringKind::default(),
        Some(name) => SpringKind::from_name(name)
            .map_err(|reason| invalid(format!("{key}.law"), format!("\"{name}\""), reason))?,
    };
    match kind {
        SpringKind::Linear => Ok(resistance(key, r, normal.reference().as_ref())?.into()),
        SpringKind::Mindlin => Ok(mindlin(key, role, r, normal)?.into()),
    }
}

/// Mindlin's sliding spring from its keys (`mu` or `mu_static`/`mu_dynamic`, and
/// `damping_ratio`, the fraction of Tsuji's normal dashpot), with `G*` of the contact's
/// Hertz normal law.
fn mindlin(
    key: &str,
    role: &str,
    r: &ResistanceSpec,
    normal: &Normal,
) -> Result<Mindlin, ScenarioError> {
    if role != "friction" {
        return Err(invalid(
            format!("{key}.law"),
            "\"mindlin\"",
            "Mindlin's spring is a sliding-friction law: use it under `friction`, not for rolling or torsion",
        ));
    }
    let Some(hertz) = normal.hertz() else {
        return Err(invalid(
            format!("{key}.law"),
            "\"mindlin\"",
            format!(
                "Mindlin's spring takes G* from a hertz normal law; this contact's normal law is {}",
                normal.kind()
            ),
        ));
    };
    for (k, given) in [
        ("stiffness", r.stiffness.is_some()),
        ("stiffness_ratio", r.stiffness_ratio.is_some()),
        ("damping", r.damping.is_some()),
        ("damping_per_mass", r.damping_per_mass.is_some()),
    ] {
        if given {
            return Err(invalid(
                format!("{key}.{k}"),
                "(given)",
                "Mindlin's stiffness is 8 G* √(R* δ) from the hertz law and its dashpot a `damping_ratio` of the normal one; give only mu (or mu_static, mu_dynamic) and damping_ratio",
            ));
        }
    }
    let (mu_s, mu_d) = coulomb(key, r)?;
    let x_t = non_negative(
        &format!("{key}.damping_ratio"),
        r.damping_ratio.unwrap_or(0.0),
    )?;
    Ok(Mindlin {
        effective_shear_modulus: hertz.effective_shear_modulus,
        dashpot: x_t
            * std::f64::consts::SQRT_2
            * tsuji_alpha(hertz.restitution)
            * (4.0 / 3.0 * hertz.effective_modulus).sqrt(),
        mu_static: mu_s,
        mu_dynamic: mu_d,
    })
}

/// The Coulomb coefficients `(μ_s, μ_d)` of a spring's keys.
fn coulomb(key: &str, r: &ResistanceSpec) -> Result<(f64, f64), ScenarioError> {
    let (mu_s, mu_d) = match (r.mu, r.mu_static, r.mu_dynamic) {
        (Some(m), None, None) => (m, m),
        (None, Some(s), Some(d)) => (s, d),
        (None, Some(s), None) => (s, s),
        (None, None, None) => {
            return Err(invalid(
                format!("{key}.mu"),
                "(missing)",
                "give `mu`, or `mu_static` and `mu_dynamic`",
            ));
        }
        _ => {
            return Err(invalid(
                key,
                "mu with mu_static/mu_dynamic",
                "give either `mu` or `mu_static` (and `mu_dynamic`), not both",
            ));
        }
    };
    let mu_s = non_negative(&format!("{key}.mu_static"), mu_s)?;
    let mu_d = non_negative(&format!("{key}.mu_dynamic"), mu_d)?;
    if mu_d > mu_s {
        return Err(invalid(
            format!("{key}.mu_dynamic"),
            mu_d,
            format!("must not exceed mu_static = {mu_s}"),
        ));
    }
    Ok((mu_s, mu_d))
}

/// The linear spring–dashpot–Coulomb law from its keys; `normal` is the linear law its
/// ratios refer to (`None` beside a normal law without one, which refuses the ratios).
fn resistance(
    key: &str,
    r: &ResistanceSpec,
    normal: Option<&LinearNormal>,
) -> Result<Resistance, ScenarioError> {
    let reference = |ratio: &str| {
        normal.ok_or_else(|| {
            invalid(
                format!("{key}.{ratio}"),
                "(given)",
                "the contact's normal law has no linear stiffness to take a ratio of: give `stiffness` and `damping` (or use law = \"mindlin\" beside hertz)",
            )
        })
    };
    at_most_one(
        key,
        &[
            ("stiffness", r.stiffness.is_some()),
            ("stiffness_ratio", r.stiffness_ratio.is_some()),
        ],
    )?;
    let stiffness = match (r.stiffness, r.stiffness_ratio) {
        (Some(k), _) => non_negative(&format!("{key}.stiffness"), k)?,
        (None, Some(q)) => {
            non_negative(&format!("{key}.stiffness_ratio"), q)?
                * reference("stiffness_ratio")?.stiffness
        }
        (None, None) => {
            return Err(invalid(
                format!("{key}.stiffness"),
                "(missing)",
                "give `stiffness` (N/m) or `stiffness_ratio` (fraction of k_n)",
            ));
        }
    };
    at_most_one(
        key,
        &[
            ("damping", r.damping.is_some()),
            ("damping_ratio", r.damping_ratio.is_some()),
            ("damping_per_mass", r.damping_per_mass.is_some()),
        ],
    )?;
    let damping = if let Some(g) = r.damping {
        Damping {
            fixed: non_negative(&format!("{key}.damping"), g)?,
            ..Damping::NONE
        }
    } else if let Some(q) = r.damping_ratio {
        reference("damping_ratio")?
            .damping
            .scaled(non_negative(&format!("{key}.damping_ratio"), q)?)
    } else if let Some(g) = r.damping_per_mass {
        Damping {
            per_mass: non_negative(&format!("{key}.damping_per_mass"), g)?,
            ..Damping::NONE
        }
    } else {
        Damping::NONE
    };
    let (mu_s, mu_d) = coulomb(key, r)?;
    if stiffness == 0.0 && damping.is_zero() && mu_s > 0.0 {
        return Err(invalid(
            format!("{key}.stiffness"),
            0,
            "a resistance with a Coulomb limit needs a spring or a dashpot",
        ));
    }
    Ok(Resistance {
        stiffness,
        damping,
        mu_static: mu_s,
        mu_dynamic: mu_d,
    })
}

fn adhesion(key: &str, spec: &Option<LawSpec>) -> Result<Adhesion, ScenarioError> {
    match spec {
        None => Ok(Adhesion::None),
        Some(spec) => spec.build().map_err(|e| law_error(key, e)),
    }
}

/// A law's parameter error as a scenario error under `key` (the law's table).
pub fn law_error(key: &str, e: LawError) -> ScenarioError {
    let key = if e.key.is_empty() {
        key.to_string()
    } else {
        format!("{key}.{}", e.key)
    };
    invalid(key, e.value, e.reason)
}

/// The validated contact laws of a scenario, indexed by species in declaration order.
pub fn contact_table(s: &Scenario) -> Result<ContactTable, ScenarioError> {
    let ns = s.species.len();
    // Which [[contact]] gives each pair's law: the default, then the pairs named.
    let mut default = None;
    let mut named: Vec<(usize, usize, usize)> = Vec::new();
    for (k, c) in s.contacts.iter().enumerate() {
        let key = format!("contact[{k}]");
        match &c.species {
            None if default.is_some() => {
                return Err(invalid(
                    format!("{key}.species"),
                    "(missing)",
                    "only one default [[contact]] (without `species`) is allowed",
                ));
            }
            None => default = Some(k),
            Some([a, b]) => {
                let ia = species_index(&format!("{key}.species[0]"), a, &s.species)? as usize;
                let ib = species_index(&format!("{key}.species[1]"), b, &s.species)? as usize;
                if named
                    .iter()
                    .any(|&(x, y, _)| (x, y) == (ia, ib) || (x, y) == (ib, ia))
                {
                    return Err(invalid(
                        format!("{key}.species"),
                        format!("[\"{a}\", \"{b}\"]"),
                        "this pair already has a contact law",
                    ));
                }
                named.push((ia, ib, k));
            }
        }
        // Every [[contact]] is checked, also one that no pair ends up using.
        let (a, b) = match named.last() {
            Some(&(a, b, last)) if last == k => (a, b),
            _ => (0, 0),
        };
        contact_law(s, k, a, b)?;
    }
    let mut given = vec![default; ns * ns];
    for &(a, b, k) in &named {
        given[a * ns + b] = Some(k);
        given[b * ns + a] = Some(k);
    }
    if let Some(missing) = given.iter().position(Option::is_none) {
        let (a, b) = (missing / ns, missing % ns);
        return Err(invalid(
            "contact",
            format!(
                "no law for [\"{}\", \"{}\"]",
                s.species[a].name, s.species[b].name
            ),
            "give a default [[contact]] without `species`, or one for every species pair",
        ));
    }
    let mut table = ContactTable::uniform(ns, contact_law(s, given[0].unwrap_or(0), 0, 0)?);
    for a in 0..ns {
        for b in a..ns {
            if (a, b) != (0, 0) {
                table.set(a, b, contact_law(s, given[a * ns + b].unwrap_or(0), a, b)?);
            }
        }
    }
    Ok(table)
}

/// The law `[[contact]]` number `k` gives the pair of species `a`, `b`.
fn contact_law(s: &Scenario, k: usize, a: usize, b: usize) -> Result<ContactLaw, ScenarioError> {
    let c = &s.contacts[k];
    let key = format!("contact[{k}]");
    let normal = normal_law(
        &format!("{key}.normal"),
        &c.normal,
        &s.species[a],
        &s.species[b],
    )?;
    Ok(ContactLaw {
        normal,
        tangential: spring(&format!("{key}.friction"), "friction", &c.friction, &normal)?,
        rolling: spring(&format!("{key}.rolling"), "rolling", &c.rolling, &normal)?,
        torsion: spring(&format!("{key}.torsion"), "torsion", &c.torsion, &normal)?,
        adhesion: adhesion(&format!("{key}.adhesion"), &c.adhesion)?,
    })
}

fn motion(key: &str, m: &MotionSpec) -> Result<Motion, ScenarioError> {
    Ok(match m {
        MotionSpec::Free => Motion::Free,
        MotionSpec::Fixed => Motion::Fixed,
        MotionSpec::Rotating {
            center,
            axis,
            omega,
        } => Motion::Rotating {
            center: finite3(&format!("{key}.rotating.center"), *center)?,
            axis: unit3(&format!("{key}.rotating.axis"), *axis)?,
            omega: if omega.is_finite() {
                *omega
            } else {
                return Err(invalid(
                    format!("{key}.rotating.omega"),
                    omega,
                    "must be finite",
                ));
            },
        },
    })
}

/// A scenario validated and resolved without running anything (see [`check`]).
pub struct Checked {
    /// The derived values (`preparation` is `None`: it was not run).
    pub resolved: Resolved,
    /// The preparation the scenario asks for, in words, if any.
    pub preparation: Option<String>,
}

/// Largest number of particles a scenario may create.
const MAX_PARTICLES: usize = 50_000_000;

/// Largest number of steps a run may take.
pub const MAX_STEPS: u64 = 10_000_000_000_000;

/// Initial overlaps beyond this fraction of the smaller radius are reported as warnings.
const WARN_OVERLAP: f64 = 0.1;

/// Validates the scenario and assembles the simulation: species, contact laws, particles
/// (generated with the scenario seed), walls, time step; runs the preparation if any.
/// `base_dir` resolves relative file paths.
pub fn build(s: &Scenario, base_dir: &Path) -> Result<Built, ScenarioError> {
    let Assembled {
        mut simulation,
        preparation: target,
        context,
    } = assemble(s, base_dir)?;
    let preparation = match target {
        None => None,
        Some(p) => Some(
            prepare(&mut simulation, p.target, p.strain_rate, p.relax_steps).map_err(
                |e| match e {
                    super::prepare::PrepareError::Neighbor(e) => {
                        context.box_error(e, s.neighbor.skin.is_some())
                    }
                    super::prepare::PrepareError::Unreachable(msg) => {
                        invalid("preparation", "(target)", msg)
                    }
                },
            )?,
        ),
    };
    configure_flow(s, &mut simulation)?;
    let resolved = context.resolve(&simulation, preparation);
    Ok(Built {
        simulation,
        resolved,
    })
}

/// Validates the scenario and resolves its derived values like [`build`], but runs no
/// dynamics: the preparation, if any, is described, not run.
pub fn check(s: &Scenario, base_dir: &Path) -> Result<Checked, ScenarioError> {
    let Assembled {
        mut simulation,
        preparation,
        context,
    } = assemble(s, base_dir)?;
    configure_flow(s, &mut simulation)?;
    Ok(Checked {
        resolved: context.resolve(&simulation, None),
        preparation: preparation.map(|p| p.description),
    })
}

/// The preparation a scenario asks for.
struct PlannedPreparation {
    target: Target,
    strain_rate: f64,
    relax_steps: u64,
    description: String,
}

/// What [`assemble`] knows that the resolved values need.
struct Context {
    seed: u64,
    dt: f64,
    contact_time: f64,
    steps: u64,
    skin: f64,
    radius_range: [f64; 2],
    mean_diameter: f64,
    distribution: String,
    size: [f64; 3],
    warnings: Vec<String>,
}

impl Context {
    /// The key to blame for a neighbour-grid error: `neighbor.skin` when a skin given by
    /// the user (`skin_given`) is what makes the cutoff too long for the box, else
    /// `domain.size`.
    fn box_error(&self, e: NeighborError, skin_given: bool) -> ScenarioError {
        if let NeighborError::BoxTooSmall {
            axis,
            length,
            cutoff,
        } = e
        {
            let without_skin = cutoff - self.skin;
            if skin_given && 3.0 * without_skin < length {
                return invalid(
                    "neighbor.skin",
                    self.skin,
                    format!(
                        "makes the neighbour cutoff {cutoff:.6e} m (largest diameter + \
                         interaction range + skin) too long for the box along {axis} (length \
                         {length:.6e} m, at least 3 cutoffs): the skin must be below {:.6e} m",
                        length / 3.0 - without_skin
                    ),
                );
            }
        }
        invalid("domain.size", format!("{:?}", self.size), e.to_string())
    }

    fn resolve(self, simulation: &Simulation, preparation: Option<PreparationReport>) -> Resolved {
        let obs = simulation.observables();
        Resolved {
            version: crate::VERSION.to_string(),
            commit: crate::COMMIT.to_string(),
            seed: self.seed,
            dt: self.dt,
            contact_time: self.contact_time,
            steps: self.steps,
            skin: self.skin,
            free_particles: simulation.particles.free_count(),
            wall_particles: simulation.particles.len() - simulation.particles.free_count(),
            radius_range: self.radius_range,
            mean_diameter: self.mean_diameter,
            radius_distribution: self.distribution,
            volume_fraction: obs.volume_fraction,
            box_size: simulation.domain.lengths().to_array(),
            preparation,
            warnings: self.warnings,
        }
    }
}

/// A validated scenario assembled into a simulation, before preparation and shear.
struct Assembled {
    simulation: Simulation,
    preparation: Option<PlannedPreparation>,
    context: Context,
}

/// Everything of [`build`] up to the preparation.
fn assemble(s: &Scenario, base_dir: &Path) -> Result<Assembled, ScenarioError> {
    if let Some(f) = &s.fields {
        crate::cg::periodic::BoxFields::new(f)?;
    }
    if s.species.is_empty() {
        return Err(invalid("species", "[]", "declare at least one [[species]]"));
    }
    for (k, sp) in s.species.iter().enumerate() {
        positive(&format!("species[{k}].density"), sp.density)?;
        if s.species[..k].iter().any(|o| o.name == sp.name) {
            return Err(invalid(
                format!("species[{k}].name"),
                format!("\"{}\"", sp.name),
                "species names must be unique",
            ));
        }
    }
    if s.species.len() > u16::MAX as usize {
        return Err(invalid("species", s.species.len(), "at most 65535 species"));
    }
    if s.contacts.is_empty() {
        return Err(invalid(
            "contact",
            "[]",
            "give at least one [[contact]] law",
        ));
    }
    let laws = contact_table(s)?;
    let gravity = finite3("gravity", s.gravity)?;
    let mut rng = Rng::seed_from_u64(s.seed);

    // Box: explicit, or the edge of a packing file.
    let lo = finite3("domain.lo", s.domain.lo)?;
    let mut size = s.domain.size;
    if size.is_none() {
        for g in &s.particles {
            if let ParticleGroup::File {
                path, length_scale, ..
            } = g
            {
                let text = read(base_dir, path)?;
                if let Ok(p) = parse_packing(&text) {
                    size = p.box_edge.map(|e| [e * length_scale; 3]);
                }
                break;
            }
        }
    }
    let Some(size) = size else {
        return Err(invalid(
            "domain.size",
            "(missing)",
            "give the box edges [Lx, Ly, Lz] in m (or read a packing file whose header gives `# L <edge>`)",
        ));
    };
    for (a, &l) in size.iter().enumerate() {
        positive(&format!("domain.size[{a}]"), l)?;
    }
    let domain = Domain::new(lo, lo + DVec3::from_array(size), s.domain.periodic);

    let mut particles = Particles::default();
    let mut distribution = Vec::new();
    let mut walls = Vec::new();
    for (k, w) in s.walls.iter().enumerate() {
        let key = format!("wall[{k}]");
        let species = species_index(&format!("{key}.species"), &w.species, &s.species)?;
        let normal = unit3(&format!("{key}.normal"), w.normal)?;
        // A plane that is not parallel to a periodic axis cuts through the periodic
        // images: particles would pass it through the boundary.
        let unit = normal.normalize();
        for (axis, name) in ["x", "y", "z"].iter().enumerate() {
            if s.domain.periodic[axis] && unit[axis].abs() > 1e-12 {
                return Err(invalid(
                    format!("{key}.normal"),
                    format!("{:?}", w.normal),
                    format!(
                        "the wall is not parallel to the periodic axis {name} \
                         (domain.periodic[{axis}] = true): its normal must have no {name} \
                         component, or make {name} non-periodic"
                    ),
                ));
            }
        }
        walls.push((finite3(&format!("{key}.point"), w.point)?, normal, species));
    }

    // First particle id of each group, to name particles in messages.
    let mut group_start = Vec::with_capacity(s.particles.len());
    for (k, g) in s.particles.iter().enumerate() {
        let key = format!("particles[{k}]");
        group_start.push(particles.len() as u32);
        match g {
            ParticleGroup::Explicit {
                species,
                motion: m,
                spheres,
            } => {
                let sp = species_index(&format!("{key}.species"), species, &s.species)?;
                let motion = motion(&format!("{key}.motion"), m)?;
                if spheres.is_empty() {
                    return Err(invalid(
                        format!("{key}.spheres"),
                        "[]",
                        "list at least one sphere",
                    ));
                }
                for (n, sph) in spheres.iter().enumerate() {
                    let skey = format!("{key}.spheres[{n}]");
                    let sphere = Sphere {
                        position: finite3(&format!("{skey}.position"), sph.position)?,
                        velocity: finite3(&format!("{skey}.velocity"), sph.velocity)?,
                        angular_velocity: finite3(
                            &format!("{skey}.angular_velocity"),
                            sph.angular_velocity,
                        )?,
                        radius: positive(&format!("{skey}.radius"), sph.radius)?,
                        species: sp,
                        motion,
                    };
                    particles.push(sphere, s.species[sp as usize].density);
                }
                distribution.push(format!("{key}: {} explicit spheres", spheres.len()));
            }
            ParticleGroup::Random {
                species,
                count,
                mean_diameter,
                polydispersity,
                velocity_spread,
            } => {
                let sp = species_index(&format!("{key}.species"), species, &s.species)?;
                if *count == 0 || *count > MAX_PARTICLES {
                    return Err(invalid(
                        format!("{key}.count"),
                        count,
                        format!("must lie in [1, {MAX_PARTICLES}]"),
                    ));
                }
                let d = positive(&format!("{key}.mean_diameter"), *mean_diameter)?;
                let w = *polydispersity;
                if !(w.is_finite() && (1.0..=20.0).contains(&w)) {
                    return Err(invalid(
                        format!("{key}.polydispersity"),
                        w,
                        "the width ratio w = r_max/r_min must lie in [1, 20]",
                    ));
                }
                let spread = non_negative(&format!("{key}.velocity_spread"), *velocity_spread)?;
                let radii = polydisperse_radii(&mut rng, *count, d, w);
                let group_volume: f64 = radii
                    .iter()
                    .map(|r| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3))
                    .sum();
                let fraction = (group_volume + particles.free_volume()) / domain.volume();
                if fraction > MAX_INSERTION_FRACTION {
                    return Err(invalid(
                        format!("{key}.count"),
                        count,
                        format!(
                            "impossible packing: these spheres would fill {:.3} of the box, but random insertion stalls near 0.35; \
                             enlarge domain.size (at most {:.0} such spheres fit) and compress with [preparation]",
                            fraction,
                            *count as f64 * MAX_INSERTION_FRACTION / fraction
                        ),
                    ));
                }
                let mut obstacles: Vec<Obstacle> = (0..particles.len())
                    .map(|i| Obstacle::Sphere(particles.position[i], particles.radius[i]))
                    .collect();
                obstacles.extend(walls.iter().map(|(p, n, _)| Obstacle::Plane(*p, *n)));
                let pos = insert_random(&mut rng, &radii, &domain, &obstacles, 10_000).map_err(|placed| {
                    invalid(
                        format!("{key}.count"),
                        count,
                        format!("impossible packing: random insertion placed only {placed} spheres; enlarge domain.size or reduce the count"),
                    )
                })?;
                for (r, a) in pos.into_iter().zip(radii) {
                    particles.push(
                        Sphere {
                            position: r,
                            velocity: gaussian_vector(&mut rng, spread),
                            angular_velocity: DVec3::ZERO,
                            radius: a,
                            species: sp,
                            motion: Motion::Free,
                        },
                        s.species[sp as usize].density,
                    );
                }
                distribution.push(format!(
                    "{key}: {count} radii uniform in [d_p/(1+w), w d_p/(1+w)] with d_p = {d:e} m, w = {w}"
                ));
            }
            ParticleGroup::File {
                species,
                path,
                length_scale,
                motion: m,
            } => {
                let sp = species_index(&format!("{key}.species"), species, &s.species)?;
                let scale = positive(&format!("{key}.length_scale"), *length_scale)?;
                let motion = motion(&format!("{key}.motion"), m)?;
                let text = read(base_dir, path)?;
                let packing = parse_packing(&text).map_err(|e| {
                    invalid(
                        format!("{key}.path"),
                        format!("\"{path}\""),
                        format!("not a valid packing file: {e}"),
                    )
                })?;
                for (diameter, r) in &packing.spheres {
                    particles.push(
                        Sphere {
                            position: *r * scale,
                            velocity: DVec3::ZERO,
                            angular_velocity: DVec3::ZERO,
                            radius: 0.5 * diameter * scale,
                            species: sp,
                            motion,
                        },
                        s.species[sp as usize].density,
                    );
                }
                distribution.push(format!(
                    "{key}: {} spheres read from {path}",
                    packing.spheres.len()
                ));
            }
            ParticleGroup::Lattice {
                species,
                origin,
                edge_a,
                edge_b,
                radius,
                spacing,
                motion: m,
            } => {
                let sp = species_index(&format!("{key}.species"), species, &s.species)?;
                let a = positive(&format!("{key}.radius"), *radius)?;
                let h = positive(&format!("{key}.spacing"), spacing.unwrap_or(2.0 * a))?;
                let o = finite3(&format!("{key}.origin"), *origin)?;
                let ea = finite3(&format!("{key}.edge_a"), *edge_a)?;
                let eb = finite3(&format!("{key}.edge_b"), *edge_b)?;
                if ea.cross(eb).length() == 0.0 {
                    return Err(invalid(
                        format!("{key}.edge_b"),
                        format!("{edge_b:?}"),
                        "the two edges must span a parallelogram (non-zero, not parallel)",
                    ));
                }
                let (na, nb) = super::size::lattice_counts(ea.length(), eb.length(), h);
                if na.saturating_mul(nb) > MAX_PARTICLES {
                    return Err(invalid(
                        format!("{key}.spacing"),
                        h,
                        "too many lattice spheres; use a larger spacing",
                    ));
                }
                let motion = motion(&format!("{key}.motion"), m)?;
                for u in 0..na {
                    for v in 0..nb {
                        let r =
                            o + ea.normalize() * (u as f64 * h) + eb.normalize() * (v as f64 * h);
                        particles.push(
                            Sphere {
                                position: r,
                                velocity: DVec3::ZERO,
                                angular_velocity: DVec3::ZERO,
                                radius: a,
                                species: sp,
                                motion,
                            },
                            s.species[sp as usize].density,
                        );
                    }
                }
                distribution.push(format!("{key}: {}×{} lattice of radius {a:e} m", na, nb));
            }
        }
    }
    if particles.free_count() == 0 {
        return Err(invalid(
            "particles",
            particles.len(),
            "the scenario needs at least one free particle",
        ));
    }
    if particles.len() > MAX_PARTICLES {
        return Err(invalid(
            "particles",
            particles.len(),
            format!("at most {MAX_PARTICLES} particles"),
        ));
    }

    let plane_walls: Vec<Wall> = walls
        .iter()
        .map(|(p, n, sp)| Wall::plane(*p, *n, *sp))
        .collect();
    let t_c = shortest_contact_time(&particles, &laws, &plane_walls)
        .map_err(|e| invalid("contact", "(laws)", e.to_string()))?;
    at_most_one(
        "run",
        &[
            ("dt", s.run.dt.is_some()),
            ("dt_fraction", s.run.dt_fraction.is_some()),
        ],
    )?;
    let dt = match (s.run.dt, s.run.dt_fraction) {
        (Some(dt), _) => {
            let dt = positive("run.dt", dt)?;
            if dt > MAX_FRACTION * t_c {
                return Err(invalid(
                    "run.dt",
                    dt,
                    format!(
                        "must not exceed t_c/10 = {:e} s (t_c = {t_c:e} s, the shortest contact time)",
                        MAX_FRACTION * t_c
                    ),
                ));
            }
            dt
        }
        (None, Some(q)) => {
            if !(q > 0.0 && q <= MAX_FRACTION) {
                return Err(invalid("run.dt_fraction", q, "must lie in (0, 0.1]"));
            }
            q * t_c
        }
        (None, None) => DEFAULT_FRACTION * t_c,
    };
    let steps = match (s.run.duration, s.run.steps) {
        (Some(t), None) => {
            let t = positive("run.duration", t)?;
            let n = (t / dt).round().max(1.0);
            if n > MAX_STEPS as f64 {
                return Err(invalid(
                    "run.duration",
                    t,
                    format!("needs {n:e} steps of {dt:e} s; at most {MAX_STEPS:e}"),
                ));
            }
            n as u64
        }
        (None, Some(n)) if n == 0 || n > MAX_STEPS => {
            return Err(invalid(
                "run.steps",
                n,
                format!("must lie in [1, {MAX_STEPS:e}]"),
            ));
        }
        (None, Some(n)) => n,
        _ => {
            return Err(invalid(
                "run",
                "duration/steps",
                "give exactly one of `duration` (s) and `steps`",
            ));
        }
    };
    if s.output.timeseries_rows == 0 {
        return Err(invalid("output.timeseries_rows", 0, "must be at least 1"));
    }

    let free: Vec<usize> = (0..particles.len())
        .filter(|&i| particles.motion[i].is_free())
        .collect();
    let r_min = free
        .iter()
        .map(|&i| particles.radius[i])
        .fold(f64::INFINITY, f64::min);
    let r_max = free
        .iter()
        .map(|&i| particles.radius[i])
        .fold(0.0, f64::max);
    let mean_diameter =
        2.0 * free.iter().map(|&i| particles.radius[i]).sum::<f64>() / free.len() as f64;
    let skin = match s.neighbor.skin {
        Some(v) => positive("neighbor.skin", v)?,
        None => 0.4 * r_min,
    };

    let target = match &s.preparation {
        None => None,
        Some(p) => {
            at_most_one(
                "preparation",
                &[
                    ("volume_fraction", p.volume_fraction.is_some()),
                    ("pressure", p.pressure.is_some()),
                ],
            )?;
            let target = match (p.volume_fraction, p.pressure) {
                (Some(phi), None) if phi > 0.0 && phi <= 0.70 => Target::VolumeFraction(phi),
                (Some(phi), None) => {
                    return Err(invalid(
                        "preparation.volume_fraction",
                        phi,
                        "must lie in (0, 0.70]",
                    ));
                }
                (None, Some(pr)) => Target::Pressure(positive("preparation.pressure", pr)?),
                _ => {
                    return Err(invalid(
                        "preparation",
                        "{}",
                        "give `volume_fraction` or `pressure`",
                    ));
                }
            };
            if s.domain.periodic != [true; 3] {
                return Err(invalid(
                    "domain.periodic",
                    format!("{:?}", s.domain.periodic),
                    "[preparation] compresses the box, which needs periodic = [true, true, true]",
                ));
            }
            if !s.walls.is_empty() || particles.free_count() != particles.len() {
                return Err(invalid(
                    "preparation",
                    "(with walls)",
                    "[preparation] compresses a box of free particles only: remove walls and prescribed particles",
                ));
            }
            let rate = p.strain_per_contact_time.unwrap_or(2e-3);
            if !(rate > 0.0 && rate <= 0.1) {
                return Err(invalid(
                    "preparation.strain_per_contact_time",
                    rate,
                    "must lie in (0, 0.1]",
                ));
            }
            let relax = non_negative(
                "preparation.relax_contact_times",
                p.relax_contact_times.unwrap_or(200.0),
            )?;
            let goal = match target {
                Target::VolumeFraction(phi) => format!("volume fraction {phi}"),
                Target::Pressure(pr) => format!("mean stress {pr:e} Pa"),
            };
            Some(PlannedPreparation {
                target,
                strain_rate: rate / t_c,
                relax_steps: (relax * t_c / dt).round() as u64,
                description: format!(
                    "compress to {goal} at strain {rate} per contact time, then relax for \
                     {relax} contact times"
                ),
            })
        }
    };
    let limits = Limits {
        displacement: fraction_limit(
            "run.max_displacement",
            s.run.max_displacement,
            DEFAULT_DISPLACEMENT,
        )?,
        overlap: fraction_limit("run.max_overlap", s.run.max_overlap, DEFAULT_OVERLAP)?,
    };

    let mut context = Context {
        seed: s.seed,
        dt,
        contact_time: t_c,
        steps,
        skin,
        radius_range: [r_min, r_max],
        mean_diameter,
        distribution: distribution.join("; "),
        size,
        warnings: Vec::new(),
    };
    in_box(s, &particles, &group_start, lo, size, &mut context.warnings)?;
    weight_within_limits(&particles, &laws, gravity, limits.overlap)?;
    let mut simulation = Simulation::new(particles, domain, laws, plane_walls, gravity, dt, skin)
        .map_err(|e| context.box_error(e, s.neighbor.skin.is_some()))?;
    simulation.limits = limits;
    initial_state(s, &simulation, &group_start, &mut context.warnings)?;
    Ok(Assembled {
        simulation,
        preparation: target,
        context,
    })
}

/// Refuses a free sphere whose centre lies outside the box along a non-periodic axis (it
/// would sit beyond the box's faces, counted in the volume fraction), and warns of those
/// outside along a periodic axis, which the run wraps into the box.
fn in_box(
    s: &Scenario,
    particles: &Particles,
    group_start: &[u32],
    lo: DVec3,
    size: [f64; 3],
    warnings: &mut Vec<String>,
) -> Result<(), ScenarioError> {
    let hi = lo + DVec3::from_array(size);
    let mut wrapped = Vec::new();
    for i in 0..particles.len() {
        if !particles.motion[i].is_free() {
            continue;
        }
        let r = particles.position[i];
        for (axis, name) in ["x", "y", "z"].into_iter().enumerate() {
            if (lo[axis]..=hi[axis]).contains(&r[axis]) {
                continue;
            }
            let who = particle_name(s, group_start, particles.id[i]);
            if s.domain.periodic[axis] {
                if wrapped.len() < 3 {
                    wrapped.push(format!("{who} ({name} = {:e} m)", r[axis]));
                } else if wrapped.len() == 3 {
                    wrapped.push("…".into());
                }
            } else {
                return Err(invalid(
                    format!("{who}.position"),
                    format!("{:?}", r.to_array()),
                    format!(
                        "lies outside the box along the non-periodic axis {name}: it must be in \
                         [{:e}, {:e}] m (domain.lo, domain.lo + domain.size)",
                        lo[axis], hi[axis]
                    ),
                ));
            }
        }
    }
    if !wrapped.is_empty() {
        warnings.push(format!(
            "spheres outside the box along a periodic axis are wrapped into it: {}",
            wrapped.join(", ")
        ));
    }
    Ok(())
}

/// Refuses a gravity under which even the lightest free sphere, resting on its own kind,
/// would overlap beyond `run.max_overlap` (`m g / k_n > max_overlap · a`): a run would stop
/// at once on its overlap limit.
fn weight_within_limits(
    particles: &Particles,
    laws: &ContactTable,
    gravity: DVec3,
    max_overlap: f64,
) -> Result<(), ScenarioError> {
    // |g| without overflow for huge components.
    let top = gravity.abs().max_element();
    let g = if top > 0.0 {
        top * (gravity / top).length()
    } else {
        0.0
    };
    let lightest = (0..particles.len())
        .filter(|&i| particles.motion[i].is_free())
        .min_by(|&a, &b| particles.mass[a].total_cmp(&particles.mass[b]));
    let Some(i) = lightest else { return Ok(()) };
    let sp = particles.species[i];
    let k_n = laws
        .get(sp, sp)
        .normal
        .max_stiffness(0.5 * particles.radius[i]);
    let (m, a) = (particles.mass[i], particles.radius[i]);
    if m * g > max_overlap * a * k_n {
        return Err(invalid(
            "gravity",
            format!("{:?}", gravity.to_array()),
            format!(
                "is too strong: the lightest sphere (m = {m:.4e} kg, radius {a:.4e} m) would \
                 overlap its support by m g / k_n = {:.4e} m, beyond run.max_overlap = \
                 {max_overlap} of its radius; |g| must be at most {:.4e} m/s²",
                m * g / k_n,
                max_overlap * a * k_n / m
            ),
        ));
    }
    Ok(())
}

/// An optional limit in (0, 10], or its default.
fn fraction_limit(key: &str, value: Option<f64>, default: f64) -> Result<f64, ScenarioError> {
    match value {
        None => Ok(default),
        Some(v) if v > 0.0 && v <= 10.0 => Ok(v),
        Some(v) => Err(invalid(
            key,
            v,
            "must lie in (0, 10] (a fraction of a radius)",
        )),
    }
}

/// The scenario's name of the particle with `id`: its group and index in the group.
fn particle_name(s: &Scenario, group_start: &[u32], id: u32) -> String {
    let k = group_start
        .partition_point(|&start| start <= id)
        .saturating_sub(1);
    let n = id - group_start.get(k).copied().unwrap_or(0);
    match s.particles.get(k) {
        Some(ParticleGroup::Explicit { .. }) => format!("particles[{k}].spheres[{n}]"),
        Some(ParticleGroup::File { path, .. }) => {
            format!("particles[{k}] (sphere {n} of {path})")
        }
        Some(_) => format!("particles[{k}] (sphere {n} of the group)"),
        None => format!("particle {id}"),
    }
}

/// Refuses an initial state the run would stop on at once (coincident or swallowed
/// spheres, speeds beyond `run.max_displacement`) naming the particles, and warns of
/// initial overlaps deeper than [`WARN_OVERLAP`] of the smaller radius.
fn initial_state(
    s: &Scenario,
    sim: &Simulation,
    group_start: &[u32],
    warnings: &mut Vec<String>,
) -> Result<(), ScenarioError> {
    let name = |id| particle_name(s, group_start, id);
    let pair_name = |pair: [u32; 2], wall: bool| {
        if wall {
            format!("{} and wall[{}]", name(pair[0]), pair[1])
        } else {
            format!("{} and {}", name(pair[0]), name(pair[1]))
        }
    };
    match sim.check_sanity() {
        Ok(()) => {}
        Err(Instability::TooDeep {
            pair,
            wall,
            overlap,
            ratio,
            limit,
        }) => {
            let what = if ratio >= 2.0 {
                "coincide (or one holds the other)"
            } else {
                "overlap too deeply"
            };
            return Err(invalid(
                "particles",
                pair_name(pair, wall),
                format!(
                    "these spheres {what}: overlap {overlap:e} m, {ratio:.3} of the smaller \
                     radius, beyond `run.max_overlap` = {limit}; move them apart"
                ),
            ));
        }
        Err(Instability::TooFast {
            id, speed, limit, ..
        }) => {
            return Err(invalid(
                format!("{}.velocity", name(id)),
                format!("{speed:e} m/s"),
                format!(
                    "moves more than `run.max_displacement` = {limit} of the smallest radius \
                     per step at this speed; lower the speed or the time step"
                ),
            ));
        }
        Err(e) => return Err(invalid("particles", "(initial state)", e.to_string())),
    }
    let deepest = sim.observables_deepest();
    if deepest.ratio > WARN_OVERLAP {
        warnings.push(format!(
            "{} overlap by {:.1} % of the smaller radius ({:e} m) at the start: expect a burst \
             of elastic energy in the first steps",
            pair_name(deepest.pair, deepest.wall),
            100.0 * deepest.ratio,
            deepest.overlap
        ));
    }
    Ok(())
}

/// Lees-Edwards shear and stress control, after the preparation.
fn configure_flow(s: &Scenario, simulation: &mut Simulation) -> Result<(), ScenarioError> {
    if s.domain.shear_rate.is_none() && s.domain.shear_dynamics != ShearDynamics::Lab {
        return Err(invalid(
            "domain.shear_dynamics",
            s.domain.shear_dynamics,
            "needs domain.shear_rate (a Lees-Edwards box)",
        ));
    }
    if let Some(rate) = s.domain.shear_rate {
        if !rate.is_finite() {
            return Err(invalid("domain.shear_rate", rate, "must be finite (1/s)"));
        }
        if !(s.domain.periodic[0] && s.domain.periodic[1]) {
            return Err(invalid(
                "domain.shear_rate",
                rate,
                "Lees-Edwards shear needs periodic x and y",
            ));
        }
        simulation.domain = simulation.domain.clone().with_lees_edwards(rate);
        if let Some(le) = simulation.domain.as_lees_edwards_mut() {
            le.dynamics = s.domain.shear_dynamics;
        }
        // The prepared velocities become those relative to the mean flow.
        let (p, domain) = (&mut simulation.particles, &simulation.domain);
        for i in 0..p.len() {
            if p.motion[i].is_free() {
                p.velocity[i] = domain.stored_velocity(p.position[i], p.velocity[i]);
            }
        }
        // The list stays valid: the shift starts at zero, so images keep their meaning.
    }
    if let Some(c) = &s.stress_control {
        if s.domain.shear_rate.is_none() {
            return Err(invalid(
                "stress_control",
                "(table)",
                "needs domain.shear_rate (a Lees-Edwards box)",
            ));
        }
        simulation.set_stress_control(StressControl {
            target: positive("stress_control.target", c.target)?,
            modulus: positive("stress_control.modulus", c.modulus)?,
            time: positive("stress_control.time", c.time)?,
            max_strain_per_step: 1e-4,
        });
    }
    Ok(())
}

fn read(base_dir: &Path, path: &str) -> Result<String, ScenarioError> {
    let full = base_dir.join(path);
    std::fs::read_to_string(&full).map_err(|source| ScenarioError::Io { path: full, source })
}
