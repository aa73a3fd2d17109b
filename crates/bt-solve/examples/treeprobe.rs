//! A fixed workload for instruction counts (docs/performance.md): the living room at order 3,
//! `N` times. Wall-clock benchmarks are in `benches/beamtree.rs`; this probe exists so that
//! valgrind's cachegrind can count instructions, which do not depend on the machine's load:
//!
//! ```text
//! cargo build --release -p bt-solve --example treeprobe
//! valgrind --tool=cachegrind --cache-sim=no target/release/examples/treeprobe cand 11
//! ```
//!
//! WHAT: `cand` (beam-tree candidates), `image` / `exh` (whole image-method trace with the beam
//! tree / exhaustive candidates), `ipc` (whole IPC Gauss-Seidel trace), `walk` (a new RX on a
//! kept tree, walk only), `newrx` (walk + image method + validation), `diff` (candidates with
//! one diffraction), `rxtree` (a tree materialised to depth 2, as the RX side of `diff`), `diffimage` (the
//! whole image-method trace with one diffraction), `diff2t` (the same with two diffractions
//! and transmission).

use bt_paths::beamtree::{BeamTree, TreeCache, TreeOptions, candidates_in};
use bt_scene::{Scene, Terminals, Vec3};
use bt_solve::Tracer;
use bt_solve::pipeline::{CandidateMode, TraceOptions, Traced};
use bt_solve::{IpcOptions, Solver, UpdateOrder};

fn trace_options(solver: Solver, candidates: CandidateMode) -> TraceOptions {
    TraceOptions {
        solver,
        candidates,
        parallel: false,
        max_candidates: u64::MAX,
        max_wvrn_tests: u64::MAX,
        ..TraceOptions::new(3)
    }
}

/// What the calls of one run keep, as a stream of traces does: the tracer (with its beam-tree
/// caches) and the cache of the bare candidate walks.
#[derive(Default)]
struct Kept {
    tracer: Option<Tracer>,
    cache: TreeCache,
}

/// `scene` traced between its own terminals by the run's tracer (made on the first call).
fn trace_scene(kept: &mut Kept, scene: &Scene, options: &TraceOptions) -> Traced {
    let tracer = kept
        .tracer
        .get_or_insert_with(|| Tracer::new(scene.clone(), *options));
    tracer
        .trace(scene.tx_world().unwrap(), scene.rx_world().unwrap())
        .unwrap()
}

fn traced_paths(kept: &mut Kept, scene: &Scene, options: &TraceOptions) -> usize {
    trace_scene(kept, scene, options).result.paths.len()
}

/// The RX of call `i` (scene-local frame): a few millimetres apart, so that no call repeats
/// the previous one.
fn moved_rx(scene: &Scene, i: usize) -> Vec3 {
    scene.rx().unwrap() + Vec3::new(0.001 * (i % 7) as f64, 0.0, 0.0)
}

fn run(what: &str, scene: &Scene, i: usize, tree: &BeamTree, kept: &mut Kept) -> usize {
    match what {
        "cand" => candidates_in(scene, TreeOptions::new(3), &mut kept.cache, &mut |_| {})
            .unwrap()
            .len(),
        "image" => traced_paths(
            kept,
            scene,
            &trace_options(Solver::Image, CandidateMode::BeamTree),
        ),
        "diffimage" => traced_paths(
            kept,
            scene,
            &TraceOptions {
                diffraction: bt_solve::pipeline::DiffractionOptions::first_order(),
                ..trace_options(Solver::Image, CandidateMode::BeamTree)
            },
        ),
        "diff2t" => traced_paths(
            kept,
            scene,
            &TraceOptions {
                diffraction: bt_solve::pipeline::DiffractionOptions {
                    max_diffractions: 2,
                    min_edge_length: 0.0,
                },
                transmission: true,
                ..trace_options(Solver::Image, CandidateMode::BeamTree)
            },
        ),
        "report" => {
            let traced = trace_scene(
                kept,
                scene,
                &trace_options(Solver::Image, CandidateMode::BeamTree),
            );
            bt_beams::report(
                scene,
                &traced.result.paths,
                &bt_beams::RadioOptions::default(),
            )
            .unwrap()
            .len()
        }
        "exh" => traced_paths(
            kept,
            scene,
            &trace_options(Solver::Image, CandidateMode::Exhaustive),
        ),
        "ipc" => {
            let ipc = Solver::Ipc(IpcOptions::for_scene(scene, UpdateOrder::GaussSeidel));
            traced_paths(kept, scene, &trace_options(ipc, CandidateMode::BeamTree))
        }
        "ipc-newton" => {
            let ipc = IpcOptions {
                acceleration: bt_solve::Acceleration::Newton,
                ..IpcOptions::for_scene(scene, UpdateOrder::GaussSeidel)
            };
            traced_paths(
                kept,
                scene,
                &trace_options(Solver::Ipc(ipc), CandidateMode::BeamTree),
            )
        }
        "walk" => tree.candidates(moved_rx(scene, i)).len(),
        "diff" => bt_paths::beamtree::candidates_and_diffracted_in(
            scene,
            TreeOptions::new(3),
            Some(bt_paths::diffraction::Diffracting {
                min_edge_length: 0.0,
                max_diffractions: 1,
            }),
            &mut kept.cache,
            &mut |_| {},
        )
        .unwrap()
        .diffracted
        .len(),
        "rxtree" => BeamTree::build(scene, TreeOptions::new(2)).unwrap().len(),
        "newrx" => {
            let rx = moved_rx(scene, i);
            let set = tree.candidates(rx);
            let moved = scene.with_receiver(scene.to_world(rx)).unwrap();
            bt_solve::trace(&moved, &set, &Solver::Image, false)
                .unwrap()
                .paths
                .len()
        }
        other => {
            panic!(
                "unknown workload {other:?}: cand, image, exh, ipc, walk, newrx, diff, rxtree, diffimage or diff2t"
            )
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (what, n) = match args.as_slice() {
        [_, what, n] => (what.as_str(), n.parse::<usize>().expect("N is a count")),
        _ => panic!("usage: treeprobe WHAT N"),
    };
    let scene = bt_import::builtin_scene("living-room", Terminals::default())
        .unwrap()
        .unwrap();
    let tree = BeamTree::build(&scene, TreeOptions::new(3)).unwrap();
    let mut kept = Kept::default();
    if std::env::var_os("TREEPROBE_TIME").is_some() {
        // Wall clock: the best of 20 batches of `n` calls, per call.
        let best = (0..20)
            .map(|_| {
                let t = std::time::Instant::now();
                let total: usize = (0..n).map(|i| run(what, &scene, i, &tree, &mut kept)).sum();
                std::hint::black_box(total);
                t.elapsed().as_secs_f64() / n as f64
            })
            .fold(f64::INFINITY, f64::min);
        println!(
            "{what}: {:.1} µs per call (best of 20 batches of {n})",
            best * 1e6
        );
        return;
    }
    let total: usize = (0..n).map(|i| run(what, &scene, i, &tree, &mut kept)).sum();
    println!("{total}");
}
