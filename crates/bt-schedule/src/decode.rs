//! The greedy placer shared by the list scheduler and the GA: paths in a given priority
//! order, their units (phases of rounds, see [`Prepared`]) in order, each job at the earliest
//! free cell it may use.

use crate::occupancy::{self, NONE, NextFree};
use crate::problem::{InstanceSet, Prepared};
use crate::{Job, Schedule};

/// How the jobs of one unit (a phase of a path's round) are put into slots.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Placement {
    /// Every job at its own earliest free cell (the list scheduler).
    Individual,
    /// All jobs of the unit in one slot when that slot is at most `slack` slots after the
    /// earliest end of the unit; otherwise the unit ends at that earliest end with every
    /// job at the latest free cell before it (least spread for that end).
    Aligned { slack: u32 },
}

/// What the GA minimises, compared lexicographically: makespan first, then the latency
/// factor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Default)]
pub(crate) struct Fitness {
    /// Slots.
    pub makespan: u32,
    /// Sum over units (phases of path rounds) of latest minus earliest slot.
    pub latency_factor: u64,
}

/// `(slot, column)` of every job, indexed by job index (see [`Prepared::job_offset`]).
pub(crate) type Positions = Vec<(u32, u32)>;

/// Places all paths in `order` (a permutation of path indices); `sink(job index, slot,
/// column)` receives every placement. O(jobs) near-constant-time "next free" queries.
pub(crate) fn decode<F: FnMut(u32, u32, u32)>(
    prep: &Prepared<'_>,
    inst: &InstanceSet,
    order: &[u32],
    placement: Placement,
    mut sink: F,
) -> Fitness {
    // The busiest plane's jobs per copy: the makespan is rarely much beyond it.
    let hint = prep
        .used_planes
        .iter()
        .map(|&q| prep.load[q as usize].div_ceil(inst.columns(q).len().max(1) as u64))
        .max()
        .unwrap_or(0);
    let hint = u32::try_from(hint + hint / 16).unwrap_or(u32::MAX / 2);
    let mut occ = NextFree::new(inst.len(), hint);
    let (mut out, mut cursors) = (Vec::new(), Vec::new());
    let mut fitness = Fitness::default();
    for &p in order {
        let path = &prep.problem.paths[p as usize];
        let order_len = path.planes.len() as u32;
        let mut earliest = 0u32;
        for r in 0..path.rounds {
            for h in 0..prep.phases(p as usize) {
                out.clear();
                let planes = prep.phase_planes(p as usize, h);
                let needs = prep.needs(p as usize, h);
                place_unit(
                    &mut occ,
                    inst,
                    (planes, needs),
                    earliest,
                    placement,
                    (&mut out, &mut cursors),
                );
                let base = prep.job_offset[p as usize]
                    + r * order_len
                    + prep.phase_ranks(p as usize, h).start as u32;
                let (mut start, mut end) = (u32::MAX, 0);
                for (j, &(slot, col)) in out.iter().enumerate() {
                    sink(base + j as u32, slot, col);
                    start = start.min(slot);
                    end = end.max(slot);
                }
                fitness.latency_factor += u64::from(end - start);
                fitness.makespan = fitness.makespan.max(end + 1);
                earliest = end + 1;
            }
        }
    }
    fitness
}

/// Places the jobs of one unit on `planes` (rank order; `needs` their distinct `(plane,
/// count)`) at or after slot `earliest`, appending `(slot, column)` per job to `out`.
fn place_unit(
    occ: &mut NextFree,
    inst: &InstanceSet,
    (planes, needs): (&[u32], &[(u32, u32)]),
    earliest: u32,
    placement: Placement,
    (out, cursors): (&mut Vec<(u32, u32)>, &mut Vec<u32>),
) {
    match placement {
        Placement::Individual => {
            let placed = occupancy::place_individually(occ, inst, planes, earliest, out);
            debug_assert!(placed, "an unbounded horizon always has a free cell");
        }
        Placement::Aligned { slack } => {
            // Where the unit ends at the earliest, whatever its spread.
            let end = needs
                .iter()
                .map(|&(plane, n)| occupancy::nth_free_cell(occ, inst, plane, earliest, n, cursors))
                .max()
                .unwrap_or(earliest);
            debug_assert_ne!(end, NONE);
            let limit = end.saturating_add(slack);
            match occupancy::aligned_slot(occ, inst, needs, end, limit, cursors) {
                Some(t) => occupancy::place_aligned(occ, inst, planes, t, out),
                None => occupancy::place_latest(occ, inst, planes, earliest, end, out),
            }
        }
    }
}

/// [`decode`] keeping every job's position.
pub(crate) fn decode_positions(
    prep: &Prepared<'_>,
    inst: &InstanceSet,
    order: &[u32],
    placement: Placement,
) -> (Fitness, Positions) {
    let mut pos = vec![(NONE, NONE); prep.total_jobs()];
    let fitness = decode(prep, inst, order, placement, |job, slot, col| {
        pos[job as usize] = (slot, col);
    });
    (fitness, pos)
}

/// Calls `f(path, round, unit index, jobs of that unit)` for every unit (phase of a path
/// round, in order), in path order; the jobs are a range of job indices.
pub(crate) fn for_each_unit<F: FnMut(u32, u32, usize, std::ops::Range<usize>)>(
    prep: &Prepared<'_>,
    mut f: F,
) {
    for (p, path) in prep.problem.paths.iter().enumerate() {
        let k = path.planes.len();
        let base = prep.job_offset[p] as usize;
        let mut unit = prep.unit_offset[p] as usize;
        for r in 0..path.rounds {
            for h in 0..prep.phases(p) {
                let ranks = prep.phase_ranks(p, h);
                let start = base + r as usize * k;
                f(p as u32, r, unit, start + ranks.start..start + ranks.end);
                unit += 1;
            }
        }
    }
}

/// Makespan and latency factor of complete positions.
pub(crate) fn measure(prep: &Prepared<'_>, pos: &Positions) -> Fitness {
    let mut fitness = Fitness::default();
    for_each_unit(prep, |_, _, _, jobs| {
        let slots = pos[jobs].iter().map(|&(s, _)| s);
        let (start, end) = slots.fold((u32::MAX, 0), |(a, b), s| (a.min(s), b.max(s)));
        fitness.latency_factor += u64::from(end - start);
        fitness.makespan = fitness.makespan.max(end + 1);
    });
    fitness
}

/// The slots table of complete positions.
pub(crate) fn build(prep: &Prepared<'_>, inst: &InstanceSet, pos: &Positions) -> Schedule {
    let makespan = measure(prep, pos).makespan as usize;
    let mut slots = vec![vec![None; inst.len()]; makespan];
    for_each_unit(prep, |path, round, _, jobs| {
        let round_base = prep.job_offset[path as usize] as usize
            + round as usize * prep.problem.paths[path as usize].planes.len();
        for j in jobs {
            let (slot, col) = pos[j];
            debug_assert!(slots[slot as usize][col as usize].is_none());
            slots[slot as usize][col as usize] = Some(Job {
                path,
                round,
                point: prep.point_of_rank(path as usize, j - round_base),
            });
        }
    });
    Schedule {
        instances: inst.instances.clone(),
        slots,
    }
}
