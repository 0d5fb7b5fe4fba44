//! `lixel view`: offscreen screenshots of every method against reference
//! images, the overlays changing the picture, the density overlay against
//! the CPU's `score::badness`, the command line without a display, and a
//! window under Xvfb where `xvfb-run` is installed (CI installs it).
#![cfg(feature = "view")]

#[path = "render_common/mod.rs"]
mod render_common;

use std::process::Command;

use lixel::experiment::{MethodSpec, Preset, SceneSource};
use lixel::view::{Overlays, ViewConfig, Viewer, SCREENSHOT_FORMAT};

/// The quick preset's scene, smaller: 128² pixels, 256² maps.
fn config() -> ViewConfig {
    let mut c = ViewConfig::preset(Preset::Quick);
    c.experiment.scene = SceneSource::Builtin { triangles: 4_000 };
    c.experiment.screen = 128;
    c.experiment.map = 256;
    c.overlays = Overlays::default();
    c
}

fn viewer(config: ViewConfig) -> Option<Viewer> {
    let gpu = render_common::gpu_on(None)?;
    Some(Viewer::new(&gpu.device, &gpu.queue, config, SCREENSHOT_FORMAT).expect("viewer"))
}

/// Pixels whose channels differ by more than 8.
fn differing(a: &image::RgbaImage, b: &image::RgbaImage) -> usize {
    a.pixels().zip(b.pixels()).filter(|(p, q)| (0..3).any(|c| p.0[c].abs_diff(q.0[c]) > 8)).count()
}

#[test]
fn every_method_renders_its_default_view() {
    let Some(mut v) = viewer(config()) else { return };
    let mut shots = Vec::new();
    for method in MethodSpec::ALL {
        v.set_method(method).unwrap();
        // Enough frames for the scene-optimized loop to take a few readbacks.
        let shot = v.screenshot(10, None).unwrap();
        render_common::assert_matches_reference(&format!("view-{}", method.name()), &shot, 24, 0.01);
        shots.push((method, shot));
    }
    // The methods' shadows differ: the views are not all the same picture.
    let (_, normal) = &shots[0];
    let (_, optimized) = shots.iter().find(|(m, _)| *m == MethodSpec::OPTIMIZED).unwrap();
    assert!(differing(normal, optimized) > 20, "normal and optimized give the same picture");
}

#[test]
fn overlays_change_the_picture() {
    let mut c = config();
    c.method = MethodSpec::NORMAL;
    c.experiment.map = 128;
    let Some(mut v) = viewer(c) else { return };
    let base = v.screenshot(2, None).unwrap();
    let pixels = base.width() as usize * base.height() as usize;
    let with = |v: &mut Viewer, overlays: Overlays| {
        v.set_overlays(overlays);
        v.screenshot(2, None).unwrap()
    };
    let density = with(&mut v, Overlays { density: true, ..Overlays::default() });
    assert!(differing(&base, &density) > pixels / 5, "density changed {} of {pixels}", differing(&base, &density));
    let grid = with(&mut v, Overlays { grid: true, ..Overlays::default() });
    assert!(differing(&base, &grid) > pixels / 100, "grid changed {}", differing(&base, &grid));
    let map = with(&mut v, Overlays { shadow_map: true, ..Overlays::default() });
    // Only the bottom-right corner.
    let (w, h) = (base.width(), base.height());
    assert_ne!(map.get_pixel(w - 12, h - 12), base.get_pixel(w - 12, h - 12));
    assert_eq!(map.get_pixel(2, 2), base.get_pixel(2, 2));
    let hud = with(&mut v, Overlays { hud: true, ..Overlays::default() });
    assert!(differing(&base, &hud) > 200, "HUD changed {}", differing(&base, &hud));
    let error = with(&mut v, Overlays { error: true, ..Overlays::default() });
    let counts = v.stats().error.expect("error counts");
    assert!(counts.counted > 1000, "{counts:?}");
    // A 128² normal map over the whole scene misclassifies pixels; each is painted.
    assert!(counts.misclassified() > 0, "{counts:?}");
    let painted = differing(&base, &error);
    assert!(painted > 0 && painted as u64 <= counts.misclassified(), "{painted} painted, {counts:?}");
    let off = with(&mut v, Overlays::default());
    assert_eq!(differing(&base, &off), 0, "overlays off restores the picture");
}

/// The boundary-samples overlay draws the optimizer's samples of the last
/// readback where the camera sees them, and nothing for a fixed method.
#[test]
fn samples_overlay_shows_the_optimizers_boundary_samples() {
    let mut c = config();
    c.method = MethodSpec::OPTIMIZED;
    let Some(mut v) = viewer(c) else { return };
    // A few analysis passes (every 3 frames) and their readbacks.
    let base = v.screenshot(10, None).unwrap();
    let samples = v.boundary_samples().first().map_or(0, Vec::len);
    assert!(samples > 0, "no boundary samples after 10 frames");
    v.set_overlays(Overlays { samples: true, ..Overlays::default() });
    let shown = v.screenshot(1, None).unwrap();
    let magenta = |img: &image::RgbaImage| img.pixels().filter(|p| p.0[0] > 200 && p.0[1] < 60 && p.0[2] > 200).count();
    let (before, after) = (magenta(&base), magenta(&shown));
    assert!(after > before, "{samples} samples, magenta pixels {before} -> {after}");
    // Each sample is at most one 9-pixel cross.
    assert!(after - before <= 9 * samples, "{samples} samples, {} magenta pixels", after - before);
    v.set_overlays(Overlays::default());
    let off = v.screenshot(1, None).unwrap();
    assert_eq!(magenta(&off), before, "turning the overlay off removes the crosses");
    // A method without analysis passes has no samples to show.
    v.set_method(MethodSpec::FOCUSED).unwrap();
    v.screenshot(4, None).unwrap();
    assert!(v.boundary_samples().iter().all(Vec::is_empty));
}

fn lixel_view(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_lixel"));
    c.arg("view").args(["--preset", "quick", "--screen", "96", "--map", "128"]).args(args);
    c
}

#[test]
fn without_a_display_the_window_names_screenshot() {
    let out = lixel_view(&[]).env_remove("DISPLAY").env_remove("WAYLAND_DISPLAY").output().unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("--screenshot"), "{stderr}");
}

#[test]
fn screenshot_from_the_command_line_follows_a_path() {
    if render_common::gpu_on(None).is_none() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("lixel-view-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("path.txt");
    std::fs::write(&path, "# frame eye target\n0 0 3 40 0 0 0\n4 30 3 30 0 0 0\n").unwrap();
    let shot = |name: &str, extra: &[&str]| {
        let file = dir.join(name);
        let mut args = vec!["--screenshot", file.to_str().unwrap(), "--frames", "5", "--overlay", "density"];
        args.extend_from_slice(extra);
        let out = lixel_view(&args).env_remove("DISPLAY").output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        image::open(&file).unwrap().to_rgba8()
    };
    let plain = shot("plain.png", &[]);
    let moved = shot("moved.png", &["--path", path.to_str().unwrap()]);
    assert_eq!(plain.dimensions(), (96, 96));
    assert!(differing(&plain, &moved) > 500, "the path did not move the camera");
    let bad = lixel_view(&["--screenshot", "x.png", "--path", dir.join("missing").to_str().unwrap()]).output().unwrap();
    assert!(!bad.status.success());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn window_under_xvfb() {
    let has_xvfb = Command::new("xvfb-run").arg("--help").output().is_ok();
    if !has_xvfb {
        let ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
        assert!(!ci, "CI=true but xvfb-run is missing (apt-get install xvfb)");
        eprintln!("skipping: no xvfb-run");
        return;
    }
    if render_common::gpu_on(None).is_none() {
        return;
    }
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 640x480x24", env!("CARGO_BIN_EXE_lixel")])
        .args(["view", "--preset", "quick", "--screen", "128", "--frames", "12", "--overlay", "density,grid,hud"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("12 frames"), "{stderr}");
}

fn linear(srgb: u8) -> f64 {
    let c = f64::from(srgb) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The density overlay is `score::badness` per pixel: at pixels on a flat
/// surface (away from edges, found by ray casting), the overlay's colour is
/// the legend's colour of the CPU's badness at that surface point.
#[test]
fn density_overlay_is_the_cpu_badness() {
    use lixel::mesh::raycast::Ray;
    let mut c = config();
    c.method = MethodSpec::LISPSM;
    let scene = lixel::experiment::load_scene(&c.experiment.scene).unwrap();
    let Some(mut v) = viewer(c) else { return };
    let base = v.screenshot(1, None).unwrap();
    v.set_overlays(Overlays { density: true, ..Overlays::default() });
    let density = v.screenshot(1, None).unwrap();
    let matrix = v.matrices()[0];
    let camera = v.camera.camera(v.size()).unwrap();
    let caster = lixel::mesh::RayCaster::new(&scene);
    let world_from_clip = camera.clip_from_world().inverse();
    let (w, h) = (v.size().x, v.size().y);
    let hit = |x: u32, y: u32| {
        let ndc = |z| {
            let p = glam::DVec3::new(
                (f64::from(x) + 0.5) / f64::from(w) * 2.0 - 1.0,
                1.0 - (f64::from(y) + 0.5) / f64::from(h) * 2.0,
                z,
            );
            world_from_clip.project_point3(p)
        };
        let (near, far) = (ndc(0.0), ndc(1.0));
        let hit = caster.bvh().closest_hit(&Ray { origin: near.as_vec3(), direction: (far - near).as_vec3() }, 1.0)?;
        let (_, normal) = caster.normals_at(&hit);
        Some((near + (far - near) * f64::from(hit.t), normal.as_dvec3()))
    };
    let (mut tested, mut agreeing) = (0, 0);
    for y in (4..h - 4).step_by(3) {
        for x in (4..w - 4).step_by(3) {
            let Some((point, normal)) = hit(x, y) else { continue };
            // A flat neighbourhood: the same plane around the pixel.
            let flat = [(x - 2, y), (x + 2, y), (x, y - 2), (x, y + 2)].iter().all(|&(a, b)| {
                hit(a, b).is_some_and(|(p, n)| n.dot(normal) > 0.9999 && (p - point).dot(normal).abs() < 1e-3)
            });
            let clip = matrix.clip_from_world * point.extend(1.0);
            let inside = clip.w > 0.0 && (clip.x / clip.w).abs() < 0.98 && (clip.y / clip.w).abs() < 0.98;
            let Some(b) = lixel::score::badness(&matrix, &camera, point, normal) else { continue };
            if !flat || !inside || !b.is_finite() {
                continue;
            }
            let want = lixel::view::density_color(b);
            let (d, o) = (density.get_pixel(x, y).0, base.get_pixel(x, y).0);
            // The shader mixes 65% of the legend colour into the linear picture.
            let got: Vec<f64> = (0..3).map(|k| (linear(d[k]) - 0.35 * linear(o[k])) / 0.65).collect();
            tested += 1;
            if (0..3).all(|k| (got[k] - want[k]).abs() < 0.06) {
                agreeing += 1;
            } else if tested - agreeing <= 3 {
                eprintln!("pixel ({x}, {y}): b = {b:.4}, want {want:?}, got {got:?}");
            }
        }
    }
    eprintln!("{agreeing} of {tested} flat pixels inside the map match the CPU badness");
    assert!(tested > 100, "only {tested} flat pixels inside the map");
    assert!(agreeing as f64 >= 0.98 * tested as f64, "{agreeing} of {tested} pixels match the CPU badness");
}
