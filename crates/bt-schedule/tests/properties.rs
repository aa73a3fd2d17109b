//! Property tests: every schedule is legal, the GA never loses to the list scheduler,
//! duplication never hurts, the GA is deterministic.

use bt_schedule::{Budget, GaParams, PathJob, Problem, schedule_ga, schedule_list};
use proptest::prelude::*;

/// Random valid problems: 1-5 planes, 0-10 paths of order 1-4 (no plane twice in a row),
/// 1-6 rounds of 1-3 phases each.
fn problems() -> impl Strategy<Value = Problem> {
    (1u32..=5).prop_flat_map(|num_planes| {
        let path = (
            prop::collection::vec(0..num_planes, 1..=4),
            1u32..=6,
            1u32..=3,
        )
            .prop_map(move |(mut planes, rounds, phases)| {
                // Shift a repeat to the next plane; with one plane keep a single point.
                for i in 1..planes.len() {
                    if planes[i] == planes[i - 1] {
                        planes[i] = (planes[i] + 1) % num_planes;
                    }
                }
                if num_planes == 1 {
                    planes.truncate(1);
                }
                PathJob {
                    planes,
                    rounds,
                    phases,
                }
            });
        prop::collection::vec(path, 0..=10).prop_map(move |paths| Problem { num_planes, paths })
    })
}

fn params(seed: u64) -> GaParams {
    GaParams {
        seed,
        population: 6,
        generations: 5,
        ..GaParams::default()
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn schedules_are_legal_and_ga_is_never_worse(
        problem in problems(),
        extra in 0u32..4,
        seed in any::<u64>(),
    ) {
        problem.validate().unwrap();
        let base = Budget::originals_only(&problem);
        let list = schedule_list(&problem, &base).unwrap();
        list.check(&problem).unwrap();
        let ga = schedule_ga(&problem, &base, &params(seed)).unwrap();
        ga.check(&problem).unwrap();
        let (l, g) = (list.stats(&problem), ga.stats(&problem));
        prop_assert!(g.makespan <= l.makespan, "ga {g:?} list {l:?}");
        prop_assert!(g.makespan >= g.makespan_lower_bound);
        prop_assert_eq!(g.duplicates, 0);

        let bigger = Budget { max_instances: base.max_instances + extra };
        let dup = schedule_ga(&problem, &bigger, &params(seed)).unwrap();
        dup.check(&problem).unwrap();
        let d = dup.stats(&problem);
        prop_assert!(d.makespan <= g.makespan, "dup {d:?} ga {g:?}");
        prop_assert!(d.instances <= bigger.max_instances);
        prop_assert!(d.makespan >= d.makespan_lower_bound);
    }

    #[test]
    fn larger_budget_never_lengthens_the_schedule(
        problem in problems(),
        extra in 0u32..4,
        more in 1u32..4,
    ) {
        let base = Budget::originals_only(&problem).max_instances;
        let small = schedule_ga(&problem, &Budget { max_instances: base + extra }, &params(7)).unwrap();
        let large =
            schedule_ga(&problem, &Budget { max_instances: base + extra + more }, &params(7)).unwrap();
        large.check(&problem).unwrap();
        prop_assert!(large.makespan() <= small.makespan());
    }

    #[test]
    fn same_seed_gives_the_same_schedule(problem in problems(), seed in any::<u64>()) {
        let budget = Budget { max_instances: Budget::originals_only(&problem).max_instances + 2 };
        let a = schedule_ga(&problem, &budget, &params(seed)).unwrap();
        let b = schedule_ga(&problem, &budget, &params(seed)).unwrap();
        prop_assert_eq!(a, b);
    }
}

#[test]
fn living_room_sized_problem_schedules_legally() {
    let problem = bt_schedule::synthetic::living_room(3, 25, 300);
    problem.validate().unwrap();
    let budget = Budget { max_instances: 35 };
    let params = GaParams {
        generations: 3,
        ..GaParams::default()
    };
    let list = schedule_list(&problem, &Budget::originals_only(&problem)).unwrap();
    let ga = schedule_ga(&problem, &budget, &params).unwrap();
    list.check(&problem).unwrap();
    ga.check(&problem).unwrap();
    let (l, g) = (list.stats(&problem), ga.stats(&problem));
    assert!(
        g.makespan < l.makespan,
        "duplication should pay off: ga {g:?} list {l:?}"
    );
    assert!(g.duplicates > 0);
    // Same seed, same schedule, also through the parallel fitness evaluation.
    let again = schedule_ga(&problem, &budget, &params).unwrap();
    assert_eq!(again, ga);
}
