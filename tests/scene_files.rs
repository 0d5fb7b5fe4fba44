//! Users' scene files: OBJ and glTF loading, every refusal and repair of
//! `lixel::mesh::load_scene_file`, and the default framing of a loaded model
//! (every configuration of a small experiment counts pixels).
#![cfg(feature = "cli")]

#[path = "render_common/mod.rs"]
mod render_common;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use base64::Engine as _;
use glam::{DVec3, Quat, Vec3};
use lixel::experiment::{ExperimentConfig, LightKind, MethodSpec, Preset, Runner, SceneSource, Truth};
use lixel::mesh::{
    load_scene_file, primitives, Mesh, Repair, Role, SceneLoadError, SceneOptions, UpAxis, MAX_TRIANGLES,
};

/// A fresh temporary directory for one test.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lixel-scene-files-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn no_floor() -> SceneOptions {
    SceneOptions { floor: false, ..SceneOptions::default() }
}

fn load_text(name: &str, text: &str) -> Result<lixel::mesh::LoadReport, SceneLoadError> {
    let dir = temp_dir(name);
    load_scene_file(write(&dir, &format!("{name}.obj"), text), &no_floor()).map(|(_, report)| report)
}

/// A scanned-statue stand-in: ~10 units tall, y up, standing at
/// `(2, 0, -1)`, about 3.7k triangles, without normals in the file.
fn statue_obj() -> String {
    statue_obj_at(DVec3::ZERO)
}

/// [`statue_obj`] moved by `shift`, written in double precision.
fn statue_obj_at(shift: DVec3) -> String {
    let parts: [(Mesh, Vec3, Quat); 4] = [
        (primitives::cylinder(1.4, 3.5, 1500), Vec3::new(2.0, 3.5, -1.0), Quat::IDENTITY),
        (primitives::sphere(1.3, 1500), Vec3::new(2.0, 8.5, -1.0), Quat::IDENTITY),
        (primitives::cuboid(Vec3::new(0.3, 2.0, 0.3), 12), Vec3::new(0.2, 5.0, -1.0), Quat::from_rotation_z(0.4)),
        (primitives::torus(1.6, 0.3, 700), Vec3::new(2.0, 0.3, -1.0), Quat::IDENTITY),
    ];
    let mut text = String::from("# generated statue\n");
    let mut base = 1;
    for (k, (mesh, offset, rotation)) in parts.iter().enumerate() {
        let _ = writeln!(text, "o part{k}");
        for p in &mesh.positions {
            let p = (*rotation * *p + *offset).as_dvec3() + shift;
            let _ = writeln!(text, "v {} {} {}", p.x, p.y, p.z);
        }
        for t in mesh.indices.chunks_exact(3) {
            let _ = writeln!(text, "f {} {} {}", t[0] + base, t[1] + base, t[2] + base);
        }
        base += mesh.positions.len() as u32;
    }
    text
}

#[test]
fn obj_with_byte_order_mark_loads() {
    let report = load_text("bom", "\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    assert_eq!((report.vertices, report.triangles), (3, 1));
}

#[test]
fn directories_and_binary_files_are_named_as_such() {
    let dir = temp_dir("kinds");
    let e = load_scene_file(&dir, &no_floor()).unwrap_err();
    assert!(matches!(e, SceneLoadError::IsDirectory { .. }) && e.to_string().contains("is a directory"), "{e}");

    let binary = write(&dir, "model.obj", [0x7f, b'E', b'L', b'F', 2, 1, 1, 0, 0, 0, 0xff, 0xfe]);
    let e = load_scene_file(&binary, &no_floor()).unwrap_err();
    assert!(matches!(e, SceneLoadError::NotText { .. }) && e.to_string().contains("not a text OBJ"), "{e}");
    let e = load_scene_file(dir.join("missing.obj"), &no_floor()).unwrap_err();
    assert!(matches!(e, SceneLoadError::Io { .. }), "{e}");
}

#[test]
fn far_and_non_finite_vertices_are_refused_with_the_vertex() {
    let e = load_text("far", "v 0 0 0\nv 1 0 0\nv 1e30 1 0\nf 1 2 3\n").unwrap_err();
    assert!(matches!(e, SceneLoadError::CoordinateRange { vertex: 2, .. }), "{e}");
    assert!(e.to_string().contains("coordinates beyond 1e15"), "{e}");
    // --scale can push a model out of range too.
    let dir = temp_dir("far-scaled");
    let path = write(&dir, "m.obj", "v 0 0 0\nv 1e9 0 0\nv 0 1e9 0\nf 1 2 3\n");
    let options = SceneOptions { scale: 1e7, ..no_floor() };
    assert!(matches!(load_scene_file(&path, &options), Err(SceneLoadError::CoordinateRange { .. })));
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let options = SceneOptions { scale: bad, ..no_floor() };
        assert!(matches!(load_scene_file(&path, &options), Err(SceneLoadError::InvalidScale { .. })), "{bad}");
    }

    for (name, value) in [("nan", "nan"), ("inf", "inf"), ("neg-inf", "-inf")] {
        let e = load_text(name, &format!("v 0 0 0\nv 1 {value} 0\nv 0 1 0\nf 1 2 3\n")).unwrap_err();
        assert!(matches!(e, SceneLoadError::NonFinite { vertex: 1, .. }), "{name}: {e}");
    }
}

#[test]
fn empty_zero_size_and_all_degenerate_meshes_are_refused() {
    for (name, text) in
        [("empty", ""), ("comments", "# nothing\nv 1 2 3\n"), ("lines-only", "v 0 0 0\nv 1 0 0\nl 1 2\n")]
    {
        let e = load_text(name, text).unwrap_err();
        assert!(matches!(e, SceneLoadError::NoTriangles { .. }), "{name}: {e}");
    }
    let e = load_text("point", "v 1 2 3\nv 1 2 3\nv 1 2 3\nf 1 2 3\nf 3 2 1\n").unwrap_err();
    assert!(matches!(e, SceneLoadError::AllVerticesCoincide { .. }), "{e}");
    assert!(e.to_string().contains("all vertices coincide"), "{e}");
    let e = load_text("collinear", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n").unwrap_err();
    assert!(matches!(e, SceneLoadError::AllDegenerate { triangles: 1, .. }), "{e}");
}

#[test]
fn repairs_are_made_and_reported() {
    let text = "o a\nv 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\nv 5 5 5\nv 9 9 9\n\
                f 1 2 3 4\nf 1 2 2\nf 1 2 5\nl 1 2\n\
                o b\nv 0 1 0\nv 1 1 0\nv 2 1 0\nf 7 8 9\n";
    let report = load_text("repairs", text).unwrap();
    // The quad (2 triangles) and 1-2-5 stay; the repeated and the collinear triangle go, and object b with it.
    assert_eq!(report.triangles, 3, "{report}");
    for expected in [
        Repair::Triangulated { polygons: 1 },
        Repair::IgnoredNonTriangles { count: 1 },
        Repair::DroppedDegenerate { triangles: 2 },
        Repair::ComputedNormals { objects: 1 },
        Repair::DroppedEmptyObjects { objects: 1 },
    ] {
        assert!(report.repairs.contains(&expected), "{expected:?} missing: {report}");
    }
    // The unused vertex at (9, 9, 9) is gone and does not stretch the bounds.
    assert!(report.repairs.iter().any(|r| matches!(r, Repair::DroppedUnreferenced { .. })), "{report}");
    assert_eq!(report.bounds.max, DVec3::new(5.0, 5.0, 5.0), "{report}");
    let shown = report.to_string();
    assert!(shown.contains("3 triangles") && shown.contains("triangulated 1 polygons"), "{shown}");

    // Normals in the file are used; zero normals make the loader compute them.
    let with_normals = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n";
    assert!(load_text("normals", with_normals).unwrap().repairs.is_empty());
    let zero_normals = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nf 1//1 2//1 3//1\n";
    let dir = temp_dir("zero-normals");
    let (scene, report) = load_scene_file(write(&dir, "z.obj", zero_normals), &no_floor()).unwrap();
    assert!(report.repairs.contains(&Repair::ComputedNormals { objects: 1 }), "{report}");
    assert!(scene.objects[0].mesh.normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-6));
}

#[test]
fn ten_million_triangles_are_refused_with_the_limit() {
    // One polygon of 10^7 + 2 vertices: 10^7 triangles once fanned, a 20 MB file.
    let mut text = String::with_capacity(21_000_000);
    text.push_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nf");
    for k in 0..10_000_002u32 {
        text.push_str([" 1", " 2", " 3"][(k % 3) as usize]);
    }
    text.push('\n');
    let e = load_text("huge", &text).unwrap_err();
    assert!(matches!(e, SceneLoadError::TooManyTriangles { triangles: 10_000_000, limit: MAX_TRIANGLES, .. }), "{e}");
    assert!(e.to_string().contains(&MAX_TRIANGLES.to_string()), "{e}");
}

#[test]
fn up_axis_scale_and_floor() {
    let dir = temp_dir("up");
    // A 1 x 1 x 10 box standing along +z.
    let mut text = String::new();
    for (x, y, z) in [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 10), (1, 0, 10), (1, 1, 10), (0, 1, 10)] {
        let _ = writeln!(text, "v {x} {y} {z}");
    }
    text.push_str("f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
    let path = write(&dir, "tower.obj", text);
    let options = SceneOptions { up: UpAxis::Z, scale: 0.5, floor: true };
    let (scene, report) = load_scene_file(&path, &options).unwrap();
    let height = report.bounds.max.y - report.bounds.min.y;
    assert!((height - 5.0).abs() < 1e-6, "{report}");
    assert!((report.bounds.max.z - report.bounds.min.z - 0.5).abs() < 1e-6, "{report}");
    // The floor: receiver only, under the model, wider than it.
    let floor = scene.objects.iter().find(|o| o.role == Role::Receiver).expect("a floor");
    let floor_bounds = floor.mesh.bounds().unwrap();
    assert!(floor_bounds.max.y <= report.bounds.min.y && floor_bounds.max.y > report.bounds.min.y - 1e-3);
    assert!(floor_bounds.max.x - floor_bounds.min.x > 10.0 * 0.5);
    assert_eq!(scene.bounds().casters, report.bounds);
    let (flat, _) = load_scene_file(&path, &SceneOptions { floor: false, ..options }).unwrap();
    assert!(flat.objects.iter().all(|o| o.role == Role::CasterAndReceiver));
}

/// A glTF 2.0 JSON document with one buffer (`uri`), a quad mesh (4
/// positions, 6 u16 indices) under a parent node translated by (10, 0, 0)
/// and a child scaled by 2; `mode` is the primitive mode.
fn quad_gltf(uri: &str, mode: u32) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"translation":[10,0,0],"children":[1]}},{{"scale":[2,2,2],"mesh":0}}],
"meshes":[{{"name":"quad","primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":{mode}}}]}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":12}}],
"buffers":[{{"byteLength":60{uri}}}]}}"#
    )
}

fn quad_buffer() -> Vec<u8> {
    let mut bytes = Vec::new();
    for v in [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]] {
        bytes.extend(v.iter().flat_map(|c| c.to_le_bytes()));
    }
    bytes.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    bytes
}

fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let pad = |mut v: Vec<u8>, fill: u8| {
        while !v.len().is_multiple_of(4) {
            v.push(fill);
        }
        v
    };
    let (json, bin) = (pad(json.as_bytes().to_vec(), b' '), pad(bin.to_vec(), 0));
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(&bin);
    out
}

#[test]
fn gltf_and_glb_load_with_node_transforms() {
    let dir = temp_dir("gltf");
    let data = base64::engine::general_purpose::STANDARD.encode(quad_buffer());
    let embedded =
        write(&dir, "embedded.gltf", quad_gltf(&format!(r#","uri":"data:application/octet-stream;base64,{data}""#), 4));
    write(&dir, "quad data.bin", quad_buffer());
    let external = write(&dir, "external.gltf", quad_gltf(r#","uri":"quad%20data.bin""#, 4));
    let binary = write(&dir, "binary.glb", glb(&quad_gltf("", 4), &quad_buffer()));
    for path in [&embedded, &external, &binary] {
        let (scene, report) = load_scene_file(path, &no_floor()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((report.triangles, report.vertices), (2, 4), "{}: {report}", path.display());
        assert_eq!(report.bounds.min, DVec3::new(10.0, 0.0, 0.0), "{report}");
        assert_eq!(report.bounds.max, DVec3::new(12.0, 2.0, 0.0), "{report}");
        // Counter-clockwise seen from +z: computed normals point at +z.
        assert!(scene.objects[0].mesh.normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-6));
    }
    // A strip of 6 indices is 4 triangles (two of them repeat vertices and are dropped).
    let strip = write(&dir, "strip.glb", glb(&quad_gltf("", 5), &quad_buffer()));
    let (_, report) = load_scene_file(&strip, &no_floor()).unwrap();
    assert!(report.repairs.contains(&Repair::UnrolledStripsAndFans { primitives: 1 }), "{report}");
    // Lines are skipped, leaving nothing.
    let lines = write(&dir, "lines.glb", glb(&quad_gltf("", 1), &quad_buffer()));
    assert!(matches!(load_scene_file(&lines, &no_floor()), Err(SceneLoadError::NoTriangles { .. })));

    // Broken files: typed errors.
    let missing = write(&dir, "missing.gltf", quad_gltf(r#","uri":"nowhere.bin""#, 4));
    assert!(matches!(load_scene_file(&missing, &no_floor()), Err(SceneLoadError::Gltf(_))));
    let short = write(&dir, "short.glb", glb(&quad_gltf("", 4), &quad_buffer()[..20]));
    assert!(load_scene_file(&short, &no_floor()).is_err());
    let garbage = write(&dir, "garbage.gltf", "{\"asset\": 3");
    assert!(matches!(load_scene_file(&garbage, &no_floor()), Err(SceneLoadError::Gltf(_))));
    // A huge declared index count is refused before its buffer is looked for.
    let huge = quad_gltf(r#","uri":"nowhere.bin""#, 4)
        .replace(r#""count":6"#, r#""count":30000000"#)
        .replace(r#""byteLength":12"#, r#""byteLength":60000000"#)
        .replace(r#""byteLength":60}"#, r#""byteLength":60000048}"#);
    let huge = write(&dir, "huge.gltf", huge);
    let e = load_scene_file(&huge, &no_floor()).unwrap_err();
    assert!(matches!(e, SceneLoadError::TooManyTriangles { triangles: 10_000_000, .. }), "{e}");
}

/// The issue's case: a scanned model ~10 units tall, y up, no floor. With
/// the default (framed) camera every configuration of a small experiment
/// counts pixels — with the old walkthrough camera 11 of 20 counted none.
#[test]
fn default_framing_of_a_model_counts_pixels_in_every_configuration() {
    let Some((device, queue)) = render_common::gpu() else { return };
    let dir = temp_dir("framing");
    let path = write(&dir, "statue.obj", statue_obj());
    let cases = [
        ("y up, no floor", SceneOptions { floor: false, ..SceneOptions::default() }, LightKind::Point),
        ("y up, floor", SceneOptions::default(), LightKind::Directional),
    ];
    for (name, options, light) in cases {
        let config = ExperimentConfig {
            scene: SceneSource::File { path: path.clone(), options },
            light,
            configs: 20,
            screen: 64,
            map: 128,
            methods: vec![MethodSpec::FOCUSED],
            truth: Truth::RayCast,
            equivalence_configs: 0,
            out: dir.join("report"),
            ..ExperimentConfig::preset(Preset::Quick)
        };
        let mut runner = Runner::new(&config, &device, &queue).unwrap();
        let triangles = runner.scene().triangle_count();
        assert!((3000..5000).contains(&triangles), "{triangles}");
        // The model is not a speck: the (tall) model spans most of the screen's rows.
        let light = lixel::experiment::light_for(&config, runner.scene(), 0);
        let truth = runner.truths(light).unwrap().0.expect("ray-cast truth");
        let rows = (0..64).filter(|y| (0..64).any(|x| truth.visible(y * 64 + x))).count();
        assert!(rows >= 40, "{name}: the scene shows on only {rows} of 64 rows");
        for index in 0..config.configs {
            let outcome = runner.run_config(index).unwrap();
            let counts = outcome.results[0].1.counts.expect("focused never fails here");
            assert!(counts.counted > 0, "{name}: configuration {index} counted no pixel");
        }
    }
}

/// A model far from the origin for its size (a georeferenced or CAD file):
/// read in double precision, moved to the origin before it is rounded to
/// single precision, and reported. Its shadows then come out as the same
/// model's near the origin; before, 10⁵ units out, the standard lookup
/// misclassified ~20× more pixels and `+aa8`'s visibility error was ~10×.
#[test]
fn far_off_models_are_recentred_and_shadowed_like_near_ones() {
    let dir = temp_dir("far");
    let shift = DVec3::new(250_000.37, 1_100.0, -370_000.21);
    let near = write(&dir, "near.obj", statue_obj());
    let far = write(&dir, "far.obj", statue_obj_at(shift));
    let (near_scene, near_report) = load_scene_file(&near, &no_floor()).unwrap();
    let (far_scene, far_report) = load_scene_file(&far, &no_floor()).unwrap();
    assert!(!near_report.repairs.iter().any(|r| matches!(r, Repair::Recentred { .. })), "{near_report}");
    let offset = far_report
        .repairs
        .iter()
        .find_map(|r| match r {
            Repair::Recentred { offset } => Some(*offset),
            _ => None,
        })
        .unwrap_or_else(|| panic!("not recentred: {far_report}"));
    let center = near_report.bounds.center();
    assert!((offset - (center + shift)).length() < 1e-6, "offset {offset} for centre {}", center + shift);
    // Every vertex where the near model's is, relative to the centre: the
    // file's digits survive (single-precision parsing would be off by ~1e-2).
    for (a, b) in near_scene.objects.iter().zip(&far_scene.objects) {
        for (p, q) in a.mesh.positions.iter().zip(&b.mesh.positions) {
            let error = (p.as_dvec3() - center - q.as_dvec3()).length();
            assert!(error < 1e-5, "{} vs {}: {error}", p.as_dvec3() - center, q);
        }
    }

    let Some((device, queue)) = render_common::gpu() else { return };
    let run = |path: &Path| {
        let config = ExperimentConfig {
            scene: SceneSource::File { path: path.to_path_buf(), options: SceneOptions::default() },
            configs: 3,
            screen: 64,
            map: 128,
            methods: vec![MethodSpec::FOCUSED, MethodSpec::parse("focused+aa8").unwrap()],
            truth: Truth::RayCast,
            equivalence_configs: 0,
            out: dir.join("report"),
            ..ExperimentConfig::preset(Preset::Quick)
        };
        let mut runner = Runner::new(&config, &device, &queue).unwrap();
        let (mut misclassified, mut visibility) = ([0u64; 2], [0f64; 2]);
        for index in 0..config.configs {
            let outcome = runner.run_config(index).unwrap();
            for (k, (_, result)) in outcome.results.iter().enumerate() {
                misclassified[k] += result.counts.expect("counted").misclassified();
                visibility[k] += result.visibility.and_then(|v| v.mean()).expect("visibility error");
            }
        }
        (misclassified, visibility)
    };
    let (near, far) = (run(&near), run(&far));
    for k in 0..2 {
        let (a, b) = (near.0[k] as f64, far.0[k] as f64);
        assert!((a - b).abs() <= 0.1 * a + 10.0, "method {k}: misclassified {a} near, {b} far");
        let (a, b) = (near.1[k], far.1[k]);
        assert!((a - b).abs() <= 0.25 * a + 1e-3, "method {k}: visibility error {a} near, {b} far");
    }
}
