//! Per-object culling leaves the output unchanged: the same shadow maps,
//! camera image and masks as drawing every object, for every classical
//! method (PSM's inverted and unclipped lights included), while it does
//! leave objects out. Likewise keeping a layer's map for a later frame
//! (`RendererOptions::reuse_maps`), and drawing several lights in one frame
//! (each light's bits are those of its own frame; the experiment's shared
//! frame relies on it). And work an experiment does not repeat: masks read
//! from the frame that already wrote them, and a loop's first frame shared
//! by a second loop at the same view.

#![cfg(feature = "render")]

mod render_common;

use glam::{DVec3, UVec2};
use lixel::optimize::{OptimizeOptions, SearchStrategy};
use lixel::render::{
    AnalysisRequest, FirstFrame, Frame, LoopOptions, LoopPolicy, LoopView, Renderer, RendererOptions, ShadowLookup,
    ShadowLoop, SpsmOptions,
};
use lixel::{Camera, Light, Parameterization, ShadowMapSize, ShadowProblem};
use render_common::*;

#[test]
fn culling_changes_nothing_but_the_work() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let total = scene.triangle_count() as u64;
    // Inside the scene, looking past some objects and away from others.
    let camera = Camera::look_at(
        DVec3::new(-2.0, 3.0, 4.0),
        DVec3::new(12.0, 0.5, -10.0),
        DVec3::Y,
        50f64.to_radians(),
        UVec2::splat(96),
        0.3,
        150.0,
    )
    .unwrap();
    let lights = [
        Light::directional(DVec3::new(0.6, -1.0, 0.35)),
        Light::point(DVec3::new(-8.0, 30.0, 12.0)),
        // Behind the viewer and low: PSM inverts this light.
        Light::point(DVec3::new(-20.0, 6.0, 25.0)),
        Light::spot(DVec3::new(6.0, 15.0, -4.0), DVec3::new(0.2, -1.0, -0.1), 12f64.to_radians()),
    ];
    let mut culled = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    let options = RendererOptions { cull_objects: false, ..RendererOptions::default() };
    let mut everything = Renderer::new(&device, &queue, &scene, options).unwrap();
    let (mut compared, mut saved_shadow, mut saved_camera) = (0, false, false);
    for parameterization in Parameterization::ALL_DEFAULT {
        let matrices: Vec<_> = lights
            .iter()
            .filter_map(|&light| {
                ShadowProblem::new(camera, light, scene.bounds(), ShadowMapSize::square(256))
                    .and_then(|p| p.solve(&parameterization))
                    .ok()
            })
            .collect();
        let frame =
            Frame { camera: &camera, lights: &matrices, masks: true, analysis: None, lookup: Default::default() };
        let a = culled.render(&frame).unwrap();
        let b = everything.render(&frame).unwrap();
        assert_eq!(b.shadow_triangles, total * matrices.len() as u64);
        assert!(a.shadow_triangles <= b.shadow_triangles && a.camera_triangles <= b.camera_triangles);
        eprintln!(
            "{parameterization:?}: shadow triangles {} of {}, camera {} of {}",
            a.shadow_triangles, b.shadow_triangles, a.camera_triangles, b.camera_triangles
        );
        saved_shadow |= a.shadow_triangles < b.shadow_triangles;
        saved_camera |= a.camera_triangles < b.camera_triangles;
        for light in 0..matrices.len() {
            let (ma, mb) = (culled.read_shadow_map(light).unwrap(), everything.read_shadow_map(light).unwrap());
            let differing = ma.depth.iter().zip(&mb.depth).filter(|(x, y)| x != y).count();
            assert_eq!(differing, 0, "{parameterization:?} light {light}: shadow maps differ");
        }
        assert_eq!(culled.read_color().unwrap(), everything.read_color().unwrap(), "{parameterization:?}");
        assert_eq!(culled.read_masks().unwrap(), everything.read_masks().unwrap(), "{parameterization:?}");
        compared += matrices.len();
    }
    assert!(compared >= 16, "most configurations solve: {compared}");
    assert!(saved_shadow, "some shadow pass left objects out");
    assert!(saved_camera, "the camera pass left objects out");
}

#[test]
fn reused_maps_give_the_frames_of_drawn_maps() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let camera = walkthrough_camera(96);
    let focused = matrices(&scene, &camera, &test_lights(), 192, &Parameterization::Focused);
    let lispsm = matrices(&scene, &camera, &test_lights(), 160, &Parameterization::LiSpsm(Default::default()));
    let (a, b, c) = (focused[0], focused[1], lispsm[0]);
    let options = RendererOptions { analysis_size: (32, 32), timestamps: false, ..Default::default() };
    let mut drawn = Renderer::new(&device, &queue, &scene, options).unwrap();
    let mut kept = Renderer::new(&device, &queue, &scene, RendererOptions { reuse_maps: true, ..options }).unwrap();
    let spsm = ShadowLookup::Spsm(SpsmOptions::default());
    // (lights, lookup, analysis, maps expected kept)
    let frames: Vec<(Vec<_>, ShadowLookup, bool, u32)> = vec![
        (vec![a], ShadowLookup::DepthCompare, false, 0),
        (vec![a], ShadowLookup::DepthCompare, false, 1),
        (vec![b, a], ShadowLookup::DepthCompare, false, 0),
        (vec![b, a], ShadowLookup::DepthCompare, true, 2),
        (vec![b, c], ShadowLookup::DepthCompare, false, 1),
        // Another lookup's maps: their own layers and records.
        (vec![b, c], spsm, false, 0),
        (vec![b, c], spsm, false, 2),
        // A third layer: new maps, nothing kept.
        (vec![b, c, a], ShadowLookup::DepthCompare, false, 0),
        (vec![b, c, a], ShadowLookup::DepthCompare, false, 3),
        (vec![c], ShadowLookup::DepthCompare, false, 0),
    ];
    for (k, (lights, lookup, analysis, expected)) in frames.iter().enumerate() {
        let frame = Frame {
            camera: &camera,
            lights,
            masks: true,
            analysis: analysis.then(AnalysisRequest::default),
            lookup: *lookup,
        };
        let d = drawn.render(&frame).unwrap();
        let r = kept.render(&frame).unwrap();
        assert_eq!(d.maps_reused, 0, "frame {k}");
        assert_eq!(r.maps_reused, *expected, "frame {k}");
        assert_eq!(r.shadow_passes + r.maps_reused, d.shadow_passes, "frame {k}");
        assert_eq!(kept.read_masks().unwrap(), drawn.read_masks().unwrap(), "frame {k}");
        assert_eq!(kept.read_color().unwrap(), drawn.read_color().unwrap(), "frame {k}");
        for light in 0..lights.len() {
            let (x, y) = (kept.read_shadow_map(light).unwrap(), drawn.read_shadow_map(light).unwrap());
            assert!(x.depth == y.depth, "frame {k} light {light}: maps differ");
        }
        if *analysis {
            drawn.wait_idle().unwrap();
            kept.wait_idle().unwrap();
            let (x, y) = (kept.try_take_analysis().unwrap(), drawn.try_take_analysis().unwrap());
            assert_eq!(x.masks, y.masks, "frame {k}: analysis readbacks differ");
        }
    }
    // A timed frame draws every pass.
    let mut timed =
        Renderer::new(&device, &queue, &scene, RendererOptions { reuse_maps: true, ..Default::default() }).unwrap();
    let frame = Frame { camera: &camera, lights: &focused, masks: true, analysis: None, lookup: Default::default() };
    timed.render(&frame).unwrap();
    let again = timed.render(&frame).unwrap();
    assert_eq!(again.maps_reused, u32::from(!timed.timestamps_enabled()) * 2);
}

#[test]
fn each_light_of_a_frame_gets_the_bits_of_its_own_frame() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let camera = walkthrough_camera(64);
    let mut matrices = Vec::new();
    for p in [Parameterization::Focused, Parameterization::Normal, Parameterization::LiSpsm(Default::default())] {
        matrices.extend(lixel_matrices(&scene, &camera, &p));
    }
    assert!(matrices.len() >= 6);
    let options = RendererOptions { timestamps: false, ..Default::default() };
    let mut renderer = Renderer::new(&device, &queue, &scene, options).unwrap();
    let own: Vec<_> = matrices
        .iter()
        .map(|m| {
            let frame = Frame {
                camera: &camera,
                lights: std::slice::from_ref(m),
                masks: true,
                analysis: None,
                lookup: Default::default(),
            };
            renderer.render(&frame).unwrap();
            renderer.read_masks().unwrap()
        })
        .collect();
    // Every count of layers up to seven (six is a cube map on GL if unguarded).
    for n in 2..=matrices.len().min(7) {
        let frame =
            Frame { camera: &camera, lights: &matrices[..n], masks: true, analysis: None, lookup: Default::default() };
        renderer.render(&frame).unwrap();
        let shared = renderer.read_masks().unwrap();
        for (bit, single) in own[..n].iter().enumerate() {
            assert_eq!(shared.depth, single.depth, "{n} lights");
            let differing = (0..single.shadow.len())
                .filter(|&i| {
                    shared.shadow[i] >> bit & 1 != single.shadow[i] & 1
                        || shared.facing[i] >> bit & 1 != single.facing[i] & 1
                })
                .count();
            assert_eq!(differing, 0, "{n} lights: light {bit}'s bits differ from its own frame's");
        }
    }
}

#[test]
fn masks_come_from_the_last_frame_only_when_it_wrote_them() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let camera = walkthrough_camera(64);
    let focused = matrices(&scene, &camera, &test_lights(), 128, &Parameterization::Focused);
    let (a, b) = (focused[0], focused[1]);
    let options = RendererOptions { analysis_size: (32, 32), timestamps: false, ..Default::default() };
    let mut renderer = Renderer::new(&device, &queue, &scene, options).unwrap();
    let mut fresh = Renderer::new(&device, &queue, &scene, options).unwrap();
    let masks_of = |m, lookup| masks_frame(&camera, m, lookup);
    let spsm = ShadowLookup::Spsm(SpsmOptions::default());
    assert!(!renderer.has_masks_of(&masks_of(&a, ShadowLookup::DepthCompare)), "nothing rendered yet");
    // A loop's frame: no masks asked for, but its analysis pass reads them.
    let analysis =
        Frame { masks: false, analysis: Some(AnalysisRequest::default()), ..masks_of(&a, Default::default()) };
    renderer.render(&analysis).unwrap();
    assert!(renderer.has_masks_of(&masks_of(&a, ShadowLookup::DepthCompare)));
    assert!(!renderer.has_masks_of(&masks_of(&b, ShadowLookup::DepthCompare)), "another matrix");
    assert!(!renderer.has_masks_of(&masks_of(&a, spsm)), "another lookup");
    let two = Frame { lights: &focused, ..masks_of(&a, ShadowLookup::DepthCompare) };
    assert!(!renderer.has_masks_of(&two), "other lights");
    fresh.render(&masks_of(&a, ShadowLookup::DepthCompare)).unwrap();
    assert_eq!(renderer.read_masks().unwrap(), fresh.read_masks().unwrap(), "the analysis frame's masks");
    // A frame without masks or analysis writes none.
    renderer.render(&Frame::new(&camera, std::slice::from_ref(&a))).unwrap();
    assert!(!renderer.has_masks_of(&masks_of(&a, ShadowLookup::DepthCompare)));
    renderer.render(&masks_of(&a, ShadowLookup::DepthCompare)).unwrap();
    assert!(renderer.has_masks_of(&masks_of(&a, ShadowLookup::DepthCompare)));
    // A new capture of the view forgets them.
    renderer.capture_view(&camera).unwrap();
    assert!(!renderer.has_masks_of(&masks_of(&a, ShadowLookup::DepthCompare)));
}

#[test]
fn a_second_loop_at_the_view_takes_the_first_frame_of_the_first() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let camera = walkthrough_camera(96);
    let lights = [Light::point(DVec3::new(-8.0, 30.0, 12.0))];
    let view = LoopView { camera: &camera, lights: &lights, bounds: scene.bounds(), map: ShadowMapSize::square(128) };
    let options = RendererOptions { analysis_size: (48, 48), timestamps: false, ..Default::default() };
    let mut shared = Renderer::new(&device, &queue, &scene, options).unwrap();
    let mut alone = Renderer::new(&device, &queue, &scene, options).unwrap();
    let loop_of = |strategy| {
        let optimize = OptimizeOptions { strategy, ..Default::default() };
        ShadowLoop::new(LoopPolicy::Optimized, 1, LoopOptions { optimize, ..Default::default() }).unwrap()
    };
    let strategies = [SearchStrategy::Paper, SearchStrategy::NelderMead { max_iterations: 60 }];
    let mut first = FirstFrame::default();
    // The frame index the next frame would get: frames rendered so far.
    let rendered = |r: &mut Renderer| r.render(&Frame::new(&camera, &[])).unwrap().frame;
    let mut frames = Vec::new();
    for (k, strategy) in strategies.into_iter().enumerate() {
        let (before_shared, before_alone) = (rendered(&mut shared), rendered(&mut alone));
        let (mut a, mut b) = (loop_of(strategy), loop_of(strategy));
        let kept = a.settle_from(&mut shared, &view, 5, &mut first).unwrap();
        let own = b.settle(&mut alone, &view, 5).unwrap();
        assert_eq!(kept, own, "loop {k}");
        assert_eq!(a.frames(), b.frames(), "loop {k}: the shared frame counts");
        let drawn = (rendered(&mut shared) - before_shared - 1, rendered(&mut alone) - before_alone - 1);
        frames.push(drawn);
    }
    assert_eq!(frames[0].0, frames[0].1, "the first loop renders every frame");
    assert_eq!(frames[1].0 + 1, frames[1].1, "the second loop takes the first frame");
    // Another map size is another view: nothing taken.
    let other = LoopView { map: ShadowMapSize::square(96), ..view };
    let before = rendered(&mut shared);
    let settled = loop_of(SearchStrategy::Paper).settle_from(&mut shared, &other, 5, &mut first).unwrap();
    assert_eq!(rendered(&mut shared) - before - 1, settled.frames as u64);
}

/// A frame of `matrix` alone that writes its masks.
fn masks_frame<'a>(camera: &'a Camera, matrix: &'a lixel::LightMatrix, lookup: ShadowLookup) -> Frame<'a> {
    Frame { camera, lights: std::slice::from_ref(matrix), masks: true, analysis: None, lookup }
}

/// A matrix per test light (directional and point) and per lookup-free method.
fn lixel_matrices(scene: &lixel::mesh::Scene, camera: &Camera, p: &Parameterization) -> Vec<lixel::LightMatrix> {
    let lights = [
        Light::directional(DVec3::new(0.6, -1.0, 0.35)),
        Light::point(DVec3::new(-8.0, 30.0, 12.0)),
        Light::point(DVec3::new(6.0, 18.0, -9.0)),
    ];
    lights
        .iter()
        .filter_map(|&l| {
            ShadowProblem::new(*camera, l, scene.bounds(), ShadowMapSize::square(128)).and_then(|q| q.solve(p)).ok()
        })
        .collect()
}
