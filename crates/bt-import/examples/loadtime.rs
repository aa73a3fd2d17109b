//! Load times of scene files, fresh and through the load cache (docs/performance.md, "Fast
//! loads"): `cargo run --release -p bt-import --example loadtime -- FILE... [--runs N]`.
//! Best of N in-process wall times (N = 3 by default) of `bt_import::load` and of a cache hit
//! (`LoadCache::load` after one load that writes the entry, in a fresh temporary cache
//! directory), with the surface count and the entry's size.

use bt_import::LoadOptions;
use bt_import::cache::LoadCache;
use std::time::{Duration, Instant};

/// The shortest of `runs` calls of `f`; what it returns is dropped outside the timing.
fn best<T>(runs: usize, mut f: impl FnMut() -> T) -> Duration {
    (0..runs)
        .map(|_| {
            let start = Instant::now();
            let made = f();
            let took = start.elapsed();
            drop(made);
            took
        })
        .min()
        .unwrap_or_default()
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut runs = 3;
    if let Some(i) = args.iter().position(|a| a == "--runs") {
        runs = args.get(i + 1).and_then(|n| n.parse().ok()).unwrap_or(3);
        args.drain(i..(i + 2).min(args.len()));
    }
    let dir = std::env::temp_dir().join(format!("bt-loadtime-{}", std::process::id()));
    let cache = LoadCache::at(&dir);
    let options = LoadOptions::default();
    println!("| scene | surfaces | fresh load | cache hit | entry |");
    println!("|---|---:|---:|---:|---:|");
    for file in &args {
        let loaded = bt_import::load(file, &options).expect("loads");
        let fresh = best(runs, || {
            drop(bt_import::load(file, &options).expect("loads"))
        });
        cache.load(file, &options, &mut |_| {}).expect("loads");
        let hit = best(runs, || {
            drop(cache.load(file, &options, &mut |_| {}).expect("loads"))
        });
        let entry: u64 = (std::fs::read_dir(&dir).expect("cache written"))
            .map(|e| {
                e.map(|e| e.metadata().map(|m| m.len()).unwrap_or(0))
                    .unwrap_or(0)
            })
            .sum();
        println!(
            "| {file} | {} | {:.1} ms | {:.1} ms | {:.2} MB |",
            loaded.scene.surfaces().len(),
            fresh.as_secs_f64() * 1e3,
            hit.as_secs_f64() * 1e3,
            entry as f64 / 1e6
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
