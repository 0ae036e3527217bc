//! Triggers: when an operation of a stage fires, counted in the stage's steps.

/// Fires every `n` steps of a stage, at steps `n, 2n, …`; never when `n` is 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Every(pub u64);

impl Every {
    /// `count` firings spread over a stage of `steps` steps: every `steps / count` steps
    /// (at least 1), never when `count` is 0.
    pub fn spread(steps: u64, count: u64) -> Every {
        Every(steps.checked_div(count).map_or(0, |e| e.max(1)))
    }

    /// Whether it fires at step `step` of the stage (counted from 1).
    pub fn fires(self, step: u64) -> bool {
        self.0 != 0 && step.is_multiple_of(self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::Every;

    #[test]
    fn spread_fires_count_times_and_never_for_zero() {
        let fired = |e: Every, steps: u64| (1..=steps).filter(|&s| e.fires(s)).count();
        assert_eq!(fired(Every::spread(100, 4), 100), 4);
        assert_eq!(fired(Every::spread(10, 3), 10), 3);
        // More firings than steps: every step.
        assert_eq!(fired(Every::spread(5, 50), 5), 5);
        assert_eq!(fired(Every::spread(100, 0), 100), 0);
        assert_eq!(fired(Every(0), 100), 0);
    }
}
