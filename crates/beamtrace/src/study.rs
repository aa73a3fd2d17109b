//! `beamtrace study 2d`, `study living-room` and `study beam-management`: run a study with a progress bar and write
//! its outputs (the studies themselves live in `bt-study`).

use crate::args::{SceneArgs, Study2dArgs, StudyBeamManagementArgs, StudyLivingRoomArgs};
use anyhow::Context;
use bt_study::beam_management::scenario::{ScanSettings, Scenario};
use bt_study::beam_management::{self, BeamManagementConfig};
use bt_study::living_room::{self, LivingRoomConfig};
use bt_study::{StudyConfig, report};
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

pub fn run_2d(args: &Study2dArgs) -> anyhow::Result<ExitCode> {
    let config = StudyConfig {
        rooms: args.rooms,
        steps: args.steps,
        seed: args.seed,
        max_order: args.max_order,
        sbr_step_deg: args.sbr_step_deg,
        sbr_sphere: args.sbr_sphere,
        max_candidates: args.budgets.max_candidates,
        max_room_steps: args.max_room_steps,
    };
    let problems = config.problems();
    if !problems.is_empty() {
        anyhow::bail!("{}", problems.join("; "));
    }
    let sbr = bt_solve::SbrOptions::grid(args.sbr_step_deg);
    let sbr = if args.sbr_sphere { sbr } else { sbr.planar() };
    if let Some(problem) = sbr.over_budget(args.budgets.max_rays) {
        anyhow::bail!("{problem}");
    }
    // indicatif draws to stderr and hides itself when stderr is not a terminal.
    let bar = crate::progress::counter(
        (config.rooms as u64).saturating_mul(config.steps as u64),
        "room-steps",
    );
    let results = bt_study::run(&config, &mut |done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    let done = bt_study::io::write_outputs(&args.out, &results)?;
    crate::files::warn_left_alone(&done);
    let r = report::ratios(&results);
    let headline = format!(
        "{} rooms × {} steps, seed {}: SBR/IPC time {:.3}, SBR error {:.3e}°, IPC error {:.3e}° (ratio {:.2e})",
        config.rooms,
        config.steps,
        config.seed,
        r.sbr_over_ipc_time,
        r.sbr_error_deg,
        r.ipc_error_deg,
        r.sbr_over_ipc_error
    );
    print_headline_and_files(&headline, &done.files);
    Ok(ExitCode::SUCCESS)
}

/// Prints a study's one-line `headline` and the `files` it wrote. Written, not println!: a
/// closed pipe (`| head`) must not panic.
fn print_headline_and_files(headline: &str, files: &[PathBuf]) {
    let mut stdout = std::io::stdout().lock();
    let _ = writeln!(stdout, "{headline}");
    for f in files {
        let _ = writeln!(stdout, "wrote {}", f.display());
    }
}

pub fn run_living_room(args: &StudyLivingRoomArgs) -> anyhow::Result<ExitCode> {
    let config = LivingRoomConfig {
        scene: args.steps_from.clone(),
        max_order: args.max_order,
        sbr_step_deg: args.sbr_step_deg,
        threshold_lsb: args.threshold_lsb,
        max_rounds: args.max_rounds,
        seed: args.seed,
        pe_budget: args.pe_budget,
        warm_start: !args.cold_start,
        round_order: args.round_order.order(),
        ..LivingRoomConfig::default()
    };
    let problems = config.problems();
    if !problems.is_empty() {
        anyhow::bail!("{}", problems.join("; "));
    }
    let loaded = crate::load::load_dynamic(&SceneArgs::defaults_for(&args.steps_from))?;
    let scene = &loaded.scene;
    if let Some(problem) =
        bt_solve::SbrOptions::grid(args.sbr_step_deg).over_budget(args.budgets.max_rays)
    {
        anyhow::bail!("{problem}");
    }
    for step in scene.scenes() {
        bt_solve::pipeline::exhaustive_budget(step, args.max_order, args.budgets.max_candidates)?;
    }
    let bar = crate::progress::counter(scene.len() as u64, "time steps");
    bar.tick();
    let results =
        bt_study::living_room::run(scene, &config, &mut |done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    let done = bt_study::io::write_living_room(&args.out, &results, &loaded.sources)?;
    crate::files::warn_left_alone(&done);
    let h = living_room::report::headline(&results);
    let headline = format!(
        "{} × {} steps, order <= {}: FPGA IPC error {:.3e}° / {:.3e}° (TX / RX), SBR {:.3e}° / {:.3e}° (ratio {:.2e}); FPGA {:.3} ms per step at 50 MHz; SBR/IPC CPU time {:.3}",
        results.scene_name,
        results.steps,
        config.max_order,
        h.fixed_err_deg[0],
        h.fixed_err_deg[1],
        h.sbr_err_deg[0],
        h.sbr_err_deg[1],
        h.sbr_over_fixed_error,
        h.fpga_mean_latency_s * 1e3,
        h.sbr_over_ipc_time
    );
    print_headline_and_files(&headline, &done.files);
    Ok(ExitCode::SUCCESS)
}

pub fn run_beam_management(args: &StudyBeamManagementArgs) -> anyhow::Result<ExitCode> {
    let config = BeamManagementConfig {
        positions: args.positions,
        seed: args.seed,
        truth_max_order: args.max_order,
        truth_diffraction: !args.no_diffraction,
        twin_max_order: args.twin_max_order,
        twin_diffraction: args.twin_diffraction,
        rsrp_noise_db: args.rsrp_noise_db,
        rsrp_step_db: args.rsrp_step_db,
        position_sigmas_m: args.position_sigmas.clone(),
        latencies_s: args.latencies_ms.iter().map(|ms| ms / 1e3).collect(),
        top_k: args.top_k.clone(),
        tx_power_dbm: args.tx_power_dbm,
        scan: ScanSettings {
            density_per_m2: args.scan_density,
            noise_m: args.scan_noise,
            max_points: args.max_scan_points,
            seed: args.seed,
        },
        max_candidates: args.max_candidates,
        ..BeamManagementConfig::default()
    };
    let problems = config.problems();
    if !problems.is_empty() {
        anyhow::bail!("{}", problems.join("; "));
    }
    let names = match args.scenarios.is_empty() {
        true => vec!["living-room".to_string(), "city".to_string()],
        false => args.scenarios.clone(),
    };
    let mut scenarios = Vec::new();
    let mut inputs = Vec::new();
    for name in &names {
        let bar = crate::progress::spinner(&format!("scenario {name}: loading, scanning"));
        let (scenario, sources) = beam_management_scenario(name, &config)?;
        bar.finish_and_clear();
        scenarios.push(scenario);
        inputs.extend(sources);
    }
    let total = beam_management::planned_traces(&scenarios, &config);
    let bar = crate::progress::counter(total as u64, "traces");
    let results = beam_management::run(&scenarios, &config, &mut |done, _| {
        bar.set_position(done as u64)
    })?;
    bar.finish_and_clear();
    let done = bt_study::io::write_beam_management(&args.out, &results, &inputs)?;
    crate::files::warn_left_alone(&done);
    let mut headline = format!(
        "seed {}, {} positions per scenario",
        config.seed, config.positions
    );
    for s in &results.scenarios {
        let of = |name: &str| s.methods.iter().find(|m| m.name == name);
        let part = |name: &str, label: &str| {
            of(name).map_or(String::new(), |m| {
                format!(
                    "; {label}: top-1 {:.3}, loss {:.2} dB mean, {:.1} beams",
                    m.metrics.top1, m.metrics.snr_loss_db_mean, m.metrics.beams_measured
                )
            })
        };
        headline += &format!("\n{}", s.name);
        headline += &part("exhaustive", "exhaustive");
        headline += &part("twin-exact-s0.05m-l0ms-top4", "exact twin top-4 at 5 cm");
    }
    print_headline_and_files(&headline, &done.files);
    Ok(ExitCode::SUCCESS)
}

/// Load the scenario `name` (`living-room`, `city` or a scene file) and build it; returns it
/// and the files read.
fn beam_management_scenario(
    name: &str,
    config: &BeamManagementConfig,
) -> anyhow::Result<(Scenario, Vec<PathBuf>)> {
    let source = beam_management::scenario::source_of(name);
    let loaded = crate::load::load_dynamic(&SceneArgs::defaults_for(source))
        .with_context(|| format!("--scenario {name}"))?;
    let scenario = Scenario::named(name, loaded.scene, config.positions, &config.scan)
        .with_context(|| format!("--scenario {name}"))?;
    Ok((scenario, loaded.sources))
}
