//! An error told with its causes, for text that outlives the error (the
//! recording's notes, a message carrying a second error).

use std::error::Error;

/// The error and its causes, `: `-separated, as the binary prints them.
pub fn with_causes(e: &dyn Error) -> String {
    let mut text = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        text.push_str(": ");
        text.push_str(&c.to_string());
        cause = c.source();
    }
    text
}
