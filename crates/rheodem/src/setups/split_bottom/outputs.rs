//! The outputs of a split-bottom run: the time series, the velocity profiles of the
//! band, the fields with their band and maps, the figures and the summary.

use super::fields::{self as cell_fields, BandRheology};
use super::state::{OUTER_BOTTOM, OUTER_WALL, PARTS, Row, SLABS, SplitBottomState, Stage};
use crate::band::erf_profile;
use crate::io::atomic::write_atomic;
use crate::plot::{Labels, Markers, Series, plot_svg};
use crate::run::{RunError, io_err};
use crate::scenario::invalid;
use std::path::Path;

impl SplitBottomState {
    /// Writes the time series, the band profiles, the fields (with their band and maps)
    /// and, once the run is done, the figures; returns the summary.
    pub(super) fn write_files(&self, dir: &Path) -> Result<serde_json::Value, RunError> {
        let mut csv = String::from(
            "time,stage,angle,kinetic_energy,elastic_energy,contacts,coordination,\
             bridges_per_particle,surface_height,torque_inner_wall,torque_inner_bottom,\
             torque_outer_bottom,torque_outer_wall,torque_backstops,net_torque\n",
        );
        for r in &self.rows {
            let stage = match r.stage {
                Stage::Settle => "settle",
                _ => "shear",
            };
            csv.push_str(&format!(
                "{:e},{stage},{:e},{:e},{:e},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}\n",
                r.time,
                r.angle,
                r.kinetic_energy,
                r.elastic_energy,
                r.contacts,
                r.coordination,
                r.bridges_per_particle,
                r.surface_height,
                r.torque[0],
                r.torque[1],
                r.torque[2],
                r.torque[3],
                r.torque[4],
                r.net_torque
            ));
        }
        let path = dir.join("timeseries.csv");
        write_atomic(&path, csv.as_bytes()).map_err(io_err("write", &path))?;

        let mut band = String::from("slab,z_lo,z_hi,r,ratio,stderr,count\n");
        for (p, name) in self.profiles.iter().zip(SLABS) {
            let (lo, hi) = p.slab();
            for b in p.bins() {
                band.push_str(&format!(
                    "{name},{lo:e},{hi:e},{:e},{:e},{:e},{}\n",
                    b.r, b.mean, b.stderr, b.count
                ));
            }
        }
        let path = dir.join("band.csv");
        write_atomic(&path, band.as_bytes()).map_err(io_err("write", &path))?;
        let band = match self.fields.as_ref().filter(|s| s.snapshots > 0) {
            Some(sums) => Some(cell_fields::write_outputs(self, sums, dir)?),
            None => None,
        };

        if self.stage == Stage::Done {
            self.write_figures(dir)?;
        }
        Ok(self.summary_with(band.as_ref()))
    }

    /// The summary (the driver adds the status, version, commit and last checkpoint), with
    /// the shear band of the fields when there is one.
    pub(super) fn summary_with(&self, band: Option<&BandRheology>) -> serde_json::Value {
        serde_json::json!({
            "program": "rheodem split-bottom",
            "seed": self.spec.seed,
            "stage": self.stage,
            "from": self.from,
            "time": self.simulation.time,
            "steps": self.simulation.step,
            "wall_seconds": self.wall_seconds,
            "particles": self.simulation.particles.len(),
            "free_particles": self.simulation.particles.free_count(),
            "particle_steps_per_second": if self.wall_seconds > 0.0 {
                let steps = self.simulation.step - self.first_step;
                self.simulation.particles.len() as f64 * steps as f64 / self.wall_seconds
            } else { 0.0 },
            "threads": rayon::current_num_threads(),
            "spec": self.spec,
            "geometry": self.geometry,
            "groups": self.spec.groups(&self.geometry, self.simulation.dt),
            "time_step_rule": self.spec.time_step,
            "parts": PARTS,
            "settled": self.settled,
            "results": (self.stage != Stage::Settle).then(|| self.results()),
            "fields": self.fields.as_ref().map(|f| serde_json::json!({
                "samples": f.snapshots,
                "grid": f.grid,
                "kernel": self.spec.cg_kernel,
                "width": self.spec.cg_width * self.spec.diameter,
            })),
            "band_rheology": band.map(|b| cell_fields::BandSummary::new(
                b,
                self.results().net_torque.map(|e| e.mean),
            )),
        })
    }

    /// `torque.svg`: the torques against the rotation angle (Roy et al. 2016, Fig. 10);
    /// `band.svg`: the velocity profiles with their fits.
    fn write_figures(&self, dir: &Path) -> Result<(), RunError> {
        let shear: Vec<&Row> = self
            .rows
            .iter()
            .filter(|r| r.stage != Stage::Settle)
            .collect();
        let curve = |f: &dyn Fn(&Row) -> f64| -> Vec<(f64, f64)> {
            shear.iter().map(|r| (r.angle, f(r))).collect()
        };
        let net = curve(&|r| r.net_torque);
        let drive = curve(&|r| -(r.torque[OUTER_BOTTOM as usize] + r.torque[OUTER_WALL as usize]));
        let balance = curve(&|r| r.torque.iter().sum());
        let svg = plot_svg(
            &Labels {
                title: "Wall torque, full ring",
                x: "rotation angle (rad)",
                y: "torque (N m)",
            },
            &[
                Series {
                    dashed_as: None,
                    label: "net (fixed − rotating parts)",
                    points: &net,
                },
                Series {
                    dashed_as: None,
                    label: "drive (−rotating parts)",
                    points: &drive,
                },
                Series {
                    dashed_as: None,
                    label: "balance (all parts)",
                    points: &balance,
                },
            ],
            &[],
        )
        .map_err(|e| RunError::Scenario(invalid("figure", "torque.svg", e)))?;
        let path = dir.join("torque.svg");
        write_atomic(&path, svg.as_bytes()).map_err(io_err("write", &path))?;

        let results = self.results();
        let mut measured = Vec::new();
        let mut fitted = Vec::new();
        for p in &self.profiles {
            let bins = p.bins();
            measured.push(
                bins.iter()
                    .filter(|b| b.count > 1)
                    .map(|b| (b.r, b.mean, b.stderr))
                    .collect::<Vec<_>>(),
            );
        }
        for fit in &results.band {
            let points = match &fit.fit {
                Ok(f) => {
                    let (lo, hi) = (self.geometry.inner_radius, self.geometry.outer_radius);
                    (0..=100)
                        .map(|k| {
                            let r = lo + (hi - lo) * k as f64 / 100.0;
                            (r, erf_profile(r, f.centre, f.width))
                        })
                        .collect()
                }
                Err(_) => Vec::new(),
            };
            fitted.push(points);
        }
        let names: Vec<String> = SLABS.iter().map(|s| format!("{s} slab, fit")).collect();
        let series: Vec<Series<'_>> = fitted
            .iter()
            .zip(&names)
            .map(|(p, n)| Series {
                dashed_as: None,
                label: n,
                points: p,
            })
            .collect();
        let markers: Vec<Markers<'_>> = measured
            .iter()
            .zip(SLABS)
            .map(|(p, n)| Markers {
                label: n,
                points: p,
            })
            .collect();
        let svg = plot_svg(
            &Labels {
                title: "Azimuthal velocity of the grains",
                x: "r (m)",
                y: "v_φ / (Ω r)",
            },
            &series,
            &markers,
        )
        .map_err(|e| RunError::Scenario(invalid("figure", "band.svg", e)))?;
        let path = dir.join("band.svg");
        write_atomic(&path, svg.as_bytes()).map_err(io_err("write", &path))
    }
}
