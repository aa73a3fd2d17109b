//! GA vs list scheduler on a seeded living-room-size problem (25 planes, 2000 paths), and on
//! one time step's work (200 paths: what the host schedules per step).
//!
//! `cargo bench -p bt-schedule`. `BT_SCHEDULE_BENCH_PATHS=10000` changes the path count.
//! Before timing, prints makespan / latency factor of list, GA (originals only) and GA with
//! duplication (budget 40 PE instances) to stderr.

use std::hint::black_box;
use std::time::Instant;

use bt_schedule::{Budget, GaParams, Problem, Schedule, schedule_ga, schedule_list, synthetic};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

const SEED: u64 = 2024;
const PLANES: u32 = 25;
const DUPLICATION_BUDGET: u32 = 40;

/// Path count from environment variable `name`, else `default`.
fn env_paths(name: &str, default: u32) -> u32 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn report(name: &str, problem: &Problem, run: impl Fn() -> Schedule) {
    let start = Instant::now();
    let schedule = run();
    let elapsed = start.elapsed();
    schedule.check(problem).expect("legal schedule");
    let s = schedule.stats(problem);
    eprintln!(
        "{name:>8}: makespan {:>6} slots (bound {:>6}), LF {:>8}, utilisation {:.3}, \
         instances {:>3} ({} dup), {:.3} s",
        s.makespan,
        s.makespan_lower_bound,
        s.latency_factor,
        s.utilisation,
        s.instances,
        s.duplicates,
        elapsed.as_secs_f64()
    );
}

fn bench(c: &mut Criterion) {
    let paths = env_paths("BT_SCHEDULE_BENCH_PATHS", 2000);
    let problem = synthetic::living_room(SEED, PLANES, paths);
    let jobs: u64 = problem
        .paths
        .iter()
        .map(|p| p.planes.len() as u64 * u64::from(p.rounds))
        .sum();
    let originals = Budget::originals_only(&problem);
    let duplication = Budget {
        max_instances: DUPLICATION_BUDGET,
    };
    let params = GaParams::default();
    eprintln!(
        "living_room(seed {SEED}, {PLANES} planes, {paths} paths): {jobs} jobs, ga {params:?}"
    );
    report("list", &problem, || {
        schedule_list(&problem, &originals).unwrap()
    });
    report("ga", &problem, || {
        schedule_ga(&problem, &originals, &params).unwrap()
    });
    report("ga+dup", &problem, || {
        schedule_ga(&problem, &duplication, &params).unwrap()
    });

    let mut group = c.benchmark_group(format!("schedule_{paths}_paths"));
    group.sample_size(10);
    group.throughput(Throughput::Elements(u64::from(paths)));
    group.bench_function("list", |b| {
        b.iter(|| schedule_list(black_box(&problem), &originals).unwrap())
    });
    group.bench_function("ga", |b| {
        b.iter(|| schedule_ga(black_box(&problem), &originals, &params).unwrap())
    });
    group.bench_function("ga_duplication", |b| {
        b.iter(|| schedule_ga(black_box(&problem), &duplication, &params).unwrap())
    });
    group.finish();
}

/// Per time step on the host: one step's work as the beam tree sends it (about 200
/// candidates of order <= 3 in the living room; `BT_SCHEDULE_STEP_PATHS` changes it), list
/// scheduler (the host's, target <= 1 ms) against the GA (offline sizing).
fn bench_step(c: &mut Criterion) {
    let paths = env_paths("BT_SCHEDULE_STEP_PATHS", 200);
    let problem = synthetic::living_room(SEED, PLANES, paths);
    let originals = Budget::originals_only(&problem);
    let params = GaParams::default();
    eprintln!("one step: living_room(seed {SEED}, {PLANES} planes, {paths} paths)");
    report("list", &problem, || {
        schedule_list(&problem, &originals).unwrap()
    });
    report("ga", &problem, || {
        schedule_ga(&problem, &originals, &params).unwrap()
    });
    let mut group = c.benchmark_group(format!("step_{paths}_paths"));
    group.sample_size(20);
    group.bench_function("list", |b| {
        b.iter(|| schedule_list(black_box(&problem), &originals).unwrap())
    });
    group.bench_function("ga", |b| {
        b.iter(|| schedule_ga(black_box(&problem), &originals, &params).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench_step, bench);
criterion_main!(benches);
