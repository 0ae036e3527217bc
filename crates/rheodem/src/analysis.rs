//! Statistics of time series: block-averaged error bars and steady-state detection.

use serde::{Deserialize, Serialize};

/// Mean of a correlated series with its standard error from block averaging
/// (Flyvbjerg & Petersen 1989): the series is coarsened by pairwise averaging, level after
/// level, and the largest standard-error estimate over the levels that keep at least 8
/// blocks is reported — the plateau value when the series decorrelates within the
/// window, a conservative bound when it does not. Under 8 samples the plain standard error
/// is reported (it underestimates the error of a correlated series).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// Mean.
    pub mean: f64,
    /// Standard error of the mean.
    pub error: f64,
    /// Samples used.
    pub samples: usize,
}

/// Block-averaged mean and standard error of `x` (`None` with fewer than 2 samples).
pub fn block_average(x: &[f64]) -> Option<Estimate> {
    let n = x.len();
    if n < 2 {
        return None;
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let mut blocks: Vec<f64> = x.to_vec();
    let mut best = 0.0f64;
    while blocks.len() >= 8 {
        let m = blocks.len() as f64;
        let bm = blocks.iter().sum::<f64>() / m;
        let var = blocks.iter().map(|b| (b - bm) * (b - bm)).sum::<f64>() / (m - 1.0);
        best = best.max((var / m).sqrt());
        blocks = blocks
            .chunks_exact(2)
            .map(|c| 0.5 * (c[0] + c[1]))
            .collect();
    }
    if best == 0.0 {
        let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n as f64 - 1.0);
        best = (var / n as f64).sqrt();
    }
    Some(Estimate {
        mean,
        error: best,
        samples: n,
    })
}

/// Whether the two halves of a series agree: their means differ by less than
/// `3 · sqrt(e₁² + e₂²)` (block-averaged errors) or by less than `relative · |mean|`.
pub fn halves_agree(x: &[f64], relative: f64) -> bool {
    let h = x.len() / 2;
    match (block_average(&x[..h]), block_average(&x[h..])) {
        (Some(a), Some(b)) => {
            let diff = (a.mean - b.mean).abs();
            diff <= 3.0 * (a.error * a.error + b.error * b.error).sqrt()
                || diff <= relative * 0.5 * (a.mean.abs() + b.mean.abs())
        }
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    #[test]
    fn white_noise_error_is_sigma_over_sqrt_n() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(5);
        let x: Vec<f64> = (0..4096).map(|_| rng.random::<f64>() - 0.5).collect();
        let e = block_average(&x).expect("enough samples");
        let expected = (1.0f64 / 12.0).sqrt() / 64.0;
        assert!(e.mean.abs() < 4.0 * expected);
        assert!(
            (e.error / expected - 1.0).abs() < 0.35,
            "{} vs {expected}",
            e.error
        );
    }

    #[test]
    fn correlated_series_has_larger_error() {
        // Each value repeated 32 times: 128 independent samples, not 4096.
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(6);
        let x: Vec<f64> = (0..128)
            .flat_map(|_| std::iter::repeat_n(rng.random::<f64>() - 0.5, 32))
            .collect();
        let e = block_average(&x).expect("enough samples");
        let expected = (1.0f64 / 12.0).sqrt() / (128f64).sqrt();
        assert!(
            (e.error / expected - 1.0).abs() < 0.4,
            "{} vs {expected}",
            e.error
        );
    }

    #[test]
    fn a_trend_is_not_steady() {
        let x: Vec<f64> = (0..200).map(|k| k as f64).collect();
        assert!(!halves_agree(&x, 1e-3));
        let flat: Vec<f64> = (0..200)
            .map(|k| 1.0 + 1e-3 * ((k * 7919) % 13) as f64)
            .collect();
        assert!(halves_agree(&flat, 1e-3));
    }
}
