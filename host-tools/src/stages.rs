//! How long each stage of a long run took, from the names its progress
//! callback hears: a user whose diagnosis takes a minute sees where the
//! minute went, and a slow session is profiled without a profiler.

use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Stages in the order they began, each with its start.
pub struct Stages {
    started: Instant,
    marks: Mutex<Vec<(String, Instant)>>,
}

impl Stages {
    /// Starts the clock.
    pub fn new() -> Self {
        Self {
            started: Instant::now(),
            marks: Mutex::new(Vec::new()),
        }
    }

    /// The stage `name` begins now (and the one before it ends).
    pub fn begin(&self, name: &str) {
        // A poisoned lock only loses the timing line, never the run.
        if let Ok(mut marks) = self.marks.lock() {
            marks.push((name.to_string(), Instant::now()));
        }
    }

    /// Time since [`Stages::new`].
    pub fn total(&self) -> Duration {
        self.started.elapsed()
    }

    /// Each stage's time, `name 1.2 s` joined by `; `, the last ending now.
    pub fn summary(&self) -> String {
        let Ok(marks) = self.marks.lock() else {
            return String::new();
        };
        let now = Instant::now();
        let ends = marks.iter().skip(1).map(|m| m.1).chain([now]);
        marks
            .iter()
            .zip(ends)
            .map(|((name, from), to)| format!("{name} {:.1} s", (to - *from).as_secs_f64()))
            .collect::<Vec<_>>()
            .join("; ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_stage_is_named_once_in_order() {
        let s = Stages::new();
        assert_eq!(s.summary(), "");
        s.begin("baseline");
        s.begin("round 1: 3 candidates");
        let line = s.summary();
        let parts: Vec<&str> = line.split("; ").collect();
        assert_eq!(parts.len(), 2, "{line}");
        assert!(parts[0].starts_with("baseline ") && parts[0].ends_with(" s"));
        assert!(parts[1].starts_with("round 1: 3 candidates "));
    }
}
