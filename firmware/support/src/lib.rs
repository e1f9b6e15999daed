//! `finrs-firmware-support`: the fin driver firmware's pure pieces, in a
//! crate of their own so that the firmware (`firmware`) and the host's
//! tests (`tests/scenarios`) depend on the same code instead of including
//! its files.
//!
//! - [`calibration_store`]: the calibration's append-only records in a
//!   flash sector, safe against a reset or power cut at any byte
//!   ([`record_log`], shared with [`model_store`], the fitted model's).
//! - [`config`]: the segment count and DAC segments chosen at build time
//!   (`FINRS_SEGMENTS`, `FINRS_DAC_SEGMENTS`), the sample rate, limits and
//!   sensor scales both boards run with.
//! - [`identity`]: the firmware's version and git commit for its Info
//!   frame.
//! - [`keepalive`]: the pin only a running sample task moves, which keeps
//!   the bridges awake.
//! - [`pins`]: the analogue inputs' pins, ADCs and channels, checked
//!   against the datasheet.
//! - [`reset`]: why the core last reset, from RCC_CSR's flags.
//! - [`stack_guard`]: the MPU region at the stack's bottom that turns an
//!   overflow into a fault whose handler can still run.
//! - [`supply`]: VDDA and the bridge supply, measured at boot and
//!   checked before anything drives.
//! - [`sync`]: the camera's sync mark, lit when a drive starts after a
//!   rest.
//! - [`shunt_filter`]: the shunt amplifier's low-pass, and the mean
//!   it makes of the bridge's two-level current.
//! - [`sim`]: the QEMU board's simulated plant, as numbers (run length,
//!   load-cell offset and noise, the injected fault).
//! - [`watermark`]: the stack high-water mark's paint pattern and scan.
//! - [`world`]: the virtual bench's world channel (the clamp and the
//!   camera around the QEMU board), its messages and decoders.
#![no_std]
#![deny(unsafe_code, missing_docs)]

pub mod calibration_store;
pub mod config;
pub mod flash_timing;
pub mod identity;
pub mod keepalive;
pub mod model_store;
pub mod pins;
pub mod record_log;
pub mod reset;
pub mod shunt_filter;
pub mod sim;
pub mod stack_guard;
pub mod supply;
pub mod sync;
pub mod watermark;
pub mod world;
