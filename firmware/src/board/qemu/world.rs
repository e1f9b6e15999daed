//! The virtual bench's world (`qemu-serial`): the strip free in its clamp
//! or blocked against the load cell, as the host's operator requests, and
//! a camera that watches it free, on USART2 (messages in
//! `finrs_firmware_support::world`). The firmware never sees this: it
//! drives and samples as on a board; only the plant behind its ADC changes.

use finrs_firmware_support::sync::SyncMark;
use finrs_firmware_support::world::{
    encode_event, Event, Request, RequestDecoder, CAMERA_NOISE_M, CAMERA_PERIOD_TICKS, MAX_DOTS,
    MAX_MARKS,
};
use heapless::spsc::Producer;
use model_core::Strip;

use super::{serial, S};
use crate::config::N;

/// The world's state beside the board's (blocked) plant.
pub struct World {
    /// The strip free in the clamp: its own model (the fixture is part of
    /// the finite-element model), in a static as the blocked one.
    free: &'static Strip<f32, N, 1, S>,
    x: [f32; S],
    is_free: bool,
    dots: usize,
    dots_s_m: [f32; MAX_DOTS],
    decoder: RequestDecoder,
    /// The sync mark, as the board's LED lights it: its onset is the
    /// camera's sync event.
    sync: SyncMark,
    noise: u32,
    out: Producer<'static, u8>,
}

impl World {
    /// Blocked, as at power-up; no dots until the host names them.
    pub fn new(free: &'static Strip<f32, N, 1, S>, out: Producer<'static, u8>) -> Self {
        Self {
            free,
            x: free.rest(),
            is_free: false,
            dots: 0,
            dots_s_m: [0.0; MAX_DOTS],
            decoder: RequestDecoder::new(),
            sync: SyncMark::new(),
            noise: 0x9E37_79B9,
            out,
        }
    }

    /// Applies the operator's acts received so far, at period `tick`.
    /// Re-clamping puts the strip at rest in either fixture (an idealised
    /// operator who lets it rest between recordings, as each recording's
    /// model starts at rest) and says so to the host; true when the
    /// blocked plant must be put at rest too.
    pub fn poll(&mut self, tick: u64) -> bool {
        let mut buf = [0u8; 16];
        let mut reclamped = false;
        loop {
            let n = serial::WORLD_RX.read(&mut buf);
            if n == 0 {
                return reclamped;
            }
            for &b in &buf[..n] {
                match self.decoder.push(b) {
                    Some(Ok(request @ (Request::Free | Request::Blocked))) => {
                        self.is_free = request == Request::Free;
                        self.x = self.free.rest();
                        reclamped = true;
                        // This period's sample showed the old fixture; the
                        // step below starts from rest in the new one.
                        self.send(&Event::Clamped {
                            tick: tick as u32 + 1,
                            free: self.is_free,
                        });
                    }
                    Some(Ok(Request::Dots { dots, s_m })) => {
                        self.dots = usize::from(dots);
                        self.dots_s_m = s_m;
                    }
                    Some(Err(e)) => defmt::warn!("world: {}", defmt::Debug2Format(&e)),
                    None => {}
                }
            }
        }
    }

    /// Whether the strip is free (the load cell then reads no force).
    pub fn is_free(&self) -> bool {
        self.is_free
    }

    /// One period with `applied` on the segments at period `tick`: the
    /// onset event, and if free, the free strip's step (its currents
    /// returned) and the camera's frame.
    pub fn step(&mut self, applied: &[f32; N], tick: u64) -> Option<[f32; N]> {
        if self.sync.update(applied).onset {
            self.send(&Event::Onset { tick: tick as u32 });
        }
        if !self.is_free {
            return None;
        }
        self.free.step(&mut self.x, applied);
        let currents = self.free.currents_a(&self.x, applied);
        // The state after this period's step is the next period's.
        let seen = tick + 1;
        if seen % u64::from(CAMERA_PERIOD_TICKS) == 0 {
            let mut y_m = [0.0f32; MAX_MARKS];
            let length_m = self.free.params().length_m;
            let marks = self.dots + 1;
            for (k, y) in y_m[..marks].iter_mut().enumerate() {
                let s_m = self.dots_s_m.get(k).filter(|_| k < self.dots);
                let s_m = s_m.map_or(length_m, |&s| f64::from(s));
                // A dot off the strip is seen nowhere: NaN, as a tracker's
                // lost mark.
                *y = self.free.deflection_at_m(&self.x, s_m).unwrap_or(f32::NAN)
                    + self.next_noise_m();
            }
            self.send(&Event::Camera {
                tick: seen as u32,
                marks: marks as u8,
                y_m,
            });
        }
        Some(currents)
    }

    /// Uniform tracking error in ±`CAMERA_NOISE_M` (xorshift32).
    fn next_noise_m(&mut self) -> f32 {
        let x = finrs_firmware_support::sim::xorshift32(&mut self.noise);
        (x as f32 / u32::MAX as f32 * 2.0 - 1.0) * CAMERA_NOISE_M
    }

    fn send(&mut self, e: &Event) {
        let mut buf = [0u8; 64];
        let n = encode_event(e, &mut buf);
        if self.out.capacity() - self.out.len() < n {
            defmt::warn!("world: the camera's queue is full; a frame is lost");
            return;
        }
        for &b in &buf[..n] {
            let _ = self.out.enqueue(b);
        }
    }
}
