//! Beam-tree benchmarks, single-threaded, figures as ratios inside one run
//! (`cargo bench -p bt-solve --bench beamtree`; docs/performance.md):
//! - living room, order <= 3: candidates only; whole traces as the issue defines them
//!   (candidates + solver + validation) with the beam tree and with exhaustive enumeration,
//!   IPC Gauss-Seidel (the paper's rounds, and with Newton polish); the image-method trace
//!   followed by the per-path report (gains, angles, names); a new RX answered by a kept tree;
//! - living room with one diffraction per path, order <= 3, beside the specular trace;
//! - the built-in city (39,692 triangles): orders 1, 2 and 3.

use bt_paths::beamtree::{BeamTree, TreeCache, TreeOptions, candidates_in};
use bt_scene::{Scene, Terminals, Vec3};
use bt_solve::pipeline::{CandidateMode, TraceOptions};
use bt_solve::{IpcOptions, Solver, Tracer, UpdateOrder};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::Duration;

fn options(order: usize, mode: CandidateMode, solver: Solver) -> TraceOptions {
    TraceOptions {
        solver,
        candidates: mode,
        parallel: false,
        max_candidates: u64::MAX,
        max_wvrn_tests: u64::MAX,
        ..TraceOptions::new(order)
    }
}

/// The tracer's scene traced between its own terminals (the tracer, made outside the timed
/// loop, keeps the beam tree's caches from one iteration to the next, as a stream of traces
/// does).
fn trace_own(tracer: &mut Tracer) -> bt_solve::pipeline::Traced {
    let (tx, rx) = (
        tracer.scene().tx_world().unwrap(),
        tracer.scene().rx_world().unwrap(),
    );
    tracer.trace(black_box(tx), rx).expect("trace runs")
}

/// Candidates, solver and validation: the valid paths.
fn whole_trace(tracer: &mut Tracer) -> usize {
    trace_own(tracer).result.paths.len()
}

/// [`whole_trace`] and the per-path report the CLI prints (gains, angles, names).
fn trace_and_report(tracer: &mut Tracer) -> usize {
    let traced = trace_own(tracer);
    bt_beams::report(
        tracer.scene(),
        &traced.result.paths,
        &bt_beams::RadioOptions::default(),
    )
    .expect("gains")
    .len()
}

fn living_room(c: &mut Criterion) {
    let scene = bt_import::builtin_scene("living-room", Terminals::default())
        .unwrap()
        .unwrap();
    let gs_options = IpcOptions::for_scene(&scene, UpdateOrder::GaussSeidel);
    let gs = Solver::Ipc(gs_options);
    let gs_newton = Solver::Ipc(IpcOptions {
        acceleration: bt_solve::Acceleration::Newton,
        ..gs_options
    });
    let mut group = c.benchmark_group("living-room-order3");
    // A stream of candidate walks keeps its cache, as the tracer does.
    let mut cache = TreeCache::default();
    group.bench_function("beam-tree-candidates", |b| {
        b.iter(|| {
            let options = TreeOptions::new(3);
            candidates_in(black_box(&scene), options, &mut cache, &mut |_| {})
        })
    });
    for (name, mode, solver) in [
        (
            "trace-image-beam-tree",
            CandidateMode::BeamTree,
            Solver::Image,
        ),
        (
            "trace-image-exhaustive",
            CandidateMode::Exhaustive,
            Solver::Image,
        ),
        ("trace-ipc-gs-beam-tree", CandidateMode::BeamTree, gs),
        (
            "trace-ipc-gs-newton-beam-tree",
            CandidateMode::BeamTree,
            gs_newton,
        ),
        ("trace-ipc-gs-exhaustive", CandidateMode::Exhaustive, gs),
    ] {
        let opts = options(3, mode, solver);
        let mut tracer = Tracer::new(scene.clone(), opts);
        group.bench_function(name, |b| b.iter(|| whole_trace(&mut tracer)));
    }
    let mut tracer = Tracer::new(
        scene.clone(),
        options(3, CandidateMode::BeamTree, Solver::Image),
    );
    group.bench_function("trace-image-beam-tree-and-report", |b| {
        b.iter(|| trace_and_report(&mut tracer))
    });
    // Fixed TX, moving RX: the tree is kept; each new RX is a walk plus the image method.
    let tree = BeamTree::build(&scene, TreeOptions::new(3)).unwrap();
    let receivers: Vec<Vec3> = (0..16)
        .map(|i| Vec3::new(0.8 + 0.3 * i as f64, 1.0 + 0.15 * i as f64, 0.72))
        .collect();
    let moved: Vec<Scene> = receivers
        .iter()
        .map(|rx| scene.with_receiver(*rx).unwrap())
        .collect();
    group.bench_function("new-rx-kept-tree", |b| {
        let mut k = 0;
        b.iter(|| {
            k = (k + 1) % receivers.len();
            let set = tree.candidates(moved[k].rx().unwrap());
            bt_solve::trace(&moved[k], &set, &Solver::Image, false)
                .unwrap()
                .paths
                .len()
        })
    });
    group.bench_function("new-rx-walk-only", |b| {
        let mut k = 0;
        b.iter(|| {
            k = (k + 1) % receivers.len();
            tree.candidates(moved[k].rx().unwrap()).len()
        })
    });
    group.finish();
}

fn city(c: &mut Criterion) {
    let scene = bt_import::builtin_scene("city", Terminals::default())
        .unwrap()
        .unwrap();
    let mut group = c.benchmark_group("city");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(20));
    for order in 1..=3 {
        let opts = options(order, CandidateMode::BeamTree, Solver::Image);
        let mut tracer = Tracer::new(scene.clone(), opts);
        group.bench_function(format!("trace-image-order{order}"), |b| {
            b.iter(|| whole_trace(&mut tracer))
        });
    }
    group.finish();
}

/// First-order diffraction in the living room at order ≤ 3 (the issue's ≤ 1 ms target): the
/// specular trace beside it, the trace with diffraction, and its candidates alone.
fn living_room_diffraction(c: &mut Criterion) {
    let scene = bt_import::builtin_scene("living-room", Terminals::default())
        .unwrap()
        .unwrap();
    let mut group = c.benchmark_group("living-room-diffraction");
    let specular = options(3, CandidateMode::BeamTree, Solver::Image);
    let diffraction = TraceOptions {
        diffraction: bt_solve::pipeline::DiffractionOptions::first_order(),
        ..specular
    };
    let mut tracer = Tracer::new(scene.clone(), specular);
    group.bench_function("trace-specular", |b| b.iter(|| whole_trace(&mut tracer)));
    let mut tracer = Tracer::new(scene.clone(), diffraction);
    group.bench_function("trace-one-diffraction", |b| {
        b.iter(|| whole_trace(&mut tracer))
    });
    // A fixed access point and a moving handset: the RX moves by a millimetre every trace,
    // and the tracer's cache keeps the TX side's reaches.
    let (tx, rx) = (scene.tx_world().unwrap(), scene.rx_world().unwrap());
    let step = |i: usize| Vec3::new(0.001 * (i % 7) as f64, 0.0, 0.0);
    let mut i = 0;
    group.bench_function("trace-one-diffraction-moving-rx", |b| {
        b.iter(|| {
            i += 1;
            tracer.trace(tx, rx + step(i)).unwrap().result.paths.len()
        })
    });
    // The TX moves every trace too: nothing of the TX side can be kept.
    group.bench_function("trace-one-diffraction-moving-tx", |b| {
        b.iter(|| {
            i += 1;
            tracer.trace(tx + step(i), rx).unwrap().result.paths.len()
        })
    });
    group.bench_function("candidates-one-diffraction", |b| {
        b.iter(|| {
            bt_solve::pipeline::candidates(black_box(&scene), &diffraction)
                .unwrap()
                .diffracted
                .len()
        })
    });
    group.finish();
}

/// Transmission in the living room at order ≤ 3 (issue 28): every slab reflector (furniture,
/// plasterboard, glass) is crossed, the concrete shell stays opaque; beside it the specular
/// trace, and with one diffraction too.
fn living_room_transmission(c: &mut Criterion) {
    let scene = bt_import::builtin_scene("living-room", Terminals::default())
        .unwrap()
        .unwrap();
    let mut group = c.benchmark_group("living-room-transmission");
    let specular = options(3, CandidateMode::BeamTree, Solver::Image);
    let mut tracer = Tracer::new(scene.clone(), specular);
    group.bench_function("trace-specular", |b| b.iter(|| whole_trace(&mut tracer)));
    let transmission = TraceOptions {
        transmission: true,
        ..specular
    };
    let mut tracer = Tracer::new(scene.clone(), transmission);
    group.bench_function("trace-transmission", |b| {
        b.iter(|| whole_trace(&mut tracer))
    });
    let both = TraceOptions {
        diffraction: bt_solve::pipeline::DiffractionOptions::first_order(),
        ..transmission
    };
    let mut tracer = Tracer::new(scene, both);
    group.bench_function("trace-transmission-one-diffraction", |b| {
        b.iter(|| whole_trace(&mut tracer))
    });
    group.finish();
}

criterion_group!(
    benches,
    living_room,
    living_room_diffraction,
    living_room_transmission,
    city
);
criterion_main!(benches);
