//! The wire format: CRC, lengths, byte layout, round trips of every kind,
//! and what the encoder and decoder refuse.

mod common;

use common::*;
use finrs_frames::{
    crc16, encode_dropped, encode_fault, encode_sample, encode_tracking, frame_len,
    tracking_frame_len, Decoder, Dropped, EncodeError, Event, Fault, FaultCode, Sample,
    SampleFlags, Tracking, TrackingFlags, DROPPED_FRAME_LEN, FAULT_FRAME_LEN, MAX_FRAME_LEN,
};

#[test]
fn crc_is_ccitt_false() {
    assert_eq!(crc16(b"123456789"), 0x29B1);
    assert_eq!(crc16(b""), 0xFFFF);
}

#[test]
fn frame_lengths() {
    assert_eq!(frame_len(1), 4 + 21 + 2);
    assert_eq!(frame_len(3), 4 + 37 + 2);
    assert_eq!(frame_len(8), 4 + 77 + 2);
    assert_eq!(MAX_FRAME_LEN, frame_len(8));
    assert_eq!(DROPPED_FRAME_LEN, 4 + 8 + 2);
    assert_eq!(FAULT_FRAME_LEN, 4 + 10 + 2);
    assert_eq!(frame_len(usize::MAX), usize::MAX);
}

#[test]
fn sample_layout_is_as_documented() {
    let s = Sample::<1> {
        seq: 0x0403_0201,
        t_us: 0x0807_0605,
        force_n: 1.0,
        flags: SampleFlags(SampleFlags::TARING | SampleFlags::RUNNING),
        voltages_v: [-2.0],
        currents_a: [0.5],
    };
    let f = sample_frame(&s);
    let body = [
        0x01, 0x15, // kind, len = 21
        0x01, 0x02, 0x03, 0x04, // seq
        0x05, 0x06, 0x07, 0x08, // t_us
        0x00, 0x00, 0x80, 0x3F, // 1.0
        0x14, // flags: taring, running
        0x00, 0x00, 0x00, 0xC0, // -2.0
        0x00, 0x00, 0x00, 0x3F, // 0.5
    ];
    assert_eq!(f.len(), frame_len(1));
    assert_eq!(f[..2], [0xF1, 0x5E]);
    assert_eq!(f[2..25], body);
    assert_eq!(f[25..], crc16(&body).to_le_bytes());
}

#[test]
fn dropped_and_fault_layout_is_as_documented() {
    let d = dropped_frame(&Dropped {
        first_seq: 0x0403_0201,
        count: 0x0807_0605,
    });
    assert_eq!(d[..12], [0xF1, 0x5E, 2, 8, 1, 2, 3, 4, 5, 6, 7, 8]);
    assert_eq!(d[12..], crc16(&d[2..12]).to_le_bytes());

    let f = fault_frame(&Fault {
        seq: 9,
        t_us: 10,
        code: FaultCode::MissedDeadline,
        segment: None,
    });
    assert_eq!(
        f[..14],
        [0xF1, 0x5E, 3, 10, 9, 0, 0, 0, 10, 0, 0, 0, 3, 0xFF]
    );
    assert_eq!(f[14..], crc16(&f[2..14]).to_le_bytes());
}

#[test]
fn tracking_layout_is_as_documented_and_decodes_back() {
    let mut t = Tracking {
        t_us: 0x0403_0201,
        flags: TrackingFlags(TrackingFlags::AT_LIMIT),
        n: 2,
        gains: [0.0; 8],
        phases_deg: [0.0; 8],
    };
    t.gains[..2].copy_from_slice(&[1.0, 2.0]);
    t.phases_deg[..2].copy_from_slice(&[-2.0, 0.5]);
    let mut buf = [0u8; MAX_FRAME_LEN];
    let len = encode_tracking(&t, &mut buf).unwrap();
    assert_eq!(len, tracking_frame_len(2));
    let body = [
        0x05, 0x15, // kind, len = 5 + 16
        0x01, 0x02, 0x03, 0x04, // t_us
        0x02, // flags: at the limit
        0x00, 0x00, 0x80, 0x3F, // gain 1.0
        0x00, 0x00, 0x00, 0x40, // gain 2.0
        0x00, 0x00, 0x00, 0xC0, // phase -2.0
        0x00, 0x00, 0x00, 0x3F, // phase 0.5
    ];
    assert_eq!(buf[..2], [0xF1, 0x5E]);
    assert_eq!(buf[2..len - 2], body);
    assert_eq!(buf[len - 2..len], crc16(&body).to_le_bytes());
    let mut got = Vec::new();
    Decoder::new().push(&buf[..len], &mut |e| got.push(e));
    assert_eq!(got, vec![Event::Tracking(t)]);
    // No segment, or more than 8: refused, not written.
    for n in [0, 9] {
        let bad = Tracking { n, ..t };
        assert!(encode_tracking(&bad, &mut buf).is_err(), "{n} segments");
    }
    assert_eq!(tracking_frame_len(8), 4 + 69 + 2);
}

/// Values that a lossy conversion would change: NaN payloads, signed zero,
/// infinities, subnormals.
const AWKWARD: [f32; 8] = [
    f32::from_bits(0x7FC0_1234),
    -0.0,
    f32::INFINITY,
    f32::NEG_INFINITY,
    f32::from_bits(1),
    f32::from_bits(0xFFBF_FFFF),
    f32::MAX,
    -1.5e-3,
];

fn sample_round_trip<const N: usize>() {
    let awkward = Sample::<N> {
        seq: u32::MAX,
        t_us: 0xDEAD_BEEF,
        force_n: f32::from_bits(0x7F80_0001),
        flags: SampleFlags(0xFF),
        voltages_v: core::array::from_fn(|k| AWKWARD[k]),
        currents_a: core::array::from_fn(|k| AWKWARD[7 - k]),
    };
    for s in [sample::<N>(0), sample::<N>(123_456), awkward] {
        let f = sample_frame(&s);
        assert_eq!(f.len(), frame_len(N));
        let (keys, stats) = decode(&f);
        assert_eq!(keys, [sample_key(&s)]);
        assert_eq!(stats.samples, 1);
        assert_eq!(stats.corrupt_bytes, 0);
    }
}

#[test]
fn samples_round_trip() {
    sample_round_trip::<1>();
    sample_round_trip::<3>();
    sample_round_trip::<8>();
}

#[test]
fn decoded_sample_exposes_n_segments() {
    let s = sample::<3>(5);
    let mut got = Vec::new();
    finrs_frames::Decoder::new().push(&sample_frame(&s), &mut |e| {
        if let finrs_frames::Event::Sample(d) = e {
            got.push(d);
        }
    });
    assert_eq!(got.len(), 1);
    let d = got[0];
    assert_eq!(d.n, 3);
    assert_eq!(d.voltages(), s.voltages_v);
    assert_eq!(d.currents(), s.currents_a);
    assert_eq!(d.voltages_v[3..], [0.0; 5]);
    assert_eq!(d.currents_a[3..], [0.0; 5]);
}

#[test]
fn dropped_round_trips() {
    for d in [
        Dropped {
            first_seq: 0,
            count: 1,
        },
        Dropped {
            first_seq: u32::MAX,
            count: u32::MAX,
        },
    ] {
        let f = dropped_frame(&d);
        assert_eq!(f.len(), DROPPED_FRAME_LEN);
        let (keys, stats) = decode(&f);
        assert_eq!(keys, [Key::Dropped(d)]);
        assert_eq!(stats.dropped_reported, u64::from(d.count));
    }
}

#[test]
fn faults_round_trip() {
    let codes = [
        FaultCode::Overcurrent,
        FaultCode::AdcSaturation,
        FaultCode::MissedDeadline,
        FaultCode::Other,
        FaultCode::Supply,
    ];
    for (i, code) in codes.into_iter().enumerate() {
        assert_eq!(FaultCode::from_u8(code as u8), Some(code));
        assert_eq!(code as u8, i as u8 + 1);
        for segment in [None, Some(0), Some(7)] {
            let fault = Fault {
                seq: 42,
                t_us: u32::MAX,
                code,
                segment,
            };
            let f = fault_frame(&fault);
            assert_eq!(f.len(), FAULT_FRAME_LEN);
            let (keys, stats) = decode(&f);
            assert_eq!(keys, [Key::Fault(fault)]);
            assert_eq!(stats.faults, 1);
        }
    }
    assert_eq!(FaultCode::from_u8(0), None);
    assert_eq!(FaultCode::from_u8(6), None);
}

#[test]
fn encoders_refuse_short_buffers_and_stay_in_bounds() {
    let mut buf = [0u8; MAX_FRAME_LEN];
    for len in 0..frame_len(8) {
        let needed = frame_len(8);
        assert_eq!(
            encode_sample(&sample::<8>(1), &mut buf[..len]),
            Err(EncodeError::BufferTooSmall { needed })
        );
    }
    for len in 0..DROPPED_FRAME_LEN {
        let d = Dropped {
            first_seq: 1,
            count: 2,
        };
        assert_eq!(
            encode_dropped(&d, &mut buf[..len]),
            Err(EncodeError::BufferTooSmall {
                needed: DROPPED_FRAME_LEN
            })
        );
    }
    let fault = Fault {
        seq: 1,
        t_us: 2,
        code: FaultCode::Other,
        segment: Some(1),
    };
    for len in 0..FAULT_FRAME_LEN {
        assert_eq!(
            encode_fault(&fault, &mut buf[..len]),
            Err(EncodeError::BufferTooSmall {
                needed: FAULT_FRAME_LEN
            })
        );
    }
    assert_eq!(buf, [0u8; MAX_FRAME_LEN], "a refused frame writes nothing");
    // A longer buffer is fine; the frame takes its start.
    let mut long = [0xAAu8; 200];
    assert_eq!(encode_sample(&sample::<3>(1), &mut long), Ok(frame_len(3)));
    assert_eq!(long[..frame_len(3)], sample_frame(&sample::<3>(1))[..]);
    assert!(long[frame_len(3)..].iter().all(|&b| b == 0xAA));
}

#[test]
fn encoder_refuses_segments_out_of_range() {
    let mut buf = [0u8; MAX_FRAME_LEN];
    for s in [8, 0xFE, 0xFF] {
        let fault = Fault {
            seq: 1,
            t_us: 2,
            code: FaultCode::Overcurrent,
            segment: Some(s),
        };
        assert_eq!(
            encode_fault(&fault, &mut buf),
            Err(EncodeError::BadSegment(s))
        );
    }
}

/// A frame with a good CRC around `body` (kind, len and payload).
fn framed(body: &[u8]) -> Vec<u8> {
    let mut f = vec![0xF1, 0x5E];
    f.extend_from_slice(body);
    f.extend_from_slice(&crc16(body).to_le_bytes());
    f
}

#[test]
fn decoder_refuses_invalid_content_despite_good_crc() {
    let fault = |code: u8, segment: u8| framed(&[3, 10, 1, 0, 0, 0, 2, 0, 0, 0, code, segment]);
    let bad = [
        fault(0, 0xFF),
        fault(6, 0xFF),
        fault(1, 8),
        fault(1, 0xFE),
        framed(&[5, 8, 0, 0, 0, 0, 0, 0, 0, 0]), // unknown kind
        framed(&[0, 8, 0, 0, 0, 0, 0, 0, 0, 0]),
        framed(&[2, 9, 0, 0, 0, 0, 0, 0, 0, 0, 0]), // Dropped, wrong length
        framed(&[4, 8, 0, 0, 0, 0, 0, 0, 0, 0]),    // Info, wrong length
        framed(&[1, 13, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]), // Sample, N = 0
        framed(&[
            1, 22, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
        ]), // Sample, 13 + 9 bytes
        framed(&[
            1, 20, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
        ]), // the old layout's N = 1
    ];
    let good = sample::<1>(3);
    for b in bad {
        let mut stream = b.clone();
        stream.extend(sample_frame(&good));
        let (keys, stats) = decode(&stream);
        assert_eq!(
            keys,
            [
                Key::Corrupt {
                    skipped_bytes: b.len()
                },
                sample_key(&good)
            ],
            "{b:02X?}"
        );
        assert_eq!(stats.corrupt_bytes, b.len() as u64);
        assert_eq!(stats.faults, 0);
    }
    // And a good fault built the same way decodes.
    let (keys, _) = decode(&fault(2, 7));
    assert_eq!(
        keys,
        [Key::Fault(Fault {
            seq: 1,
            t_us: 2,
            code: FaultCode::AdcSaturation,
            segment: Some(7)
        })]
    );
}

fn info() -> finrs_frames::Info {
    finrs_frames::Info {
        version: [0, 1, 2],
        git_hash: 0x1a2b_3c4d,
        segments: 3,
        dac_segments: [Some(2), None],
        sample_hz: 1000,
        calibration: finrs_frames::Calibration {
            newtons_per_count: 2.5e-5,
            current_zero_counts: [2048, 2049, 2047, 2048, 2048, 2048, 2048, 2050],
        },
        amps_per_count: 2.5e-4,
        max_abs_v: 3.64,
        slew_v_per_s: 200.0,
        bridge_supply_v: 5.0,
        overcurrent_a: 0.4,
        calibration_origin: finrs_frames::CalibrationOrigin::Stored,
        reset_cause: finrs_frames::ResetCause::Watchdog,
        model_crc: Some(0xbeef),
    }
}

#[test]
fn info_layout_is_as_documented_and_round_trips() {
    use finrs_frames::{encode_info, Decoder, Event, INFO_FRAME_LEN};
    let i = info();
    let mut buf = [0u8; INFO_FRAME_LEN];
    assert_eq!(encode_info(&i, &mut buf), Ok(4 + 62 + 2));
    assert_eq!(&buf[..4], &[0xF1, 0x5E, 4, 62]);
    let p = &buf[4..66];
    assert_eq!(p[0], 3, "layout version");
    assert_eq!(&p[1..4], &[0, 1, 2]);
    assert_eq!(&p[4..8], &0x1a2b_3c4du32.to_le_bytes());
    assert_eq!(&p[8..11], &[3, 2, 0xFF]);
    assert_eq!(&p[11..15], &1000u32.to_le_bytes());
    assert_eq!(&p[15..19], &2.5e-5f32.to_le_bytes());
    assert_eq!(&p[19..21], &2048u16.to_le_bytes());
    assert_eq!(&p[21..23], &2049u16.to_le_bytes());
    assert_eq!(&p[33..35], &2050u16.to_le_bytes(), "segment 8's zero");
    assert_eq!(&p[35..39], &2.5e-4f32.to_le_bytes());
    assert_eq!(&p[39..43], &3.64f32.to_le_bytes());
    assert_eq!(&p[51..55], &0.4f32.to_le_bytes());
    assert_eq!(p[55], 1, "stored calibration");
    assert_eq!(p[56], 5, "watchdog");
    assert_eq!(p[57], 1, "a model held");
    assert_eq!(&p[58..60], &0xbeefu16.to_le_bytes(), "the model's CRC");
    assert_eq!(&p[60..62], &crc16(&p[8..55]).to_le_bytes());
    assert_eq!(i.config_crc(), Some(crc16(&p[8..55])));
    assert_eq!(&buf[66..], &crc16(&buf[2..66]).to_le_bytes());
    let mut d = Decoder::new();
    let mut got = Vec::new();
    d.push(&buf, &mut |e| got.push(e));
    assert_eq!(got, [Event::Info(i)]);
    assert_eq!(d.stats().infos, 1);
    // The reset cause is not configuration: another cause, same CRC.
    let other = finrs_frames::Info {
        reset_cause: finrs_frames::ResetCause::PowerOn,
        ..i
    };
    assert_eq!(other.config_crc(), i.config_crc());
    let lower = finrs_frames::Info {
        max_abs_v: 1.5,
        ..i
    };
    assert_ne!(lower.config_crc(), i.config_crc());
    // The calibration is configuration, its origin is not.
    let mut recalibrated = i;
    recalibrated.calibration.current_zero_counts[7] = 2051;
    assert_ne!(recalibrated.config_crc(), i.config_crc());
    let unsaved = finrs_frames::Info {
        calibration_origin: finrs_frames::CalibrationOrigin::Unsaved,
        ..i
    };
    assert_eq!(unsaved.config_crc(), i.config_crc());
    // The model is not configuration either; none round-trips as none.
    let no_model = finrs_frames::Info {
        model_crc: None,
        ..i
    };
    assert_eq!(no_model.config_crc(), i.config_crc());
    encode_info(&no_model, &mut buf).unwrap();
    assert_eq!(&buf[4 + 57..4 + 60], &[0, 0, 0]);
    let mut d = Decoder::new();
    let mut got = Vec::new();
    d.push(&buf, &mut |e| got.push(e));
    assert_eq!(got, [Event::Info(no_model)]);
}

#[test]
fn a_bad_info_is_refused_by_the_encoder_and_the_decoder() {
    use finrs_frames::{encode_info, Decoder, Event, INFO_FRAME_LEN};
    let mut buf = [0u8; INFO_FRAME_LEN];
    for bad in [
        finrs_frames::Info {
            segments: 0,
            ..info()
        },
        finrs_frames::Info {
            segments: 9,
            ..info()
        },
        finrs_frames::Info {
            dac_segments: [Some(8), None],
            ..info()
        },
    ] {
        assert_eq!(encode_info(&bad, &mut buf), Err(EncodeError::BadInfo));
    }
    // A config CRC that does not match, an unknown reset cause, another
    // layout version, a model flag that is neither 0 nor 1, none with a
    // CRC: each a frame whose CRC checks but whose content is refused as
    // corrupt.
    for (at, value) in [
        (4 + 60, 0u8),
        (4 + 56, 99),
        (4 + 55, 3),
        (4, 2),
        (4 + 57, 2),
        (4 + 57, 0),
    ] {
        encode_info(&info(), &mut buf).unwrap();
        buf[at] = value;
        let crc = crc16(&buf[2..66]);
        buf[66..].copy_from_slice(&crc.to_le_bytes());
        let mut events = Vec::new();
        let mut d = Decoder::new();
        d.push(&buf, &mut |e| events.push(e));
        d.finish(&mut |e| events.push(e));
        assert_eq!(
            events,
            [Event::Corrupt {
                skipped_bytes: INFO_FRAME_LEN
            }],
            "byte {at} = {value}"
        );
    }
}
