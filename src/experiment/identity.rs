//! What identifies a run: its settings, the content of its scene and the
//! binary that made it. Written to `settings.json` in the report directory;
//! `--resume` and `lixel merge` compare identities instead of paths, so an
//! edited OBJ file or a different `--map` is refused, while the same scene
//! reached by another path, or more configurations, is accepted.

use std::io::Read as _;
use std::path::Path;

use serde_json::Value;
use sha2::{Digest as _, Sha256};

use super::{ExperimentConfig, ExperimentError, SceneSource};

/// Settings that never change a row of `configs.csv`, so `--resume` accepts
/// a run that differs in them: the number of configurations (each light is
/// seeded by its own index, so a run can be resumed to more of them) and the
/// resolution-equivalence settings (measured after the configurations, over
/// the whole run). The scene's path is also accepted when its content hash
/// is unchanged. The report directory, `--resume` and `--force` are not
/// recorded at all.
pub const RESULT_NEUTRAL_SETTINGS: [&str; 3] = ["configs", "equivalence_configs", "equivalence_ladder"];

/// Version of the `settings.json` layout.
const FORMAT: u32 = 1;

/// The identity of a run, as stored in `settings.json`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Identity {
    /// Layout version of this file.
    pub format: u32,
    /// `lixel` version that made the run (rows of different versions are
    /// never mixed: the methods or the procedural scene may have changed).
    pub lixel_version: String,
    /// SHA-256 of the scene file, OBJ or glTF (a `.gltf` file's external
    /// buffers are not hashed; `None` for the built-in scene, which the
    /// version and the triangle budget determine).
    pub scene_sha256: Option<String>,
    /// Every setting of the run (see [`ExperimentConfig`]).
    pub settings: ExperimentConfig,
}

/// The flag that sets a field of [`ExperimentConfig`], for messages.
fn flag(setting: &str) -> &'static str {
    match setting {
        "scene" => "--scene/--triangles",
        "eye" => "--eye",
        "target" => "--target",
        "fov_y_degrees" => "--fov",
        "light" => "--light",
        "configs" => "--configs",
        "seed" => "--seed",
        "screen" => "--screen",
        "map" => "--map",
        "cascades" => "--cascades",
        "methods" => "--methods",
        "truth" => "--truth",
        "equivalence_configs" => "--equivalence",
        "shard" => "--shard",
        _ => "--preset",
    }
}

/// SHA-256 of a file, in hex.
fn sha256_file(path: &Path) -> Result<String, ExperimentError> {
    let io = |source| ExperimentError::Io { path: path.to_path_buf(), source };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut hasher = Sha256::new();
    let mut buffer = vec![0u8; 1 << 16];
    loop {
        let n = file.read(&mut buffer).map_err(io)?;
        if n == 0 {
            break;
        }
        hasher.update(&buffer[..n]);
    }
    Ok(hasher.finalize().iter().map(|b| format!("{b:02x}")).collect())
}

impl Identity {
    /// The identity of a run with `config` (reads and hashes the scene file).
    ///
    /// # Errors
    /// [`ExperimentError::Io`] when the scene file cannot be read.
    pub fn of(config: &ExperimentConfig) -> Result<Self, ExperimentError> {
        let scene_sha256 = match &config.scene {
            SceneSource::Builtin { .. } | SceneSource::Large { .. } => None,
            SceneSource::File { path, .. } => Some(sha256_file(path)?),
        };
        Ok(Self {
            format: FORMAT,
            lixel_version: env!("CARGO_PKG_VERSION").to_string(),
            scene_sha256,
            settings: config.clone(),
        })
    }

    /// `settings.json`'s text.
    #[must_use]
    pub fn to_json(&self) -> String {
        // An identity always serializes (no maps with non-string keys, no
        // non-finite floats from the CLI); fall back to a marker otherwise.
        serde_json::to_string_pretty(self).map_or_else(|e| format!("{{\"error\": \"{e}\"}}"), |s| s + "\n")
    }

    /// Reads `settings.json` in `dir`.
    ///
    /// # Errors
    /// [`ExperimentError::Config`] when it is missing or unreadable (naming
    /// the file and what to do).
    pub fn read(dir: &Path) -> Result<Self, ExperimentError> {
        let path = dir.join("settings.json");
        let text = std::fs::read_to_string(&path).map_err(|e| {
            ExperimentError::Config(format!(
                "{}: {e}; without it the rows there cannot be checked against these settings (a report of an older lixel, or not a report)",
                path.display()
            ))
        })?;
        serde_json::from_str(&text)
            .map_err(|e| ExperimentError::Config(format!("{}: not a lixel settings file: {e}", path.display())))
    }

    /// Checks that rows made under `recorded` can stand beside rows made
    /// under `self`. `neutral` lists the settings allowed to differ; the
    /// scene's path may differ when the content hash agrees. Returns a line
    /// for every accepted difference.
    ///
    /// # Errors
    /// [`ExperimentError::SettingsDiffer`] naming the first differing setting
    /// that changes results, with both values.
    pub fn check_against(
        &self,
        recorded: &Self,
        neutral: &[&str],
        context: &str,
    ) -> Result<Vec<String>, ExperimentError> {
        let differ = |setting: &str, recorded: String, now: String| ExperimentError::SettingsDiffer {
            context: context.to_string(),
            setting: setting.to_string(),
            recorded,
            now,
        };
        if recorded.format != self.format {
            return Err(differ("settings.json format", recorded.format.to_string(), self.format.to_string()));
        }
        if recorded.lixel_version != self.lixel_version {
            return Err(differ("lixel version", recorded.lixel_version.clone(), self.lixel_version.clone()));
        }
        if recorded.scene_sha256 != self.scene_sha256 {
            let show =
                |h: &Option<String>| h.clone().map_or_else(|| "the built-in scene".into(), |h| format!("sha256 {h}"));
            return Err(differ("scene content (--scene)", show(&recorded.scene_sha256), show(&self.scene_sha256)));
        }
        let (Value::Object(old), Value::Object(new)) = (
            serde_json::to_value(&recorded.settings).unwrap_or(Value::Null),
            serde_json::to_value(&self.settings).unwrap_or(Value::Null),
        ) else {
            return Err(ExperimentError::Config(format!("{context}: settings do not serialize as a table")));
        };
        let mut accepted = Vec::new();
        let keys: std::collections::BTreeSet<&String> = old.keys().chain(new.keys()).collect();
        for key in keys {
            let (a, b) = (old.get(key).unwrap_or(&Value::Null), new.get(key).unwrap_or(&Value::Null));
            if a == b {
                continue;
            }
            // Two scene files that differ only in their path (the hashes agree).
            let only_path = match (&recorded.settings.scene, &self.settings.scene) {
                (SceneSource::File { options: a, .. }, SceneSource::File { options: b, .. }) => a == b,
                _ => false,
            };
            let line = format!("{key} ({}): {a} then {b}", flag(key));
            if neutral.contains(&key.as_str()) || (key == "scene" && only_path) {
                accepted.push(line);
            } else {
                return Err(differ(&format!("{key} ({})", flag(key)), a.to_string(), b.to_string()));
            }
        }
        Ok(accepted)
    }
}

#[cfg(test)]
mod tests {
    use super::super::Preset;
    use super::*;

    fn identity(config: ExperimentConfig, hash: Option<&str>) -> Identity {
        Identity {
            format: FORMAT,
            lixel_version: "1.0.0".into(),
            scene_sha256: hash.map(String::from),
            settings: config,
        }
    }

    #[test]
    fn settings_round_trip_as_json_with_names_not_debug_dumps() {
        let id = identity(ExperimentConfig::preset(Preset::Quick), None);
        let json = id.to_json();
        assert!(
            json.contains("\"truth\": \"both\"") && json.contains("\"plane-optimal\"") && json.contains("\"lispsm\"")
        );
        assert!(!json.contains("\"out\"") && !json.contains("\"resume\""), "{json}");
        let back: Identity = serde_json::from_str(&json).unwrap();
        assert_eq!(
            back,
            identity(
                ExperimentConfig { out: std::path::PathBuf::new(), ..ExperimentConfig::preset(Preset::Quick) },
                None
            )
        );
    }

    #[test]
    fn result_changing_differences_are_named_and_neutral_ones_accepted() {
        let quick = ExperimentConfig::preset(Preset::Quick);
        let old = identity(quick.clone(), None);
        let seed = identity(ExperimentConfig { seed: 7, ..quick.clone() }, None);
        let e = seed.check_against(&old, &RESULT_NEUTRAL_SETTINGS, "test").unwrap_err().to_string();
        assert_eq!(e, "test: seed (--seed) differs: recorded 2006, now 7");
        let more = identity(ExperimentConfig { configs: 60, equivalence_configs: 0, ..quick.clone() }, None);
        let accepted = more.check_against(&old, &RESULT_NEUTRAL_SETTINGS, "test").unwrap();
        assert_eq!(accepted.len(), 2, "{accepted:?}");
        let newer = Identity { lixel_version: "1.0.1".into(), ..old.clone() };
        assert!(newer.check_against(&old, &[], "t").unwrap_err().to_string().contains("lixel version"));
        // OBJ scenes: the path may change, the content may not.
        let obj = |p: &str| ExperimentConfig {
            scene: SceneSource::File { path: p.into(), options: crate::mesh::SceneOptions::default() },
            ..quick.clone()
        };
        let a = identity(obj("a.obj"), Some("aa"));
        identity(obj("/abs/a.obj"), Some("aa")).check_against(&a, &[], "t").unwrap();
        let e = identity(obj("a.obj"), Some("bb")).check_against(&a, &[], "t").unwrap_err().to_string();
        assert!(e.contains("scene content") && e.contains("sha256 aa") && e.contains("sha256 bb"), "{e}");
    }
}
