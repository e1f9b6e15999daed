//! The down-channel command decoder on arbitrary bytes, cut in two at a
//! point the input chooses: it must never panic, give the same events
//! however the stream is cut, and every command it yields must be one that
//! was really in the stream (its encoding appears in the bytes).
#![no_main]

use finrs_frames::{encode_command, CommandDecoder, CommandEvent, MAX_COMMAND_LEN};
use libfuzzer_sys::fuzz_target;

fn decode(chunks: &[&[u8]]) -> Vec<CommandEvent> {
    let mut decoder = CommandDecoder::new();
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
    assert_eq!(format!("{whole:?}"), format!("{split:?}"));
    for event in &whole {
        if let CommandEvent::Command(c) = event {
            let mut buf = [0u8; MAX_COMMAND_LEN];
            let n = encode_command(c, &mut buf).expect("a decoded command encodes");
            assert!(
                data.windows(n).any(|w| w == &buf[..n]),
                "decoded {c:?}, which is not in the stream"
            );
        }
    }
});
