//! Where an experiment run's wall time goes, stage by stage, so that the
//! throughput work on the paper preset (issue 15, item 5) measures before it
//! changes anything, and every report says what it cost.
//!
//! The stages are wall-clock spans of the runner's own work in this process;
//! they add up to a little less than the run time (scene loading, the report
//! writers and the row journal are not split out). A resumed run counts only
//! the configurations it ran itself.
//!
//! With several workers (`--jobs`), the per-configuration stages (truth to
//! comparison) are each worker's wall spans summed over the workers
//! (worker-seconds: up to `N` times the loop's wall time); the table then
//! gives the configurations' loop as one wall-clock line and those stages
//! as shares of the workers' summed time. The equivalence and the
//! pictures are wall time either way.

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
    /// Workers of the configurations' loop and its wall time, when more
    /// than one ran at once.
    workers: Option<(usize, Duration)>,
}

/// The stages each worker runs per configuration.
const PER_CONFIGURATION: [RunStage; 5] =
    [RunStage::Truth, RunStage::Coverage, RunStage::Matrices, RunStage::Lookups, RunStage::Compare];

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

    /// All stages together (with several workers, worker-seconds: see
    /// [`wall`](Self::wall)).
    #[must_use]
    pub fn total(&self) -> Duration {
        self.spent.iter().sum()
    }

    /// Adds another worker's stage times.
    pub fn absorb(&mut self, other: &Self) {
        for (mine, theirs) in self.spent.iter_mut().zip(other.spent) {
            *mine += theirs;
        }
    }

    /// Records that `workers` ran the configurations in `wall` (nothing
    /// changes for one worker).
    pub fn set_workers(&mut self, workers: usize, wall: Duration) {
        self.workers = (workers > 1).then_some((workers, wall));
    }

    /// Workers of the configurations' loop (1 unless several ran at once).
    #[must_use]
    pub fn workers(&self) -> usize {
        self.workers.map_or(1, |(n, _)| n)
    }

    /// Wall time of the timed stages: [`total`](Self::total) for one
    /// worker; with several, the configurations' loop plus the stages
    /// after it.
    #[must_use]
    pub fn wall(&self) -> Duration {
        match self.workers {
            None => self.total(),
            Some((_, wall)) => wall + self.get(RunStage::Equivalence) + self.get(RunStage::Pictures),
        }
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
        let Some((workers, wall)) = self.workers else {
            for stage in RunStage::ALL {
                let d = self.get(stage);
                let _ = writeln!(md, "| {} | {:.1} | {} |", stage.name(), d.as_secs_f64(), share(d));
            }
            let rest = elapsed.saturating_sub(self.total());
            let _ =
                writeln!(md, "| other (scene, caster, report files) | {:.1} | {} |", rest.as_secs_f64(), share(rest));
            return md;
        };
        let _ = writeln!(
            md,
            "| configurations ({workers} workers at once) | {:.1} | {} |",
            wall.as_secs_f64(),
            share(wall)
        );
        for stage in [RunStage::Equivalence, RunStage::Pictures] {
            let d = self.get(stage);
            let _ = writeln!(md, "| {} | {:.1} | {} |", stage.name(), d.as_secs_f64(), share(d));
        }
        let rest = elapsed.saturating_sub(self.wall());
        let _ = writeln!(
            md,
            "| other (scene, caster, workers' devices, report files) | {:.1} | {} |",
            rest.as_secs_f64(),
            share(rest)
        );
        let busy: Duration = PER_CONFIGURATION.iter().map(|&s| self.get(s)).sum();
        let _ = writeln!(
            md,
            "\nThe configurations' stages, each worker's wall time summed over the {workers} workers \
             ({:.1} worker-seconds in {:.1} s: {:.2} workers busy on average):\n",
            busy.as_secs_f64(),
            wall.as_secs_f64(),
            if wall.is_zero() { 0.0 } else { busy.as_secs_f64() / wall.as_secs_f64() }
        );
        let _ = writeln!(md, "| stage | worker s | share of worker time |");
        let _ = writeln!(md, "|---|---:|---:|");
        for stage in PER_CONFIGURATION {
            let d = self.get(stage);
            let part = if busy.is_zero() { 0.0 } else { 100.0 * d.as_secs_f64() / busy.as_secs_f64() };
            let _ = writeln!(md, "| {} | {:.1} | {part:.1}% |", stage.name(), d.as_secs_f64());
        }
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
        assert_eq!(s.wall(), s.total());
    }

    #[test]
    fn workers_sum_their_stages_and_the_loop_is_wall_time() {
        let mut a = RunStages::default();
        a.add(RunStage::Truth, Duration::from_secs(2));
        a.add(RunStage::Lookups, Duration::from_secs(6));
        let mut b = RunStages::default();
        b.add(RunStage::Truth, Duration::from_secs(2));
        b.add(RunStage::Lookups, Duration::from_secs(6));
        a.absorb(&b);
        a.set_workers(2, Duration::from_secs(9));
        a.add(RunStage::Equivalence, Duration::from_secs(1));
        assert_eq!((a.workers(), a.total(), a.wall()), (2, Duration::from_secs(17), Duration::from_secs(10)));
        let md = a.markdown(Duration::from_secs(10));
        assert!(md.contains("| configurations (2 workers at once) | 9.0 | 90.0% |"), "{md}");
        assert!(md.contains("16.0 worker-seconds in 9.0 s: 1.78 workers busy"), "{md}");
        assert!(md.contains("| ground truth | 4.0 | 25.0% |"), "{md}");
        assert!(md.contains("| method renders + readback | 12.0 | 75.0% |"), "{md}");
        // One worker: the table of a run without workers.
        let mut one = b.clone();
        one.set_workers(1, Duration::from_secs(8));
        assert_eq!((one.workers(), one.wall()), (1, Duration::from_secs(8)));
        assert!(!one.markdown(Duration::from_secs(9)).contains("workers"));
    }
}
