//! The one error every refusal of a recording carries.

use std::fmt;

/// A recording refused: which file, which line (if one), which rule.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RecordingError {
    file: String,
    line: Option<usize>,
    message: String,
}

impl RecordingError {
    /// An error about line `line` (1-based) of `file`.
    pub fn at(file: &str, line: usize, message: impl Into<String>) -> Self {
        RecordingError {
            file: file.to_string(),
            line: Some(line),
            message: message.into(),
        }
    }

    /// An error about `file` as a whole.
    pub fn file(file: &str, message: impl Into<String>) -> Self {
        RecordingError {
            file: file.to_string(),
            line: None,
            message: message.into(),
        }
    }

    /// The 1-based line, if the error is about one.
    pub fn line(&self) -> Option<usize> {
        self.line
    }

    /// The rule broken, without file and line.
    pub fn message(&self) -> &str {
        &self.message
    }
}

impl fmt::Display for RecordingError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(l) => write!(f, "{}:{}: {}", self.file, l, self.message),
            None => write!(f, "{}: {}", self.file, self.message),
        }
    }
}

impl std::error::Error for RecordingError {}
