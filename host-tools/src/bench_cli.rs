//! `finrs bench run`: reads the protocol (refused before any probe is
//! touched), connects, runs the session through the library
//! ([`finrs::bench`]) with the operator's prompts on the terminal, and
//! diagnoses the session if asked.

use finrs::bench::protocol::Protocol;
use finrs::bench::run::{run_session, BenchOptions};
use finrs::link::capture::{self, Firmware};

use crate::cli::{timeout, BenchRunArgs, BenchWhat, DiagnoseArgs};
use crate::commands::{capture_flags, prompt, StatusLine};

/// `finrs bench ...`.
pub fn run(what: BenchWhat) -> anyhow::Result<()> {
    match what {
        BenchWhat::Run(args) => bench_run(args),
    }
}

fn bench_run(args: BenchRunArgs) -> anyhow::Result<()> {
    let protocol = Protocol::read(&args.protocol)?;
    let opts = BenchOptions {
        timeout: timeout("--timeout-s", args.timeout_s)?,
    };
    let probe = args.probe.options()?;
    let status = StatusLine::new();
    let mut connected = capture::connect(&probe, &Firmware::Running(args.elf.clone()), &status)
        .map_err(capture_flags)?;
    let report = run_session(
        &mut connected.link,
        &protocol,
        &args.out,
        &opts,
        connected.table.as_ref(),
        &mut prompt,
        &status,
    )?;
    drop(status);
    eprintln!(
        "session {}: {} recordings",
        args.out.display(),
        report.written.len()
    );
    if args.diagnose {
        crate::commands::diagnose(DiagnoseArgs {
            session: args.out,
            json: None,
            report: None,
        })?;
    }
    Ok(())
}
