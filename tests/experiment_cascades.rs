//! `lixel experiment --light directional --cascades N` end to end on a tiny
//! scene: the four cascade methods beside one-map methods at equal total
//! texels, in every report file, deterministic; and the typed refusals.
#![cfg(feature = "cli")]

#[path = "render_common/mod.rs"]
mod render_common;

use lixel::experiment::{self, ExperimentConfig, ExperimentError, LightKind, MethodSpec, Preset, SceneSource, Truth};

fn config(out: &std::path::Path) -> ExperimentConfig {
    ExperimentConfig {
        scene: SceneSource::Builtin { triangles: 2_000 },
        light: LightKind::Directional,
        out: out.to_path_buf(),
        configs: 2,
        screen: 96,
        map: 128,
        cascades: 2,
        methods: [MethodSpec::FOCUSED]
            .into_iter()
            .chain(MethodSpec::CASCADED)
            .chain([MethodSpec::SDSM.with_lookup(lixel::render::ShadowLookup::parse("aa8").unwrap())])
            .collect(),
        truth: Truth::RayCast,
        max_optimize_frames: 4,
        equivalence_configs: 0,
        coverage_samples: 0,
        ..ExperimentConfig::preset(Preset::Quick)
    }
}

fn csv_rows(path: &std::path::Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path).unwrap().lines().skip(1).map(|l| l.split(',').map(str::to_string).collect()).collect()
}

#[test]
fn two_cascades_run_every_cascade_method_at_equal_texels_deterministically() {
    let Some((device, queue)) = render_common::gpu() else { return };
    let dir = std::env::temp_dir().join(format!("lixel-experiment-cascades-{}", std::process::id()));
    let (first, second) = (dir.join("first"), dir.join("second"));
    let _ = std::fs::remove_dir_all(&dir);

    let c = config(&first);
    assert_eq!(c.single_map(), 181, "one map of (128·√2)²");
    let summary = experiment::run(&c, &device, &queue, &mut |_| {}).unwrap();
    let names: Vec<String> = c.methods.iter().map(|m| m.name()).collect();
    assert_eq!(names, ["focused", "csm", "sdsm", "sdsm-lispsm", "optimized-cascades", "sdsm+aa8"]);

    let summary_rows = csv_rows(&first.join("summary.csv"));
    for name in &names {
        assert!(summary_rows.iter().any(|r| &r[0] == name), "{name} missing from summary.csv");
    }
    let report = std::fs::read_to_string(first.join("report.md")).unwrap();
    assert!(
        report.contains("2 cascades of 128x128 per sun") && report.contains("one 181x181 map for the others"),
        "{report}"
    );
    for name in &names {
        assert!(report.contains(name.as_str()), "{name} missing from report.md");
    }
    let images: Vec<String> = std::fs::read_dir(first.join("images"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    for name in &names {
        assert!(images.iter().any(|f| f.starts_with(&format!("{name}-"))), "no image of {name}: {images:?}");
    }

    // Every method counts the same pixels (the truth's), each cascade method
    // classified them (the sun's cascade bits folded into one light: a fold
    // that lost the sun would call most lit pixels shadowed).
    let rows = csv_rows(&first.join("configs.csv"));
    assert_eq!(rows.len(), c.configs * c.methods.len());
    for config in 0..c.configs {
        let of: Vec<&Vec<String>> = rows.iter().filter(|r| r[0] == config.to_string()).collect();
        let counted: u64 = of[0][5].parse().unwrap();
        assert!(counted > 0);
        for r in &of {
            let (n, mis): (u64, u64) = (r[5].parse().unwrap(), r[6].parse().unwrap());
            assert_eq!(n, counted, "{r:?}");
            assert!(mis * 10 < counted, "{r:?}: more than 10% misclassified");
            let frames: usize = r[9].parse().unwrap();
            assert!(frames >= 1 && frames <= c.max_optimize_frames + 1, "{r:?}");
        }
    }
    for m in &summary.methods {
        assert_eq!(m.configs, c.configs, "{:?} failed somewhere", m.method);
    }

    // Same seeds, same rows.
    let _ = experiment::run(&config(&second), &device, &queue, &mut |_| {}).unwrap();
    assert_eq!(
        std::fs::read_to_string(first.join("configs.csv")).unwrap(),
        std::fs::read_to_string(second.join("configs.csv")).unwrap(),
        "same seeds must give the same configs.csv"
    );
    assert_eq!(
        std::fs::read_to_string(first.join("summary.csv")).unwrap(),
        std::fs::read_to_string(second.join("summary.csv")).unwrap()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cascade_methods_need_suns_and_a_cascade_count() {
    let out = std::path::Path::new("unused");
    let cascades = |e: Result<(), ExperimentError>| match e {
        Err(ExperimentError::Cascades { what, reason }) => format!("{what}: {reason}"),
        other => panic!("expected a cascade refusal, got {other:?}"),
    };
    let point = ExperimentConfig { light: LightKind::Point, cascades: 0, ..config(out) };
    let m = cascades(experiment::check_cascades(&point));
    assert!(m.contains("--methods csm") && m.contains("--light directional"), "{m}");
    let none = ExperimentConfig { cascades: 0, ..config(out) };
    let m = cascades(experiment::check_cascades(&none));
    assert!(m.contains("--cascades N"), "{m}");
    let point_cascades =
        ExperimentConfig { light: LightKind::Point, methods: vec![MethodSpec::FOCUSED], ..config(out) };
    assert!(cascades(experiment::check_cascades(&point_cascades)).contains("--cascades 2"));
    let nine = ExperimentConfig { cascades: 9, ..config(out) };
    assert!(cascades(experiment::check_cascades(&nine)).contains("at most 8"));
    // Every lookup honours the cascade choice (tests/render_cascades.rs).
    let spsm = lixel::render::ShadowLookup::parse("spsm").unwrap();
    let lookup = ExperimentConfig { methods: vec![MethodSpec::CSM.with_lookup(spsm)], ..config(out) };
    experiment::check_cascades(&lookup).unwrap();
    experiment::check_cascades(&config(out)).unwrap();
    // Without cascade methods a run records no cascades (old settings read the same).
    let plain = ExperimentConfig::preset(Preset::Quick);
    assert_eq!(plain.single_map(), plain.map);
    let json = serde_json::to_string(&plain).unwrap();
    assert!(!json.contains("cascades"), "{json}");
    let large = ExperimentConfig::preset(Preset::Large);
    assert_eq!((large.cascades, large.map, large.single_map()), (4, 1024, 2048));
    experiment::check_cascades(&large).unwrap();
    let json = serde_json::to_string(&large).unwrap();
    let back: ExperimentConfig = serde_json::from_str(&json).unwrap();
    assert_eq!(ExperimentConfig { out: large.out.clone(), ..back }, large);
}

#[test]
fn the_large_preset_looks_across_a_far_floor_from_near_the_ground() {
    let config =
        ExperimentConfig { scene: SceneSource::Large { triangles: 20_000 }, ..ExperimentConfig::preset(Preset::Large) };
    let scene = experiment::load_scene(&config.scene).unwrap();
    let camera = experiment::camera_for(&config, &scene).unwrap();
    let bounds = scene.bounds().scene();
    assert!(bounds.max.x - bounds.min.x >= 1900.0, "{bounds:?}");
    assert!(camera.z_far() >= 1000.0 && camera.z_near() <= 0.1, "{camera:?}");
    let eye = camera.eye();
    assert!(eye.y - bounds.min.y < 2.0, "eye {eye} not near the ground");
}
