//! `_SEGGER_RTT` is found in an ELF that defines it: this test program
//! defines one, as a firmware built with RTT does.

#![cfg(feature = "probe")]

/// Stands in for the firmware's RTT control block.
#[no_mangle]
#[used]
pub static _SEGGER_RTT: [u8; 16] = *b"SEGGER RTT\0\0\0\0\0\0";

#[test]
fn the_control_block_address_is_read_from_the_elf() {
    let me = std::env::current_exe().unwrap();
    let image = std::fs::read(&me).unwrap();
    let at = finrs::link::probe::rtt_address("rtt_symbol", &image).unwrap();
    // The link-time address: page-aligned load offsets keep the low 12 bits
    // of the run-time address.
    let runtime = std::ptr::addr_of!(_SEGGER_RTT) as u64;
    assert_ne!(at, 0);
    assert_eq!(at & 0xfff, runtime & 0xfff);
}
