//! The same model core, in `f32`, on x86 and on a Cortex-M4F in QEMU.
//!
//! The test builds `finrs-qemu-tests` for thumbv7em-none-eabihf (its own
//! target directory, so it cannot wait on this `cargo test`'s lock), runs it
//! in `qemu-system-arm -machine netduinoplus2` with semihosting, and
//! compares every number with the same scenarios run here.
//!
//! Tolerance: both targets do IEEE-754 single precision with the same
//! operation order (Rust does not contract `a * b + c` into a fused
//! multiply-add unless asked), and the discretisation runs in `f64` on both
//! with the same `libm`. We measured the two outputs bit-identical; the test
//! still allows 4 units in the last place of `f32` (relative 5e-7, with a
//! floor at 1e-12 of the scenario's largest value) so that a compiler's
//! legitimate choice of instruction cannot fail it, while any real
//! divergence of the model (orders of magnitude larger) does.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod common;

fn build_elf() -> PathBuf {
    build_dir().join("finrs-qemu-tests")
}

/// The QEMU test programs' folder, every program of the package built.
fn build_dir() -> PathBuf {
    common::build_release(
        &common::workspace(),
        "finrs-qemu-tests",
        |_| {},
        "building the QEMU program failed (is the target installed? run scripts/setup)",
    )
}

/// The board's shaper at N = 6 (`MAX_SHAPED_SEGMENTS`) on the Cortex-M4F:
/// every motion's program needs no more stack than a SetModel's check
/// plus 16 KiB (the force wave builds the model's held strip inside its
/// program), as `shape_stack` measures and checks; its numbers are
/// printed (docs/model.md quotes them).
#[test]
fn the_shapers_motions_fit_the_stack_a_models_check_needs() {
    let out = run_qemu(&build_dir().join("shape_stack"), None);
    eprint!("{out}");
    assert_eq!(out.lines().count(), 4, "{out}");
}

/// The `-icount` shift `store_cost` runs under: 8 ns of the guest's clock
/// an instruction, 1.344 SysTick counts at 168 MHz.
const STORE_ICOUNT_SHIFT: u32 = 3;

/// One calibration store on the Cortex-M4F after 0, 1 000, 4 095 and
/// 4 096 records (#50, part 1): it reads back the one record it wrote,
/// whatever the log holds, and executes the same instructions within 2 %
/// (a store made to scan the log first, as one did before #50, read the
/// whole 256 KiB region each time); only the 4 096th erases first.
/// Its numbers are printed (docs/firmware.md quotes them).
#[test]
fn a_store_costs_the_same_however_full_the_log() {
    let out = run_qemu(&build_dir().join("store_cost"), Some(STORE_ICOUNT_SHIFT));
    let per_instruction = 168e6 * f64::from(1u32 << STORE_ICOUNT_SHIFT) * 1e-9;
    let rows: Vec<(u32, u32, f64, bool)> = out
        .lines()
        .map(|line| {
            let f: Vec<u32> = line
                .split(' ')
                .map(|w| w.parse().unwrap_or_else(|_| panic!("bad line `{line}`")))
                .collect();
            assert_eq!(f.len(), 4, "bad line `{line}`");
            (f[0], f[1], f64::from(f[2]) / per_instruction, f[3] == 1)
        })
        .collect();
    for &(records, bytes, instructions, erased) in &rows {
        eprintln!(
            "store after {records} records: {bytes} bytes read, {instructions:.0} instructions{}",
            if erased { ", an erase first" } else { "" }
        );
    }
    let filled: Vec<u32> = rows.iter().map(|r| r.0).collect();
    assert_eq!(filled, [0, 1000, 4095, 4096], "{out}");
    let empty = rows[0].2;
    for &(records, bytes, instructions, erased) in &rows {
        assert_eq!(bytes, 32, "after {records} records: {out}");
        assert_eq!(erased, records == 4096, "after {records} records: {out}");
        assert!(
            (instructions - empty).abs() <= 0.02 * empty && instructions < 5_000.0,
            "after {records} records: {instructions:.0} instructions against {empty:.0} on an empty log"
        );
    }
}

/// Runs `elf` in QEMU, under `-icount shift=S` if given; its stdout, the
/// run having succeeded.
fn run_qemu(elf: &Path, icount_shift: Option<u32>) -> String {
    let run = qemu(elf, icount_shift, &[], Duration::from_secs(300));
    let status = run
        .status
        .unwrap_or_else(|| panic!("QEMU did not finish in 300 s"));
    assert!(
        status.success(),
        "QEMU run failed ({status}): {}",
        run.stderr
    );
    run.stdout
}

/// How a QEMU run ended.
struct Run {
    /// `None` if it was stopped at the time limit.
    status: Option<std::process::ExitStatus>,
    stdout: String,
    stderr: String,
}

/// Runs `elf` in QEMU, under `-icount shift=S` if given, with `args` on
/// its semihosting command line after the program's name, for at most
/// `limit`.
fn qemu(elf: &Path, icount_shift: Option<u32>, args: &[&str], limit: Duration) -> Run {
    let mut qemu = Command::new("qemu-system-arm");
    qemu.args([
        "-cpu",
        "cortex-m4",
        "-machine",
        "netduinoplus2",
        "-nographic",
    ]);
    if let Some(shift) = icount_shift {
        qemu.args(["-icount", &format!("shift={shift},align=off,sleep=off")]);
    }
    let mut semihosting = "enable=on,target=native,arg=program".to_string();
    for a in args {
        semihosting += &format!(",arg={a}");
    }
    let mut child = qemu
        .args(["-semihosting-config", &semihosting, "-kernel"])
        .arg(elf)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("qemu-system-arm is installed (run scripts/setup)");
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break Some(status);
        }
        if start.elapsed() > limit {
            child.kill().unwrap();
            break None;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let out = child.wait_with_output().unwrap();
    Run {
        status,
        stdout: String::from_utf8(out.stdout).expect("the program prints UTF-8"),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// A stack overflow on the Cortex-M4F (#50, part 3), `stack_guard`'s
/// recursion of 1 KiB frames. With the board's guard and handler
/// (`finrs_firmware_support::stack_guard`), in thread mode as an RTIC
/// task runs, the MemManage handler is reached on the stack's top again
/// (where the firmware zeroes the outputs), the fault a data access or
/// a stacking error in the guard, after tens of KiB of recursion; with
/// interrupts masked (init, a critical section) the fault escalates to
/// HardFault, whose handler runs (the MPU is off for it, so the guard is
/// RAM to stack on). Without the guard, as the board was, the core locks
/// up (QEMU stops with `Lockup`, or runs on, stopped here after 20 s).
#[test]
fn a_stack_overflow_reaches_the_guards_handler() {
    let elf = build_dir().join("stack_guard");
    let limit = Duration::from_secs(20);

    let guarded = qemu(&elf, None, &["guarded"], limit);
    let status = guarded.status.expect("the guarded run ends");
    assert!(status.success(), "guarded: {status}: {}", guarded.stderr);
    let f: Vec<u64> = guarded
        .stdout
        .trim()
        .strip_prefix("reached ")
        .unwrap_or_else(|| panic!("guarded: no handler line in `{}`", guarded.stdout))
        .split(' ')
        .map(|w| {
            let w = w.trim_start_matches("0x");
            u64::from_str_radix(w, if w.len() == 8 { 16 } else { 10 }).unwrap()
        })
        .collect();
    let (mstkerr, daccviol, depth) = (f[0], f[1], f[3]);
    eprintln!("guarded: {}", guarded.stdout.trim());
    assert!(
        mstkerr == 1 || daccviol == 1,
        "a MemManage fault of the guard: {f:?}"
    );
    assert!(depth > 32, "the recursion used the stack first: {f:?}");

    let masked = qemu(&elf, None, &["masked"], limit);
    eprintln!("masked: {:?} {}", masked.status, masked.stderr.trim());
    assert_eq!(
        masked.status.and_then(|s| s.code()),
        Some(1),
        "{}",
        masked.stderr
    );
    assert!(masked.stderr.contains("HardFault"), "{}", masked.stderr);
    assert!(!masked.stderr.contains("Lockup"), "{}", masked.stderr);

    let unguarded = qemu(&elf, None, &["unguarded"], limit);
    let first = unguarded.stderr.lines().next().unwrap_or("");
    eprintln!("unguarded: {:?} {first}", unguarded.status);
    assert!(
        unguarded.stdout.is_empty()
            && (unguarded.status.is_none() || unguarded.stderr.contains("Lockup")),
        "unguarded: {:?} {} {}",
        unguarded.status,
        unguarded.stdout,
        unguarded.stderr
    );
}

/// A line: scenario, sample index, numbers.
fn parse(line: &str) -> (String, usize, Vec<f64>) {
    let mut it = line.split(' ');
    let name = it.next().unwrap().to_string();
    let k = it
        .next()
        .unwrap()
        .parse()
        .unwrap_or_else(|_| panic!("bad line `{line}`"));
    let nums = it
        .map(|s| {
            s.parse::<f64>()
                .unwrap_or_else(|_| panic!("bad number in `{line}`"))
        })
        .collect();
    (name, k, nums)
}

#[test]
fn cortex_m4f_in_qemu_matches_x86() {
    let elf = build_elf();
    let qemu = run_qemu(&elf, None);
    let mut x86 = String::new();
    finrs_tests::run_all::<f32, _>(&mut x86).unwrap();

    let (q, h): (Vec<&str>, Vec<&str>) = (qemu.lines().collect(), x86.lines().collect());
    assert_eq!(
        q.len(),
        h.len(),
        "QEMU printed {} lines, x86 {}",
        q.len(),
        h.len()
    );
    assert!(
        h.len() > 500,
        "the scenarios print every {} samples",
        finrs_tests::EVERY
    );
    // Each scenario's largest magnitude per column sets the absolute floor.
    let mut scale = std::collections::HashMap::<(String, usize), f64>::new();
    for line in &h {
        let (name, _, nums) = parse(line);
        for (c, v) in nums.iter().enumerate() {
            let s = scale.entry((name.clone(), c)).or_insert(0.0);
            *s = s.max(v.abs());
        }
    }
    let (mut worst, mut bit_identical) = (0.0f64, true);
    for (ql, hl) in q.iter().zip(&h) {
        bit_identical &= ql == hl;
        let (qn, qk, qv) = parse(ql);
        let (hn, hk, hv) = parse(hl);
        assert_eq!(
            (&qn, qk, qv.len()),
            (&hn, hk, hv.len()),
            "line layout differs"
        );
        for (c, (a, b)) in qv.iter().zip(&hv).enumerate() {
            let floor = 1e-12 * scale[&(hn.clone(), c)];
            let rel = (a - b).abs() / b.abs().max(floor).max(f64::MIN_POSITIVE);
            worst = worst.max(rel);
            assert!(
                rel <= 5e-7,
                "{hn} sample {hk} column {c}: QEMU {a:e} vs x86 {b:e} (relative {rel:e})"
            );
        }
    }
    eprintln!(
        "{} lines compared; largest relative difference {worst:e}; bit-identical: {bit_identical}",
        h.len()
    );
}
