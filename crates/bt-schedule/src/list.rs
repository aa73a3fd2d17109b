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
