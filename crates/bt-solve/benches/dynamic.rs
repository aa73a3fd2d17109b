//! WVRN build time and candidate reduction on the living room; time per step of the dynamic
//! living room, incremental vs from scratch, per candidate generator (single thread, image
//! method, order 3).
//!
//! `cargo bench -p bt-solve --bench dynamic`; the reduction ratio and the incremental/scratch ratio of the
//! mean step times are printed to stderr before the criterion groups run.

use bt_import::builtin_dynamic_scene;
use bt_paths::wvrn::Wvrn;
use bt_paths::{AllVisible, enumerate};
use bt_scene::Terminals;
use bt_solve::Solver;
use bt_solve::Tracer;
use bt_solve::pipeline::{CandidateMode, TraceOptions};
use bt_solve::steps::trace_scratch;
use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::Instant;

const ORDER: usize = 3;

fn options(candidates: CandidateMode) -> TraceOptions {
    TraceOptions {
        max_order: ORDER,
        solver: Solver::Image,
        candidates,
        max_candidates: u64::MAX,
        max_wvrn_tests: u64::MAX,
        parallel: false,
        transmission: false,
        diffraction: Default::default(),
    }
}

fn wvrn(c: &mut Criterion) {
    let scene = bt_import::builtin_scene("living-room", Terminals::default())
        .unwrap()
        .unwrap();
    let dynamic = builtin_dynamic_scene("living-room-dynamic", Terminals::default())
        .unwrap()
        .unwrap();
    let w = Wvrn::build(&scene).unwrap();
    let (all, routed) = (
        enumerate(&scene, ORDER, &AllVisible).unwrap().len(),
        enumerate(&scene, ORDER, &w).unwrap().len(),
    );
    eprintln!(
        "living room order {ORDER}: {routed} of {all} candidates over the WVRN (ratio {:.3})",
        routed as f64 / all as f64
    );
    let (mut all_d, mut routed_d) = (0, 0);
    for s in dynamic.scenes() {
        all_d += enumerate(s, ORDER, &AllVisible).unwrap().len();
        routed_d += enumerate(s, ORDER, &Wvrn::build(s).unwrap()).unwrap().len();
    }
    eprintln!(
        "dynamic living room, 10 steps: {routed_d} of {all_d} candidates (ratio {:.3})",
        routed_d as f64 / all_d as f64
    );

    let mut g = c.benchmark_group("wvrn");
    g.bench_function("build/living-room", |b| {
        b.iter(|| Wvrn::build(black_box(&scene)).unwrap())
    });
    let moved = bt_scene::dynamic::moved_surfaces(dynamic.step(4), dynamic.step(5)).unwrap();
    let w4 = Wvrn::build(dynamic.step(4)).unwrap();
    g.bench_function("update/living-room-dynamic-step-5", |b| {
        b.iter_batched(
            || w4.clone(),
            |mut w| w.update(dynamic.step(5), &moved),
            BatchSize::SmallInput,
        )
    });
    g.throughput(Throughput::Elements(all as u64));
    g.bench_function("enumerate-exhaustive/living-room", |b| {
        b.iter(|| enumerate(&scene, ORDER, &AllVisible).unwrap())
    });
    g.bench_function("enumerate-wvrn/living-room", |b| {
        b.iter(|| enumerate(&scene, ORDER, &w).unwrap())
    });
    g.finish();
}

fn steps(c: &mut Criterion) {
    let dynamic = builtin_dynamic_scene("living-room-dynamic", Terminals::default())
        .unwrap()
        .unwrap();
    let n = dynamic.len();
    for mode in [
        CandidateMode::Wvrn,
        CandidateMode::Exhaustive,
        CandidateMode::BeamTree,
    ] {
        let opts = options(mode);
        // Tracers positioned after step k - 1, to time step k alone.
        let mut tracer = Tracer::new(dynamic.step(0).clone(), opts);
        let mut before: Vec<Tracer> = Vec::new();
        for s in dynamic.scenes() {
            before.push(tracer.clone());
            tracer.update(s).unwrap();
        }
        // Quick ratio over steps 1..n (mean of a few rounds), printed for the record.
        let rounds = 20;
        let t0 = Instant::now();
        for _ in 0..rounds {
            for k in 1..n {
                black_box(trace_scratch(dynamic.step(k), k, &opts).unwrap());
            }
        }
        let scratch = t0.elapsed().as_secs_f64() / (rounds * (n - 1)) as f64;
        let t0 = Instant::now();
        for _ in 0..rounds {
            for (k, b) in before.iter().enumerate().skip(1) {
                let mut t = b.clone();
                black_box(t.update(dynamic.step(k)).unwrap());
            }
        }
        let incremental = t0.elapsed().as_secs_f64() / (rounds * (n - 1)) as f64;
        eprintln!(
            "dynamic living room ({mode:?}), steps 1-{}: scratch {:.3} ms/step, incremental {:.3} ms/step (incl. state clone), ratio {:.3}",
            n - 1,
            scratch * 1e3,
            incremental * 1e3,
            incremental / scratch
        );

        let name = match mode {
            CandidateMode::Wvrn => "wvrn",
            CandidateMode::Exhaustive => "exhaustive",
            CandidateMode::BeamTree => "beam-tree",
        };
        let mut g = c.benchmark_group(format!("steps-{name}"));
        g.throughput(Throughput::Elements((n - 1) as u64));
        g.bench_function("scratch/steps-1-9", |b| {
            b.iter(|| {
                (1..n)
                    .map(|k| {
                        trace_scratch(dynamic.step(k), k, &opts)
                            .unwrap()
                            .trace
                            .paths
                            .len()
                    })
                    .sum::<usize>()
            })
        });
        g.bench_function("incremental/steps-1-9", |b| {
            b.iter_batched(
                || before[1].clone(),
                |mut t| {
                    (1..n)
                        .map(|k| t.update(dynamic.step(k)).unwrap().trace.paths.len())
                        .sum::<usize>()
                },
                BatchSize::SmallInput,
            )
        });
        g.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).measurement_time(std::time::Duration::from_secs(3));
    targets = wvrn, steps
}
criterion_main!(benches);
