//! All-lights sample extraction and parallel optimization give exactly the
//! per-light, sequential answers (issue 15).

use glam::DVec3;
use lixel::optimize::{
    optimize_lights, OptimizeOptions, OptimizeReport, Optimized, Optimizer, SampleOptions, SampleWorkspace,
};
use lixel::{Light, LightMatrix, LixelError, Samples};

mod common;

fn lights() -> Vec<Light> {
    vec![
        Light::directional(DVec3::new(0.5, -1.0, -0.2)),
        Light::directional(DVec3::new(-0.7, -0.6, 0.1)),
        Light::point(DVec3::new(2.0, 6.0, -3.0)),
        Light::spot(DVec3::new(-1.0, 5.0, -2.0), DVec3::new(0.1, -1.0, -0.4), 40f64.to_radians()),
        Light::directional(DVec3::new(0.05, -1.0, 0.9)),
    ]
}

#[test]
fn all_lights_extraction_equals_one_light_at_a_time() {
    let lights = lights();
    let (problems, readback) = common::setup(&lights);
    for normals in [false, true] {
        let readback = readback.as_readback(normals);
        let all = Samples::from_readback_all(&problems, &readback, &SampleOptions::default()).unwrap();
        assert_eq!(all.len(), problems.len());
        let mut boundaries = 0;
        for (i, (problem, together)) in problems.iter().zip(&all).enumerate() {
            let alone = Samples::from_readback(problem, &readback, i as u32, &SampleOptions::default()).unwrap();
            assert_eq!(together.counts(), alone.counts(), "light {i}, normals {normals}");
            assert_eq!(together.boundary(), alone.boundary(), "light {i}, normals {normals}");
            assert_eq!(together.relevant_count(), alone.relevant_count(), "light {i}");
            // The optimizer reads every relevant sample: same samples, same answer.
            let mut optimizer = Optimizer::new(OptimizeOptions::default());
            assert_eq!(
                format!("{:?}", optimizer.optimize(together, None)),
                format!("{:?}", optimizer.optimize(&alone, None)),
                "light {i}, normals {normals}"
            );
            boundaries += alone.boundary().len();
        }
        // The comparison is not vacuous.
        assert!(boundaries > 0, "no boundary samples at all");
    }
}

/// Extraction into reused samples and workspace (grown on other lights,
/// another camera, more lights, the other normals setting) gives exactly
/// the fresh extraction.
#[test]
fn extraction_into_reused_buffers_equals_fresh() {
    let lights = lights();
    let (problems, readback) = common::setup(&lights);
    let (other_problems, other_readback) = common::setup_with_eye(&lights[..3], DVec3::new(3.0, 2.5, 6.0));
    let options = SampleOptions::default();
    let mut workspace = SampleWorkspace::new();
    let mut out = Vec::new();
    let mut one = Samples::from_readback(&other_problems[2], &other_readback.as_readback(true), 2, &options).unwrap();
    for (round, normals) in [(0, false), (1, true), (2, false)] {
        // Dirty the buffers with the other camera's view first.
        let other = other_readback.as_readback(!normals);
        let count = if round == 1 { 2 } else { 3 };
        Samples::from_readback_all_into(&other_problems[..count], &other, &options, &mut out, &mut workspace).unwrap();
        let readback = readback.as_readback(normals);
        Samples::from_readback_all_into(&problems, &readback, &options, &mut out, &mut workspace).unwrap();
        let fresh = Samples::from_readback_all(&problems, &readback, &options).unwrap();
        assert_eq!(format!("{out:?}"), format!("{fresh:?}"), "round {round}");
        for (i, problem) in problems.iter().enumerate() {
            one.from_readback_into(problem, &readback, i as u32, &options, &mut workspace).unwrap();
            let alone = Samples::from_readback(problem, &readback, i as u32, &options).unwrap();
            assert_eq!(format!("{one:?}"), format!("{alone:?}"), "round {round}, light {i}");
        }
    }
    // An error leaves the previous samples as they were.
    let before = format!("{out:?}");
    let too_many = vec![problems[0].clone(); 33];
    let readback = readback.as_readback(false);
    assert!(Samples::from_readback_all_into(&too_many, &readback, &options, &mut out, &mut workspace).is_err());
    assert_eq!(format!("{out:?}"), before);
}

#[test]
fn parallel_optimization_equals_sequential() {
    let lights = lights();
    let (problems, readback) = common::setup(&lights);
    let samples =
        Samples::from_readback_all(&problems, &readback.as_readback(false), &SampleOptions::default()).unwrap();
    let mut prev: Vec<Option<LightMatrix>> = vec![None; samples.len()];
    let mut optimizers = vec![Optimizer::new(OptimizeOptions::default()); samples.len()];
    let mut sequential = vec![Optimizer::new(OptimizeOptions::default()); samples.len()];
    // Several frames, each starting from the previous frame's matrices.
    for _ in 0..3 {
        let together = optimize_lights(&mut optimizers, &samples, &prev).unwrap();
        let one_by_one: Vec<_> = sequential
            .iter_mut()
            .zip(&samples)
            .zip(&prev)
            .map(|((optimizer, samples), prev)| optimizer.optimize(samples, prev.as_ref()))
            .collect();
        assert_eq!(format!("{together:?}"), format!("{one_by_one:?}"));
        prev = together.into_iter().map(|r| r.ok().map(|o| o.matrix)).collect();
        assert!(prev.iter().all(Option::is_some));
    }
}

/// `optimize_into` (one optimizer and one report reused across lights and
/// frames, so the report's buffer holds another light's angles) gives what
/// `optimize` gives, matrix and report, bit for bit.
#[test]
fn optimize_into_equals_optimize() {
    let lights = lights();
    let (problems, readback) = common::setup(&lights);
    let samples =
        Samples::from_readback_all(&problems, &readback.as_readback(false), &SampleOptions::default()).unwrap();
    let mut prev: Vec<Option<LightMatrix>> = vec![None; samples.len()];
    let mut reused = Optimizer::new(OptimizeOptions::default());
    let mut report = OptimizeReport::default();
    for _ in 0..3 {
        for (samples, prev) in samples.iter().zip(&mut prev) {
            let fresh = Optimizer::new(OptimizeOptions::default()).optimize(samples, prev.as_ref());
            let into = reused
                .optimize_into(samples, prev.as_ref(), &mut report)
                .map(|matrix| Optimized { matrix, report: report.clone() });
            assert_eq!(format!("{into:?}"), format!("{fresh:?}"));
            *prev = into.ok().map(|o| o.matrix);
        }
    }
    assert!(prev.iter().all(Option::is_some));
}

#[test]
fn mismatched_inputs_are_refused() {
    let lights = lights();
    let (problems, readback) = common::setup(&lights);
    let readback = readback.as_readback(false);
    let too_many = vec![problems[0].clone(); 33];
    assert!(matches!(
        Samples::from_readback_all(&too_many, &readback, &SampleOptions::default()),
        Err(LixelError::UnusableSamples { .. })
    ));
    let samples = Samples::from_readback_all(&problems, &readback, &SampleOptions::default()).unwrap();
    let mut optimizers = vec![Optimizer::new(OptimizeOptions::default()); 2];
    assert!(matches!(
        optimize_lights(&mut optimizers, &samples, &vec![None; samples.len()]),
        Err(LixelError::UnusableSamples { .. })
    ));
    assert!(Samples::from_readback_all(&[], &readback, &SampleOptions::default()).unwrap().is_empty());
}
