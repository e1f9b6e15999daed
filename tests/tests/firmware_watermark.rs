//! The firmware's stack scan (`firmware/src/watermark.rs`, the pure half of
//! its stack measurement) on the host: this file includes the firmware's
//! own file, whose unit tests then run here.

#[path = "../../firmware/src/watermark.rs"]
mod watermark;
