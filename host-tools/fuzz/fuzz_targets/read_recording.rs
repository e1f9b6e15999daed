//! The recording reader on arbitrary bytes: it must never panic, and what
//! it accepts must pass every rule again when written.
#![no_main]

use finrs::recording::Recording;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(rec) = Recording::parse_bytes("fuzz.csv", data) {
        rec.validate("fuzz.csv").expect("what is read is valid");
    }
});
