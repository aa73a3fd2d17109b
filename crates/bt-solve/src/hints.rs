//! Where each candidate was blocked last, per thread: a stream of nearby receivers (`beamtrace
//! serve`, `trace_many`) meets the same candidates answer after answer, most of them blocked
//! by the same surface on the same segment (in the living room 70 of 115). Testing that
//! surface first ([`crate::validate::validate_hinted`]) replaces the segments' BVH walks with
//! one polygon test. A hint is only a guess, checked against the scene at hand: a wrong or
//! stale one (another scene, a receiver far away) costs that one test and changes nothing.

use bt_geom::hash::KeyMap;
use bt_scene::SurfaceId;
use std::cell::RefCell;

/// Hints a thread keeps at most: beyond, they are forgotten at once (a room's kept tree has
/// ~1,600 nodes; a city's candidates come and go), so the memory stays bounded.
const MAX_HINTS: usize = 1 << 14;

/// The blocked candidates' segment and blocker, by candidate ([`key`]).
#[derive(Debug, Default)]
pub(crate) struct Hints(KeyMap<Key, (u32, SurfaceId)>);

/// A candidate's surfaces ([`key`]): two words, hashed as two by [`KeyMap`]'s hasher.
pub(crate) type Key = (u64, u64);

thread_local! {
    /// This thread's hints, taken for a batch and given back after it ([`Hints::take`]).
    static HINTS: RefCell<Hints> = RefCell::default();
}

impl Hints {
    /// This thread's hints, for one batch (an empty store inside a batch of this thread that
    /// holds them already); give them back with [`Hints::give_back`].
    pub(crate) fn take() -> Hints {
        HINTS.take()
    }

    /// Hand the hints back to this thread for its next batch.
    pub(crate) fn give_back(self) {
        HINTS.set(self);
    }

    /// The segment and surface that blocked the candidate of `key` last.
    #[inline(always)]
    pub(crate) fn get(&self, key: Key) -> Option<(usize, SurfaceId)> {
        self.0
            .get(&key)
            .map(|&(segment, by)| (segment as usize, by))
    }

    /// Record the candidate's verdict: blocked at `segment` by `by`, or (`None`) not blocked.
    #[inline(always)]
    pub(crate) fn record(&mut self, key: Key, blocked: Option<(usize, SurfaceId)>) {
        match blocked {
            Some((segment, by)) => {
                if self.0.len() >= MAX_HINTS {
                    self.0.clear();
                }
                self.0.insert(key, (segment as u32, by));
            }
            None => {
                self.0.remove(&key);
            }
        }
    }
}

/// A candidate's key: its surfaces' ids + 1 in 32 bits each, the first lowest (distinct
/// sequences, distinct keys); `None` for more than four surfaces or an id of `u32::MAX`.
#[inline(always)]
pub(crate) fn key(seq: &[SurfaceId]) -> Option<Key> {
    if seq.len() > 4 {
        return None;
    }
    let mut key = [0u64; 2];
    for (k, id) in seq.iter().enumerate() {
        key[k / 2] |= u64::from(id.0.checked_add(1)?) << (32 * (k % 2));
    }
    Some((key[0], key[1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distinct sequences of up to four surfaces get distinct keys (prefixes, zeros, the
    /// largest id); longer ones and an id of `u32::MAX` get none.
    #[test]
    fn keys_tell_sequences_apart() {
        let ids = [0, 1, 2, 7, u32::MAX - 1];
        let mut seqs: Vec<Vec<SurfaceId>> = vec![vec![]];
        for _ in 0..4 {
            let longer: Vec<Vec<SurfaceId>> = (seqs.iter())
                .filter(|s| s.len() == seqs.last().unwrap().len())
                .flat_map(|s| {
                    ids.iter().map(move |&i| {
                        let mut t = s.clone();
                        t.push(SurfaceId(i));
                        t
                    })
                })
                .collect();
            seqs.extend(longer);
        }
        let keys: std::collections::HashSet<Key> = seqs.iter().map(|s| key(s).unwrap()).collect();
        assert_eq!(keys.len(), seqs.len());
        assert_eq!(key(&[SurfaceId(1); 5]), None);
        assert_eq!(key(&[SurfaceId(1), SurfaceId(u32::MAX)]), None);
    }

    /// A hint is kept, replaced, forgotten when the candidate is not blocked, and the store
    /// never holds more than [`MAX_HINTS`].
    #[test]
    fn hints_are_recorded_and_bounded() {
        let mut hints = Hints::default();
        let key = (5, 0);
        hints.record(key, Some((1, SurfaceId(3))));
        assert_eq!(hints.get(key), Some((1, SurfaceId(3))));
        hints.record(key, Some((0, SurfaceId(4))));
        assert_eq!(hints.get(key), Some((0, SurfaceId(4))));
        hints.record(key, None);
        assert_eq!(hints.get(key), None);
        for k in 0..(MAX_HINTS as u64 + 10) {
            hints.record((k, 1), Some((0, SurfaceId(1))));
            assert!(hints.0.len() <= MAX_HINTS);
        }
    }
}
