//! CRC-16/CCITT-FALSE, bit by bit: frames are short and a 512-byte table
//! would cost more flash than the time it saves.

/// CRC-16/CCITT-FALSE of `data`: polynomial 0x1021, initial value 0xFFFF,
/// no reflection, no final xor (check value 0x29B1 for `b"123456789"`).
pub const fn crc16(data: &[u8]) -> u16 {
    let mut crc: u16 = 0xFFFF;
    let mut i = 0;
    while i < data.len() {
        crc ^= (data[i] as u16) << 8;
        let mut bit = 0;
        while bit < 8 {
            crc = if crc & 0x8000 != 0 {
                (crc << 1) ^ 0x1021
            } else {
                crc << 1
            };
            bit += 1;
        }
        i += 1;
    }
    crc
}
