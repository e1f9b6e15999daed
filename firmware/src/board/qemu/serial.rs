//! The virtual bench's serial ports (`qemu-serial`): USART1 carries the
//! firmware's link (frames out, commands in, in place of the board's RTT
//! channels) and USART2 the bench's world ([`super::world`]). QEMU's
//! netduinoplus2 connects USART1, USART2 to its first and second `-serial`
//! chardevs (the sockets `finrs bench run --qemu` holds).
//!
//! How QEMU 7.2's STM32F2xx USART model behaves (hw/char/stm32f2xx_usart.c),
//! which shapes this file:
//! - a write to DR goes to the chardev at once, whole (TXE is always set):
//!   if the host does not read, the core waits, so nothing is dropped;
//! - it takes one received byte at a time, and only while UE and RE are set
//!   (a byte that comes earlier is dropped: the host waits for the first
//!   frame before it sends); it raises the interrupt while RXNE and RXNEIE
//!   are set, and offers the next byte once DR is read. A poll every 10 ms
//!   would take a 20-byte command in 200 ms; the interrupt takes each byte
//!   as it comes, into a ring the command task drains.
//!
//! Neither the baud rate nor the clocks matter to QEMU (it emulates no
//! RCC); the real board has no USART link (it speaks RTT).

use core::sync::atomic::{AtomicU8, AtomicUsize, Ordering};

use stm32f4xx_hal::interrupt;
use stm32f4xx_hal::pac::{self, usart1::RegisterBlock, Interrupt, NVIC};

/// Bytes a ring holds: more than the longest command (a SetWave), so a
/// whole one fits while its reader waits.
const RING_LEN: usize = 256;

/// Received bytes not yet taken: a single-producer (the port's interrupt),
/// single-consumer (its reader) ring of atomics. heapless's spsc queue would
/// need its producer handed to the handler through a lock, and its mpmc
/// queue can refuse under preemption.
pub struct Ring {
    bytes: [AtomicU8; RING_LEN],
    /// Bytes written so far (the handler's counter; wraps).
    head: AtomicUsize,
    /// Bytes taken so far (the reader's counter; wraps).
    tail: AtomicUsize,
}

impl Ring {
    const fn new() -> Self {
        Self {
            bytes: [const { AtomicU8::new(0) }; RING_LEN],
            head: AtomicUsize::new(0),
            tail: AtomicUsize::new(0),
        }
    }

    /// Takes the received bytes, up to `buf.len()`; 0 when none came.
    pub fn read(&self, buf: &mut [u8]) -> usize {
        let head = self.head.load(Ordering::Acquire);
        let mut tail = self.tail.load(Ordering::Relaxed);
        let mut n = 0;
        while n < buf.len() && tail != head {
            buf[n] = self.bytes[tail % RING_LEN].load(Ordering::Relaxed);
            tail = tail.wrapping_add(1);
            n += 1;
        }
        // Frees the slots only after they were read.
        self.tail.store(tail, Ordering::Release);
        n
    }

    /// Moves what the USART received into the ring (its interrupt).
    fn fill(&self, usart: &RegisterBlock) {
        while usart.sr().read().rxne().bit_is_set() {
            // Reading DR clears RXNE and lets QEMU offer the next byte.
            let b = usart.dr().read().dr().bits() as u8;
            let head = self.head.load(Ordering::Relaxed);
            if head.wrapping_sub(self.tail.load(Ordering::Acquire)) >= RING_LEN {
                // The reader is behind by a whole ring: the command decoder
                // then sees a gap, refuses the broken command and resyncs.
                defmt::warn!("serial port: a received byte did not fit; dropped");
                continue;
            }
            self.bytes[head % RING_LEN].store(b, Ordering::Relaxed);
            // Publishes the byte only after it is in its slot.
            self.head.store(head.wrapping_add(1), Ordering::Release);
        }
    }
}

/// USART1's received bytes: the firmware's commands.
pub static LINK_RX: Ring = Ring::new();
/// USART2's received bytes: the world's requests.
pub static WORLD_RX: Ring = Ring::new();

/// A port's transmit side: a USART's register block, owned.
pub struct Tx<U: core::ops::Deref<Target = RegisterBlock>> {
    usart: U,
}

impl<U: core::ops::Deref<Target = RegisterBlock>> Tx<U> {
    /// Sends all of `bytes` (each DR write is one byte on the chardev).
    pub fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            while self.usart.sr().read().txe().bit_is_clear() {}
            self.usart.dr().write(|w| w.dr().set(u16::from(b)));
        }
    }
}

/// Enables `usart` for both directions and unmasks its receive interrupt
/// at the lowest priority (the handler shares nothing with the tasks).
pub fn enable<U: core::ops::Deref<Target = RegisterBlock>>(
    usart: U,
    irq: Interrupt,
    nvic: &mut NVIC,
) -> Tx<U> {
    usart.cr1().write(|w| {
        w.ue()
            .set_bit()
            .te()
            .set_bit()
            .re()
            .set_bit()
            .rxneie()
            .set_bit()
    });
    // SAFETY: the port's handler below touches only its ring and the
    // USART's receive side; unmasking it breaks no critical section (init
    // runs with interrupts disabled; RTIC enables them after).
    #[allow(unsafe_code)]
    unsafe {
        // The NVIC's 4 priority bits sit high in the byte: 0xF0 is the lowest.
        nvic.set_priority(irq, 0xF0);
        NVIC::unmask(irq);
    }
    Tx { usart }
}

#[interrupt]
fn USART1() {
    // SAFETY: the handler reads only SR and DR (the receiver's side); the
    // owner of `pac::USART1` ([`Tx`]) writes only DR's transmit side and
    // reads SR, which reading does not change.
    #[allow(unsafe_code)]
    LINK_RX.fill(unsafe { &*pac::USART1::ptr() });
}

#[interrupt]
fn USART2() {
    // SAFETY: as USART1's.
    #[allow(unsafe_code)]
    WORLD_RX.fill(unsafe { &*pac::USART2::ptr() });
}
