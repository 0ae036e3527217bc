//! Coarse-grained fields of the split-bottom cell (docs/coarse-graining.md): the
//! axisymmetric `(r, z)` grid over the cell, sampled while the run goes through its
//! averaging window, and the same fields from the run's stored snapshots afterwards
//! ([`offline_fields`]).

use super::spec::SplitBottomSpec;
use super::state::SplitBottomState;
use crate::cg::shear_band::{
    BandAtHeight, LinearFit, RheologyPoint, band_by_height, band_points, fit_friction_line,
};
use crate::cg::snapshot::{contacts_csv, particles_csv, read_contacts_csv, read_particles_csv};
use crate::cg::{
    CgError, CgSums, ContactRecord, FieldPoint, Grid, Kernel, KernelShape, Material,
    ParticleRecord, Snapshot, fields,
};
use crate::io::atomic::write_atomic;
use crate::plot::{HeatMap, Labels, Markers, Series, plot_svg};
use crate::rheology::{MuLaw, PhiLaw};
use crate::run::{RunError, io_err, read_checkpoint};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// How the cell's fields are coarse-grained (the `cg_*` keys of the spec).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldSettings {
    /// Kernel shape.
    pub kernel: KernelShape,
    /// Kernel width in units of `d_p`.
    pub width: f64,
    /// Grid spacing in units of `d_p`.
    pub spacing: f64,
}

impl FieldSettings {
    /// The settings of a spec.
    pub fn of(spec: &SplitBottomSpec) -> FieldSettings {
        FieldSettings {
            kernel: spec.cg_kernel,
            width: spec.cg_width,
            spacing: spec.cg_spacing,
        }
    }

    /// The kernel (width `width · d_p`).
    ///
    /// # Errors
    /// [`CgError::Invalid`] for a width that is not positive.
    pub fn kernel(&self, diameter: f64) -> Result<Kernel, CgError> {
        Kernel::new(self.kernel, self.width * diameter)
    }

    /// The `(r, z)` grid over the cell of a run: `R_i ≤ r ≤ R_o`, from the bottom to a
    /// diameter above the settled surface, cells of `spacing · d_p`.
    ///
    /// # Errors
    /// [`CgError::Invalid`] for a spacing that is not positive or a grid too large.
    pub fn grid(&self, run: &SplitBottomState) -> Result<Grid, CgError> {
        let d = run.spec.diameter;
        if !(self.spacing.is_finite() && self.spacing > 0.0) {
            return Err(CgError::Invalid(format!(
                "the grid spacing (cg_spacing) must be > 0 diameters, got {}",
                self.spacing
            )));
        }
        let g = &run.geometry;
        let top = run.settled.as_ref().map_or(g.height, |s| s.surface_height) + d;
        let h = self.spacing * d;
        let cells = |len: f64| ((len / h).ceil() as usize).max(1);
        let grid = Grid::Axisymmetric {
            r: [g.inner_radius, g.outer_radius],
            z: [0.0, top],
            bins: [cells(g.outer_radius - g.inner_radius), cells(top)],
            angle: g.angle,
        };
        grid.validate()?;
        Ok(grid)
    }
}

/// The particle-scale constants of a run for the local `I`, `p*` and `Bo`: `f_a^max` of
/// a pair of mean particles under the law the run uses (one law for every pair).
pub fn material(run: &SplitBottomState) -> Material {
    let spec = &run.spec;
    let a = 0.5 * spec.diameter;
    Material {
        diameter: spec.diameter,
        particle_density: spec.density,
        stiffness: spec.stiffness,
        max_adhesion: run.simulation.laws.get(0, 0).adhesion.max_force(a, a),
    }
}

/// The snapshot of the run's current state, with the contacts of its last step.
pub fn snapshot(run: &SplitBottomState, contacts: &[ContactRecord]) -> Snapshot {
    let p = &run.simulation.particles;
    Snapshot::assemble(
        run.simulation.time,
        &ParticleRecord::all(p),
        contacts,
        Vec::new(),
    )
}

/// The files holding a stored snapshot's particles and contacts, next to its `.vtp` file.
pub fn record_paths(dir: &Path, vtp: &str) -> (PathBuf, PathBuf) {
    let stem = vtp.strip_suffix(".vtp").unwrap_or(vtp);
    (
        dir.join(format!("{stem}.particles.csv")),
        dir.join(format!("{stem}.contacts.csv")),
    )
}

/// Writes the particle and contact records of the run's current state next to the snapshot
/// `vtp` (a path relative to `dir`).
pub fn write_records(
    run: &SplitBottomState,
    contacts: &[ContactRecord],
    dir: &Path,
    vtp: &str,
) -> Result<(), RunError> {
    let (pp, cp) = record_paths(dir, vtp);
    let particles = particles_csv(&ParticleRecord::all(&run.simulation.particles));
    write_atomic(&pp, particles.as_bytes()).map_err(io_err("write", &pp))?;
    write_atomic(&cp, contacts_csv(contacts).as_bytes()).map_err(io_err("write", &cp))
}

/// Writes every output of `sums`' fields into `dir`: `fields.csv` and `fields.vti`, the band
/// tables and figure ([`write_band`]) and the heat maps ([`write_maps`]); returns the band.
///
/// # Errors
/// [`RunError`] when a file cannot be written.
pub fn write_outputs(
    run: &SplitBottomState,
    sums: &CgSums,
    dir: &Path,
) -> Result<BandRheology, RunError> {
    let points = fields(sums, Some(&material(run)));
    let csv = dir.join("fields.csv");
    write_atomic(
        &csv,
        crate::cg::output::to_csv(&sums.grid, &points).as_bytes(),
    )
    .map_err(io_err("write", &csv))?;
    let vti = dir.join("fields.vti");
    write_atomic(
        &vti,
        crate::cg::output::to_vti(&sums.grid, &points).as_bytes(),
    )
    .map_err(io_err("write", &vti))?;
    let band = band_of_fields(run, &sums.grid, &points);
    write_band(&band, dir)?;
    write_maps(&sums.grid, &points, &band, dir)?;
    Ok(band)
}

/// The state of the run in `dir` as of its last checkpoint, read without locking or
/// changing the directory.
///
/// # Errors
/// [`RunError`] when the checkpoint cannot be read.
pub fn read_run(dir: &Path) -> Result<SplitBottomState, RunError> {
    read_checkpoint(&dir.join("checkpoint.bin"))
}

/// The fields of the run in `dir` (read by [`read_run`]) from its stored snapshots in the
/// averaging window, with `settings`.
///
/// # Errors
/// [`RunError`] when a snapshot's record files cannot be read, or the settings are out of
/// range.
pub fn offline_fields(
    dir: &Path,
    run: &SplitBottomState,
    settings: FieldSettings,
) -> Result<CgSums, RunError> {
    let kernel = settings.kernel(run.spec.diameter)?;
    let mut sums = CgSums::new(settings.grid(run)?)?;
    // Refused before anything is read or written: fields of no sample are all NaN.
    if window_records(dir, run).next().is_none() {
        return Err(RunError::Scenario(crate::scenario::invalid(
            "snapshots",
            run.spec.snapshots,
            format!(
                "the run stored {} snapshots, none in its averaging window (from \
                 average_from = {} s after the start of shear): there is nothing to \
                 coarse-grain; run the cell with snapshots ≥ 1 (its own fields, \
                 cg_every > 0, are in its fields.csv already)",
                run.snapshots.len(),
                run.spec.average_from
            ),
        )));
    }
    for snapshot in window_records(dir, run) {
        let (time, particles, contacts) = snapshot?;
        sums.add_snapshot(
            &kernel,
            &Snapshot::assemble(time, &particles, &contacts, Vec::new()),
        );
    }
    Ok(sums)
}

/// A stored snapshot's time (s) with its particle and contact records.
type Records = (f64, Vec<ParticleRecord>, Vec<ContactRecord>);

/// The records of the run's stored snapshots in the averaging window, read one at a time.
fn window_records<'a>(
    dir: &'a Path,
    run: &'a SplitBottomState,
) -> impl Iterator<Item = Result<Records, RunError>> + 'a {
    let t0 = run.shear_start.map_or(f64::INFINITY, |s| s.0);
    run.snapshots
        .iter()
        .filter(move |(time, _)| time - t0 >= run.spec.average_from)
        .map(move |(time, vtp)| {
            let (pp, cp) = record_paths(dir, vtp);
            let read = |p: &Path| std::fs::read_to_string(p).map_err(io_err("read", p));
            let particles = read_particles_csv(&read(&pp)?, &pp.display().to_string())?;
            let contacts = read_contacts_csv(&read(&cp)?, &cp.display().to_string())?;
            Ok((*time, particles, contacts))
        })
}

/// Writes `mercury.data` and `mercury.fstat` into `out`: the run's stored snapshots in the
/// averaging window in MercuryDPM's formats ([`crate::cg::mercury`]); returns how many.
///
/// # Errors
/// [`RunError`] when a snapshot cannot be read or exported, or a file cannot be written.
pub fn export_mercury(dir: &Path, run: &SplitBottomState, out: &Path) -> Result<usize, RunError> {
    let (mut data, mut fstat, mut count) = (String::new(), String::new(), 0);
    for snapshot in window_records(dir, run) {
        let (time, particles, contacts) = snapshot?;
        crate::cg::mercury::data_block(&mut data, time, &particles)?;
        crate::cg::mercury::fstat_block(&mut fstat, time, &particles, &contacts)?;
        count += 1;
    }
    for (name, text) in [("mercury.data", data), ("mercury.fstat", fstat)] {
        let path = out.join(name);
        write_atomic(&path, text.as_bytes()).map_err(io_err("write", &path))?;
    }
    Ok(count)
}

/// Lowest pressure, in units of `f_g / d_p²`, of the band points fitted by `τ = μ P + c`
/// (Roy et al. 2016 leave out `P* < 4.42`, where the data bend away from the line).
pub const BAND_PRESSURE_MIN_SCALED: f64 = 4.42;

/// The shear band of the fields and its local rheology, with the torque it implies.
#[derive(Clone, Debug, serde::Serialize)]
pub struct BandRheology {
    /// The band per height.
    pub heights: Vec<BandAtHeight>,
    /// The rheology points of the centre regions.
    pub points: Vec<RheologyPoint>,
    /// Lowest pressure fitted (Pa).
    pub pressure_min: f64,
    /// `τ = μ P + c` over the points above `pressure_min`, if there are enough.
    pub fit: Option<LinearFit>,
    /// The cohesion `c* = c d_p² / f_g`.
    pub cohesion_scaled: Option<f64>,
    /// Mean pressure of the fitted points `P_avg` (Pa).
    pub pressure_avg: f64,
    /// The factor `M = 2πH(R_o² − R_i²) + (2/3)π(R_o³ + R_i³ − 2R_s³)` (m³) of the
    /// macroscopic torque (Roy et al. 2016, Eq. 26), `H` the settled height.
    pub torque_factor: f64,
    /// The macroscopic torque `T_macro = M (μ P_avg + c)` of the full ring (N m).
    pub torque_macro: Option<f64>,
    /// The particles' sliding friction `μ_p`, which picks the laws' row.
    pub mu_p: f64,
    /// The band's `φ` and `μ` against the shear box's laws at the same `I`, `p*`, `Bo`, if
    /// the cell's `μ_p` is tabulated.
    pub laws: Option<LawComparison>,
}

/// The band rheology of a run as its `summary.json` records it (`band_rheology`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BandSummary {
    /// Lowest pressure fitted (Pa).
    pub pressure_min: f64,
    /// Rheology points of the centre regions (fitted or not).
    pub points: usize,
    /// `τ = μ P + c` (`c` in Pa), if there were enough points.
    pub fit: Option<LinearFit>,
    /// `c* = c d_p² / f_g`.
    pub cohesion_scaled: Option<f64>,
    /// Mean pressure of the fitted points `P_avg` (Pa).
    pub pressure_avg: f64,
    /// `M` of Roy et al. 2016, Eq. 26 (m³).
    pub torque_factor: f64,
    /// `T_macro = M (μ P_avg + c)` of the full ring (N m).
    pub torque_macro: Option<f64>,
    /// The measured wall torque of the full ring, the mean of the window (N m).
    pub torque_measured: Option<f64>,
    /// `c_eq = T/M − μ P_avg` (Pa; Roy et al. 2016, Eq. 27).
    pub cohesion_from_torque: Option<f64>,
    /// The band against the shear box's laws.
    pub shear_box_laws: Option<LawComparison>,
}

impl BandSummary {
    /// The summary of `band` with the run's measured wall torque `torque` (N m).
    pub fn new(band: &BandRheology, torque: Option<f64>) -> BandSummary {
        BandSummary {
            pressure_min: band.pressure_min,
            points: band.points.len(),
            fit: band.fit,
            cohesion_scaled: band.cohesion_scaled,
            pressure_avg: band.pressure_avg,
            torque_factor: band.torque_factor,
            torque_macro: band.torque_macro,
            torque_measured: torque,
            cohesion_from_torque: band
                .fit
                .zip(torque)
                .map(|(f, t)| t / band.torque_factor - f.slope * band.pressure_avg),
            shear_box_laws: band.laws,
        }
    }
}

/// Ratios of a quantity measured at the band points to a law's prediction at the same local
/// numbers: their mean and its standard error, over the points inside the law's fit range.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Ratio {
    /// Mean of measured over predicted.
    pub mean: f64,
    /// Standard error of the mean (the points are correlated over a kernel width, so this
    /// understates the uncertainty).
    pub stderr: f64,
    /// Points compared.
    pub points: usize,
}

impl Ratio {
    fn of(ratios: &[f64]) -> Option<Ratio> {
        let n = ratios.len();
        if n < 2 {
            return None;
        }
        let mean = ratios.iter().sum::<f64>() / n as f64;
        let var = ratios.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        Some(Ratio {
            mean,
            stderr: (var / n as f64).sqrt(),
            points: n,
        })
    }
}

/// The band's local rheology against Shi et al. 2020's shear-box laws (docs/model.md §8):
/// `φ(I, p*, Bo)` over its fit range (`φ > 0.5`, `I < 0.25`, `p* < 0.03`) and `μ(I, p*, Bo)`
/// over its own (`0.005 < I < 0.5`, `p* < 0.1`), at the band points above the fitted
/// pressure cut-off.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LawComparison {
    /// `μ_p` of the laws' row.
    pub mu_p: f64,
    /// Median inertial number of the compared points.
    pub inertial_median: f64,
    /// Median softness of the compared points.
    pub softness_median: f64,
    /// `φ / φ_law` (named `volume_fraction` in summaries written before 2026-12-06).
    #[serde(alias = "volume_fraction")]
    pub volume_fraction_ratio: Option<Ratio>,
    /// `μ / μ_law` (named `friction` in summaries written before 2026-12-06).
    #[serde(alias = "friction")]
    pub friction_ratio: Option<Ratio>,
}

/// `φ_law` and `μ_law` at a band point (`NaN` outside the laws' fit ranges or without a
/// tabulated `μ_p`).
fn law_values(mu_p: f64, p: &RheologyPoint) -> (f64, f64) {
    let (i, ps, bo) = (p.inertial_number, p.softness, p.bond_number);
    let phi = PhiLaw::for_mu_p(mu_p)
        .filter(|_| p.volume_fraction > 0.5 && i < 0.25 && ps < 0.03)
        .map_or(f64::NAN, |l| l.phi(i, ps, bo));
    let mu = MuLaw::for_mu_p(mu_p)
        .filter(|_| (0.005..0.5).contains(&i) && ps < 0.1)
        .map_or(f64::NAN, |l| l.mu(i, ps, bo));
    (phi, mu)
}

fn compare_laws(mu_p: f64, points: &[RheologyPoint], p_min: f64) -> Option<LawComparison> {
    if PhiLaw::for_mu_p(mu_p).is_none() && MuLaw::for_mu_p(mu_p).is_none() {
        return None;
    }
    let used: Vec<&RheologyPoint> = points
        .iter()
        .filter(|p| p.pressure >= p_min && p.inertial_number.is_finite())
        .collect();
    let (mut phi, mut mu, mut inertial, mut softness) = (vec![], vec![], vec![], vec![]);
    for p in &used {
        let (phi_law, mu_law) = law_values(mu_p, p);
        if phi_law.is_finite() {
            phi.push(p.volume_fraction / phi_law);
        }
        if mu_law.is_finite() {
            mu.push(p.friction / mu_law);
        }
        if phi_law.is_finite() || mu_law.is_finite() {
            inertial.push(p.inertial_number);
            softness.push(p.softness);
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    Some(LawComparison {
        mu_p,
        inertial_median: median(&mut inertial),
        softness_median: median(&mut softness),
        volume_fraction_ratio: Ratio::of(&phi),
        friction_ratio: Ratio::of(&mu),
    })
}

/// The band and its rheology from `sums`' fields (Roy et al. 2016, Sects. 3.1–3.2).
pub fn band_rheology(run: &SplitBottomState, sums: &CgSums) -> BandRheology {
    band_of_fields(run, &sums.grid, &fields(sums, Some(&material(run))))
}

/// The band and its rheology from the fields `points` on `grid`.
fn band_of_fields(run: &SplitBottomState, grid: &Grid, points: &[FieldPoint]) -> BandRheology {
    let spec = &run.spec;
    let heights = band_by_height(grid, points, spec.omega, 0.8);
    let band = band_points(grid, points, &heights);
    let d = spec.diameter;
    let weight = spec.groups(&run.geometry, run.simulation.dt).weight;
    let pressure_min = BAND_PRESSURE_MIN_SCALED * weight / (d * d);
    let fit = fit_friction_line(&band, pressure_min);
    let used: Vec<f64> = band
        .iter()
        .filter(|p| p.pressure >= pressure_min)
        .map(|p| p.pressure)
        .collect();
    let pressure_avg = used.iter().sum::<f64>() / used.len().max(1) as f64;
    let g = &run.geometry;
    let h = run.settled.as_ref().map_or(g.height, |s| s.surface_height);
    let (ro, ri, rs) = (g.outer_radius, g.inner_radius, g.split_radius);
    let torque_factor = 2.0 * std::f64::consts::PI * h * (ro * ro - ri * ri)
        + 2.0 / 3.0 * std::f64::consts::PI * (ro.powi(3) + ri.powi(3) - 2.0 * rs.powi(3));
    BandRheology {
        laws: compare_laws(spec.friction, &band, pressure_min),
        mu_p: spec.friction,
        cohesion_scaled: fit.map(|f| f.intercept * d * d / weight),
        torque_macro: fit.map(|f| torque_factor * (f.slope * pressure_avg + f.intercept)),
        heights,
        points: band,
        pressure_min,
        fit,
        pressure_avg,
        torque_factor,
    }
}

/// Writes `band-heights.csv` (the band per height) and `band-points.csv` (its rheology
/// points) into `dir`.
pub fn write_band(band: &BandRheology, dir: &Path) -> Result<(), RunError> {
    let mut s = String::from(
        "z,max_strain_rate,r_at_max,centre_r_lo,centre_r_hi,erf_centre,erf_centre_err,\
         erf_width,erf_width_err,gauss_centre,gauss_centre_err,gauss_sigma,gauss_sigma_err\n",
    );
    for b in &band.heights {
        let e = b.erf.as_ref().ok();
        let g = b.gauss.as_ref().ok();
        let nan = f64::NAN;
        let cols = [
            b.z,
            b.max_strain_rate,
            b.r_at_max,
            b.centre_region[0],
            b.centre_region[1],
            e.map_or(nan, |e| e.centre),
            e.map_or(nan, |e| e.centre_err),
            e.map_or(nan, |e| e.width),
            e.map_or(nan, |e| e.width_err),
            g.map_or(nan, |g| g.centre),
            g.map_or(nan, |g| g.centre_err),
            g.map_or(nan, |g| g.sigma),
            g.map_or(nan, |g| g.sigma_err),
        ];
        let row: Vec<String> = cols.iter().map(|x| format!("{x:e}")).collect();
        s.push_str(&row.join(","));
        s.push('\n');
    }
    let path = dir.join("band-heights.csv");
    write_atomic(&path, s.as_bytes()).map_err(io_err("write", &path))?;
    let mut s = String::from("r,z,I,pstar,Bo,phi,mu,tau,P,strain_rate,Z,phi_law,mu_law\n");
    for p in &band.points {
        let (phi_law, mu_law) = law_values(band.mu_p, p);
        let cols = [
            p.r,
            p.z,
            p.inertial_number,
            p.softness,
            p.bond_number,
            p.volume_fraction,
            p.friction,
            p.shear_stress,
            p.pressure,
            p.strain_rate,
            p.coordination,
            phi_law,
            mu_law,
        ];
        let row: Vec<String> = cols.iter().map(|x| format!("{x:e}")).collect();
        s.push_str(&row.join(","));
        s.push('\n');
    }
    let path = dir.join("band-points.csv");
    write_atomic(&path, s.as_bytes()).map_err(io_err("write", &path))?;
    write_band_figure(band, dir)
}

/// `band-rheology.svg`: `τ` against `P` of the band points, with the fitted line over the
/// fitted range.
fn write_band_figure(band: &BandRheology, dir: &Path) -> Result<(), RunError> {
    let finite = || {
        band.points
            .iter()
            .filter(|p| p.pressure.is_finite() && p.shear_stress.is_finite())
    };
    // The fit takes the points at or above its pressure cut-off; those below are drawn
    // apart.
    type Points = Vec<(f64, f64, f64)>;
    let (fitted, excluded): (Points, Points) = finite()
        .map(|p| (p.pressure, p.shear_stress, 0.0))
        .partition(|p| p.0 >= band.pressure_min);
    if fitted.is_empty() && excluded.is_empty() {
        return Ok(());
    }
    let top = finite().map(|p| p.pressure).fold(0.0, f64::max);
    let line: Vec<(f64, f64)> = band
        .fit
        .iter()
        .flat_map(|f| [band.pressure_min, top].map(|p| (p, f.slope * p + f.intercept)))
        .collect();
    let label = band.fit.map_or("no fit (too few points)".to_string(), |f| {
        let sign = if f.intercept < 0.0 { '−' } else { '+' };
        format!("τ = {:.3} P {sign} {:.3} Pa", f.slope, f.intercept.abs())
    });
    let cut = format!("below P_min = {:.3} Pa, not fitted", band.pressure_min);
    let svg = plot_svg(
        &Labels {
            title: "Shear band: shear stress against pressure",
            x: "pressure P (Pa)",
            y: "shear stress τ (Pa)",
        },
        &[Series {
            dashed_as: None,
            label: &label,
            points: &line,
        }],
        &[
            Markers {
                label: "band centre points, fitted",
                points: &fitted,
            },
            Markers {
                label: &cut,
                points: &excluded,
            },
        ],
    )
    .map_err(|e| RunError::Scenario(crate::scenario::invalid("figure", "band-rheology.svg", e)))?;
    let path = dir.join("band-rheology.svg");
    write_atomic(&path, svg.as_bytes()).map_err(io_err("write", &path))
}

/// The fields drawn as heat maps over `(r, z)`: file stem, title, colour-bar label, and how to
/// read the value (in the unit of the label) from a point.
type MapField = (
    &'static str,
    &'static str,
    &'static str,
    fn(&FieldPoint) -> f64,
);

const MAPS: [MapField; 5] = [
    ("map-velocity", "Azimuthal velocity", "v_φ (mm/s)", |p| {
        1e3 * p.velocity[1]
    }),
    ("map-strain-rate", "Strain rate", "γ̇ (1/s)", |p| {
        p.strain_rate
    }),
    ("map-volume-fraction", "Volume fraction", "φ", |p| {
        p.volume_fraction
    }),
    ("map-pressure", "Pressure", "P (Pa)", |p| p.pressure),
    ("map-friction", "Macroscopic friction", "μ = τ/P", |p| {
        p.friction
    }),
];

/// Writes `map-*.svg` and `map-*.png`: `v_φ`, `γ̇`, `φ`, `P` and `μ` over `(r, z)` (in mm),
/// with the band centre per height (the error-function fit's `R_c`, and the strain-rate
/// maximum) drawn over them. Points below a hundredth of the largest density (outside the
/// packing) are left blank.
///
/// # Errors
/// [`RunError`] when a map cannot be drawn or written.
pub fn write_maps(
    grid: &Grid,
    points: &[FieldPoint],
    band: &BandRheology,
    dir: &Path,
) -> Result<(), RunError> {
    let ax = grid.axes();
    let mm = |a: usize| -> Vec<f64> { (0..ax.n[a]).map(|i| 1e3 * ax.point(a, i)).collect() };
    let (rs, zs) = (mm(0), mm(1));
    let top = points.iter().map(|p| p.density).fold(0.0, f64::max);
    let erf: Vec<(f64, f64)> = band
        .heights
        .iter()
        .filter_map(|b| b.erf.as_ref().ok().map(|e| (1e3 * e.centre, 1e3 * b.z)))
        .collect();
    let peak: Vec<(f64, f64)> = band
        .heights
        .iter()
        .map(|b| (1e3 * b.r_at_max, 1e3 * b.z))
        .collect();
    let overlays = [
        Series {
            dashed_as: None,
            label: "band centre R_c (erf fit)",
            points: &erf,
        },
        Series {
            dashed_as: None,
            label: "strain-rate maximum",
            points: &peak,
        },
    ];
    let failed = |name: &str, e: String| {
        RunError::Scenario(crate::scenario::invalid("figure", format!("{name}.svg"), e))
    };
    // The maps are drawn and written side by side on rayon's pool.
    MAPS.par_iter().try_for_each(|(name, title, value, read)| {
        let values: Vec<f64> = points
            .iter()
            .map(|p| {
                if p.density > 0.01 * top {
                    read(p)
                } else {
                    f64::NAN
                }
            })
            .collect();
        let map = HeatMap {
            title,
            x: "r (mm)",
            y: "z (mm)",
            value,
            xs: &rs,
            ys: &zs,
            values: &values,
            overlays: &overlays,
        };
        let svg = map.to_svg().map_err(|e| failed(name, e))?;
        let path = dir.join(format!("{name}.svg"));
        write_atomic(&path, svg.as_bytes()).map_err(io_err("write", &path))?;
        let png = map.to_png().map_err(|e| failed(name, e))?;
        let path = dir.join(format!("{name}.png"));
        write_atomic(&path, &png).map_err(io_err("write", &path))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(inertial: f64, softness: f64, scale: f64) -> RheologyPoint {
        let phi = PhiLaw::for_mu_p(0.01).expect("tabulated");
        let mu = MuLaw::for_mu_p(0.01).expect("tabulated");
        RheologyPoint {
            r: 0.08,
            z: 0.01,
            inertial_number: inertial,
            softness,
            bond_number: 0.5,
            volume_fraction: scale * phi.phi(inertial, softness, 0.5),
            friction: scale * mu.mu(inertial, softness, 0.5),
            shear_stress: 30.0,
            pressure: 200.0,
            strain_rate: 1.0,
            coordination: 4.0,
        }
    }

    #[test]
    fn band_points_on_the_laws_give_ratios_of_one_inside_the_fit_ranges() {
        let mut points: Vec<RheologyPoint> = (1..=9)
            .map(|k| point(0.01 * f64::from(k), 0.002 * f64::from(k), 1.0))
            .collect();
        // Outside both fit ranges (I ≥ 0.5), below the pressure cut-off, or beyond the φ
        // law's softness (p* ≥ 0.03, where only μ counts): not, or only partly, compared.
        points.push(point(0.6, 0.01, 2.0));
        points.push(RheologyPoint {
            pressure: 50.0,
            ..point(0.02, 0.01, 2.0)
        });
        points.push(point(0.02, 0.05, 1.0));
        let c = compare_laws(0.01, &points, 100.0).expect("tabulated μ_p");
        let (phi, mu) = (
            c.volume_fraction_ratio.expect("φ"),
            c.friction_ratio.expect("μ"),
        );
        assert_eq!((phi.points, mu.points), (9, 10));
        assert!((phi.mean - 1.0).abs() < 1e-12 && phi.stderr < 1e-12);
        assert!((mu.mean - 1.0).abs() < 1e-12 && mu.stderr < 1e-12);
        assert!((c.inertial_median - 0.05).abs() < 1e-12);
        // Scaled points give the scale; an untabulated μ_p gives no comparison.
        let scaled: Vec<RheologyPoint> = (1..=4)
            .map(|k| point(0.01 * f64::from(k), 0.005, 0.9))
            .collect();
        let c = compare_laws(0.01, &scaled, 100.0).expect("tabulated μ_p");
        assert!((c.friction_ratio.expect("μ").mean - 0.9).abs() < 1e-12);
        assert!(compare_laws(0.123, &scaled, 100.0).is_none());
    }
}
