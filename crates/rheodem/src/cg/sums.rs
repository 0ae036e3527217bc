//! Kernel-weighted sums over particles and contacts at every grid point, accumulated over
//! snapshots (docs/coarse-graining.md §2). Fields ([`super::fields`]) are derived from the
//! time averages of these sums.

use super::CgError;
use super::grid::{Axes, Grid};
use super::kernel::Kernel;
use super::snapshot::{Body, Segment, Snapshot};
use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The sums at one grid point, each `Σ q ψ` (q's unit per m³). Vectors and tensors are in
/// the grid's components (Cartesian, or `(r, φ, z)` for the axisymmetric grid); tensors
/// row-major, `[a * 3 + b]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PointSums {
    /// `Σ m ψ`: mass density (kg/m³).
    pub mass: f64,
    /// `Σ V ψ`: volume fraction (1).
    pub volume: f64,
    /// `Σ ψ`: number density (1/m³).
    pub number: f64,
    /// `Σ c ψ`, `c` a particle's touching contacts (1/m³).
    pub contacts: f64,
    /// `Σ b ψ`, `b` a particle's attracting pairs apart (open bridges) (1/m³).
    pub bridges: f64,
    /// `Σ m v ψ`: momentum density (kg/(m² s)).
    pub momentum: [f64; 3],
    /// `Σ m v ⊗ v ψ` (Pa).
    pub kinetic: [f64; 9],
    /// `Σ f ⊗ l ∫₀¹ ψ ds` over contacts, spread along each contact's segment (Pa).
    pub contact: [f64; 9],
}

impl PointSums {
    fn add(&mut self, o: &PointSums) {
        self.mass += o.mass;
        self.volume += o.volume;
        self.number += o.number;
        self.contacts += o.contacts;
        self.bridges += o.bridges;
        add_into(&mut self.momentum, &o.momentum);
        add_into(&mut self.kinetic, &o.kinetic);
        add_into(&mut self.contact, &o.contact);
    }

    fn scaled(&self, s: f64) -> PointSums {
        PointSums {
            mass: self.mass * s,
            volume: self.volume * s,
            number: self.number * s,
            contacts: self.contacts * s,
            bridges: self.bridges * s,
            momentum: self.momentum.map(|x| x * s),
            kinetic: self.kinetic.map(|x| x * s),
            contact: self.contact.map(|x| x * s),
        }
    }
}

/// A kernel weight, plain or averaged around a ring (see [`Kernel::ring`]), that knows how
/// to carry a source's vectors and tensors into the field point's components.
#[derive(Clone, Copy, Debug)]
enum Weight {
    /// One number for scalars, vectors and tensors alike (Cartesian components).
    Plain(f64),
    /// `[K₀, K₁, K₂]`, the ring moments: components from the source's cylindrical basis
    /// to the ring point's.
    Ring([f64; 3]),
}

impl Weight {
    #[inline]
    fn scalar(self) -> f64 {
        match self {
            Weight::Plain(w) => w,
            Weight::Ring(k) => k[0],
        }
    }

    /// `∫ ψ v(θ)`, `v(θ)` the source's vector seen in the basis of the ring point at angle
    /// `θ`: `(v_r cos θ + v_φ sin θ, −v_r sin θ + v_φ cos θ, v_z)`; the `sin` terms vanish.
    #[inline]
    fn vector(self, v: [f64; 3]) -> [f64; 3] {
        match self {
            Weight::Plain(w) => v.map(|x| x * w),
            Weight::Ring([k0, k1, _]) => [k1 * v[0], k1 * v[1], k0 * v[2]],
        }
    }

    /// As [`Weight::vector`] for a tensor: `T' = Rᵀ T R` with `R` the rotation by `θ`
    /// about `z`, integrated; `cos²θ = (1 + cos 2θ)/2`, `sin²θ = (1 − cos 2θ)/2`.
    #[inline]
    fn tensor(self, t: [f64; 9]) -> [f64; 9] {
        match self {
            Weight::Plain(w) => t.map(|x| x * w),
            Weight::Ring([k0, k1, k2]) => {
                let (c2, s2) = (0.5 * (k0 + k2), 0.5 * (k0 - k2));
                let (rr, rp, rz) = (t[0], t[1], t[2]);
                let (pr, pp, pz) = (t[3], t[4], t[5]);
                let (zr, zp, zz) = (t[6], t[7], t[8]);
                [
                    c2 * rr + s2 * pp,
                    c2 * rp - s2 * pr,
                    k1 * rz,
                    c2 * pr - s2 * rp,
                    s2 * rr + c2 * pp,
                    k1 * pz,
                    k1 * zr,
                    k1 * zp,
                    k0 * zz,
                ]
            }
        }
    }
}

/// The source's cylindrical basis `(e_r, e_φ)` at its azimuth (any basis on the axis).
#[inline]
fn cylindrical_basis(p: DVec3) -> (DVec3, DVec3) {
    let rho = p.truncate().length();
    if rho > 0.0 {
        let (c, s) = (p.x / rho, p.y / rho);
        (DVec3::new(c, s, 0.0), DVec3::new(-s, c, 0.0))
    } else {
        (DVec3::X, DVec3::Y)
    }
}

#[inline]
fn outer(a: [f64; 3], b: [f64; 3]) -> [f64; 9] {
    std::array::from_fn(|k| a[k / 3] * b[k % 3])
}

/// Most Gauss-Legendre nodes along a contact's segment.
const MAX_SEGMENT_NODES: usize = 8;

/// Kernel-weighted sums on a grid, accumulated over snapshots.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CgSums {
    /// The grid.
    pub grid: Grid,
    /// Snapshots added.
    pub snapshots: u64,
    /// Sum over the snapshots of each point's sums.
    pub points: Vec<PointSums>,
}

impl CgSums {
    /// Empty sums on `grid`.
    ///
    /// # Errors
    /// [`CgError::Invalid`] for a grid that fails [`Grid::validate`].
    pub fn new(grid: Grid) -> Result<CgSums, CgError> {
        grid.validate()?;
        let n = grid.len();
        Ok(CgSums {
            grid,
            snapshots: 0,
            points: vec![PointSums::default(); n],
        })
    }

    /// The time average: each point's sums divided by the number of snapshots.
    pub fn mean(&self) -> Vec<PointSums> {
        let s = 1.0 / self.snapshots.max(1) as f64;
        self.points.iter().map(|p| p.scaled(s)).collect()
    }

    /// Adds the sums of another accumulation on the same grid (another run, another stretch
    /// of the same run).
    ///
    /// # Errors
    /// [`CgError::Invalid`] if the grids differ.
    pub fn merge(&mut self, other: &CgSums) -> Result<(), CgError> {
        if self.grid != other.grid {
            return Err(CgError::Invalid(
                "coarse-graining sums on different grids cannot be merged".into(),
            ));
        }
        self.snapshots += other.snapshots;
        for (a, b) in self.points.iter_mut().zip(&other.points) {
            a.add(b);
        }
        Ok(())
    }

    /// Adds one snapshot: every body and contact segment, and their images, spread with
    /// `kernel`. The work is split into as many fixed blocks as the thread pool has threads,
    /// of about equal cost (a body counts one point, a segment its quadrature nodes), and
    /// the blocks' sums are added in block order, so the result does not depend on
    /// scheduling (only on the thread count, through the order of additions).
    pub fn add_snapshot(&mut self, kernel: &Kernel, snap: &Snapshot) {
        let blocks = rayon::current_num_threads().max(1);
        let bounds = block_bounds(kernel, snap, blocks);
        let partial: Vec<Vec<PointSums>> = (0..blocks)
            .into_par_iter()
            .map(|b| spread_block(&self.grid, kernel, snap, bounds[b]..bounds[b + 1]))
            .collect();
        for acc in partial {
            for (a, b) in self.points.iter_mut().zip(&acc) {
                a.add(b);
            }
        }
        self.snapshots += 1;
    }
}

/// The first item of each of `blocks` consecutive blocks of a snapshot's items (bodies,
/// then segments), and the item count last: blocks of about equal numbers of source points.
fn block_bounds(kernel: &Kernel, snap: &Snapshot, blocks: usize) -> Vec<usize> {
    let cost: Vec<usize> = std::iter::repeat_n(1, snap.bodies.len())
        .chain(snap.segments.iter().map(|s| segment_nodes(kernel, s)))
        .collect();
    let total: usize = cost.iter().sum();
    let mut bounds = Vec::with_capacity(blocks + 1);
    bounds.push(0);
    let mut done = 0;
    for (k, c) in cost.iter().enumerate() {
        // Block `b` ends at the first item whose cumulated cost reaches `b/blocks` of all.
        while bounds.len() < blocks && done * blocks >= bounds.len() * total {
            bounds.push(k);
        }
        done += c;
    }
    bounds.resize(blocks + 1, cost.len());
    bounds
}

/// The sums of the items `items` of `snap` (bodies first, then segments) and their images.
fn spread_block(
    grid: &Grid,
    kernel: &Kernel,
    snap: &Snapshot,
    items: std::ops::Range<usize>,
) -> Vec<PointSums> {
    let ax = grid.axes();
    let mut acc = vec![PointSums::default(); grid.len()];
    for k in items {
        if k < snap.bodies.len() {
            for image in snap.body_images(k, grid, kernel.cutoff()) {
                add_body(grid, &ax, kernel, &image, &mut acc);
            }
        } else {
            let s = k - snap.bodies.len();
            for image in snap.segment_images(s, grid, kernel.cutoff()) {
                add_segment(grid, &ax, kernel, &image, &mut acc);
            }
        }
    }
    acc
}

/// Visits every grid point within the kernel's reach of `p` with its weight.
#[inline(always)]
fn for_each_weight(
    grid: &Grid,
    ax: &Axes,
    kernel: &Kernel,
    p: DVec3,
    mut visit: impl FnMut(usize, Weight),
) {
    let c = kernel.cutoff();
    if !grid.reaches(p, c) {
        return;
    }
    match grid {
        Grid::Cartesian { .. } => {
            let (Some(rx), Some(ry), Some(rz)) =
                (ax.near(0, p.x, c), ax.near(1, p.y, c), ax.near(2, p.z, c))
            else {
                return;
            };
            for iz in rz {
                let dz = ax.point(2, iz) - p.z;
                for iy in ry.clone() {
                    let dy = ax.point(1, iy) - p.y;
                    for ix in rx.clone() {
                        let dx = ax.point(0, ix) - p.x;
                        let w = kernel.value(dx * dx + dy * dy + dz * dz);
                        if w > 0.0 {
                            visit(ax.index(&[ix, iy, iz]), Weight::Plain(w));
                        }
                    }
                }
            }
        }
        Grid::Slab { axis, area, .. } => {
            let Some(range) = ax.near(0, p[*axis], c) else {
                return;
            };
            for i in range {
                let w = kernel.plane(ax.point(0, i) - p[*axis]) / area;
                if w > 0.0 {
                    visit(i, Weight::Plain(w));
                }
            }
        }
        Grid::Axisymmetric { angle, .. } => {
            let rho = p.truncate().length();
            let (Some(rr), Some(rz)) = (ax.near(0, rho, c), ax.near(1, p.z, c)) else {
                return;
            };
            for iz in rz {
                let dz = ax.point(1, iz) - p.z;
                for ir in rr.clone() {
                    let w = kernel.ring(ax.point(0, ir), rho, dz, *angle);
                    if w[0] > 0.0 {
                        visit(ax.index(&[ir, iz]), Weight::Ring(w));
                    }
                }
            }
        }
    }
}

/// A vector in the components the grid's weights expect at a source at `p`: Cartesian, or
/// the cylindrical components at `p`'s azimuth.
#[inline]
fn components(grid: &Grid, p: DVec3, v: DVec3) -> [f64; 3] {
    match grid {
        Grid::Axisymmetric { .. } => {
            let (er, ep) = cylindrical_basis(p);
            [v.dot(er), v.dot(ep), v.z]
        }
        _ => v.to_array(),
    }
}

#[inline(always)]
fn add_body(grid: &Grid, ax: &Axes, kernel: &Kernel, b: &Body, acc: &mut [PointSums]) {
    let v = components(grid, b.position, b.velocity);
    let mv = v.map(|x| x * b.mass);
    let mvv = outer(mv, v);
    for_each_weight(grid, ax, kernel, b.position, |k, w| {
        let s = w.scalar();
        let p = &mut acc[k];
        p.mass += b.mass * s;
        p.volume += b.volume * s;
        p.number += s;
        p.contacts += f64::from(b.contacts) * s;
        p.bridges += f64::from(b.bridges) * s;
        add_into(&mut p.momentum, &w.vector(mv));
        add_into(&mut p.kinetic, &w.tensor(mvv));
    });
}

#[inline]
fn add_into<const N: usize>(acc: &mut [f64; N], x: &[f64; N]) {
    for (a, b) in acc.iter_mut().zip(x) {
        *a += b;
    }
}

/// Spreads `f ⊗ (to − from)` along the segment by Gauss-Legendre nodes in `s ∈ [0, 1]`,
/// about two per kernel width (at least one, at most [`MAX_SEGMENT_NODES`]).
#[inline(always)]
fn add_segment(grid: &Grid, ax: &Axes, kernel: &Kernel, seg: &Segment, acc: &mut [PointSums]) {
    let l = seg.to - seg.from;
    for &(s, ws) in segment_rule(segment_nodes(kernel, seg)) {
        let p = seg.from + l * s;
        let t = outer(components(grid, p, seg.force), components(grid, p, l)).map(|x| x * ws);
        for_each_weight(grid, ax, kernel, p, |k, w| {
            add_into(&mut acc[k].contact, &w.tensor(t));
        });
    }
}

/// Nodes along a segment: about two per kernel width, at least one, at most
/// [`MAX_SEGMENT_NODES`].
fn segment_nodes(kernel: &Kernel, seg: &Segment) -> usize {
    let l = (seg.to - seg.from).length();
    ((2.0 * l / kernel.width()).ceil() as usize).clamp(1, MAX_SEGMENT_NODES)
}

/// Gauss-Legendre nodes and weights on `[0, 1]` for `n` nodes (1 ≤ n ≤ 8), computed once.
fn segment_rule(n: usize) -> &'static [(f64, f64)] {
    static RULES: std::sync::OnceLock<Vec<Vec<(f64, f64)>>> = std::sync::OnceLock::new();
    let rules = RULES.get_or_init(|| {
        (1..=MAX_SEGMENT_NODES)
            .map(|n| {
                if n == 1 {
                    return vec![(0.5, 1.0)];
                }
                super::kernel::gauss_legendre_unit(n)
            })
            .collect()
    });
    &rules[n - 1]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cg::KernelShape;

    /// Bodies spread over a `(r, z)` ring cell, and contact segments of assorted lengths
    /// (one to eight quadrature nodes).
    fn snapshot() -> Snapshot {
        let bodies = (0..40)
            .map(|k| {
                let f = f64::from(k);
                Body {
                    position: DVec3::new(3.0 + 0.05 * f, 0.1 * (f * 0.7).sin(), 1.0 + 0.02 * f),
                    velocity: DVec3::new((f * 1.3).cos(), 1.0, 0.1 * f),
                    mass: 1.0 + 0.01 * f,
                    volume: 0.5,
                    contacts: k % 5,
                    bridges: k % 2,
                }
            })
            .collect();
        let segments = (0..60)
            .map(|k| {
                let f = f64::from(k);
                let from = DVec3::new(3.2 + 0.03 * f, 0.05 * f.cos(), 1.2 + 0.01 * f);
                Segment {
                    from,
                    to: from + DVec3::new(0.02 * f, 0.01, 0.005 * f),
                    force: DVec3::new(1.0, -0.5 * f.sin(), 0.2),
                }
            })
            .collect();
        Snapshot {
            time: 0.0,
            bodies,
            segments,
            images: Vec::new(),
        }
    }

    #[test]
    fn blocks_cover_the_items_in_order_with_about_equal_cost() {
        let kernel = Kernel::new(KernelShape::Lucy, 0.2).expect("valid");
        let snap = snapshot();
        let cost: Vec<usize> = std::iter::repeat_n(1, snap.bodies.len())
            .chain(snap.segments.iter().map(|s| segment_nodes(&kernel, s)))
            .collect();
        assert!(cost.iter().any(|&c| c > 1), "segments of several nodes");
        let total: usize = cost.iter().sum();
        let heaviest = *cost.iter().max().expect("items");
        for blocks in [1, 2, 3, 7, 200] {
            let bounds = block_bounds(&kernel, &snap, blocks);
            assert_eq!(bounds.len(), blocks + 1);
            assert_eq!((bounds[0], bounds[blocks]), (0, cost.len()));
            for b in 0..blocks {
                assert!(bounds[b] <= bounds[b + 1], "{blocks} blocks: {bounds:?}");
                let block: usize = cost[bounds[b]..bounds[b + 1]].iter().sum();
                assert!(
                    block * blocks <= total + heaviest * blocks,
                    "{blocks} blocks: block {b} costs {block} of {total}"
                );
            }
        }
    }

    #[test]
    fn the_sums_do_not_depend_on_the_block_split_beyond_rounding() {
        let kernel = Kernel::new(KernelShape::Lucy, 0.2).expect("valid");
        let grid = Grid::Axisymmetric {
            r: [3.0, 5.0],
            z: [0.8, 2.0],
            bins: [12, 8],
            angle: 0.5,
        };
        let snap = snapshot();
        let sums_on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a pool");
            let mut sums = CgSums::new(grid.clone()).expect("valid");
            pool.install(|| sums.add_snapshot(&kernel, &snap));
            sums.points
        };
        let one = sums_on(1);
        assert!(one.iter().any(|p| p.mass > 0.0 && p.contact[0] != 0.0));
        for threads in [2, 3] {
            for (a, b) in one.iter().zip(&sums_on(threads)) {
                let close = |x: f64, y: f64| (x - y).abs() <= 1e-12 * (1.0 + x.abs());
                assert!(close(a.mass, b.mass) && close(a.number, b.number));
                for c in 0..9 {
                    assert!(close(a.contact[c], b.contact[c]), "{threads} threads");
                    assert!(close(a.kinetic[c], b.kinetic[c]), "{threads} threads");
                }
            }
        }
    }
}
