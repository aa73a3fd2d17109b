//! Dynamic dispatch: the host loads one round of every path as *groups*
//! ([`bt_schedule::round_template`]) and the accelerator decides at run time which group runs
//! in which slot, so a path that converged or froze frees its PEs at once and no path's
//! round count is needed beforehand (no oracle: the host never runs the model to plan).
//!
//! The controller of `bt_top` keeps a ready queue of groups (`rq`, one entry per path that
//! is not running: `{first group, next group}`). While slot `s` computes (from the end of
//! slot `s − 1`'s write-back, which its load overlaps), the dispatcher pops up to
//! [`SCAN_LIMIT`] queued groups and puts each into slot `s + 1` when all its PE columns are
//! still free there (else back to the queue's tail). At write-back
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
/// dispatcher outlast the PE latency, so 10 took the fewest cycles. Measured again with the
/// write-back/load overlap and the pop at a group's last job: 8, 9 and 12 gave 50,480,
/// 47,241 and 48,974 cycles on seed 13 against 46,247 at 10; docs/hardware.md.)
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
    /// Cycles slots' loads waited for the write-back of a shared PE column in the slot
    /// before (the sum of the slots' load delays).
    #[serde(default)]
    pub load_delay_cycles: u64,
}

/// One dispatched slot: its groups in slot order, and the cycles the load waits after the
/// previous slot's write-back starts (`delay`).
#[derive(Debug, Clone, Default)]
struct Slot {
    groups: Vec<(u32, usize)>,
    /// Jobs in the slot.
    jobs: u64,
    /// `max(0, max over the PE columns both slots use of (position in the front slot −
    /// position in this one))`: the load of a column may not overtake the write-back of the
    /// front slot's job on that column, which reads its PE's result.
    delay: u64,
}

/// The PE column of every job of `slot`, in slot (load and write-back) order.
fn slot_columns<'a>(
    groups: &'a [Vec<Group>],
    slot: &'a [(u32, usize)],
) -> impl Iterator<Item = u32> + 'a {
    slot.iter()
        .flat_map(|&(p, g)| groups[p as usize][g].jobs.iter().map(|&(c, _)| c))
}

/// The dispatcher's choice for one slot and its cycles (`D_WARM`, a `D_POP` for the first
/// examined group, one `D_JOB` per job of each examined group, whose last also pops the next
/// group, and `D_FIN`); `front` is the slot running (loading or computing) while it
/// dispatches, whose write-back the new slot's load overlaps.
fn dispatch_slot(
    groups: &[Vec<Group>],
    queue: &mut std::collections::VecDeque<(u32, usize)>,
    columns: usize,
    front: Option<&Slot>,
) -> (Slot, u64) {
    let mut used = vec![false; columns];
    let mut placed = Vec::new();
    let mut scan = (queue.len() as u32).min(SCAN_LIMIT);
    // D_WARM (the queue's head is read once before the first pop), the first D_POP, D_FIN.
    let mut cycles = 3u64;
    while scan > 0 && !used.iter().all(|&u| u) {
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
    let mut front_pos = vec![None; columns];
    if let Some(f) = front {
        for (i, c) in slot_columns(groups, &f.groups).enumerate() {
            front_pos[c as usize] = Some(i as u64);
        }
    }
    let mut slot = Slot::default();
    for (i, c) in slot_columns(groups, &placed).enumerate() {
        if let Some(fi) = front_pos[c as usize] {
            slot.delay = slot.delay.max(fi.saturating_sub(i as u64));
        }
        slot.jobs += 1;
    }
    slot.groups = placed;
    (slot, cycles)
}

/// Write-back of `slot`, job by job in slot order: each group's last job queues its path's
/// next group at the queue's head, or its first group again while the path runs rounds.
fn write_back(
    groups: &[Vec<Group>],
    slot: &Slot,
    rounds: &[u32],
    done: &mut [u32],
    queue: &mut std::collections::VecDeque<(u32, usize)>,
) {
    for &(p, g) in &slot.groups {
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
}

/// The `CYCLES` of one run of the dispatching controller whose PEs take `latency` cycles,
/// for a template ([`groups`]) over `columns` PE columns when path `p` runs `rounds[p]`
/// rounds (at least one). Cycle 0 is the first after the start command.
///
/// A slot of `n` jobs whose load enters at cycle `L` loads its first job at `P = L + delay +
/// 2` (the slot buffer's and the point memory's registered reads) and its last at `P + n −
/// 1`; each PE starts the cycle after its own load. Its write-back starts at `W = max(P +
/// max(latency − 1, n + 1), previous write-back's last cycle + 2, dispatcher's last cycle +
/// 2)` (its EXEC ends in a cycle with neither running), reads an
/// entry a cycle and takes job `i`'s result at `W + i + 2` (`n + 2` cycles). The next slot's
/// load enters at `W` (it overlaps the write-back: its own slot-buffer port, and a third
/// point-memory copy for the written points' old values), the dispatcher of the slot after it
/// starts when this write-back ends (so it sees the paths it queued). A slot dispatched with
/// no slot running waits for that dispatch: its load enters `d + 1` cycles after it began.
pub fn predict(groups: &[Vec<Group>], columns: usize, rounds: &[u32], latency: u32) -> DispatchRun {
    let mut queue: std::collections::VecDeque<(u32, usize)> =
        (0..groups.len() as u32).map(|p| (p, 0)).collect();
    let mut done = vec![0u32; groups.len()];
    let mut run = DispatchRun::default();
    let lat = u64::from(latency);
    let (mut slot, d) = dispatch_slot(groups, &mut queue, columns, None);
    run.dispatch_wait_cycles += d + 1;
    // The load of `slot` enters at `enter`; the dispatcher of the next ends at `d_end` (its
    // last cycle); the previous write-back's last cycle is `wb_last`.
    let mut enter = d + 1;
    let mut wb_last = None::<u64>;
    let (mut next, d) = dispatch_slot(groups, &mut queue, columns, Some(&slot));
    let mut d_end = enter + d - 1;
    while slot.jobs > 0 {
        let n = slot.jobs;
        let first_load = enter + slot.delay + 2;
        let pe_ready = first_load + (lat - 1).max(n + 1);
        // Ready but for the dispatcher: the PEs done and the previous write-back over.
        let ready = pe_ready.max(wb_last.map_or(0, |w| w + 2));
        let wb = ready.max(d_end + 2);
        run.dispatch_wait_cycles += wb - ready;
        run.slots += 1;
        run.jobs += n;
        run.load_delay_cycles += slot.delay;
        write_back(groups, &slot, rounds, &mut done, &mut queue);
        let last = wb + n + 1;
        wb_last = Some(last);
        if next.jobs > 0 {
            enter = wb;
            slot = next;
            let (nn, d) = dispatch_slot(groups, &mut queue, columns, Some(&slot));
            d_end = last + d;
            next = nn;
        } else if queue.is_empty() {
            run.cycles = last + 1;
            break;
        } else {
            // No slot running: dispatch now (DISP), then load it.
            let (s, d) = dispatch_slot(groups, &mut queue, columns, None);
            run.dispatch_wait_cycles += d + 1;
            enter = last + d + 2;
            slot = s;
            let (nn, d) = dispatch_slot(groups, &mut queue, columns, Some(&slot));
            d_end = enter + d - 1;
            next = nn;
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
        // Dispatch 0 (cycles 0-4): D_WARM, D_POP, 2 jobs [both PEs taken: stop], D_FIN;
        // DISP ends at cycle 5, slot 1's load enters at 6. Its first job loads at 8 (two
        // registered reads), the last at 9; write-back starts at max(8 + 9, the dispatch of
        // path 1 [cycles 6-9: D_WARM, D_POP, 1 job, D_FIN] + 2) = 17 and ends at 20. Slot 2
        // shares column 0 at the same position (no delay): its load enters at 17, loads at
        // 19, writes back from max(19 + 9, 20 + 2, the empty dispatch at 21-23 + 2) = 28 to
        // 30: 31 cycles.
        let r = predict(&g, 2, &[1, 1], latency);
        assert_eq!((r.slots, r.jobs), (2, 3));
        assert_eq!(r.cycles, 31);
        assert_eq!(r.dispatch_wait_cycles, 6);
        // Slot 2's column 0 is at position 0 in slot 1 too; put path 1 on plane 1 behind
        // path 0's job on it (position 1) and its load waits a cycle for that write-back.
        let p2 = Problem {
            num_planes: 2,
            paths: vec![PathJob::jacobi(vec![0, 1], 1), PathJob::jacobi(vec![1], 1)],
        };
        let g2 = groups(&round_template(&p2, &[]).unwrap(), 2).unwrap();
        assert_eq!(predict(&g2, 2, &[1, 1], latency).cycles, 32);
        // More rounds: more slots, never fewer cycles.
        let r3 = predict(&g, 2, &[3, 2], latency);
        assert_eq!(r3.jobs, 3 * 2 + 2);
        assert!(r3.cycles > r.cycles);
    }
}
