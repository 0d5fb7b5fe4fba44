//! The frame-loop helper's cadence and state.

use glam::DVec3;
mod common;

use common::setup;
use lixel::optimize::{AnalysisKind, Optimizer, SampleOptions, ScheduleOptions, ShadowScheduler};
use lixel::{Light, Parameterization, Samples};

#[test]
fn cadence_follows_the_paper() {
    let scheduler = ShadowScheduler::new(2, ScheduleOptions::default(), Optimizer::new(Default::default())).unwrap();
    let plans: Vec<Option<AnalysisKind>> = (0..31).map(|f| scheduler.plan(f).analysis).collect();
    for (frame, plan) in plans.iter().enumerate() {
        match frame {
            f if f % 15 == 0 => assert_eq!(*plan, Some(AnalysisKind::Focused), "frame {f}"),
            f if f % 3 == 0 => assert_eq!(*plan, Some(AnalysisKind::CurrentMatrices), "frame {f}"),
            f => assert_eq!(*plan, None, "frame {f}"),
        }
    }
    assert!(ShadowScheduler::new(33, ScheduleOptions::default(), Optimizer::new(Default::default())).is_err());
    assert!(ShadowScheduler::new(
        1,
        ScheduleOptions { optimize_every: 0, focused_every: 1 },
        Optimizer::new(Default::default())
    )
    .is_err());
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
