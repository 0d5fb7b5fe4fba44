//! Shards for batch schedulers: shard `I` of `N` runs the configurations
//! `k` with `k mod N = I` (interleaved rather than contiguous blocks, so
//! every shard gets a similar mix of light positions and similar run
//! time). The index comes from the command line (`--shard I/N`) or from the
//! environment a scheduler sets (`--shard env`: Slurm array jobs, or
//! Kubernetes Indexed Jobs with `--shard-count`).

use super::ExperimentConfig;

/// Shard `index` of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    /// This shard, `0..count`.
    pub index: usize,
    /// Shards in total.
    pub count: usize,
}

/// Why a shard could not be determined.
#[derive(Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum ShardError {
    /// `--shard` is not `I/N` or `env`.
    #[error("--shard {0:?}: expected I/N with 0 <= I < N (e.g. 3/20), or env")]
    Syntax(String),
    /// `I` is not below `N`, or `N` is 0.
    #[error("--shard: index {index} is not below the count {count}")]
    OutOfRange {
        /// The index.
        index: usize,
        /// The count.
        count: usize,
    },
    /// `--shard env` found no scheduler variables.
    #[error(
        "--shard env: neither SLURM_ARRAY_TASK_ID (with SLURM_ARRAY_TASK_COUNT) nor JOB_COMPLETION_INDEX (with --shard-count) is set"
    )]
    NoScheduler,
    /// A scheduler variable is not a number, or a count is missing.
    #[error("--shard env: {0}")]
    Environment(String),
}

impl Shard {
    /// Parses `I/N`.
    ///
    /// # Errors
    /// [`ShardError::Syntax`], [`ShardError::OutOfRange`].
    pub fn parse(text: &str) -> Result<Self, ShardError> {
        let (i, n) = text.split_once('/').ok_or_else(|| ShardError::Syntax(text.into()))?;
        let parse = |s: &str| s.trim().parse::<usize>().map_err(|_| ShardError::Syntax(text.into()));
        Self::new(parse(i)?, parse(n)?)
    }

    /// Shard `index` of `count`.
    ///
    /// # Errors
    /// [`ShardError::OutOfRange`] unless `index < count`.
    pub fn new(index: usize, count: usize) -> Result<Self, ShardError> {
        if index >= count {
            return Err(ShardError::OutOfRange { index, count });
        }
        Ok(Self { index, count })
    }

    /// The shard a scheduler assigned, from `var` (the environment):
    /// Slurm's `SLURM_ARRAY_TASK_ID` minus `SLURM_ARRAY_TASK_MIN` (0 when
    /// unset) of `SLURM_ARRAY_TASK_COUNT`, or Kubernetes'
    /// `JOB_COMPLETION_INDEX` of `count` (`--shard-count`, which also
    /// overrides Slurm's count).
    ///
    /// # Errors
    /// [`ShardError`] when no variable is set or one is not a number.
    pub fn from_env(var: impl Fn(&str) -> Option<String>, count: Option<usize>) -> Result<Self, ShardError> {
        let number = |name: &str| -> Result<Option<usize>, ShardError> {
            var(name)
                .map(|v| v.trim().parse().map_err(|_| ShardError::Environment(format!("{name}={v:?} is not a number"))))
                .transpose()
        };
        if let Some(id) = number("SLURM_ARRAY_TASK_ID")? {
            let min = number("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let count = match count {
                Some(c) => c,
                None => number("SLURM_ARRAY_TASK_COUNT")?.ok_or_else(|| {
                    ShardError::Environment("SLURM_ARRAY_TASK_COUNT is not set; give --shard-count".into())
                })?,
            };
            let index = id.checked_sub(min).ok_or_else(|| {
                ShardError::Environment(format!("SLURM_ARRAY_TASK_ID {id} is below SLURM_ARRAY_TASK_MIN {min}"))
            })?;
            return Self::new(index, count);
        }
        if let Some(index) = number("JOB_COMPLETION_INDEX")? {
            let count = count.ok_or_else(|| {
                ShardError::Environment("JOB_COMPLETION_INDEX is set but the shard count is not; give --shard-count N (the Job's completions)".into())
            })?;
            return Self::new(index, count);
        }
        Err(ShardError::NoScheduler)
    }

    /// Whether configuration `k` belongs to this shard.
    #[must_use]
    pub fn owns(self, k: usize) -> bool {
        k % self.count == self.index
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// The configurations `config` runs (its shard's, when sharded).
pub(super) fn indices(config: &ExperimentConfig) -> impl Iterator<Item = usize> + '_ {
    (0..config.configs).filter(move |&k| config.shard.is_none_or(|s| s.owns(k)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(pairs: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |name| pairs.iter().find(|(k, _)| *k == name).map(|(_, v)| (*v).to_string())
    }

    #[test]
    fn parses_i_of_n_and_rejects_the_rest() {
        assert_eq!(Shard::parse("3/20"), Ok(Shard { index: 3, count: 20 }));
        assert_eq!(Shard::parse("20/20"), Err(ShardError::OutOfRange { index: 20, count: 20 }));
        assert_eq!(Shard::parse("0/0"), Err(ShardError::OutOfRange { index: 0, count: 0 }));
        assert!(matches!(Shard::parse("3"), Err(ShardError::Syntax(_))));
        assert!(matches!(Shard::parse("-1/4"), Err(ShardError::Syntax(_))));
    }

    #[test]
    fn reads_slurm_and_kubernetes_variables() {
        let slurm = [("SLURM_ARRAY_TASK_ID", "7"), ("SLURM_ARRAY_TASK_COUNT", "20")];
        assert_eq!(Shard::from_env(env(&slurm), None), Ok(Shard { index: 7, count: 20 }));
        // `--array=1-20`: ids start at the array's minimum.
        let one_based =
            [("SLURM_ARRAY_TASK_ID", "20"), ("SLURM_ARRAY_TASK_MIN", "1"), ("SLURM_ARRAY_TASK_COUNT", "20")];
        assert_eq!(Shard::from_env(env(&one_based), None), Ok(Shard { index: 19, count: 20 }));
        let k8s = [("JOB_COMPLETION_INDEX", "4")];
        assert_eq!(Shard::from_env(env(&k8s), Some(5)), Ok(Shard { index: 4, count: 5 }));
        assert!(matches!(Shard::from_env(env(&k8s), None), Err(ShardError::Environment(_))));
        assert_eq!(Shard::from_env(env(&[]), Some(5)), Err(ShardError::NoScheduler));
        let bad = [("JOB_COMPLETION_INDEX", "x")];
        assert!(matches!(Shard::from_env(env(&bad), Some(5)), Err(ShardError::Environment(_))));
    }

    #[test]
    fn shards_partition_the_configurations() {
        let n = 4;
        let mut seen = vec![0; 23];
        for i in 0..n {
            let s = Shard::new(i, n).unwrap();
            for (k, count) in seen.iter_mut().enumerate() {
                *count += usize::from(s.owns(k));
            }
        }
        assert!(seen.iter().all(|&c| c == 1), "{seen:?}");
    }
}
