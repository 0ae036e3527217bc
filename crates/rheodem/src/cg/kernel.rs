//! Coarse-graining kernels: the weight `ψ(d)` (1/m³) a particle at distance `d` gives a field
//! point, normalised so that `∫ ψ dV = 1` over space (docs/coarse-graining.md §1).
//!
//! Both kernels are parametrised by the same width `w`, the standard deviation of the kernel
//! along one axis (`∫ x² ψ dV = w²`), so that switching kernels keeps the smoothing scale:
//!
//! - **Gaussian**, cut at `c = 3w` and renormalised over the ball it covers:
//!   `ψ(d) = A exp(−d²/2w²)` for `d < c`, `A = 1 / (4π w³ [√(π/2) erf(3/√2) − 3 e^{−9/2}])`.
//!   (The cut removes 2.9 % of the untruncated weight, so its standard deviation is 0.958 w.)
//! - **Lucy** polynomial, `ψ(d) = 105/(16π c³) (1 + 3x)(1 − x)³`, `x = d/c < 1`, whose standard
//!   deviation along an axis is `c/√12`: its cut-off is `c = √12 w ≈ 3.46 w`. It is twice
//!   continuously differentiable at the cut-off.
//!
//! Besides the point value, each kernel integrates exactly in the two reductions the grids
//! use: over a plane ([`Kernel::plane`], for slabs) and around a ring about the `z` axis
//! ([`Kernel::ring`], for the axisymmetric `(r, z)` grid).

use super::CgError;
use std::f64::consts::PI;

/// The two kernel shapes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum KernelShape {
    /// Gaussian cut at three widths.
    Gaussian,
    /// Lucy's quartic polynomial.
    Lucy,
}

impl KernelShape {
    /// The name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            KernelShape::Gaussian => "gaussian",
            KernelShape::Lucy => "lucy",
        }
    }
}

/// Gauss-Legendre nodes on `[0, 1]` for the angular integral of [`Kernel::ring`].
const RING_NODES: usize = 8;

/// A kernel of a given shape and width, with its normalisation.
#[derive(Clone, Debug)]
pub struct Kernel {
    shape: KernelShape,
    width: f64,
    cutoff: f64,
    /// `1 / cutoff` (1/m): the Lucy kernel's `x = d/c` as a product, not a division.
    inv_cutoff: f64,
    /// `ψ(0)` (1/m³).
    peak: f64,
    /// Nodes of the angular quadrature on `[0, 1]`.
    ring_nodes: [f64; RING_NODES],
    /// Weights of the angular quadrature (summing to one).
    ring_weights: [f64; RING_NODES],
}

impl Kernel {
    /// A kernel of standard deviation `width` (m) along each axis.
    ///
    /// # Errors
    /// [`CgError::Invalid`] unless `width` is finite and positive.
    pub fn new(shape: KernelShape, width: f64) -> Result<Kernel, CgError> {
        if !(width.is_finite() && width > 0.0) {
            return Err(CgError::Invalid(format!(
                "the coarse-graining width must be finite and > 0 m, got {width}"
            )));
        }
        let (cutoff, peak) = match shape {
            KernelShape::Gaussian => {
                let s = (0.5 * PI).sqrt() * libm::erf(3.0 / 2f64.sqrt()) - 3.0 * (-4.5f64).exp();
                (3.0 * width, 1.0 / (4.0 * PI * width.powi(3) * s))
            }
            KernelShape::Lucy => {
                let c = 12f64.sqrt() * width;
                (c, 105.0 / (16.0 * PI * c.powi(3)))
            }
        };
        let rule = gauss_legendre_unit(RING_NODES);
        Ok(Kernel {
            shape,
            width,
            cutoff,
            inv_cutoff: 1.0 / cutoff,
            peak,
            ring_nodes: std::array::from_fn(|k| rule[k].0),
            ring_weights: std::array::from_fn(|k| rule[k].1),
        })
    }

    /// The shape.
    pub fn shape(&self) -> KernelShape {
        self.shape
    }

    /// The width `w` (m), the standard deviation along one axis.
    pub fn width(&self) -> f64 {
        self.width
    }

    /// The distance beyond which the kernel is zero (m).
    pub fn cutoff(&self) -> f64 {
        self.cutoff
    }

    /// `ψ` at squared distance `d2` (m²), in 1/m³.
    #[inline]
    pub fn value(&self, d2: f64) -> f64 {
        let c = self.cutoff;
        if d2 >= c * c {
            return 0.0;
        }
        match self.shape {
            KernelShape::Gaussian => self.peak * (-0.5 * d2 / (self.width * self.width)).exp(),
            KernelShape::Lucy => {
                let x = d2.sqrt() * self.inv_cutoff;
                let m = 1.0 - x;
                self.peak * (1.0 + 3.0 * x) * m * m * m
            }
        }
    }

    /// [`Kernel::value`] at each of the squared distances `d2` (m²), in 1/m³, without a
    /// branch per entry.
    #[inline(always)]
    fn values(&self, d2: [f64; RING_NODES]) -> [f64; RING_NODES] {
        let c = self.cutoff;
        let mut psi = [0.0; RING_NODES];
        match self.shape {
            KernelShape::Gaussian => {
                for (psi, &d2) in psi.iter_mut().zip(&d2) {
                    *psi = self.value(d2);
                }
            }
            KernelShape::Lucy => {
                for (psi, &d2) in psi.iter_mut().zip(&d2) {
                    let x = d2.sqrt() * self.inv_cutoff;
                    let m = 1.0 - x;
                    let value = self.peak * (1.0 + 3.0 * x) * m * m * m;
                    *psi = if d2 >= c * c { 0.0 } else { value };
                }
            }
        }
        psi
    }

    /// The kernel integrated over the plane at distance `h` (m) from the source,
    /// `∫∫ ψ dx dz` (1/m): the weight of a slab point, per unit cross-section.
    pub fn plane(&self, h: f64) -> f64 {
        let c = self.cutoff;
        let h = h.abs();
        if h >= c {
            return 0.0;
        }
        // ∫∫ ψ over the plane = 2π ∫_h^c ψ(u) u du (polar coordinates, u = √(ρ² + h²)).
        match self.shape {
            KernelShape::Gaussian => {
                let w2 = self.width * self.width;
                2.0 * PI * self.peak * w2 * ((-0.5 * h * h / w2).exp() - (-0.5 * c * c / w2).exp())
            }
            KernelShape::Lucy => {
                // ∫ (1 − 6x² + 8x³ − 3x⁴) x dx = x²/2 − 3x⁴/2 + 8x⁵/5 − x⁶/2, which is 1/10 at 1.
                let t = h / c;
                let t2 = t * t;
                let f = t2 * (0.5 + t2 * (-1.5 + t * 1.6 - t2 * 0.5));
                2.0 * PI * self.peak * c * c * (0.1 - f)
            }
        }
    }

    /// The kernel averaged around the ring of radius `r` (m) about the `z` axis, for a source at
    /// distance `r_s` (m) from the axis and height `dz` (m) below or above the ring, with
    /// the angle `θ` from the source's azimuth:
    /// `[∫ ψ dθ, ∫ ψ cos θ dθ, ∫ ψ cos 2θ dθ] / Φ` (1/m³), over `θ ∈ (−π, π]`.
    ///
    /// `Φ` is the angle the particles fill (`2π` for a full ring, the wedge angle for a wedge
    /// whose images fill the rest): the first entry is then the field of a density averaged
    /// over the azimuth. The other two carry vectors and tensors from the source's
    /// cylindrical basis into the ring point's (the `sin` moments vanish by symmetry).
    /// The integral runs over the arc `|θ| < θ_c` where the kernel is non-zero, by
    /// Gauss-Legendre quadrature in `t = sin(θ/2)` (in `θ` when the arc exceeds about half
    /// the circle, near the axis).
    #[inline(always)]
    pub fn ring(&self, r: f64, r_s: f64, dz: f64, angle: f64) -> [f64; 3] {
        let c = self.cutoff;
        let base = (r - r_s) * (r - r_s) + dz * dz;
        if base >= c * c {
            return [0.0; 3];
        }
        // d² = base + 4 r r_s t², t = sin(θ/2); the arc ends where d = c.
        let four_rr = 4.0 * r * r_s;
        let reach = c * c - base;
        // The integrand at every node first (loops of one kind that the compiler turns
        // into vector instructions), then summed node by node in order.
        if reach < 0.81 * four_rr {
            // An arc short of half the circle (t_c < 0.9): in t, dθ = 2 dt / √(1 − t²),
            // cos θ = 1 − 2t², a smooth integrand without trigonometric calls.
            let t_c = (reach / four_rr).sqrt();
            let t2 = self.ring_nodes.map(|x| (x * t_c) * (x * t_c));
            let psi = self.values(t2.map(|t2| base + four_rr * t2));
            let mut v = [0.0; RING_NODES];
            for k in 0..RING_NODES {
                v[k] = self.ring_weights[k] * psi[k] * 2.0 / (1.0 - t2[k]).sqrt();
            }
            let cos1 = t2.map(|t2| 1.0 - 2.0 * t2);
            // Both halves of the arc, over the angle the particles fill.
            return ring_sums(&v, &cos1).map(|s| s * 2.0 * t_c / angle);
        }
        // Near the axis the arc may close into the whole circle: integrate in θ.
        let theta_c = if reach >= four_rr {
            PI
        } else {
            2.0 * (reach / four_rr).sqrt().asin()
        };
        let (mut d2, mut cos1) = ([0.0; RING_NODES], [0.0; RING_NODES]);
        for k in 0..RING_NODES {
            let (s, c) = (0.5 * self.ring_nodes[k] * theta_c).sin_cos();
            d2[k] = base + four_rr * s * s;
            cos1[k] = c * c - s * s;
        }
        let psi = self.values(d2);
        let mut v = [0.0; RING_NODES];
        for k in 0..RING_NODES {
            v[k] = self.ring_weights[k] * psi[k];
        }
        let sums = ring_sums(&v, &cos1);
        sums.map(|s| s * 2.0 * theta_c / angle)
    }
}

/// `[Σ v, Σ v cos θ, Σ v cos 2θ]` over the nodes in order, from `v` and `cos θ`.
#[inline(always)]
fn ring_sums(v: &[f64; RING_NODES], cos1: &[f64; RING_NODES]) -> [f64; 3] {
    let mut sums = [0.0; 3];
    for (v, cos1) in v.iter().zip(cos1) {
        sums[0] += v;
        sums[1] += v * cos1;
        sums[2] += v * (2.0 * cos1 * cos1 - 1.0);
    }
    sums
}

/// The `n`-point Gauss-Legendre rule (`n ≥ 2`) mapped onto `[0, 1]`: `(node, weight)` pairs
/// whose weights sum to one.
pub(crate) fn gauss_legendre_unit(n: usize) -> Vec<(f64, f64)> {
    gauss_quad::GaussLegendre::new(n)
        .expect("a Gauss-Legendre rule of at least two nodes")
        .iter()
        .map(|&(x, w)| (0.5 * (x + 1.0), 0.5 * w))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn radial_integral(k: &Kernel, moment: i32) -> f64 {
        // ∫ 4π d² ψ(d) d^moment dd by the midpoint rule on a fine mesh.
        let n = 200_000;
        let h = k.cutoff() / n as f64;
        (0..n)
            .map(|i| {
                let d = (i as f64 + 0.5) * h;
                4.0 * PI * d * d * d.powi(moment) * k.value(d * d) * h
            })
            .sum()
    }

    #[test]
    fn kernels_are_normalised_with_the_stated_width() {
        for shape in [KernelShape::Gaussian, KernelShape::Lucy] {
            let k = Kernel::new(shape, 1.3e-3).expect("valid");
            let norm = radial_integral(&k, 0);
            assert!((norm - 1.0).abs() < 1e-8, "{shape:?}: ∫ψ = {norm}");
            // Per-axis variance is a third of ⟨d²⟩.
            let sd = (radial_integral(&k, 2) / 3.0).sqrt() / k.width();
            let expected = if shape == KernelShape::Lucy {
                1.0
            } else {
                0.958
            };
            assert!((sd - expected).abs() < 1e-3, "{shape:?}: sd/w = {sd}");
        }
    }

    #[test]
    fn the_plane_integral_matches_a_direct_sum() {
        for shape in [KernelShape::Gaussian, KernelShape::Lucy] {
            let k = Kernel::new(shape, 1.0).expect("valid");
            for h in [0.0, 0.4, 1.7, 2.9, 3.3] {
                // 2π ∫ ρ ψ(√(ρ² + h²)) dρ by the midpoint rule.
                let n = 100_000;
                let top = k.cutoff();
                let step = top / n as f64;
                let direct: f64 = (0..n)
                    .map(|i| {
                        let rho = (i as f64 + 0.5) * step;
                        2.0 * PI * rho * k.value(rho * rho + h * h) * step
                    })
                    .sum();
                let tol = if shape == KernelShape::Gaussian {
                    2e-4
                } else {
                    1e-7
                };
                assert!(
                    (k.plane(h) - direct).abs() < tol * k.plane(0.0),
                    "{shape:?} h = {h}: {} vs {direct}",
                    k.plane(h)
                );
            }
            // And the plane weights integrate to one over the normal axis.
            let n = 100_000;
            let step = 2.0 * k.cutoff() / n as f64;
            let total: f64 = (0..n)
                .map(|i| k.plane(-k.cutoff() + (i as f64 + 0.5) * step) * step)
                .sum();
            assert!((total - 1.0).abs() < 1e-6, "{shape:?}: {total}");
        }
    }

    #[test]
    fn the_ring_average_matches_a_fine_angular_sum() {
        // The Gaussian's step at its cut-off needs many points on a uniform mesh; the
        // quadrature integrates only over the arc where the kernel is non-zero.
        for shape in [KernelShape::Gaussian, KernelShape::Lucy] {
            let k = Kernel::new(shape, 1.0).expect("valid");
            for &(r, r_s, dz) in &[
                (0.5, 0.3, 0.2),
                (10.0, 11.0, 0.5),
                (40.0, 40.5, 1.0),
                (3.0, 0.0, 1.0),
                (0.0, 2.0, 0.0),
            ] {
                let n = 400_000;
                let mut direct = [0.0; 3];
                for i in 0..n {
                    let t = -PI + (i as f64 + 0.5) * 2.0 * PI / n as f64;
                    let d2 = r * r + r_s * r_s - 2.0 * r * r_s * t.cos() + dz * dz;
                    let v = k.value(d2) * 2.0 * PI / n as f64 / (2.0 * PI);
                    direct[0] += v;
                    direct[1] += v * t.cos();
                    direct[2] += v * (2.0 * t).cos();
                }
                let ring = k.ring(r, r_s, dz, 2.0 * PI);
                let scale = k.value(0.0);
                let tol = if shape == KernelShape::Gaussian {
                    1e-4
                } else {
                    1e-7
                };
                for m in 0..3 {
                    assert!(
                        (ring[m] - direct[m]).abs() < tol * scale,
                        "{shape:?} ({r}, {r_s}, {dz}) moment {m}: {} vs {}",
                        ring[m],
                        direct[m]
                    );
                }
            }
        }
    }

    #[test]
    fn bad_widths_are_refused() {
        for w in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(Kernel::new(KernelShape::Lucy, w).is_err());
        }
    }
}
