//! `beamtrace sweep`: a coverage sweep over a receiver grid, with a progress bar; writes
//! coverage.csv and the heat map into the output directory.

use crate::args::SweepArgs;
use crate::load::load_scene;
use anyhow::{Context, bail};
use indicatif::{ProgressBar, ProgressStyle};
use std::process::ExitCode;

pub fn run(args: &SweepArgs) -> anyhow::Result<ExitCode> {
    if args.scene.rx.is_some() {
        bail!("sweep takes its receivers from --grid; --rx is not used");
    }
    // Budget first: a grid too large is refused before the scene is even loaded.
    let points = args.grid.points(args.max_points)?;
    let loaded = load_scene(&args.scene)?;
    for w in &loaded.warnings {
        eprintln!("warning: {w}");
    }
    let scene = loaded.scene;
    crate::load::require_terminals(&scene, &[bt_scene::Terminal::Tx], &args.scene)?;
    let options = crate::trace::options_for(&args.solve, &scene)?;
    // Every output checked before the work and the first write: a heat map that could not be
    // written leaves no CSV behind.
    let csv = args.out.join("coverage.csv");
    let stem = args.out.join("coverage");
    for path in [
        csv.clone(),
        stem.with_extension("svg"),
        stem.with_extension("png"),
    ] {
        crate::files::check(&path, &loaded.sources, &[])?;
    }
    // indicatif draws to stderr and hides itself when stderr is not a terminal.
    let bar = ProgressBar::new(points.len() as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:40} {pos}/{len} receivers, {elapsed} elapsed, ETA {eta}",
        )
        .context("progress bar template")?,
    );
    crate::progress::heartbeat(&bar, "sweep");
    let radio = args.coefficient.options().for_order(options.max_order);
    let rows = bt_coverage::sweep(&scene, &points, (&options, &radio), &mut |done, _| {
        bar.set_position(done as u64)
    })?;
    bar.finish_and_clear();
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    crate::files::write(
        &csv,
        bt_coverage::csv(&rows).as_bytes(),
        &loaded.sources,
        &[],
    )?;
    let map = bt_coverage::HeatMap {
        scene: &scene,
        grid: &args.grid,
        rows: &rows,
        quantity: args.map.quantity(),
    };
    let [svg, png] = map.write(&stem)?;
    let skipped = rows
        .iter()
        .filter(|r| matches!(r.status, bt_coverage::PointStatus::Skipped(_)))
        .count();
    println!(
        "{} receivers ({} skipped: on a surface or at the TX) -> {}, {}, {}",
        rows.len(),
        skipped,
        csv.display(),
        svg.display(),
        png.display()
    );
    Ok(ExitCode::SUCCESS)
}
