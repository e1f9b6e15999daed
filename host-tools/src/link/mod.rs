//! The running firmware: the debug probe ([`probe`]), its force stream
//! turned into a recording ([`stream`], [`capture`]), the commands sent
//! to it ([`command`]), the board as one client sees it ([`board`]) and
//! its calibration ([`calibrate`]), the firmware's defmt log
//! ([`defmt_log`]), and the firmware in QEMU as a board
//! ([`qemu`]).

pub mod board;
pub mod calibrate;
pub mod capture;
pub(crate) mod causes;
pub mod command;
pub mod defmt_log;
#[cfg(test)]
pub(crate) mod fake_board;
pub mod probe;
pub mod qemu;
pub mod replay;
pub mod stream;
