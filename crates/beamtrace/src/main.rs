//! The `beamtrace` command line: argument parsing and output only; the algorithms live in the
//! library crates.

mod args;
mod channel;
mod cloud;
mod files;
mod hls;
mod load;
mod numbers;
mod output;
mod progress;
mod serve;
mod steps;
mod study;
mod sweep;
mod trace;
mod view;
mod wvrn;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    restore_default_sigpipe();
    exit_cleanly_when_stdout_fails();
    let cli = match args::Cli::try_parse_from(args::with_default_subcommands(std::env::args_os())) {
        Ok(cli) => cli,
        Err(e) => exit_with(e),
    };
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {}", error_chain(&e));
            ExitCode::from(2)
        }
    }
}

/// Print clap's error (or help, or version) and exit as clap does, with the value it refuses
/// cut short as every other message cuts names ([`bt_scene::name::shown`]): a 10 kB argument
/// is not echoed whole.
fn exit_with(e: clap::Error) -> ! {
    use clap::error::{ContextKind, ContextValue};
    let Some(ContextValue::String(value)) = e.get(ContextKind::InvalidValue) else {
        e.exit()
    };
    let text = e.render().to_string();
    eprint!(
        "{}",
        text.replace(value.as_str(), &bt_scene::name::shown(value))
    );
    std::process::exit(e.exit_code())
}

/// The error and its causes joined by `: `, each cause printed once: library errors that show
/// their source in their own message (`{path}: {source}`) would otherwise repeat the OS error.
fn error_chain(e: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if out.contains(&text) {
            continue;
        }
        if !out.is_empty() {
            out.push_str(": ");
        }
        out.push_str(&text);
    }
    out
}

fn run(cli: args::Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        args::Command::Trace(a) => trace::run(&a),
        args::Command::Demo(a) => trace::run(&a.into_trace()),
        args::Command::Wvrn(a) => wvrn::run(&a),
        args::Command::Sweep(a) => sweep::run(&a),
        args::Command::View(a) => view::run(&a),
        args::Command::Channel(a) => channel::run_channel(&a),
        args::Command::Beams(a) => channel::run_beams(&a),
        args::Command::Serve(a) => serve::run(&a),
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
        args::Command::Study {
            command: args::StudyCommand::BeamManagement(a),
        } => study::run_beam_management(&a),
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

/// `println!` panics when stdout cannot be written (`beamtrace ... > /dev/full`): report it as
/// an error with exit code 2 instead of a panic (exit 101). Every other panic keeps the
/// default report.
fn exit_cleanly_when_stdout_fails() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let message = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if message.starts_with("failed printing to stdout") {
            eprintln!(
                "error: writing to stdout: {}",
                message.trim_start_matches("failed printing to stdout: ")
            );
            std::process::exit(2);
        }
        default(info);
    }));
}
