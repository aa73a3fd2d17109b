//! Rounds per candidate of one IPC Gauss-Seidel trace of the living room (order 3).
use bt_paths::beamtree::{TreeOptions, candidates};
use bt_scene::Terminals;
use bt_solve::{CandidateOutcome, IpcOptions, Solver, UpdateOrder};
fn main() {
    let scene = bt_import::builtin_scene("living-room", Terminals::default())
        .unwrap()
        .unwrap();
    let set = candidates(&scene, TreeOptions::new(3)).unwrap();
    let opts = IpcOptions::for_scene(&scene, UpdateOrder::GaussSeidel);
    let solver = Solver::Ipc(opts);
    let (mut total, mut blocked_rounds) = (0u64, 0u64);
    let ends = scene.terminals().unwrap();
    for i in 0..set.len() {
        let seq = set.get(i);
        let mut pts = vec![bt_geom::Vec3::ZERO; seq.len()];
        let mut scr = pts.clone();
        let (start, out) = (set.start(i), &mut pts);
        let out = bt_solve::solve_candidate_from(&scene, ends, seq, &solver, start, out, &mut scr);
        let it = match &out {
            CandidateOutcome::Solved { ipc, .. } => ipc.map_or(0, |o| o.iterations()),
            CandidateOutcome::NotConverged(o)
            | CandidateOutcome::LeftPolygon(o)
            | CandidateOutcome::Degenerate(o)
            | CandidateOutcome::Blocked(o) => o.iterations(),
            _ => 0,
        };
        total += it as u64;
        let blocked = matches!(
            out,
            CandidateOutcome::Solved {
                validity: bt_solve::Validity::Blocked { .. },
                ..
            } | CandidateOutcome::Blocked(_)
        );
        if blocked {
            blocked_rounds += it as u64;
        }
        if it > 300 {
            let names: Vec<&str> = seq
                .iter()
                .map(|s| scene.surface(*s).name.as_str())
                .collect();
            println!(
                "{it:6} {:?} {}",
                names,
                if blocked { "blocked" } else { "" }
            );
        }
    }
    println!("total rounds {total}, on blocked candidates {blocked_rounds}");
}
