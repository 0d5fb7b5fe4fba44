//! The frame-loop helper's cadence and state.

use glam::DVec3;
mod common;

use common::setup;
use lixel::optimize::{Optimizer, SampleOptions, ScheduleOptions, ShadowScheduler};
use lixel::{Light, Parameterization, Samples, ShadowMapSize};

#[test]
fn cadence_follows_the_paper() {
    for lights in [1usize, 2, 4, 5, 7, 32] {
        let scheduler =
            ShadowScheduler::new(lights, ScheduleOptions::default(), Optimizer::new(Default::default())).unwrap();
        let mut turns = vec![0; lights];
        for frame in 0..60u64 {
            let plan = scheduler.plan(frame).analysis;
            // An analysis pass every 3 frames.
            assert_eq!(plan.is_some(), frame % 3 == 0, "{lights} lights, frame {frame}");
            let Some(plan) = plan else { continue };
            let focused: Vec<usize> = (0..lights).filter(|&i| plan.is_focused(i)).collect();
            assert_eq!(plan.focused.count_ones() as usize, focused.len(), "no bits past the lights");
            // Staggered: no pass carries more than its share of focused maps.
            assert!(focused.len() <= lights.div_ceil(5), "{lights} lights, frame {frame}: {focused:?}");
            for i in focused {
                turns[i] += 1;
            }
        }
        // 20 passes: every light had its focused map once per 5 passes.
        assert_eq!(turns, vec![4; lights], "{lights} lights");
    }
    // Light 0 starts, as the paper's first (focused) analysis.
    let one = ShadowScheduler::new(1, ScheduleOptions::default(), Optimizer::new(Default::default())).unwrap();
    assert!(one.plan(0).analysis.unwrap().is_focused(0));
    assert!(!one.plan(3).analysis.unwrap().is_focused(0));
    assert!(ShadowScheduler::new(33, ScheduleOptions::default(), Optimizer::new(Default::default())).is_err());
    assert!(ShadowScheduler::new(
        1,
        ScheduleOptions { optimize_every: 0, ..Default::default() },
        Optimizer::new(Default::default())
    )
    .is_err());
}

#[test]
fn focused_analysis_maps_are_limited_in_size() {
    let optimizer = || Optimizer::new(Default::default());
    let scheduler = ShadowScheduler::new(1, ScheduleOptions::default(), optimizer()).unwrap();
    assert_eq!(scheduler.focused_analysis_size(ShadowMapSize::new(1000, 500)), ShadowMapSize::new(360, 180));
    assert_eq!(scheduler.focused_analysis_size(ShadowMapSize::new(700, 700)), ShadowMapSize::square(360));
    assert_eq!(scheduler.focused_analysis_size(ShadowMapSize::square(256)), ShadowMapSize::square(256));
    // A very thin map keeps at least one texel.
    assert_eq!(scheduler.focused_analysis_size(ShadowMapSize::new(8000, 1)), ShadowMapSize::new(360, 1));
    let unlimited =
        ShadowScheduler::new(1, ScheduleOptions { focused_map_limit: 0, ..Default::default() }, optimizer()).unwrap();
    assert_eq!(unlimited.focused_analysis_size(ShadowMapSize::square(4096)), ShadowMapSize::square(4096));
}

#[test]
fn scheduler_keeps_previous_matrices_until_samples_arrive() {
    let lights = [Light::directional(DVec3::new(0.5, -1.0, -0.2)), Light::point(DVec3::new(-6.0, 12.0, -2.0))];
    let (problems, readback) = setup(&lights);
    let mut scheduler =
        ShadowScheduler::new(2, ScheduleOptions::default(), Optimizer::new(Default::default())).unwrap();
    for (k, p) in problems.iter().enumerate() {
        scheduler.set_matrix(k, p.solve(&Parameterization::Focused).unwrap());
    }
    let initial: Vec<_> = (0..2).map(|k| *scheduler.matrix(k).unwrap()).collect();
    // A readback that never arrives: nothing calls update, matrices stay.
    for frame in 0..10 {
        let _ = scheduler.plan(frame);
    }
    assert_eq!(*scheduler.matrix(0).unwrap(), initial[0]);
    assert_eq!(*scheduler.matrix(1).unwrap(), initial[1]);
    // It arrives in frame 10: both lights are optimized from it.
    for (k, p) in problems.iter().enumerate() {
        let samples =
            Samples::from_readback(p, &readback.as_readback(true), k as u32, &SampleOptions::default()).unwrap();
        let report = scheduler.update(k, &samples, 10).unwrap().clone();
        assert!(report.boundary_samples > 0, "light {k} has no boundary samples");
        assert_eq!(scheduler.optimized_frame(k), Some(10));
        if report.accepted {
            assert_ne!(*scheduler.matrix(k).unwrap(), initial[k]);
        }
    }
    assert!(scheduler.update(5, &Samples::from_points(&problems[0], &[], &[]), 11).is_err());
}

#[test]
fn update_all_equals_light_by_light_updates() {
    let lights = [
        Light::directional(DVec3::new(0.5, -1.0, -0.2)),
        Light::point(DVec3::new(-6.0, 12.0, -2.0)),
        Light::directional(DVec3::new(-0.3, -1.0, 0.6)),
    ];
    let (problems, readback) = setup(&lights);
    let new = || ShadowScheduler::new(3, ScheduleOptions::default(), Optimizer::new(Default::default())).unwrap();
    let (mut one_by_one, mut together) = (new(), new());
    for frame in [10u64, 13, 16] {
        let all = Samples::from_readback_all(&problems, &readback.as_readback(true), &SampleOptions::default());
        let mut samples: Vec<lixel::Result<Samples>> = all.unwrap().into_iter().map(Ok).collect();
        // A light whose samples failed keeps its state in both.
        if frame == 13 {
            samples[1] = Err(lixel::LixelError::UnusableSamples { reason: "test" });
        }
        let reports = together.update_all(samples.clone(), frame).unwrap();
        for (k, (samples, report)) in samples.iter().zip(&reports).enumerate() {
            match samples {
                Ok(samples) => {
                    let expected = one_by_one.update(k, samples, frame).unwrap().clone();
                    assert_eq!(report.as_ref().unwrap(), &expected, "light {k}, frame {frame}");
                }
                Err(_) => assert!(report.is_err()),
            }
            assert_eq!(together.matrix(k), one_by_one.matrix(k), "light {k}, frame {frame}");
            assert_eq!(together.optimized_frame(k), one_by_one.optimized_frame(k));
        }
    }
    assert_eq!(together.optimized_frame(1), Some(16));
    // One sample set per light, or a typed refusal.
    assert!(together.update_all(Vec::new(), 20).is_err());
}
