//! `lixel experiment` never loses, mixes or fakes results (issue 12): a
//! report is never overwritten, one run per directory, `--resume` checks
//! the run's identity by content, a camera that sees nothing fails, and the
//! command line names what is wrong. Tiny runs (a 2,000-triangle scene,
//! 64² screens) keep this fast.
#![cfg(feature = "render")]

#[path = "render_common/mod.rs"]
mod render_common;

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::DVec3;
use lixel::experiment::{self, ExperimentConfig, ExperimentError, MethodSpec, Preset, SceneSource, Truth};
use lixel::mesh::SceneOptions;

fn tiny(out: &Path) -> ExperimentConfig {
    ExperimentConfig {
        scene: SceneSource::Builtin { triangles: 2_000 },
        configs: 2,
        screen: 64,
        map: 64,
        methods: vec![MethodSpec::NORMAL, MethodSpec::FOCUSED],
        truth: Truth::RayCast,
        equivalence_configs: 0,
        out: out.to_path_buf(),
        ..ExperimentConfig::preset(Preset::Quick)
    }
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lixel-safety-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap()
}

/// A floor and a box, as OBJ text; `lift` moves the box up.
fn obj(lift: f64) -> String {
    let mut s = String::from("v -10 0 -10\nv 10 0 -10\nv 10 0 10\nv -10 0 10\nf 1 3 2\nf 1 4 3\n");
    for (x, y, z) in [(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1), (-1, 2, -1), (1, 2, -1), (1, 2, 1), (-1, 2, 1)] {
        s.push_str(&format!("v {x} {} {z}\n", f64::from(y) + lift));
    }
    for f in [
        [5, 6, 7],
        [5, 7, 8],
        [9, 11, 10],
        [9, 12, 11],
        [5, 9, 10],
        [5, 10, 6],
        [6, 10, 11],
        [6, 11, 7],
        [7, 11, 12],
        [7, 12, 8],
        [8, 12, 9],
        [8, 9, 5],
    ] {
        s.push_str(&format!("f {} {} {}\n", f[0], f[1], f[2]));
    }
    s
}

#[test]
fn a_report_is_never_destroyed_and_resume_checks_identity_by_content() {
    let Some((device, queue)) = render_common::gpu() else { return };
    let dir = temp("identity");
    let out = dir.join("report");
    let c = tiny(&out);
    experiment::run(&c, &device, &queue, &mut |_| {}).unwrap();
    let rows = read(&out.join("configs.csv"));
    let settings = read(&out.join("settings.json"));
    assert!(settings.contains("\"map\": 64") && settings.contains("\"lixel_version\""), "{settings}");

    // 1. Running again into the same --out is refused, naming both ways out; nothing changed.
    let e = experiment::run(&c, &device, &queue, &mut |_| {}).unwrap_err();
    assert!(matches!(e, ExperimentError::ReportExists { .. }), "{e}");
    let m = e.to_string();
    assert!(m.contains("--resume") && m.contains("--force"), "{m}");
    assert_eq!(read(&out.join("configs.csv")), rows);

    // 3. --resume with a result-changing setting names it and both values; rows untouched.
    let e = experiment::run(&ExperimentConfig { map: 128, resume: true, ..c.clone() }, &device, &queue, &mut |_| {})
        .unwrap_err();
    let m = e.to_string();
    assert!(matches!(e, ExperimentError::SettingsDiffer { .. }), "{m}");
    assert!(m.contains("map (--map)") && m.contains("recorded 64") && m.contains("now 128"), "{m}");
    assert_eq!(read(&out.join("configs.csv")), rows);
    // ...and accepts settings that change no row: more configurations, another equivalence.
    let more = ExperimentConfig { configs: 3, equivalence_configs: 5, resume: true, ..c.clone() };
    let summary = experiment::run(&more, &device, &queue, &mut |_| {}).unwrap();
    assert!(summary.warnings.iter().any(|w| w.contains("configs")), "{:?}", summary.warnings);
    assert!(read(&out.join("configs.csv")).starts_with(&rows), "the first two configurations were redone");

    // 1. --force moves the old report aside, never deletes it.
    let before = read(&out.join("configs.csv"));
    experiment::run(&ExperimentConfig { force: true, ..c.clone() }, &device, &queue, &mut |_| {}).unwrap();
    assert_eq!(read(&out.join("replaced-1").join("configs.csv")), before);
    assert_eq!(read(&out.join("configs.csv")), rows, "the forced run is a fresh 2-configuration run");

    // 3. Without settings.json the rows cannot be checked: say so.
    std::fs::remove_file(out.join("settings.json")).unwrap();
    let m = experiment::run(&ExperimentConfig { resume: true, ..c.clone() }, &device, &queue, &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(m.contains("settings.json") && !m.contains("other settings"), "{m}");

    // 3. An OBJ scene is identified by its content: the same file by another
    // path resumes, an edited file is refused.
    let (scene_a, scene_b) = (dir.join("a.obj"), dir.join("copy-of-a.obj"));
    std::fs::write(&scene_a, obj(0.0)).unwrap();
    std::fs::write(&scene_b, obj(0.0)).unwrap();
    let obj_out = dir.join("obj");
    let with = |path: &Path| ExperimentConfig {
        scene: SceneSource::File { path: path.to_path_buf(), options: SceneOptions::default() },
        ..tiny(&obj_out)
    };
    experiment::run(&ExperimentConfig { configs: 1, ..with(&scene_a) }, &device, &queue, &mut |_| {}).unwrap();
    experiment::run(&ExperimentConfig { resume: true, ..with(&scene_b) }, &device, &queue, &mut |_| {}).unwrap();
    std::fs::write(&scene_a, obj(0.5)).unwrap();
    let m = experiment::run(&ExperimentConfig { resume: true, ..with(&scene_a) }, &device, &queue, &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(m.contains("scene content") && m.contains("sha256"), "{m}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_camera_that_sees_nothing_fails_and_suggests_eye_and_target() {
    let Some((device, queue)) = render_common::gpu() else { return };
    let dir = temp("sky");
    // 5. Aimed at the sky: no configuration counts a pixel.
    let c = ExperimentConfig {
        eye: Some(DVec3::new(0.0, 1000.0, 0.0)),
        target: Some(DVec3::new(0.0, 2000.0, 500.0)),
        ..tiny(&dir.join("report"))
    };
    let mut warned = Vec::new();
    let e = experiment::run(&c, &device, &queue, &mut |p| warned.extend(p.zero_pixels)).unwrap_err();
    assert!(matches!(e, ExperimentError::NothingCounted { configs: 2 }), "{e}");
    assert!(e.to_string().contains("--eye") && e.to_string().contains("--target"), "{e}");
    assert_eq!(warned, vec![0, 1], "each configuration warned as it finished");
    let _ = std::fs::remove_dir_all(&dir);
}

fn lixel(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_lixel")).args(args).output().unwrap();
    (out.status.success(), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn the_command_line_names_each_invalid_flag() {
    let dir = temp("cli");
    let out = dir.join("r");
    let out = out.to_str().unwrap();
    let base = ["experiment", "--preset", "quick", "--quiet", "--out", out];
    let run = |extra: &[&str]| lixel(&[&base[..], extra].concat());
    // 6. Negative values are values, not flags; --fov is in degrees.
    let (ok, e) = run(&["--eye", "-5,1,0", "--target", "-1,-2,-3", "--fov", "-10"]);
    assert!(!ok && !e.contains("unexpected argument"), "{e}");
    if !e.contains("no GPU adapter") {
        assert!(e.contains("--fov -10 degrees") && e.contains("between 0 and 180 degrees"), "{e}");
        let (_, e) = run(&["--fov", "0"]);
        assert!(e.contains("--fov 0 degrees"), "{e}");
        let (_, e) = run(&["--methods", "focused,focused"]);
        assert!(e.contains("--methods lists focused twice"), "{e}");
        let (_, e) = run(&["--screen", "100000"]);
        assert!(e.contains("--screen 100000 is too large") && e.contains("largest texture"), "{e}");
        let (_, e) = run(&["--triangles", "18446744073709551615"]);
        assert!(e.contains("--triangles 18446744073709551615 is too large"), "{e}");
    }
    let (_, e) = run(&["--eye", "1,2"]);
    assert!(e.contains("--eye") && e.contains("three numbers"), "{e}");
    for flag in ["--configs", "--screen", "--map", "--jobs"] {
        let (ok, e) = run(&[flag, "0"]);
        assert!(!ok && e.contains(flag), "{flag}: {e}");
    }
    let (_, e) = run(&["--methods", "bogus"]);
    assert!(
        e.contains("\"bogus\"")
            && e.contains("normal, focused, focused-snapped, lispsm, psm, plane-optimal, optimized"),
        "{e}"
    );
    let (_, e) = run(&["--resume", "--force"]);
    assert!(e.contains("--resume") && e.contains("--force") && e.contains("cannot be used with"), "{e}");
    let (_, e) = run(&["--shard", "4/4"]);
    assert!(e.contains("--shard") && e.contains("not below"), "{e}");
    assert!(!Path::new(out).join("configs.csv").exists(), "a refused run wrote rows");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_second_run_on_the_same_directory_fails_at_once_naming_the_first() {
    if render_common::gpu().is_none() {
        return;
    }
    let dir = temp("lock");
    let out = dir.join("r");
    let args = |configs: &str| {
        let mut v: Vec<String> =
            ["experiment", "--preset", "quick", "--quiet", "--truth", "raytrace", "--screen", "64"]
                .map(String::from)
                .to_vec();
        v.extend(["--methods", "normal", "--equivalence", "0", "--configs", configs, "--out"].map(String::from));
        v.push(out.to_str().unwrap().to_string());
        v
    };
    // 2. A long first run holds the directory...
    let mut first = Command::new(env!("CARGO_BIN_EXE_lixel"))
        .args(args("100000"))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let lock = out.join(".lixel.lock");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    while std::fs::read_to_string(&lock).map_or(true, |t| t.trim() != first.id().to_string()) {
        assert!(std::time::Instant::now() < deadline, "the first run never took the lock");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    // ...so a second one (even with --resume) fails at once and names it.
    let started = std::time::Instant::now();
    let second = Command::new(env!("CARGO_BIN_EXE_lixel")).args(args("2")).arg("--resume").output().unwrap();
    let message = String::from_utf8_lossy(&second.stderr).into_owned();
    let _ = first.kill();
    let _ = first.wait();
    assert!(!second.status.success(), "{message}");
    assert!(message.contains(&format!("PID {}", first.id())), "{message}");
    assert!(started.elapsed().as_secs() < 30, "the second run did work before failing");
    let _ = std::fs::remove_dir_all(&dir);
}
