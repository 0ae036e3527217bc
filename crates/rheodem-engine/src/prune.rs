//! The inner list: the pairs of the Verlet list that lie within a smaller skin, re-selected
//! ("pruned") every few steps, so that the force loop's distance test runs over them only.
//!
//! The Verlet list keeps every pair within reach plus the skin `s` and lasts until two
//! particles could have closed that skin (tens of steps). Most of its pairs are far from
//! contact most of the time: in the sheared standard problem about half of them touch, and
//! a third lie beyond 0.05 of contact. At a prune, the force loop's full scan also keeps
//! the pairs within their reach plus a margin `m < s`; until the particles could have
//! closed `m`, a pair left out cannot come within reach, so the scan of the kept pairs
//! finds the same pairs in the same order as the full scan would, and the forces keep
//! their bits. The margin is checked with the skin check's bound ([`crate::displacement`],
//! [`crate::neighbor::NeighborList::needs_rebuild`]): at a prune, the pairs outside the
//! Verlet list are still at least `s − c` beyond reach (`c` the bound on how far the skin
//! has closed since the build), so `m` is at most that. Between prunes the check measures
//! the displacements since the prune only, and bounds those since the build by them, so
//! that a step still makes one pass over the particles, and the list is rebuilt at the
//! same steps as without the inner list.
//!
//! The plan lives with the list but not in checkpoints: a list read back or cloned scans
//! whole until its next check prunes it; a build prunes at once. The kept pairs themselves
//! are the force loop's scratch, tagged with the plan's stamp, which is unique in the
//! process, so that a scratch never takes the kept pairs of another list or of an older
//! prune.

use std::sync::atomic::{AtomicU64, Ordering};

/// The inner skin as a fraction of the Verlet skin.
///
/// Chosen by measurement on the standard problem (BENCHMARKS.md): a fifth of the skin
/// (0.04 of a mean diameter of 1) keeps about three quarters of the list's pairs, and one
/// scan in about a dozen covers the whole list. From 0.15 to 0.3 of the skin ran equally
/// fast within the noise: a smaller margin keeps fewer pairs but prunes more often.
pub const INNER_SKIN_FRACTION: f64 = 0.2;

/// Below this fraction of the inner skin, what is left of the Verlet skin is not worth a
/// prune (the kept pairs would last a step or two): the loop scans the whole list until
/// the next build.
const LEAST_MARGIN_FRACTION: f64 = 0.5;

/// The process-wide source of prune stamps.
static NEXT_STAMP: AtomicU64 = AtomicU64::new(1);

/// What the force loop scans: the whole list, or the pairs kept by the prune `stamp`
/// within their reach plus `margin` (m).
#[derive(Debug, Default)]
pub struct PrunePlan {
    /// Identifies the prune (unique in the process); 0 for none.
    pub stamp: u64,
    /// The margin beyond reach within which the prune keeps pairs (m); 0 when the loop
    /// scans the whole list.
    pub margin: f64,
}

impl Clone for PrunePlan {
    /// A clone scans the whole list until its own next prune (its kept pairs would be
    /// another list's).
    fn clone(&self) -> PrunePlan {
        PrunePlan::default()
    }
}

impl PrunePlan {
    /// A new prune within `margin` (m) of reach, with a stamp of its own.
    pub fn new(margin: f64) -> PrunePlan {
        PrunePlan {
            stamp: NEXT_STAMP.fetch_add(1, Ordering::Relaxed),
            margin,
        }
    }

    /// The prune for a list whose pairs are still at least `left` (m) beyond reach, with an
    /// inner skin of [`INNER_SKIN_FRACTION`] of `skin` (m): none when less is left than is
    /// worth a prune.
    pub fn within(left: f64, skin: f64) -> PrunePlan {
        let inner = INNER_SKIN_FRACTION * skin;
        let margin = left.min(inner);
        if margin >= LEAST_MARGIN_FRACTION * inner && margin > 0.0 {
            PrunePlan::new(margin)
        } else {
            PrunePlan::default()
        }
    }

    /// Whether the loop scans kept pairs (rather than the whole list).
    pub fn is_active(&self) -> bool {
        self.margin > 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_prune_has_its_own_stamp_and_a_clone_prunes_afresh() {
        let (a, b) = (PrunePlan::new(0.05), PrunePlan::new(0.05));
        assert_ne!(a.stamp, b.stamp);
        assert!(a.stamp > 0 && b.stamp > 0);
        let c = a.clone();
        assert!(!c.is_active());
        assert_eq!(c.stamp, 0);
    }

    #[test]
    fn the_margin_is_what_the_skin_leaves_up_to_the_inner_skin() {
        let skin = 0.2;
        let inner = INNER_SKIN_FRACTION * skin;
        assert_eq!(PrunePlan::within(1.0, skin).margin, inner);
        assert_eq!(PrunePlan::within(0.8 * inner, skin).margin, 0.8 * inner);
        assert!(!PrunePlan::within(0.4 * inner, skin).is_active());
        assert!(!PrunePlan::within(-1.0, skin).is_active());
    }
}
