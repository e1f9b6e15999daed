//! Scenarios shared by the x86 tests and the QEMU program.
#![no_std]
#![deny(missing_docs)]
