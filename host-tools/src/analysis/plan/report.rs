//! The plan as the terminal shows it.

use std::fmt;

use super::proposals::Plan;

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let model = if self.effects.is_empty() {
            "the baseline".to_string()
        } else {
            format!("the baseline + {}", self.effects.join(", "))
        };
        writeln!(f, "plan for {model}")?;
        writeln!(
            f,
            "now (smallest strength the diagnosis could name; plausible):"
        )?;
        for i in &self.now {
            // Large deflection has no strength: it is the arc, whole.
            let smallest = match (i.smallest_detectable, i.detectable) {
                (Some(s), _) => format!("from {s:.3e}"),
                (None, true) => "as a whole".to_string(),
                (None, false) => "at no strength up to the ceiling".to_string(),
            };
            let state = if i.detectable {
                "testable"
            } else {
                "NOT testable"
            };
            writeln!(
                f,
                "  {:<30} {state:<13} {smallest} ({}; plausible {})",
                i.effect, i.strength, i.plausible
            )?;
        }
        for a in &self.advice {
            writeln!(f, "  {:<30} not testable here: {}", a.effect, a.change)?;
        }
        writeln!(f, "each recording added alone, best first:")?;
        for p in &self.proposals {
            let chosen = if self.chosen.contains(&p.step.name) {
                "*"
            } else {
                " "
            };
            if let Some(why) = &p.refused {
                writeln!(f, "{chosen} {:<32} not assessed: {why}", p.step.name)?;
                continue;
            }
            let newly = if p.newly_detectable.is_empty() {
                String::new()
            } else {
                format!("; makes testable: {}", p.newly_detectable.join(", "))
            };
            writeln!(
                f,
                "{chosen} {:<32} {:>5.1} s {:>6.1} bits{newly}",
                p.step.name, p.duration_s, p.bits
            )?;
            writeln!(
                f,
                "    {} `{}`: {}",
                p.step.fixture.name(),
                p.step.wave,
                p.purpose
            )?;
        }
        let used: f64 = self
            .proposals
            .iter()
            .filter(|p| self.chosen.contains(&p.step.name))
            .map(|p| p.duration_s)
            .sum();
        if self.chosen.is_empty() {
            writeln!(
                f,
                "chosen: none (no recording adds information within {:.0} s)",
                self.budget_s
            )
        } else {
            writeln!(
                f,
                "chosen (*): {} recording(s), {used:.1} s of the {:.0} s budget; each was assessed alone, so two that show the same thing are worth less than their sum",
                self.chosen.len(),
                self.budget_s
            )
        }
    }
}
