//! The firmware's identity for its Info frame, from what the build knows:
//! the crate's version and the git commit (`FINRS_GIT_HASH`, which the
//! app's build script sets from `git rev-parse`), parsed at compile time.
//!
//! ```
//! use finrs_firmware_support::identity::{git_hash, version};
//!
//! assert_eq!(version("0.12.3"), [0, 12, 3]);
//! assert_eq!(git_hash(Some("1a2b3c4d")), 0x1a2b_3c4d);
//! assert_eq!(git_hash(None), 0);
//! ```

/// `major.minor.patch` as three bytes; a part above 255, missing or not a
/// number reads as 0 (a version is information, not a reason to fail).
pub const fn version(text: &str) -> [u8; 3] {
    let b = text.as_bytes();
    let mut out = [0u8; 3];
    let (mut part, mut value, mut i) = (0, 0u32, 0);
    while i <= b.len() && part < 3 {
        if i == b.len() || b[i] == b'.' || b[i] == b'-' || b[i] == b'+' {
            out[part] = if value > 255 { 0 } else { value as u8 };
            part += 1;
            value = 0;
            if i == b.len() || b[i] != b'.' {
                break;
            }
        } else if b[i].is_ascii_digit() {
            value = value * 10 + (b[i] - b'0') as u32;
            if value > 255 {
                value = 256;
            }
        } else {
            return [0; 3];
        }
        i += 1;
    }
    out
}

/// The first eight hex digits of a commit hash as a number; 0 if the hash
/// is unknown or not hex.
pub const fn git_hash(text: Option<&str>) -> u32 {
    let Some(text) = text else { return 0 };
    let b = text.as_bytes();
    let mut value = 0u32;
    let mut i = 0;
    while i < b.len() && i < 8 {
        let d = match b[i] {
            c @ b'0'..=b'9' => c - b'0',
            c @ b'a'..=b'f' => c - b'a' + 10,
            c @ b'A'..=b'F' => c - b'A' + 10,
            _ => return 0,
        };
        value = value << 4 | d as u32;
        i += 1;
    }
    if i < 8 {
        return 0;
    }
    value
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn versions_and_hashes_parse_or_read_as_zero() {
        assert_eq!(version("0.1.0"), [0, 1, 0]);
        assert_eq!(version("1.2.3-rc.1"), [1, 2, 3]);
        assert_eq!(version("1.2"), [1, 2, 0]);
        assert_eq!(version("256.1.1"), [0, 1, 1]);
        assert_eq!(version("x.1.1"), [0, 0, 0]);
        assert_eq!(git_hash(Some("deadbeef0123")), 0xdead_beef);
        assert_eq!(git_hash(Some("DEADBEEF")), 0xdead_beef);
        assert_eq!(git_hash(Some("dead")), 0, "too short");
        assert_eq!(git_hash(Some("not-hex!")), 0);
        assert_eq!(git_hash(Some("")), 0);
    }
}
