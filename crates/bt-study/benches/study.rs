//! Image method vs IPC vs SBR on generated 2-D rooms, in one run so the ratios are comparable.
//!
//! `cargo bench -p bt-study --bench study`. One room of each shape (seed 1, the study's first
//! four rooms, time step 0), third order; each solver's whole job from scene to paths,
//! single-threaded, as in the study. Throughput: exact paths per second.

use bt_paths::{AllVisible, enumerate};
use bt_solve::{SbrOptions, Solver, sbr, trace};
use bt_study::{StudySolver, embed, room};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;

const MAX_ORDER: usize = 3;

fn solvers(c: &mut Criterion) {
    for index in 0..4 {
        let r = room::generate(1, index, 1).expect("room generates");
        let scene = embed::scene("bench", &r.contours[0], r.tx, r.rx).expect("room embeds");
        let exact = trace(
            &scene,
            &enumerate(&scene, MAX_ORDER, &AllVisible).unwrap(),
            &Solver::Image,
            false,
        )
        .unwrap();
        let mut group =
            c.benchmark_group(format!("room-{index}-{}-{}-edges", r.shape.name(), r.edges));
        group.throughput(Throughput::Elements(exact.paths.len() as u64));
        for study_solver in [
            StudySolver::Image,
            StudySolver::IpcGaussSeidel,
            StudySolver::IpcJacobi,
        ] {
            let (name, solver) = (
                study_solver.name(),
                study_solver.exact_solver(&scene).unwrap(),
            );
            group.bench_function(BenchmarkId::from_parameter(name), |b| {
                b.iter(|| {
                    let candidates = enumerate(black_box(&scene), MAX_ORDER, &AllVisible).unwrap();
                    trace(&scene, &candidates, &solver, false).unwrap()
                })
            });
        }
        for (name, options) in [
            ("sbr-1deg-planar", SbrOptions::grid(1.0).planar()),
            ("sbr-1deg-sphere", SbrOptions::grid(1.0)),
        ] {
            group.bench_function(BenchmarkId::from_parameter(name), |b| {
                b.iter(|| {
                    sbr::trace_detailed(black_box(&scene), &options, MAX_ORDER, false).unwrap()
                })
            });
        }
        group.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(2));
    targets = solvers
}
criterion_main!(benches);
