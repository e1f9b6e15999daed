//! The reader on arbitrary and on nearly valid input: it never panics, and
//! whatever it accepts is a recording that passes every rule.

use finrs::recording::{
    max_written_error, Channel, Fixture, Geometry, Medium, Metadata, Recording, Voltages,
};
use proptest::prelude::*;

const VALID: &str = include_str!("data/good/free_camera.csv");

fn accepted_is_valid(rec: Result<Recording, finrs::recording::RecordingError>) {
    match rec {
        Ok(r) => r.validate("accepted").expect("what is read is valid"),
        Err(e) => assert!(!e.message().is_empty()),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..2048)) {
        accepted_is_valid(Recording::parse_bytes("fuzz.csv", &bytes));
    }

    #[test]
    fn mutated_valid_files_never_panic(
        at in 0usize..VALID.len(),
        byte in any::<u8>(),
        drop_line in 0usize..14,
        field in "[-+0-9.eEinfNa,#= \"]{0,8}",
    ) {
        // A byte replaced.
        let mut bytes = VALID.as_bytes().to_vec();
        bytes[at] = byte;
        accepted_is_valid(Recording::parse_bytes("mutated.csv", &bytes));
        // A line deleted.
        let lines: Vec<&str> = VALID.lines().collect();
        let mut kept = lines.clone();
        kept.remove(drop_line.min(lines.len() - 1));
        accepted_is_valid(Recording::parse("dropped.csv", &(kept.join("\n") + "\n")));
        // A field replaced by something number-like.
        let mut text = VALID.to_string();
        let commas: Vec<usize> = text.match_indices(',').map(|(i, _)| i).collect();
        let c = commas[at % commas.len()];
        text.insert_str(c + 1, &field);
        accepted_is_valid(Recording::parse("field.csv", &text));
    }

    #[test]
    fn valid_recordings_round_trip_within_resolution(
        segments in 1usize..=8,
        rows in proptest::collection::vec((1e-6f64..10.0, -4.0f64..=4.0, proptest::option::of(prop_oneof![-1.0f64..1.0, -1e-6f64..1e-6, -200.0f64..200.0])), 1..40),
        blocked in any::<bool>(),
        notes in any::<String>(),
    ) {
        let mut t = 0.0;
        let mut t_s = Vec::new();
        let mut v_v = Voltages::with_capacity(segments, rows.len());
        let mut meas = Vec::new();
        for (dt, v, m) in &rows {
            t += dt;
            t_s.push(t);
            v_v.push(&vec![*v; segments]);
            meas.push(*m);
        }
        let fixture = if blocked { Fixture::Blocked } else { Fixture::Free };
        let ch = if blocked { Channel::Force } else { Channel::TipY };
        let rec = Recording {
            meta: Metadata {
                sample: Some("p \"q\" \\ r".to_string()),
                notes: Some(notes),
                ..Metadata::new(segments, Geometry::THESIS_2006, fixture, Medium::Water)
            },
            t_s,
            v_v,
            channels: vec![(Channel::Current(segments - 1), meas.clone()), (ch, meas)],
        };
        rec.validate("gen.csv").unwrap();
        let back = Recording::parse("gen.csv", &rec.to_csv_string()).unwrap();
        // Metadata, time and voltages exactly; empty fields stay empty;
        // measured values within the written resolution.
        prop_assert_eq!(&back.meta, &rec.meta);
        prop_assert_eq!(&back.t_s, &rec.t_s);
        prop_assert_eq!(&back.v_v, &rec.v_v);
        prop_assert_eq!(back.channels.len(), rec.channels.len());
        for ((bc, bv), (rc, rv)) in back.channels.iter().zip(&rec.channels) {
            prop_assert_eq!(bc, rc);
            prop_assert_eq!(bv.len(), rv.len());
            for (b, r) in bv.iter().zip(rv) {
                match (b, r) {
                    (Some(b), Some(r)) => prop_assert!((b - r).abs() <= max_written_error(*r), "{} read back as {}", r, b),
                    (None, None) => {}
                    _ => prop_assert!(false, "{:?} read back as {:?}", r, b),
                }
            }
        }
    }
}
