//! The host's side of the virtual bench's world channel
//! (`finrs_firmware_support::world`): the operator's acts sent, the
//! camera's frames and the drive's onsets kept, and a recording's stretch
//! of them written as a tracker's CSV that `finrs merge-camera` reads
//! (`camera::track`'s format), as a real bench's camera and tracker would
//! give it.

use std::fmt::Write as _;

use finrs_firmware_support::world::{encode_request, Event, EventDecoder, Request, MAX_DOTS};

/// The virtual camera's scale at the strip's plane, m per pixel: pass it
/// to `finrs merge-camera --m-per-px`. Its y grows with the strip's
/// positive bending, its x from the clamp toward the tip (no flips).
pub const VIRTUAL_M_PER_PX: f64 = 5e-5;

/// What the world has shown and not yet been taken.
#[derive(Debug, Default)]
pub struct WorldLog {
    decoder: EventDecoder,
    events: Vec<Event>,
    refused: u64,
    clamped: u64,
}

impl WorldLog {
    /// Takes bytes from the world's channel.
    pub fn push(&mut self, bytes: &[u8]) {
        for &b in bytes {
            match self.decoder.push(b) {
                Some(Ok(Event::Clamped { .. })) => self.clamped += 1,
                Some(Ok(e)) => self.events.push(e),
                Some(Err(_)) => self.refused += 1,
                None => {}
            }
        }
    }

    /// The period of the newest camera frame kept, if any.
    pub fn newest_frame(&self) -> Option<u32> {
        self.events.iter().rev().find_map(|e| match *e {
            Event::Camera { tick, .. } => Some(tick),
            _ => None,
        })
    }

    /// Fixture requests done so far.
    pub fn clamped(&self) -> u64 {
        self.clamped
    }

    /// Bytes that broke the world's format so far (none on a sound link).
    pub fn refused(&self) -> u64 {
        self.refused
    }

    /// The track of sample periods `first..=last` as a tracker's CSV, the
    /// dots at `dots_s_m` and the tip at `length_m` (the recording's
    /// geometry); the events up to `last` are dropped. `None` when the
    /// camera saw no frame in the stretch (the strip was blocked).
    ///
    /// `frame` is the board's sample period at which the camera saw the
    /// strip (a camera frame every 33 periods), `time_s` the same on the
    /// recording's clock; the `sync` row is the drive's onset, exact to the
    /// period (a real camera sees a sync LED to within a frame).
    pub fn take_track(
        &mut self,
        first: u32,
        last: u32,
        sample_hz: f64,
        dots_s_m: &[f64],
        length_m: f64,
    ) -> Option<String> {
        let in_range = |tick: u32| (first..=last).contains(&tick);
        let mut csv = String::from("frame,time_s,dot,x_px,y_px\n");
        let mut frames = 0;
        let mut synced = false;
        let px = |m: f64| m / VIRTUAL_M_PER_PX;
        for e in &self.events {
            match *e {
                Event::Onset { tick } if in_range(tick) && !synced => {
                    synced = true;
                    let t = f64::from(tick - first) / sample_hz;
                    let _ = writeln!(csv, "{tick},{t},sync,,");
                }
                Event::Camera { tick, marks, y_m } if in_range(tick) => {
                    frames += 1;
                    let t = f64::from(tick - first) / sample_hz;
                    let marks = usize::from(marks);
                    for (k, &y) in y_m[..marks].iter().enumerate() {
                        let (name, s_m) = if k + 1 == marks {
                            ("tip".to_string(), length_m)
                        } else {
                            (
                                (k + 1).to_string(),
                                dots_s_m.get(k).copied().unwrap_or(f64::NAN),
                            )
                        };
                        if y.is_finite() && s_m.is_finite() {
                            let _ =
                                writeln!(csv, "{tick},{t},{name},{},{}", px(s_m), px(f64::from(y)));
                        } else {
                            // Lost by the tracker: an empty position.
                            let _ = writeln!(csv, "{tick},{t},{name},,");
                        }
                    }
                }
                _ => {}
            }
        }
        self.events.retain(|e| match *e {
            Event::Onset { tick } | Event::Camera { tick, .. } | Event::Clamped { tick, .. } => {
                tick > last
            }
        });
        (frames > 0).then_some(csv)
    }
}

/// The world's bytes for the strip `free` (else blocked) with the camera
/// on `dots_s_m` (at most `MAX_DOTS`, the rest ignored).
pub fn setup_bytes(free: bool, dots_s_m: &[f64]) -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut buf = [0u8; 64];
    let dots = dots_s_m.len().min(MAX_DOTS);
    if dots > 0 {
        let mut s_m = [0.0f32; MAX_DOTS];
        for (s, &d) in s_m.iter_mut().zip(dots_s_m) {
            *s = d as f32;
        }
        let n = encode_request(
            &Request::Dots {
                dots: dots as u8,
                s_m,
            },
            &mut buf,
        );
        bytes.extend_from_slice(&buf[..n]);
    }
    let n = encode_request(
        if free {
            &Request::Free
        } else {
            &Request::Blocked
        },
        &mut buf,
    );
    bytes.extend_from_slice(&buf[..n]);
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::track::{Mark, Track};
    use finrs_firmware_support::world::{encode_event, MAX_MARKS};

    fn bytes_of(events: &[Event]) -> Vec<u8> {
        let mut out = Vec::new();
        let mut buf = [0u8; 64];
        for e in events {
            let n = encode_event(e, &mut buf);
            out.extend_from_slice(&buf[..n]);
        }
        out
    }

    #[test]
    fn a_stretch_becomes_a_track_merge_camera_reads() {
        let mut y_m = [0.0f32; MAX_MARKS];
        y_m[..3].copy_from_slice(&[1e-3, f32::NAN, 4e-3]);
        let frame = |tick| Event::Camera {
            tick,
            marks: 3,
            y_m,
        };
        let mut log = WorldLog::default();
        // Split mid-message: the decoder reassembles.
        let bytes = bytes_of(&[
            frame(990),
            frame(1023),
            Event::Onset { tick: 1040 },
            frame(1056),
            Event::Onset { tick: 1070 },
            frame(2013),
        ]);
        log.push(&bytes[..7]);
        log.push(&bytes[7..]);
        assert_eq!(log.refused(), 0);
        let csv = log
            .take_track(1000, 2000, 1000.0, &[0.01, 0.02], 0.05)
            .unwrap();
        let track = Track::parse("virtual", &csv, None).unwrap();
        // The first onset in the stretch, on the recording's clock.
        assert_eq!(track.sync_time_s, Some(0.040));
        // Two frames in the stretch, dot 2 lost in both.
        assert_eq!(track.points.len(), 4, "{csv}");
        assert_eq!(track.points[0].mark, Mark::Dot(1));
        assert_eq!(track.points[1].mark, Mark::Tip);
        assert!((track.points[0].t_s - 0.023).abs() < 1e-12);
        assert!((track.points[0].x_px - 0.01 / VIRTUAL_M_PER_PX).abs() < 1e-9);
        assert!((track.points[1].y_px - 4e-3 / VIRTUAL_M_PER_PX).abs() < 1e-3);
        // What came after the stretch stays for the next one.
        let next = log.take_track(2001, 3000, 1000.0, &[], 0.05).unwrap();
        assert!(next.contains("2013,"), "{next}");
        // A stretch with no frame (blocked): no track.
        assert_eq!(log.take_track(3001, 4000, 1000.0, &[], 0.05), None);
    }

    #[test]
    fn setup_names_the_dots_then_the_fixture() {
        let bytes = setup_bytes(true, &[0.01, 0.02]);
        let mut d = finrs_firmware_support::world::RequestDecoder::new();
        let got: Vec<_> = bytes.iter().filter_map(|&b| d.push(b)).collect();
        assert_eq!(got.len(), 2);
        assert!(matches!(got[0], Ok(Request::Dots { dots: 2, .. })));
        assert_eq!(got[1], Ok(Request::Free));
        assert_eq!(setup_bytes(false, &[]), [b'B']);
    }
}
