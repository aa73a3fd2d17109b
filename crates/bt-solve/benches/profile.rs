//! Profiling driver (not a criterion bench): runs one solver over the living room's order-3
//! candidates `REPS` times, single-threaded, so that `valgrind --tool=callgrind` or `perf`
//! see only the hot loop. Build with `cargo bench -p bt-solve --bench profile --no-run`, then
//! run the printed binary: `profile <image|ipc-gs|ipc-jacobi|ipc-newton|candidates> [reps]`.
//! Under `cargo bench` (argument `--bench`) it runs every solver once as a smoke test.

use bt_paths::{AllVisible, enumerate};
use bt_solve::{Acceleration, IpcOptions, Solver, UpdateOrder, trace};
use std::hint::black_box;

fn main() {
    let scene = bt_import::builtin_scene("living-room", Default::default())
        .unwrap()
        .unwrap();
    let candidates = enumerate(&scene, 3, &AllVisible).unwrap();
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let reps: usize = args.get(1).and_then(|r| r.parse().ok()).unwrap_or(1);
    let gs = IpcOptions::for_scene(&scene, UpdateOrder::GaussSeidel);
    let newton = IpcOptions {
        acceleration: Acceleration::Newton,
        ..gs
    };
    let solvers = [
        ("image", Solver::Image),
        ("ipc-gs", Solver::Ipc(gs)),
        (
            "ipc-jacobi",
            Solver::Ipc(IpcOptions::for_scene(&scene, UpdateOrder::Jacobi)),
        ),
        ("ipc-newton", Solver::Ipc(newton)),
    ];
    let wanted = args.first().map(String::as_str);
    if let Some(name) = wanted.and_then(|w| w.strip_prefix("stats-")) {
        let (_, solver) = solvers
            .iter()
            .find(|(n, _)| *n == name)
            .expect("known solver");
        stats(&scene, &candidates, solver);
        return;
    }
    if wanted == Some("candidates") {
        for _ in 0..reps {
            black_box(enumerate(black_box(&scene), 3, &AllVisible).unwrap());
        }
        return;
    }
    for (name, solver) in &solvers {
        if wanted.is_some_and(|w| w != *name) {
            continue;
        }
        let mut valid = 0;
        for _ in 0..reps {
            valid = black_box(trace(black_box(&scene), &candidates, solver, false))
                .unwrap()
                .counts
                .valid;
        }
        println!(
            "{name}: {} candidates, {valid} valid, {reps} reps",
            candidates.len()
        );
    }
}

/// Rounds spent per outcome kind (for docs/performance.md).
fn stats(scene: &bt_scene::Scene, candidates: &bt_paths::CandidateSet, solver: &Solver) {
    use bt_solve::{CandidateOutcome, solve_candidate};
    use std::collections::BTreeMap;
    let mut by_kind: BTreeMap<&str, (u64, u64, u32)> = BTreeMap::new();
    let ends = scene.terminals().unwrap();
    for seq in candidates.iter() {
        let n = seq.len();
        let mut points = vec![bt_geom::Vec3::ZERO; n];
        let mut scratch = points.clone();
        let outcome = solve_candidate(scene, ends, seq, solver, &mut points, &mut scratch);
        let (kind, ipc) = match outcome {
            CandidateOutcome::Solved { validity, ipc } => (
                match validity {
                    bt_solve::Validity::Valid => "valid",
                    bt_solve::Validity::OutsidePolygon { .. } => "outside",
                    bt_solve::Validity::OppositeSides { .. } => "opposite",
                    bt_solve::Validity::Blocked { .. } => "blocked",
                    _ => "other",
                },
                ipc,
            ),
            CandidateOutcome::LeftPolygon(o) => ("left-polygon", Some(o)),
            CandidateOutcome::Blocked(o) => ("stopped-blocked", Some(o)),
            CandidateOutcome::Degenerate(o) => ("degenerate", Some(o)),
            CandidateOutcome::NotConverged(o) => ("not-converged", Some(o)),
            _ => ("other", None),
        };
        let rounds = ipc.map_or(0, |o| o.iterations());
        let e = by_kind.entry(kind).or_default();
        e.0 += 1;
        e.1 += rounds as u64 * n as u64;
        e.2 = e.2.max(rounds);
    }
    for (kind, (count, point_updates, max)) in by_kind {
        println!(
            "{kind:>14}: {count:5} candidates, {point_updates:9} point updates, max {max} rounds"
        );
    }
}
