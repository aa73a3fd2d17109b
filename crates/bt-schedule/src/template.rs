//! The one-round template of dynamic dispatch: what the host loads when the accelerator
//! decides at run time which path runs next (`bt-hls`, `docs/hardware.md`).

use crate::error::ScheduleError;
use crate::problem::{InstanceSet, Prepared};
use crate::{Job, PeInstance, Problem, Schedule};

/// One round of every path of `problem` as *groups*, one group per slot: a group is jobs of
/// one phase of one path on distinct PE instances, so the accelerator can run a whole group
/// in one slot whenever its PEs are free. Paths in index order, each path's phases in order,
/// a phase's points in ascending order; a point joins the current group while the group has
/// a free copy of its plane (copy 0 first), else it opens the next group. `copies[p]` PEs of
/// plane `p`, raised to one for every plane the problem uses (as [`crate::schedule_list_on`]).
///
/// The problem's `rounds` are not read: the template holds round 0 of every path (it is
/// legal for [`Problem::one_round`]), and the hardware repeats a path's groups until the
/// path converges, freezes or reaches its round cap. No model run is needed to build it.
pub fn round_template(problem: &Problem, copies: &[u32]) -> Result<Schedule, ScheduleError> {
    let one = problem.one_round();
    let prep = Prepared::new(&one)?;
    let inst = InstanceSet::from_copies(&prep.copies_at_least(copies));
    let slots = groups_on(&one, &prep, inst.len(), |plane| inst.columns(plane));
    Ok(Schedule {
        instances: inst.instances,
        slots,
    })
}

/// One round of every path of `problem` as groups (as [`round_template`]) on `pes` *generic*
/// PEs ([`PeInstance::generic`]), each of which takes any plane's job: a phase's points fill
/// a group on distinct PEs, the free PE with the fewest jobs so far first (ties to the lower
/// column), and a phase of more than `pes` points continues in the next group. The PE count
/// then follows the work, not the planes. Refused: `pes` = 0.
pub fn generic_round_template(problem: &Problem, pes: u32) -> Result<Schedule, ScheduleError> {
    if pes == 0 {
        return Err(ScheduleError::NoGenericPe);
    }
    let one = problem.one_round();
    let prep = Prepared::new(&one)?;
    let slots = groups_on(&one, &prep, pes as usize, |_| 0..pes as usize);
    Ok(Schedule {
        instances: (0..pes).map(PeInstance::generic).collect(),
        slots,
    })
}

/// The groups of one round of `one` on `width` columns, `columns(plane)` those that take a
/// plane's job: paths in index order, each path's phases in order, a phase's points in
/// ascending order; a point joins the current group while it has a free column for the
/// point's plane, else it opens the next group.
fn groups_on(
    one: &Problem,
    prep: &Prepared<'_>,
    width: usize,
    columns: impl Fn(u32) -> std::ops::Range<usize>,
) -> Vec<Vec<Option<Job>>> {
    let mut slots = Vec::new();
    // Jobs given to each column so far: a point takes a free column with the fewest, so the
    // copies share the paths (a fixed copy 0 first would leave them to A-B-A paths).
    let mut given = vec![0u64; width];
    for (p, path) in one.paths.iter().enumerate() {
        let phases = prep.phases(p);
        for phase in 0..phases {
            let mut row: Vec<Option<Job>> = vec![None; width];
            for point in (phase..path.planes.len() as u32).step_by(phases as usize) {
                let plane = path.planes[point as usize];
                let least = |row: &[Option<Job>]| {
                    columns(plane)
                        .filter(|&c| row[c].is_none())
                        .min_by_key(|&c| (given[c], c))
                };
                let column = match least(&row) {
                    Some(c) => c,
                    None => {
                        slots.push(std::mem::replace(&mut row, vec![None; width]));
                        least(&row).unwrap_or(columns(plane).start)
                    }
                };
                given[column] += 1;
                row[column] = Some(Job {
                    path: p as u32,
                    round: 0,
                    point,
                });
            }
            slots.push(row);
        }
    }
    slots
}

/// PE copies per plane for dynamic dispatch within `budget`, from one round of `problem`
/// (its `rounds` are not read: no model run). One per used plane; then one more at a time for
/// the plane whose next copy saves the most *groups* of a round (a plane met `n` times in one
/// phase of a path splits that phase into `n` groups, and each group is a link of the path's
/// chain of slots; ties to the lower plane); once no copy saves a group, for the plane with the
/// largest one-round load per copy (the rule of [`crate::size_copies`]).
pub fn dispatch_copies(
    problem: &Problem,
    budget: &crate::Budget,
) -> Result<Vec<u32>, ScheduleError> {
    let one = problem.one_round();
    let prep = Prepared::new(&one)?;
    prep.check_budget(budget)?;
    let mut copies = prep.base_copies();
    // Per plane: how often each path meets it in one phase, where more than once.
    let mut repeats: Vec<Vec<u32>> = vec![Vec::new(); copies.len()];
    for (p, path) in one.paths.iter().enumerate() {
        let phases = prep.phases(p);
        for phase in 0..phases {
            let mut count = std::collections::BTreeMap::new();
            for point in (phase..path.planes.len() as u32).step_by(phases as usize) {
                *count.entry(path.planes[point as usize]).or_insert(0u32) += 1;
            }
            for (plane, n) in count.into_iter().filter(|&(_, n)| n > 1) {
                repeats[plane as usize].push(n);
            }
        }
    }
    let mut total: u32 = copies.iter().sum();
    while total < budget.max_instances {
        let saved = |pl: usize| repeats[pl].iter().filter(|&&n| n > copies[pl]).count();
        let best = (0..copies.len()).max_by_key(|&pl| (saved(pl), std::cmp::Reverse(pl)));
        match best {
            Some(pl) if saved(pl) > 0 => {
                copies[pl] += 1;
                total += 1;
            }
            _ => break,
        }
    }
    Ok(crate::list::grow_by_load(&one, copies, budget))
}

impl Problem {
    /// The same paths with one round each: the problem a [`round_template`] is legal for.
    pub fn one_round(&self) -> Problem {
        Problem {
            num_planes: self.num_planes,
            paths: self
                .paths
                .iter()
                .map(|p| crate::PathJob {
                    rounds: 1,
                    ..p.clone()
                })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Budget, PathJob};

    fn one_point(plane: u32) -> PathJob {
        PathJob {
            planes: vec![plane],
            rounds: 1,
            phases: 1,
        }
    }

    #[test]
    fn copies_share_the_paths_of_their_plane() {
        // Two one-point paths on plane 0, two copies: each path gets its own copy, so both
        // can run in one slot (a fixed copy 0 first served only paths meeting a plane twice).
        let p = Problem {
            num_planes: 1,
            paths: vec![one_point(0), one_point(0), one_point(0)],
        };
        let t = round_template(&p, &[2]).unwrap();
        t.check(&p.one_round()).unwrap();
        let column = |slot: usize| t.slots[slot].iter().position(Option::is_some).unwrap();
        assert_ne!(column(0), column(1));
        // The third goes to the copy with fewer jobs so far; both have one: the lower.
        assert_eq!(column(2), column(0));
    }

    #[test]
    fn dispatch_copies_go_first_to_a_plane_met_twice_in_a_phase() {
        // Path 0 meets plane 0 at points 0 and 2, both in red-black's phase 0: its round is
        // three groups on one PE of plane 0, two with a copy. Plane 1 carries more jobs.
        let p = Problem {
            num_planes: 2,
            paths: vec![
                PathJob {
                    planes: vec![0, 1, 0],
                    rounds: 40,
                    phases: 2,
                },
                one_point(1),
                one_point(1),
            ],
        };
        let three = dispatch_copies(&p, &Budget { max_instances: 3 }).unwrap();
        assert_eq!(three, vec![2, 1]);
        let groups = |c: &[u32]| round_template(&p, c).unwrap().slots.len();
        assert_eq!((groups(&[1, 1]), groups(&three)), (5, 4));
        // No copy saves another group: the one-round load decides (plane 1: 3 jobs, plane 0:
        // 2 on two copies); the rounds (40) are not read.
        let four = dispatch_copies(&p, &Budget { max_instances: 4 }).unwrap();
        assert_eq!(four, vec![2, 2]);
        assert!(dispatch_copies(&p, &Budget { max_instances: 1 }).is_err());
    }

    fn problem(phases: u32) -> Problem {
        Problem {
            num_planes: 4,
            paths: vec![
                PathJob {
                    planes: vec![0, 1, 0],
                    rounds: 7,
                    phases,
                },
                PathJob {
                    planes: vec![2, 3],
                    rounds: 30,
                    phases,
                },
                PathJob {
                    planes: vec![3],
                    rounds: 1,
                    phases,
                },
            ],
        }
    }

    /// `(point, plane, copy)` of each job of a group.
    type GroupJobs = Vec<(u32, u32, u32)>;

    /// Groups of each path as (point, plane, copy) lists, slot by slot.
    fn groups(s: &Schedule) -> Vec<(u32, GroupJobs)> {
        s.slots
            .iter()
            .map(|row| {
                let jobs: GroupJobs = row
                    .iter()
                    .enumerate()
                    .filter_map(|(c, j)| {
                        j.map(|j| (j.point, s.instances[c].plane, s.instances[c].copy))
                    })
                    .collect();
                let path = row.iter().flatten().next().map_or(u32::MAX, |j| j.path);
                (path, jobs)
            })
            .collect()
    }

    #[test]
    fn a_repeated_plane_splits_a_phase_unless_it_has_a_copy() {
        for phases in [1, 2] {
            let p = problem(phases);
            let s = round_template(&p, &[]).unwrap();
            s.check(&p.one_round()).unwrap();
            let g = groups(&s);
            // Path 0 (planes 0, 1, 0): Jacobi puts points 0 and 1 together and point 2 (plane
            // 0 again) in a second group; red-black runs {0} then {2} (phase 0 holds both
            // plane-0 points) and {1}.
            let path0: Vec<Vec<u32>> = g
                .iter()
                .filter(|(p, _)| *p == 0)
                .map(|(_, j)| j.iter().map(|x| x.0).collect())
                .collect();
            let expected = if phases == 1 {
                vec![vec![0, 1], vec![2]]
            } else {
                vec![vec![0], vec![2], vec![1]]
            };
            assert_eq!(path0, expected, "phases {phases}");
            // The rounds of the problem are never read: every job is round 0.
            assert_eq!(s.job_count(), 6);
            let with_copy = round_template(&p, &[2]).unwrap();
            with_copy.check(&p.one_round()).unwrap();
            let first = &groups(&with_copy)[0].1;
            assert!(first.contains(&(0, 0, 0)), "{first:?}");
            if phases == 1 {
                assert!(
                    first.contains(&(2, 0, 1)),
                    "the copy takes point 2: {first:?}"
                );
            }
        }
    }

    #[test]
    fn invalid_problems_are_refused() {
        let mut p = problem(1);
        p.paths[0].planes[0] = 9;
        assert!(round_template(&p, &[]).is_err());
    }

    #[test]
    fn generic_pes_take_any_plane_and_split_only_long_phases() {
        for seed in 0..20 {
            let mut p = crate::synthetic::living_room(seed, 12, 40);
            for (i, path) in p.paths.iter_mut().enumerate() {
                path.phases = 1 + (i as u32 % 2);
            }
            for g in [1u32, 2, 3, 5, 12] {
                let s = generic_round_template(&p, g).unwrap();
                let one = p.one_round();
                s.check(&one).unwrap();
                let jobs: u64 = one.paths.iter().map(|q| q.planes.len() as u64).sum();
                assert!(s.instances.iter().all(|i| i.is_generic()));
                assert_eq!(s.job_count(), jobs);
                // A group is one phase of one path; a phase splits only when it has more
                // points than PEs, so its groups are ceil(points / g).
                let want: u32 = one
                    .paths
                    .iter()
                    .map(|path| {
                        let n = path.planes.len() as u32;
                        let h = path.phases.clamp(1, n);
                        (0..h).map(|k| (n - k).div_ceil(h).div_ceil(g)).sum::<u32>()
                    })
                    .sum();
                assert_eq!(s.makespan(), want, "seed {seed}, {g} PEs");
                // The least-loaded rule gives every PE work when there is enough.
                let mut load = vec![0u64; g as usize];
                for row in &s.slots {
                    for (c, j) in row.iter().enumerate() {
                        load[c] += u64::from(j.is_some());
                    }
                }
                if jobs >= u64::from(g) {
                    assert!(
                        load.iter().all(|&l| l > 0),
                        "seed {seed}, {g} PEs: {load:?}"
                    );
                }
            }
        }
        assert!(generic_round_template(&crate::synthetic::living_room(0, 4, 4), 0).is_err());
    }
}
