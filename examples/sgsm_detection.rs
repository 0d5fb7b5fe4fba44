//! SGSM's overlap detection rate (issue 17): per texel, the triangles
//! visible from the light (a CPU reference from the mesh: exact
//! triangle/texel overlap lists, nearest triangle at 8x8 samples and the
//! corners), and the share of texels whose visible triangles the normal
//! detection recognises — the CPU sweep (`lixel::render::sgsm::sweep`, the
//! GPU sweep's reference) over the map an exact conservative pass would
//! keep. On the built-in scene and on dense curved meshes (a sphere and a
//! torus on a floor). No GPU needed.
//!
//! `--closeup PATH` instead renders the tiny built-in scene with SPSM and
//! SGSM (focused 256² map, a point light above), compares both with the ray cast and writes
//! the 64x64-pixel window where SPSM errs most against SGSM, enlarged:
//! SPSM left, SGSM right (grey: correct, dark: shadow; red: false shadow;
//! blue: false light).
//!
//! ```text
//! cargo run --release --example sgsm_detection -- [--maps 512,1024]
//!     [--triangles 1137772] [--curved 200000] [--samples 8]
//! cargo run --release --example sgsm_detection -- --closeup docs/sgsm-closeup.png
//! ```

#[path = "support/mod.rs"]
mod support;

use glam::{DVec3, UVec2, Vec3};
use lixel::mesh::{primitives, ProceduralScene, Role, Scene, SceneObject};
use lixel::render::sgsm::overlap::{self, Detection, OverlapMap};
use lixel::{Camera, Light, Parameterization, ShadowMapSize, ShadowProblem};

fn main() {
    if let Err(e) = run() {
        eprintln!("sgsm_detection: {e}");
        std::process::exit(1);
    }
}

fn curved(name: &str, mesh: lixel::mesh::Mesh) -> Scene {
    let lifted = mesh.transformed(&glam::Affine3A::from_translation(Vec3::new(0.0, 4.0, 0.0)));
    Scene {
        objects: vec![
            SceneObject { name: name.into(), mesh: lifted, role: Role::CasterAndReceiver, albedo: Vec3::splat(0.8) },
            SceneObject {
                name: "floor".into(),
                mesh: primitives::floor(30.0, 2),
                role: Role::Receiver,
                albedo: Vec3::splat(0.7),
            },
        ],
    }
}

fn run() -> Result<(), String> {
    let args = support::Args::from_env();
    if let Some(path) = args.value("--closeup") {
        return closeup(path);
    }
    let maps: Vec<u32> = args.list("--maps", &[512, 1024])?;
    let triangles: usize = args.parse("--triangles", 1_137_772)?;
    let dense: usize = args.parse("--curved", 200_000)?;
    let samples: u32 = args.parse("--samples", 8)?;
    let scenes = [
        (
            format!("built-in ({triangles} triangles budget)"),
            ProceduralScene { triangle_budget: triangles, ..ProceduralScene::default() }.build(),
            support::walk_camera(0.1, UVec2::splat(512)),
        ),
        (format!("sphere r=3 ({dense} triangles)"), curved("sphere", primitives::sphere(3.0, dense)), close_camera()),
        (format!("torus 3/1 ({dense} triangles)"), curved("torus", primitives::torus(3.0, 1.0, dense)), close_camera()),
    ];
    let lights = [Light::directional(DVec3::new(0.6, -1.0, 0.35)), Light::point(DVec3::new(-8.0, 30.0, 12.0))];
    println!("| scene | light | map | texels with a triangle | 1 visible | 2 | 3 | 4 | >4 | recognised 2-4 | recognised >4 | touching 2 / 3 / 4 / >4 |");
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|");
    for (name, scene, camera) in &scenes {
        for light in &lights {
            for &map in &maps {
                let m = ShadowProblem::new(*camera, *light, scene.bounds(), ShadowMapSize::square(map))
                    .and_then(|p| p.solve(&Parameterization::Focused))
                    .map_err(|e| e.to_string())?;
                let started = std::time::Instant::now();
                let tris = overlap::project(scene, &m);
                let overlap = OverlapMap::new(&tris, map, map);
                let words = overlap.sweep_map(&tris).sweep();
                let d = overlap::detection(&tris, &overlap, &words, samples);
                eprintln!("{name}, {light:?}, {map}²: {:.1} s", started.elapsed().as_secs_f64());
                println!("{}", row(name, light, map, &d));
            }
        }
    }
    Ok(())
}

fn close_camera() -> Camera {
    Camera::look_at(
        DVec3::new(0.0, 9.0, 14.0),
        DVec3::new(0.0, 2.0, 0.0),
        DVec3::Y,
        55f64.to_radians(),
        UVec2::splat(512),
        0.5,
        100.0,
    )
    .expect("valid camera")
}

fn row(name: &str, light: &Light, map: u32, d: &Detection) -> String {
    let pct = |r: u64, t: u64| if t == 0 { "–".to_string() } else { format!("{:.1}%", 100.0 * r as f64 / t as f64) };
    let kind = if matches!(light, Light::Directional { .. }) { "directional" } else { "point" };
    let cells: Vec<String> = d.rows.iter().map(|r| format!("{} ({})", r.texels, pct(r.recognised, r.texels))).collect();
    let (t24, r24) = d.rows[1..4].iter().fold((0, 0), |(t, r), row| (t + row.texels, r + row.recognised));
    format!(
        "| {name} | {kind} | {map}² | {} | {} | {} | {} | {} | {} | {} | {} | {} / {} / {} / {} |",
        d.covered,
        cells[0],
        cells[1],
        cells[2],
        cells[3],
        cells[4],
        pct(r24, t24),
        pct(d.rows[4].recognised, d.rows[4].texels),
        d.touching[0],
        d.touching[1],
        d.touching[2],
        d.touching[3]
    )
}

/// Error colours of one method's light-0 bits against the truth.
fn errors(masks: &lixel::mesh::ShadowMasks, truth: &lixel::mesh::ShadowMasks) -> (image::RgbaImage, Vec<bool>) {
    let wrong: Vec<bool> = (0..truth.shadow.len())
        .map(|i| truth.visible(i) && truth.facing[i] & 1 == 1 && (masks.shadow[i] ^ truth.shadow[i]) & 1 == 1)
        .collect();
    let image = image::RgbaImage::from_fn(truth.width, truth.height, |x, y| {
        let i = (y * truth.width + x) as usize;
        let (t, m) = (truth.shadow[i] & 1 == 1, masks.shadow[i] & 1 == 1);
        image::Rgba(match (truth.visible(i), wrong[i], t, m) {
            (false, ..) => [255, 255, 255, 255],
            (_, true, _, true) => [220, 40, 40, 255],
            (_, true, _, false) => [40, 90, 230, 255],
            (_, false, true, _) => [90, 90, 90, 255],
            (_, false, false, _) => [200, 200, 200, 255],
        })
    });
    (image, wrong)
}

fn closeup(path: &str) -> Result<(), String> {
    use lixel::render::{Frame, Renderer, RendererOptions, SgsmOptions, ShadowLookup, SpsmOptions};
    let scene = ProceduralScene::tiny().build();
    let size = 320;
    let camera = Camera::look_at(
        DVec3::new(4.0, 5.0, 34.0),
        DVec3::ZERO,
        DVec3::Y,
        55f64.to_radians(),
        UVec2::splat(size),
        0.5,
        150.0,
    )
    .map_err(|e| e.to_string())?;
    let lights = [Light::point(DVec3::new(-8.0, 30.0, 12.0))];
    let m = ShadowProblem::new(camera, lights[0], scene.bounds(), ShadowMapSize::square(256))
        .and_then(|p| p.solve(&Parameterization::Focused))
        .map_err(|e| e.to_string())?;
    let (device, queue, _) = support::gpu()?;
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).map_err(|e| e.to_string())?;
    let truth = lixel::mesh::RayCaster::new(&scene).trace_masks(&camera, &lights, size, size);
    let mut out = Vec::new();
    for lookup in [ShadowLookup::Spsm(SpsmOptions::PAPER), ShadowLookup::Sgsm(SgsmOptions::PAPER)] {
        let lights = [m];
        renderer.render(&Frame { masks: true, lookup, ..Frame::new(&camera, &lights) }).map_err(|e| e.to_string())?;
        out.push(errors(&renderer.read_masks().map_err(|e| e.to_string())?, &truth));
    }
    let count = |w: &[bool]| w.iter().filter(|&&b| b).count();
    println!("misclassified pixels (light 0, {size}²): SPSM {}, SGSM {}", count(&out[0].1), count(&out[1].1));
    // The window where SPSM's errors exceed SGSM's most.
    let win = 64;
    let mut best = (i64::MIN, 0, 0);
    for y in (0..size - win).step_by(4) {
        for x in (0..size - win).step_by(4) {
            let mut d = 0i64;
            for j in y..y + win {
                for i in x..x + win {
                    let k = (j * size + i) as usize;
                    d += i64::from(out[0].1[k]) - i64::from(out[1].1[k]);
                }
            }
            if d > best.0 {
                best = (d, x, y);
            }
        }
    }
    let (d, x, y) = best;
    println!("window {win}x{win} at ({x}, {y}): SPSM errs at {d} more pixels than SGSM");
    if d <= 0 {
        // Issue 16, session 4: SPSM's own-plane rule removed the false shadow
        // SGSM used to fix here; no picture rather than an empty one.
        return Err(format!("no window where SPSM errs more than SGSM; {path} not written"));
    }
    let crops: Vec<image::RgbaImage> = out
        .iter()
        .map(|(img, _)| {
            let crop = image::imageops::crop_imm(img, x, y, win, win).to_image();
            image::imageops::resize(&crop, win * 4, win * 4, image::imageops::FilterType::Nearest)
        })
        .collect();
    support::montage(&crops, 2).save(path).map_err(|e| e.to_string())?;
    println!("wrote {path}");
    Ok(())
}
