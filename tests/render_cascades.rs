//! Cascades in the renderer: each cascade's map is looked up exactly where
//! the CPU's per-pixel choice ([`Splits::choose`]) puts the pixel, on every
//! backend (the facing bits of the masks show which cascade a pixel used),
//! and the cascaded sun's shadow (the OR of its cascades' bits) agrees with
//! ray-cast truth about as well as one focused map.

#![cfg(feature = "render")]

mod render_common;

use glam::{DVec2, DVec3, UVec2};
use lixel::cascade::{CascadeProblems, CascadeSplits, SplitScheme, Splits};
use lixel::mesh::RayCaster;
use lixel::render::{Frame, Renderer, RendererOptions};
use lixel::{Camera, Light, Parameterization, ShadowMapSize, ShadowProblem};
use render_common::*;

#[test]
fn each_pixel_uses_the_cascade_the_cpu_chooses() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let size = 128;
    let camera = Camera::look_at(
        DVec3::new(-30.0, 2.5, 30.0),
        DVec3::new(10.0, 0.0, -10.0),
        DVec3::Y,
        60f64.to_radians(),
        UVec2::splat(size),
        0.2,
        150.0,
    )
    .unwrap();
    let sun = Light::directional(DVec3::new(0.5, -1.0, 0.3));
    let problem = ShadowProblem::new(camera, sun, scene.bounds(), ShadowMapSize::square(256)).unwrap();
    let policy = CascadeSplits { count: 4, scheme: SplitScheme::Practical { lambda: 0.75 }, overlap: 0.1 };
    let cascades = CascadeProblems::new(&problem, policy.for_problem(&problem).unwrap()).unwrap();
    let splits = cascades.splits().clone();
    let matrices: Vec<_> = cascades.solve(&Parameterization::Focused).into_iter().collect::<Result<_, _>>().unwrap();
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    renderer.set_cascades(0, Some(&splits));
    let frame = Frame { camera: &camera, lights: &matrices, masks: true, analysis: None, lookup: Default::default() };
    renderer.render(&frame).unwrap();
    let masks = renderer.read_masks().unwrap();

    let world_from_screen = camera.screen_from_world().inverse();
    let (mut checked, mut used, mut in_band) = (0usize, [0usize; 4], 0usize);
    let mut band_pixels = Vec::new();
    let b = splits.boundaries();
    let edges: Vec<f64> = b.iter().copied().chain((1..4).map(|k| b[k] - 0.5 * splits.band(k - 1))).collect();
    let mut disagree = Vec::new();
    for y in 0..size {
        for x in 0..size {
            let i = (y * size + x) as usize;
            if !masks.visible(i) || masks.facing[i] == 0 {
                continue;
            }
            let pixel = DVec2::new(f64::from(x), f64::from(y)) + 0.5;
            let world = world_from_screen.project_point3(pixel.extend(f64::from(masks.depth[i])));
            let d = camera.view_depth(world);
            let Some(choice) = splits.choose(d) else { continue };
            // f32 shading positions: leave pixels at a boundary or the
            // middle of a band (where the bits change hands) out.
            if edges.iter().any(|b| (d - b).abs() <= 1e-3 * b) {
                continue;
            }
            checked += 1;
            let owner = choice.bit_owner();
            used[owner] += 1;
            in_band += usize::from(choice.blend > 0.0);
            if masks.facing[i] != 1 << owner || masks.shadow[i] & !masks.facing[i] != 0 {
                disagree.push(format!(
                    "({x}, {y}) depth {d}: facing {:#b}, shadow {:#b}, cpu {owner} ({choice:?})",
                    masks.facing[i], masks.shadow[i]
                ));
            }
            if choice.blend > 0.02 && choice.blend < 0.98 {
                band_pixels.push((i, choice.blend));
            }
        }
    }
    eprintln!(
        "{checked} pixels checked ({in_band} in bands); per bit owner {used:?}; splits {:?}",
        splits.boundaries()
    );
    assert!(disagree.is_empty(), "{} of {checked} disagree: {:?}", disagree.len(), &disagree[..disagree.len().min(5)]);
    assert!(checked > 2000 && used.iter().all(|&n| n > 50), "{checked} checked, per cascade {used:?}");
    assert!(in_band > 500, "{in_band} pixels in blend bands");

    // The colour blends the two cascades' lighting across a band: it is the
    // blend of the colours with the band given wholly to the nearer
    // cascade and wholly to the farther one (same matrices). So that the
    // two lookups differ often, the odd cascades belong to another sun.
    let other = ShadowProblem::new(
        camera,
        Light::directional(DVec3::new(-0.6, -1.0, 0.1)),
        scene.bounds(),
        ShadowMapSize::square(256),
    )
    .unwrap();
    let other: Vec<_> = CascadeProblems::new(&other, splits.clone())
        .unwrap()
        .solve(&Parameterization::Focused)
        .into_iter()
        .map(Result::unwrap)
        .collect();
    let matrices: Vec<_> = (0..4).map(|k| if k % 2 == 1 { other[k] } else { matrices[k] }).collect();
    let blended = hard_or_blended(&mut renderer, &camera, &matrices, &splits);
    let hard = |boundaries: Vec<f64>, renderer: &mut Renderer| {
        hard_or_blended(renderer, &camera, &matrices, &Splits::from_boundaries(&boundaries, 0.0).unwrap())
    };
    let nearer = hard(b.to_vec(), &mut renderer);
    let farther =
        hard((0..=4).map(|k| if k == 0 || k == 4 { b[k] } else { b[k] - splits.band(k - 1) }).collect(), &mut renderer);
    let linear = |c: u8| {
        let c = f64::from(c) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let (mut differing, mut wrong) = (0usize, Vec::new());
    for &(i, w) in &band_pixels {
        let (x, y) = (i as u32 % size, i as u32 / size);
        let (a, n, f) = (blended.get_pixel(x, y).0, nearer.get_pixel(x, y).0, farther.get_pixel(x, y).0);
        differing += usize::from(n != f);
        for c in 0..3 {
            let expected = (1.0 - w) * linear(n[c]) + w * linear(f[c]);
            if (linear(a[c]) - expected).abs() > 0.01 + 0.02 * expected {
                wrong.push(format!("({x}, {y}) blend {w:.3}: {a:?} vs nearer {n:?}, farther {f:?}"));
                break;
            }
        }
    }
    eprintln!("{} band pixels, {differing} where the cascades' colours differ", band_pixels.len());
    assert!(
        wrong.is_empty(),
        "{} of {} band pixels: {:?}",
        wrong.len(),
        band_pixels.len(),
        &wrong[..wrong.len().min(5)]
    );
    assert!(differing > 10, "only {differing} band pixels where the cascades differ: the check checks little");
    renderer.set_cascades(0, Some(&splits));

    // The sun's bit is the OR of its cascades'; it agrees with ray-cast
    // truth about as well as one focused map of the same size.
    let truth = RayCaster::new(&scene).trace_masks(&camera, &[sun], size, size);
    let mut sun_masks = masks.clone();
    for (s, f) in sun_masks.shadow.iter_mut().zip(sun_masks.facing.iter_mut()) {
        *s = u32::from(*s != 0);
        *f = u32::from(*f != 0);
    }
    let cascaded = sun_masks.misclassified(&truth, 0).unwrap();
    let single = [problem.solve(&Parameterization::Focused).unwrap()];
    renderer.set_cascades(0, None);
    renderer
        .render(&Frame { camera: &camera, lights: &single, masks: true, analysis: None, lookup: Default::default() })
        .unwrap();
    let focused = renderer.read_masks().unwrap().misclassified(&truth, 0).unwrap();
    eprintln!("misclassified: 4 cascades of 256² {cascaded}, one focused 256² {focused}");
    assert!(cascaded <= focused, "cascades {cascaded} vs one focused map {focused}");
}

/// Splits placed over part of the visible depths (as SDSM splits from an
/// earlier readback are when the camera has moved): pixels nearer than the
/// first split use the first cascade, beyond the last split the last one,
/// never no cascade (which would leave them without the sun).
#[test]
fn depths_outside_the_splits_use_the_end_cascades() {
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let size = 96;
    let (camera, sun) = loop_view(size);
    let problem = ShadowProblem::new(camera, sun, scene.bounds(), ShadowMapSize::square(128)).unwrap();
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    // Which pixels face the sun, and their view depths, from one plain map.
    let one = [problem.solve(&Parameterization::Focused).unwrap()];
    renderer.render(&Frame { masks: true, ..Frame::new(&camera, &one) }).unwrap();
    let plain = renderer.read_masks().unwrap();
    let world_from_screen = camera.screen_from_world().inverse();
    let depths: Vec<(usize, f64)> = (0..size * size)
        .map(|i| i as usize)
        .filter(|&i| plain.visible(i) && plain.facing[i] & 1 == 1)
        .map(|i| {
            let (x, y) = (i as u32 % size, i as u32 / size);
            let pixel = DVec2::new(f64::from(x), f64::from(y)) + 0.5;
            (i, camera.view_depth(world_from_screen.project_point3(pixel.extend(f64::from(plain.depth[i])))))
        })
        .collect();
    let mut sorted: Vec<f64> = depths.iter().map(|d| d.1).collect();
    sorted.sort_by(f64::total_cmp);
    let (near, far) = (sorted[sorted.len() / 4], sorted[3 * sorted.len() / 4]);
    let splits = CascadeSplits { count: 3, scheme: SplitScheme::Logarithmic, overlap: 0.1 }.place(near, far).unwrap();
    let matrices: Vec<_> = CascadeProblems::new(&problem, splits.clone())
        .unwrap()
        .solve(&Parameterization::Focused)
        .into_iter()
        .collect::<Result<_, _>>()
        .unwrap();
    renderer.set_cascades(0, Some(&splits));
    renderer.render(&Frame { masks: true, ..Frame::new(&camera, &matrices) }).unwrap();
    let masks = renderer.read_masks().unwrap();
    let (mut nearer, mut beyond) = (0, 0);
    for &(i, d) in &depths {
        // f32 positions: leave the split ends themselves out.
        if d < near * 0.999 {
            nearer += 1;
            assert_eq!(masks.facing[i], 0b001, "pixel {i} at depth {d} (splits {near}..{far})");
        } else if d > far * 1.001 {
            beyond += 1;
            assert_eq!(masks.facing[i], 0b100, "pixel {i} at depth {d} (splits {near}..{far})");
        }
    }
    assert!(nearer > 100 && beyond > 100, "{nearer} nearer, {beyond} beyond the splits");
}

/// The colour of a frame whose lights are the cascades of `splits`.
fn hard_or_blended(
    renderer: &mut Renderer,
    camera: &Camera,
    matrices: &[lixel::LightMatrix],
    splits: &Splits,
) -> image::RgbaImage {
    renderer.set_cascades(0, Some(splits));
    renderer
        .render(&Frame { camera, lights: matrices, masks: false, analysis: None, lookup: Default::default() })
        .unwrap();
    renderer.read_color().unwrap()
}

/// The camera and sun of the loop tests: a low eye over the tiny scene.
fn loop_view(size: u32) -> (Camera, Light) {
    let camera = Camera::look_at(
        DVec3::new(-30.0, 2.5, 30.0),
        DVec3::new(10.0, 0.0, -10.0),
        DVec3::Y,
        60f64.to_radians(),
        UVec2::splat(size),
        0.2,
        150.0,
    )
    .unwrap();
    (camera, Light::directional(DVec3::new(0.5, -1.0, 0.3)))
}

/// Misclassified pixels of the sun (its cascades' bits OR-ed) rendered with
/// `matrices` as the renderer's cascades stand.
fn sun_misclassified(
    renderer: &mut Renderer,
    camera: &Camera,
    matrices: &[lixel::LightMatrix],
    truth: &lixel::mesh::ShadowMasks,
) -> u64 {
    renderer
        .render(&Frame { camera, lights: matrices, masks: true, analysis: None, lookup: Default::default() })
        .unwrap();
    let mut masks = renderer.read_masks().unwrap();
    for (s, f) in masks.shadow.iter_mut().zip(masks.facing.iter_mut()) {
        *s = u32::from(*s != 0);
        *f = u32::from(*f != 0);
    }
    masks.misclassified(truth, 0).unwrap()
}

#[test]
fn the_frame_loop_drives_cascades() {
    use lixel::render::{CascadePolicy, LoopOptions, LoopPolicy, LoopView, ShadowLoop};
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let size = 96;
    let (camera, sun) = loop_view(size);
    let map = ShadowMapSize::square(128);
    let lights = [sun, Light::point(DVec3::new(0.0, 60.0, 0.0))];
    let view = LoopView { camera: &camera, lights: &lights, bounds: scene.bounds(), map };
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    let truth = RayCaster::new(&scene).trace_masks(&camera, &[sun], size, size);
    let problem = ShadowProblem::new(camera, sun, scene.bounds(), map).unwrap();

    // csm: fixed practical splits, snapped focused cascades, exactly the
    // solver's; the point light keeps one map after the sun's four.
    let csm = CascadePolicy::csm(4);
    let mut shadows = ShadowLoop::new(LoopPolicy::Cascaded(csm.clone()), 2, LoopOptions::default()).unwrap();
    let done = shadows.frame(&mut renderer, &view).unwrap();
    let splits = done.splits.clone().unwrap();
    assert_eq!(splits, csm.splits.for_problem(&problem).unwrap());
    let expected: Vec<_> = CascadeProblems::new(&problem, splits.clone())
        .unwrap()
        .solve(&Parameterization::FocusedSnapped(Default::default()))
        .into_iter()
        .map(Result::unwrap)
        .collect();
    assert_eq!(done.matrices.len(), 5);
    assert_eq!(&done.matrices[..4], &expected[..]);
    assert!(done.readback.is_none(), "csm runs no analysis");
    let csm_errors = sun_misclassified(&mut renderer, &camera, &done.matrices, &truth);

    // sdsm: the splits move inside the visible depth range of the readback.
    let sdsm = CascadePolicy::sdsm(4, Parameterization::Focused);
    let mut shadows = ShadowLoop::new(LoopPolicy::Cascaded(sdsm), 2, LoopOptions::default()).unwrap();
    let settled = shadows.settle(&mut renderer, &view, 4).unwrap();
    assert_eq!(settled.frames, 2, "one frame to read back, one to place the splits");
    let full = splits.clone();
    let sdsm_splits = shadows.frame(&mut renderer, &view).unwrap().splits.unwrap();
    let depths: Vec<f64> = {
        renderer.set_cascades(0, None);
        let one = [problem.solve(&Parameterization::Focused).unwrap()];
        renderer
            .render(&Frame { camera: &camera, lights: &one, masks: true, analysis: None, lookup: Default::default() })
            .unwrap();
        let masks = renderer.read_masks().unwrap();
        let world_from_screen = camera.screen_from_world().inverse();
        (0..masks.depth.len())
            .filter(|&i| masks.visible(i))
            .map(|i| {
                let (x, y) = ((i as u32 % size) as f64 + 0.5, (i as u32 / size) as f64 + 0.5);
                camera.view_depth(world_from_screen.project_point3(DVec3::new(x, y, f64::from(masks.depth[i]))))
            })
            .collect()
    };
    let (lo, hi) = depths.iter().fold((f64::MAX, 0f64), |(lo, hi), &d| (lo.min(d), hi.max(d)));
    eprintln!("visible {lo}..{hi}; csm {:?}; sdsm {:?}", full.boundaries(), sdsm_splits.boundaries());
    // The analysis pass is coarser than the check's pixels: 2% slack.
    assert!(sdsm_splits.near() <= lo * 1.02 && sdsm_splits.far() >= hi * 0.98, "{sdsm_splits:?} vs {lo}..{hi}");
    assert!(sdsm_splits.near() > full.near() * 2.0, "{sdsm_splits:?} vs {full:?}");

    // optimized-cascades: every cascade optimized from the readback; the
    // result holds its own against csm on the sun's shadow.
    let mut shadows =
        ShadowLoop::new(LoopPolicy::Cascaded(CascadePolicy::optimized(4)), 2, LoopOptions::default()).unwrap();
    let settled = shadows.settle(&mut renderer, &view, 6).unwrap();
    assert!(settled.frames >= 2 && settled.frames <= 7, "{settled:?}");
    let done = shadows.frame(&mut renderer, &view).unwrap();
    let optimized_errors = sun_misclassified(&mut renderer, &camera, &done.matrices, &truth);
    eprintln!("misclassified: csm {csm_errors}, optimized cascades {optimized_errors} (settled in {})", settled.frames);
    assert!(optimized_errors <= csm_errors * 3 / 2 + 20, "optimized {optimized_errors} vs csm {csm_errors}");
}

/// Every lookup mode honours the per-pixel cascade choice: SPSM and SGSM
/// shade through `shade` (common.wgsl) and so set the same facing bits as
/// the depth compare, and the antialiased passes (`aa_passes.wgsl`, once per
/// map slot) compute a cascade's occlusion words only where the camera pass
/// gave that cascade the pixel's facing bit, so OR-ing a sun's slots gives
/// the owning cascade's words; the supersampled lookup's sub-samples are
/// each owned by one cascade.
#[test]
fn every_lookup_honours_the_cascade_choice() {
    use lixel::render::subpixel::AaSamples;
    use lixel::render::ShadowLookup;
    let Some((device, queue)) = gpu() else { return };
    let scene = tiny_scene();
    let size = 96;
    let (camera, sun) = loop_view(size);
    let problem = ShadowProblem::new(camera, sun, scene.bounds(), ShadowMapSize::square(128)).unwrap();
    let policy = CascadeSplits { count: 3, scheme: SplitScheme::Practical { lambda: 0.75 }, overlap: 0.1 };
    let cascades = CascadeProblems::new(&problem, policy.for_problem(&problem).unwrap()).unwrap();
    let matrices: Vec<_> = cascades.solve(&Parameterization::Focused).into_iter().collect::<Result<_, _>>().unwrap();
    let mut renderer = Renderer::new(&device, &queue, &scene, RendererOptions::default()).unwrap();
    renderer.set_cascades(0, Some(cascades.splits()));
    let render = |renderer: &mut Renderer, lookup: ShadowLookup| {
        renderer.render(&Frame { camera: &camera, lights: &matrices, masks: true, analysis: None, lookup }).unwrap();
        renderer.read_masks().unwrap()
    };
    let standard = render(&mut renderer, ShadowLookup::DepthCompare);
    let used: Vec<usize> = (0..3).map(|k| standard.facing.iter().filter(|&&f| f == 1 << k).count()).collect();
    assert!(used.iter().all(|&n| n > 50), "cascade use {used:?}");
    let lookups = [
        ShadowLookup::Spsm(Default::default()),
        ShadowLookup::Sgsm(Default::default()),
        ShadowLookup::SubPixelAa(AaSamples::X8),
        ShadowLookup::Supersampled(AaSamples::X8),
    ];
    for lookup in lookups {
        let masks = render(&mut renderer, lookup);
        assert_eq!(masks.facing, standard.facing, "{}: another cascade choice", lookup.name());
        assert!(masks.shadow.iter().zip(&masks.facing).all(|(s, f)| s & !f == 0), "{}", lookup.name());
        if let ShadowLookup::Supersampled(_) = lookup {
            // Each sub-sample is owned by one cascade: the slots' valid
            // words are disjoint, and a slot shadows only what it owns.
            let words: Vec<_> = (0..3).map(|k| renderer.read_supersampled(k).unwrap()).collect();
            let mut owned = 0;
            for i in 0..masks.facing.len() {
                let mut seen = 0u32;
                for w in &words {
                    assert_eq!(seen & w.valid[i], 0, "pixel {i}: a sub-sample owned by two cascades");
                    assert_eq!(w.occluded[i] & !w.valid[i], 0, "pixel {i}");
                    seen |= w.valid[i];
                }
                owned += usize::from(seen != 0);
            }
            assert!(owned > 1000, "only {owned} pixels with owned sub-samples");
            continue;
        }
        if let ShadowLookup::SubPixelAa(_) = lookup {
            let words: Vec<Vec<u32>> = (0..3).map(|k| renderer.read_occlusion(k).unwrap()).collect();
            let mut occluded = 0;
            for (i, &f) in masks.facing.iter().enumerate() {
                for (k, w) in words.iter().enumerate() {
                    if w[i] != 0 {
                        occluded += 1;
                        assert_eq!(f, 1 << k, "pixel {i}: cascade {k}'s occlusion {:#x} where facing is {f:#b}", w[i]);
                    }
                }
            }
            assert!(occluded > 100, "only {occluded} occluded pixels");
        }
    }
}
