//! Progress of a long command: a bar on a terminal, and a plain line every minute or so
//! when standard error goes to a file or a pipe (a batch job's log), so that a long run in
//! a log is never silent.

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Seconds between the lines written when standard error is not a terminal; the
/// environment variable `RHEODEM_PROGRESS_SECONDS` overrides it.
const LINE_EVERY: f64 = 60.0;

/// A progress report for `particles` particles: a bar, a log line now and then, or
/// nothing (`quiet`).
pub struct Progress {
    bar: ProgressBar,
    log: Option<Mutex<Lines>>,
}

/// The state of the plain lines.
struct Lines {
    every: Duration,
    last: Instant,
    stage: String,
    stage_start: (Instant, u64),
    particles: usize,
}

impl Progress {
    /// A report for a run of `particles` particles.
    pub fn new(quiet: bool, particles: usize) -> Progress {
        let terminal = std::io::stderr().is_terminal();
        let bar = if quiet || !terminal {
            ProgressBar::hidden()
        } else {
            ProgressBar::new(1)
        };
        bar.set_style(
            ProgressStyle::with_template(
                "{msg:7} {bar:40} {pos}/{len} steps  {per_sec}  ETA {eta}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        let log = (!quiet && !terminal).then(|| {
            let every = std::env::var("RHEODEM_PROGRESS_SECONDS")
                .ok()
                .and_then(|s| s.parse::<f64>().ok())
                .filter(|s| s.is_finite() && *s >= 0.0)
                .unwrap_or(LINE_EVERY);
            Mutex::new(Lines {
                every: Duration::from_secs_f64(every),
                last: Instant::now(),
                stage: String::new(),
                stage_start: (Instant::now(), 0),
                particles,
            })
        });
        Progress { bar, log }
    }

    /// Step `done` of `total` of the stage `stage`.
    pub fn update(&self, stage: &str, done: u64, total: u64) {
        if self.bar.message() != stage {
            self.bar.set_message(stage.to_string());
            self.bar.reset();
        }
        self.bar.set_length(total);
        self.bar.set_position(done);
        if let Some(l) = &self.log {
            let Ok(mut l) = l.lock() else { return };
            if l.stage != stage {
                l.stage = stage.to_string();
                l.stage_start = (Instant::now(), done);
            }
            if l.last.elapsed() >= l.every || (done == total && l.every.is_zero()) {
                l.last = Instant::now();
                eprintln!("{}", l.line(done, total));
            }
        }
    }

    /// Writes `text` on its own line (above the bar on a terminal).
    pub fn note(&self, text: &str) {
        self.bar.suspend(|| eprintln!("{text}"));
    }

    /// Removes the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Lines {
    /// `stage: step 1200 of 5000 (24.0 %), 6.31 M particle-steps/s, ETA 12 min`.
    fn line(&self, done: u64, total: u64) -> String {
        let (since, from) = self.stage_start;
        let seconds = since.elapsed().as_secs_f64();
        let steps = done.saturating_sub(from);
        let rate = if seconds > 0.0 {
            steps as f64 / seconds
        } else {
            0.0
        };
        let eta = if rate > 0.0 {
            format_duration(total.saturating_sub(done) as f64 / rate)
        } else {
            "unknown".into()
        };
        format!(
            "{}: step {done} of {total} ({:.1} %), {:.2} M particle-steps/s, ETA {eta}",
            self.stage,
            100.0 * done as f64 / total.max(1) as f64,
            rate * self.particles as f64 / 1e6
        )
    }
}

/// `42 s`, `12 min`, `3.4 h`.
fn format_duration(seconds: f64) -> String {
    if seconds < 90.0 {
        format!("{seconds:.0} s")
    } else if seconds < 5400.0 {
        format!("{:.0} min", seconds / 60.0)
    } else {
        format!("{:.1} h", seconds / 3600.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_read_naturally() {
        assert_eq!(format_duration(42.0), "42 s");
        assert_eq!(format_duration(720.0), "12 min");
        assert_eq!(format_duration(12240.0), "3.4 h");
    }
}
