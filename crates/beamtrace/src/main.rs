//! The `beamtrace` command line: argument parsing and output only; the algorithms live in the
//! library crates.

mod args;
mod channel;
mod cloud;
mod hls;
mod output;
mod steps;
mod study;
mod trace;
mod wvrn;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    restore_default_sigpipe();
    let cli = args::Cli::parse_from(args::with_default_subcommands(std::env::args_os()));
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn run(cli: args::Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        args::Command::Trace(a) => trace::run(&a),
        args::Command::Demo(a) => trace::run(&a.into_trace()),
        args::Command::Wvrn(a) => wvrn::run(&a),
        args::Command::Channel(a) => channel::run_channel(&a),
        args::Command::Beams(a) => channel::run_beams(&a),
        args::Command::Extract(a) => cloud::run_extract(&a),
        args::Command::Hls(a) => hls::run(&a),
        args::Command::Sample(a) => cloud::run_sample(&a),
        args::Command::Scene {
            command: args::SceneCommand::Check(a),
        } => trace::check(&a),
        args::Command::Study {
            command: args::StudyCommand::TwoD(a),
        } => study::run_2d(&a),
        args::Command::Study {
            command: args::StudyCommand::LivingRoom(a),
        } => study::run_living_room(&a),
    }
}

/// Rust ignores SIGPIPE, so `beamtrace ... | head` would panic on the closed pipe; restore the
/// default action (end quietly), as every Unix filter does.
fn restore_default_sigpipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in main, before any thread exists; SIG_DFL is a valid action.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
