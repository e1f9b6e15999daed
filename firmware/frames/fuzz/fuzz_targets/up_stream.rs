//! The up-channel decoder on arbitrary bytes, cut in two at a point the
//! input chooses: it must never panic, give the same events however the
//! stream is cut, and account for every byte exactly once (in a frame it
//! decoded or as corrupt), so that no sample is invented or lost unseen.
#![no_main]

use finrs_frames::{frame_len, Decoder, Event, DROPPED_FRAME_LEN, FAULT_FRAME_LEN, INFO_FRAME_LEN};
use libfuzzer_sys::fuzz_target;

fn decode(chunks: &[&[u8]]) -> Vec<Event> {
    let mut decoder = Decoder::new();
    let mut events = Vec::new();
    for chunk in chunks {
        decoder.push(chunk, &mut |e| events.push(e));
    }
    decoder.finish(&mut |e| events.push(e));
    events
}

fuzz_target!(|data: &[u8]| {
    let cut = data.first().map_or(0, |&b| b as usize % (data.len() + 1));
    let whole = decode(&[data]);
    let split = decode(&[&data[..cut], &data[cut..]]);
    // f32 fields may be NaN: compare what the events say, not `==`.
    assert_eq!(format!("{whole:?}"), format!("{split:?}"));
    let accounted: usize = whole
        .iter()
        .map(|e| match e {
            Event::Sample(s) => frame_len(s.voltages().len()),
            Event::Dropped(_) => DROPPED_FRAME_LEN,
            Event::Fault(_) => FAULT_FRAME_LEN,
            Event::Info(_) => INFO_FRAME_LEN,
            Event::Gap { .. } => 0,
            Event::Corrupt { skipped_bytes } => *skipped_bytes,
        })
        .sum();
    assert_eq!(accounted, data.len(), "every byte is a frame's or corrupt");
});
