//! Trace benchmarks on the built-in living room, order <= 3, single-threaded, so the solvers
//! compare as ratios inside one run: `cargo bench -p bt-solve --bench trace`.

use bt_paths::{AllVisible, enumerate};
use bt_solve::{Acceleration, IpcOptions, Solver, UpdateOrder, trace};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;

fn living_room(c: &mut Criterion) {
    let scene = bt_import::builtin_scene("living-room", Default::default())
        .unwrap()
        .unwrap();
    let candidates = enumerate(&scene, 3, &AllVisible).unwrap();
    let mut group = c.benchmark_group("living-room-order3");
    group.throughput(Throughput::Elements(candidates.len() as u64));
    group.bench_function("candidates", |b| {
        b.iter(|| enumerate(black_box(&scene), 3, &AllVisible).unwrap())
    });
    let solvers = [
        ("image", Solver::Image),
        (
            "ipc-gauss-seidel",
            Solver::Ipc(IpcOptions::for_scene(&scene, UpdateOrder::GaussSeidel)),
        ),
        (
            "ipc-jacobi",
            Solver::Ipc(IpcOptions::for_scene(&scene, UpdateOrder::Jacobi)),
        ),
        (
            "ipc-gauss-seidel-newton",
            Solver::Ipc(IpcOptions {
                acceleration: Acceleration::Newton,
                ..IpcOptions::for_scene(&scene, UpdateOrder::GaussSeidel)
            }),
        ),
    ];
    for (name, solver) in &solvers {
        group.bench_function(*name, |b| {
            b.iter(|| trace(black_box(&scene), &candidates, solver, false))
        });
    }
    group.bench_function("full-image-trace", |b| {
        b.iter(|| {
            let c = enumerate(black_box(&scene), 3, &AllVisible).unwrap();
            let r = trace(&scene, &c, &Solver::Image, false).unwrap();
            bt_beams::report(&scene, &r.paths, &bt_beams::RadioOptions::default())
        })
    });
    group.finish();
}

criterion_group!(benches, living_room);
criterion_main!(benches);
