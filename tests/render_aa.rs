//! Sub-pixel antialiased shadows (`ShadowLookup::SubPixelAa`): the GPU
//! silhouette mask and its summed-area table against the CPU reference,
//! the triangle-tile pair count against a CPU count, and the per-pixel
//! visibility against the ray-cast coverage truth on the tiny scene; the
//! supersampled standard lookup (`ShadowLookup::Supersampled`, the cost
//! baseline) against the same truth; the validity mask on a tetrahedron
//! standing on the floor, the hidden test's gate and the exact path of
//! pixels whose depth compare is uncertain.

#![cfg(all(feature = "render", feature = "cli"))]

mod render_common;

use glam::{DVec2, DVec3, Vec3};
use lixel::experiment::{Coverage, VisibilityError};
use lixel::mesh::{Mesh, RayCaster, Role, Scene, SceneObject};
use lixel::render::subpixel::bitmask::visibility_of_valid;
use lixel::render::subpixel::reference::{summed_area, EdgeAdjacency};
use lixel::render::subpixel::AaSamples;
use lixel::render::{Frame, Renderer, RendererOptions, ShadowLookup};
use lixel::{Camera, Light, LightMatrix, Parameterization};
use render_common::*;

const AA32: ShadowLookup = ShadowLookup::SubPixelAa(AaSamples::X32);

/// The scene's objects as one mesh (as the renderer merges them).
fn merged(scene: &Scene) -> Mesh {
    let mut mesh = Mesh::default();
    for o in &scene.objects {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(&o.mesh.positions);
        mesh.normals.extend(&o.mesh.normals);
        mesh.indices.extend(o.mesh.indices.iter().map(|i| i + base));
    }
    mesh
}

/// Texel coordinates (x right, y down) of a world point; `None` behind the light.
fn texel_of(m: &LightMatrix, p: Vec3) -> Option<DVec2> {
    let t = m.texel_from_world() * p.as_dvec3().extend(1.0);
    (t.w > 0.0).then(|| DVec2::new(t.x / t.w, t.y / t.w))
}

fn camera(size: u32) -> Camera {
    walkthrough_camera(size)
}

/// What [`check_silhouette_mask`] checked: visible silhouette points found
/// in marked texels, and texels of hidden silhouette edges found unmarked.
struct MaskCheck {
    visible_points: usize,
    dropped_texels: usize,
}

/// Checks the GPU's silhouette mask of light `light` (the renderer's last
/// frame, map `m`) against a CPU model that casts rays from the light:
/// - every point of every CPU silhouette edge (sampled at 1/8 texel, away
///   from texel borders) that the light sees (no surface nearer than it by
///   1e-3 world units along its light ray) lies in a marked texel;
/// - the depth check: a texel is unmarked when every silhouette point in it
///   is hidden by more than `HIDDEN` world units, no silhouette point within
///   two texels of it is less hidden, and the first surface the light meets
///   through each of its nine texel centres (its 3x3 neighbourhood) lies
///   more than `HIDDEN / 2` nearer than every silhouette point within a
///   texel of it (the shader compares the edge's nearest depth over the
///   texel, grown by a texel along the edge, with the neighbourhood's
///   largest stored depth);
/// - every marked texel lies within 1.5 texels of a CPU silhouette edge;
/// - the GPU's summed-area table equals the CPU's over the GPU mask.
fn check_silhouette_mask(renderer: &Renderer, scene: &Scene, light: &Light, m: &LightMatrix) -> MaskCheck {
    const HIDDEN: f64 = 0.5;
    let mesh = merged(scene);
    let bvh = RayCaster::new(scene);
    let bvh = bvh.bvh();
    let (mask, sat) = renderer.read_silhouette_mask(0).unwrap();
    let (w, h) = (m.map_size.width as usize, m.map_size.height as usize);
    assert_eq!(sat, summed_area(&mask, w, h), "summed-area table");
    let l = light.homogeneous_position();
    // Depth along the light's rays (world units), and the depth of the
    // first surface on the light ray through world point `p`.
    let depth = |p: DVec3| if l.w > 0.0 { p.distance(l.truncate()) } else { p.dot(-l.truncate()) };
    let first_depth = |p: DVec3| -> f64 {
        let (origin, direction) = if l.w > 0.0 {
            (l.truncate(), p - l.truncate())
        } else {
            let d = -l.truncate().normalize();
            (p - d * 1000.0, d * 1000.0)
        };
        let ray = lixel::mesh::raycast::Ray { origin: origin.as_vec3(), direction: direction.as_vec3() };
        bvh.closest_hit(&ray, 2.0).map_or(f64::INFINITY, |hit| depth(origin + direction * f64::from(hit.t)))
    };
    let world_from_texel = m.texel_from_world().inverse();
    let centre_depth = |x: i64, y: i64| -> f64 {
        let (x, y) = (x.clamp(0, w as i64 - 1), y.clamp(0, h as i64 - 1));
        let p = world_from_texel * glam::DVec4::new(x as f64 + 0.5, y as f64 + 0.5, 0.5, 1.0);
        first_depth(p.truncate() / p.w)
    };
    let world_segments: Vec<[DVec3; 2]> =
        EdgeAdjacency::new(&mesh).silhouette(&mesh, l).into_iter().map(|[a, b]| [a.as_dvec3(), b.as_dvec3()]).collect();
    let segments: Vec<[DVec2; 2]> = world_segments
        .iter()
        .filter_map(|[a, b]| Some([texel_of(m, a.as_vec3())?, texel_of(m, b.as_vec3())?]))
        .collect();
    assert!(segments.len() >= 12, "{} silhouette segments", segments.len());
    // Every sample point: its texel, its depth and how far it is hidden.
    let mut samples: Vec<(DVec2, f64, f64)> = Vec::new();
    for [a, b] in &world_segments {
        let (Some(ta), Some(tb)) = (texel_of(m, a.as_vec3()), texel_of(m, b.as_vec3())) else { continue };
        let steps = (ta.distance(tb) * 8.0).ceil().max(1.0) as usize;
        for k in 0..=steps {
            let p = a.lerp(*b, k as f64 / steps as f64);
            let Some(t) = texel_of(m, p.as_vec3()) else { continue };
            if t.x < 0.0 || t.y < 0.0 || t.x >= w as f64 || t.y >= h as f64 {
                continue;
            }
            samples.push((t, depth(p), depth(p) - first_depth(p)));
        }
    }
    let mut visible_points = 0;
    for &(p, _, hidden) in &samples {
        let f = p - p.floor();
        if hidden > 1e-3 || f.min_element() < 1e-3 || f.max_element() > 1.0 - 1e-3 {
            continue;
        }
        visible_points += 1;
        let i = p.y as usize * w + p.x as usize;
        assert_eq!(mask[i], 1, "visible silhouette point {p} in an unmarked texel ({light:?})");
    }
    let texel = |p: DVec2| (p.x.floor() as i64, p.y.floor() as i64);
    let within = |p: DVec2, (x, y): (i64, i64), r: i64| {
        let (px, py) = texel(p);
        (px - x).abs() <= r && (py - y).abs() <= r
    };
    let mut candidates: Vec<(i64, i64)> = samples.iter().filter(|s| s.2 > HIDDEN).map(|s| texel(s.0)).collect();
    candidates.sort_unstable();
    candidates.dedup();
    let mut dropped_texels = 0;
    for (x, y) in candidates {
        if samples.iter().any(|s| s.2 <= HIDDEN && within(s.0, (x, y), 2)) {
            continue;
        }
        let near = samples.iter().filter(|s| within(s.0, (x, y), 1)).map(|s| s.1).fold(f64::INFINITY, f64::min);
        let deepest =
            (-1..=1).flat_map(|dy| (-1..=1).map(move |dx| (dx, dy))).map(|(dx, dy)| centre_depth(x + dx, y + dy));
        if deepest.fold(f64::NEG_INFINITY, f64::max) > near - 0.5 * HIDDEN {
            continue;
        }
        dropped_texels += 1;
        assert_eq!(mask[y as usize * w + x as usize], 0, "texel ({x}, {y}) of a hidden silhouette marked ({light:?})");
    }
    let distance_to = |p: DVec2, [a, b]: &[DVec2; 2]| {
        let d = *b - *a;
        let t = if d.length_squared() > 0.0 { ((p - *a).dot(d) / d.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
        p.distance(*a + d * t)
    };
    let marked: Vec<usize> = (0..mask.len()).filter(|&i| mask[i] != 0).collect();
    assert!(!marked.is_empty());
    for &i in &marked {
        let centre = DVec2::new((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
        let near = segments.iter().map(|s| distance_to(centre, s)).fold(f64::INFINITY, f64::min);
        assert!(near < 1.5, "texel {centre} marked {near} texels from every silhouette edge ({light:?})");
    }
    MaskCheck { visible_points, dropped_texels }
}

/// The silhouette mask against the CPU model of [`check_silhouette_mask`]
/// on the tiny scene, a directional and a point light.
#[test]
fn silhouette_mask_and_summed_area_match_the_cpu_reference() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let cam = camera(64);
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    for light in test_lights() {
        let m = matrices(&scene, &cam, &[light], 96, &Parameterization::Focused)[0];
        renderer.render(&Frame { lookup: AA32, ..Frame::new(&cam, &[m]) }).unwrap();
        let check = check_silhouette_mask(&renderer, &scene, &light, &m);
        eprintln!("{light:?}: {} visible points, {} hidden texels", check.visible_points, check.dropped_texels);
        assert!(check.visible_points > 100, "{} points checked", check.visible_points);
    }
}

/// A floor (20 x 20, y = 0), a plate (6 x 0.5 x 6) at y = 8 and a cube (1 x
/// 1 x 1) at y = 1.5 under the plate's middle: seen from above, the cube's
/// silhouette lies under the plate, more than two units from its outline.
fn hidden_cube_scene() -> Scene {
    use lixel::mesh::primitives::{cuboid, floor};
    let at = |mesh: Mesh, y: f32| mesh.transformed(&glam::Affine3A::from_translation(Vec3::new(0.0, y, 0.0)));
    let object =
        |name: &str, mesh| SceneObject { name: name.into(), mesh, role: Role::CasterAndReceiver, albedo: Vec3::ONE };
    Scene {
        objects: vec![
            object("floor", floor(20.0, 2)),
            object("plate", at(cuboid(Vec3::new(3.0, 0.25, 3.0), 12), 8.0)),
            object("cube", at(cuboid(Vec3::splat(0.5), 12), 1.5)),
        ],
    }
}

/// The silhouette pass's depth check: a cube hidden from the light under a
/// larger plate leaves no texel marked (before the check every texel its
/// silhouette crossed was: the test then fails on its first hidden texel),
/// while the plate's outline and the floor's border stay marked
/// ([`check_silhouette_mask`]). With the check off
/// (`Renderer::set_aa_depth_check`) every walked texel is marked again: a
/// superset, at least the hidden texels more. The marked count in
/// `AaStats::silhouette_texels` equals the mask's. A near-vertical sun and a
/// point light above.
#[test]
fn hidden_silhouettes_are_not_marked() {
    let Some((device, queue)) = gpu() else { return };
    let scene = hidden_cube_scene();
    let cam = Camera::look_at(
        DVec3::new(4.0, 14.0, 16.0),
        DVec3::ZERO,
        DVec3::Y,
        55f64.to_radians(),
        glam::UVec2::splat(64),
        0.5,
        150.0,
    )
    .expect("valid camera");
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    for light in [Light::directional(DVec3::new(0.15, -1.0, 0.1)), Light::point(DVec3::new(0.5, 30.0, 0.3))] {
        let m = matrices(&scene, &cam, &[light], 128, &Parameterization::Focused)[0];
        renderer.render(&Frame { lookup: AA32, ..Frame::new(&cam, &[m]) }).unwrap();
        let check = check_silhouette_mask(&renderer, &scene, &light, &m);
        let kept = renderer.read_aa_stats(0).unwrap().silhouette_texels;
        let (mask, _) = renderer.read_silhouette_mask(0).unwrap();
        assert_eq!(kept as usize, mask.iter().filter(|&&t| t != 0).count(), "the marked texels' count");
        renderer.set_aa_depth_check(false).unwrap();
        renderer.render(&Frame { lookup: AA32, ..Frame::new(&cam, &[m]) }).unwrap();
        let (all, _) = renderer.read_silhouette_mask(0).unwrap();
        let walked = renderer.read_aa_stats(0).unwrap().silhouette_texels;
        renderer.set_aa_depth_check(true).unwrap();
        eprintln!(
            "{light:?}: {} visible points, {} hidden texels; {kept} of {walked} walked texels marked",
            check.visible_points, check.dropped_texels
        );
        assert!(check.visible_points > 100, "{} points checked", check.visible_points);
        assert!(
            check.dropped_texels >= 10,
            "{} hidden texels: the test needs the cube's outline",
            check.dropped_texels
        );
        assert!(mask.iter().zip(&all).all(|(&a, &b)| a <= b), "the check only drops texels");
        assert!(kept + check.dropped_texels as u32 <= walked, "{kept} + {} > {walked}", check.dropped_texels);
    }
}

/// The pair count (triangle-tile list entries) equals a CPU count: each
/// triangle's projected bounding box grown by a texel, its list tiles
/// (4x4 texels, `LIST_TILE` in gpu.rs) whose tile of 8x8 has a
/// neighbourhood (grown by 16 texels) holding a silhouette texel of the
/// GPU's own mask. f32 against f64 box corners may move a box edge
/// across a tile border, so within 1%.
#[test]
fn pair_count_matches_a_cpu_count() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let mesh = merged(&scene);
    let cam = camera(64);
    let light = test_lights()[0];
    let m = matrices(&scene, &cam, &[light], 128, &Parameterization::Focused)[0];
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    // Uncertain pixels may force tiles active beyond the mask's.
    renderer.set_aa_uncertain_pixels(false).unwrap();
    renderer.render(&Frame { lookup: AA32, ..Frame::new(&cam, &[m]) }).unwrap();
    let (mask, _) = renderer.read_silhouette_mask(0).unwrap();
    let stats = renderer.read_aa_stats(0).unwrap();
    let (w, h) = (m.map_size.width as i64, m.map_size.height as i64);
    let active = |tx: i64, ty: i64| {
        let (x0, y0) = ((tx * 8 - 16).max(0), (ty * 8 - 16).max(0));
        let (x1, y1) = ((tx * 8 + 23).min(w - 1), (ty * 8 + 23).min(h - 1));
        (y0..=y1).any(|y| (x0..=x1).any(|x| mask[(y * w + x) as usize] != 0))
    };
    let mut expected = 0u64;
    for tri in mesh.indices.chunks_exact(3) {
        let p: Vec<DVec2> = tri.iter().filter_map(|&i| texel_of(&m, mesh.positions[i as usize])).collect();
        assert_eq!(p.len(), 3, "directional light: nothing behind it");
        let lo = p.iter().fold(DVec2::INFINITY, |a, b| a.min(*b));
        let hi = p.iter().fold(DVec2::NEG_INFINITY, |a, b| a.max(*b));
        if hi.x < -1.0 || hi.y < -1.0 || lo.x > w as f64 + 1.0 || lo.y > h as f64 + 1.0 {
            continue;
        }
        let a = ((lo.x.floor() as i64 - 1).clamp(0, w - 1), (lo.y.floor() as i64 - 1).clamp(0, h - 1));
        let b = ((hi.x.floor() as i64 + 1).clamp(0, w - 1), (hi.y.floor() as i64 + 1).clamp(0, h - 1));
        const LIST: i64 = 4;
        for ly in a.1 / LIST..=b.1 / LIST {
            for lx in a.0 / LIST..=b.0 / LIST {
                expected += u64::from(active(lx * LIST / 8, ly * LIST / 8));
            }
        }
    }
    assert!(expected > 100, "{expected} pairs: the test needs silhouettes");
    let got = u64::from(stats.pairs);
    assert!(got.abs_diff(expected) * 100 <= expected, "GPU {got} pairs, CPU {expected}");
    assert_eq!(stats.overflow_pixels, 0);
}

/// The pairs themselves against a CPU reference: every list tile's
/// triangles (read back, sorted) equal the CPU's set from the same rules
/// (box grown by a texel, list tiles of active tiles of the GPU's own
/// mask), except where a CPU box corner lies within 0.01 texel of a texel
/// border (f32 against f64 corners may floor differently there). A sun
/// and a point light, 128² focused maps.
#[test]
fn pair_lists_match_a_cpu_reference() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let mesh = merged(&scene);
    let cam = camera(64);
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    renderer.set_aa_uncertain_pixels(false).unwrap();
    const LIST: i64 = Renderer::AA_LIST_TILE as i64;
    for light in test_lights() {
        let m = matrices(&scene, &cam, &[light], 128, &Parameterization::Focused)[0];
        renderer.render(&Frame { lookup: AA32, ..Frame::new(&cam, &[m]) }).unwrap();
        let (mask, _) = renderer.read_silhouette_mask(0).unwrap();
        let lists = renderer.read_aa_lists(0).unwrap();
        let (w, h) = (m.map_size.width as i64, m.map_size.height as i64);
        let lists_x = (w + LIST - 1) / LIST;
        assert_eq!(lists.len() as i64, lists_x * ((h + LIST - 1) / LIST));
        let active = |tx: i64, ty: i64| {
            let (x0, y0) = ((tx * 8 - 16).max(0), (ty * 8 - 16).max(0));
            let (x1, y1) = ((tx * 8 + 23).min(w - 1), (ty * 8 + 23).min(h - 1));
            (y0..=y1).any(|y| (x0..=x1).any(|x| mask[(y * w + x) as usize] != 0))
        };
        let mut expected: Vec<Vec<u32>> = vec![Vec::new(); lists.len()];
        let mut borderline = std::collections::HashSet::new();
        for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
            let p: Vec<DVec2> = tri.iter().filter_map(|&i| texel_of(&m, mesh.positions[i as usize])).collect();
            assert_eq!(p.len(), 3, "nothing behind the light");
            let lo = p.iter().fold(DVec2::INFINITY, |a, b| a.min(*b));
            let hi = p.iter().fold(DVec2::NEG_INFINITY, |a, b| a.max(*b));
            if hi.x < -1.0 || hi.y < -1.0 || lo.x > w as f64 + 1.0 || lo.y > h as f64 + 1.0 {
                continue;
            }
            let near_border = [lo.x, lo.y, hi.x, hi.y].iter().any(|c| (c - c.round()).abs() < 0.01);
            if near_border {
                borderline.insert(t as u32);
            }
            let a = ((lo.x.floor() as i64 - 1).clamp(0, w - 1), (lo.y.floor() as i64 - 1).clamp(0, h - 1));
            let b = ((hi.x.floor() as i64 + 1).clamp(0, w - 1), (hi.y.floor() as i64 + 1).clamp(0, h - 1));
            for ly in a.1 / LIST..=b.1 / LIST {
                for lx in a.0 / LIST..=b.0 / LIST {
                    if active(lx * LIST / 8, ly * LIST / 8) {
                        expected[(ly * lists_x + lx) as usize].push(t as u32);
                    }
                }
            }
        }
        let (mut pairs, mut differ) = (0usize, 0usize);
        for (i, (got, want)) in lists.iter().zip(&expected).enumerate() {
            let got = got.as_ref().expect("no list overflows on the tiny scene");
            pairs += want.len();
            let (g, e): (std::collections::BTreeSet<u32>, std::collections::BTreeSet<u32>) =
                (got.iter().copied().collect(), want.iter().copied().collect());
            assert_eq!(g.len(), got.len(), "list {i}: a triangle entered twice");
            for t in g.symmetric_difference(&e) {
                differ += 1;
                assert!(borderline.contains(t), "list {i}: triangle {t} differs ({light:?})");
            }
        }
        eprintln!("{light:?}: {pairs} pairs, {differ} borderline differences");
        assert!(pairs > 1000, "{pairs} pairs: the test needs silhouettes");
        assert!(differ * 100 <= pairs, "{differ} of {pairs} pairs differ");
    }
}

/// On the tiny scene (96x96 pixels, focused 256² map), the 32-sample
/// visibility of the antialiased lookup is within 0.006 mean absolute error
/// of the ray-cast coverage truth and under 0.3x the standard lookup's
/// error (measured with facets on the triangles' planes: 0.0036 against
/// 0.0258 for the sun, 0.0032 against 0.0147 for the point light; 0.0060
/// and 0.0047 on the interpolated normals); its shadow bits are the
/// standard lookup's. Every light kind: a sun, a point light and a spot
/// light whose cone edge crosses the floor in view (the truth counts only
/// sub-samples inside the cone; the occlusion words scored here count every
/// sample, the cone is in the validity words, see
/// `samples_outside_a_spots_cone_are_not_valid`); the spot within 0.008
/// (measured 0.0059 against the standard lookup's 0.0287).
#[test]
fn visibility_matches_the_coverage_truth() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let cam = camera(96);
    let caster = RayCaster::new(&scene);
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    let spot_at = DVec3::new(-8.0, 30.0, 12.0);
    let spot = Light::spot(spot_at, -spot_at, 20f64.to_radians());
    for light in test_lights().into_iter().chain([spot]) {
        let m = matrices(&scene, &cam, &[light], 256, &Parameterization::Focused)[0];
        let truth = caster.trace_masks(&cam, &[light], 96, 96);
        let coverage = Coverage::trace(&caster, &cam, &light, &truth);
        renderer.render(&Frame { masks: true, ..Frame::new(&cam, &[m]) }).unwrap();
        let standard = renderer.read_masks().unwrap();
        renderer.render(&Frame { masks: true, lookup: AA32, ..Frame::new(&cam, &[m]) }).unwrap();
        let aa_masks = renderer.read_masks().unwrap();
        assert_eq!(aa_masks.shadow, standard.shadow, "the mode's bit is the depth compare's");
        let occlusion = renderer.read_occlusion(0).unwrap();
        let stats = renderer.read_aa_stats(0).unwrap();
        let e_std = VisibilityError::of_masks(&standard, &truth, &coverage, AaSamples::X32).mean().unwrap();
        let e_aa = VisibilityError::of_occlusion(&occlusion, &truth, &coverage, AaSamples::X32).mean().unwrap();
        eprintln!("{light:?}: standard {e_std:.4}, aa32 {e_aa:.4}, {stats:?}");
        assert!(stats.exact_pixels > 50, "{stats:?}");
        assert_eq!(stats.overflow_pixels, 0);
        assert!(e_aa < 0.3 * e_std, "aa32 {e_aa} against standard {e_std}");
        let bound = if matches!(light, Light::Spot { .. }) { 0.008 } else { 0.006 };
        assert!(e_aa < bound, "aa32 {e_aa}");
        // Partial pixels exist: the words are not all-or-nothing.
        let partial = occlusion.iter().filter(|&&w| w != 0 && w != u32::MAX).count();
        assert!(partial > 20, "{partial} partial pixels");
        // Only pixels on the exact path may leave the standard bit: every
        // other word is the depth compare's bit in every sample.
        let off = occlusion
            .iter()
            .zip(&standard.shadow)
            .filter(|&(&w, &s)| w != if s & 1 != 0 { u32::MAX } else { 0 })
            .count();
        assert!(off >= partial && off <= stats.exact_pixels as usize, "{off} words off the standard bit, {stats:?}");
    }
}

/// A floor (y = 0, 20 x 20) under a grating of 0.1-wide bars 0.1 apart at
/// y = 6, all along z: a striped shadow, so that a curve on the floor
/// crosses many shadow edges.
fn grating_scene() -> Scene {
    let quad = |x0: f32, x1: f32, y: f32| Mesh {
        positions: vec![
            Vec3::new(x0, y, -10.0),
            Vec3::new(x1, y, -10.0),
            Vec3::new(x1, y, 10.0),
            Vec3::new(x0, y, 10.0),
        ],
        normals: vec![Vec3::Y; 4],
        indices: vec![0, 2, 1, 0, 3, 2],
    };
    let object = |name: String, mesh| SceneObject { name, mesh, role: Role::CasterAndReceiver, albedo: Vec3::ONE };
    let mut objects = vec![object("floor".into(), quad(-10.0, 10.0, 0.0))];
    for k in 0..40 {
        let x = -4.0 + 0.2 * k as f32;
        objects.push(object(format!("bar {k}"), quad(x, x + 0.1, 6.0)));
    }
    Scene { objects }
}

/// A spot light's cone: at the cone's edge the coverage truth leaves the
/// sub-samples outside the cone out of its valid ones (the surface there is
/// unlit, not shadowed), as the standard lookup leaves a pixel whose centre
/// lies outside out of its facing bits; the exact path's validity words
/// leave them out too. A spot above a grating (`grating_scene`) whose
/// cone's edge crosses the striped shadow in view; the camera, below the
/// grating and looking down, sees only the floor (so the paper's validity
/// mask hides no sample: the cone alone decides). The samples outside are
/// found by tracing the same pixels for a point light at the spot's
/// position (which differs only by the cone). Over the partial pixels
/// (occlusion neither 0 nor all: the exact path) on the cone's edge, at
/// most a tenth of the samples outside may stay valid (measured: none;
/// before the cone was applied, every one that no triangle hid stayed
/// valid), and their visibility error must fall below the error with those
/// samples valid.
#[test]
fn samples_outside_a_spots_cone_are_not_valid() {
    let Some((device, queue)) = gpu() else { return };
    let scene = grating_scene();
    let cam = Camera::look_at(
        DVec3::new(0.0, 4.0, 4.0),
        DVec3::ZERO,
        DVec3::Y,
        55f64.to_radians(),
        glam::UVec2::splat(96),
        0.5,
        150.0,
    )
    .expect("valid camera");
    let caster = RayCaster::new(&scene);
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    let spot_at = DVec3::new(0.5, 12.0, 0.0);
    let spot = Light::spot(spot_at, DVec3::NEG_Y, (2.0f64 / 12.0).atan());
    let m = matrices(&scene, &cam, &[spot], 256, &Parameterization::Focused)[0];
    let truth = caster.trace_masks(&cam, &[spot], 96, 96);
    let coverage = Coverage::trace(&caster, &cam, &spot, &truth);
    let open = Coverage::trace(&caster, &cam, &Light::point(spot_at), &truth);
    renderer.render(&Frame { lookup: AA32, ..Frame::new(&cam, &[m]) }).unwrap();
    let occlusion = renderer.read_occlusion(0).unwrap();
    let valid = renderer.read_validity(0).unwrap();
    let (mut pixels, mut outside, mut kept) = (0u32, 0u32, 0u32);
    let (mut e_cone, mut e_open) = (0.0, 0.0);
    for i in 0..occlusion.len() {
        let cut = open.valid[i] & !coverage.valid[i];
        let w = occlusion[i];
        if cut == 0 || w == 0 || w == u32::MAX {
            continue;
        }
        pixels += 1;
        outside += cut.count_ones();
        kept += (valid[i] & cut).count_ones();
        let want = coverage.visibility(i, AaSamples::X32).unwrap_or(if truth.shadow[i] & 1 != 0 { 0.0 } else { 1.0 });
        e_cone += (visibility_of_valid(w, valid[i], AaSamples::X32) - want).abs();
        e_open += (visibility_of_valid(w, valid[i] | cut, AaSamples::X32) - want).abs();
    }
    eprintln!(
        "{pixels} partial pixels on the cone's edge: {kept} of {outside} samples outside stay valid; \
         summed error {e_cone:.3} (with them valid {e_open:.3})"
    );
    assert!(pixels >= 20 && outside >= 100, "{pixels} pixels, {outside} samples outside the cone");
    assert!(kept * 10 <= outside, "{kept} of {outside} samples outside the cone stay valid");
    assert!(e_cone < e_open, "error {e_cone} against {e_open} with the samples outside valid");
}

/// The occlusion words keep only the pattern's bits; reading before any
/// antialiased frame is a typed error.
#[test]
fn sample_counts_and_errors() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let cam = camera(32);
    let m = matrices(&scene, &cam, &test_lights()[..1], 64, &Parameterization::Focused)[0];
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    assert!(renderer.read_occlusion(0).is_err());
    renderer.render(&Frame::new(&cam, &[m])).unwrap();
    assert!(renderer.read_occlusion(0).is_err());
    for samples in AaSamples::ALL {
        renderer.render(&Frame { lookup: ShadowLookup::SubPixelAa(samples), ..Frame::new(&cam, &[m]) }).unwrap();
        let words = renderer.read_occlusion(0).unwrap();
        assert_eq!(words.len(), 32 * 32);
        assert!(words.iter().all(|w| w & !samples.mask() == 0), "{samples:?}");
        assert!(words.iter().any(|&w| w != 0), "{samples:?}: something is shadowed");
    }
    assert!(renderer.read_occlusion(1).is_err());
}

/// The overflow policy: with room for a tenth of the pairs, pixels whose
/// tiles' lists did not fit keep the standard bit in every sample and are
/// counted; the words of every other pixel are unchanged.
#[test]
fn overflowing_lists_keep_the_standard_bit() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let cam = camera(64);
    let m = matrices(&scene, &cam, &test_lights()[..1], 128, &Parameterization::Focused)[0];
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    renderer.render(&Frame { masks: true, lookup: AA32, ..Frame::new(&cam, &[m]) }).unwrap();
    let full = renderer.read_occlusion(0).unwrap();
    let full_stats = renderer.read_aa_stats(0).unwrap();
    let masks = renderer.read_masks().unwrap();
    assert_eq!(full_stats.overflow_pixels, 0);
    renderer.set_aa_pair_capacity(full_stats.pairs / 10).unwrap();
    renderer.render(&Frame { masks: true, lookup: AA32, ..Frame::new(&cam, &[m]) }).unwrap();
    let cut = renderer.read_occlusion(0).unwrap();
    let stats = renderer.read_aa_stats(0).unwrap();
    assert_eq!(stats.pairs, full_stats.pairs, "pairs wanted do not depend on the room");
    assert!(stats.overflow_pixels > 0, "{stats:?}");
    // Pixels on the exact path, overflowing or wide: the same set either way
    // (a footprint's tiles are checked in order, so a pixel may move from
    // wide to overflow).
    let off_standard = |s: &lixel::render::subpixel::gpu::AaStats| s.exact_pixels + s.overflow_pixels + s.wide_pixels;
    assert_eq!(off_standard(&stats), off_standard(&full_stats), "{stats:?} {full_stats:?}");
    let mut changed = 0;
    for i in 0..cut.len() {
        if cut[i] != full[i] {
            changed += 1;
            let standard = if masks.shadow[i] & 1 != 0 { u32::MAX } else { 0 };
            assert_eq!(cut[i], standard, "pixel {i}: a changed word must be the standard bit");
        }
    }
    assert!(changed > 0 && changed <= stats.overflow_pixels as usize, "{changed} changed, {stats:?}");
}

/// Two lights in one frame give each light the words it gets alone (the
/// passes run per light with their own parameters and output range).
#[test]
fn lights_in_one_frame_match_lights_alone() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let cam = camera(48);
    let both = matrices(&scene, &cam, &test_lights(), 96, &Parameterization::Focused);
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    renderer.render(&Frame { lookup: AA32, ..Frame::new(&cam, &both) }).unwrap();
    let together: Vec<Vec<u32>> = (0..2).map(|i| renderer.read_occlusion(i).unwrap()).collect();
    let stats: Vec<_> = (0..2).map(|i| renderer.read_aa_stats(i).unwrap()).collect();
    for (i, m) in both.iter().enumerate() {
        renderer.render(&Frame { lookup: AA32, ..Frame::new(&cam, std::slice::from_ref(m)) }).unwrap();
        assert_eq!(renderer.read_occlusion(0).unwrap(), together[i], "light {i}");
        // Every count but the triangle tests, which depend on the lists'
        // (atomic) order: a pixel's walk stops once every sample is occluded.
        let alone = renderer.read_aa_stats(0).unwrap();
        let counts =
            |s: &lixel::render::subpixel::gpu::AaStats| (s.pairs, s.exact_pixels, s.overflow_pixels, s.wide_pixels);
        assert_eq!(counts(&alone), counts(&stats[i]), "light {i}");
        assert!(stats[i].exact_pixels > 0, "light {i}: {:?}", stats[i]);
    }
}

/// The per-pixel culling of list entries by the triangles' boxes tests far
/// fewer triangles and gives the words of testing every entry of the
/// footprint's tiles: a sun and a point light, a focused and a LiSPSM
/// (anisotropic texels) matrix, a coarse and a fine map. The culled entries'
/// boxes miss the footprint by more than the lists' texel, so only the
/// table's quantization (0.025 px, or more at a sliver's tip where two
/// edges' errors meet) can make one occlude a sample: at most one word in
/// 500 of the exact path may differ, and where one does the culled word
/// must agree with the ray-cast truth on every differing bit (measured: 4
/// words in 6 cases, each one sample the unculled word occluded and the
/// truth finds lit).
#[test]
fn footprint_culling_keeps_the_words() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let cam = camera(96);
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    for light in test_lights() {
        for (p, map) in [
            (Parameterization::Focused, 256),
            (Parameterization::Focused, 1024),
            (Parameterization::LiSpsm(Default::default()), 256),
        ] {
            let m = matrices(&scene, &cam, &[light], map, &p)[0];
            renderer.set_aa_footprint_culling(false).unwrap();
            renderer.render(&Frame { lookup: AA32, ..Frame::new(&cam, &[m]) }).unwrap();
            let all = renderer.read_occlusion(0).unwrap();
            let all_stats = renderer.read_aa_stats(0).unwrap();
            renderer.set_aa_footprint_culling(true).unwrap();
            renderer.render(&Frame { lookup: AA32, ..Frame::new(&cam, &[m]) }).unwrap();
            let culled = renderer.read_occlusion(0).unwrap();
            let stats = renderer.read_aa_stats(0).unwrap();
            let differ = all.iter().zip(&culled).filter(|(a, b)| a != b).count();
            let caster = RayCaster::new(&scene);
            let truth = caster.trace_masks(&cam, &[light], 96, 96);
            let coverage = Coverage::trace(&caster, &cam, &light, &truth);
            for (i, (a, b)) in all.iter().zip(&culled).enumerate() {
                let bits = a ^ b;
                let shadowed = coverage.valid[i] & !coverage.lit[i];
                assert!(
                    bits & coverage.valid[i] == bits && b & bits == shadowed & bits,
                    "pixel {i}: all {a:08x} culled {b:08x}, truth valid {:08x} lit {:08x}",
                    coverage.valid[i],
                    coverage.lit[i]
                );
            }
            eprintln!("{light:?} {p:?} {map}: {differ} words differ; all {all_stats:?}; culled {stats:?}");
            assert!(all_stats.exact_pixels > 50, "{all_stats:?}");
            assert_eq!(
                (stats.exact_pixels, stats.wide_pixels, stats.overflow_pixels),
                (all_stats.exact_pixels, all_stats.wide_pixels, all_stats.overflow_pixels)
            );
            assert!(2 * stats.triangle_tests < all_stats.triangle_tests, "{stats:?} {all_stats:?}");
            // Every entry read is tested with culling off; with it on, the
            // culled ones are read and not tested.
            assert_eq!(all_stats.entries_scanned, all_stats.triangle_tests, "{all_stats:?}");
            assert!(stats.entries_scanned > stats.triangle_tests, "{stats:?}");
            assert!(differ * 500 <= stats.exact_pixels as usize, "{differ} words differ");
        }
    }
}

const SS32: ShadowLookup = ShadowLookup::Supersampled(AaSamples::X32);

/// The supersampled standard lookup (the baseline of the antialiased one's
/// cost goal) answers the coverage truth's question at the truth's own
/// sub-samples: with a fine map (1024² on 64x64 pixels) its valid bits are
/// the truth's, its occluded bits the truth's shadowed ones at the pixels
/// the truth finds partly lit, and its error is a small part of the
/// standard lookup's; its centre bit is the depth compare's.
#[test]
fn supersampling_matches_the_coverage_truth_with_a_fine_map() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let size = 64;
    let cam = camera(size);
    let caster = RayCaster::new(&scene);
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    for light in test_lights() {
        let m = matrices(&scene, &cam, &[light], 1024, &Parameterization::Focused)[0];
        let truth = caster.trace_masks(&cam, &[light], size, size);
        let coverage = Coverage::trace(&caster, &cam, &light, &truth);
        renderer.render(&Frame { masks: true, ..Frame::new(&cam, &[m]) }).unwrap();
        let standard = renderer.read_masks().unwrap();
        renderer.render(&Frame { masks: true, lookup: SS32, ..Frame::new(&cam, &[m]) }).unwrap();
        let ss_masks = renderer.read_masks().unwrap();
        assert_eq!(ss_masks.shadow, standard.shadow, "the centre pass is the depth compare's");
        let words = renderer.read_supersampled(0).unwrap();
        let (mut valid_bits, mut valid_differ, mut partial_bits, mut partial_differ) = (0u32, 0u32, 0u32, 0u32);
        for i in 0..coverage.valid.len() {
            let v = coverage.valid[i];
            if v == 0 {
                continue;
            }
            valid_bits += v.count_ones();
            valid_differ += (v ^ words.valid[i]).count_ones();
            let lit = coverage.lit[i];
            if lit != 0 && lit != v {
                let both = v & words.valid[i];
                partial_bits += both.count_ones();
                partial_differ += ((v & !lit & both) ^ (words.occluded[i] & both)).count_ones();
            }
        }
        let e_std = VisibilityError::of_masks(&standard, &truth, &coverage, AaSamples::X32).mean().unwrap();
        let e_ss =
            VisibilityError::of_supersampled(&words, &ss_masks, &truth, &coverage, AaSamples::X32).mean().unwrap();
        eprintln!(
            "{light:?}: standard {e_std:.4}, ss32 {e_ss:.4}; valid bits {valid_differ}/{valid_bits} differ, \
             bits of partial pixels {partial_differ}/{partial_bits} differ"
        );
        assert!(valid_bits > 10_000 && partial_bits > 500, "{valid_bits} valid, {partial_bits} partial bits");
        assert!(valid_differ * 100 <= valid_bits, "{valid_differ} of {valid_bits} valid bits differ");
        assert!(partial_differ * 10 <= partial_bits, "{partial_differ} of {partial_bits} bits differ");
        assert!(e_ss < 0.5 * e_std, "ss32 {e_ss} against standard {e_std}");
    }
}

/// The supersampled words keep only the pattern's bits (occluded within
/// valid); reading before any supersampled frame, or a light the frame did
/// not have, is a typed error.
#[test]
fn supersampled_sample_counts_and_errors() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let cam = camera(32);
    let m = matrices(&scene, &cam, &test_lights()[..1], 64, &Parameterization::Focused)[0];
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    assert!(renderer.read_supersampled(0).is_err());
    renderer.render(&Frame::new(&cam, &[m])).unwrap();
    assert!(renderer.read_supersampled(0).is_err());
    for samples in AaSamples::ALL {
        renderer.render(&Frame { lookup: ShadowLookup::Supersampled(samples), ..Frame::new(&cam, &[m]) }).unwrap();
        let words = renderer.read_supersampled(0).unwrap();
        assert_eq!((words.valid.len(), words.occluded.len()), (32 * 32, 32 * 32));
        assert!(words.valid.iter().all(|w| w & !samples.mask() == 0), "{samples:?}");
        assert!(words.occluded.iter().zip(&words.valid).all(|(o, v)| o & !v == 0), "{samples:?}");
        assert!(words.occluded.iter().any(|&w| w != 0), "{samples:?}: something is shadowed");
        assert!(words.valid.contains(&samples.mask()), "{samples:?}: some pixel wholly facing the light");
    }
    assert!(renderer.read_supersampled(1).is_err());
}

/// The experiment's framing of a tetrahedron standing on the floor: 64x64
/// pixels and a 64² focused map for light `light` of the quick preset, the
/// ray-cast truth and coverage, and a renderer with the experiment's
/// options.
struct Tetrahedron {
    cam: Camera,
    matrix: LightMatrix,
    truth: lixel::mesh::ShadowMasks,
    coverage: Coverage,
    renderer: Renderer,
}

impl Tetrahedron {
    fn new(device: &wgpu::Device, queue: &wgpu::Queue, light: usize) -> Self {
        use lixel::experiment::{camera_for, experiment_renderer_options, light_for, load_scene};
        use lixel::experiment::{ExperimentConfig, Preset, SceneSource};
        use lixel::{ShadowMapSize, ShadowProblem};
        // One folder per call: the tests run in parallel.
        static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("lixel-render-aa-{}-{call}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("tetrahedron.obj");
        std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n").unwrap();
        let config = ExperimentConfig {
            scene: SceneSource::File { path, options: Default::default() },
            screen: 64,
            map: 64,
            ..ExperimentConfig::preset(Preset::Quick)
        };
        let scene = load_scene(&config.scene).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        let cam = camera_for(&config, &scene).unwrap();
        let light = light_for(&config, &scene, light);
        let matrix = ShadowProblem::new(cam, light, scene.bounds(), ShadowMapSize::square(64))
            .and_then(|p| p.solve(&Parameterization::Focused))
            .unwrap();
        let caster = RayCaster::new(&scene);
        let truth = caster.trace_masks(&cam, &[light], 64, 64);
        let coverage = Coverage::trace(&caster, &cam, &light, &truth);
        let renderer = Renderer::new(device, queue, &scene, experiment_renderer_options()).unwrap();
        Self { cam, matrix, truth, coverage, renderer }
    }

    /// Renders one antialiased frame: the masks, occlusion and validity words.
    fn render(&mut self) -> (lixel::mesh::ShadowMasks, Vec<u32>, Vec<u32>) {
        let lights = [self.matrix];
        let frame = Frame { masks: true, lookup: AA32, ..Frame::new(&self.cam, &lights) };
        self.renderer.render(&frame).unwrap();
        let r = &self.renderer;
        (r.read_masks().unwrap(), r.read_occlusion(0).unwrap(), r.read_validity(0).unwrap())
    }

    /// The mean visibility error of the words.
    fn error(&self, occlusion: &[u32], valid: &[u32]) -> f64 {
        VisibilityError::of_valid_occlusion(occlusion, valid, &self.truth, &self.coverage, AaSamples::X32)
            .mean()
            .unwrap()
    }
}

/// The validity mask (Pan et al.'s Figure 7): a tetrahedron standing on the
/// floor (its first light). Along the crease where the tetrahedron meets the
/// floor, a floor pixel's facet runs on under the tetrahedron, whose faces
/// shadow those facet points although the camera sees the tetrahedron's lit
/// face there. Without the mask the antialiased lookup's error exceeded the
/// standard lookup's (measured 0.0039 against 0.0032); with it, samples a
/// listed triangle hides from the camera are left out of the ratio
/// (measured 0.0012). The occlusion words are the same either way.
#[test]
fn validity_mask_keeps_crease_pixels_from_self_shadowing() {
    let Some((device, queue)) = gpu() else { return };
    let mut tet = Tetrahedron::new(&device, &queue, 0);
    tet.renderer.set_aa_validity(false).unwrap();
    let (_, unmasked, all_valid) = tet.render();
    assert!(all_valid.iter().all(|&v| v == u32::MAX), "validity off: every sample valid");
    tet.renderer.set_aa_validity(true).unwrap();
    let (masks, occlusion, valid) = tet.render();
    assert_eq!(occlusion, unmasked, "the mask changes no occlusion word");
    let hidden: u32 = valid.iter().map(|v| (!v).count_ones()).sum();
    let e_std = VisibilityError::of_masks(&masks, &tet.truth, &tet.coverage, AaSamples::X32).mean().unwrap();
    let e_all = tet.error(&occlusion, &all_valid);
    let e_aa = tet.error(&occlusion, &valid);
    eprintln!("standard {e_std:.4}, aa32 without the mask {e_all:.4}, with it {e_aa:.4}; {hidden} hidden samples");
    assert!(hidden > 50, "{hidden} hidden samples");
    assert!(e_aa < 0.5 * e_std, "aa32 {e_aa} against standard {e_std}");
    assert!(e_aa < 0.5 * e_all, "aa32 {e_aa} against {e_all} without the mask");
}

/// The hidden test's screen-box gate skips only triangles that cannot hide
/// a sample: the occlusion and validity words are the same with it and
/// without it, on the tetrahedron's crease (where hundreds of samples are
/// hidden) and on the tiny scene for both test lights.
#[test]
fn hidden_gate_keeps_the_words() {
    let Some((device, queue)) = gpu() else { return };
    let mut tet = Tetrahedron::new(&device, &queue, 0);
    tet.renderer.set_aa_hidden_gate(false).unwrap();
    let (_, occlusion, valid) = tet.render();
    tet.renderer.set_aa_hidden_gate(true).unwrap();
    let (_, gated_occlusion, gated_valid) = tet.render();
    let hidden: u32 = valid.iter().map(|v| (!v).count_ones()).sum();
    assert!(hidden > 50, "{hidden} hidden samples");
    assert_eq!(gated_occlusion, occlusion);
    assert_eq!(gated_valid, valid);
    let scene = tiny_scene();
    let cam = camera(96);
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    for light in test_lights() {
        let m = matrices(&scene, &cam, &[light], 256, &Parameterization::Focused)[0];
        let frame = Frame { lookup: AA32, ..Frame::new(&cam, std::slice::from_ref(&m)) };
        let mut words = Vec::new();
        for gate in [false, true] {
            renderer.set_aa_hidden_gate(gate).unwrap();
            renderer.render(&frame).unwrap();
            words.push((renderer.read_occlusion(0).unwrap(), renderer.read_validity(0).unwrap()));
        }
        let hidden: u32 = words[0].1.iter().map(|v| (!v).count_ones()).sum();
        assert!(hidden > 0, "{light:?}: no hidden sample");
        assert!(words[0] == words[1], "{light:?}: the gate changed a word");
    }
}

/// Pixels whose depth compare is uncertain take the exact path: on the
/// tetrahedron's third light, faces that the smooth normals turn towards
/// the light while they look away from it are shadowed in the truth, and
/// the bias lights them, with no silhouette texel in their footprints.
/// Measured: mean error 0.0053 with only silhouette pixels exact, 0.0031
/// with the uncertain ones too (76 pixels).
#[test]
fn uncertain_pixels_take_the_exact_path() {
    let Some((device, queue)) = gpu() else { return };
    let mut tet = Tetrahedron::new(&device, &queue, 2);
    tet.renderer.set_aa_uncertain_pixels(false).unwrap();
    let (_, occlusion, valid) = tet.render();
    let e_off = tet.error(&occlusion, &valid);
    assert_eq!(tet.renderer.read_aa_stats(0).unwrap().uncertain_pixels, 0);
    tet.renderer.set_aa_uncertain_pixels(true).unwrap();
    let (_, occlusion, valid) = tet.render();
    let e_on = tet.error(&occlusion, &valid);
    let stats = tet.renderer.read_aa_stats(0).unwrap();
    eprintln!("only silhouette pixels exact {e_off:.4}, uncertain ones too {e_on:.4}; {stats:?}");
    assert!(stats.uncertain_pixels > 0, "{stats:?}");
    assert!(e_on < 0.75 * e_off, "{e_on} against {e_off}");
}

/// A surface grazing the light is not uncertain by itself: a directional
/// light 2.7° above the floor, no caster near most of the floor. Session
/// 7's rule took every facing pixel within 5° of grazing, which sent the
/// whole floor to the exact path (about 100 000 pixels on each of the
/// default preset's four lights 1°–5° above the horizon) for words that
/// scored exactly as those of the bias-band test alone. Now only pixels
/// whose map depth lies in the band are uncertain: under 5% of the pixels
/// facing the light.
#[test]
fn a_grazing_floor_is_not_uncertain_by_itself() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let cam = camera(96);
    let light = lixel::Light::directional(glam::DVec3::new(1.0, -0.05, 0.3));
    let m = matrices(&scene, &cam, &[light], 256, &Parameterization::Focused)[0];
    let options = lixel::experiment::experiment_renderer_options();
    let mut renderer = Renderer::new(&device, &queue, &scene, options).unwrap();
    renderer.render(&Frame { masks: true, lookup: AA32, ..Frame::new(&cam, &[m]) }).unwrap();
    let masks = renderer.read_masks().unwrap();
    let facing = masks.facing.iter().filter(|&&f| f & 1 != 0).count() as u32;
    let stats = renderer.read_aa_stats(0).unwrap();
    eprintln!("{facing} pixels facing the light; {stats:?}");
    assert!(facing > 2000, "{facing} pixels facing the light");
    assert!(stats.uncertain_pixels * 20 < facing, "{stats:?} of {facing} facing pixels");
}

/// llvmpipe and lavapipe end every loop of a shader invocation once 65 535
/// loop iterations have run in it, all loops together (gallivm's loop
/// limiter): the exact path's nested scan of a footprint's lists, one
/// iteration per entry, silently skipped the rest of a long scan (the paper
/// preset's wide footprints with 4x4 lists, issue-18 note, session 12).
/// Here 70 000 tiny triangles lie under the floor on the sun's ray through
/// a shadow-edge pixel's floor point: they occlude nothing the camera sees
/// and their list tile holds more entries than the limit. Every pixel the
/// exact path served without them keeps its word, or keeps the standard bit
/// and is counted as wide (a scan that cannot finish); the old scan changed
/// words uncounted.
#[test]
fn a_list_longer_than_the_loop_limit_keeps_the_words() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let cam = camera(96);
    let light = test_lights()[0];
    let m = matrices(&scene, &cam, &[light], 256, &Parameterization::Focused);
    let frame = Frame { lookup: AA32, ..Frame::new(&cam, &m) };
    let m = m[0];
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    renderer.render(&frame).unwrap();
    let plain = renderer.read_occlusion(0).unwrap();
    let plain_stats = renderer.read_aa_stats(0).unwrap();
    drop(renderer);
    let floor_y = scene
        .objects
        .iter()
        .filter(|o| o.role == Role::Receiver)
        .flat_map(|o| o.mesh.positions.iter())
        .map(|p| f64::from(p.y))
        .fold(f64::INFINITY, f64::min);
    // The lowest partial pixel on the screen whose centre's ray meets the floor.
    let world_from_screen = cam.screen_from_world().inverse();
    let floor_point = (0..plain.len())
        .rev()
        .filter(|&i| plain[i] != 0 && plain[i] != u32::MAX)
        .find_map(|i| {
            let (x, y) = ((i % 96) as f64 + 0.5, (i / 96) as f64 + 0.5);
            let a = world_from_screen.project_point3(DVec3::new(x, y, 0.0));
            let b = world_from_screen.project_point3(DVec3::new(x, y, 1.0));
            let t = (floor_y - a.y) / (b.y - a.y);
            (t > 0.0 && t < 1.0).then(|| a + (b - a) * t)
        })
        .expect("a partial floor pixel");
    let Light::Directional { direction } = light else { panic!("the sun") };
    let d = direction.normalize();
    let centre = floor_point + d * 0.5;
    let (u, v) = (d.any_orthonormal_pair().0, d.any_orthonormal_pair().1);
    let texel = |p: DVec3| texel_of(&m, p.as_vec3()).unwrap();
    // World units per texel across the ray.
    let per_texel = 1e-3 / (texel(centre + u * 1e-3) - texel(centre)).length();
    let mut filler = Mesh::default();
    let mut seed = 12345u64;
    let mut next = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    const FILLER: usize = 70_000;
    for _ in 0..FILLER {
        let c = centre + (u * next() + v * next()) * 0.6 * per_texel + d * next() * 0.1;
        let base = filler.positions.len() as u32;
        for corner in [DVec3::ZERO, u * 0.2 * per_texel, v * 0.2 * per_texel] {
            filler.positions.push((c + corner).as_vec3());
            filler.normals.push((-d).as_vec3());
        }
        filler.indices.extend([base, base + 1, base + 2]);
    }
    let mut objects =
        vec![SceneObject { name: "filler".into(), mesh: filler, role: Role::Receiver, albedo: Vec3::splat(0.5) }];
    objects.extend(scene.objects.iter().cloned());
    let filled = Scene { objects };
    let mut renderer = Renderer::new(&device, &queue, &filled, RendererOptions::default()).unwrap();
    renderer.render(&frame).unwrap();
    let words = renderer.read_occlusion(0).unwrap();
    let stats = renderer.read_aa_stats(0).unwrap();
    let served = plain.iter().filter(|&&w| w != 0 && w != u32::MAX).count();
    let differ = (0..plain.len()).filter(|&i| plain[i] != 0 && plain[i] != u32::MAX && words[i] != plain[i]).count();
    eprintln!("{served} partial pixels, {differ} words differ; plain {plain_stats:?}; filled {stats:?}");
    assert_eq!(stats.overflow_pixels, 0, "{stats:?}");
    assert!(
        differ as u32 <= stats.wide_pixels.saturating_sub(plain_stats.wide_pixels),
        "{differ} of {served} served words changed, wide {} -> {}",
        plain_stats.wide_pixels,
        stats.wide_pixels
    );
    // The filler's list was read: more entries than the loop limit.
    assert!(stats.entries_scanned >= plain_stats.entries_scanned + 65_535, "{stats:?}");
}

/// A triangle whose box spans more than 240 tiles of 8 texels along a side
/// (here one under the floor, across the whole 2048² map) would take
/// `enter_lists` past the CPU backends' loop limit (65 535 iterations per
/// invocation), which cut it silently on main: the light is refused
/// instead, every pixel keeping the standard bit and counted as overflowed.
/// Issue-18 note, session 12 (hloop).
#[test]
fn a_triangle_over_too_many_tiles_refuses_the_light() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let cam = camera(48);
    let light = test_lights()[0];
    let frame_m = matrices(&scene, &cam, &[light], 2048, &Parameterization::Focused);
    let Light::Directional { direction } = light else { panic!("the sun") };
    let d = direction.normalize();
    let (u, v) = d.any_orthonormal_pair();
    let centre = scene.bounds().receivers.center() + d * 50.0;
    let mut big = Mesh::default();
    for corner in [u * -1e3 + v * -1e3, u * 3e3 + v * -1e3, u * -1e3 + v * 3e3] {
        big.positions.push((centre + corner).as_vec3());
        big.normals.push((-d).as_vec3());
    }
    big.indices.extend([0, 1, 2]);
    let mut objects =
        vec![SceneObject { name: "big".into(), mesh: big, role: Role::Receiver, albedo: Vec3::splat(0.5) }];
    objects.extend(scene.objects.iter().cloned());
    let with_big = Scene { objects };
    let mut renderer = Renderer::new(&device, &queue, &with_big, RendererOptions::default()).unwrap();
    renderer.render(&Frame { masks: true, lookup: AA32, ..Frame::new(&cam, &frame_m) }).unwrap();
    let words = renderer.read_occlusion(0).unwrap();
    let stats = renderer.read_aa_stats(0).unwrap();
    let masks = renderer.read_masks().unwrap();
    eprintln!("{stats:?}");
    assert!(stats.overflow_pixels > 0 && stats.exact_pixels == 0, "{stats:?}");
    for (i, (&word, &shadow)) in words.iter().zip(&masks.shadow).enumerate() {
        let standard = if shadow & 1 != 0 { u32::MAX } else { 0 };
        assert_eq!(word, standard, "pixel {i} keeps the standard bit");
    }
}
