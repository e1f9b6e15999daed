//! The pure half of the stack measurement (`firmware/src/stack.rs`
//! holds the unsafe half): the paint pattern and the scan for the
//! high-water mark. No pointers here, so the scan is unit-tested on the
//! host.

/// The word painted over free stack. Not 0 (zeroed locals) nor a small
/// count, an address in RAM or flash (0x2…, 0x0…/0x1…) or an `f32` a
/// computation is likely to leave behind.
pub const PAINT: u32 = 0xA5C3_5A3C;

/// Number of painted words at the bottom of a stack of `len` words, where
/// `read(i)` reads word `i` counting up from the lowest address: the scan
/// stops at the first word that is not [`PAINT`], as the stack grows down
/// and what it has touched once stays unpainted.
pub fn painted_words(len: usize, read: impl Fn(usize) -> u32) -> usize {
    (0..len).find(|&i| read(i) != PAINT).unwrap_or(len)
}

/// Bytes of a stack of `len` words used at its high-water mark: everything
/// above the painted words at the bottom.
pub fn used_bytes(len: usize, read: impl Fn(usize) -> u32) -> usize {
    (len - painted_words(len, read)) * 4
}

#[cfg(test)]
mod tests {
    use super::*;

    fn used(words: &[u32]) -> usize {
        used_bytes(words.len(), |i| words[i])
    }

    #[test]
    fn an_untouched_stack_is_unused() {
        assert_eq!(used(&[PAINT; 16]), 0);
        assert_eq!(used(&[]), 0);
    }

    #[test]
    fn the_lowest_touched_word_sets_the_mark() {
        let mut words = [PAINT; 16];
        // Word 12 touched: words 12..16 (4 words) count as used.
        words[12] = 0;
        assert_eq!(used(&words), 16);
        // A deeper touch moves the mark down, whatever lies above it.
        words[5] = 7;
        assert_eq!(used(&words), 44);
        assert_eq!(painted_words(words.len(), |i| words[i]), 5);
    }

    #[test]
    fn a_word_written_back_with_the_pattern_above_the_mark_does_not_hide_it() {
        // A frame that happened to store the pattern itself: the scan stops
        // at the lowest word that differs, so the mark is still found.
        let mut words = [PAINT; 8];
        words[2] = 1;
        words[3] = PAINT;
        assert_eq!(used(&words), 24);
    }

    #[test]
    fn a_fully_used_stack_is_all_used() {
        assert_eq!(used(&[0u32; 10]), 40);
        let mut words = [PAINT; 10];
        words[0] = !PAINT;
        assert_eq!(used(&words), 40);
    }
}
