//! The grids on which coarse-grained fields are evaluated: points at the centres of equal
//! cells over a box (Cartesian), along one axis (slabs) or over the `(r, z)` half-plane about
//! the `z` axis (axisymmetric). All lengths in metres.

use super::CgError;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// The most points a grid may have (a bound on memory, 26 numbers per point and thread).
pub const MAX_POINTS: usize = 1 << 22;

/// A grid of field points.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Grid {
    /// Points at the centres of `bins[0] × bins[1] × bins[2]` cells over `[lo, hi]`;
    /// fields in Cartesian components.
    Cartesian {
        /// Lower corner (m).
        lo: DVec3,
        /// Upper corner (m).
        hi: DVec3,
        /// Cells along `x`, `y`, `z`.
        bins: [usize; 3],
    },
    /// Points at the centres of `bins` slabs over `[lo, hi]` along `axis` (0, 1, 2 for `x`,
    /// `y`, `z`): fields averaged over planes of cross-section `area` (m²) normal to the
    /// axis, in Cartesian components.
    Slab {
        /// The axis normal to the slabs (0, 1 or 2).
        axis: usize,
        /// Lower end (m).
        lo: f64,
        /// Upper end (m).
        hi: f64,
        /// Number of slabs.
        bins: usize,
        /// Area of the planes averaged over (m²).
        area: f64,
    },
    /// Points at the centres of `bins[0] × bins[1]` cells over `[r_lo, r_hi] × [z_lo, z_hi]`
    /// in the `(r, z)` half-plane about the `z` axis through the origin: fields averaged over
    /// the azimuth, in cylindrical components `(r, φ, z)`. The particles fill the angle
    /// `angle` (rad): `2π` for a full ring, a wedge's angle when its periodic images fill
    /// the rest.
    Axisymmetric {
        /// Radial range (m).
        r: [f64; 2],
        /// Height range (m).
        z: [f64; 2],
        /// Cells along `r` and `z`.
        bins: [usize; 2],
        /// The angle the particles fill (rad), in `(0, 2π]`.
        angle: f64,
    },
}

impl Grid {
    /// Checks the grid's numbers.
    ///
    /// # Errors
    /// [`CgError::Invalid`] naming the offending value.
    pub fn validate(&self) -> Result<(), CgError> {
        let bad = |what: String| Err(CgError::Invalid(what));
        let range = |name: &str, lo: f64, hi: f64| -> Result<(), CgError> {
            if lo.is_finite() && hi.is_finite() && lo < hi {
                Ok(())
            } else {
                Err(CgError::Invalid(format!(
                    "the grid's {name} range must be finite and increasing, got [{lo}, {hi}]"
                )))
            }
        };
        match self {
            Grid::Cartesian { lo, hi, bins } => {
                for a in 0..3 {
                    range(["x", "y", "z"][a], lo[a], hi[a])?;
                }
                if bins.contains(&0) {
                    return bad(format!(
                        "every grid axis needs at least one cell, got {bins:?}"
                    ));
                }
            }
            Grid::Slab {
                axis,
                lo,
                hi,
                bins,
                area,
            } => {
                if *axis > 2 {
                    return bad(format!("the slab axis must be 0, 1 or 2, got {axis}"));
                }
                range("slab", *lo, *hi)?;
                if *bins == 0 {
                    return bad("a slab grid needs at least one slab".into());
                }
                if !(area.is_finite() && *area > 0.0) {
                    return bad(format!(
                        "the slab area must be finite and > 0 m², got {area}"
                    ));
                }
            }
            Grid::Axisymmetric { r, z, bins, angle } => {
                range("r", r[0], r[1])?;
                range("z", z[0], z[1])?;
                if r[0] < 0.0 {
                    return bad(format!(
                        "the grid's inner radius must be ≥ 0 m, got {}",
                        r[0]
                    ));
                }
                if bins.contains(&0) {
                    return bad(format!(
                        "every grid axis needs at least one cell, got {bins:?}"
                    ));
                }
                if !(angle.is_finite() && *angle > 0.0 && *angle <= std::f64::consts::TAU) {
                    return bad(format!(
                        "the angle the particles fill must be in (0, 2π] rad, got {angle}"
                    ));
                }
            }
        }
        let n = self
            .dims()
            .iter()
            .try_fold(1usize, |a, &b| a.checked_mul(b));
        match n {
            Some(n) if n <= MAX_POINTS => Ok(()),
            _ => bad(format!(
                "the grid has more than {MAX_POINTS} points ({:?} cells)",
                self.dims()
            )),
        }
    }

    /// The grid's axes: lower ends, spacings and point counts.
    pub fn axes(&self) -> Axes {
        let mut ax = Axes {
            lo: [0.0; 3],
            h: [1.0; 3],
            n: [1; 3],
            count: 0,
        };
        let mut set = |a: usize, lo: f64, hi: f64, n: usize| {
            ax.lo[a] = lo;
            ax.h[a] = (hi - lo) / n as f64;
            ax.n[a] = n;
            ax.count = a + 1;
        };
        match self {
            Grid::Cartesian { lo, hi, bins } => {
                for a in 0..3 {
                    set(a, lo[a], hi[a], bins[a]);
                }
            }
            Grid::Slab { lo, hi, bins, .. } => set(0, *lo, *hi, *bins),
            Grid::Axisymmetric { r, z, bins, .. } => {
                set(0, r[0], r[1], bins[0]);
                set(1, z[0], z[1], bins[1]);
            }
        }
        ax
    }

    /// Number of points along each of the grid's axes (`x, y, z`; the slab axis; `r, z`).
    pub fn dims(&self) -> Vec<usize> {
        let ax = self.axes();
        ax.n[..ax.count].to_vec()
    }

    /// Total number of points.
    pub fn len(&self) -> usize {
        self.dims().iter().product()
    }

    /// Whether the grid has no points (never, once validated).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The spacing along each of the grid's axes (m).
    pub fn spacing(&self) -> Vec<f64> {
        let ax = self.axes();
        ax.h[..ax.count].to_vec()
    }

    /// Index of the point with per-axis indices `idx` (first axis fastest).
    pub fn index(&self, idx: &[usize]) -> usize {
        self.axes().index(idx)
    }

    /// Per-axis indices of point `k`.
    pub fn indices(&self, k: usize) -> Vec<usize> {
        let ax = self.axes();
        ax.indices(k)[..ax.count].to_vec()
    }

    /// The coordinates of point `k` along the grid's axes (m).
    pub fn coordinates(&self, k: usize) -> Vec<f64> {
        let ax = self.axes();
        let idx = ax.indices(k);
        (0..ax.count).map(|a| ax.point(a, idx[a])).collect()
    }

    /// The names of the grid's coordinates, in the order of [`Grid::coordinates`].
    pub fn axis_names(&self) -> &'static [&'static str] {
        match self {
            Grid::Cartesian { .. } => &["x", "y", "z"],
            Grid::Slab { axis, .. } => [&["x"][..], &["y"][..], &["z"][..]][*axis],
            Grid::Axisymmetric { .. } => &["r", "z"],
        }
    }

    /// The names of the three vector components fields are given in.
    pub fn component_names(&self) -> [&'static str; 3] {
        match self {
            Grid::Axisymmetric { .. } => ["r", "phi", "z"],
            _ => ["x", "y", "z"],
        }
    }

    /// The volume a point stands for (m³), so that `Σ_k f_k V_k` approximates `∫ f dV` over
    /// the grid's region (for the axisymmetric grid, over the angle the particles fill).
    pub fn cell_volume(&self, k: usize) -> f64 {
        let h = self.spacing();
        match self {
            Grid::Cartesian { .. } => h[0] * h[1] * h[2],
            Grid::Slab { area, .. } => h[0] * area,
            Grid::Axisymmetric { angle, .. } => angle * self.coordinates(k)[0] * h[0] * h[1],
        }
    }

    /// Whether a source at `p` (m) can reach any point of the grid through a kernel of
    /// cut-off `reach` (m).
    pub(crate) fn reaches(&self, p: DVec3, reach: f64) -> bool {
        match self {
            Grid::Cartesian { lo, hi, .. } => {
                (0..3).all(|a| p[a] > lo[a] - reach && p[a] < hi[a] + reach)
            }
            Grid::Slab { axis, lo, hi, .. } => p[*axis] > lo - reach && p[*axis] < hi + reach,
            Grid::Axisymmetric { r, z, .. } => {
                let rho = p.truncate().length();
                rho > r[0] - reach && rho < r[1] + reach && p.z > z[0] - reach && p.z < z[1] + reach
            }
        }
    }
}

/// A grid's axes in a form cheap to use in the accumulation loops: for axis `a < count`,
/// points at `lo[a] + (i + ½) h[a]`, `i < n[a]`.
#[derive(Clone, Copy, Debug)]
pub struct Axes {
    /// Lower end of each axis (m).
    pub lo: [f64; 3],
    /// Spacing along each axis (m).
    pub h: [f64; 3],
    /// Points along each axis.
    pub n: [usize; 3],
    /// Number of axes in use (1 to 3).
    pub count: usize,
}

impl Axes {
    /// Coordinate of point `i` along axis `a` (m).
    #[inline]
    pub fn point(&self, a: usize, i: usize) -> f64 {
        self.lo[a] + (i as f64 + 0.5) * self.h[a]
    }

    /// Index of the point with per-axis indices `idx` (first axis fastest).
    #[inline]
    pub fn index(&self, idx: &[usize]) -> usize {
        let mut k = 0;
        for a in (0..self.count).rev() {
            k = k * self.n[a] + idx[a];
        }
        k
    }

    /// Per-axis indices of point `k` (unused axes 0).
    #[inline]
    pub fn indices(&self, mut k: usize) -> [usize; 3] {
        let mut idx = [0; 3];
        for (a, i) in idx.iter_mut().enumerate().take(self.count) {
            *i = k % self.n[a];
            k /= self.n[a];
        }
        idx
    }

    /// The indices along axis `a` of the points within `reach` (m) of `x` (m) (the range
    /// may hold one more point at each end), or `None` if there are none.
    #[inline]
    pub fn near(&self, a: usize, x: f64, reach: f64) -> Option<std::ops::Range<usize>> {
        let first = ((x - reach - self.lo[a]) / self.h[a] - 0.5)
            .floor()
            .max(0.0);
        let last = ((x + reach - self.lo[a]) / self.h[a] - 0.5)
            .ceil()
            .min(self.n[a] as f64 - 1.0);
        if !(first.is_finite() && last.is_finite()) || first > last {
            return None;
        }
        Some(first as usize..last as usize + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indices_round_trip_and_points_sit_at_cell_centres() {
        let g = Grid::Cartesian {
            lo: DVec3::new(0.0, -1.0, 2.0),
            hi: DVec3::new(1.0, 1.0, 3.0),
            bins: [4, 5, 2],
        };
        g.validate().expect("valid");
        assert_eq!(g.len(), 40);
        for k in 0..g.len() {
            assert_eq!(g.index(&g.indices(k)), k);
        }
        let c = g.coordinates(g.index(&[1, 0, 1]));
        assert_eq!(c, vec![0.375, -0.8, 2.75]);
        assert!((g.cell_volume(0) - 0.25 * 0.4 * 0.5).abs() < 1e-15);
    }

    #[test]
    fn near_covers_exactly_the_points_within_reach() {
        let g = Grid::Slab {
            axis: 1,
            lo: 0.0,
            hi: 10.0,
            bins: 10,
            area: 1.0,
        };
        let ax = g.axes();
        let r = ax.near(0, 3.2, 1.0).expect("some");
        // Points at 0.5, 1.5, …: within 1 of 3.2 are 2.5 and 3.5 (and the range may be one
        // wider on each side, never narrower).
        assert!(
            r.start <= 2 && r.end >= 4 && r.start >= 1 && r.end <= 5,
            "{r:?}"
        );
        assert!(ax.near(0, -5.0, 1.0).is_none());
        assert!(ax.near(0, 15.0, 1.0).is_none());
    }

    #[test]
    fn bad_grids_are_refused() {
        let bad = [
            Grid::Slab {
                axis: 3,
                lo: 0.0,
                hi: 1.0,
                bins: 1,
                area: 1.0,
            },
            Grid::Slab {
                axis: 0,
                lo: 1.0,
                hi: 1.0,
                bins: 1,
                area: 1.0,
            },
            Grid::Axisymmetric {
                r: [-1.0, 1.0],
                z: [0.0, 1.0],
                bins: [2, 2],
                angle: 1.0,
            },
            Grid::Axisymmetric {
                r: [0.0, 1.0],
                z: [0.0, 1.0],
                bins: [2, 2],
                angle: 7.0,
            },
            Grid::Cartesian {
                lo: DVec3::ZERO,
                hi: DVec3::ONE,
                bins: [1 << 10, 1 << 10, 1 << 10],
            },
        ];
        for g in bad {
            assert!(g.validate().is_err(), "{g:?}");
        }
    }
}
