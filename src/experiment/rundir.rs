//! The report directory as a resource that a run owns: one run at a time
//! (an advisory lock on `.lixel.lock`, which records the holder's PID), a
//! previous report is never destroyed (refused, or moved aside into
//! `replaced-N/` with `force`), `--resume` continues only a run with the
//! same identity, and every rewrite is atomic (temporary file in the same
//! directory, fsync, rename), so a kill at any moment leaves either the old
//! file or the new one.

use std::fs::File;
use std::io::{Read as _, Seek as _, Write as _};
use std::path::{Path, PathBuf};

use fs4::FileExt;

use super::identity::{Identity, RESULT_NEUTRAL_SETTINGS};
use super::{ExperimentConfig, ExperimentError};

/// Files and folders that make a directory hold a report.
pub(super) const REPORT_FILES: [&str; 9] = [
    "configs.csv",
    "summary.csv",
    "report.md",
    "settings.json",
    "settings.txt",
    "sorted-errors.png",
    "equivalence.png",
    "images",
    "merge.md",
];

const LOCK_FILE: &str = ".lixel.lock";

/// How long a run waits for a report directory's lock before it refuses.
const LOCK_PATIENCE: std::time::Duration = std::time::Duration::from_secs(1);

pub(super) fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ExperimentError + '_ {
    move |source| ExperimentError::Io { path: path.to_path_buf(), source }
}

/// A locked report directory; the lock is released when this is dropped
/// (or the process dies: the kernel drops advisory locks with the file).
#[derive(Debug)]
pub(super) struct RunDir {
    path: PathBuf,
    _lock: File,
    /// Accepted differences from the resumed run's settings.
    pub(super) resumed_with: Vec<String>,
    /// Where a previous report was moved by `force`.
    pub(super) moved_to: Option<PathBuf>,
}

impl RunDir {
    /// Creates and locks the report directory of `config`; refuses a
    /// previous report unless `resume` (same identity required) or `force`
    /// (moves it aside).
    pub(super) fn prepare(config: &ExperimentConfig, identity: &Identity) -> Result<Self, ExperimentError> {
        let mut dir = Self::lock(&report_dir(config))?;
        if !holds_report(&dir.path) {
            return Ok(dir);
        }
        if config.resume {
            if dir.path.join("configs.csv").exists() {
                let recorded = Identity::read(&dir.path)?;
                let context = format!("--resume in {}", dir.path.display());
                dir.resumed_with = identity.check_against(&recorded, &RESULT_NEUTRAL_SETTINGS, &context)?;
            }
            return Ok(dir);
        }
        if config.force {
            dir.moved_to = Some(move_aside(&dir.path)?);
            return Ok(dir);
        }
        Err(ExperimentError::ReportExists { dir: dir.path.clone() })
    }

    /// Creates `path` and takes its lock, recording this process's id.
    pub(super) fn lock(path: &Path) -> Result<Self, ExperimentError> {
        std::fs::create_dir_all(path).map_err(io(path))?;
        let lock_path = path.join(LOCK_FILE);
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&lock_path)
            .map_err(io(&lock_path))?;
        // A lock held only by a child this process is spawning (its copy of
        // the descriptor lives from fork to exec) or by a run that is just
        // ending clears within milliseconds; a run that holds the directory
        // keeps it. So a refusal waits out LOCK_PATIENCE first.
        let asked = std::time::Instant::now();
        while FileExt::try_lock(&file).is_err() {
            if asked.elapsed() >= LOCK_PATIENCE {
                let mut text = String::new();
                let _ = file.read_to_string(&mut text);
                return Err(ExperimentError::Locked { dir: path.to_path_buf(), pid: text.trim().parse().ok() });
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
        // The holder's PID, for the message a second run gets.
        let record = file
            .set_len(0)
            .and_then(|()| file.rewind())
            .and_then(|()| writeln!(file, "{}", std::process::id()))
            .and_then(|()| file.flush());
        record.map_err(io(&lock_path))?;
        Ok(Self { path: path.to_path_buf(), _lock: file, resumed_with: Vec::new(), moved_to: None })
    }

    /// The directory.
    pub(super) fn path(&self) -> &Path {
        &self.path
    }
}

/// The report directory of `config`: `out`, or `out/shard-I-of-N` for a shard.
#[must_use]
pub fn report_dir(config: &ExperimentConfig) -> PathBuf {
    match config.shard {
        Some(s) => config.out.join(format!("shard-{}-of-{}", s.index, s.count)),
        None => config.out.clone(),
    }
}

/// Whether `dir` holds any file of a report.
pub(super) fn holds_report(dir: &Path) -> bool {
    REPORT_FILES.iter().any(|f| dir.join(f).exists())
}

/// Moves every report file of `dir` into the first free `dir/replaced-N/`.
fn move_aside(dir: &Path) -> Result<PathBuf, ExperimentError> {
    let target = (1u32..)
        .map(|n| dir.join(format!("replaced-{n}")))
        .find(|p| !p.exists())
        .unwrap_or_else(|| dir.join("replaced"));
    std::fs::create_dir(&target).map_err(io(&target))?;
    for f in REPORT_FILES {
        let from = dir.join(f);
        if from.exists() {
            std::fs::rename(&from, target.join(f)).map_err(io(&from))?;
        }
    }
    Ok(target)
}

/// Writes `bytes` to `path` atomically: a temporary file in the same
/// directory, fsync, rename over `path`, fsync of the directory. A crash at
/// any point leaves either the old content or the new.
///
/// # Errors
/// [`ExperimentError::Io`] naming the file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), ExperimentError> {
    write_atomic_with(path, bytes, |_| Ok(())).map_err(io(path))
}

/// [`write_atomic`] with a hook run between the write (and fsync) of the
/// temporary file and the rename: tests inject a failure there, as a kill
/// in that window would. On failure the temporary file is removed and
/// `path` is untouched.
pub(super) fn write_atomic_with(
    path: &Path,
    bytes: &[u8],
    before_rename: impl FnOnce(&Path) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| {
        let mut file = File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        drop(file);
        before_rename(&tmp)?;
        std::fs::rename(&tmp, path)?;
        // The rename itself is durable once the directory is synced.
        if let Ok(d) = File::open(&dir) {
            let _ = d.sync_all();
        }
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("lixel-rundir-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_failure_between_write_and_rename_keeps_the_old_file_and_no_temporary() {
        let dir = temp("atomic");
        let path = dir.join("configs.csv");
        std::fs::write(&path, "old content\n").unwrap();
        let err = write_atomic_with(&path, b"new content\n", |tmp| {
            // The new bytes are complete and durable in the temporary file...
            assert_eq!(std::fs::read(tmp).unwrap(), b"new content\n");
            // ...and the process dies before the rename.
            Err(std::io::Error::other("killed"))
        });
        assert!(err.is_err());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old content\n");
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(left, vec![std::ffi::OsString::from("configs.csv")], "temporary file left behind");
        write_atomic(&path, b"new content\n").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new content\n");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_second_lock_fails_at_once_naming_the_holder() {
        let dir = temp("lock");
        let first = RunDir::lock(&dir).unwrap();
        match RunDir::lock(&dir) {
            Err(ExperimentError::Locked { pid, .. }) => assert_eq!(pid, Some(std::process::id())),
            other => panic!("expected Locked, got {other:?}"),
        }
        let message = RunDir::lock(&dir).unwrap_err().to_string();
        assert!(message.contains(&format!("PID {}", std::process::id())), "{message}");
        drop(first);
        RunDir::lock(&dir).expect("the lock is released with the run");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn force_moves_the_old_report_aside_and_never_deletes_it() {
        let dir = temp("force");
        std::fs::write(dir.join("configs.csv"), "rows\n").unwrap();
        std::fs::write(dir.join("notes.txt"), "mine\n").unwrap();
        assert!(holds_report(&dir));
        let first = move_aside(&dir).unwrap();
        assert_eq!(first, dir.join("replaced-1"));
        assert_eq!(std::fs::read_to_string(first.join("configs.csv")).unwrap(), "rows\n");
        assert!(!holds_report(&dir));
        assert!(dir.join("notes.txt").exists(), "files that are not the report stay");
        std::fs::write(dir.join("report.md"), "second\n").unwrap();
        assert_eq!(move_aside(&dir).unwrap(), dir.join("replaced-2"));
        assert!(first.join("configs.csv").exists());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
