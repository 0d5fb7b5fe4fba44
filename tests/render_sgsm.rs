//! Sub-geometry shadow maps: the pattern table (CPU mirror and shader),
//! the decode on synthetic texels, the GPU sweep against the CPU
//! reference, and SGSM bits against ray casting.

#![cfg(feature = "render")]

mod render_common;

use glam::{DVec2, DVec3};
use lixel::mesh::RayCaster;
use lixel::render::sgsm::overlap::{OverlapMap, Projected};
use lixel::render::sgsm::pattern::{self, MaskWord, Status};
use lixel::render::sgsm::sweep::{self, SweepMap};
use lixel::render::{
    Frame, LoopOptions, LoopPolicy, LoopView, Renderer, RendererOptions, SgsmOptions, ShadowLookup, ShadowLoop,
    SpsmOptions,
};
use lixel::{Parameterization, ShadowMapSize};
use render_common::*;

const SPSM: ShadowLookup = ShadowLookup::Spsm(SpsmOptions::PAPER);
const SGSM: ShadowLookup = ShadowLookup::Sgsm(SgsmOptions::COUNTED);

/// A triangle around the corner points `s` (texel coordinates) that
/// contains them and no other corner of their texel.
fn around(s: &[DVec2]) -> [DVec2; 3] {
    match s.len() {
        1 => {
            let c = s[0];
            [0.0f64, 2.1, 4.2].map(|a| c + 0.4 * DVec2::new(a.cos(), a.sin()))
        }
        2 => {
            let (a, b) = (s[0], s[1]);
            let d = b - a;
            let n = DVec2::new(-d.y, d.x) / d.length();
            [a - 0.2 * d + 0.3 * n, a - 0.2 * d - 0.3 * n, b + 0.5 * d]
        }
        3 => {
            let c = (s[0] + s[1] + s[2]) / 3.0;
            [s[0], s[1], s[2]].map(|v| c + 1.3 * (v - c))
        }
        _ => {
            let c = (s[0] + s[3]) / 2.0;
            [c + DVec2::new(-3.0, -3.0), c + DVec2::new(5.0, -3.0), c + DVec2::new(-3.0, 5.0)]
        }
    }
}

/// Every pattern of the table, built from one triangle per group around
/// its corners of texel (2, 2) of a 5x5 map (nearer planes for lower
/// groups, a floor behind everything), is recognised with its index, and
/// wherever the decode names a triangle it is the one nearest the light
/// at the sample (the ray-cast truth); where it names none, no group
/// triangle contains the sample (the floor: the lookup falls back to SPSM).
#[test]
fn every_pattern_decodes_to_the_right_triangle() {
    let k = [2i64, 2];
    let corners: Vec<DVec2> = pattern::CORNERS
        .iter()
        .map(|o| DVec2::new((k[0] + i64::from(o[0])) as f64, (k[1] + i64::from(o[1])) as f64))
        .collect();
    let centre = DVec2::new(2.5, 2.5);
    let mut decided = 0;
    for index in 0..pattern::PATTERNS.len() as u8 {
        let groups = pattern::groups(index).unwrap();
        let mut tris: Vec<(usize, Projected)> = Vec::new();
        for (g, mask) in groups.iter().enumerate() {
            let points: Vec<DVec2> = (0..4).filter(|q| mask & 1 << q != 0).map(|q| corners[q]).collect();
            let slope = DVec2::new(0.01 * (g as f64 + 1.0), -0.007 * g as f64);
            let vertices = around(&points);
            let zeta = vertices.map(|v| 0.2 + 0.05 * g as f64 + slope.dot(v - centre));
            tris.push((g, Projected { vertices, zeta }));
        }
        for floor in [
            [DVec2::ZERO, DVec2::new(5.0, 0.0), DVec2::new(5.0, 5.0)],
            [DVec2::ZERO, DVec2::new(5.0, 5.0), DVec2::new(0.0, 5.0)],
        ] {
            tris.push((tris.len(), Projected { vertices: floor, zeta: [0.9; 3] }));
        }
        let overlap = OverlapMap::new(&tris, 5, 5);
        let map = overlap.sweep_map(&tris);
        let words = map.sweep();
        let word = words[12];
        let expected = if groups.len() == 1 { Status::Full } else { Status::Pattern };
        assert_eq!(word.status(), expected, "pattern {index} {:?}: {word:?}", pattern::PATTERNS[index as usize]);
        assert_eq!(word.pattern(), index, "pattern {index}");
        assert!(word.slots().count_ones() as usize >= groups.len(), "pattern {index}: a slot per group at least");
        let own = overlap.kept[12].unwrap() as usize;
        for s in 0..64 {
            let p = DVec2::new(2.0 + (f64::from(s % 8) + 0.5) / 8.0, 2.0 + (f64::from(s / 8) + 0.5) / 8.0);
            let truth = tris
                .iter()
                .enumerate()
                .filter(|(_, (_, t))| t.contains(p))
                .min_by(|a, b| a.1 .1.depth_at(p).total_cmp(&b.1 .1.depth_at(p)))
                .map(|(i, _)| i)
                .unwrap();
            if tris[own].1.contains(p) {
                assert_eq!(own, truth, "pattern {index}: own triangle");
                continue;
            }
            match sweep::choose(&map, word, k, p) {
                Some(slot) => {
                    let t = [k[0] + i64::from(slot % 3) - 1, k[1] + i64::from(slot / 3) - 1];
                    let chosen = overlap.kept[(t[1] * 5 + t[0]) as usize].unwrap() as usize;
                    assert_eq!(chosen, truth, "pattern {index}, sample {p}");
                    decided += 1;
                }
                None => assert!(truth >= groups.len(), "pattern {index}, sample {p}: a group triangle was missed"),
            }
        }
    }
    eprintln!("samples decided by the pattern: {decided}");
    assert!(decided > 100, "{decided}");
}

/// The shader's pattern code (canonical labels, table lookup) equals the
/// CPU mirror for all 4^4 labellings.
#[test]
fn shader_pattern_table_matches_the_cpu() {
    let Some((device, queue)) = gpu() else { return };
    let source = lixel::render::sgsm::common_wgsl(&SgsmOptions::PAPER)
        + "@group(0) @binding(0) var<storage, read_write> results: array<u32, 256>;\n\
           @compute @workgroup_size(64) fn main(@builtin(global_invocation_id) id: vec3<u32>) {\n\
             let i = id.x;\n\
             let labels = vec4<u32>(i & 3u, (i >> 2u) & 3u, (i >> 4u) & 3u, (i >> 6u) & 3u);\n\
             let p = sgsm_pattern_index(labels);\n\
             results[i] = p | (sgsm_groups[p] << 8u);\n\
           }\n";
    let results = run_compute(&device, &queue, &source, 256);
    for (i, r) in results.iter().enumerate() {
        let i = i as u32;
        let labels = [i & 3, i >> 2 & 3, i >> 4 & 3, i >> 6 & 3];
        let p = pattern::pattern_index(labels);
        assert_eq!(r & 0xff, u32::from(p), "labels {labels:?}");
        assert_eq!(r >> 8, pattern::table_word(p), "labels {labels:?}");
    }
}

fn run_compute(device: &wgpu::Device, queue: &wgpu::Queue, source: &str, words: u64) -> Vec<u32> {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: None,
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: None,
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: words * 4,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: words * 4,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry { binding: 0, resource: buffer.as_entire_binding() }],
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups((words as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&buffer, 0, &staging, 0, words * 4);
    queue.submit([encoder.finish()]);
    staging.map_async(wgpu::MapMode::Read, .., |r| r.unwrap());
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let view = staging.get_mapped_range(..).unwrap();
    bytemuck::cast_slice::<u8, u32>(&view).to_vec()
}

/// The GPU sweep's mask words equal the CPU sweep of the same maps (read
/// back), for a directional and a point light on the tiny scene.
#[test]
fn gpu_sweep_matches_the_cpu_reference() {
    // Measured (lavapipe, 96² focused maps): 0 and 0 words differ; 0 and 27
    // corner ties broken differently.
    sweep_matches_the_cpu_at(96);
}

/// The same at 1024² maps, whose rows are longer than the CPU backends'
/// loop limit allows one invocation to sweep (65 535 loop iterations, all
/// loops together; a texel costs up to ≈ 230): one invocation per row cut
/// every row near column 550 on lavapipe and llvmpipe (checked by putting
/// main's shader back). Issue-18 note, session 12 (hloop).
#[test]
fn gpu_sweep_matches_the_cpu_reference_on_long_rows() {
    sweep_matches_the_cpu_at(1024);
}

fn sweep_matches_the_cpu_at(size: u32) {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let camera = walkthrough_camera(64);
    let lights = test_lights();
    let m = matrices(&scene, &camera, &lights, size, &Parameterization::Focused);
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    renderer.render(&Frame { lookup: SGSM, ..Frame::new(&camera, &m) }).unwrap();
    for (light, matrix) in m.iter().enumerate() {
        let (w, h) = (matrix.map_size.width, matrix.map_size.height);
        let words = renderer.read_map_words(light).unwrap().unwrap();
        let lixel::render::sgsm::SgsmWords { normals, masks } = renderer.read_sgsm_words(light).unwrap().unwrap();
        let map = SweepMap::new(&words, &normals, w, h, SpsmOptions::PAPER.gradient_code);
        let cpu = map.sweep();
        let mut by_status = [0usize; 4];
        let (mut differ, mut tie_breaks) = (0, 0);
        for (i, (g, c)) in masks.iter().zip(&cpu).enumerate() {
            let g = MaskWord(*g);
            by_status[g.status() as usize] += 1;
            if g == *c {
                continue;
            }
            // A corner on two stored copies of one plane (equal depths) may
            // be given to either texel: f32 against f64.
            let k = [(i as u32 % w) as i64, (i as u32 / w) as i64];
            let at = |s: u8| [k[0] + i64::from(s % 3) - 1, k[1] + i64::from(s / 3) - 1];
            let centre = DVec2::new(k[0] as f64 + 0.5, k[1] as f64 + 0.5);
            let same_corners = (0..4).all(|q| {
                let (a, b) = (g.corner(q), c.corner(q));
                a == b || (a < 9 && b < 9 && map.same_plane(at(a), at(b), centre))
            });
            if same_corners && g.0 & 0x7fff == c.0 & 0x7fff {
                tie_breaks += 1;
            } else {
                differ += 1;
                if differ <= 5 {
                    eprintln!("gpu {g:?} cpu {c:?}");
                }
            }
        }
        eprintln!(
            "light {light}: {w}x{h}, statuses (empty, full, pattern, unrecognised) {by_status:?}, {differ} differ, \
             {tie_breaks} corner ties broken differently"
        );
        assert!(by_status[2] > 0 && by_status[1] > 0, "patterns and full texels occur: {by_status:?}");
        assert!(differ * 1000 <= masks.len(), "GPU and CPU sweeps differ at {differ} of {} texels", masks.len());
    }
}

/// SGSM shadow bits agree with the ray cast away from boundaries (99%) and
/// misclassify no more pixels than SPSM on the tiny scene; every lookup
/// path is counted.
#[test]
fn sgsm_bits_agree_with_ray_cast() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let camera = walkthrough_camera(160);
    let lights = test_lights();
    let truth = RayCaster::new(&scene).trace_masks(&camera, &lights, 160, 160);
    let matrices = matrices(&scene, &camera, &lights, 256, &Parameterization::Focused);
    let mut counts = Vec::new();
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    for lookup in [ShadowLookup::DepthCompare, SPSM, SGSM] {
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
    let paths = renderer.take_sgsm_counts().unwrap().expect("counting");
    eprintln!("misclassified: standard {}, spsm {}, sgsm {}; sgsm paths {paths:?}", counts[0], counts[1], counts[2]);
    // Measured (lavapipe and GL): standard 439, SPSM 206, SGSM 207 (issue 16,
    // session 14, parallelogram partners and edge-on faces dropped: SPSM's
    // neighbour loop sees a neighbour's partner, SGSM's sweep does not;
    // session 6, the log-polar gradient code: 233 and 233; session 5: 244 and 244 with
    // the standard fallback; session 4: 254 and 254 with SPSM's own-plane rule; before
    // it SPSM 305, SGSM 289).
    assert!(counts[2] * 100 <= counts[1] * 101, "SGSM within 1% of SPSM: {counts:?}");
    assert!(counts[2] < counts[0], "SGSM lowers the standard lookup's error: {counts:?}");
    assert!(paths.own > 0 && paths.full > 0 && paths.pattern > 0 && paths.fallback > 0, "{paths:?}");
    assert!(renderer.take_sgsm_counts().unwrap().unwrap().on_triangles() == 0, "taking resets the counters");
}

/// SGSM on every other light matrix (normal, snapped focused, PSM,
/// LiSPSM, plane-optimal) and on the scene-optimized matrices a
/// [`ShadowLoop`] settles on with SGSM's analysis bits (`optimized+sgsm`):
/// the tiny scene, every light kind (sun, point, spot), 256² maps. Each
/// frame runs SGSM's plane paths (counted), agrees with the ray cast away
/// from boundaries as well as SPSM does (99% where SPSM does: with PSM's
/// matrices both agree at 97%) and misclassifies at most 1% more pixels
/// than SPSM. Measured (lavapipe, session 13), misclassified SPSM / SGSM:
/// normal 358 / 359, snapped 294 / 294, PSM 1366 / 1368, LiSPSM 185 / 185,
/// plane-optimal 134 / 133, the loop's 102 / 102 — SGSM is not below SPSM
/// pixel for pixel on every matrix (the goal is on the presets).
#[test]
fn sgsm_works_with_every_matrix_and_the_frame_loop() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let camera = walkthrough_camera(128);
    let mut lights = test_lights();
    lights.push(lixel::Light::spot(DVec3::new(6.0, 18.0, -9.0), DVec3::new(-6.0, -18.0, 9.0), 35f64.to_radians()));
    let truth = RayCaster::new(&scene).trace_masks(&camera, &lights, 128, 128);
    let options = RendererOptions { analysis_size: (48, 48), ..RendererOptions::default() };
    let mut renderer = Renderer::new(&device, &queue, &scene, options).unwrap();
    let mut sets: Vec<(String, Vec<lixel::LightMatrix>)> = Parameterization::ALL_DEFAULT
        .iter()
        .filter(|p| !matches!(p, Parameterization::Focused))
        .map(|p| (format!("{:?}", p.method()), matrices(&scene, &camera, &lights, 256, p)))
        .collect();
    let view = LoopView { camera: &camera, lights: &lights, bounds: scene.bounds(), map: ShadowMapSize::square(256) };
    let mut shadows =
        ShadowLoop::new(LoopPolicy::Optimized, lights.len(), LoopOptions { lookup: SGSM, ..LoopOptions::default() })
            .unwrap();
    let settled = shadows.settle(&mut renderer, &view, 4).unwrap();
    assert!(settled.frames >= 1 && settled.matrices.len() == lights.len(), "{settled:?}");
    sets.push(("optimized (ShadowLoop with SGSM)".into(), settled.matrices));
    for (name, m) in &sets {
        let mut counts = Vec::new();
        let _ = renderer.take_sgsm_counts();
        let mut agreements = Vec::new();
        for lookup in [SPSM, SGSM] {
            renderer.render(&Frame { masks: true, lookup, ..Frame::new(&camera, m) }).unwrap();
            let gpu = renderer.read_masks().unwrap();
            let mut total = 0;
            for light in 0..lights.len() as u32 {
                let agreement = truth.agreement_away_from_boundaries(&gpu, light, 1);
                agreements.push(agreement.fraction());
                total += gpu.misclassified(&truth, light).unwrap();
            }
            counts.push(total);
        }
        let paths = renderer.take_sgsm_counts().unwrap().expect("counting");
        eprintln!(
            "{name}: misclassified spsm {}, sgsm {}; agreement per light (spsm, then sgsm) {agreements:.4?}; \
             sgsm paths {paths:?}",
            counts[0], counts[1]
        );
        let (spsm, sgsm) = agreements.split_at(lights.len());
        for (light, (a, b)) in spsm.iter().zip(sgsm).enumerate() {
            assert!(*b >= a.min(0.99) - 1e-3, "{name}, light {light}: SGSM agrees {b:.4}, SPSM {a:.4}");
        }
        assert!(paths.own > 0 && paths.full + paths.pattern > 0, "{name}: SGSM's plane paths ran: {paths:?}");
        // Within 1% plus one pixel (issue 16, session 14: SPSM's partners
        // made optimized 83 / 84; SGSM's sweep does not see partners).
        assert!(counts[1] * 100 <= counts[0] * 101 + 100, "{name}: SGSM within 1% (+1 pixel) of SPSM: {counts:?}");
    }
}

/// The detection rate of the CPU reference on the tiny scene (focused 256²
/// maps, sun and point light): the texels with 2–4 visible triangles are
/// counted and at least 87% of them recognised (the paper's figure, the
/// issue's goal); texels with more than four are reported.
#[test]
fn detection_rate_on_the_tiny_scene() {
    let scene = tiny_scene();
    let camera = walkthrough_camera(128);
    let lights = test_lights();
    for (light, m) in matrices(&scene, &camera, &lights, 256, &Parameterization::Focused).iter().enumerate() {
        let tris = lixel::render::sgsm::overlap::project(&scene, m);
        let overlap = OverlapMap::new(&tris, 256, 256);
        let words = overlap.sweep_map(&tris).sweep();
        let d = lixel::render::sgsm::overlap::detection(&tris, &overlap, &words, 8);
        let rate = d.rate_2_to_4();
        eprintln!("light {light}: covered {}, rows (1, 2, 3, 4, >4) {:?}, 2-4 recognised {rate:.4}", d.covered, d.rows);
        assert!(d.rows[1..4].iter().all(|r| r.texels > 0), "every class occurs: {d:?}");
        assert!(rate >= 0.87, "light {light}: {rate:.4} of texels with 2-4 visible triangles recognised: {d:?}");
    }
}
