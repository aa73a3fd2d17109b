//! Pass 3 of the paper's procedure: ASAP fill of empty slots.

use crate::decode::{self, Fitness, Positions};
use crate::occupancy::{self, FreeSlots, Occupancy};
use crate::problem::{InstanceSet, Prepared};

/// Moves jobs into earlier empty cells where the phase order allows, then (implicitly, as
/// the makespan is recomputed) drops empty trailing slots.
///
/// Units (phases of path rounds) are visited in order of their current first slot, so a
/// unit's predecessor has already moved and its new end gives the earliest legal slot. Each
/// unit is taken out and put back in the best of three ways, compared by (unit end, unit
/// spread): where it was, all jobs in one slot, or ending at the earliest possible slot with
/// every job at the latest free cell before it. The old cells are one of the
/// options and the unit's predecessor never ends later, so no unit ends later than before
/// and the makespan never grows; a unit's spread (its share of the latency factor) only
/// grows when that makes the unit end earlier.
pub(crate) fn asap_fill(prep: &Prepared<'_>, inst: &InstanceSet, pos: &mut Positions) -> Fitness {
    let horizon = decode::measure(prep, pos).makespan;
    let mut free = FreeSlots::all_free(inst.len(), horizon);
    for &(slot, col) in pos.iter() {
        free.take(col as usize, slot);
    }
    let mut units = Vec::with_capacity(prep.total_units());
    decode::for_each_unit(prep, |path, _, unit, jobs| {
        let start = pos[jobs.clone()].iter().map(|&(s, _)| s).min().unwrap_or(0);
        let p = path as usize;
        let phase = (unit - prep.unit_offset[p] as usize) as u32 % prep.phases(p);
        units.push((start, path, unit as u32, phase, jobs.start as u32));
    });
    units.sort_unstable();

    let mut new_end = vec![0u32; prep.total_units()];
    let mut cursors = Vec::new();
    let mut cells = Vec::new();
    for (start, p, unit, phase, first) in units {
        let planes = prep.phase_planes(p as usize, phase);
        let needs = prep.needs(p as usize, phase);
        let first = first as usize;
        let jobs = first..first + planes.len();
        let ro = unit as usize;
        let earliest = if ro == prep.unit_offset[p as usize] as usize {
            0
        } else {
            new_end[ro - 1] + 1
        };
        let old_end = pos[jobs.clone()]
            .iter()
            .map(|&(s, _)| s)
            .max()
            .unwrap_or(start);
        debug_assert!(start >= earliest);
        if start == earliest && old_end == start {
            new_end[ro] = old_end;
            continue;
        }
        for &(slot, col) in &pos[jobs.clone()] {
            free.give(col as usize, slot);
        }

        let ind_end = needs
            .iter()
            .map(|&(plane, n)| {
                occupancy::nth_free_cell(&mut free, inst, plane, earliest, n, &mut cursors)
            })
            .max()
            .unwrap_or(earliest);
        debug_assert!(ind_end <= old_end, "the unit's own old cells are free");
        cells.clear();
        occupancy::place_latest(&mut free, inst, planes, earliest, ind_end, &mut cells);
        let ind_start = cells.iter().map(|&(s, _)| s).min().unwrap_or(earliest);
        for &(slot, col) in &cells {
            free.give(col as usize, slot);
        }
        let aligned =
            occupancy::aligned_slot(&mut free, inst, needs, ind_end, old_end, &mut cursors);

        let old_key = (old_end, old_end - start);
        let ind_key = (ind_end, ind_end - ind_start);
        let end = match aligned {
            Some(t) if (t, 0) < old_key && (t, 0) <= ind_key => {
                cells.clear();
                occupancy::place_aligned(&mut free, inst, planes, t, &mut cells);
                pos[jobs].copy_from_slice(&cells);
                t
            }
            _ if ind_key < old_key => {
                cells.clear();
                occupancy::place_latest(&mut free, inst, planes, earliest, ind_end, &mut cells);
                pos[jobs].copy_from_slice(&cells);
                ind_end
            }
            _ => {
                for &(slot, col) in &pos[jobs] {
                    free.take(col as usize, slot);
                }
                old_end
            }
        };
        new_end[ro] = end;
    }
    decode::measure(prep, pos)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decode::Placement;
    use crate::synthetic;

    /// The ASAP pass keeps schedules legal and never delays a unit, from both decoders, with
    /// duplicates and with red-black paths.
    #[test]
    fn asap_fill_is_legal_and_never_later() {
        for seed in 0..24 {
            let mut problem = synthetic::living_room(seed, 2 + (seed % 5) as u32, 40);
            for path in problem.paths.iter_mut().skip(seed as usize % 2) {
                path.phases = 2;
            }
            let prep = Prepared::new(&problem).unwrap();
            let mut copies = prep.base_copies();
            copies[0] += (seed % 3) as u32;
            let inst = InstanceSet::from_copies(&copies);
            let mut order: Vec<u32> = (0..problem.paths.len() as u32).collect();
            order.reverse();
            for placement in [Placement::Individual, Placement::Aligned { slack: 3 }] {
                let (before, mut pos) = decode::decode_positions(&prep, &inst, &order, placement);
                let ends_before = round_ends(&prep, &pos);
                let after = asap_fill(&prep, &inst, &mut pos);
                assert_eq!(after, decode::measure(&prep, &pos));
                assert!(after.makespan <= before.makespan);
                let ends_after = round_ends(&prep, &pos);
                assert!(ends_after.iter().zip(&ends_before).all(|(a, b)| a <= b));
                decode::build(&prep, &inst, &pos).check(&problem).unwrap();
            }
        }
    }

    fn round_ends(prep: &Prepared<'_>, pos: &Positions) -> Vec<u32> {
        let mut ends = Vec::new();
        decode::for_each_unit(prep, |_, _, _, jobs| {
            ends.push(pos[jobs].iter().map(|&(s, _)| s).max().unwrap_or(0));
        });
        ends
    }
}
