//! The memory a run will take, estimated from its particle count before anything is
//! allocated, and the limit it is held to (by default the machine's physical memory), so
//! that an oversized input is refused with the key that makes it large instead of ending
//! in an allocation failure or hours of swapping.

use std::fmt;

/// Estimated bytes per particle: the particle arrays, the Verlet list with its contact
/// histories, the cell lists and the outputs' per-particle buffers. Measured as the peak
/// resident memory of a split-bottom cell at two sizes (13 093 and 102 179 particles while
/// filling: 2.6 kB per particle more, 2026-12-06); a settled or sheared dense packing holds
/// more pairs per particle, so the estimate takes 4 kB.
pub const BYTES_PER_PARTICLE: u64 = 4096;

/// Estimated bytes per particle and extra worker thread: an upper bound on what grows with
/// the thread count (each thread's table of the history carried over a rebuild, one count
/// per particle, and the force and torque buffers of a chunk's halo, `2 × 3 × 8` bytes per
/// halo slot, a halo being at most a layer of cells; see `crate::halo`).
pub const BYTES_PER_PARTICLE_THREAD: u64 = 64;

/// Fixed memory of a run besides its particles (program, thread stacks, tables).
pub const BASE_BYTES: u64 = 32 << 20;

/// The estimated peak memory (bytes) of a run of `particles` particles on `threads`
/// worker threads.
pub fn estimate(particles: u64, threads: usize) -> u64 {
    let per = BYTES_PER_PARTICLE
        .saturating_add(BYTES_PER_PARTICLE_THREAD.saturating_mul(threads.saturating_sub(1) as u64));
    BASE_BYTES.saturating_add(particles.saturating_mul(per))
}

/// The most particles that fit in `limit` bytes on `threads` worker threads.
pub fn particles_within(limit: u64, threads: usize) -> u64 {
    let per = estimate(1, threads) - BASE_BYTES;
    limit.saturating_sub(BASE_BYTES) / per
}

/// The physical memory of this machine (bytes), if the system says (`MemTotal` of
/// `/proc/meminfo` on Linux; `None` elsewhere, where no limit is applied by default).
pub fn physical_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib.saturating_mul(1024))
}

/// A size in bytes, printed with a binary unit (`1.5 GiB`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Bytes(pub u64);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
        let mut v = self.0 as f64;
        let mut unit = 0;
        while v >= 1024.0 && unit + 1 < UNITS.len() {
            v /= 1024.0;
            unit += 1;
        }
        if unit == 0 {
            write!(f, "{} B", self.0)
        } else {
            write!(f, "{v:.1} {}", UNITS[unit])
        }
    }
}

/// Parses a size such as `512MiB`, `8GiB`, `8G`, `2.5GB` or `1000000` (bytes); decimal
/// (`kB`, `MB`, `GB`, `TB`) and binary (`K`, `M`, `G`, `T`, `KiB`, `MiB`, `GiB`, `TiB`)
/// units, case-insensitive.
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let value: f64 = number
        .parse()
        .map_err(|_| format!("`{text}`: not a size (write e.g. 512MiB, 8GiB or 8GB)"))?;
    let factor: f64 = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "kb" => 1e3,
        "mb" => 1e6,
        "gb" => 1e9,
        "tb" => 1e12,
        "k" | "kib" => 1024.0,
        "m" | "mib" => 1024f64.powi(2),
        "g" | "gib" => 1024f64.powi(3),
        "t" | "tib" => 1024f64.powi(4),
        other => {
            return Err(format!(
                "`{text}`: unknown unit `{other}` (B, kB, MB, GB, TB, KiB, MiB, GiB, TiB)"
            ));
        }
    };
    let bytes = value * factor;
    if !((1.0..1.8e19).contains(&bytes)) {
        return Err(format!("`{text}`: must lie between 1 B and 16 EiB"));
    }
    Ok(bytes as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_in_decimal_and_binary_units() {
        assert_eq!(parse_size("1000").expect("a size"), 1000);
        assert_eq!(parse_size("2kB").expect("a size"), 2000);
        assert_eq!(parse_size("8GiB").expect("a size"), 8 << 30);
        assert_eq!(parse_size("8g").expect("a size"), 8 << 30);
        assert_eq!(parse_size("1.5 MB").expect("a size"), 1_500_000);
        assert!(parse_size("lots").is_err());
        assert!(
            parse_size("5 parsecs")
                .expect_err("refused")
                .contains("unknown unit")
        );
        assert!(parse_size("0").is_err());
        assert_eq!(Bytes(512).to_string(), "512 B");
        assert_eq!(Bytes(3 << 29).to_string(), "1.5 GiB");
    }

    #[test]
    fn the_estimate_and_its_inverse_agree() {
        for threads in [1, 2, 16] {
            let n = particles_within(8 << 30, threads);
            assert!(estimate(n, threads) <= 8 << 30);
            assert!(estimate(n + 1, threads) > 8 << 30);
        }
        // Saturates rather than overflowing on absurd counts.
        assert_eq!(estimate(u64::MAX, 4), u64::MAX);
    }
}
