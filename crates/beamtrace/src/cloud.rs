//! `beamtrace extract` (point cloud -> scene file) and `beamtrace sample` (scene -> synthetic
//! point cloud), and loading a point cloud wherever a scene is expected.

use crate::args::{ExtractArgs, SampleArgs};
use anyhow::{Context, bail};
use bt_import::cloud::ReadOptions;
use bt_pointcloud::{ExtractParams, Extraction, PointCloud};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Read a cloud and extract its planes, with a progress bar on stderr.
fn extract_from(
    path: &Path,
    params: &ExtractParams,
    read: &ReadOptions,
) -> anyhow::Result<(Extraction, u64)> {
    let loaded = bt_import::cloud::read_path(path, read)?;
    let (bar, mut progress) = crate::progress::extraction_progress();
    let extraction =
        bt_pointcloud::extract_planes_with_progress(&loaded.cloud, params, &mut progress)
            .with_context(|| format!("extracting planes from {}", path.display()))?;
    bar.finish_and_clear();
    Ok((extraction, loaded.skipped_non_finite))
}

pub fn run_extract(args: &ExtractArgs) -> anyhow::Result<ExitCode> {
    if !(args.min_reflector_area.is_finite() && args.min_reflector_area >= 0.0) {
        bail!(
            "--min-reflector-area must be a finite number of m² >= 0, got {}",
            args.min_reflector_area
        );
    }
    if !(args.distance_threshold.is_finite() && args.distance_threshold > 0.0) {
        bail!(
            "--distance-threshold must be a positive number of metres, got {}",
            args.distance_threshold
        );
    }
    // Refuse a bad output before the (possibly long) extraction.
    let inputs = [args.cloud.clone()];
    // Both outputs are checked before the work, so a bad --report leaves no scene behind.
    crate::files::check(&args.output, &inputs, &["json", "toml"])?;
    let format = bt_output::extension_in(&args.output, &["json", "toml"])?;
    if let Some(report) = &args.report {
        crate::files::check(report, &inputs, &["json"])?;
    }
    let params = ExtractParams {
        seed: args.seed,
        distance_threshold_m: args.distance_threshold,
        min_reflector_area_m2: args.min_reflector_area,
        ..ExtractParams::default()
    };
    let read = ReadOptions {
        max_points: args.max_cloud_points,
        max_file_bytes: args.max_file_bytes,
        ..ReadOptions::default()
    };
    let (extraction, skipped) = extract_from(&args.cloud, &params, &read)?;
    let name = args
        .cloud
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("extracted");
    let desc = bt_import::cloud::cloud_description(
        &extraction,
        name,
        args.tx.map(|v| v.to_array()),
        args.rx.map(|v| v.to_array()),
    );
    let text = bt_import::write_description(&desc, format)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.output.display()))?;
    crate::files::write(&args.output, text.as_bytes(), &inputs, &[format])?;
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
        let text = serde_json::to_string_pretty(r)? + "\n";
        crate::files::write(report, text.as_bytes(), &inputs, &["json"])?;
    }
    Ok(ExitCode::SUCCESS)
}

pub fn run_sample(args: &SampleArgs) -> anyhow::Result<ExitCode> {
    // The named scene before the load (a cloud's extraction can take long), every file the
    // load read after it.
    bt_output::refuse_input(&args.output, &[PathBuf::from(&args.scene.scene)])?;
    bt_output::extension_in(&args.output, &["ply", "pcd"])?;
    let loaded = crate::load::load_scene(&args.scene)?;
    bt_output::refuse_input(&args.output, &loaded.sources)?;
    let polygons: Vec<Vec<glam::DVec3>> = loaded
        .scene
        .surfaces()
        .iter()
        .map(|s| {
            let world = |v: &glam::DVec3| loaded.scene.to_world(*v);
            s.polygon.vertices().iter().map(world).collect()
        })
        .collect();
    let area: f64 = loaded
        .scene
        .surfaces()
        .iter()
        .map(|s| s.polygon.area())
        .sum();
    let estimate = area * args.density;
    if estimate > args.max_points as f64 {
        bail!(
            "point budget exceeded: {estimate:.3e} points ({area:.1} m² at {} pts/m², about {:.1} GB) \
             (budget {}); lower --density or raise the budget with --max-points",
            args.density,
            estimate * 48.0 / 1e9,
            args.max_points
        );
    }
    let cloud: PointCloud =
        bt_pointcloud::sample_polygons(&polygons, args.density, args.noise, args.seed);
    bt_import::cloud::write_path(&cloud, &args.output)
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
