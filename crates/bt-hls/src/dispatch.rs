//! Dynamic dispatch: the host loads one round of every path as *groups*
//! ([`bt_schedule::round_template`]) and the accelerator decides at run time which group runs
//! in which slot, so a path that converged or froze frees its PEs at once and no path's
//! round count is needed beforehand (no oracle: the host never runs the model to plan).
//!
//! The controller of `bt_top` keeps a ready queue of groups (`rq`, one entry per path that
//! is not running: `{first group, next group}`). While slot `s` loads and its PEs compute,
//! the dispatcher pops up to [`SCAN_LIMIT`] queued groups and puts each into slot `s + 1` when
//! all its PE columns are still free there (else back to the queue's tail). At write-back
//! the last job of a group queues the path's next group at the queue's *head*, so running
//! paths go before waiting ones (a long chain is not held up behind every queued path); after
//! a round's last group the path is queued again only if it neither converged nor froze and
//! is below the round cap.
//!
//! [`predict`] is the cycle-exact twin of that controller (pinned by co-simulation): it
//! needs each path's rounds, which only the run itself (or the model run *after* it, for
//! verification) knows.

use bt_schedule::Schedule;

use crate::HlsError;

/// Most queued groups the dispatcher examines for one slot: a bound on its time when many
/// queued groups wait for the same busy PE.
/// (Measured on three unseen 29-plane rooms at order 3: 8, 10, 12 and 16 examined groups
/// gave 1,816, 1,724, 1,660 and 1,606 slots on one of them, but 12 and more make the
/// dispatcher outlast the PE latency, so 10 took the fewest cycles.)
pub const SCAN_LIMIT: u32 = 10;

/// One group: the jobs of one phase of one path's round that run together in one slot.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Group {
    /// Path index.
    pub path: u32,
    /// `(column, point)` of each job: the schedule's instance column and the point within
    /// the path, ascending column.
    pub jobs: Vec<(u32, u32)>,
}

/// A template's groups, path by path: `groups[p]` are path `p`'s groups in run order.
pub fn groups(template: &Schedule, paths: usize) -> Result<Vec<Vec<Group>>, HlsError> {
    let mut out: Vec<Vec<Group>> = vec![Vec::new(); paths];
    let mut last_path = None;
    for (t, row) in template.slots.iter().enumerate() {
        let jobs: Vec<(u32, bt_schedule::Job)> = row
            .iter()
            .enumerate()
            .filter_map(|(c, j)| j.map(|j| (c as u32, j)))
            .collect();
        let Some((_, first)) = jobs.first() else {
            return Err(HlsError::Schedule(format!(
                "slot {t} of the round template holds no job"
            )));
        };
        let path = first.path;
        if jobs.iter().any(|(_, j)| j.path != path || j.round != 0) {
            return Err(HlsError::Schedule(format!(
                "slot {t} of the round template mixes paths or rounds: a template slot is one \
                 group of one path's round 0"
            )));
        }
        let Some(list) = out.get_mut(path as usize) else {
            return Err(HlsError::Schedule(format!(
                "slot {t}: path {path} out of range"
            )));
        };
        if last_path != Some(path) && !list.is_empty() {
            return Err(HlsError::Schedule(format!(
                "the groups of path {path} are not consecutive in the round template"
            )));
        }
        last_path = Some(path);
        list.push(Group {
            path,
            jobs: jobs.iter().map(|(c, j)| (*c, j.point)).collect(),
        });
    }
    if let Some(p) = out.iter().position(Vec::is_empty) {
        return Err(HlsError::Schedule(format!(
            "path {p} has no group in the round template"
        )));
    }
    Ok(out)
}

/// Cycles and slots of one dispatched run ([`predict`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct DispatchRun {
    /// Clock cycles from the start command to done (the `CYCLES` register).
    pub cycles: u64,
    /// Slots the controller ran.
    pub slots: u64,
    /// Jobs run (PE evaluations).
    pub jobs: u64,
    /// Cycles the PEs waited for the dispatcher (EXEC longer than the PE latency, and the
    /// dispatches that found no slot running).
    pub dispatch_wait_cycles: u64,
}

/// The dispatcher's choice for one slot and its cycles (`D_WARM`, then per examined group a
/// `D_POP` and one `D_JOB` per job, a last `D_POP` and `D_FIN`).
fn dispatch_slot(
    groups: &[Vec<Group>],
    queue: &mut std::collections::VecDeque<(u32, usize)>,
    columns: usize,
) -> (Vec<(u32, usize)>, u64) {
    let mut used = vec![false; columns];
    let mut placed = Vec::new();
    let mut scan = (queue.len() as u32).min(SCAN_LIMIT);
    // D_WARM: the queue's head is read once before the first pop.
    let mut cycles = 1u64;
    loop {
        cycles += 1;
        if scan == 0 || used.iter().all(|&u| u) {
            break;
        }
        let Some((p, g)) = queue.pop_front() else {
            break;
        };
        scan -= 1;
        let group = &groups[p as usize][g];
        cycles += group.jobs.len() as u64;
        if group.jobs.iter().all(|&(c, _)| !used[c as usize]) {
            for &(c, _) in &group.jobs {
                used[c as usize] = true;
            }
            placed.push((p, g));
        } else {
            queue.push_back((p, g));
        }
    }
    (placed, cycles + 1)
}

/// The `CYCLES` of one run of the dispatching controller whose PEs take `latency` cycles,
/// for a template ([`groups`]) over `columns` PE columns when path `p` runs `rounds[p]`
/// rounds (at least one). Per slot of `n` jobs: load `n + 2`, or `n` right after a
/// write-back (which read its first two entries ahead), PEs `max(latency - n - 1, 1,
/// dispatch + 1 - load)` (each PE starts after its own load, write-back takes its result two
/// cycles after reading its entry; the dispatcher starts with the load), write back `n + 2`; a dispatch with no slot running costs its own cycles plus one.
pub fn predict(groups: &[Vec<Group>], columns: usize, rounds: &[u32], latency: u32) -> DispatchRun {
    let mut queue: std::collections::VecDeque<(u32, usize)> =
        (0..groups.len() as u32).map(|p| (p, 0)).collect();
    let mut done = vec![0u32; groups.len()];
    let mut run = DispatchRun::default();
    let (mut slot, d) = dispatch_slot(groups, &mut queue, columns);
    run.cycles += d + 1;
    run.dispatch_wait_cycles += d + 1;
    let mut ahead = false;
    while !slot.is_empty() {
        let n: u64 = slot
            .iter()
            .map(|&(p, g)| groups[p as usize][g].jobs.len() as u64)
            .sum();
        // The load takes n + 2 cycles, or n when the previous write-back read its first two
        // entries ahead; the dispatcher starts with it, the PEs after it.
        let load = if ahead { n } else { n + 2 };
        let (next, d) = dispatch_slot(groups, &mut queue, columns);
        // Each PE starts the cycle after its own load and write-back reads the jobs in load
        // order, each two cycles after its entry's read, so the last job's PE needs `latency`
        // cycles less the slot's other loads and those two (at least one); the dispatcher
        // must have finished too.
        let lat = u64::from(latency).saturating_sub(n + 1).max(1);
        let exec = lat.max((d + 1).saturating_sub(load));
        run.cycles += load + exec + n + 2;
        run.dispatch_wait_cycles += exec - lat;
        run.slots += 1;
        run.jobs += n;
        // Write-back, job by job in slot order: each group's last job queues its path's next
        // group at the queue's head.
        for &(p, g) in &slot {
            let pi = p as usize;
            if g + 1 < groups[pi].len() {
                queue.push_front((p, g + 1));
            } else {
                done[pi] += 1;
                if done[pi] < rounds.get(pi).copied().unwrap_or(1).max(1) {
                    queue.push_front((p, 0));
                }
            }
        }
        slot = next;
        ahead = true;
        if slot.is_empty() && !queue.is_empty() {
            let (s, d) = dispatch_slot(groups, &mut queue, columns);
            run.cycles += d + 1;
            run.dispatch_wait_cycles += d + 1;
            slot = s;
            ahead = false;
        }
    }
    run
}

#[cfg(test)]
mod tests {
    use super::*;
    use bt_schedule::{PathJob, Problem, round_template};

    fn problem() -> Problem {
        Problem {
            num_planes: 3,
            paths: vec![
                PathJob::jacobi(vec![0, 1], 1),
                PathJob::jacobi(vec![0], 1),
                PathJob::jacobi(vec![2, 0, 2], 1),
            ],
        }
    }

    #[test]
    fn a_template_splits_into_each_paths_groups() {
        let t = round_template(&problem(), &[]).unwrap();
        let g = groups(&t, 3).unwrap();
        assert_eq!(g[0].len(), 1);
        assert_eq!(g[1].len(), 1);
        // Path 2 meets plane 2 twice: two groups.
        assert_eq!(g[2].len(), 2);
        assert_eq!(g[2][0].jobs.len() + g[2][1].jobs.len(), 3);
        assert!(groups(&t, 2).is_err(), "a path beyond the count is refused");
        assert!(groups(&t, 4).is_err(), "a path without a group is refused");
    }

    /// Hand count: paths 0 (planes 0, 1) and 1 (plane 0) share plane 0, so each round of
    /// one waits a slot for the other; the last slots run alone.
    #[test]
    fn the_prediction_counts_every_slot_of_a_hand_example() {
        let p = Problem {
            num_planes: 2,
            paths: vec![PathJob::jacobi(vec![0, 1], 1), PathJob::jacobi(vec![0], 1)],
        };
        let t = round_template(&p, &[]).unwrap();
        let g = groups(&t, 2).unwrap();
        let latency = 10;
        // One round each: slot 1 = path 0 (2 jobs), slot 2 = path 1 (1 job).
        // Dispatch 0: D_WARM, D_POP, 2 jobs [placed: both PEs taken], D_POP (every PE
        // taken: stop), D_FIN = 6 cycles, DISP 7. Slot 1: load 4, PEs max(10 - 2 - 1 (the
        // first PE started a cycle before the last, write-back takes a result two cycles
        // after reading its entry), dispatch of path 1 (D_WARM, D_POP, 1 job, D_POP, D_FIN =
        // 5) + 1 - the load's 4), write back 4 = 15. Slot 2: its entry was read ahead during
        // slot 1's write-back: load 1, PEs 8, write back 3 = 12 (the queue is empty: D_WARM,
        // D_POP, D_FIN).
        let r = predict(&g, 2, &[1, 1], latency);
        assert_eq!((r.slots, r.jobs), (2, 3));
        assert_eq!(r.cycles, 7 + 15 + 12);
        assert_eq!(r.dispatch_wait_cycles, 7);
        // More rounds: more slots, never fewer cycles.
        let r3 = predict(&g, 2, &[3, 2], latency);
        assert_eq!(r3.jobs, 3 * 2 + 2);
        assert!(r3.cycles > r.cycles);
    }
}
