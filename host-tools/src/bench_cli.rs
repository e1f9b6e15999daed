//! `finrs bench run`: reads the protocol (refused before any probe is
//! touched), connects, runs the session through the library
//! ([`finrs::bench`]) with the operator's prompts on the terminal, and
//! diagnoses the session if asked. `finrs bench live`: the library's live
//! view on the real terminal, its keys read from it.

use finrs::bench::run::{run_session, BenchOptions};
use finrs::link::capture::{self, Firmware, Monitor};
use finrs::link::defmt_log::{no_table_notice, Table};
use finrs::link::qemu::{Pace, VirtualBoard, QEMU};
use finrs::protocol::Protocol;

/// How long the virtual board is waited for, s (`bench run --qemu`'s
/// answers when `--timeout-s` is not given, `bench live --qemu`'s first
/// frame): QEMU's emulated floating point inverts a model several times
/// slower than the board, and a CI runner's busy cores slow it again.
const QEMU_WAIT_S: f64 = 60.0;

use crate::cli::{timeout, BenchLiveArgs, BenchRunArgs, BenchWhat, DiagnoseArgs};
use crate::commands::{capture_flags, prompt, StatusLine};

/// `finrs bench ...`.
pub fn run(what: BenchWhat) -> anyhow::Result<()> {
    match what {
        BenchWhat::Run(args) => bench_run(args),
        BenchWhat::Live(args) => bench_live(args),
    }
}

fn bench_live(args: BenchLiveArgs) -> anyhow::Result<()> {
    if let Some(path) = &args.from_bytes {
        let opts = args.record.options(format!(
            "the byte dump {} (finrs bench live)",
            path.display()
        ))?;
        let mut replay = finrs::link::replay::Replay::read(path)?;
        return live_on(&mut replay, None, &opts);
    }
    if let Some(elf) = &args.qemu {
        let opts = args.record.options(format!(
            "the virtual bench, {} in QEMU (finrs bench live)",
            elf.display()
        ))?;
        let started = VirtualBoard::start(
            QEMU,
            elf,
            Pace::RealTime,
            std::time::Duration::from_secs_f64(QEMU_WAIT_S),
        )?;
        if started.table.is_none() {
            // Before the view takes the screen: left on it when the view ends.
            eprintln!("{}", no_table_notice(&elf.display().to_string()));
        }
        let mut board = started.board;
        return live_on(&mut board, started.table.as_ref(), &opts);
    }
    let probe = args.probe.options()?;
    let opts = args.record.options(format!(
        "RTT up channel {} on {} (finrs bench live)",
        finrs::link::probe::FORCE_UP_CHANNEL,
        probe.chip
    ))?;
    let mut connected = {
        let status = StatusLine::new();
        capture::connect(&probe, &Firmware::Running(args.elf.clone()), &status)
            .map_err(capture_flags)?
    };
    live_on(&mut connected.link, connected.table.as_ref(), &opts)
}

/// The live view on the real terminal.
fn live_on(
    board: &mut impl finrs::link::board::Board,
    table: Option<&Table>,
    opts: &finrs::link::capture::CaptureOptions,
) -> anyhow::Result<()> {
    use finrs::bench::live::{run_live, Key};
    use ratatui::crossterm::event::{self, Event, KeyCode, KeyEventKind};
    // The terminal in raw mode on its alternate screen, put back whatever
    // happens (ratatui's panic hook restores it too).
    let mut term = ratatui::try_init()?;
    let mut keys = || -> std::io::Result<Option<Key>> {
        while event::poll(std::time::Duration::ZERO)? {
            if let Event::Key(k) = event::read()? {
                if k.kind != KeyEventKind::Press {
                    continue;
                }
                return Ok(match k.code {
                    KeyCode::Char(c) => Some(Key::Char(c)),
                    KeyCode::Enter => Some(Key::Enter),
                    KeyCode::Esc => Some(Key::Esc),
                    KeyCode::Backspace => Some(Key::Backspace),
                    _ => continue,
                });
            }
        }
        Ok(None)
    };
    let result = run_live(board, table, opts, &mut term, &mut keys);
    ratatui::restore();
    eprint!("{}", result?);
    Ok(())
}

/// The wait for the board's answers when `--timeout-s` is not given.
fn default_wait_s(args: &BenchRunArgs) -> f64 {
    if args.qemu.is_some() {
        QEMU_WAIT_S
    } else {
        10.0
    }
}

fn bench_run(args: BenchRunArgs) -> anyhow::Result<()> {
    let protocol = Protocol::read(&args.protocol)?;
    let opts = BenchOptions {
        timeout: timeout(
            "--timeout-s",
            args.timeout_s.unwrap_or(default_wait_s(&args)),
        )?,
    };
    let status = StatusLine::new();
    let report = if let Some(elf) = &args.qemu {
        let started = VirtualBoard::start(QEMU, elf, Pace::Fast, opts.timeout)?;
        if started.table.is_none() {
            status.line(&no_table_notice(&elf.display().to_string()));
        }
        let mut board = started.board;
        // No operator at a virtual bench: the prompt is shown and passed.
        let mut show = |text: &str| {
            status.line(&format!("(virtual bench, not waiting) {text}"));
            Ok(())
        };
        run_session(
            &mut board,
            &protocol,
            &args.out,
            &opts,
            started.table.as_ref(),
            &mut show,
            &status,
        )?
    } else {
        let probe = args.probe.options()?;
        let mut connected = capture::connect(&probe, &Firmware::Running(args.elf.clone()), &status)
            .map_err(capture_flags)?;
        run_session(
            &mut connected.link,
            &protocol,
            &args.out,
            &opts,
            connected.table.as_ref(),
            &mut prompt,
            &status,
        )?
    };
    drop(status);
    eprintln!(
        "session {}: {} recordings{}",
        args.out.display(),
        report.written.len(),
        match report.tracks.len() {
            0 => String::new(),
            n => format!(
                ", {n} camera tracks in {} (finrs merge-camera each)",
                args.out.join("tracks").display()
            ),
        }
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
