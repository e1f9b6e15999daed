//! The one error every refusal of an import carries.

/// An import refused: the mapping, or an export, breaks a rule. Each
/// variant names the file; a mapping's error names its key, an export's
/// the sheet, row and column (a spreadsheet cell, `Sheet1!D57`) where it
/// can, and the rule.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    /// A file could not be read (the cause is the source).
    #[error("{file}: cannot read")]
    Io {
        /// The file.
        file: String,
        /// What the system said.
        source: std::io::Error,
    },
    /// The mapping is not TOML of the mapping's shape: a syntax error, a
    /// key unknown or missing, a value of the wrong type.
    #[error("{file}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    MappingSyntax {
        /// The mapping file.
        file: String,
        /// The 1-based line, where the TOML parser knows it.
        line: Option<usize>,
        /// The parser's message, which names the key.
        message: String,
    },
    /// A key of the mapping breaks a rule of `finrs-import/1`.
    #[error("{file}: {key}: {rule}")]
    Mapping {
        /// The mapping file.
        file: String,
        /// The key, as `time.rate_hz`, `channel[2].scale` (the second
        /// `[[channel]]`) or `files."02.xlsx".fixture`.
        key: String,
        /// The rule broken.
        rule: String,
    },
    /// An export is not a workbook calamine can read (not a zip, no
    /// sheets, damaged XML, password-protected).
    #[error("{file}: cannot read as an XLSX workbook: {message}")]
    Workbook {
        /// The export.
        file: String,
        /// What the workbook reader said.
        message: String,
    },
    /// An export, or a place in it, breaks a rule.
    #[error("{file}: {}{rule}", at.as_ref().map(|a| format!("{a}: ")).unwrap_or_default())]
    Export {
        /// The export.
        file: String,
        /// Where: a cell (`Sheet1!D57`, `line 57, field 4 (D)`), a row,
        /// a column or a merged region; `None` for the file as a whole.
        at: Option<String>,
        /// The rule broken.
        rule: String,
    },
}

impl ImportError {
    /// A refusal of `file` as a whole.
    pub(crate) fn export(file: &str, rule: impl Into<String>) -> ImportError {
        ImportError::Export {
            file: file.to_string(),
            at: None,
            rule: rule.into(),
        }
    }

    /// A refusal of the place `at` in `file`.
    pub(crate) fn at(file: &str, at: impl Into<String>, rule: impl Into<String>) -> ImportError {
        ImportError::Export {
            file: file.to_string(),
            at: Some(at.into()),
            rule: rule.into(),
        }
    }

    /// A refusal of the mapping `file`'s `key`.
    pub(crate) fn mapping(file: &str, key: impl Into<String>, rule: impl Into<String>) -> Self {
        ImportError::Mapping {
            file: file.to_string(),
            key: key.into(),
            rule: rule.into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_file_the_place_and_the_rule() {
        let e = ImportError::at("a.xlsx", "Sheet1!D57", "holds the text `x`");
        assert_eq!(e.to_string(), "a.xlsx: Sheet1!D57: holds the text `x`");
        let e = ImportError::export("a.xlsx", "the sheet is empty");
        assert_eq!(e.to_string(), "a.xlsx: the sheet is empty");
        let e = ImportError::mapping("lab.toml", "time.rate_hz", "must be positive");
        assert_eq!(e.to_string(), "lab.toml: time.rate_hz: must be positive");
        let e = ImportError::MappingSyntax {
            file: "lab.toml".into(),
            line: Some(3),
            message: "unknown field `sheeet`".into(),
        };
        assert_eq!(e.to_string(), "lab.toml:3: unknown field `sheeet`");
    }
}
