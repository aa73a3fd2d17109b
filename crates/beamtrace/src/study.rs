//! `beamtrace study 2d`: run the 2-D validation study with a progress bar and write its
//! outputs (the study itself lives in `bt-study`).

use crate::args::Study2dArgs;
use anyhow::Context;
use bt_study::{StudyConfig, report};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::Write;
use std::process::ExitCode;

pub fn run_2d(args: &Study2dArgs) -> anyhow::Result<ExitCode> {
    let config = StudyConfig {
        rooms: args.rooms,
        steps: args.steps,
        seed: args.seed,
        max_order: args.max_order,
        sbr_step_deg: args.sbr_step_deg,
        sbr_sphere: args.sbr_sphere,
    };
    let problems = config.problems();
    if !problems.is_empty() {
        anyhow::bail!("{}", problems.join("; "));
    }
    // indicatif draws to stderr and hides itself when stderr is not a terminal.
    let bar = ProgressBar::new((config.rooms * config.steps) as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} room-steps  {elapsed} (eta {eta})")
            .context("progress bar template")?,
    );
    let results = bt_study::run(&config, &mut |done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    let files = bt_study::io::write_outputs(&args.out, &results)?;
    let r = report::ratios(&results);
    // Written, not println!: a closed pipe (`| head`) must not panic.
    let mut stdout = std::io::stdout().lock();
    let _ = writeln!(
        stdout,
        "{} rooms × {} steps, seed {}: SBR/IPC time {:.3}, SBR error {:.3e}°, IPC error {:.3e}° (ratio {:.2e})",
        config.rooms,
        config.steps,
        config.seed,
        r.sbr_over_ipc_time,
        r.sbr_error_deg,
        r.ipc_error_deg,
        r.sbr_over_ipc_error
    );
    for f in files {
        let _ = writeln!(stdout, "wrote {}", f.display());
    }
    Ok(ExitCode::SUCCESS)
}
