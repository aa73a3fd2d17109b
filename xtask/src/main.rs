//! `cargo xtask <task>` (alias in `.cargo/config.toml`): chores that are neither library code
//! nor tests.
//!
//! - `docs`: regenerate the measured tables of `docs/` and print them as Markdown. Today: the
//!   corner-reflector accuracy table of `docs/numerics.md` (400 seeded scenes, plain IPC and
//!   Newton-accelerated IPC against the image method). The assertions on those numbers live in
//!   `crates/bt-solve/tests`; this only measures and prints.

use std::process::ExitCode;

use bt_geom::Real;
use bt_paths::{AllVisible, enumerate};
use bt_scene::Scene;
use bt_solve::{Acceleration, FoundPath, IpcOptions, Solver, UpdateOrder, trace};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("docs") => {
            corner_accuracy_table();
            ExitCode::SUCCESS
        }
        _ => {
            eprintln!("usage: cargo xtask docs   (print the measured tables of docs/)");
            ExitCode::FAILURE
        }
    }
}

/// Per solver: worst distance from the image method (m), scenes over 1e-9 m and 1e-11 m,
/// scenes whose valid paths differ, rounds (plus Newton steps) spent on valid paths.
#[derive(Default, Clone, Copy)]
struct Accuracy {
    worst_m: Real,
    over_1e9: u32,
    over_1e11: u32,
    mismatches: u32,
    iterations: u64,
}

fn run(scene: &Scene, solver: &Solver) -> Vec<FoundPath> {
    let candidates = enumerate(scene, 3, &AllVisible).unwrap();
    trace(scene, &candidates, solver, true).unwrap().paths
}

fn solvers(scene: &Scene) -> [(&'static str, Solver); 4] {
    let ipc = |order, acceleration| {
        Solver::Ipc(IpcOptions {
            acceleration,
            ..IpcOptions::for_scene(scene, order)
        })
    };
    [
        (
            "Gauss-Seidel",
            ipc(UpdateOrder::GaussSeidel, Acceleration::None),
        ),
        ("Jacobi", ipc(UpdateOrder::Jacobi, Acceleration::None)),
        (
            "Gauss-Seidel + Newton",
            ipc(UpdateOrder::GaussSeidel, Acceleration::Newton),
        ),
        (
            "Jacobi + Newton",
            ipc(UpdateOrder::Jacobi, Acceleration::Newton),
        ),
    ]
}

/// The table of `docs/numerics.md`, "Known limitation: paths bouncing near a corner".
fn corner_accuracy_table() {
    let (scenes, tries) = bt_testkit::corner_scenes(2024, 400);
    let mut stats = [Accuracy::default(); 4];
    let mut names = [""; 4];
    for scene in &scenes {
        let reference = run(scene, &Solver::Image);
        let surfaces =
            |paths: &[FoundPath]| -> Vec<_> { paths.iter().map(|p| p.surfaces.clone()).collect() };
        for ((s, name), (label, solver)) in stats.iter_mut().zip(&mut names).zip(solvers(scene)) {
            *name = label;
            let paths = run(scene, &solver);
            if surfaces(&paths) != surfaces(&reference) {
                s.mismatches += 1;
                continue;
            }
            let d = paths
                .iter()
                .zip(&reference)
                .flat_map(|(p, q)| p.points.iter().zip(&q.points).map(|(x, y)| x.distance(*y)))
                .fold(0.0, Real::max);
            s.worst_m = s.worst_m.max(d);
            s.over_1e9 += u32::from(d > 1e-9);
            s.over_1e11 += u32::from(d > 1e-11);
            s.iterations += paths
                .iter()
                .map(|p| u64::from(p.iterations.unwrap_or(0)))
                .sum::<u64>();
        }
    }
    println!(
        "{} corner scenes of {tries} draws (seed 2024)\n",
        scenes.len()
    );
    println!(
        "| solver | worst vs image | scenes > 1e-9 m | scenes > 1e-11 m | scenes with other valid paths | iterations (valid paths) |"
    );
    println!("|---|---:|---:|---:|---:|---:|");
    for (name, s) in names.iter().zip(&stats) {
        println!(
            "| {name} | {:.1e} m | {} | {} | {} | {} |",
            s.worst_m, s.over_1e9, s.over_1e11, s.mismatches, s.iterations
        );
    }
}
