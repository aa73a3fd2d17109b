//! The one-round template of dynamic dispatch: what the host loads when the accelerator
//! decides at run time which path runs next (`bt-hls`, `docs/hardware.md`).

use crate::error::ScheduleError;
use crate::problem::{InstanceSet, Prepared};
use crate::{Job, Problem, Schedule};

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
    let mut slots = Vec::new();
    for (p, path) in one.paths.iter().enumerate() {
        let phases = prep.phases(p);
        for phase in 0..phases {
            let mut row: Vec<Option<Job>> = vec![None; inst.len()];
            for point in (phase..path.planes.len() as u32).step_by(phases as usize) {
                let plane = path.planes[point as usize];
                let free = |row: &[Option<Job>]| inst.columns(plane).find(|&c| row[c].is_none());
                let column = match free(&row) {
                    Some(c) => c,
                    None => {
                        slots.push(std::mem::replace(&mut row, vec![None; inst.len()]));
                        inst.columns(plane).start
                    }
                };
                row[column] = Some(Job {
                    path: p as u32,
                    round: 0,
                    point,
                });
            }
            slots.push(row);
        }
    }
    Ok(Schedule {
        instances: inst.instances,
        slots,
    })
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
    use crate::PathJob;

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
}
