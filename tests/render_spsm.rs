//! Sub-pixel shadow maps: the shader's conservative rasterization against a
//! CPU reference, the texel packing, SPSM bits against ray casting, and thin
//! casters a standard map loses.

#![cfg(feature = "render")]

mod render_common;

use glam::{DVec2, DVec3, UVec2, Vec3};
use lixel::mesh::{Mesh, RayCaster, Role, Scene, SceneObject};
use lixel::render::sgsm::overlap::Projected;
use lixel::render::spsm::packing;
use lixel::render::{Frame, Renderer, RendererOptions, ShadowLookup, SpsmOptions, StandardFallback};

const SPSM: ShadowLookup = ShadowLookup::Spsm(SpsmOptions::PAPER);
const SPSM_THIN: ShadowLookup = ShadowLookup::Spsm(SpsmOptions::THIN_CASTERS);
use lixel::{Camera, Light, LightMatrix, Parameterization};
use render_common::*;

fn object(name: &str, mesh: Mesh, role: Role) -> SceneObject {
    SceneObject { name: name.into(), mesh, role, albedo: Vec3::splat(0.8) }
}

/// Flat triangles (normals up), one object.
fn triangles(tris: &[[Vec3; 3]]) -> Mesh {
    let mut mesh = Mesh::default();
    for t in tris {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend_from_slice(t);
        mesh.normals.extend([Vec3::Y; 3]);
        mesh.indices.extend([base, base + 1, base + 2]);
    }
    mesh
}

/// Texel coordinates (x right, y down) of a world point.
fn texel_of(m: &LightMatrix, p: Vec3) -> DVec2 {
    let t = m.texel_from_world() * p.as_dvec3().extend(1.0);
    DVec2::new(t.x / t.w, t.y / t.w)
}

/// Every texel a thin or sliver triangle touches gets a fragment, and no
/// texel it does not touch (up to 1e-3 texel), for a directional and a
/// point light; the stored triangles and depths decode to the CPU's within
/// the packing's precision, and the depth buffer holds the CPU's consistent
/// minimum depth (the plane's minimum over the covered part of the texel).
#[test]
fn conservative_coverage_matches_the_cpu_reference() {
    let Some((device, queue)) = gpu() else { return };
    // Separate thin shapes on a 10 x 10 area, well apart from each other.
    let y = 0.5;
    let shapes = [
        // Needle along x, 0.002 wide.
        [Vec3::new(-4.5, y, -4.0), Vec3::new(4.5, y, -4.0), Vec3::new(4.5, y, -4.002)],
        // Diagonal sliver.
        [Vec3::new(-4.0, y, -3.0), Vec3::new(-1.0, y, 0.0), Vec3::new(-0.99, y, -0.0)],
        // Tiny triangle inside one texel.
        [Vec3::new(2.01, y, 1.01), Vec3::new(2.02, y, 1.01), Vec3::new(2.01, y, 1.02)],
        // Long thin, slightly tilted in depth.
        [Vec3::new(0.5, 0.2, 4.0), Vec3::new(4.2, 0.9, 0.5), Vec3::new(4.21, 0.9, 0.52)],
        // An ordinary triangle.
        [Vec3::new(-4.0, y, 2.0), Vec3::new(-2.0, y, 4.0), Vec3::new(-1.0, y, 1.5)],
    ];
    let floor = triangles(&[[Vec3::new(-5.0, 0.0, 5.0), Vec3::new(5.0, 0.0, 5.0), Vec3::new(5.0, 0.0, -5.0)]]);
    let scene = Scene {
        objects: vec![
            object("shapes", triangles(&shapes), Role::CasterAndReceiver),
            object("floor", floor, Role::Receiver),
        ],
    };
    let camera = Camera::look_at(DVec3::new(0.0, 12.0, 12.0), DVec3::ZERO, DVec3::Y, 1.0, UVec2::splat(64), 0.5, 100.0)
        .expect("camera");
    let lights = [Light::directional(DVec3::new(0.2, -1.0, 0.1)), Light::point(DVec3::new(1.0, 15.0, -2.0))];
    let all = matrices(&scene, &camera, &lights, 48, &Parameterization::Normal);
    // One renderer and frame for both lights (each new renderer compiles the SPSM shaders again).
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    renderer.render(&Frame { lookup: SPSM, ..Frame::new(&camera, &all) }).unwrap();
    for (index, (light, m)) in lights.iter().zip(&all).enumerate() {
        let m = *m;
        let texels = renderer.read_map_words(index).unwrap().expect("spsm words");
        // The depth buffer: the consistent minimum depth, squeezed (spsm_depth_key).
        let keys = renderer.read_shadow_map(index).unwrap().depth;
        let mut max_min_depth_error = 0.0f64;
        let (w, h) = (m.map_size.width as i64, m.map_size.height as i64);
        // The shapes in texel space with their post-projective depths (the
        // CPU reference of the plane and of its consistent minimum depth).
        let planes: Vec<Projected> = shapes.iter().map(|t| projected(&m, t)).collect();
        let projected: Vec<[DVec2; 3]> = planes.iter().map(|p| p.vertices).collect();
        let (mut checked, mut max_vertex_error, mut max_depth_error) = (0, 0.0f64, 0.0f64);
        // The decoded gradient against the CPU plane's, relative to the code's bound.
        let mut worst_gradient = 0.0f64;
        for y in 0..h {
            for x in 0..w {
                let words = texels[(y * w + x) as usize];
                // The floor lies under everything but is clipped to the shapes' test below.
                let surely = projected.iter().any(|t| packing::texel_touches(*t, [x, y], -1e-3));
                let maybe = projected.iter().any(|t| packing::texel_touches(*t, [x, y], 1e-3));
                let decoded = packing::unpack(
                    words,
                    [x as u32, y as u32],
                    [w as u32, h as u32],
                    SpsmOptions::PAPER.gradient_code,
                );
                // The stored vertices in the shape's order (the pass may
                // permute them: the order marks a parallelogram partner).
                let in_order = |t: &[DVec2; 3], v: [DVec2; 3]| {
                    let error = |v: &[DVec2; 3]| t.iter().zip(v).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
                    [[0, 1, 2], [1, 2, 0], [2, 0, 1], [0, 2, 1], [2, 1, 0], [1, 0, 2]]
                        .map(|p| p.map(|i| v[i]))
                        .into_iter()
                        .min_by(|a, b| error(a).total_cmp(&error(b)))
                        .filter(|v| error(v) < 0.05)
                };
                let stored_shape = decoded.and_then(|d| {
                    projected.iter().enumerate().find_map(|(k, t)| in_order(t, d.vertices).map(|v| (k, v)))
                });
                if surely {
                    checked += 1;
                    let (k, vertices) =
                        stored_shape.unwrap_or_else(|| panic!("texel ({x}, {y}) touched but holds {decoded:?}"));
                    let d = decoded.unwrap();
                    for (a, b) in projected[k].iter().zip(vertices) {
                        max_vertex_error = max_vertex_error.max((*a - b).length());
                    }
                    // Depth at the texel centre on the shape's plane, from the CPU.
                    let c = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                    let plane = planes[k].depth_at(c);
                    max_depth_error = max_depth_error.max((plane - d.depth).abs());
                    // The consistent minimum depth: the plane's minimum over the
                    // part of the texel the triangle covers (paper, section 4).
                    if let Some(cpu) = planes[k].min_depth_in([x, y]) {
                        let u = 2.0 * f64::from(keys[(y * w + x) as usize]) - 1.0;
                        let gpu = u / (1.0 - u.abs());
                        max_min_depth_error = max_min_depth_error.max((gpu - cpu).abs());
                    }
                    let g =
                        DVec2::new(planes[k].depth_at(c + DVec2::X) - plane, planes[k].depth_at(c + DVec2::Y) - plane);
                    let bound = packing::gradient_error(
                        words[3] & 0xffff,
                        [w as u32, h as u32],
                        SpsmOptions::PAPER.gradient_code,
                    );
                    // f32 arithmetic in the pass: 1e-6 of slack.
                    let excess = ((d.gradient - g).abs() / (bound + 1e-6)).max_element();
                    worst_gradient = worst_gradient.max(excess);
                } else if !maybe {
                    assert!(stored_shape.is_none(), "texel ({x}, {y}) not touched but holds shape {stored_shape:?}");
                }
            }
        }
        eprintln!("{light:?}: {checked} touched texels; vertex error {max_vertex_error:.2e} texel, depth error {max_depth_error:.2e}, gradient error {worst_gradient:.2} of the code's bound, minimum depth error {max_min_depth_error:.2e}");
        assert!(max_min_depth_error < 2e-5, "consistent minimum depth against the CPU: {max_min_depth_error}");
        assert!(worst_gradient <= 1.0, "the decoded gradient lies within the code's bound: {worst_gradient}");
        assert!(checked > 60, "the shapes touch texels: {checked}");
        assert!(max_vertex_error < 0.02, "f16 vertex offsets: {max_vertex_error}");
        assert!(max_depth_error < 2e-5, "16-bit depth at the centre: {max_depth_error}");
    }
}

/// `tri` in `m`'s texel space, with the post-projective depth at each vertex.
fn projected(m: &LightMatrix, tri: &[Vec3; 3]) -> Projected {
    let zeta = |v: Vec3| {
        let p = v.as_dvec3().extend(1.0);
        (m.clip_from_world * p).z / (m.texel_from_world() * p).w
    };
    Projected { vertices: tri.map(|v| texel_of(m, v)), zeta: tri.map(zeta) }
}

/// Packing round trips for every code, and each derivative code's worst
/// relative error over slopes that matter (reported; slopes per map extent
/// along x, a 400² map). The log-polar code (the default) stays within 5%
/// from 1e-4 to 1e3 per extent; the paper's power code (exponent 5) is
/// finer on steep slopes and has a dead zone below ~0.55 (error 100%).
#[test]
fn slope_codes_round_trip() {
    let map = [400u32, 400];
    for exponent in [1.0, 3.0, 5.0] {
        for q in 0..=254u32 {
            let d = packing::decode_slope(f64::from(q), exponent);
            assert_eq!(packing::encode_slope(d, exponent), q, "code {q}, exponent {exponent}");
        }
    }
    let codes = [
        packing::GradientCode::Power { exponent: 1.0 },
        packing::GradientCode::Power { exponent: 5.0 },
        packing::GradientCode::LogPolar,
    ];
    for code in codes {
        let worst = |lo: f64, hi: f64| {
            (0..=1000)
                .map(|k| lo * (hi / lo).powf(f64::from(k) / 1000.0))
                .map(|d| {
                    let g = glam::DVec2::new(d / 400.0, 0.0);
                    let back = packing::decode_gradient(packing::encode_gradient(g, map, code), map, code);
                    (back - g).length() / g.length()
                })
                .fold(0.0, f64::max)
        };
        let ranges = [(1e-4, 1e-2), (1e-2, 0.4), (0.4, 1.0), (1.0, 10.0), (10.0, 100.0), (100.0, 1000.0)];
        let errors: Vec<String> = ranges.iter().map(|&(lo, hi)| format!("[{lo}, {hi}] {:.3}", worst(lo, hi))).collect();
        eprintln!("{code:?}: worst relative gradient error {}", errors.join(", "));
        if code == packing::GradientCode::LogPolar {
            assert!(ranges.iter().all(|&(lo, hi)| worst(lo, hi) <= 0.05), "{errors:?}");
        }
    }
}

/// SPSM shadow bits agree with the ray cast away from boundaries (99%), and
/// misclassify fewer pixels overall than the standard map, on the tiny
/// scene with a coarse 256² map; the hybrid lookup (the default) is no
/// worse than either of its parts: the standard map and SPSM without the
/// fallback.
#[test]
fn spsm_bits_agree_with_ray_cast() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let camera = walkthrough_camera(160);
    let lights = test_lights();
    let truth = RayCaster::new(&scene).trace_masks(&camera, &lights, 160, 160);
    let matrices = matrices(&scene, &camera, &lights, 256, &Parameterization::Focused);
    let mut counts = Vec::new();
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    for lookup in [ShadowLookup::DepthCompare, SPSM, ShadowLookup::Spsm(SpsmOptions::SUBPIXEL_ONLY)] {
        renderer.render(&Frame { masks: true, lookup, ..Frame::new(&camera, &matrices) }).unwrap();
        let gpu = renderer.read_masks().unwrap();
        let mut total = 0;
        for light in 0..lights.len() as u32 {
            let agreement = truth.agreement_away_from_boundaries(&gpu, light, 1);
            eprintln!("{} light {light}: {agreement:?}", lookup.name());
            assert!(agreement.fraction() >= 0.99, "{} light {light}: {agreement:?}", lookup.name());
            total += gpu.misclassified(&truth, light).unwrap();
        }
        counts.push(total);
    }
    eprintln!("misclassified: standard {}, spsm {}, spsm without fallback {}", counts[0], counts[1], counts[2]);
    // Measured (lavapipe and GL, session 6: the log-polar gradient code): standard 439, SPSM 233,
    // without the fallback 243 (session 5: 244 and 254).
    assert!(counts[1] < counts[0], "SPSM lowers the error: {counts:?}");
    assert!(counts[1] <= counts[2], "the fallback does not add error: {counts:?}");
}

/// A matrix whose post-projective depth squeezes the scene into a narrow
/// band (as the scene-optimized warps do: default preset, configuration 5,
/// `zeta` in [0.91, 0.96]) keeps SPSM's shadows: the stored planes' depth
/// gradients are small there, and the derivative code must not flatten
/// them (issue 16, session 6: the paper's power code, exponent 5, decoded
/// every slope below ~0.55 per map extent as zero, with a tolerance larger
/// than the caster-receiver gaps; `optimized+spsm` lost whole shadow
/// interiors, 6271 misclassified pixels against the standard lookup's 586).
/// The squeeze is an affine map of `zeta` (`z' = s z + (1 - s) w / 2`),
/// which leaves every depth order, and so the truth, unchanged.
#[test]
fn squeezed_depth_keeps_the_shadows() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let camera = walkthrough_camera(160);
    let lights = test_lights();
    let truth = RayCaster::new(&scene).trace_masks(&camera, &lights, 160, 160);
    let plain = matrices(&scene, &camera, &lights, 256, &Parameterization::Focused);
    let squeeze = 0.005;
    let squeezed: Vec<LightMatrix> = plain
        .iter()
        .map(|m| {
            let mut rows = [
                m.clip_from_world.row(0),
                m.clip_from_world.row(1),
                m.clip_from_world.row(2),
                m.clip_from_world.row(3),
            ];
            rows[2] = rows[2] * squeeze + rows[3] * (0.5 * (1.0 - squeeze));
            LightMatrix {
                clip_from_world: glam::DMat4::from_cols(rows[0], rows[1], rows[2], rows[3]).transpose(),
                ..*m
            }
        })
        .collect();
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    let mut count = |matrices: &[LightMatrix], options: SpsmOptions| {
        let lookup = ShadowLookup::Spsm(options);
        renderer.render(&Frame { masks: true, lookup, ..Frame::new(&camera, matrices) }).unwrap();
        let gpu = renderer.read_masks().unwrap();
        (0..lights.len() as u32).map(|light| gpu.misclassified(&truth, light).unwrap()).sum::<u64>()
    };
    let power =
        SpsmOptions { gradient_code: packing::GradientCode::Power { exponent: 5.0 }, ..SpsmOptions::SUBPIXEL_ONLY };
    let counts = [
        count(&plain, SpsmOptions::SUBPIXEL_ONLY),
        count(&squeezed, SpsmOptions::SUBPIXEL_ONLY),
        count(&plain, power),
        count(&squeezed, power),
    ];
    eprintln!(
        "misclassified (SPSM without the fallback), plain / squeezed depth: log-polar code {} / {}, the paper's power code {} / {}",
        counts[0], counts[1], counts[2], counts[3]
    );
    assert!(counts[1] <= counts[0] + counts[0] / 4 + 10, "the squeeze keeps the shadows: {counts:?}");
}

/// SPSM's centre-sampled depths are a standard map: the lookup with the
/// standard verdict everywhere ([`StandardFallback::Always`]) gives the
/// standard lookup's bits but at a handful of pixels (the rasterizer's
/// tie rule for centres on an edge, the slope bias from the plane rather
/// than from `dpdx`/`dpdy`). Measured (lavapipe and GL): 4 of 20788.
#[test]
fn centre_depths_reproduce_the_standard_lookup() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let camera = walkthrough_camera(160);
    let lights = test_lights();
    let matrices = matrices(&scene, &camera, &lights, 256, &Parameterization::Focused);
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    let always = SpsmOptions { standard_fallback: StandardFallback::Always, ..SpsmOptions::PAPER };
    let mut masks = Vec::new();
    for lookup in [ShadowLookup::DepthCompare, ShadowLookup::Spsm(always)] {
        renderer.render(&Frame { masks: true, lookup, ..Frame::new(&camera, &matrices) }).unwrap();
        masks.push(renderer.read_masks().unwrap());
    }
    let (standard, centre) = (&masks[0], &masks[1]);
    let visible = (0..standard.depth.len()).filter(|&i| standard.visible(i)).count();
    let shadowed = (0..standard.depth.len()).filter(|&i| standard.visible(i) && standard.shadow[i] != 0).count();
    let differ =
        (0..standard.depth.len()).filter(|&i| standard.visible(i) && standard.shadow[i] != centre.shadow[i]).count();
    eprintln!("visible {visible}, standard shadowed {shadowed}, centre depths differ at {differ}");
    assert!(shadowed > 1000, "the scene has shadows: {shadowed}");
    assert!(differ * 1000 <= visible, "centre-sampled depths against the standard map: {differ} of {visible}");
}

/// A thin pole and a wire fence (0.2-0.3 texel wide in a 256² map): SPSM
/// with [`SpsmOptions::THIN_CASTERS`] keeps nearly all of their shadow
/// pixels, more than the standard map.
///
/// Measured on lavapipe (issue 16 note): of 279 ray-cast shadow pixels the
/// standard map finds 183 (4 false shadow), SPSM with the thin-caster rules
/// 277 (120 false shadow: the recovery widens a wire's shadow inside the
/// texels it crosses), SPSM with the paper's defaults 82 (0). The issue's
/// premise, a standard map losing them entirely, does not hold at this
/// thickness, so the test asks for what SPSM does: keep them.
#[test]
fn thin_casters_keep_their_shadows() {
    let Some((device, queue)) = gpu() else { return };
    let mut casters = Mesh::default();
    // A pole 0.03 wide and 4 high, and a fence of wires 0.02 thick.
    let pole = lixel::mesh::primitives::cuboid(Vec3::new(0.015, 2.0, 0.015), 12);
    casters.append(&pole.transformed(&glam::Affine3A::from_translation(Vec3::new(-3.0, 2.0, 0.0))));
    for k in 0..4 {
        let wire = lixel::mesh::primitives::cuboid(Vec3::new(4.0, 0.01, 0.01), 12);
        casters.append(&wire.transformed(&glam::Affine3A::from_translation(Vec3::new(2.0, 0.8 + 0.6 * k as f32, 0.0))));
    }
    let floor = lixel::mesh::primitives::floor(24.0, 2);
    let scene = Scene {
        objects: vec![object("casters", casters, Role::CasterAndReceiver), object("floor", floor, Role::Receiver)],
    };
    let camera = Camera::look_at(
        DVec3::new(0.0, 9.0, 12.0),
        DVec3::new(0.0, 0.0, -2.0),
        DVec3::Y,
        1.0,
        UVec2::splat(200),
        0.5,
        100.0,
    )
    .expect("camera");
    let lights = [Light::directional(DVec3::new(0.3, -1.0, -0.8))];
    let truth = RayCaster::new(&scene).trace_masks(&camera, &lights, 200, 200);
    let floor_shadow = |masks: &lixel::mesh::ShadowMasks| {
        (0..truth.depth.len())
            .filter(|&i| truth.visible(i) && truth.shadow[i] & 1 == 1 && masks.shadow[i] & 1 == 1)
            .count()
    };
    let expected = floor_shadow(&truth);
    assert!(expected > 200, "the ray cast sees the thin shadows: {expected}");
    let m = matrices(&scene, &camera, &lights, 256, &Parameterization::Normal);
    let mut found = Vec::new();
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    for lookup in [ShadowLookup::DepthCompare, SPSM_THIN, SPSM] {
        renderer.render(&Frame { masks: true, lookup, ..Frame::new(&camera, &m) }).unwrap();
        let masks = renderer.read_masks().unwrap();
        let false_shadow = (0..truth.depth.len())
            .filter(|&i| truth.visible(i) && truth.shadow[i] & 1 == 0 && masks.shadow[i] & 1 == 1)
            .count();
        found.push((floor_shadow(&masks), false_shadow));
    }
    eprintln!(
        "true shadow pixels {expected}; (found, false) standard {:?}, spsm thin casters {:?}, spsm paper {:?}",
        found[0], found[1], found[2]
    );
    assert!(found[1].0 * 10 >= expected * 9, "SPSM keeps at least 90%: {found:?}");
    assert!(found[1].0 > found[0].0, "more than the standard map: {found:?}");
    assert!(found[1].1 * 2 < expected, "false shadow below half the true shadow: {found:?}");
}

/// A finely tessellated cylinder lying above a floor keeps its shadow edges
/// with [`SpsmOptions::inner_edges`] (issue 16, session 7; on by default
/// since session 9). Its facets are narrower than a texel, so the
/// conservative pass keeps, in the texels along the shadow's edges, the
/// facets nearest the light and loses the thin outer ones that shade the
/// floor there; without the pass's inner-edge codes the lookup calls many of
/// those floor pixels lit. Counts the shadowed pixels each lookup calls lit
/// and the lit ones it calls shadowed, against the ray-cast truth; and
/// checks the compact texels that carry the codes decode on the CPU
/// (`packing::unpack`) to a triangle touching their texel.
#[test]
fn tessellated_cylinder_keeps_its_shadow_edges() {
    let Some((device, queue)) = gpu() else { return };
    let lying = glam::Affine3A::from_translation(Vec3::new(0.0, 1.2, 0.0))
        * glam::Affine3A::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let cylinder = lixel::mesh::primitives::cylinder(0.6, 2.5, 20_000).transformed(&lying);
    let scene = Scene {
        objects: vec![
            object("cylinder", cylinder, Role::CasterAndReceiver),
            object("floor", lixel::mesh::primitives::floor(10.0, 2), Role::Receiver),
        ],
    };
    let camera = Camera::look_at(
        DVec3::new(0.0, 7.0, 6.0),
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::Y,
        0.9,
        UVec2::splat(200),
        0.5,
        100.0,
    )
    .expect("camera");
    let lights = [Light::directional(DVec3::new(0.2, -1.0, -0.35))];
    let truth = RayCaster::new(&scene).trace_masks(&camera, &lights, 200, 200);
    let m = matrices(&scene, &camera, &lights, 128, &Parameterization::Focused);
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    let without = ShadowLookup::Spsm(SpsmOptions { inner_edges: false, ..SpsmOptions::PAPER });
    let mut errors = Vec::new();
    for lookup in [ShadowLookup::DepthCompare, without, SPSM] {
        renderer.render(&Frame { masks: true, lookup, ..Frame::new(&camera, &m) }).unwrap();
        let masks = renderer.read_masks().unwrap();
        if lookup == SPSM {
            let words = renderer.read_map_words(0).unwrap().expect("spsm words");
            let size = [m[0].map_size.width, m[0].map_size.height];
            let mut compact = 0;
            for (i, w) in words.iter().enumerate() {
                if w[3] & 0xffff == 0 || w[0] & packing::COMPACT_MARK != packing::COMPACT_MARK {
                    continue;
                }
                compact += 1;
                let texel = [i as u32 % size[0], i as u32 / size[0]];
                let codes = packing::compact_codes([w[0], w[1], w[2]]);
                assert!(codes != 0, "a compact texel has an inner edge: {w:?}");
                let d = packing::unpack(*w, texel, size, SpsmOptions::PAPER.gradient_code).expect("a triangle");
                let at = [i64::from(texel[0]), i64::from(texel[1])];
                assert!(packing::texel_touches(d.vertices, at, 0.01), "texel {texel:?} holds {d:?}");
            }
            eprintln!("compact texels {compact} of {}", words.len());
            assert!(compact > 100, "the cylinder's small facets are stored compact: {compact}");
        }
        let wrong = |truth_bit: u32| {
            (0..truth.depth.len())
                .filter(|&i| truth.visible(i) && truth.shadow[i] & 1 == truth_bit && masks.shadow[i] & 1 != truth_bit)
                .count()
        };
        errors.push((wrong(1), wrong(0)));
    }
    let shadowed = (0..truth.depth.len()).filter(|&i| truth.visible(i) && truth.shadow[i] & 1 == 1).count();
    eprintln!(
        "shadowed pixels {shadowed}; (false lit, false shadow) standard {:?}, spsm without inner edges {:?}, spsm {:?}",
        errors[0], errors[1], errors[2]
    );
    assert!(shadowed > 1000, "the cylinder casts a shadow: {shadowed}");
    // Measured (lavapipe): standard (120, 3), SPSM without inner edges (127, 0);
    // session 7's unbounded continuation (6, 50), session 9's bounded one (96, 0):
    // the facets here are so thin that the continuation, bounded by the
    // neighbour grown 3x, reaches only part of the way to the silhouette.
    assert!(errors[2].0 * 100 < errors[1].0 * 85, "inner edges cut the false light by 15%: {errors:?}");
    assert!(errors[2].1 * 100 < shadowed, "false shadow below 1% of the shadow: {errors:?}");
}

/// The acne report: SPSM's depth test uses the stored triangle's
/// plane with a constant bias of 1e-5 of the depth range
/// ([`SpsmOptions::bias`], no slope-scaled bias), so acne is false shadow on
/// surfaces the truth calls lit and facing the light. Counted on the tiny
/// scene (focused 256² maps, sun and point light) for the default lookup,
/// for the plane test with the constant bias alone (no packing tolerance),
/// and for the paper's lookup alone (no standard fallback) with the constant
/// bias alone; "interior" leaves out pixels within one pixel of a shadow
/// boundary or silhouette in the truth (edge error, not acne).
#[test]
fn acne_at_the_constant_bias() {
    let Some((device, queue)) = gpu() else { return };
    assert_eq!(SpsmOptions::PAPER.bias, 1e-5, "the issue's constant bias");
    let scene = tiny_scene();
    let camera = walkthrough_camera(160);
    let lights = test_lights();
    let truth = RayCaster::new(&scene).trace_masks(&camera, &lights, 160, 160);
    let matrices = matrices(&scene, &camera, &lights, 256, &Parameterization::Focused);
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    let bias_alone = SpsmOptions { packing_tolerance: false, ..SpsmOptions::PAPER };
    let paper_alone = SpsmOptions { packing_tolerance: false, ..SpsmOptions::SUBPIXEL_ONLY };
    let lookups = [
        ("standard (slope-scaled bias)", ShadowLookup::DepthCompare),
        ("spsm default", SPSM),
        ("spsm, constant bias alone", ShadowLookup::Spsm(bias_alone)),
        ("spsm without fallback, constant bias alone", ShadowLookup::Spsm(paper_alone)),
    ];
    let lit_facing = |light: u32| {
        (0..truth.depth.len())
            .filter(|&i| truth.visible(i) && truth.facing[i] >> light & 1 == 1 && truth.shadow[i] >> light & 1 == 0)
            .count()
    };
    let lit: usize = (0..lights.len() as u32).map(lit_facing).sum();
    let mut acne = Vec::new();
    for (name, lookup) in lookups {
        renderer.render(&Frame { masks: true, lookup, ..Frame::new(&camera, &matrices) }).unwrap();
        let gpu = renderer.read_masks().unwrap();
        let (mut all, mut interior, mut compared) = (0usize, 0usize, 0u64);
        for light in 0..lights.len() as u32 {
            all += (0..truth.depth.len())
                .filter(|&i| truth.visible(i) && truth.facing[i] >> light & 1 == 1)
                .filter(|&i| truth.shadow[i] >> light & 1 == 0 && gpu.shadow[i] >> light & 1 == 1)
                .count();
            let a = truth.agreement_away_from_boundaries(&gpu, light, 1);
            interior += a.false_shadow as usize;
            compared += a.compared;
        }
        eprintln!("{name}: false shadow on lit light-facing pixels {all} of {lit}, interior {interior} of {compared} compared");
        acne.push((all, interior));
    }
    // Measured (lavapipe and GL, session 13): standard 101 (interior 0),
    // SPSM default 5 (0), the constant bias alone 7381 (6298) and without the
    // fallback 7401 (6312) of 24979 lit light-facing pixels: at 1e-5 alone
    // the decoded planes' error (16-bit centre depth, 16-bit gradient code,
    // extrapolated up to a texel and more) exceeds the bias on about a third
    // of the lit surfaces; the packing tolerance (on by default) removes it.
    assert!(lit > 10_000, "the scene has lit light-facing pixels: {lit}");
    assert!(acne[1].1 * 1000 <= lit, "default SPSM: interior acne at most 0.1% of the lit pixels: {acne:?}");
    assert!(acne[1].0 <= acne[0].0, "default SPSM: no more false shadow on lit surfaces than standard: {acne:?}");
    assert!(acne[2].0 > acne[1].0, "the packing tolerance is what removes the acne: {acne:?}");
}

/// SPSM works with every light matrix and every light kind (issue 16: "usable
/// with every `LightMatrix`"): on the tiny scene with a sun, a point light and
/// a spot light, for the normal, focused, focused-snapped, PSM, LiSPSM and
/// plane-optimal maps and the scene optimizer settled by a `ShadowLoop` whose
/// analysis bits come from the SPSM lookup, SPSM's bits agree with the ray
/// cast away from boundaries (99%, or as well as the standard lookup where
/// that is lower: PSM), and with each matrix it misclassifies fewer pixels
/// than the standard lookup. Measured (lavapipe, session 13), standard /
/// SPSM: normal 874 / 528, focused 466 / 239, focused-snapped 664 / 418,
/// PSM 2849 / 2088, LiSPSM 501 / 287, plane-optimal 428 / 173, optimized
/// 404 / 186.
#[test]
fn spsm_works_with_every_matrix_and_light_kind() {
    use lixel::render::{LoopOptions, LoopPolicy, LoopView, ShadowLoop};
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let camera = walkthrough_camera(160);
    let lights = [
        Light::directional(DVec3::new(0.6, -1.0, 0.35)),
        Light::point(DVec3::new(-8.0, 30.0, 12.0)),
        Light::spot(DVec3::new(6.0, 25.0, 10.0), DVec3::new(-6.0, -25.0, -10.0), 35f64.to_radians()),
    ];
    let truth = RayCaster::new(&scene).trace_masks(&camera, &lights, 160, 160);
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    let mut sets: Vec<(String, Vec<LightMatrix>)> = Parameterization::ALL_DEFAULT
        .iter()
        .map(|p| (format!("{:?}", p.method()), matrices(&scene, &camera, &lights, 256, p)))
        .collect();
    let view =
        LoopView { camera: &camera, lights: &lights, bounds: scene.bounds(), map: lixel::ShadowMapSize::square(256) };
    let options = LoopOptions { lookup: SPSM, ..Default::default() };
    let settled =
        ShadowLoop::new(LoopPolicy::Optimized, lights.len(), options).unwrap().settle(&mut renderer, &view, 6).unwrap();
    sets.push(("Optimized (settled with SPSM)".into(), settled.matrices));
    let (mut standard_total, mut spsm_total) = (0, 0);
    for (name, m) in &sets {
        let (mut counts, mut agreements) = (Vec::new(), Vec::new());
        for lookup in [ShadowLookup::DepthCompare, SPSM] {
            renderer.render(&Frame { masks: true, lookup, ..Frame::new(&camera, m) }).unwrap();
            let gpu = renderer.read_masks().unwrap();
            let mut total = 0;
            for light in 0..lights.len() as u32 {
                agreements.push(truth.agreement_away_from_boundaries(&gpu, light, 1).fraction());
                total += gpu.misclassified(&truth, light).unwrap();
            }
            counts.push(total);
        }
        eprintln!("{name}: misclassified standard {}, spsm {}; agreement away from boundaries per light, standard then spsm {agreements:.4?}", counts[0], counts[1]);
        // PSM's own standard lookup agrees on only 96.4% (sun) here: SPSM
        // must reach 99% or the standard lookup's agreement.
        let (standard, spsm) = agreements.split_at(lights.len());
        for (light, (a, b)) in standard.iter().zip(spsm).enumerate() {
            assert!(*b >= a.min(0.99), "{name}, light {light}: spsm {b} against standard {a}");
        }
        assert!(counts[1] < counts[0], "{name}: SPSM lowers the error: {counts:?}");
        standard_total += counts[0];
        spsm_total += counts[1];
    }
    let spot_lit = (0..truth.depth.len()).filter(|&i| truth.visible(i) && truth.facing[i] >> 2 & 1 == 1).count();
    eprintln!("all matrices: standard {standard_total}, spsm {spsm_total}; spot light reaches {spot_lit} pixels");
    assert!(spot_lit > 1000, "the spot light reaches the view: {spot_lit}");
    assert!(spsm_total < standard_total, "SPSM lowers the error over every matrix: {spsm_total} vs {standard_total}");
}

/// The premise at the scale where it holds: a pole and a fence of
/// four wires 0.0015 thick (about 0.05 texel of a 256² normal map), seen
/// close up (a 4° camera looking down on their shadows, a screen pixel about
/// 0.03 texel), so the ray-cast shadows are a few pixels wide. A standard
/// map samples texel centres, which such casters almost never cover: it
/// loses them entirely. SPSM's conservative pass keeps every texel they
/// touch, and [`SpsmOptions::THIN_CASTERS`] keeps every shadow pixel.
///
/// Measured (lavapipe and GL, issue 16 session 13): of 1592 ray-cast shadow
/// pixels, (found, false shadow) standard (0, 0), SPSM default (`PAPER`)
/// (0, 0), `THIN_CASTERS` (1592, 23408). So the default lookup loses these
/// casters as the standard map does (the stored triangle is one of a wire
/// face's two slivers, p mostly lies in the other, and the hybrid lookup
/// takes the standard verdict), and the thin-caster rules keep them only at
/// texel width: the false shadow fills the texel rows the wires cross
/// (58% of this close-up view). The "SPSM keeps them" holds only in
/// that coarse sense; not asserted beyond it.
#[test]
fn sub_texel_fence_lost_by_the_standard_map() {
    let Some((device, queue)) = gpu() else { return };
    let half = 0.00075;
    let mut casters = Mesh::default();
    let pole = lixel::mesh::primitives::cuboid(Vec3::new(half, 0.5, half), 12);
    casters.append(&pole.transformed(&glam::Affine3A::from_translation(Vec3::new(-0.4, 0.5, 0.0))));
    for (k, z) in [-0.06f32, -0.02, 0.02, 0.06].into_iter().enumerate() {
        let wire = lixel::mesh::primitives::cuboid(Vec3::new(1.0, half, half), 12);
        let at = Vec3::new(0.0, 0.6 + 0.2 * k as f32, z);
        casters.append(&wire.transformed(&glam::Affine3A::from_translation(at)));
    }
    let scene = Scene {
        objects: vec![
            object("fence", casters, Role::CasterAndReceiver),
            object("floor", lixel::mesh::primitives::floor(8.0, 2), Role::Receiver),
        ],
    };
    let size = 200;
    let camera = Camera::look_at(
        DVec3::new(0.0, 3.0, 0.0),
        DVec3::ZERO,
        DVec3::NEG_Z,
        4f64.to_radians(),
        UVec2::splat(size),
        0.5,
        100.0,
    )
    .expect("camera");
    let lights = [Light::directional(DVec3::new(0.5, -1.0, 0.0))];
    let truth = RayCaster::new(&scene).trace_masks(&camera, &lights, size, size);
    let count = |masks: &lixel::mesh::ShadowMasks, truth_bit: u32, bit: u32| {
        (0..truth.depth.len())
            .filter(|&i| truth.visible(i) && truth.shadow[i] & 1 == truth_bit && masks.shadow[i] & 1 == bit)
            .count()
    };
    let expected = count(&truth, 1, 1);
    let m = matrices(&scene, &camera, &lights, 256, &Parameterization::Normal);
    let texel = {
        let (a, b) = (texel_of(&m[0], Vec3::ZERO), texel_of(&m[0], Vec3::new(0.0, 0.0, 0.1)));
        0.1 / (a - b).length()
    };
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    let mut found = Vec::new();
    for lookup in [ShadowLookup::DepthCompare, SPSM, SPSM_THIN] {
        renderer.render(&Frame { masks: true, lookup, ..Frame::new(&camera, &m) }).unwrap();
        let masks = renderer.read_masks().unwrap();
        found.push((count(&masks, 1, 1), count(&masks, 0, 1)));
    }
    eprintln!(
        "texel {texel:.4} units, casters {:.3} texel thick; true shadow pixels {expected}; (found, false shadow) standard {:?}, spsm {:?}, spsm thin casters {:?}",
        2.0 * half as f64 / texel,
        found[0],
        found[1],
        found[2]
    );
    assert!(expected > 500, "the ray cast sees the thin shadows: {expected}");
    assert!(2.0 * f64::from(half) / texel < 0.1, "the casters are thinner than a tenth of a texel");
    assert!(found[0].0 * 10 < expected, "the standard map loses (nearly) all of them: {found:?}");
    // The default lookup (session 14: edge-on faces no longer stored,
    // parallelogram partners): every caster that has its texels to itself
    // keeps its whole shadow; the pole and the wire at z = -0.02 share
    // texel columns (0.6 texel apart), each texel holds the one nearer the
    // light, and each loses its shadow where the other is stored (about
    // a sixth of the total).
    assert!(found[1].0 * 10 >= expected * 8, "the default SPSM lookup keeps at least 80%: {found:?}");
    assert!(
        found[1].1 * 10 <= expected,
        "the default SPSM lookup's false shadow stays below a tenth of the true shadow: {found:?}"
    );
    assert!(found[2].0 * 10 >= expected * 9, "SPSM with the thin-caster rules keeps at least 90%: {found:?}");
}

/// `RendererOptions::hardware_conservative`: where the device has
/// `CONSERVATIVE_RASTERIZATION`, the SPSM maps (texel words and the
/// consistent minimum depths) and the masks from the rasterizer's
/// conservative mode equal the shader path's, bit for bit, on the tiny
/// scene (focused 128² maps, sun and point light). Where the device lacks
/// the feature (lavapipe, llvmpipe GL) the option is ignored and the test
/// checks only that (the comparison then holds trivially); it says which.
#[test]
fn hardware_conservative_maps_match_the_shader_path() {
    let Some((device, queue)) = gpu() else { return };
    let has = device.features().contains(wgpu::Features::CONSERVATIVE_RASTERIZATION);
    let scene = tiny_scene();
    let camera = walkthrough_camera(96);
    let lights = test_lights();
    let m = matrices(&scene, &camera, &lights, 128, &Parameterization::Focused);
    let shader = RendererOptions::default();
    let hardware = RendererOptions { hardware_conservative: true, ..RendererOptions::default() };
    let mut results = Vec::new();
    for options in [shader, hardware] {
        let mut renderer = Renderer::new(&device, &queue, &scene, options).unwrap();
        renderer.render(&Frame { masks: true, lookup: SPSM, ..Frame::new(&camera, &m) }).unwrap();
        let words: Vec<_> =
            (0..lights.len()).map(|l| renderer.read_map_words(l).unwrap().expect("spsm words")).collect();
        let depths: Vec<_> = (0..lights.len()).map(|l| renderer.read_shadow_map(l).unwrap().depth).collect();
        results.push((renderer.hardware_conservative(), words, depths, renderer.read_masks().unwrap()));
    }
    eprintln!("device has CONSERVATIVE_RASTERIZATION: {has}; renderers use it: {} / {}", results[0].0, results[1].0);
    assert!(!results[0].0, "off by default");
    assert_eq!(results[1].0, has, "used exactly where the device has it");
    for light in 0..lights.len() {
        let differ = results[0].1[light].iter().zip(&results[1].1[light]).filter(|(a, b)| a != b).count();
        let depth_differ = results[0].2[light].iter().zip(&results[1].2[light]).filter(|(a, b)| a != b).count();
        eprintln!("light {light}: {differ} texel words and {depth_differ} depths differ");
        assert_eq!((differ, depth_differ), (0, 0), "light {light}: hardware and shader maps differ");
    }
    assert!(results[0].3 == results[1].3, "the masks differ");
}
