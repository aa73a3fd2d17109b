//! Per-PE-instance "next free slot" structures and the placement moves built on them.
//!
//! Both structures answer "first free slot at or after `t` on column `c`" in near-constant
//! time, so placing a job never scans the slots x instances table.

use crate::problem::InstanceSet;

/// Returned by [`Occupancy::next_free`] when a column has no free slot at or after `t`.
pub(crate) const NONE: u32 = u32::MAX;

/// Free/busy state of every (column, slot) cell.
pub(crate) trait Occupancy {
    /// Smallest free slot `>= t` of `column`, or [`NONE`].
    fn next_free(&mut self, column: usize, t: u32) -> u32;
    /// Largest free slot `<= t` of `column`, or [`NONE`].
    fn prev_free(&mut self, column: usize, t: u32) -> u32;
    /// Marks a free cell busy.
    fn take(&mut self, column: usize, t: u32);
}

/// Unbounded horizon, cells are only ever taken: per column one union-find "next free" array
/// and one "previous free" array (path halving), grown on demand. Used by the decoders, where
/// cells are never freed.
pub(crate) struct NextFree {
    next: Vec<Vec<u32>>,
    /// Shifted by one: `prev[t + 1]` leads towards the free slot at or below `t`, and the root
    /// 0 stands for "none".
    prev: Vec<Vec<u32>>,
}

impl NextFree {
    /// All cells of `columns` columns free; arrays presized for `horizon` slots (they grow
    /// past it on demand), which saves reallocation when the makespan is roughly known.
    pub fn new(columns: usize, horizon: u32) -> Self {
        NextFree {
            next: vec![(0..horizon).collect(); columns],
            prev: vec![(0..=horizon).collect(); columns],
        }
    }
}

impl Occupancy for NextFree {
    fn next_free(&mut self, column: usize, t: u32) -> u32 {
        let v = &mut self.next[column];
        let len = v.len() as u32;
        let mut x = t;
        loop {
            if x >= len {
                return x;
            }
            let p = v[x as usize];
            if p == x {
                return x;
            }
            if p >= len {
                return p;
            }
            let gp = v[p as usize];
            v[x as usize] = gp;
            x = gp;
        }
    }

    fn prev_free(&mut self, column: usize, t: u32) -> u32 {
        let v = &mut self.prev[column];
        let len = v.len() as u32;
        let mut x = t + 1;
        if x >= len {
            return t;
        }
        loop {
            let p = v[x as usize];
            if p == x {
                return if x == 0 { NONE } else { x - 1 };
            }
            let gp = v[p as usize];
            v[x as usize] = gp;
            x = gp;
        }
    }

    fn take(&mut self, column: usize, t: u32) {
        let v = &mut self.next[column];
        if t as usize >= v.len() {
            let new_len = (t as usize + 1).max(v.len() * 2).max(64);
            let old = v.len() as u32;
            v.extend(old..new_len as u32);
            let w = &mut self.prev[column];
            let old = w.len() as u32;
            w.extend(old..=new_len as u32);
        }
        debug_assert_eq!(v[t as usize], t, "slot {t} of column {column} is not free");
        v[t as usize] = t + 1;
        self.prev[column][t as usize + 1] = t;
    }
}

/// Fixed horizon `[0, horizon)`, cells can be freed again: a two-level bitset per column
/// (bit set = free). Used by the ASAP pass, which moves jobs.
pub(crate) struct FreeSlots {
    words: Vec<Vec<u64>>,
    summary: Vec<Vec<u64>>,
    horizon: u32,
}

impl FreeSlots {
    /// All cells of `columns` columns over `[0, horizon)` free.
    pub fn all_free(columns: usize, horizon: u32) -> Self {
        let n_words = (horizon as usize).div_ceil(64);
        let mut words = vec![!0u64; n_words];
        let tail = horizon % 64;
        if let Some(last) = words.last_mut().filter(|_| tail != 0) {
            *last = (1u64 << tail) - 1;
        }
        let n_summary = n_words.div_ceil(64);
        let mut summary = vec![0u64; n_summary];
        for (w, &bits) in words.iter().enumerate() {
            if bits != 0 {
                summary[w / 64] |= 1 << (w % 64);
            }
        }
        FreeSlots {
            words: vec![words; columns],
            summary: vec![summary; columns],
            horizon,
        }
    }

    /// Marks a busy cell free.
    pub fn give(&mut self, column: usize, t: u32) {
        let w = t as usize / 64;
        self.words[column][w] |= 1 << (t % 64);
        self.summary[column][w / 64] |= 1 << (w % 64);
    }
}

impl Occupancy for FreeSlots {
    fn next_free(&mut self, column: usize, t: u32) -> u32 {
        if t >= self.horizon {
            return NONE;
        }
        let words = &self.words[column];
        let summary = &self.summary[column];
        let w = t as usize / 64;
        let bits = words[w] & (!0u64 << (t % 64));
        if bits != 0 {
            return (w * 64) as u32 + bits.trailing_zeros();
        }
        let mut sw = w + 1;
        loop {
            let s = sw / 64;
            if s >= summary.len() {
                return NONE;
            }
            let sbits = summary[s] & (!0u64 << (sw % 64));
            if sbits != 0 {
                let word = s * 64 + sbits.trailing_zeros() as usize;
                return (word * 64) as u32 + words[word].trailing_zeros();
            }
            sw = (s + 1) * 64;
        }
    }

    fn prev_free(&mut self, column: usize, t: u32) -> u32 {
        let t = t.min(self.horizon.saturating_sub(1));
        if self.horizon == 0 {
            return NONE;
        }
        let words = &self.words[column];
        let summary = &self.summary[column];
        let w = t as usize / 64;
        let bits = words[w] & (!0u64 >> (63 - t % 64));
        if bits != 0 {
            return (w * 64) as u32 + 63 - bits.leading_zeros();
        }
        // Words strictly below `w`.
        let mut sw = w;
        while sw > 0 {
            let top = sw - 1;
            let s = top / 64;
            let sbits = summary[s] & (!0u64 >> (63 - top % 64));
            if sbits != 0 {
                let word = s * 64 + 63 - sbits.leading_zeros() as usize;
                return (word * 64) as u32 + 63 - words[word].leading_zeros();
            }
            sw = s * 64;
        }
        NONE
    }

    fn take(&mut self, column: usize, t: u32) {
        let w = t as usize / 64;
        debug_assert!(self.words[column][w] & (1 << (t % 64)) != 0);
        self.words[column][w] &= !(1u64 << (t % 64));
        if self.words[column][w] == 0 {
            self.summary[column][w / 64] &= !(1u64 << (w % 64));
        }
    }
}

/// Slot of the `n`-th free (column, slot) cell of `plane` in time order at or after `t`
/// (`n >= 1`): where a round's `n` jobs on that plane end at the earliest when placed one by
/// one. [`NONE`] if there are fewer such cells.
pub(crate) fn nth_free_cell<O: Occupancy>(
    occ: &mut O,
    inst: &InstanceSet,
    plane: u32,
    t: u32,
    n: u32,
    cursors: &mut Vec<u32>,
) -> u32 {
    let cols = inst.columns(plane);
    if n == 1 {
        return cols.map(|c| occ.next_free(c, t)).min().unwrap_or(NONE);
    }
    cursors.clear();
    cursors.extend(cols.clone().map(|c| occ.next_free(c, t)));
    for _ in 1..n {
        let Some((k, &cur)) = cursors.iter().enumerate().min_by_key(|&(_, &v)| v) else {
            return NONE;
        };
        if cur == NONE {
            return NONE;
        }
        cursors[k] = occ.next_free(cols.start + k, cur + 1);
    }
    cursors.iter().copied().min().unwrap_or(NONE)
}

/// Smallest slot in `[t0, limit]` where every `(plane, count)` of `needs` has `count` free
/// copies at once, so a whole round fits in one slot (latency factor 0).
///
/// Jumps forward to the next candidate each time instead of stepping slot by slot and gives
/// up after a few jumps: on a fragmented schedule the round is then placed job by job.
pub(crate) fn aligned_slot<O: Occupancy>(
    occ: &mut O,
    inst: &InstanceSet,
    needs: &[(u32, u32)],
    t0: u32,
    limit: u32,
    cursors: &mut Vec<u32>,
) -> Option<u32> {
    const MAX_JUMPS: u32 = 16;
    let mut t = t0;
    for _ in 0..MAX_JUMPS {
        if t > limit {
            return None;
        }
        let mut next = t;
        for &(plane, count) in needs {
            let cols = inst.columns(plane);
            if cols.len() < count as usize {
                return None;
            }
            // The `count`-th smallest "next free" over the copies: before it fewer than
            // `count` copies are free at any slot.
            if count == 1 {
                let v = cols.map(|c| occ.next_free(c, t)).min().unwrap_or(NONE);
                if v == NONE {
                    return None;
                }
                next = next.max(v);
                continue;
            }
            cursors.clear();
            cursors.extend(cols.map(|c| occ.next_free(c, t)));
            let (_, &mut v, _) = cursors.select_nth_unstable(count as usize - 1);
            if v == NONE {
                return None;
            }
            next = next.max(v);
        }
        if next == t {
            return Some(t);
        }
        t = next;
    }
    None
}

/// Puts every point of `planes` in slot `t` (which [`aligned_slot`] found), appending
/// `(slot, column)` per point to `out`.
pub(crate) fn place_aligned<O: Occupancy>(
    occ: &mut O,
    inst: &InstanceSet,
    planes: &[u32],
    t: u32,
    out: &mut Vec<(u32, u32)>,
) {
    for &plane in planes {
        let cols = inst.columns(plane);
        let col = cols
            .clone()
            .find(|&c| occ.next_free(c, t) == t)
            .unwrap_or(cols.start);
        occ.take(col, t);
        out.push((t, col as u32));
    }
}

/// Puts every point of `planes` at the latest free cell in `[earliest, end]`, appending
/// `(slot, column)` per point to `out`: the round keeps its end and spreads as little as the
/// free cells allow. `end` must leave enough free cells for every plane (for instance the
/// largest [`nth_free_cell`] of the round's planes from `earliest`).
pub(crate) fn place_latest<O: Occupancy>(
    occ: &mut O,
    inst: &InstanceSet,
    planes: &[u32],
    earliest: u32,
    end: u32,
    out: &mut Vec<(u32, u32)>,
) {
    for &plane in planes {
        let best = inst
            .columns(plane)
            .map(|c| (occ.prev_free(c, end), std::cmp::Reverse(c)))
            .filter(|&(t, _)| t != NONE && t >= earliest)
            .max();
        debug_assert!(
            best.is_some(),
            "no free cell of plane {plane} in [{earliest}, {end}]"
        );
        if let Some((t, std::cmp::Reverse(col))) = best {
            occ.take(col, t);
            out.push((t, col as u32));
        }
    }
}

/// Puts every point of `planes` at its earliest free cell at or after `earliest`, appending
/// `(slot, column)` per point to `out`. Returns `false` (with `out` partly filled and those
/// cells taken) if some point finds no free cell.
pub(crate) fn place_individually<O: Occupancy>(
    occ: &mut O,
    inst: &InstanceSet,
    planes: &[u32],
    earliest: u32,
    out: &mut Vec<(u32, u32)>,
) -> bool {
    for &plane in planes {
        let best = inst
            .columns(plane)
            .map(|c| (occ.next_free(c, earliest), c))
            .min();
        match best {
            Some((t, col)) if t != NONE => {
                occ.take(col, t);
                out.push((t, col as u32));
            }
            _ => return false,
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both structures agree with a plain boolean table.
    #[test]
    fn next_and_previous_free_match_a_table() {
        let horizon = 300u32;
        let mut table = vec![true; horizon as usize];
        let mut uf = NextFree::new(1, 16);
        let mut bits = FreeSlots::all_free(1, horizon);
        let mut x = 7u32;
        for _ in 0..250 {
            x = (x * 37 + 11) % horizon;
            if table[x as usize] {
                table[x as usize] = false;
                uf.take(0, x);
                bits.take(0, x);
            }
            for t in 0..horizon {
                let next = (t..horizon).find(|&s| table[s as usize]);
                let prev = (0..=t).rev().find(|&s| table[s as usize]);
                assert_eq!(uf.next_free(0, t), next.unwrap_or(horizon));
                assert_eq!(bits.next_free(0, t), next.unwrap_or(NONE));
                assert_eq!(uf.prev_free(0, t), prev.unwrap_or(NONE));
                assert_eq!(bits.prev_free(0, t), prev.unwrap_or(NONE));
            }
        }
        // Past the horizon the union-find is free, the bitset full.
        assert_eq!(uf.next_free(0, horizon + 5), horizon + 5);
        assert_eq!(uf.prev_free(0, horizon + 5), horizon + 5);
        bits.give(0, 0);
        assert_eq!(bits.prev_free(0, 0), 0);
    }
}
