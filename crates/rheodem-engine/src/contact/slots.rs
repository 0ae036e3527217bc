//! The contact history of a pair list, one slot per pair, in structure-of-arrays form.
//!
//! A touching pair under sliding friction alone reads and writes its tangential spring
//! only; with the springs, the bridge flag and the laws' states in separate arrays
//! (the force loop touches a state only under a law that keeps one), the force loop streams
//! 24 bytes per pair instead of a whole [`ContactHistory`] record (96 bytes), and the
//! array it walks each step fits in a core's L2 cache on the standard problem. Stored
//! (checkpoints) as a sequence of [`ContactHistory`] records, as before the split.

use super::ContactHistory;
use glam::DVec3;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// Contact history of every pair of a list (see the module documentation).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HistorySlots {
    tangential: Vec<DVec3>,
    rolling: Vec<DVec3>,
    torsion: Vec<DVec3>,
    bridge: Vec<bool>,
    state: Vec<f64>,
    sliding_state: Vec<f64>,
}

impl HistorySlots {
    /// Number of slots.
    pub fn len(&self) -> usize {
        self.bridge.len()
    }

    /// Whether there are no slots.
    pub fn is_empty(&self) -> bool {
        self.bridge.is_empty()
    }

    /// Makes the number of slots `n`; slots added are empty.
    pub fn resize(&mut self, n: usize) {
        self.tangential.resize(n, DVec3::ZERO);
        self.rolling.resize(n, DVec3::ZERO);
        self.torsion.resize(n, DVec3::ZERO);
        self.bridge.resize(n, false);
        self.state.resize(n, 0.0);
        self.sliding_state.resize(n, 0.0);
    }

    /// The history of slot `k`.
    pub fn get(&self, k: usize) -> ContactHistory {
        record(
            &self.tangential,
            &self.rolling,
            &self.torsion,
            &self.bridge,
            &self.state,
            &self.sliding_state,
            k,
        )
    }

    /// Every slot's history, in order.
    pub fn iter(&self) -> impl Iterator<Item = ContactHistory> + '_ {
        (0..self.len()).map(|k| self.get(k))
    }

    /// Mutable views of all the slots.
    pub fn view(&mut self) -> HistoryView<'_> {
        HistoryView {
            tangential: &mut self.tangential,
            rolling: &mut self.rolling,
            torsion: &mut self.torsion,
            bridge: &mut self.bridge,
            state: &mut self.state,
            sliding_state: &mut self.sliding_state,
        }
    }
}

/// Slot `k` of the six arrays as one record.
#[inline(always)]
fn record(
    tangential: &[DVec3],
    rolling: &[DVec3],
    torsion: &[DVec3],
    bridge: &[bool],
    state: &[f64],
    sliding_state: &[f64],
    k: usize,
) -> ContactHistory {
    ContactHistory {
        tangential: tangential[k],
        rolling: rolling[k],
        torsion: torsion[k],
        bridge: bridge[k],
        state: state[k],
        sliding_state: sliding_state[k],
    }
}

impl FromIterator<ContactHistory> for HistorySlots {
    fn from_iter<I: IntoIterator<Item = ContactHistory>>(records: I) -> HistorySlots {
        let mut slots = HistorySlots::default();
        for h in records {
            slots.tangential.push(h.tangential);
            slots.rolling.push(h.rolling);
            slots.torsion.push(h.torsion);
            slots.bridge.push(h.bridge);
            slots.state.push(h.state);
            slots.sliding_state.push(h.sliding_state);
        }
        slots
    }
}

impl Serialize for HistorySlots {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_seq(self.iter())
    }
}

impl<'de> Deserialize<'de> for HistorySlots {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<HistorySlots, D::Error> {
        Ok(Vec::<ContactHistory>::deserialize(deserializer)?
            .into_iter()
            .collect())
    }
}

/// Mutable views of a run of slots of [`HistorySlots`] (the springs in m).
#[derive(Debug, Default)]
pub struct HistoryView<'a> {
    /// Tangential (sliding) springs `ξ_t`.
    pub tangential: &'a mut [DVec3],
    /// Rolling springs `ξ_r`.
    pub rolling: &'a mut [DVec3],
    /// Torsion springs `ξ_o`.
    pub torsion: &'a mut [DVec3],
    /// Whether an irreversible law's bridge exists.
    pub bridge: &'a mut [bool],
    /// The normal law's per-contact state.
    pub state: &'a mut [f64],
    /// The sliding spring law's per-contact state.
    pub sliding_state: &'a mut [f64],
}

impl<'a> HistoryView<'a> {
    /// Number of slots in view.
    pub fn len(&self) -> usize {
        self.bridge.len()
    }

    /// Whether no slot is in view.
    pub fn is_empty(&self) -> bool {
        self.bridge.is_empty()
    }

    /// Splits the view into the slots before `mid` and those from it on.
    pub fn split_at(self, mid: usize) -> (HistoryView<'a>, HistoryView<'a>) {
        let (t0, t1) = self.tangential.split_at_mut(mid);
        let (r0, r1) = self.rolling.split_at_mut(mid);
        let (o0, o1) = self.torsion.split_at_mut(mid);
        let (b0, b1) = self.bridge.split_at_mut(mid);
        let (s0, s1) = self.state.split_at_mut(mid);
        let (q0, q1) = self.sliding_state.split_at_mut(mid);
        (
            HistoryView {
                tangential: t0,
                rolling: r0,
                torsion: o0,
                bridge: b0,
                state: s0,
                sliding_state: q0,
            },
            HistoryView {
                tangential: t1,
                rolling: r1,
                torsion: o1,
                bridge: b1,
                state: s1,
                sliding_state: q1,
            },
        )
    }

    /// The history of slot `k`.
    pub fn get(&self, k: usize) -> ContactHistory {
        record(
            self.tangential,
            self.rolling,
            self.torsion,
            self.bridge,
            self.state,
            self.sliding_state,
            k,
        )
    }

    /// Every slot's history in view, in order.
    pub fn iter(&self) -> impl Iterator<Item = ContactHistory> + '_ {
        (0..self.len()).map(|k| self.get(k))
    }

    /// Sets the history of slot `k`.
    #[inline(always)]
    pub fn set(&mut self, k: usize, h: &ContactHistory) {
        self.tangential[k] = h.tangential;
        self.rolling[k] = h.rolling;
        self.torsion[k] = h.torsion;
        self.bridge[k] = h.bridge;
        self.state[k] = h.state;
        self.sliding_state[k] = h.sliding_state;
    }

    /// Empties slot `k`: springs and state at zero, no bridge.
    #[inline(always)]
    pub fn clear(&mut self, k: usize) {
        self.set(k, &ContactHistory::default());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(k: usize) -> ContactHistory {
        let x = k as f64;
        ContactHistory {
            tangential: DVec3::new(x, 1.0, 2.0),
            rolling: DVec3::new(3.0, x, 4.0),
            torsion: DVec3::new(5.0, 6.0, x),
            bridge: k % 2 == 1,
            state: 0.5 * x,
            sliding_state: 0.25 * x,
        }
    }

    #[test]
    fn slots_keep_records_and_store_as_records() {
        let records: Vec<ContactHistory> = (0..5).map(record).collect();
        let mut slots: HistorySlots = records.iter().copied().collect();
        assert_eq!(slots.iter().collect::<Vec<_>>(), records);
        // Stored exactly as the records were, so checkpoints keep their shape.
        let stored = rmp_serde::to_vec(&slots).expect("store");
        assert_eq!(stored, rmp_serde::to_vec(&records).expect("store records"));
        let back: HistorySlots = rmp_serde::from_slice(&stored).expect("load");
        assert_eq!(back, slots);

        let (mut low, mut high) = slots.view().split_at(2);
        assert_eq!((low.len(), high.len()), (2, 3));
        high.clear(0);
        low.set(1, &record(9));
        assert_eq!(slots.get(2), ContactHistory::default());
        assert_eq!(slots.get(1), record(9));
        slots.resize(7);
        assert_eq!(slots.get(6), ContactHistory::default());
        assert_eq!(slots.get(4), record(4));
    }
}
