//! The baseline list scheduler.

use crate::decode::{self, Placement};
use crate::error::ScheduleError;
use crate::problem::{InstanceSet, Prepared};
use crate::{Budget, Problem, Schedule};

/// Baseline list scheduler: paths in index order, rounds in Jacobi order, every job at the
/// earliest slot at or after the end of the path's previous round where a PE of its plane is
/// free (holes left by earlier paths are filled). One PE per used plane, no duplicate, no
/// attempt to align a round's jobs in one slot.
///
/// `budget` is only checked (it must cover one PE per used plane). Runs in O(jobs).
pub fn schedule_list(problem: &Problem, budget: &Budget) -> Result<Schedule, ScheduleError> {
    let prep = Prepared::new(problem)?;
    prep.check_budget(budget)?;
    let inst = InstanceSet::from_copies(&prep.base_copies());
    let order: Vec<u32> = (0..problem.paths.len() as u32).collect();
    let (_, pos) = decode::decode_positions(&prep, &inst, &order, Placement::Individual);
    Ok(decode::build(&prep, &inst, &pos))
}

/// PE copies per plane for `problem` within `budget`: one per used plane, then one more at a
/// time for the plane with the largest load per copy (load = the jobs of the plane, i.e. the
/// sum over paths of its occurrences × rounds; ties to the lower plane). The busiest plane's
/// load per copy bounds the makespan from below, so this is the greedy way to lower it.
pub fn size_copies(problem: &Problem, budget: &Budget) -> Result<Vec<u32>, ScheduleError> {
    let prep = Prepared::new(problem)?;
    prep.check_budget(budget)?;
    Ok(grow_by_load(problem, prep.base_copies(), budget))
}

/// `copies` grown one at a time, within `budget`, for the plane with the largest load per copy
/// (the rule of [`size_copies`]).
pub(crate) fn grow_by_load(problem: &Problem, mut copies: Vec<u32>, budget: &Budget) -> Vec<u32> {
    let mut load = vec![0u64; copies.len()];
    for path in &problem.paths {
        for &plane in &path.planes {
            load[plane as usize] += u64::from(path.rounds);
        }
    }
    let mut total: u32 = copies.iter().sum();
    while total < budget.max_instances {
        // Largest load / copies, compared exactly as load_a * copies_b > load_b * copies_a.
        let busiest = (0..copies.len()).filter(|&p| copies[p] > 0).reduce(|a, b| {
            let (la, lb) = (u128::from(load[a]), u128::from(load[b]));
            if lb * u128::from(copies[a]) > la * u128::from(copies[b]) {
                b
            } else {
                a
            }
        });
        let Some(p) = busiest else { break };
        if load[p] <= u64::from(copies[p]) {
            break; // one job per copy already
        }
        copies[p] += 1;
        total += 1;
    }
    copies
}

/// The list scheduler on duplicated PEs: copies per plane from [`size_copies`] within
/// `budget`, paths longest first (jobs = order × rounds, ties by index), every job at the
/// earliest free copy of its plane at or after the end of its path's previous round.
/// Runs in O(jobs · copies).
pub fn schedule_list_duplicated(
    problem: &Problem,
    budget: &Budget,
) -> Result<Schedule, ScheduleError> {
    schedule_list_on(problem, &size_copies(problem, budget)?)
}

/// [`schedule_list_duplicated`] on a platform sized beforehand: `copies[p]` PEs of plane `p`
/// (raised to one for every plane the problem uses), e.g. the copies a platform was sized with
/// once for all its time steps.
pub fn schedule_list_on(problem: &Problem, copies: &[u32]) -> Result<Schedule, ScheduleError> {
    let prep = Prepared::new(problem)?;
    let inst = InstanceSet::from_copies(&prep.copies_at_least(copies));
    let mut order: Vec<u32> = (0..problem.paths.len() as u32).collect();
    let jobs = |p: u32| {
        let path = &problem.paths[p as usize];
        u64::from(path.rounds) * path.planes.len() as u64
    };
    order.sort_by_key(|&p| (std::cmp::Reverse(jobs(p)), p));
    let (_, pos) = decode::decode_positions(&prep, &inst, &order, Placement::Individual);
    Ok(decode::build(&prep, &inst, &pos))
}
