//! A bench protocol: the recordings of one session, in order, as a TOML
//! file (`finrs-protocol/1`, described in `docs/bench.md`). Read and checked before
//! any probe is touched; a refusal names the file, the field and the rule.
//!
//! ```
//! use finrs::protocol::Protocol;
//!
//! let p = Protocol::parse("p.toml", r#"
//! format = "finrs-protocol/1"
//! medium = "air"
//!
//! [[recording]]
//! name = "blocked_step_2.0V"
//! fixture = "blocked"
//! wave = "step:2"
//! hold_s = 4.0
//! "#).unwrap();
//! assert_eq!(p.recordings[0].file_name(1), "01_blocked_step_2.0V.csv");
//! assert!(p.recordings[0].tare, "blocked recordings tare first");
//! ```

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::recording::{Fixture, Geometry, Medium};
use crate::wave::Wave;

/// The format's name and version, the file's `format` key.
pub const FORMAT: &str = "finrs-protocol/1";

/// A refused protocol: the file, where, and the rule.
#[derive(Debug, thiserror::Error)]
#[error("{file}: {what}")]
pub struct ProtocolError {
    /// The protocol file.
    pub file: String,
    /// The field and the rule it breaks (or the TOML parser's message,
    /// with its line).
    pub what: String,
}

/// One recording of the session (serialised with the protocol's field
/// names, for a program reading `finrs plan --json`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Step {
    /// Name of the file without its number and `.csv`.
    pub name: String,
    /// How the tip is held.
    #[serde(serialize_with = "fixture_name")]
    pub fixture: Fixture,
    /// The wave, as `finrs wave` takes it.
    pub wave: String,
    /// 0 V before the wave, s.
    pub rest_s: f64,
    /// The wave, s (a chirp sweeps over it).
    pub hold_s: f64,
    /// 0 V after the wave, s.
    pub off_s: f64,
    /// Tare the load cell first (blocked recordings; default yes).
    pub tare: bool,
    /// Asked of the operator before the recording (e.g. "re-clamp the
    /// strip"); the run waits for Enter.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prompt: Option<String>,
    /// Words for the recording's notes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub notes: Option<String>,
}

fn fixture_name<S: serde::Serializer>(f: &Fixture, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(f.name())
}

impl Step {
    /// The recording's file name as the `k`-th of the session (from 1).
    pub fn file_name(&self, k: usize) -> String {
        format!("{k:02}_{}.csv", self.name)
    }
}

/// A whole protocol.
#[derive(Clone, Debug, PartialEq)]
pub struct Protocol {
    /// The sample's id, for every recording's metadata.
    pub sample: Option<String>,
    /// What surrounds the strip.
    pub medium: Medium,
    /// The strip (the seed's, unless given).
    pub geometry: Geometry,
    /// Tracked dots' positions from the clamp, m (free recordings).
    pub dots_s_m: Option<Vec<f64>>,
    /// A fitted model (`finrs fit`'s parameter file) the board is sent
    /// before the first recording (`finrs tune`), for `motion:` waves; a
    /// path relative to the protocol's folder.
    pub model: Option<PathBuf>,
    /// The recordings, in order.
    pub recordings: Vec<Step>,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawProtocol {
    format: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    sample: Option<String>,
    medium: String,
    length_m: Option<f64>,
    width_m: Option<f64>,
    thickness_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    dots_s_m: Option<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    model: Option<String>,
    #[serde(default)]
    recording: Vec<RawStep>,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RawStep {
    name: String,
    fixture: String,
    wave: String,
    #[serde(default = "default_rest_s")]
    rest_s: f64,
    hold_s: f64,
    #[serde(default = "default_off_s")]
    off_s: f64,
    tare: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    prompt: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    notes: Option<String>,
}

fn default_rest_s() -> f64 {
    1.5
}

fn default_off_s() -> f64 {
    2.5
}

impl Protocol {
    /// Reads and checks the protocol at `path`.
    pub fn read(path: &Path) -> Result<Self, ProtocolError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ProtocolError {
            file: file.clone(),
            what: format!("cannot read: {e}"),
        })?;
        Self::parse(&file, &text)
    }

    /// The protocol as `finrs-protocol/1` text, which [`Protocol::parse`]
    /// reads back as it is.
    pub fn to_toml(&self) -> String {
        let raw = RawProtocol {
            format: FORMAT.to_string(),
            sample: self.sample.clone(),
            medium: self.medium.name().to_string(),
            length_m: Some(self.geometry.length_m),
            width_m: Some(self.geometry.width_m),
            thickness_m: Some(self.geometry.thickness_m),
            dots_s_m: self.dots_s_m.clone(),
            model: self.model.as_ref().map(|p| p.display().to_string()),
            recording: self
                .recordings
                .iter()
                .map(|s| RawStep {
                    name: s.name.clone(),
                    fixture: s.fixture.name().to_string(),
                    wave: s.wave.clone(),
                    rest_s: s.rest_s,
                    hold_s: s.hold_s,
                    off_s: s.off_s,
                    tare: Some(s.tare),
                    prompt: s.prompt.clone(),
                    notes: s.notes.clone(),
                })
                .collect(),
        };
        toml::to_string(&raw).expect("strings, numbers and arrays always serialise")
    }

    /// Checks the protocol in `text`, named `file` in refusals.
    pub fn parse(file: &str, text: &str) -> Result<Self, ProtocolError> {
        let err = |what: String| ProtocolError {
            file: file.to_string(),
            what,
        };
        let raw: RawProtocol = toml::from_str(text).map_err(|e| err(e.to_string()))?;
        if raw.format != FORMAT {
            return Err(err(format!("format: {:?} is not {FORMAT:?}", raw.format)));
        }
        let medium = match raw.medium.as_str() {
            "air" => Medium::Air,
            "water" => Medium::Water,
            other => {
                return Err(err(format!(
                    "medium: {other:?} is not \"air\" or \"water\""
                )))
            }
        };
        let seed = Geometry::THESIS_2006;
        let length = |key: &str, v: Option<f64>, default: f64| match v {
            None => Ok(default),
            Some(x) if x.is_finite() && x > 0.0 => Ok(x),
            Some(x) => Err(err(format!(
                "{key}: {x} must be a positive length in metres"
            ))),
        };
        let geometry = Geometry {
            length_m: length("length_m", raw.length_m, seed.length_m)?,
            width_m: length("width_m", raw.width_m, seed.width_m)?,
            thickness_m: length("thickness_m", raw.thickness_m, seed.thickness_m)?,
        };
        if let Some(dots) = &raw.dots_s_m {
            let inside = dots.iter().all(|&s| s > 0.0 && s <= geometry.length_m);
            let increasing = dots.windows(2).all(|w| w[0] < w[1]);
            if dots.is_empty() || !inside || !increasing {
                return Err(err(format!(
                    "dots_s_m: {dots:?} must be at least one position, each in (0, length_m], strictly increasing"
                )));
            }
        }
        if raw.recording.is_empty() {
            return Err(err(
                "no [[recording]]: a protocol records at least once".to_string()
            ));
        }
        let mut recordings: Vec<Step> = Vec::with_capacity(raw.recording.len());
        for (i, r) in raw.recording.into_iter().enumerate() {
            let at =
                |field: &str, rule: String| err(format!("recording[{}].{field}: {rule}", i + 1));
            let name_ok = !r.name.is_empty()
                && r.name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || "._-".contains(c));
            if !name_ok {
                return Err(at(
                    "name",
                    format!("{:?} must be letters, digits, '.', '_' or '-' only", r.name),
                ));
            }
            if recordings.iter().any(|s| s.name == r.name) {
                return Err(at("name", format!("{:?} is used twice", r.name)));
            }
            let fixture = match r.fixture.as_str() {
                "free" => Fixture::Free,
                "blocked" => Fixture::Blocked,
                other => {
                    return Err(at(
                        "fixture",
                        format!("{other:?} is not \"free\" or \"blocked\""),
                    ))
                }
            };
            Wave::parse(&r.wave).map_err(|e| at("wave", e.to_string()))?;
            for (field, v, zero_ok) in [
                ("rest_s", r.rest_s, true),
                ("hold_s", r.hold_s, false),
                ("off_s", r.off_s, true),
            ] {
                if !(v.is_finite() && (v > 0.0 || (zero_ok && v == 0.0))) {
                    let rule = if zero_ok { "0 or more" } else { "above 0" };
                    return Err(at(field, format!("{v} must be {rule} seconds")));
                }
            }
            if r.tare == Some(true) && fixture == Fixture::Free {
                return Err(at(
                    "tare",
                    "a free recording has no load cell to tare".to_string(),
                ));
            }
            recordings.push(Step {
                name: r.name,
                fixture,
                wave: r.wave,
                rest_s: r.rest_s,
                hold_s: r.hold_s,
                off_s: r.off_s,
                tare: r.tare.unwrap_or(fixture == Fixture::Blocked),
                prompt: r.prompt,
                notes: r.notes,
            });
        }
        let model = match raw.model {
            None => None,
            Some(m) if m.is_empty() => {
                return Err(err(
                    "model: an empty path; leave the key out for none".to_string()
                ))
            }
            // Relative to the protocol's folder, as a user writes it.
            Some(m) => Some(Path::new(file).parent().unwrap_or(Path::new("")).join(m)),
        };
        Ok(Protocol {
            sample: raw.sample,
            medium,
            geometry,
            dots_s_m: raw.dots_s_m,
            model,
            recordings,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_example_protocol_is_written_as_it_reads() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/bench/protocol.toml");
        let p = Protocol::read(&path).unwrap();
        let text = p.to_toml();
        let again = Protocol::parse("again.toml", &text).unwrap();
        assert_eq!(again, p, "{text}");
        assert!(text.contains("[[recording]]"), "{text}");
    }

    /// A model's path is the protocol folder's; an empty one is refused.
    #[test]
    fn a_model_is_found_beside_the_protocol() {
        let text = |model: &str| {
            format!(
                "format = \"finrs-protocol/1\"\nmedium = \"air\"\nmodel = {model:?}\n\
                 [[recording]]\nname = \"m\"\nfixture = \"free\"\nwave = \"motion:0.001,1,60\"\nhold_s = 5\n"
            )
        };
        let p = Protocol::parse("bench/day1/protocol.toml", &text("fit.toml")).unwrap();
        assert_eq!(p.model, Some(PathBuf::from("bench/day1/fit.toml")));
        let e = Protocol::parse("p.toml", &text("")).unwrap_err();
        assert!(e.to_string().contains("model: an empty path"), "{e}");
    }
}
