//! The metadata lines, `# key = value`, values as in TOML.

use super::error::RecordingError;
use super::geometry::Geometry;

/// The only format this reader knows.
pub const FORMAT: &str = "ipmc-bench/1";

/// How the tip is held.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Fixture {
    /// Tip free; a camera tracks it.
    Free,
    /// Tip held at rest by the load cell.
    Blocked,
}

/// What surrounds the strip.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Medium {
    /// Air.
    Air,
    /// Water.
    Water,
}

impl Medium {
    /// Density of the medium, kg/m³ (fresh water at room temperature;
    /// dry air at sea level).
    pub fn density_kg_per_m3(self) -> f64 {
        match self {
            Medium::Air => 1.2,
            Medium::Water => 1000.0,
        }
    }

    /// Added mass per length of a plate of width `width_m` moving across
    /// its plane in the medium, kg/m: `ρ π b² / 4`, the classical value.
    pub fn plate_added_mass_kg_per_m(self, width_m: f64) -> f64 {
        self.density_kg_per_m3() * std::f64::consts::PI * width_m.powi(2) / 4.0
    }
}

impl Fixture {
    /// As the format writes it: `free` or `blocked`.
    pub fn name(self) -> &'static str {
        match self {
            Fixture::Free => "free",
            Fixture::Blocked => "blocked",
        }
    }
}

impl Medium {
    /// As the format writes it: `air` or `water`.
    pub fn name(self) -> &'static str {
        match self {
            Medium::Air => "air",
            Medium::Water => "water",
        }
    }
}

/// The metadata of a recording.
#[derive(Clone, Debug, PartialEq)]
pub struct Metadata {
    /// Independently driven segments N, 1..=8, equal length.
    pub segments: usize,
    /// Free length, m.
    pub length_m: f64,
    /// Width, m.
    pub width_m: f64,
    /// Thickness, m.
    pub thickness_m: f64,
    /// How the tip is held.
    pub fixture: Fixture,
    /// What surrounds the strip.
    pub medium: Medium,
    /// Sample id.
    pub sample: Option<String>,
    /// Cation of the sample.
    pub cation: Option<String>,
    /// Arc-length position of each tracked dot from the clamp, m.
    pub dots_s_m: Option<Vec<f64>>,
    /// Free text.
    pub notes: Option<String>,
    /// Seconds from the start of the session's first recording to this
    /// one's `t_s = 0`: the clock drying is measured against.
    pub t_session_start_s: Option<f64>,
}

impl Metadata {
    /// The required keys only: `segments` segments of a strip of
    /// `geometry`, held by `fixture` in `medium`; no optional key (sample,
    /// cation, dots, notes, session start).
    pub fn new(segments: usize, geometry: Geometry, fixture: Fixture, medium: Medium) -> Metadata {
        let Geometry {
            length_m,
            width_m,
            thickness_m,
        } = geometry;
        Metadata {
            segments,
            length_m,
            width_m,
            thickness_m,
            fixture,
            medium,
            sample: None,
            cation: None,
            dots_s_m: None,
            notes: None,
            t_session_start_s: None,
        }
    }

    /// The strip's geometry.
    pub fn geometry(&self) -> Geometry {
        Geometry {
            length_m: self.length_m,
            width_m: self.width_m,
            thickness_m: self.thickness_m,
        }
    }
}

const REQUIRED: [&str; 7] = [
    "format",
    "segments",
    "length_m",
    "width_m",
    "thickness_m",
    "fixture",
    "medium",
];
const OPTIONAL: [&str; 5] = ["sample", "cation", "dots_s_m", "notes", "t_session_start_s"];

/// Collects metadata lines, then checks them as a whole.
#[derive(Default)]
pub(crate) struct MetaBuilder {
    values: Vec<(String, toml::Value, usize)>,
}

impl MetaBuilder {
    /// Takes one `# key = value` line (`line` 1-based).
    pub fn line(&mut self, file: &str, line: usize, text: &str) -> Result<(), RecordingError> {
        let body = text.strip_prefix('#').unwrap_or(text);
        let table: toml::Table = body.parse().map_err(|e: toml::de::Error| {
            RecordingError::at(
                file,
                line,
                format!(
                    "metadata must be `# key = value` with a TOML value: {}",
                    e.message()
                ),
            )
        })?;
        if table.len() != 1 {
            return Err(RecordingError::at(
                file,
                line,
                "metadata must be `# key = value`, one key per line",
            ));
        }
        let (key, value) = table.into_iter().next().expect("one entry");
        if !REQUIRED.contains(&key.as_str()) && !OPTIONAL.contains(&key.as_str()) {
            return Err(RecordingError::at(
                file,
                line,
                format!("unknown metadata key `{key}`"),
            ));
        }
        if let Some((_, _, first)) = self.values.iter().find(|(k, _, _)| *k == key) {
            return Err(RecordingError::at(
                file,
                line,
                format!("metadata key `{key}` given twice (first on line {first})"),
            ));
        }
        self.values.push((key, value, line));
        Ok(())
    }

    /// Checks the collected keys; `header_line` is where a missing key is
    /// reported.
    pub fn finish(self, file: &str, header_line: usize) -> Result<Metadata, RecordingError> {
        for key in REQUIRED {
            if self.get(key).is_none() {
                return Err(RecordingError::at(
                    file,
                    header_line,
                    format!("required metadata key `{key}` is missing before the header"),
                ));
            }
        }
        self.check_format(file)?;
        let segments = self.segments(file)?;
        let length_m = self.number(file, "length_m")?;
        let width_m = self.number(file, "width_m")?;
        let thickness_m = self.number(file, "thickness_m")?;
        let fixture = self.fixture(file)?;
        let medium = self.medium(file)?;
        let dots_s_m = match self.get("dots_s_m") {
            None => None,
            Some((_, v, l)) => Some(dots(file, *l, v, length_m)?),
        };
        let t_session_start_s = self.session_start_s(file)?;
        let geometry = Geometry {
            length_m,
            width_m,
            thickness_m,
        };
        Ok(Metadata {
            sample: self.string(file, "sample")?.map(|s| s.0),
            cation: self.string(file, "cation")?.map(|s| s.0),
            dots_s_m,
            notes: self.string(file, "notes")?.map(|s| s.0),
            t_session_start_s,
            ..Metadata::new(segments, geometry, fixture, medium)
        })
    }

    /// The value of `key` and its line, if given.
    fn get(&self, key: &str) -> Option<&(String, toml::Value, usize)> {
        self.values.iter().find(|(k, _, _)| k == key)
    }

    /// A string value and its line, if given.
    fn string(&self, file: &str, key: &str) -> Result<Option<(String, usize)>, RecordingError> {
        match self.get(key) {
            None => Ok(None),
            Some((_, toml::Value::String(s), l)) => Ok(Some((s.clone(), *l))),
            Some((_, _, l)) => Err(RecordingError::at(
                file,
                *l,
                format!("`{key}` must be a quoted string"),
            )),
        }
    }

    /// A required string value and its line ([`Self::finish`] has checked
    /// that every required key is there).
    fn required_string(&self, file: &str, key: &str) -> Result<(String, usize), RecordingError> {
        Ok(self.string(file, key)?.expect("required"))
    }

    /// A required positive, finite number.
    fn number(&self, file: &str, key: &str) -> Result<f64, RecordingError> {
        let (_, v, l) = self.get(key).expect("required");
        let Some(x) = as_number(v) else {
            return Err(RecordingError::at(
                file,
                *l,
                format!("`{key}` must be a number"),
            ));
        };
        if !x.is_finite() || x <= 0.0 {
            return Err(RecordingError::at(
                file,
                *l,
                format!("`{key}` must be positive and finite, got {x}"),
            ));
        }
        Ok(x)
    }

    fn check_format(&self, file: &str) -> Result<(), RecordingError> {
        let (format, format_line) = self.required_string(file, "format")?;
        if format != FORMAT {
            return Err(RecordingError::at(
                file,
                format_line,
                format!("format must be \"{FORMAT}\", got \"{format}\""),
            ));
        }
        Ok(())
    }

    fn segments(&self, file: &str) -> Result<usize, RecordingError> {
        let (_, seg_value, seg_line) = self.get("segments").expect("required");
        match seg_value {
            toml::Value::Integer(n) if (1..=8).contains(n) => Ok(*n as usize),
            _ => Err(RecordingError::at(
                file,
                *seg_line,
                format!("`segments` must be a whole number from 1 to 8, got {seg_value}"),
            )),
        }
    }

    fn fixture(&self, file: &str) -> Result<Fixture, RecordingError> {
        let (fixture, l) = self.required_string(file, "fixture")?;
        match fixture.as_str() {
            "free" => Ok(Fixture::Free),
            "blocked" => Ok(Fixture::Blocked),
            other => Err(RecordingError::at(
                file,
                l,
                format!("fixture must be \"free\" or \"blocked\", got \"{other}\""),
            )),
        }
    }

    fn medium(&self, file: &str) -> Result<Medium, RecordingError> {
        let (medium, l) = self.required_string(file, "medium")?;
        match medium.as_str() {
            "air" => Ok(Medium::Air),
            "water" => Ok(Medium::Water),
            other => Err(RecordingError::at(
                file,
                l,
                format!("medium must be \"air\" or \"water\", got \"{other}\""),
            )),
        }
    }

    fn session_start_s(&self, file: &str) -> Result<Option<f64>, RecordingError> {
        let Some((_, v, l)) = self.get("t_session_start_s") else {
            return Ok(None);
        };
        let Some(x) = as_number(v) else {
            return Err(RecordingError::at(
                file,
                *l,
                "`t_session_start_s` must be a number of seconds".to_string(),
            ));
        };
        if !x.is_finite() || x < 0.0 {
            return Err(RecordingError::at(
                file,
                *l,
                format!("`t_session_start_s` must be zero or positive and finite, got {x}"),
            ));
        }
        Ok(Some(x))
    }
}

/// A TOML number (float or integer) as `f64`.
fn as_number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

fn dots(
    file: &str,
    line: usize,
    v: &toml::Value,
    length_m: f64,
) -> Result<Vec<f64>, RecordingError> {
    let err = |m: String| RecordingError::at(file, line, m);
    let toml::Value::Array(items) = v else {
        return Err(err("`dots_s_m` must be an array of numbers".to_string()));
    };
    if items.is_empty() {
        return Err(err("`dots_s_m` must name at least one dot".to_string()));
    }
    let mut out = Vec::with_capacity(items.len());
    for item in items {
        let Some(s) = as_number(item) else {
            return Err(err("`dots_s_m` must be an array of numbers".to_string()));
        };
        if !(s.is_finite() && s > 0.0 && s <= length_m) {
            return Err(err(format!(
                "`dots_s_m` positions must lie in (0, length_m = {length_m}], got {s}"
            )));
        }
        if out.last().is_some_and(|&prev| s <= prev) {
            return Err(err("`dots_s_m` must be strictly increasing".to_string()));
        }
        out.push(s);
    }
    Ok(out)
}

impl Metadata {
    /// The metadata lines, in the order the format lists them.
    pub(crate) fn to_lines(&self) -> String {
        let q = |s: &str| basic_string(s);
        let mut out = String::new();
        out.push_str(&format!("# format = {}\n", q(FORMAT)));
        out.push_str(&format!("# segments = {}\n", self.segments));
        out.push_str(&format!("# length_m = {:?}\n", self.length_m));
        out.push_str(&format!("# width_m = {:?}\n", self.width_m));
        out.push_str(&format!("# thickness_m = {:?}\n", self.thickness_m));
        if let Some(s) = &self.sample {
            out.push_str(&format!("# sample = {}\n", q(s)));
        }
        if let Some(s) = &self.cation {
            out.push_str(&format!("# cation = {}\n", q(s)));
        }
        out.push_str(&format!("# fixture = {}\n", q(self.fixture.name())));
        out.push_str(&format!("# medium = {}\n", q(self.medium.name())));
        if let Some(d) = &self.dots_s_m {
            let items: Vec<String> = d.iter().map(|x| format!("{x:?}")).collect();
            out.push_str(&format!("# dots_s_m = [{}]\n", items.join(", ")));
        }
        if let Some(s) = &self.notes {
            out.push_str(&format!("# notes = {}\n", q(s)));
        }
        if let Some(t) = self.t_session_start_s {
            out.push_str(&format!("# t_session_start_s = {t:?}\n"));
        }
        out
    }
}

/// A TOML basic string on one line: quotes, backslashes and control
/// characters escaped (the `toml` crate would write a multi-line string for
/// text with line breaks, which cannot stand on one metadata line).
fn basic_string(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => out.push_str(&format!("\\u{:04X}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}
