//! The mapping from a lab's export to `ipmc-bench/1`: a TOML file of
//! format `finrs-import/1` (`docs/import.md` describes every key), read
//! and checked whole before any export is read. Every refusal names the
//! mapping file and the key.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Deserialize;

use super::address::{column_letters, parse_column_letters, MAX_COLUMNS, MAX_ROWS};
use super::error::ImportError;
use crate::recording::{Channel, Fixture, Geometry, Medium, Metadata};

/// The only mapping format this reader knows.
pub const MAPPING_FORMAT: &str = "finrs-import/1";

/// How close a raw value must come to a sentinel to be it, relative to
/// the sentinel: a sensor's `-99.9999` read back through a spreadsheet's
/// binary numbers is not always the same double as the one typed.
pub const SENTINEL_RELATIVE_TOLERANCE: f64 = 1e-9;

/// Where a column of an export is.
#[derive(Clone, Debug, PartialEq)]
pub enum ColumnRef {
    /// The column whose header cell holds exactly this text (both
    /// trimmed of spaces).
    Name(String),
    /// The column at this 0-based position (`index = 1` and
    /// `letter = "A"` are both 0).
    Position(usize),
}

impl ColumnRef {
    /// As a refusal names it: `"Y axis - Voltage"` or `column C`.
    pub fn describe(&self) -> String {
        match self {
            ColumnRef::Name(name) => format!("column {name:?}"),
            ColumnRef::Position(col) => format!("column {}", column_letters(*col)),
        }
    }
}

/// The `ipmc-bench/1` column a mapped column becomes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// `vK_V`: the voltage of segment K (the index is 0-based).
    Voltage(usize),
    /// A measured column: a current, the tip or a dot, the force.
    Measured(Channel),
}

impl Target {
    /// The column's name in `ipmc-bench/1`.
    pub fn name(&self) -> String {
        match self {
            Target::Voltage(k) => format!("v{}_V", k + 1),
            Target::Measured(ch) => ch.name(),
        }
    }

    /// The target a column name denotes, if any (`v1_V`, `i2_A`,
    /// `tip_y_m`, ...; indices in plain decimal from 1, as the format
    /// writes them).
    pub fn parse(name: &str) -> Option<Target> {
        if let Some(k) = name.strip_prefix('v').and_then(|r| r.strip_suffix("_V")) {
            // `i1_A` and `v1_V` share their index rule: canonical decimal.
            return match Channel::parse(&format!("i{k}_A")) {
                Some(Channel::Current(k)) => Some(Target::Voltage(k)),
                _ => None,
            };
        }
        Channel::parse(name).map(Target::Measured)
    }
}

/// What is subtracted from a channel's raw values before they are
/// scaled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Zero {
    /// A value in the export's own units.
    Raw(f64),
    /// The mean of the channel's raw values sampled over the recording's
    /// opening `opening_s` seconds (its rest before any drive): a laser's
    /// distance to the strip at rest, a sensor's offset.
    Opening {
        /// The opening's length, s.
        opening_s: f64,
    },
}

/// What is subtracted from a time column's raw values before they are
/// scaled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TimeZero {
    /// A value in the column's own units.
    Raw(f64),
    /// The first data row's time: the recording starts at `start_s`.
    First,
}

/// Where each row's time comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Time {
    /// A column: `t_s = start_s + scale * (raw - zero)`.
    Column {
        /// The column.
        column: ColumnRef,
        /// Seconds per unit of the column (0.001 for ms).
        scale: f64,
        /// Subtracted from the raw values first.
        zero: TimeZero,
        /// Added last, s.
        start_s: f64,
    },
    /// A fixed rate, no column: data row `i` (from 0) is at
    /// `start_s + i / rate_hz`.
    Rate {
        /// Rows per second.
        rate_hz: f64,
        /// The first row's time, s.
        start_s: f64,
    },
}

/// One column of the export and the `ipmc-bench/1` column it becomes:
/// `value = sign * scale * (raw - zero)`, in SI units.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelMap {
    /// The column it becomes.
    pub to: Target,
    /// The export's column.
    pub column: ColumnRef,
    /// SI units per unit of the export (0.001 for mA to A, or mm to m).
    pub scale: f64,
    /// +1 or -1: -1 where the sensor counts the other way (a laser's
    /// distance shrinks as the strip bends toward it).
    pub sign: f64,
    /// Subtracted from the raw values first.
    pub zero: Zero,
    /// Raw values a sensor writes when it has no reading (a laser's
    /// `-99.9999` when the spot leaves its range): written as empty
    /// fields. Matched within [`SENTINEL_RELATIVE_TOLERANCE`]; an
    /// infinity matches itself, NaN matches NaN.
    pub out_of_range: Vec<f64>,
    /// The raw range a reading must lie in (both ends included): a value
    /// outside (a clipped amplifier) is written as an empty field.
    pub valid: Option<(f64, f64)>,
}

impl ChannelMap {
    /// The sentinel `raw` is, if any.
    pub fn sentinel(&self, raw: f64) -> Option<f64> {
        self.out_of_range.iter().copied().find(|&s| {
            if s.is_nan() {
                raw.is_nan()
            } else if s.is_infinite() {
                raw == s
            } else {
                (raw - s).abs() <= SENTINEL_RELATIVE_TOLERANCE * s.abs()
            }
        })
    }

    /// Whether `raw` lies outside the valid range.
    pub fn outside_valid(&self, raw: f64) -> bool {
        self.valid.is_some_and(|(lo, hi)| !(lo..=hi).contains(&raw))
    }
}

/// How the export is laid out.
#[derive(Clone, Debug, PartialEq)]
pub struct Source {
    /// The workbook's sheet to read (default: its first).
    pub sheet: Option<String>,
    /// A text export's field separator (default: by the extension,
    /// `.csv` a comma, `.tsv`, `.tab` and `.txt` a tab).
    pub delimiter: Option<u8>,
    /// The 1-based row holding the columns' names; 0 for none (columns
    /// by letter or index only). Rows of a text export are its lines.
    pub header_row: usize,
    /// The 1-based row of the first data.
    pub first_data_row: usize,
    /// Numbers written with a decimal comma (`0,25`).
    pub decimal_comma: bool,
}

/// A checked mapping: how to read a lab's exports as `ipmc-bench/1`
/// recordings.
#[derive(Clone, Debug)]
pub struct Mapping {
    name: String,
    source: Source,
    time: Time,
    channels: Vec<ChannelMap>,
    metadata: MetaToml,
    files: BTreeMap<String, MetaToml>,
}

// ------------------------------------------------------------ the TOML

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MappingToml {
    format: String,
    #[serde(default)]
    source: SourceToml,
    time: ColumnToml,
    #[serde(default)]
    channel: Vec<ColumnToml>,
    #[serde(default)]
    metadata: MetaToml,
    #[serde(default)]
    files: BTreeMap<String, MetaToml>,
}

#[derive(Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct SourceToml {
    sheet: Option<String>,
    delimiter: Option<String>,
    header_row: Option<i64>,
    first_data_row: Option<i64>,
    decimal_comma: Option<bool>,
}

/// `[time]` and each `[[channel]]`: a column and how to read it. One
/// shape for both, so that a key of the other is refused by name rather
/// than as unknown (`to` in `[time]`, `rate_hz` in a channel).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ColumnToml {
    to: Option<String>,
    column: Option<String>,
    index: Option<i64>,
    letter: Option<String>,
    rate_hz: Option<f64>,
    start_s: Option<f64>,
    scale: Option<f64>,
    sign: Option<i64>,
    zero: Option<toml::Value>,
    opening_s: Option<f64>,
    out_of_range: Option<Vec<f64>>,
    valid: Option<Vec<f64>>,
}

/// The recording's metadata keys, each optional here: `[metadata]` and a
/// file's `[files."NAME"]` together must give the required ones.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct MetaToml {
    segments: Option<i64>,
    length_m: Option<f64>,
    width_m: Option<f64>,
    thickness_m: Option<f64>,
    fixture: Option<String>,
    medium: Option<String>,
    sample: Option<String>,
    cation: Option<String>,
    dots_s_m: Option<Vec<f64>>,
    notes: Option<String>,
    t_session_start_s: Option<f64>,
}

// ------------------------------------------------------------ reading

impl Mapping {
    /// Reads and checks the mapping file at `path`.
    pub fn read(path: &Path) -> Result<Mapping, ImportError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| ImportError::Io {
            file: name.clone(),
            source,
        })?;
        Mapping::parse(&name, &text)
    }

    /// Checks the mapping `text`, whose refusals call it `name`.
    pub fn parse(name: &str, text: &str) -> Result<Mapping, ImportError> {
        let toml: MappingToml = toml::from_str(text).map_err(|e| ImportError::MappingSyntax {
            file: name.to_string(),
            line: e
                .span()
                .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1),
            // The parser says some errors over two lines (`invalid table
            // header`, then why): one line, as every refusal.
            message: e
                .message()
                .lines()
                .map(str::trim)
                .filter(|l| !l.is_empty())
                .collect::<Vec<_>>()
                .join(": "),
        })?;
        let err = |key: &str, rule: String| ImportError::mapping(name, key, rule);
        if toml.format != MAPPING_FORMAT {
            return Err(err(
                "format",
                format!("must be \"{MAPPING_FORMAT}\", got {:?}", toml.format),
            ));
        }
        let source = source(&toml.source).map_err(|(k, r)| err(&format!("source.{k}"), r))?;
        let time = time(&toml.time, &source).map_err(|(k, r)| err(&format!("time{k}"), r))?;
        if toml.channel.is_empty() {
            return Err(err(
                "channel",
                "no [[channel]]: a recording needs at least its voltages".to_string(),
            ));
        }
        let mut channels: Vec<ChannelMap> = Vec::with_capacity(toml.channel.len());
        for (i, c) in toml.channel.iter().enumerate() {
            let key = |k: &str| format!("channel[{}]{k}", i + 1);
            let c = channel(c, &source).map_err(|(k, r)| err(&key(&k), r))?;
            if let Some(j) = channels.iter().position(|d| d.to == c.to) {
                return Err(err(
                    &key(".to"),
                    format!(
                        "{} is mapped twice (channel[{}] maps it too)",
                        c.to.name(),
                        j + 1
                    ),
                ));
            }
            channels.push(c);
        }
        let mapping = Mapping {
            name: name.to_string(),
            source,
            time,
            channels,
            metadata: toml.metadata,
            files: toml.files,
        };
        // Each file's metadata checked now, not when that file comes; the
        // base alone only when no file has its own (it may then lack a key
        // every file gives).
        for file in mapping.files.keys() {
            mapping.metadata_for(file)?;
        }
        if mapping.files.is_empty() {
            mapping.metadata_for("")?;
        }
        Ok(mapping)
    }

    /// The mapping file's name, as refusals call it.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// How the exports are laid out.
    pub fn source(&self) -> &Source {
        &self.source
    }

    /// Where each row's time comes from.
    pub fn time(&self) -> &Time {
        &self.time
    }

    /// The columns read, in the mapping's order (the recording's measured
    /// columns keep it).
    pub fn channels(&self) -> &[ChannelMap] {
        &self.channels
    }

    /// The file names `[files."NAME"]` gives metadata for.
    pub fn files(&self) -> impl Iterator<Item = &str> {
        self.files.keys().map(String::as_str)
    }

    /// The metadata of the export called `file_name` (its name without
    /// folders): `[metadata]`, with the keys of `[files."file_name"]` in
    /// place of its own, checked against the channels mapped.
    pub fn metadata_for(&self, file_name: &str) -> Result<Metadata, ImportError> {
        let over = self.files.get_key_value(file_name);
        let keys = Keys {
            base: &self.metadata,
            over: over.map(|(k, v)| (k.as_str(), v)),
        };
        let meta = keys
            .metadata()
            .map_err(|(k, r)| ImportError::mapping(&self.name, k, r))?;
        self.check_channels(&meta, &keys)?;
        Ok(meta)
    }

    /// The channels against the metadata: every voltage of the segments
    /// and none beyond, currents of the segments, camera columns of a
    /// free recording and the force of a blocked one, dots that
    /// `dots_s_m` lists.
    fn check_channels(&self, meta: &Metadata, keys: &Keys) -> Result<(), ImportError> {
        let n = meta.segments;
        let err = |i: usize, rule: String| {
            ImportError::mapping(&self.name, format!("channel[{}].to", i + 1), rule)
        };
        let segments = format!("segments = {n} ({})", keys.key("segments"));
        for (i, c) in self.channels.iter().enumerate() {
            let name = c.to.name();
            match c.to {
                Target::Voltage(k) | Target::Measured(Channel::Current(k)) if k >= n => {
                    return Err(err(i, format!("{name}, but {segments}")));
                }
                Target::Measured(ch) if ch.is_camera() && meta.fixture == Fixture::Blocked => {
                    return Err(err(
                        i,
                        format!(
                            "{name} is a camera column; a blocked recording has none ({})",
                            keys.key("fixture")
                        ),
                    ));
                }
                Target::Measured(Channel::Force) if meta.fixture == Fixture::Free => {
                    return Err(err(
                        i,
                        format!(
                            "force_N belongs to a blocked recording; this one is free ({})",
                            keys.key("fixture")
                        ),
                    ));
                }
                Target::Measured(Channel::DotX(j) | Channel::DotY(j)) => {
                    let dots = meta.dots_s_m.as_ref().map_or(0, Vec::len);
                    if j >= dots {
                        return Err(err(
                            i,
                            format!(
                                "{name}, but dots_s_m lists {dots} dot(s) ({})",
                                keys.key("dots_s_m")
                            ),
                        ));
                    }
                }
                _ => {}
            }
        }
        for k in 0..n {
            if !self.channels.iter().any(|c| c.to == Target::Voltage(k)) {
                return Err(ImportError::mapping(
                    &self.name,
                    "channel",
                    format!(
                        "no [[channel]] maps to v{}_V: {segments} needs v1_V to v{n}_V, \
                         and voltages are never empty",
                        k + 1
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// A key's refusal before the mapping's name is put to it: the key (or
/// its tail after a table's name) and the rule.
type KeyError = (String, String);

fn key_err(key: &str, rule: impl Into<String>) -> KeyError {
    (key.to_string(), rule.into())
}

fn source(s: &SourceToml) -> Result<Source, KeyError> {
    let delimiter = match &s.delimiter {
        None => None,
        Some(d) => match d.as_bytes() {
            [b] if b.is_ascii() && !matches!(b, b'"' | b'\n' | b'\r') => Some(*b),
            _ => {
                return Err(key_err(
                    "delimiter",
                    format!("must be one ASCII character other than a quote or a line end (\"\\t\" for a tab), got {d:?}"),
                ))
            }
        },
    };
    let header_row = match s.header_row {
        None => 1,
        Some(r) if (0..=MAX_ROWS as i64).contains(&r) => r as usize,
        Some(r) => {
            return Err(key_err(
                "header_row",
                format!("must be a row number from 1, or 0 for no header, got {r}"),
            ))
        }
    };
    let first_data_row = match s.first_data_row {
        None => header_row + 1,
        Some(r) if r > header_row as i64 && r <= MAX_ROWS as i64 => r as usize,
        Some(r) => {
            return Err(key_err(
                "first_data_row",
                format!("must be a row number after header_row = {header_row}, got {r}"),
            ))
        }
    };
    let decimal_comma = s.decimal_comma.unwrap_or(false);
    if decimal_comma && delimiter == Some(b',') {
        return Err(key_err(
            "decimal_comma",
            "a comma cannot both separate fields (delimiter = \",\") and mark decimals",
        ));
    }
    Ok(Source {
        sheet: s.sheet.clone(),
        delimiter,
        header_row,
        first_data_row,
        decimal_comma,
    })
}

/// The one column `c` names (by `column`, `index` or `letter`), if any.
fn column_ref(c: &ColumnToml, source: &Source) -> Result<Option<ColumnRef>, KeyError> {
    let given = [c.column.is_some(), c.index.is_some(), c.letter.is_some()];
    if given.iter().filter(|&&g| g).count() > 1 {
        return Err(key_err(
            "",
            "give one of `column`, `index` and `letter`, not several",
        ));
    }
    if let Some(name) = &c.column {
        if source.header_row == 0 {
            return Err(key_err(
                ".column",
                "source.header_row = 0: there are no names; give `index` or `letter`",
            ));
        }
        if name.trim().is_empty() {
            return Err(key_err(".column", "a column's name cannot be empty"));
        }
        return Ok(Some(ColumnRef::Name(name.trim().to_string())));
    }
    if let Some(i) = c.index {
        if !(1..=MAX_COLUMNS as i64).contains(&i) {
            return Err(key_err(
                ".index",
                format!("must be a column number from 1 (A) to {MAX_COLUMNS} (XFD), got {i}"),
            ));
        }
        return Ok(Some(ColumnRef::Position(i as usize - 1)));
    }
    if let Some(l) = &c.letter {
        return match parse_column_letters(l) {
            Some(col) => Ok(Some(ColumnRef::Position(col))),
            None => Err(key_err(
                ".letter",
                format!("must be a column's letters, A to XFD, got {l:?}"),
            )),
        };
    }
    Ok(None)
}

/// `[time]`; keys are returned as `.scale` (after `time`).
fn time(c: &ColumnToml, source: &Source) -> Result<Time, KeyError> {
    let not_here = |key: &str, why: &str| Err(key_err(&format!(".{key}"), why));
    if c.to.is_some() {
        return not_here("to", "time is always t_s; `to` belongs to a [[channel]]");
    }
    for (given, key) in [
        (c.sign.is_some(), "sign"),
        (c.opening_s.is_some(), "opening_s"),
        (c.out_of_range.is_some(), "out_of_range"),
        (c.valid.is_some(), "valid"),
    ] {
        if given {
            return not_here(key, "belongs to a [[channel]]: time is never empty");
        }
    }
    let start_s = c.start_s.unwrap_or(0.0);
    if !(start_s.is_finite() && start_s >= 0.0) {
        return Err(key_err(
            ".start_s",
            format!("must be zero or a positive number of seconds, got {start_s}"),
        ));
    }
    let column = column_ref(c, source)?;
    match (column, c.rate_hz) {
        (Some(_), Some(_)) => Err(key_err(
            "",
            "give a time column (`column`, `index` or `letter`) or `rate_hz`, not both",
        )),
        (None, None) => Err(key_err(
            "",
            "give a time column (`column`, `index` or `letter`) or `rate_hz` for an export without one",
        )),
        (None, Some(rate_hz)) => {
            if !(rate_hz.is_finite() && rate_hz > 0.0) {
                return Err(key_err(
                    ".rate_hz",
                    format!("must be a positive number of rows per second, got {rate_hz}"),
                ));
            }
            for (given, key) in [(c.scale.is_some(), "scale"), (c.zero.is_some(), "zero")] {
                if given {
                    return not_here(key, "applies to a time column, not to rate_hz");
                }
            }
            Ok(Time::Rate { rate_hz, start_s })
        }
        (Some(column), None) => {
            let scale = c.scale.unwrap_or(1.0);
            if !(scale.is_finite() && scale > 0.0) {
                return Err(key_err(
                    ".scale",
                    format!("must be a positive number of seconds per unit (0.001 for ms), got {scale}"),
                ));
            }
            let zero = match &c.zero {
                None => TimeZero::Raw(0.0),
                Some(toml::Value::String(s)) if s == "first" => TimeZero::First,
                Some(v) => match number(v) {
                    Some(x) if x.is_finite() => TimeZero::Raw(x),
                    _ => {
                        return Err(key_err(
                            ".zero",
                            format!("must be a number in the column's units or \"first\", got {}", shown(v)),
                        ))
                    }
                },
            };
            Ok(Time::Column {
                column,
                scale,
                zero,
                start_s,
            })
        }
    }
}

/// A `[[channel]]`; keys are returned as `.scale` (after `channel[K]`).
fn channel(c: &ColumnToml, source: &Source) -> Result<ChannelMap, KeyError> {
    for (given, key) in [
        (c.rate_hz.is_some(), "rate_hz"),
        (c.start_s.is_some(), "start_s"),
    ] {
        if given {
            return Err(key_err(&format!(".{key}"), "belongs to [time]"));
        }
    }
    let Some(to) = &c.to else {
        return Err(key_err(
            ".to",
            "missing: the ipmc-bench/1 column it becomes (v1_V, i1_A, tip_y_m, force_N, ...)",
        ));
    };
    let Some(target) = Target::parse(to) else {
        return Err(key_err(
            ".to",
            format!("{to:?} is not an ipmc-bench/1 column: vK_V, iK_A, tip_y_m, tip_x_m, dotJ_y_m, dotJ_x_m or force_N (t_s comes from [time])"),
        ));
    };
    let Some(column) = column_ref(c, source)? else {
        return Err(key_err(
            "",
            "give its column: `column` (the header's name), `index` (1 is A) or `letter`",
        ));
    };
    let scale = c.scale.unwrap_or(1.0);
    if !(scale.is_finite() && scale != 0.0) {
        return Err(key_err(
            ".scale",
            format!("must be a finite number other than 0 (SI units per unit: 0.001 for mA or mm), got {scale}"),
        ));
    }
    let sign = match c.sign {
        None | Some(1) => 1.0,
        Some(-1) => -1.0,
        Some(s) => return Err(key_err(".sign", format!("must be 1 or -1, got {s}"))),
    };
    let opening_s = c.opening_s.unwrap_or(1.0);
    if !(opening_s.is_finite() && opening_s > 0.0) {
        return Err(key_err(
            ".opening_s",
            format!("must be a positive number of seconds, got {opening_s}"),
        ));
    }
    let zero = match &c.zero {
        None => Zero::Raw(0.0),
        Some(toml::Value::String(s)) if s == "opening" => Zero::Opening { opening_s },
        Some(v) => match number(v) {
            Some(x) if x.is_finite() => Zero::Raw(x),
            _ => {
                return Err(key_err(
                    ".zero",
                    format!(
                        "must be a number in the column's units or \"opening\", got {}",
                        shown(v)
                    ),
                ))
            }
        },
    };
    if c.opening_s.is_some() && !matches!(zero, Zero::Opening { .. }) {
        return Err(key_err(
            ".opening_s",
            "applies with zero = \"opening\" only",
        ));
    }
    let valid = match c.valid.as_deref() {
        None => None,
        Some(&[lo, hi]) if lo < hi => Some((lo, hi)),
        Some(v) => {
            return Err(key_err(
                ".valid",
                format!("must be [low, high] with low < high, in the column's units, got {v:?}"),
            ))
        }
    };
    Ok(ChannelMap {
        to: target,
        column,
        scale,
        sign,
        zero,
        out_of_range: c.out_of_range.clone().unwrap_or_default(),
        valid,
    })
}

/// A TOML value as a refusal quotes it, on one line: a string with its
/// line ends escaped, a number or a boolean as TOML writes it, an array or
/// a table by its kind (TOML would write a string in it over several
/// lines, and the parser hands a date over as a table of its own).
fn shown(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => format!("{s:?}"),
        toml::Value::Array(_) => "an array".to_string(),
        toml::Value::Table(_) | toml::Value::Datetime(_) => "a table or a date".to_string(),
        other => other.to_string(),
    }
}

/// A TOML number (float or integer) as `f64`.
fn number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// `[metadata]` with a file's `[files."NAME"]` over it.
struct Keys<'a> {
    base: &'a MetaToml,
    over: Option<(&'a str, &'a MetaToml)>,
}

impl Keys<'_> {
    /// Where `field` comes from: `files."NAME".field` if the file gives
    /// it, else `metadata.field`.
    fn key(&self, field: &str) -> String {
        match self.over {
            Some((name, over)) if over.has(field) => format!("files.{name:?}.{field}"),
            _ => format!("metadata.{field}"),
        }
    }

    fn pick<T: Clone>(&self, f: impl Fn(&MetaToml) -> &Option<T>) -> Option<T> {
        self.over
            .and_then(|(_, over)| f(over).clone())
            .or_else(|| f(self.base).clone())
    }

    /// The metadata, each value checked by the format's rule.
    fn metadata(&self) -> Result<Metadata, KeyError> {
        let missing = |field: &str| {
            let hint = match self.over {
                Some((name, _)) => format!(" (give it in [metadata] or [files.{name:?}])"),
                None => " (give it in [metadata])".to_string(),
            };
            key_err(
                &self.key(field),
                format!("missing: the recording's metadata needs it{hint}"),
            )
        };
        let segments = self
            .pick(|m| &m.segments)
            .ok_or_else(|| missing("segments"))?;
        if !(1..=8).contains(&segments) {
            return Err(key_err(
                &self.key("segments"),
                format!("must be a whole number from 1 to 8, got {segments}"),
            ));
        }
        let mut geometry = [0.0; 3];
        for (value, field) in geometry
            .iter_mut()
            .zip(["length_m", "width_m", "thickness_m"])
        {
            let x = match field {
                "length_m" => self.pick(|m| &m.length_m),
                "width_m" => self.pick(|m| &m.width_m),
                _ => self.pick(|m| &m.thickness_m),
            }
            .ok_or_else(|| missing(field))?;
            if !(x.is_finite() && x > 0.0) {
                return Err(key_err(
                    &self.key(field),
                    format!("must be a positive length in metres, got {x}"),
                ));
            }
            *value = x;
        }
        let [length_m, width_m, thickness_m] = geometry;
        let fixture = match self
            .pick(|m| &m.fixture)
            .ok_or_else(|| missing("fixture"))?
            .as_str()
        {
            "free" => Fixture::Free,
            "blocked" => Fixture::Blocked,
            other => {
                return Err(key_err(
                    &self.key("fixture"),
                    format!("must be \"free\" or \"blocked\", got {other:?}"),
                ))
            }
        };
        let medium = match self
            .pick(|m| &m.medium)
            .ok_or_else(|| missing("medium"))?
            .as_str()
        {
            "air" => Medium::Air,
            "water" => Medium::Water,
            other => {
                return Err(key_err(
                    &self.key("medium"),
                    format!("must be \"air\" or \"water\", got {other:?}"),
                ))
            }
        };
        let dots_s_m = self.pick(|m| &m.dots_s_m);
        if let Some(dots) = &dots_s_m {
            let rule = if dots.is_empty() {
                Some("must list at least one dot".to_string())
            } else if let Some(s) = dots
                .iter()
                .find(|s| !(s.is_finite() && **s > 0.0 && **s <= length_m))
            {
                Some(format!(
                    "positions must lie in (0, length_m = {length_m}], got {s}"
                ))
            } else if dots.windows(2).any(|w| w[1] <= w[0]) {
                Some("must be strictly increasing".to_string())
            } else {
                None
            };
            if let Some(rule) = rule {
                return Err(key_err(&self.key("dots_s_m"), rule));
            }
        }
        let t_session_start_s = self.pick(|m| &m.t_session_start_s);
        if let Some(t) = t_session_start_s {
            if !(t.is_finite() && t >= 0.0) {
                return Err(key_err(
                    &self.key("t_session_start_s"),
                    format!("must be zero or a positive number of seconds, got {t}"),
                ));
            }
        }
        let geometry = Geometry {
            length_m,
            width_m,
            thickness_m,
        };
        Ok(Metadata {
            sample: self.pick(|m| &m.sample),
            cation: self.pick(|m| &m.cation),
            dots_s_m,
            notes: self.pick(|m| &m.notes),
            t_session_start_s,
            ..Metadata::new(segments as usize, geometry, fixture, medium)
        })
    }
}

impl MetaToml {
    /// Whether the table gives `field`.
    fn has(&self, field: &str) -> bool {
        match field {
            "segments" => self.segments.is_some(),
            "length_m" => self.length_m.is_some(),
            "width_m" => self.width_m.is_some(),
            "thickness_m" => self.thickness_m.is_some(),
            "fixture" => self.fixture.is_some(),
            "medium" => self.medium.is_some(),
            "sample" => self.sample.is_some(),
            "cation" => self.cation.is_some(),
            "dots_s_m" => self.dots_s_m.is_some(),
            "notes" => self.notes.is_some(),
            "t_session_start_s" => self.t_session_start_s.is_some(),
            _ => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const META: &str = r#"
        [metadata]
        segments = 2
        length_m = 0.05
        width_m = 0.01
        thickness_m = 0.0003
        fixture = "free"
        medium = "air"
    "#;

    const CHANNELS: &str = r#"
        [[channel]]
        to = "v1_V"
        column = "Y axis - Voltage"
        [[channel]]
        to = "v2_V"
        letter = "c"
        [[channel]]
        to = "i1_A"
        index = 4
        scale = 0.001
        [[channel]]
        to = "tip_y_m"
        column = "Distance"
        scale = 0.001
        sign = -1
        zero = "opening"
        out_of_range = [-99.9999, inf]
        valid = [0, 60]
    "#;

    fn parse(text: &str) -> Result<Mapping, ImportError> {
        Mapping::parse("lab.toml", text)
    }

    fn whole(time: &str) -> String {
        format!("format = \"finrs-import/1\"\n[time]\n{time}\n{CHANNELS}\n{META}")
    }

    #[test]
    fn a_mapping_is_read_with_its_defaults() {
        let m = parse(&whole("rate_hz = 100")).unwrap();
        assert_eq!(
            *m.source(),
            Source {
                sheet: None,
                delimiter: None,
                header_row: 1,
                first_data_row: 2,
                decimal_comma: false
            }
        );
        assert_eq!(
            *m.time(),
            Time::Rate {
                rate_hz: 100.0,
                start_s: 0.0
            }
        );
        let c = m.channels();
        assert_eq!(c[0].column, ColumnRef::Name("Y axis - Voltage".into()));
        assert_eq!(c[1].column, ColumnRef::Position(2));
        assert_eq!(c[2].column, ColumnRef::Position(3));
        assert_eq!(c[2].to, Target::Measured(Channel::Current(0)));
        assert_eq!(
            (c[3].sign, c[3].zero),
            (-1.0, Zero::Opening { opening_s: 1.0 })
        );
        assert_eq!(c[3].sentinel(-99.99990000005), Some(-99.9999));
        assert_eq!(c[3].sentinel(-99.9998), None);
        assert_eq!(c[3].sentinel(f64::INFINITY), Some(f64::INFINITY));
        assert!(c[3].outside_valid(60.5) && !c[3].outside_valid(60.0));
        let meta = m.metadata_for("any.xlsx").unwrap();
        assert_eq!((meta.segments, meta.fixture), (2, Fixture::Free));
    }

    #[test]
    fn a_file_s_metadata_replaces_the_base_keys_it_gives() {
        let text = format!(
            "{}\n[files.\"02_step.xlsx\"]\nt_session_start_s = 65.5\nnotes = \"run 2\"\n",
            whole("column = \"t\"\nscale = 0.001\nzero = \"first\"")
        );
        let m = parse(&text).unwrap();
        let two = m.metadata_for("02_step.xlsx").unwrap();
        assert_eq!(two.t_session_start_s, Some(65.5));
        assert_eq!(two.notes.as_deref(), Some("run 2"));
        assert_eq!(m.metadata_for("01.xlsx").unwrap().t_session_start_s, None);
        assert_eq!(m.files().collect::<Vec<_>>(), ["02_step.xlsx"]);
        let bad = text.replace("65.5", "-1");
        let err = parse(&bad).unwrap_err().to_string();
        assert!(
            err.starts_with("lab.toml: files.\"02_step.xlsx\".t_session_start_s: must be zero or"),
            "{err}"
        );
    }

    #[test]
    fn every_broken_rule_names_the_file_and_the_key() {
        let ok = whole("rate_hz = 100");
        for (from, to, says) in [
            (
                "rate_hz = 100",
                "rate_hz = 0",
                "lab.toml: time.rate_hz: must be a positive",
            ),
            ("rate_hz = 100", "rate_hz = -5", "lab.toml: time.rate_hz:"),
            ("rate_hz = 100", "rate_hz = nan", "lab.toml: time.rate_hz:"),
            (
                "rate_hz = 100",
                "rate_hz = 100\ncolumn = \"t\"",
                "lab.toml: time: give a time column",
            ),
            ("rate_hz = 100", "", "lab.toml: time: give a time column"),
            (
                "rate_hz = 100",
                "rate_hz = 100\nscale = 2",
                "lab.toml: time.scale: applies to a time column",
            ),
            (
                "rate_hz = 100",
                "column = \"t\"\nscale = 0",
                "lab.toml: time.scale:",
            ),
            (
                "rate_hz = 100",
                "column = \"t\"\nzero = \"opening\"",
                "lab.toml: time.zero:",
            ),
            (
                "rate_hz = 100",
                "rate_hz = 100\nsign = -1",
                "lab.toml: time.sign: belongs to a [[channel]]",
            ),
            (
                "scale = 0.001\n",
                "scale = nan\n",
                "lab.toml: channel[3].scale: must be a finite number",
            ),
            (
                "scale = 0.001\n",
                "scale = 0\n",
                "lab.toml: channel[3].scale:",
            ),
            (
                "sign = -1",
                "sign = 2",
                "lab.toml: channel[4].sign: must be 1 or -1",
            ),
            (
                "zero = \"opening\"",
                "zero = \"first\"",
                "lab.toml: channel[4].zero:",
            ),
            (
                "valid = [0, 60]",
                "valid = [60, 0]",
                "lab.toml: channel[4].valid:",
            ),
            (
                "valid = [0, 60]",
                "valid = [0]",
                "lab.toml: channel[4].valid:",
            ),
            (
                "index = 4",
                "index = 4\nopening_s = 2\nzero = 1",
                "lab.toml: channel[3].opening_s: applies with zero = \"opening\" only",
            ),
            (
                "letter = \"c\"",
                "letter = \"C1\"",
                "lab.toml: channel[2].letter:",
            ),
            (
                "letter = \"c\"",
                "letter = \"c\"\nindex = 3",
                "lab.toml: channel[2]: give one of",
            ),
            ("index = 4", "index = 0", "lab.toml: channel[3].index:"),
            (
                "to = \"i1_A\"",
                "to = \"i01_A\"",
                "lab.toml: channel[3].to: \"i01_A\" is not an ipmc-bench/1 column",
            ),
            ("to = \"i1_A\"", "to = \"t_s\"", "lab.toml: channel[3].to:"),
            (
                "to = \"i1_A\"",
                "to = \"v1_V\"",
                "lab.toml: channel[3].to: v1_V is mapped twice",
            ),
            (
                "to = \"i1_A\"",
                "to = \"i3_A\"",
                "lab.toml: channel[3].to: i3_A, but segments = 2 (metadata.segments)",
            ),
            (
                "to = \"i1_A\"",
                "to = \"force_N\"",
                "lab.toml: channel[3].to: force_N belongs to a blocked recording",
            ),
            (
                "to = \"i1_A\"",
                "to = \"dot1_y_m\"",
                "lab.toml: channel[3].to: dot1_y_m, but dots_s_m lists 0",
            ),
            (
                "to = \"v2_V\"",
                "to = \"i2_A\"",
                "lab.toml: channel: no [[channel]] maps to v2_V",
            ),
            (
                "segments = 2",
                "segments = 9",
                "lab.toml: metadata.segments: must be a whole number from 1 to 8",
            ),
            ("segments = 2", "", "lab.toml: metadata.segments: missing"),
            (
                "length_m = 0.05",
                "length_m = -0.05",
                "lab.toml: metadata.length_m:",
            ),
            (
                "fixture = \"free\"",
                "fixture = \"clamped\"",
                "lab.toml: metadata.fixture:",
            ),
            (
                "medium = \"air\"",
                "medium = \"oil\"",
                "lab.toml: metadata.medium:",
            ),
            (
                "medium = \"air\"",
                "medium = \"air\"\ndots_s_m = [0.02, 0.01]",
                "lab.toml: metadata.dots_s_m: must be strictly",
            ),
            (
                "format = \"finrs-import/1\"",
                "format = \"finrs-import/2\"",
                "lab.toml: format: must be",
            ),
        ] {
            assert!(ok.contains(from), "{from}");
            let text = ok.replacen(from, to, 1);
            let err = parse(&text).unwrap_err().to_string();
            assert!(err.starts_with(says), "{from} -> {to}: {err}");
        }
    }

    #[test]
    fn unknown_keys_and_wrong_types_are_refused_with_their_line() {
        let ok = whole("rate_hz = 100");
        for (from, to, says) in [
            (
                "rate_hz = 100",
                "rate_hz = 100\nrate = 1",
                "unknown field `rate`",
            ),
            (
                "sign = -1",
                "sign = -1\nunit = \"mm\"",
                "unknown field `unit`",
            ),
            (
                "medium = \"air\"",
                "medium = \"air\"\nmass_kg = 1",
                "unknown field `mass_kg`",
            ),
            ("rate_hz = 100", "rate_hz = \"fast\"", "invalid type"),
            ("sign = -1", "sign = -1.0", "invalid type"),
        ] {
            let text = ok.replacen(from, to, 1);
            // The line of the key put in: the last of `to`.
            let at = text.find(to).unwrap() + to.rfind('\n').map_or(0, |i| i + 1);
            let line = text[..at].matches('\n').count() + 1;
            let err = parse(&text).unwrap_err().to_string();
            assert!(
                err.starts_with(&format!("lab.toml:{line}: ")),
                "{to}: {err}"
            );
            assert!(err.contains(says), "{to}: {err}");
        }
        let err = parse("format = \"finrs-import/1\"\n[tim]\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("unknown field `tim`"), "{err}");
        let err = parse("[time\n").unwrap_err().to_string();
        assert!(err.starts_with("lab.toml:1: "), "{err}");
    }

    #[test]
    fn a_source_s_rules() {
        let with =
            |source: &str| parse(&format!("{}\n[source]\n{source}\n", whole("rate_hz = 100")));
        let s = with("delimiter = \";\"\ndecimal_comma = true\nheader_row = 3").unwrap();
        assert_eq!(
            (s.source().delimiter, s.source().first_data_row),
            (Some(b';'), 4)
        );
        assert_eq!(
            with("delimiter = \"\\t\"").unwrap().source().delimiter,
            Some(b'\t')
        );
        for (source, says) in [
            (
                "delimiter = \";;\"",
                "source.delimiter: must be one ASCII character",
            ),
            ("delimiter = \"\"", "source.delimiter:"),
            (
                "delimiter = \",\"\ndecimal_comma = true",
                "source.decimal_comma: a comma cannot",
            ),
            ("header_row = -1", "source.header_row:"),
            (
                "header_row = 2\nfirst_data_row = 2",
                "source.first_data_row: must be a row number after header_row = 2",
            ),
            (
                "header_row = 0",
                "channel[1].column: source.header_row = 0: there are no names",
            ),
        ] {
            let err = with(source).unwrap_err().to_string();
            assert!(
                err.starts_with(&format!("lab.toml: {says}")),
                "{source}: {err}"
            );
        }
    }

    #[test]
    fn targets_parse_as_the_format_names_them() {
        for name in ["v1_V", "v8_V", "i2_A", "tip_y_m", "dot3_x_m", "force_N"] {
            assert_eq!(Target::parse(name).unwrap().name(), name);
        }
        for bad in ["v0_V", "v01_V", "V1_V", "v1_v", "t_s", "i1_a", "v_V"] {
            assert_eq!(Target::parse(bad), None, "{bad}");
        }
    }
}
