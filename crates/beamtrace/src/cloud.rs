//! `beamtrace extract` (point cloud -> scene file) and `beamtrace sample` (scene -> synthetic
//! point cloud), and loading a point cloud wherever a scene is expected.

use crate::args::{ExtractArgs, SampleArgs};
use anyhow::{Context, bail};
use bt_pointcloud::io::ReadOptions;
use bt_pointcloud::{ExtractParams, Extraction, PointCloud, Progress};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::Path;
use std::process::ExitCode;

/// A progress bar for plane extraction on stderr, shown from the first report on, and the
/// callback that feeds it.
pub fn extraction_progress() -> (ProgressBar, impl FnMut(Progress)) {
    let bar = ProgressBar::hidden();
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} extracting planes {bar:30} {pos}/{len} points assigned, {msg}",
        )
        .expect("static template"),
    );
    let feed = bar.clone();
    let callback = move |p: Progress| {
        if feed.is_hidden() {
            feed.set_draw_target(ProgressDrawTarget::stderr());
        }
        feed.set_length(p.points_total as u64);
        feed.set_position(p.points_assigned as u64);
        feed.set_message(format!("{} planes", p.ransac_planes));
    };
    (bar, callback)
}

/// Read a cloud and extract its planes, with a progress bar on stderr.
fn extract_from(path: &Path, params: &ExtractParams) -> anyhow::Result<(Extraction, u64)> {
    let loaded = bt_pointcloud::io::read_path(path, &ReadOptions::default())?;
    let (bar, mut progress) = extraction_progress();
    let extraction =
        bt_pointcloud::extract_planes_with_progress(&loaded.cloud, params, &mut progress)
            .with_context(|| format!("extracting planes from {}", path.display()))?;
    bar.finish_and_clear();
    Ok((extraction, loaded.skipped_non_finite))
}

pub fn run_extract(args: &ExtractArgs) -> anyhow::Result<ExitCode> {
    let params = ExtractParams {
        seed: args.seed,
        distance_threshold_m: args.distance_threshold,
        min_reflector_area_m2: args.min_reflector_area,
        ..ExtractParams::default()
    };
    let (extraction, skipped) = extract_from(&args.cloud, &params)?;
    let name = args
        .cloud
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("extracted");
    let desc = bt_scene::io::cloud_description(
        &extraction,
        name,
        args.tx.map(|v| v.to_array()),
        args.rx.map(|v| v.to_array()),
    );
    let json = serde_json::to_string_pretty(&desc)?;
    std::fs::write(&args.output, json + "\n")
        .with_context(|| format!("writing {}", args.output.display()))?;
    let r = &extraction.report;
    println!(
        "{}: {} points ({} skipped as non-finite) -> {} planes ({} reflectors >= {} m², {} blockers), {} inliers, RMS {:.4} m, {:.2} m² in all, {} leftover points, seed {}",
        args.cloud.display(),
        r.input_points,
        skipped,
        r.planes_found,
        r.reflectors,
        params.min_reflector_area_m2,
        r.blockers,
        r.inliers,
        r.rms_m,
        r.total_area_m2,
        r.leftover_points,
        r.seed
    );
    println!("wrote {}", args.output.display());
    if let Some(report) = &args.report {
        std::fs::write(report, serde_json::to_string_pretty(r)? + "\n")
            .with_context(|| format!("writing {}", report.display()))?;
    }
    Ok(ExitCode::SUCCESS)
}

pub fn run_sample(args: &SampleArgs) -> anyhow::Result<ExitCode> {
    if !(args.density > 0.0 && args.density.is_finite()) {
        bail!(
            "--density must be a positive number of points per m², got {}",
            args.density
        );
    }
    if !(args.noise >= 0.0 && args.noise.is_finite()) {
        bail!(
            "--noise must be a non-negative number of metres, got {}",
            args.noise
        );
    }
    let loaded = crate::trace::load_scene(&args.scene)?;
    let polygons: Vec<Vec<glam::DVec3>> = loaded
        .scene
        .surfaces()
        .iter()
        .map(|s| s.polygon.vertices().to_vec())
        .collect();
    let cloud: PointCloud =
        bt_pointcloud::sample_polygons(&polygons, args.density, args.noise, args.seed);
    bt_pointcloud::io::write_path(&cloud, &args.output)
        .with_context(|| format!("writing {}", args.output.display()))?;
    println!(
        "{} points from {} surfaces ({} pts/m², noise σ {} m, seed {}) -> {}",
        cloud.len(),
        polygons.len(),
        args.density,
        args.noise,
        args.seed,
        args.output.display()
    );
    Ok(ExitCode::SUCCESS)
}
