//! The `finrs` command line: a thin layer over the `finrs` library.
//!
//! [`cli`] declares the commands and options, [`commands`] runs each one
//! (progress bars, Ctrl-C and the files it writes), [`calibrate`] the
//! board's calibration and model, [`bench_cli`] a session by protocol,
//! [`import_cli`] a lab's exports made recordings, [`stages`]
//! a long run's time per stage, [`new_folders`] the folders made for
//! outputs; this file
//! only parses and dispatches.

mod bench_cli;
mod calibrate;
mod cli;
mod commands;
mod import_cli;
mod new_folders;
mod stages;

use std::process::ExitCode;

use clap::Parser;

use cli::{Cli, Command};

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // `{:#}`: the error and its causes, `: `-separated; each
            // library error says its cause only as source(), so once.
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Simulate(args) => commands::simulate(args),
        Command::Params { preset } => commands::params(&preset),
        Command::Fit(args) => commands::fit(args),
        Command::Diagnose(args) => commands::diagnose(args),
        Command::Plan(args) => commands::plan(args),
        Command::SeedCheck { json } => commands::seed_check(json),
        Command::Log(args) => commands::log(args),
        Command::Run(args) => commands::run(args),
        Command::Wave(args) => commands::wave(args),
        Command::Tare(args) => commands::send(&args, &finrs_frames::Command::Tare),
        Command::Stop(args) => commands::send(&args, &finrs_frames::Command::Stop),
        Command::ClearFault(args) => commands::send(&args, &finrs_frames::Command::ClearFault),
        Command::Limit { max_abs_v, send } => commands::limit(max_abs_v, &send),
        Command::Calibrate { what } => calibrate::run(what),
        Command::Tune(args) => calibrate::tune(args),
        Command::Bench { what } => bench_cli::run(what),
        Command::MergeCamera(args) => commands::merge_camera(args),
        Command::Import(args) => import_cli::run(args),
    }
}
