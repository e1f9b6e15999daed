//! When a recording's rows were taken: its sample time, and where it sits
//! in its session's time (the `t_session_start_s` key, or the same words
//! in its notes, as earlier recordings wrote it).

use super::data::Recording;
use super::meta::Metadata;

/// Why a recording has no single sample time.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SampleTimeError {
    /// A row's interval differs from the first one by more than 0.1 %.
    #[error("row {row} (t = {t_s} s): the model needs evenly spaced rows, Δt = {dt_s} s here against {dt0_s} s at the start")]
    Uneven {
        /// 0-based data row.
        row: usize,
        /// Its time, s.
        t_s: f64,
        /// Its interval, s.
        dt_s: f64,
        /// The first interval, s.
        dt0_s: f64,
    },
    /// Fewer than two rows.
    #[error("the model needs at least two rows to know the sample time")]
    TooShort,
}

impl Recording {
    /// The sample time, s: the mean interval, once every row is within
    /// 0.1 % of the first interval.
    pub fn sample_time(&self) -> Result<f64, SampleTimeError> {
        sample_time(&self.t_s)
    }
}

fn sample_time(t_s: &[f64]) -> Result<f64, SampleTimeError> {
    if t_s.len() < 2 {
        return Err(SampleTimeError::TooShort);
    }
    let dt0_s = t_s[1] - t_s[0];
    for (row, w) in t_s.windows(2).enumerate() {
        let dt_s = w[1] - w[0];
        if (dt_s - dt0_s).abs() > 1e-3 * dt0_s {
            return Err(SampleTimeError::Uneven {
                row: row + 1,
                t_s: w[1],
                dt_s,
                dt0_s,
            });
        }
    }
    // The mean interval, so rounding in printed times does not accumulate.
    Ok((t_s[t_s.len() - 1] - t_s[0]) / (t_s.len() - 1) as f64)
}

impl Metadata {
    /// Session time at the recording's start, s: the `t_session_start_s`
    /// key, or where it is missing `t_session_start_s = …` in the notes
    /// (how recordings said it before the key): the dehydration clock.
    pub fn session_start_s(&self) -> Option<f64> {
        if let Some(t) = self.t_session_start_s {
            return Some(t);
        }
        let notes = self.notes.as_deref()?;
        let rest = &notes[notes.find("t_session_start_s")? + "t_session_start_s".len()..];
        let rest = rest.trim_start().strip_prefix('=')?.trim_start();
        let end = rest
            .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | 'e' | 'E' | '-' | '+')))
            .unwrap_or(rest.len());
        rest[..end].parse::<f64>().ok().filter(|t| t.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uneven_rows_are_named() {
        let err = sample_time(&[0.0, 0.001, 0.002, 0.0035]).unwrap_err();
        assert!(err.to_string().starts_with("row 3 (t = 0.0035 s)"), "{err}");
        assert_eq!(sample_time(&[0.0]), Err(SampleTimeError::TooShort));
        let dt = sample_time(&[0.0, 0.001, 0.002, 0.003]).unwrap();
        assert!((dt - 0.001).abs() < 1e-15);
    }

    #[test]
    fn session_start_is_read_from_notes() {
        let mut m = Recording::parse(
            "x.csv",
            "# format = \"ipmc-bench/1\"\n# segments = 1\n# length_m = 0.05\n# width_m = 0.01\n# thickness_m = 0.0003\n# fixture = \"free\"\n# medium = \"air\"\nt_s,v1_V\n0,0\n",
        )
        .unwrap()
        .meta;
        m.notes = Some("t_session_start_s = 97.000; run 5 of 10".into());
        assert_eq!(m.session_start_s(), Some(97.0));
        m.notes = Some("run 5, t_session_start_s=12.5".into());
        assert_eq!(m.session_start_s(), Some(12.5));
        m.notes = Some("t_session_start_s = soon".into());
        assert_eq!(m.session_start_s(), None);
        m.notes = None;
        assert_eq!(m.session_start_s(), None);
    }

    const HEAD: &str = "# format = \"ipmc-bench/1\"\n# segments = 1\n# length_m = 0.05\n# width_m = 0.01\n# thickness_m = 0.0003\n# fixture = \"free\"\n# medium = \"air\"\n";

    #[test]
    fn session_start_is_a_key_that_wins_over_the_notes_and_round_trips() {
        let text = format!(
            "{HEAD}# notes = \"t_session_start_s = 5\"\n# t_session_start_s = 97.25\nt_s,v1_V\n0,0\n"
        );
        let r = Recording::parse("k.csv", &text).unwrap();
        assert_eq!(r.meta.t_session_start_s, Some(97.25));
        assert_eq!(r.meta.session_start_s(), Some(97.25));
        let again =
            Recording::parse("k2.csv", &format!("{}t_s,v1_V\n0,0\n", r.meta.to_lines())).unwrap();
        assert_eq!(again.meta, r.meta);
    }

    #[test]
    fn a_bad_session_start_is_refused_by_line_and_rule() {
        for (value, rule) in [
            ("-1", "zero or positive"),
            ("\"soon\"", "a number of seconds"),
            ("nan", "zero or positive and finite"),
        ] {
            let text = format!("{HEAD}# t_session_start_s = {value}\nt_s,v1_V\n0,0\n");
            let e = Recording::parse("bad.csv", &text).unwrap_err().to_string();
            assert!(e.starts_with("bad.csv:8:"), "{e}");
            assert!(e.contains("`t_session_start_s`") && e.contains(rule), "{e}");
        }
    }
}
