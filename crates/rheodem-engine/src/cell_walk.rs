//! The distance test of the neighbour search, four candidates at a time.
//!
//! A build of the neighbour list tests every particle against the particles of the cells
//! around it: about fifty candidates per particle on the standard problem, one in ten
//! within reach. The particles are sorted by cell, so the candidates come in runs of
//! consecutive slots, and [`Candidates`] keeps their coordinates, radii and freedom in
//! separate arrays so that a run is read four slots at a time. On x86-64 CPUs with AVX2 the
//! test then takes four candidates per instruction; elsewhere it runs one candidate at a
//! time. Both copies compute each squared distance and reach with the same operations in
//! the same order, so they keep exactly the same pairs.

use crate::domain::{IMAGE_COUNT, ImageTransform};
use glam::DVec3;

/// Candidates tested per step of the vector loop.
const LANES: usize = 4;

/// A run of candidate slots `lo..hi` and the image code they are seen through.
pub(crate) type Run = (u32, u32, u8);

/// Positions (m), radii (m) and freedom of the particles, by slot, in separate arrays
/// padded with [`LANES`] entries that lie infinitely far away.
#[derive(Debug, Default)]
pub(crate) struct Candidates {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
    radius: Vec<f64>,
    /// All bits set for a free particle, none for a prescribed one.
    free: Vec<u64>,
    /// Whether to take the vector copy of the test (the CPU has AVX2, and it was not
    /// turned off).
    simd: bool,
}

impl Candidates {
    /// The particles at `position` with `radius`, free where `free`; with `plain`, the
    /// test runs one candidate at a time even where the CPU has AVX2 (so that the tests
    /// compare the two copies on any machine).
    pub(crate) fn new(position: &[DVec3], radius: &[f64], free: &[bool], plain: bool) -> Self {
        let far = std::iter::repeat_n(f64::INFINITY, LANES);
        Candidates {
            x: position.iter().map(|r| r.x).chain(far.clone()).collect(),
            y: position.iter().map(|r| r.y).chain(far.clone()).collect(),
            z: position.iter().map(|r| r.z).chain(far).collect(),
            radius: radius.iter().copied().chain([0.0; LANES]).collect(),
            free: free
                .iter()
                .map(|&f| if f { u64::MAX } else { 0 })
                .chain([0; LANES])
                .collect(),
            simd: !plain && has_avx2(),
        }
    }

    /// Number of particles.
    fn len(&self) -> usize {
        self.x.len() - LANES
    }

    /// Writes the slots `j > i` of `runs` that lie within `reach` (m) beyond contact of
    /// particle `i` (seen through the run's image, a translation in `images`), and are not
    /// both prescribed, into `row` from entry `len` on, in run order, each with its
    /// image code; returns the new length. `row` grows as needed; entries past the
    /// returned length are scratch.
    pub(crate) fn scan(
        &self,
        i: usize,
        reach: f64,
        runs: &[Run],
        images: &[ImageTransform; IMAGE_COUNT],
        row: &mut Vec<(u32, u8)>,
        len: usize,
    ) -> usize {
        assert!(i < self.len(), "particle {i} of {}", self.len());
        #[cfg(target_arch = "x86_64")]
        if self.simd {
            // SAFETY: `simd` is set only where the CPU has AVX2.
            return unsafe { self.scan_avx2(i, reach, runs, images, row, len) };
        }
        self.scan_plain(i, reach, runs, images, row, len)
    }

    /// Makes room in `row` for the candidates of the run `lo..hi` after `len`, with a
    /// whole group of lanes past its end; returns the run's first slot after `i`, and its
    /// end, both checked against the particle count.
    fn prepare(&self, i: usize, run: Run, row: &mut Vec<(u32, u8)>, len: usize) -> (usize, usize) {
        let (lo, hi) = ((run.0 as usize).max(i + 1), run.1 as usize);
        assert!(hi <= self.len(), "slot {hi} past {} particles", self.len());
        if lo < hi && row.len() < len + hi - lo + LANES {
            row.resize(len + hi - lo + LANES, (0, 0));
        }
        (lo, hi)
    }

    /// [`Candidates::scan`] one candidate at a time, without a branch on the test (one
    /// candidate in ten passes it, so a branch would be mispredicted).
    fn scan_plain(
        &self,
        i: usize,
        reach: f64,
        runs: &[Run],
        images: &[ImageTransform; IMAGE_COUNT],
        row: &mut Vec<(u32, u8)>,
        mut len: usize,
    ) -> usize {
        let (xi, yi, zi, ai, free_i) = (
            self.x[i],
            self.y[i],
            self.z[i],
            self.radius[i],
            self.free[i],
        );
        for &run in runs {
            let (lo, hi) = self.prepare(i, run, row, len);
            let (s, code) = (images[run.2 as usize].shift, run.2);
            for j in lo..hi {
                let cut = ai + self.radius[j] + reach;
                let (dx, dy, dz) = (
                    xi - (self.x[j] + s.x),
                    yi - (self.y[j] + s.y),
                    zi - (self.z[j] + s.z),
                );
                row[len] = (j as u32, code);
                len += usize::from(
                    (dx * dx + dy * dy + dz * dz < cut * cut) & (free_i | self.free[j] != 0),
                );
            }
        }
        len
    }

    /// [`Candidates::scan`] four candidates at a time.
    ///
    /// # Safety
    /// The CPU has AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn scan_avx2(
        &self,
        i: usize,
        reach: f64,
        runs: &[Run],
        images: &[ImageTransform; IMAGE_COUNT],
        row: &mut Vec<(u32, u8)>,
        mut len: usize,
    ) -> usize {
        use std::arch::x86_64::*;
        let splat = _mm256_set1_pd;
        let (xi, yi, zi) = (splat(self.x[i]), splat(self.y[i]), splat(self.z[i]));
        let (ai, reach) = (splat(self.radius[i]), splat(reach));
        let free_i = _mm256_castsi256_pd(_mm256_set1_epi64x(self.free[i] as i64));
        for &run in runs {
            let (lo, hi) = self.prepare(i, run, row, len);
            let (s, code) = (images[run.2 as usize].shift, run.2);
            let (sx, sy, sz) = (splat(s.x), splat(s.y), splat(s.z));
            for j in (lo..hi).step_by(LANES) {
                // SAFETY: `j < hi`, at most the particle count (checked by `prepare`), and
                // the arrays hold `LANES` entries past it, so the four loads stay inside;
                // `row` holds `len + hi - lo + LANES` entries (`prepare`), and `len` grows
                // by at most one per candidate before `j`, so the four writes stay inside.
                unsafe {
                    let load = |v: &[f64]| _mm256_loadu_pd(v.as_ptr().add(j));
                    let dx = _mm256_sub_pd(xi, _mm256_add_pd(load(&self.x), sx));
                    let dy = _mm256_sub_pd(yi, _mm256_add_pd(load(&self.y), sy));
                    let dz = _mm256_sub_pd(zi, _mm256_add_pd(load(&self.z), sz));
                    // `(dx² + dy²) + dz²` and `(a_i + a_j) + reach`, as the scalar test.
                    let d2 = _mm256_add_pd(
                        _mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)),
                        _mm256_mul_pd(dz, dz),
                    );
                    let cut = _mm256_add_pd(_mm256_add_pd(ai, load(&self.radius)), reach);
                    let inside = _mm256_cmp_pd::<_CMP_LT_OQ>(d2, _mm256_mul_pd(cut, cut));
                    let free_j = _mm256_loadu_pd(self.free.as_ptr().add(j).cast());
                    let pass = _mm256_and_pd(inside, _mm256_or_pd(free_i, free_j));
                    // Lanes past the run's end belong to other cells.
                    let past = LANES.saturating_sub(hi - j);
                    let bits = (_mm256_movemask_pd(pass) as u32) & (0xf >> past);
                    for l in 0..LANES {
                        *row.get_unchecked_mut(len) = ((j + l) as u32, code);
                        len += ((bits >> l) & 1) as usize;
                    }
                }
            }
        }
        len
    }
}

/// Whether the CPU has AVX2.
fn has_avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::domain::IDENTITY_IMAGE;
    use rand::{RngExt, SeedableRng};

    /// Both copies keep the same candidates, in the same order, as a direct test of every
    /// candidate: runs of every length from one to a dozen, shifted images, prescribed
    /// particles, and candidates exactly at the reach.
    #[test]
    fn both_copies_keep_the_candidates_within_reach() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
        let n = 64;
        let mut position: Vec<DVec3> = (0..n)
            .map(|_| {
                DVec3::new(
                    rng.random::<f64>(),
                    rng.random::<f64>(),
                    rng.random::<f64>(),
                ) * 2.0
            })
            .collect();
        let radius: Vec<f64> = (0..n).map(|_| 0.2 + 0.2 * rng.random::<f64>()).collect();
        let free: Vec<bool> = (0..n).map(|k| k % 5 != 0).collect();
        let reach = 0.1;
        // A candidate at the edge of the reach.
        position[1] = position[0] + DVec3::X * (radius[0] + radius[1] + reach);
        let mut images = [ImageTransform::IDENTITY; IMAGE_COUNT];
        for (c, image) in images.iter_mut().enumerate() {
            image.shift = DVec3::new(
                c as f64 * 0.1 - 1.0,
                0.5 * (c % 3) as f64,
                -0.25 * (c % 2) as f64,
            );
        }
        images[usize::from(IDENTITY_IMAGE)].shift = DVec3::ZERO;
        let runs: Vec<Run> = (0..n as u32 - 12)
            .step_by(5)
            .enumerate()
            .map(|(k, lo)| (lo, lo + 1 + (k as u32 % 12), (k % IMAGE_COUNT) as u8))
            .chain([(0, n as u32, IDENTITY_IMAGE)])
            .collect();
        let plain = Candidates::new(&position, &radius, &free, true);
        let simd = Candidates::new(&position, &radius, &free, false);
        let (mut kept, mut tested) = (0, 0);
        for i in 0..n {
            let mut expected = Vec::new();
            for &(lo, hi, code) in &runs {
                for j in (lo as usize).max(i + 1)..hi as usize {
                    tested += 1;
                    let d = position[i] - (position[j] + images[code as usize].shift);
                    let cut = radius[i] + radius[j] + reach;
                    if d.length_squared() < cut * cut && (free[i] || free[j]) {
                        expected.push((j as u32, code));
                    }
                }
            }
            for candidates in [&plain, &simd] {
                let mut row = vec![(0, 0); 3];
                let len = candidates.scan(i, reach, &runs, &images, &mut row, 2);
                assert_eq!(&row[2..len], &expected[..], "particle {i}");
            }
            kept += expected.len();
        }
        // The test means something: many candidates were kept, and more left out.
        assert!(kept > 100 && 2 * kept < tested, "{kept} of {tested}");
    }
}
