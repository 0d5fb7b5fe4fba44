//! SGSM's overlap detection rate (issue 17): per texel, the triangles
//! visible from the light (a CPU reference from the mesh: exact
//! triangle/texel overlap lists, nearest triangle at 8x8 samples and the
//! corners), and the share of texels whose visible triangles the normal
//! detection recognises — the CPU sweep (`lixel::render::sgsm::sweep`, the
//! GPU sweep's reference) over the map an exact conservative pass would
//! keep. On the built-in scene and on dense curved meshes (a sphere and a
//! torus on a floor). No GPU needed.
//!
//! ```text
//! cargo run --release --example sgsm_detection -- [--maps 512,1024]
//!     [--triangles 1137772] [--curved 200000] [--samples 8]
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
