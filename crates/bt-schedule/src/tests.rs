//! Hand problems with known optimal makespan.

use crate::error::{ProblemIssue, ScheduleError, ScheduleViolation};
use crate::{
    Budget, GaParams, Job, PathJob, PeInstance, Problem, Schedule, schedule_ga, schedule_list,
};

fn problem(num_planes: u32, paths: Vec<PathJob>) -> Problem {
    Problem { num_planes, paths }
}

fn path(planes: &[u32], rounds: u32) -> PathJob {
    PathJob::jacobi(planes.to_vec(), rounds)
}

fn small_ga() -> GaParams {
    GaParams {
        population: 6,
        generations: 4,
        ..GaParams::default()
    }
}

/// The list and GA schedules of `problem` within `budget`, both checked legal.
fn list_and_ga(problem: &Problem, budget: &Budget) -> [Schedule; 2] {
    let schedules = [
        schedule_list(problem, budget).unwrap(),
        schedule_ga(problem, budget, &small_ga()).unwrap(),
    ];
    for schedule in &schedules {
        schedule.check(problem).unwrap();
    }
    schedules
}

/// The list and GA schedules of `problem` with one PE per plane (both checked legal), each
/// asserted to have the `expected` (makespan, latency factor, makespan lower bound).
fn originals_only_list_and_ga(problem: &Problem, expected: (u32, u64, u32)) -> [Schedule; 2] {
    let schedules = list_and_ga(problem, &Budget::originals_only(problem));
    for schedule in &schedules {
        let stats = schedule.stats(problem);
        let measured = (
            stats.makespan,
            stats.latency_factor,
            stats.makespan_lower_bound,
        );
        assert_eq!(measured, expected, "{stats:?}");
    }
    schedules
}

/// The violation of phase `phase` of round `round` of `path` starting in slot `start`, not
/// after the phase before it (ending in `previous_end`).
fn dependency(
    path: u32,
    round: u32,
    phase: u32,
    start: u32,
    previous_end: u32,
) -> ScheduleViolation {
    ScheduleViolation::Dependency {
        path,
        round,
        phase,
        start,
        previous_end,
    }
}

fn job(path: u32, round: u32, point: u32) -> Job {
    Job { path, round, point }
}

#[test]
fn disjoint_paths_run_in_parallel() {
    let problem = problem(4, vec![path(&[0, 1], 3), path(&[2, 3], 3)]);
    assert_eq!(Budget::originals_only(&problem).max_instances, 4);
    for schedule in originals_only_list_and_ga(&problem, (3, 0, 3)) {
        let stats = schedule.stats(&problem);
        assert_eq!((stats.instances, stats.duplicates, stats.jobs), (4, 0, 12));
        assert_eq!(stats.utilisation, 1.0);
    }
}

#[test]
fn a_b_a_needs_two_slots_per_round_without_duplicate() {
    let problem = problem(2, vec![path(&[0, 1, 0], 3)]);
    originals_only_list_and_ga(&problem, (6, 3, 6));
}

#[test]
fn a_b_a_takes_one_slot_per_round_with_a_duplicate_of_a() {
    let problem = problem(2, vec![path(&[0, 1, 0], 3)]);
    let schedule = schedule_ga(&problem, &Budget { max_instances: 3 }, &small_ga()).unwrap();
    schedule.check(&problem).unwrap();
    let stats = schedule.stats(&problem);
    assert_eq!(stats.makespan, 3);
    assert_eq!(stats.latency_factor, 0);
    assert_eq!(stats.duplicates, 1);
    assert_eq!(
        schedule.instances,
        vec![
            PeInstance { plane: 0, copy: 0 },
            PeInstance { plane: 0, copy: 1 },
            PeInstance { plane: 1, copy: 0 },
        ]
    );
    // A larger budget changes nothing: duplicates that do not help are not kept.
    let more = schedule_ga(&problem, &Budget { max_instances: 9 }, &small_ga()).unwrap();
    assert_eq!(more, schedule);
}

#[test]
fn shared_plane_is_the_bottleneck_and_a_duplicate_halves_it() {
    // Plane 0 carries 2 x 4 jobs; plane 1 and 2 four each.
    let problem = problem(3, vec![path(&[0, 1], 4), path(&[0, 2], 4)]);
    let list = schedule_list(&problem, &Budget::originals_only(&problem)).unwrap();
    list.check(&problem).unwrap();
    assert_eq!(list.stats(&problem).makespan, 8);
    let ga = schedule_ga(&problem, &Budget::originals_only(&problem), &small_ga()).unwrap();
    ga.check(&problem).unwrap();
    assert_eq!(ga.stats(&problem).makespan, 8);
    assert_eq!(ga.stats(&problem).latency_factor, 0);
    let dup = schedule_ga(&problem, &Budget { max_instances: 4 }, &small_ga()).unwrap();
    dup.check(&problem).unwrap();
    let stats = dup.stats(&problem);
    assert_eq!(
        (stats.makespan, stats.latency_factor, stats.duplicates),
        (4, 0, 1)
    );
}

#[test]
fn ga_aligns_rounds_where_the_list_scheduler_spreads_them() {
    // List order puts path 0 on plane 0 first, so path 1's plane-0 job of each round lags
    // behind its plane-1 job; the GA finds an order with the same makespan and less spread.
    let problem = problem(3, vec![path(&[0], 4), path(&[1, 0], 4), path(&[2], 8)]);
    let budget = Budget::originals_only(&problem);
    let list = schedule_list(&problem, &budget).unwrap();
    let ga = schedule_ga(&problem, &budget, &small_ga()).unwrap();
    list.check(&problem).unwrap();
    ga.check(&problem).unwrap();
    let (l, g) = (list.stats(&problem), ga.stats(&problem));
    assert!(l.latency_factor > 0);
    assert_eq!(g.makespan, 8);
    assert!(g.makespan <= l.makespan);
    assert!(g.latency_factor < l.latency_factor, "{g:?} vs {l:?}");
}

#[test]
fn empty_problem_gives_empty_schedule() {
    let problem = problem(5, vec![]);
    let budget = Budget::originals_only(&problem);
    assert_eq!(budget.max_instances, 0);
    for schedule in [
        schedule_list(&problem, &budget).unwrap(),
        schedule_ga(&problem, &budget, &GaParams::default()).unwrap(),
    ] {
        schedule.check(&problem).unwrap();
        assert!(schedule.instances.is_empty() && schedule.slots.is_empty());
        let stats = schedule.stats(&problem);
        assert_eq!((stats.makespan, stats.jobs), (0, 0));
        assert_eq!(stats.utilisation, 0.0);
    }
}

#[test]
fn validate_reports_every_issue_at_once() {
    let problem = problem(
        2,
        vec![
            path(&[], 3),
            path(&[0, 5], 2),
            path(&[1, 1], 0),
            path(&[0, 1, 0], 1),
        ],
    );
    let Err(ScheduleError::InvalidProblem(report)) = problem.validate() else {
        panic!("problem should be invalid");
    };
    assert_eq!(report.count, 4);
    assert_eq!(
        report.items,
        vec![
            ProblemIssue::EmptyPath { path: 0 },
            ProblemIssue::PlaneOutOfRange {
                path: 1,
                point: 1,
                plane: 5,
                num_planes: 2
            },
            ProblemIssue::ZeroRounds { path: 2 },
            ProblemIssue::RepeatedPlane {
                path: 2,
                point: 1,
                plane: 1
            },
        ]
    );
    let message = ScheduleError::InvalidProblem(report).to_string();
    assert!(
        message.contains("path 1 point 1 lies on plane 5"),
        "{message}"
    );
    assert!(schedule_list(&problem, &Budget { max_instances: 9 }).is_err());
}

#[test]
fn budget_and_parameters_are_checked() {
    let problem = problem(3, vec![path(&[0, 2], 1)]);
    assert_eq!(
        schedule_list(&problem, &Budget { max_instances: 1 }),
        Err(ScheduleError::BudgetTooSmall {
            max_instances: 1,
            needed: 2
        })
    );
    let budget = Budget { max_instances: 2 };
    for params in [
        GaParams {
            population: 0,
            ..GaParams::default()
        },
        GaParams {
            mutation_rate: f64::NAN,
            ..GaParams::default()
        },
        GaParams {
            elite: 20,
            ..GaParams::default()
        },
    ] {
        assert!(matches!(
            schedule_ga(&problem, &budget, &params),
            Err(ScheduleError::InvalidGaParams { .. })
        ));
    }
}

/// Path 0 = [0, 1] x 2 rounds, path 1 = [1] x 1 round, on instances (0,0), (1,0).
fn tiny() -> (Problem, Schedule) {
    let problem = problem(2, vec![path(&[0, 1], 2), path(&[1], 1)]);
    let schedule = Schedule {
        instances: vec![
            PeInstance { plane: 0, copy: 0 },
            PeInstance { plane: 1, copy: 0 },
        ],
        slots: vec![
            vec![Some(job(0, 0, 0)), Some(job(0, 0, 1))],
            vec![None, Some(job(1, 0, 0))],
            vec![Some(job(0, 1, 0)), Some(job(0, 1, 1))],
        ],
    };
    (problem, schedule)
}

fn violations(problem: &Problem, schedule: &Schedule) -> Vec<ScheduleViolation> {
    match schedule.check(problem) {
        Err(ScheduleError::IllegalSchedule(report)) => report.items,
        other => panic!("expected an illegal schedule, got {other:?}"),
    }
}

/// The violations of [`tiny`]'s schedule after `slots[slot][instance] = cell` for each
/// `(slot, instance, cell)` of `edits`, in order.
fn tiny_violations(edits: &[(usize, usize, Option<Job>)]) -> Vec<ScheduleViolation> {
    let (problem, mut schedule) = tiny();
    for &(slot, instance, cell) in edits {
        schedule.slots[slot][instance] = cell;
    }
    violations(&problem, &schedule)
}

#[test]
fn check_accepts_the_hand_schedule_and_stats_measure_it() {
    let (problem, schedule) = tiny();
    schedule.check(&problem).unwrap();
    let stats = schedule.stats(&problem);
    assert_eq!(stats.makespan, 3);
    assert_eq!(stats.latency_factor, 0);
    assert_eq!(stats.jobs, 5);
    assert!((stats.utilisation - 5.0 / 6.0).abs() < 1e-12);
    assert_eq!(stats.makespan_lower_bound, 3);
}

#[test]
fn check_rejects_a_dependency_violation() {
    // Plane 0 runs round 1 of path 0 before round 0.
    let v = tiny_violations(&[(0, 0, Some(job(0, 1, 0))), (2, 0, Some(job(0, 0, 0)))]);
    assert_eq!(v, vec![dependency(0, 1, 0, 0, 2)]);
}

#[test]
fn check_rejects_same_slot_rounds() {
    // Round 1's plane-0 job moved up next to round 0's jobs: same slot is not "strictly later".
    let v = tiny_violations(&[
        (2, 0, None),
        (1, 0, Some(job(0, 1, 0))),
        (0, 0, Some(job(0, 0, 0))),
        (1, 1, Some(job(0, 0, 1))),
        (0, 1, Some(job(1, 0, 0))),
    ]);
    assert_eq!(v, vec![dependency(0, 1, 0, 1, 1)]);
}

#[test]
fn check_rejects_missing_duplicate_unknown_and_misplaced_jobs() {
    let v = tiny_violations(&[(1, 1, None)]);
    assert_eq!(v, vec![ScheduleViolation::MissingJob { job: job(1, 0, 0) }]);

    assert_eq!(
        tiny_violations(&[(1, 0, Some(job(0, 0, 0)))]),
        vec![ScheduleViolation::DuplicateJob {
            job: job(0, 0, 0),
            first: 0,
            slot: 1
        }]
    );

    assert_eq!(
        tiny_violations(&[(1, 0, Some(job(1, 1, 0)))]),
        vec![ScheduleViolation::UnknownJob {
            slot: 1,
            instance: 0,
            job: job(1, 1, 0)
        }]
    );

    assert_eq!(
        tiny_violations(&[(1, 1, None), (1, 0, Some(job(1, 0, 0)))]),
        vec![ScheduleViolation::WrongPlane {
            job: job(1, 0, 0),
            instance: 0,
            plane: 0,
            expected: 1
        }]
    );

    let (problem, mut schedule) = tiny();
    schedule.slots[1].pop();
    schedule.instances.push(PeInstance { plane: 0, copy: 0 });
    let v = violations(&problem, &schedule);
    assert!(v.contains(&ScheduleViolation::DuplicateInstance { plane: 0, copy: 0 }));
    assert!(v.contains(&ScheduleViolation::RowLength {
        slot: 1,
        len: 1,
        expected: 3
    }));
}

#[test]
fn schedule_round_trips_through_json() {
    let (_, schedule) = tiny();
    let text = serde_json::to_string(&schedule).unwrap();
    assert!(
        text.starts_with(r#"{"instances":[{"plane":0,"copy":0}"#),
        "{text}"
    );
    let back: Schedule = serde_json::from_str(&text).unwrap();
    assert_eq!(back, schedule);
}

#[test]
fn the_duplicating_list_scheduler_copies_the_busiest_plane() {
    // Plane 0 carries 2 x 4 jobs, planes 1 and 2 four each: the one extra PE goes to plane 0
    // and the makespan halves to 4 (the optimum: 16 jobs on 4 PEs).
    let problem = problem(3, vec![path(&[0, 1], 4), path(&[0, 2], 4)]);
    let budget = Budget { max_instances: 4 };
    assert_eq!(
        crate::size_copies(&problem, &budget).unwrap(),
        vec![2, 1, 1]
    );
    let dup = crate::schedule_list_duplicated(&problem, &budget).unwrap();
    dup.check(&problem).unwrap();
    let stats = dup.stats(&problem);
    assert_eq!((stats.makespan, stats.duplicates), (4, 1));
    // A budget below one PE per used plane is refused; more copies than jobs are not made.
    assert!(crate::size_copies(&problem, &Budget { max_instances: 2 }).is_err());
    let copies = crate::size_copies(&problem, &Budget { max_instances: 100 }).unwrap();
    assert_eq!(copies, vec![8, 4, 4]);
}

#[test]
fn the_duplicating_list_scheduler_is_legal_and_never_slower_on_synthetic_rooms() {
    for seed in 0..6 {
        let problem = crate::synthetic::living_room(seed, 25, 120);
        let base = Budget::originals_only(&problem);
        let plain = schedule_list(&problem, &base)
            .unwrap()
            .stats(&problem)
            .makespan;
        let more = Budget {
            max_instances: base.max_instances + 8,
        };
        let dup = crate::schedule_list_duplicated(&problem, &more).unwrap();
        dup.check(&problem).unwrap();
        let stats = dup.stats(&problem);
        assert!(stats.instances <= more.max_instances, "seed {seed}");
        assert!(
            stats.makespan <= plain,
            "seed {seed}: {} vs {plain}",
            stats.makespan
        );
    }
}

fn red_black(planes: &[u32], rounds: u32) -> PathJob {
    PathJob {
        phases: 2,
        ..path(planes, rounds)
    }
}

#[test]
fn a_red_black_round_runs_its_two_phases_one_after_the_other() {
    // A-B-A: phase 0 = points 0 and 2 (both on A: two slots with one PE of A), phase 1 =
    // point 1 (B) after it: 3 slots a round, where Jacobi packs a round into 2.
    let problem = problem(2, vec![red_black(&[0, 1, 0], 3)]);
    // Makespan 9 = its lower bound; latency factor 3: phase 0 spreads over 2 slots each
    // round, phase 1 takes one.
    for schedule in originals_only_list_and_ga(&problem, (9, 3, 9)) {
        for round in 0..3 {
            let slot_of = |point| {
                schedule
                    .slots
                    .iter()
                    .position(|row| row.contains(&Some(job(0, round, point))))
                    .unwrap()
            };
            assert!(slot_of(1) > slot_of(0).max(slot_of(2)), "round {round}");
        }
    }
    // A second PE of A runs phase 0 in one slot: 2 slots a round.
    let schedule = schedule_ga(&problem, &Budget { max_instances: 3 }, &small_ga()).unwrap();
    schedule.check(&problem).unwrap();
    assert_eq!(schedule.stats(&problem).makespan, 6);
    assert_eq!(schedule.stats(&problem).latency_factor, 0);
}

#[test]
fn check_rejects_a_second_phase_next_to_the_first() {
    // A-B red-black, one round: point 1 must run after point 0, not beside it.
    let problem = problem(2, vec![red_black(&[0, 1], 1)]);
    let mut schedule = schedule_list(&problem, &Budget::originals_only(&problem)).unwrap();
    assert_eq!(schedule.makespan(), 2);
    schedule.slots[0][1] = schedule.slots[1][1].take();
    let v = violations(&problem, &schedule);
    assert_eq!(v, vec![dependency(0, 0, 1, 0, 0)]);
    // Zero phases is refused at the boundary.
    let bad = Problem {
        num_planes: 2,
        paths: vec![PathJob {
            phases: 0,
            ..path(&[0, 1], 1)
        }],
    };
    assert!(matches!(
        bad.validate(),
        Err(ScheduleError::InvalidProblem(r)) if r.items == vec![ProblemIssue::ZeroPhases { path: 0 }]
    ));
}
