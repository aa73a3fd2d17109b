//! Load times of scene files, fresh and through the load cache (docs/performance.md, "Fast
//! loads"): `cargo run --release -p bt-import --example loadtime -- FILE... [--runs N]`.
//! Best of N in-process wall times (N = 3 by default) of `bt_import::load` and of a cache hit
//! (`LoadCache::load` after one load that writes the entry, in a fresh temporary cache
//! directory), with the surface count and the entry's size. `--only fresh` or `--only hit`
//! times one of the two (the other column shows `-`), for profiling one alone: with
//! `--only hit` one load writes the entry first; with `--only fresh` nothing else runs.
//! `--no-digests` makes the fresh loads `bt_import::load_without_digests`, as the CLI loads
//! without `--cache`.

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
    let digests = match args.iter().position(|a| a == "--no-digests") {
        Some(i) => {
            args.remove(i);
            false
        }
        None => true,
    };
    let fresh_load = |file: &str, options: &LoadOptions| match digests {
        true => bt_import::load(file, options),
        false => bt_import::load_without_digests(file, options, &mut |_| {}),
    };
    let mut only = None;
    if let Some(i) = args.iter().position(|a| a == "--only") {
        only = args.get(i + 1).cloned();
        args.drain(i..(i + 2).min(args.len()));
    }
    let (do_fresh, do_hit) = match only.as_deref() {
        None => (true, true),
        Some("fresh") => (true, false),
        Some("hit") => (false, true),
        Some(other) => panic!("--only fresh|hit, not {other:?}"),
    };
    let dir = std::env::temp_dir().join(format!("bt-loadtime-{}", std::process::id()));
    let cache = LoadCache::at(&dir);
    let options = LoadOptions::default();
    println!("| scene | surfaces | fresh load | cache hit | entry |");
    println!("|---|---:|---:|---:|---:|");
    for file in &args {
        let mut surfaces = 0;
        let mut fresh = None;
        if do_fresh {
            drop(fresh_load(file, &options).expect("loads")); // warm-up, untimed
            fresh = Some(best(runs, || {
                let loaded = fresh_load(file, &options).expect("loads");
                surfaces = loaded.scene.surfaces().len();
                loaded
            }));
        }
        let mut hit = None;
        if do_hit {
            cache.load(file, &options, &mut |_| {}).expect("loads");
            hit = Some(best(runs, || {
                let (loaded, _) = cache.load(file, &options, &mut |_| {}).expect("loads");
                surfaces = loaded.scene.surfaces().len();
                loaded
            }));
        }
        let ms = |t: Option<Duration>| {
            t.map_or("-".into(), |t| format!("{:.1} ms", t.as_secs_f64() * 1e3))
        };
        let entry: u64 = (std::fs::read_dir(&dir).into_iter().flatten())
            .map(|e| {
                e.map(|e| e.metadata().map(|m| m.len()).unwrap_or(0))
                    .unwrap_or(0)
            })
            .sum();
        println!(
            "| {file} | {surfaces} | {} | {} | {:.2} MB |",
            ms(fresh),
            ms(hit),
            entry as f64 / 1e6
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
