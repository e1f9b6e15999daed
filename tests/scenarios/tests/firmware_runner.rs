//! `cd firmware && cargo run` must keep the board safe under probe-rs-tools'
//! `run`: its defaults halt the core on a HardFault before the handler can
//! turn the outputs off, and rewrite every RTT up channel to block when
//! full (a sample task would then spin until the watchdog resets the
//! board). The runner's flags that prevent both, and the one that keeps
//! the binary frame channel off the terminal, must stay.

#[test]
fn the_runner_keeps_the_safety_flags() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../firmware/.cargo/config.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let runner = text
        .lines()
        .find(|l| l.trim_start().starts_with("runner"))
        .unwrap_or_else(|| panic!("{}: no runner", path.display()));
    for flag in [
        "probe-rs run",
        "--chip STM32F407VGTx",
        "--no-catch-hardfault",
        "--rtt-channel-mode no-block-skip",
        "--rtt-up-channels 0",
    ] {
        assert!(
            runner.contains(flag),
            "{}: {runner} lacks {flag}",
            path.display()
        );
    }
}
