//! The firmware's defmt log: its table read from the ELF, its frames
//! decoded and shown line by line.
//!
//! Decoding needs `defmt-decoder`, a fifth of a clean build of `finrs`
//! (it brings a regex engine, a CBOR parser and a DWARF reader), so it is
//! the `defmt` feature: in the default build (the `probe` feature implies
//! it) and not in the quick start's `--no-default-features`, which only
//! simulates, fits and diagnoses. Built without it, no table is ever read:
//! the board's frames, faults included, still arrive on their own channel,
//! and a link says once that the log is not shown and why
//! ([`no_table_notice`]).

/// The ELF's defmt table: what turns the log's bytes into lines.
#[cfg(feature = "defmt")]
pub use defmt_decoder::Table;

/// The ELF's defmt table; none can be read without the `defmt` feature
/// (no value of this type exists).
#[cfg(not(feature = "defmt"))]
#[derive(Debug)]
pub enum Table {}

/// Reads the defmt table from an ELF's `bytes`: `None` where it has none
/// (or where `finrs` was built without the `defmt` feature); an error, with
/// its causes, where the table is malformed.
#[cfg(feature = "defmt")]
pub fn read_table(bytes: &[u8]) -> Result<Option<Table>, String> {
    // defmt-decoder's error is an anyhow::Error: `{:#}` keeps its causes.
    Table::parse(bytes).map_err(|e| format!("{e:#}"))
}

/// Reads the defmt table from an ELF's `bytes`: `None` where it has none
/// (or where `finrs` was built without the `defmt` feature); an error, with
/// its causes, where the table is malformed.
#[cfg(not(feature = "defmt"))]
pub fn read_table(_bytes: &[u8]) -> Result<Option<Table>, String> {
    Ok(None)
}

/// What a link says once when `elf` gave no table: that the ELF has none,
/// or that this `finrs` cannot read one.
pub fn no_table_notice(elf: &str) -> String {
    if cfg!(feature = "defmt") {
        format!("{elf}: no defmt table; the log on channel 0 is not shown")
    } else {
        format!(
            "{elf}: the log on channel 0 is not shown: this finrs was built without \
             the `defmt` feature (build it with default features to see the log)"
        )
    }
}

/// The log's decoder over one table, and how many malformed frames it met.
pub struct Log<'t> {
    #[cfg(feature = "defmt")]
    decoder: Box<dyn defmt_decoder::StreamDecoder + Send + Sync + 't>,
    #[cfg(not(feature = "defmt"))]
    decoder: &'t Table,
    malformed: u64,
}

impl<'t> Log<'t> {
    /// A decoder at the start of the log, over `table`.
    #[cfg(feature = "defmt")]
    pub fn new(table: &'t Table) -> Self {
        Self {
            decoder: table.new_stream_decoder(),
            malformed: 0,
        }
    }

    /// A decoder at the start of the log, over `table` (of which none
    /// exists without the `defmt` feature).
    #[cfg(not(feature = "defmt"))]
    pub fn new(table: &'t Table) -> Self {
        match *table {}
    }

    /// Takes the log's next `bytes` and hands every whole frame they
    /// complete to `line`, as a line of text; says so at the first
    /// malformed one. (A closure, not a link's monitor: the link's capture
    /// imports this module.)
    pub fn show(&mut self, bytes: &[u8], line: &mut dyn FnMut(&str)) {
        #[cfg(feature = "defmt")]
        {
            self.decoder.received(bytes);
            loop {
                match self.decoder.decode() {
                    Ok(frame) => line(&frame.display(false).to_string()),
                    Err(defmt_decoder::DecodeError::UnexpectedEof) => break,
                    Err(defmt_decoder::DecodeError::Malformed) => {
                        self.malformed += 1;
                        if self.malformed == 1 {
                            line("defmt: malformed frame (is the ELF the one running?)");
                        }
                    }
                }
            }
        }
        #[cfg(not(feature = "defmt"))]
        {
            let _ = (bytes, line);
            match *self.decoder {}
        }
    }

    /// How many malformed frames the log has held so far.
    pub fn malformed(&self) -> u64 {
        self.malformed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(not(feature = "defmt"))]
    #[test]
    fn without_the_feature_no_table_is_read_and_the_notice_says_why() {
        // An ELF's bytes or not, nothing is parsed: there is no decoder.
        assert!(matches!(read_table(b"\x7fELF anything"), Ok(None)));
        let notice = no_table_notice("fw.elf");
        assert!(notice.starts_with("fw.elf: "), "{notice}");
        assert!(notice.contains("`defmt` feature"), "{notice}");
    }

    #[cfg(feature = "defmt")]
    #[test]
    fn with_the_feature_a_file_that_is_no_elf_is_refused_with_its_reason() {
        let err = read_table(b"not an ELF").unwrap_err();
        assert!(!err.is_empty());
        assert!(no_table_notice("fw.elf").contains("no defmt table"));
    }
}
