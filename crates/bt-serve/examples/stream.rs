//! A probe of the serve loop in process: a seeded random walk of receivers in the living room
//! (order 3 unless given), streamed through one `Server` as JSON lines from memory into
//! memory: one request at a time (`answer_line`, as a client that waits for each answer), then
//! the whole stream at once (consecutive moves answered together), then in requests of BATCH
//! receivers. Prints the throughput, the percentiles of `latency_us` and, for one receiver per
//! request, the mean paths and stage times of an answer (docs/performance.md). With
//! `STREAM_TAIL=1` it also prints what the slowest 1 % of the answers are made of and the
//! answers by their number of paths; with `STREAM_ONE=1` it runs the first mode alone, and `STREAM_OUT=FILE`
//! writes that mode's answers to FILE, one a line; `STREAM_PARTNER_US=N` is serve's
//! `--partner-spin-us` (default as serve's). `STREAM_SAME=1` sends the walk's first
//! receiver every time: the same work each answer, so that the spread of `latency_us` is the
//! machine's, not the data's.
//!
//! `cargo run --release -p bt-serve --example stream -- [MOVES] [MAX_ORDER] [BATCH]`

use bt_beams::RadioOptions;
use bt_serve::{Limits, Server};
use bt_solve::settings::SolveSettings;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = |i: usize, default: usize| -> Result<usize, Box<dyn std::error::Error>> {
        match std::env::args().nth(i) {
            Some(v) => Ok(v
                .parse()
                .map_err(|e| format!("argument {i} ({v:?}): {e}"))?),
            None => Ok(default),
        }
    };
    let (moves, max_order, batch) = (arg(1, 10_000)?, arg(2, 3)?, arg(3, 100)?.max(1));
    let mut walk = walk(30, moves);
    if std::env::var_os("STREAM_SAME").is_some() {
        let first = walk[0];
        walk.fill(first);
    }
    let single: Vec<String> = (walk.iter().enumerate())
        .map(|(i, p)| format!("{{\"id\":{i},\"rx\":[{},{},{}]}}", p[0], p[1], p[2]))
        .collect();
    let batched: Vec<String> = (walk.chunks(batch).enumerate())
        .map(|(i, chunk)| {
            let list: Vec<String> = chunk
                .iter()
                .map(|p| format!("[{},{},{}]", p[0], p[1], p[2]))
                .collect();
            format!("{{\"id\":{i},\"rx\":[{}]}}", list.join(","))
        })
        .collect();
    println!("living room, order {max_order}, {moves} receiver moves (seed 30)");
    // A client that waits for each answer before its next request: answered alone.
    let (seconds, latencies) = one_at_a_time(max_order, &single)?;
    report("1 at a time", moves, seconds, &latencies);
    // `STREAM_ONE=1`: that mode alone (for profiles of one answer at a time).
    if std::env::var_os("STREAM_ONE").is_some() {
        return Ok(());
    }
    for (name, lines) in [("1 per request", &single), ("batched", &batched)] {
        let (seconds, latencies) = stream(max_order, lines)?;
        report(name, moves, seconds, &latencies);
    }
    Ok(())
}

/// Prints the throughput and the percentiles of the sorted `latencies`.
fn report(name: &str, moves: usize, seconds: f64, latencies: &[f64]) {
    let per_move = seconds / moves as f64 * 1e6;
    let p = |q: f64| latencies[((latencies.len() - 1) as f64 * q) as usize];
    println!(
        "{name:>14}: {:>8.0} moves/s, {per_move:>6.1} us per move; latency_us per request \
         p50 {:.1} p99 {:.1} max {:.1} ({} requests)",
        moves as f64 / seconds,
        p(0.5),
        p(0.99),
        p(1.0),
        latencies.len()
    );
}

/// Answers `lines` one at a time (`Server::answer_line`, nothing else waiting: no batch), as
/// a client that waits for each answer; the wall time and each answer's `latency_us`, sorted.
fn one_at_a_time(
    max_order: usize,
    lines: &[String],
) -> Result<(f64, Vec<f64>), Box<dyn std::error::Error>> {
    let mut server = server(max_order)?;
    // The answers are kept in one buffer reserved up front (its pages untouched until
    // written): a copy of each answer on the heap would take the memory the next answer's
    // own allocations freed, and put those on fresh pages (page faults inside `latency_us`
    // that `serve`, which writes each answer out and reuses its buffer, does not have).
    let mut answers = Vec::with_capacity(lines.len() * 64 * 1024);
    let mut ends = Vec::with_capacity(lines.len());
    let mut out = Vec::new();
    let t0 = Instant::now();
    for line in lines {
        server.answer_line(line.as_bytes(), &mut out);
        answers.extend_from_slice(&out);
        ends.push(answers.len());
    }
    let seconds = t0.elapsed().as_secs_f64();
    // `STREAM_OUT=FILE`: the answers, one a line, to compare builds.
    if let Some(path) = std::env::var_os("STREAM_OUT") {
        let mut file = std::io::BufWriter::new(std::fs::File::create(path)?);
        let starts = std::iter::once(0).chain(ends.iter().copied());
        for (a, &b) in starts.zip(&ends) {
            std::io::Write::write_all(&mut file, &answers[a..b])?;
            std::io::Write::write_all(&mut file, b"\n")?;
        }
    }
    let starts = std::iter::once(0).chain(ends.iter().copied());
    latencies(starts.zip(&ends).map(|(a, &b)| &answers[a..b]), seconds)
}

/// Each answer's `latency_us`, sorted, beside `seconds`.
fn latencies<'a>(
    answers: impl Iterator<Item = &'a [u8]>,
    seconds: f64,
) -> Result<(f64, Vec<f64>), Box<dyn std::error::Error>> {
    // One receiver's answers: its latency, paths and stage times (a list's are inside
    // `results`, not counted).
    let mut each = Vec::new();
    for line in answers.filter(|l| !l.is_empty()) {
        let v: serde_json::Value = serde_json::from_slice(line)?;
        let Some(latency) = v["latency_us"].as_f64() else {
            continue;
        };
        let stage = |s: &str| v["stats"]["time_s"][s].as_f64().unwrap_or(0.0) * 1e6;
        let paths = v["paths"].as_array().map_or(0, Vec::len);
        let stages = [stage("candidates"), stage("solve"), stage("report")];
        each.push(Sample {
            latency,
            paths,
            stages,
        });
    }
    if each.iter().any(|s| s.paths > 0) {
        println!("{:>14}  per answer: {}", "", Sample::mean(&each));
        // What the slowest answers are made of (`STREAM_TAIL=1`): the slowest 1 % beside
        // all, and the answers by their number of paths.
        if std::env::var_os("STREAM_TAIL").is_some() {
            tail(&mut each);
        }
    }
    let mut latencies: Vec<f64> = each.iter().map(|s| s.latency).collect();
    latencies.sort_by(f64::total_cmp);
    Ok((seconds, latencies))
}

/// One answer of a lone receiver: its `latency_us`, paths and stage times (µs).
struct Sample {
    latency: f64,
    paths: usize,
    stages: [f64; 3],
}

impl Sample {
    /// The mean of `samples`' paths, stages, latency and the rest (JSON, reply) as text.
    fn mean(samples: &[Sample]) -> String {
        let n = samples.len().max(1) as f64;
        let sum = |f: &dyn Fn(&Sample) -> f64| samples.iter().map(f).sum::<f64>() / n;
        let [c, s, r] = [0, 1, 2].map(|k| sum(&|x: &Sample| x.stages[k]));
        let latency = sum(&|x: &Sample| x.latency);
        format!(
            "{:.1} paths; candidates {c:.1} us, solve {s:.1} us, report {r:.1} us, rest \
             {:.1} us; latency {latency:.1} us ({} answers)",
            sum(&|x: &Sample| x.paths as f64),
            latency - c - s - r,
            samples.len()
        )
    }
}

/// Print the slowest 1 % of `samples` beside the rest, and the samples by paths.
fn tail(samples: &mut [Sample]) {
    samples.sort_by(|a, b| a.latency.total_cmp(&b.latency));
    let cut = samples.len() * 99 / 100;
    println!(
        "{:>14}  fastest 99 %: {}",
        "",
        Sample::mean(&samples[..cut])
    );
    println!("{:>14}  slowest 1 %: {}", "", Sample::mean(&samples[cut..]));
    samples.sort_by_key(|s| s.paths);
    for bin in samples.chunk_by(|a, b| a.paths / 20 == b.paths / 20) {
        let mut l: Vec<f64> = bin.iter().map(|s| s.latency).collect();
        l.sort_by(f64::total_cmp);
        println!(
            "{:>14}  {:>3}-{:<3} paths: p50 {:.1} p99 {:.1}; {}",
            "",
            bin[0].paths / 20 * 20,
            bin[0].paths / 20 * 20 + 19,
            l[l.len() / 2],
            l[(l.len() - 1) * 99 / 100],
            Sample::mean(bin)
        );
    }
}

/// A server of the living room at `max_order`, as `beamtrace serve` makes it.
fn server(max_order: usize) -> Result<Server, Box<dyn std::error::Error>> {
    let options = bt_import::LoadOptions::default();
    let dynamic = bt_import::load_dynamic("builtin:living-room", &options, &mut |_| {})?.scene;
    let settings = SolveSettings {
        max_order,
        ..SolveSettings::default()
    };
    let options = settings.trace_options(dynamic.step(0))?;
    let server = Server::new(dynamic, options, RadioOptions::default(), Limits::default());
    // `STREAM_PARTNER_US=N`: serve's `--partner-spin-us` (0: every answer on one thread).
    let spin = match std::env::var("STREAM_PARTNER_US") {
        Ok(v) => v
            .parse()
            .map_err(|e| format!("STREAM_PARTNER_US ({v:?}): {e}"))?,
        Err(_) => bt_serve::PARTNER_SPIN_US,
    };
    Ok(server.with_partner(std::time::Duration::from_micros(spin)))
}

/// Streams `lines` through a fresh server; the wall time of the whole stream and each
/// answer's `latency_us`, sorted.
fn stream(
    max_order: usize,
    lines: &[String],
) -> Result<(f64, Vec<f64>), Box<dyn std::error::Error>> {
    let mut server = server(max_order)?;
    let input = lines.join("\n");
    let mut output = Vec::with_capacity(input.len() * 64);
    let t0 = Instant::now();
    let summary = server.serve(input.as_bytes(), &mut output)?;
    let seconds = t0.elapsed().as_secs_f64();
    // Receivers of the walk that lie on a surface (a seat, a shelf) get error lines.
    println!(
        "{:>14}  {} requests, {} error answers",
        "", summary.requests, summary.errors
    );
    latencies(output.split(|&b| b == b'\n'), seconds)
}

/// The seeded walk of the tests: 0.2 m steps on a millimetre grid, 0.3 m from the walls.
fn walk(seed: u64, n: usize) -> Vec<[f64; 3]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut p: [f64; 3] = [2.3, 2.1, 0.72];
    let bounds: [(f64, f64); 3] = [(0.3, 5.7), (0.3, 4.2), (0.3, 2.4)];
    (0..n)
        .map(|_| {
            for (x, (lo, hi)) in p.iter_mut().zip(bounds) {
                let next = (*x + rng.random_range(-0.2..0.2)).clamp(lo, hi);
                *x = (next * 1e3).round() / 1e3;
            }
            p
        })
        .collect()
}
