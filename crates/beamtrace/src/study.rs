//! `beamtrace study 2d` and `study living-room`: run a study with a progress bar and write
//! its outputs (the studies themselves live in `bt-study`).

use crate::args::{SceneArgs, Study2dArgs, StudyLivingRoomArgs};
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
        schedule: args.schedule.kind(),
        seed: args.seed,
        ga_population: args.ga_population,
        ga_generations: args.ga_generations,
        pe_budget: args.pe_budget,
        warm_start: !args.cold_start,
        round_order: args.round_order.order(),
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
