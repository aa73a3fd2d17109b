//! The real-time loop's costs on the living room at order 3 (image method, beam tree):
//! - `serve/receiver-move`: one request `{"rx": [x, y, z]}` answered in process (parse, walk
//!   of the kept TX tree, report, JSON), the receivers of a seeded walk in turn;
//! - `serve/stream`: a stream of such requests through `Server::serve` (consecutive moves
//!   answered together over the cores), per move;
//! - `serve/person-move`: a request moving the person of `living-room-dynamic` (the
//!   incremental update of `trace --steps`, report, JSON), two poses in turn;
//! - `trace_many/kept-tree`: `Tracer::trace_each_then` with the full report of each receiver
//!   into its thread's reused records (what Python's `trace_many` runs before its columns), 64
//!   receivers per call, on a pool of one thread and of two: the ratio is the speed-up on two
//!   cores; `trace_many/kept-tree-1000` the same with 1,000 receivers of the walk per call
//!   (issue 30's workload: a Python `trace_many` over 1,000 nearby receivers).
//!
//! `cargo bench -p bt-serve --bench serve`

use bt_beams::RadioOptions;
use bt_geom::Vec3;
use bt_serve::{Limits, Server};
use bt_solve::Tracer;
use bt_solve::settings::SolveSettings;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;

const ORDER: usize = 3;

fn server(source: &str, parallel: bool) -> Server {
    let options = bt_import::LoadOptions::default();
    let dynamic = bt_import::load_dynamic(source, &options, &mut |_| {})
        .expect("built-in scene")
        .scene;
    let settings = SolveSettings {
        max_order: ORDER,
        parallel,
        ..SolveSettings::default()
    };
    let options = settings.trace_options(dynamic.step(0)).expect("options");
    Server::new(dynamic, options, RadioOptions::default(), Limits::default())
}

/// The seeded walk of `stream`'s example: 0.2 m steps on a millimetre grid, 0.3 m from the
/// walls; receivers on a seat or shelf (error answers) are left out.
fn walk(n: usize) -> Vec<[f64; 3]> {
    let mut rng = ChaCha8Rng::seed_from_u64(30);
    let mut p: [f64; 3] = [2.3, 2.1, 0.72];
    let bounds: [(f64, f64); 3] = [(0.3, 5.7), (0.3, 4.2), (0.3, 2.4)];
    let mut probe = server("builtin:living-room", false);
    let mut out = Vec::new();
    let mut points = Vec::new();
    while points.len() < n {
        for (x, (lo, hi)) in p.iter_mut().zip(bounds) {
            let next = (*x + rng.random_range(-0.2..0.2)).clamp(lo, hi);
            *x = (next * 1e3).round() / 1e3;
        }
        if probe.answer_line(&line(p), &mut out) {
            points.push(p);
        }
    }
    points
}

fn line(p: [f64; 3]) -> Vec<u8> {
    format!("{{\"rx\":[{},{},{}]}}", p[0], p[1], p[2]).into_bytes()
}

fn serve(c: &mut Criterion) {
    let lines: Vec<Vec<u8>> = walk(256).into_iter().map(line).collect();
    let mut group = c.benchmark_group("serve");
    group.throughput(Throughput::Elements(1));
    let mut one = server("builtin:living-room", true);
    let mut out = Vec::new();
    let mut k = 0;
    group.bench_function("receiver-move", |b| {
        b.iter(|| {
            k = (k + 1) % lines.len();
            black_box(one.answer_line(&lines[k], &mut out))
        })
    });
    let stream = lines.join(&b'\n');
    group.throughput(Throughput::Elements(lines.len() as u64));
    for (name, parallel) in [("stream-1-thread", false), ("stream", true)] {
        let mut s = server("builtin:living-room", parallel);
        let mut answers = Vec::with_capacity(lines.len() * 40_000);
        group.bench_function(name, |b| {
            b.iter(|| {
                answers.clear();
                black_box(s.serve(&stream[..], &mut answers).expect("stream"))
            })
        });
    }
    group.throughput(Throughput::Elements(1));
    let mut dynamic = server("builtin:living-room-dynamic", true);
    let poses = [
        br#"{"rx":[1.5,2.5,1.2],"objects":{"person":{"offset":[0.5,1.5,0]}}}"#.as_slice(),
        br#"{"rx":[1.5,2.5,1.2],"objects":{"person":{"offset":[0.6,1.4,0]}}}"#.as_slice(),
    ];
    let mut k = 0;
    group.bench_function("person-move", |b| {
        b.iter(|| {
            k = 1 - k;
            assert!(
                dynamic.answer_line(poses[k], &mut out),
                "{}",
                String::from_utf8_lossy(&out)
            );
        })
    });
    group.finish();
}

fn trace_many(c: &mut Criterion) {
    let scene = bt_import::builtin_scene("living-room", Default::default())
        .expect("built-in scene")
        .expect("living room");
    let settings = SolveSettings {
        max_order: ORDER,
        ..SolveSettings::default()
    };
    let options = settings.trace_options(&scene).expect("options");
    let tx = scene.tx_world().expect("the living room has a TX");
    let radio = RadioOptions::default();
    let mut group = c.benchmark_group("trace_many");
    for (count, name) in [(64, "kept-tree"), (1000, "kept-tree-1000")] {
        let receivers: Vec<Vec3> = walk(count).into_iter().map(Vec3::from_array).collect();
        group.throughput(Throughput::Elements(receivers.len() as u64));
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("pool");
            let mut tracer = Tracer::new(scene.clone(), options);
            let report = |moved: &bt_scene::Scene, t: bt_solve::pipeline::Traced| {
                REPORTS.with_borrow_mut(|records| {
                    let paths = records.report(moved, &t.result.paths, &radio);
                    let paths = paths.expect("report");
                    (paths.len(), bt_beams::received_power_dbm(paths, 0.0))
                })
            };
            group.bench_function(format!("{name}-{threads}-thread"), |b| {
                b.iter(|| {
                    pool.install(|| black_box(tracer.trace_each_then(tx, &receivers, report)))
                })
            });
        }
    }
    group.finish();
}

thread_local! {
    /// Each thread's report records, reused from receiver to receiver as Python's
    /// `trace_many` reuses them.
    static REPORTS: std::cell::RefCell<bt_beams::Records> = std::cell::RefCell::default();
}

criterion_group!(benches, serve, trace_many);
criterion_main!(benches);
