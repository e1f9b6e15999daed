//! The `finrs` command line: a thin layer over the `finrs` library.
//!
//! [`cli`] declares the commands and options, [`commands`] runs each one
//! (progress bars, Ctrl-C and the files it writes); this file only parses
//! and dispatches.

mod cli;
mod commands;

use std::process::ExitCode;

use clap::Parser;

use cli::{Cli, Command};

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", chain(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes, `: `-separated as `{:#}` prints them, but a
/// cause the message before it already ends with is said once.
fn chain(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let cause = cause.to_string();
        if !text.ends_with(&cause) {
            text += ": ";
            text += &cause;
        }
    }
    text
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Simulate(args) => commands::simulate(args),
        Command::Params { preset } => commands::params(&preset),
        Command::Fit(args) => commands::fit(args),
        Command::Diagnose(args) => commands::diagnose(args),
        Command::SeedCheck { json } => commands::seed_check(json),
        Command::Log(args) => commands::log(args),
        Command::Run(args) => commands::run(args),
        Command::Wave(args) => commands::wave(args),
        Command::Tare(args) => commands::send(&args, &finrs_frames::Command::Tare),
        Command::Stop(args) => commands::send(&args, &finrs_frames::Command::Stop),
        Command::ClearFault(args) => commands::send(&args, &finrs_frames::Command::ClearFault),
        Command::Limit { max_abs_v, send } => commands::limit(max_abs_v, &send),
    }
}
