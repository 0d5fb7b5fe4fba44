//! Where an experiment run's wall time goes, stage by stage, so that the
//! throughput work on the paper preset (issue 15, item 5) measures before it
//! changes anything, and every report says what it cost.
//!
//! The stages are wall-clock spans of the runner's own work in this process;
//! they add up to a little less than the run time (scene loading, the report
//! writers and the row journal are not split out). A resumed run counts only
//! the configurations it ran itself.

use std::fmt::Write as _;
use std::time::{Duration, Instant};

/// One stage of an experiment run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunStage {
    /// Ray-cast (and focused 4000²) ground truth per configuration.
    Truth,
    /// The coverage truth of the antialiased lookups (sub-pixel rays).
    Coverage,
    /// Solving each method's matrix; the scene-optimized loop's frames count
    /// here, renders included.
    Matrices,
    /// Rendering each method's view with its matrix and reading the masks back.
    Lookups,
    /// Comparing masks with the truth (counts, visibility error).
    Compare,
    /// The resolution-equivalence ladder (its truths and renders).
    Equivalence,
    /// The best/median/worst pictures.
    Pictures,
}

impl RunStage {
    /// Every stage, in report order.
    pub const ALL: [Self; 7] =
        [Self::Truth, Self::Coverage, Self::Matrices, Self::Lookups, Self::Compare, Self::Equivalence, Self::Pictures];

    /// The stage's name in `report.md`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Truth => "ground truth",
            Self::Coverage => "coverage truth",
            Self::Matrices => "matrices (optimized loop included)",
            Self::Lookups => "method renders + readback",
            Self::Compare => "comparison with the truth",
            Self::Equivalence => "resolution equivalence",
            Self::Pictures => "pictures",
        }
    }
}

/// Accumulated wall time per [`RunStage`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunStages {
    spent: [Duration; RunStage::ALL.len()],
}

impl RunStages {
    /// Adds `time` to `stage`.
    pub fn add(&mut self, stage: RunStage, time: Duration) {
        self.spent[stage as usize] += time;
    }

    /// Adds the time since `since` to `stage` and returns now (for chaining
    /// stages one after another).
    pub fn lap(&mut self, stage: RunStage, since: Instant) -> Instant {
        let now = Instant::now();
        self.add(stage, now - since);
        now
    }

    /// Time spent in `stage`.
    #[must_use]
    pub fn get(&self, stage: RunStage) -> Duration {
        self.spent[stage as usize]
    }

    /// All stages together.
    #[must_use]
    pub fn total(&self) -> Duration {
        self.spent.iter().sum()
    }

    /// `report.md`'s "Where the time went" table (empty when nothing was timed).
    #[must_use]
    pub fn markdown(&self, elapsed: Duration) -> String {
        let mut md = String::new();
        if self.total().is_zero() {
            return md;
        }
        let _ = writeln!(md, "| stage | wall s | share of run |");
        let _ = writeln!(md, "|---|---:|---:|");
        let share = |d: Duration| {
            if elapsed.is_zero() {
                "-".to_string()
            } else {
                format!("{:.1}%", 100.0 * d.as_secs_f64() / elapsed.as_secs_f64())
            }
        };
        for stage in RunStage::ALL {
            let d = self.get(stage);
            let _ = writeln!(md, "| {} | {:.1} | {} |", stage.name(), d.as_secs_f64(), share(d));
        }
        let rest = elapsed.saturating_sub(self.total());
        let _ = writeln!(md, "| other (scene, caster, report files) | {:.1} | {} |", rest.as_secs_f64(), share(rest));
        md
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stages_add_up_and_render() {
        let mut s = RunStages::default();
        assert_eq!(s.markdown(Duration::from_secs(1)), "");
        s.add(RunStage::Truth, Duration::from_millis(1500));
        s.add(RunStage::Lookups, Duration::from_millis(500));
        s.add(RunStage::Truth, Duration::from_millis(500));
        assert_eq!(s.get(RunStage::Truth), Duration::from_secs(2));
        assert_eq!(s.total(), Duration::from_millis(2500));
        let md = s.markdown(Duration::from_secs(4));
        assert!(md.contains("| ground truth | 2.0 | 50.0% |"), "{md}");
        assert!(md.contains("| method renders + readback | 0.5 | 12.5% |"), "{md}");
        assert!(md.contains("| other (scene, caster, report files) | 1.5 | 37.5% |"), "{md}");
    }
}
