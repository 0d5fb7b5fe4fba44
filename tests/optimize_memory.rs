//! Memory use across repeated calls of the optimizer, the all-lights sample
//! extraction and the classical methods. The classical methods must not
//! allocate at all once warm (issue 15).
//!
//! The allocation counters are global, so nothing else may allocate while
//! they run: this binary has no test harness (`harness = false` in
//! `Cargo.toml`) and runs its checks from `main`. Under libtest the test ran
//! on a thread of its own while the harness's main thread went on with its
//! bookkeeping of the running test; on a loaded machine the optimizer check
//! failed in about one run in seven (6 of 30, with or without `rayon`),
//! always with the heap exactly 900 bytes higher. Without the harness it
//! failed in none of 230 runs beside three busy loops.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicIsize, Ordering};

use glam::DVec3;
use lixel::optimize::{OptimizeOptions, OptimizeReport, Optimizer, SampleOptions, SampleWorkspace};
use lixel::{Light, Parameterization, Samples, SolveWorkspace};

mod common;

/// Counts live heap bytes (this test binary only).
struct Counting;

static LIVE: AtomicIsize = AtomicIsize::new(0);
static ALLOCATIONS: AtomicIsize = AtomicIsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LIVE.fetch_add(layout.size() as isize, Ordering::Relaxed);
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size() as isize, Ordering::Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Runs `call` 50 times to warm up, then 200 times; fails if the live heap
/// grew. Returns the allocations per call after warm-up (reported with
/// `--nocapture`).
fn steady_state(name: &str, call: impl FnMut()) -> f64 {
    steady_state_with_slack(name, 0, call)
}

/// Live-heap slack for calls that go through rayon: its job queue (a
/// crossbeam injector) keeps a block alive now and then, and a worker that
/// gets a light for the first time grows its own thread's solve workspace
/// (a few KiB each); the strict check failed intermittently under
/// `--all-features`. A leak of more than 320 bytes per call still fails.
const RAYON_SLACK: isize = if cfg!(feature = "rayon") { 65536 } else { 0 };

/// [`steady_state`], allowing the live heap to end up `slack` bytes higher.
fn steady_state_with_slack(name: &str, slack: isize, mut call: impl FnMut()) -> f64 {
    for _ in 0..50 {
        call();
    }
    let baseline = LIVE.load(Ordering::Relaxed);
    let allocations = ALLOCATIONS.load(Ordering::Relaxed);
    for _ in 0..200 {
        call();
    }
    let after = LIVE.load(Ordering::Relaxed);
    assert!(after <= baseline + slack, "{name}: live heap grew from {baseline} to {after} bytes over 200 calls");
    let per_call = (ALLOCATIONS.load(Ordering::Relaxed) - allocations) as f64 / 200.0;
    eprintln!("{name}: {per_call} allocations per call after warm-up");
    per_call
}

fn main() {
    repeated_calls_do_not_grow_memory();
    println!("optimize_memory: every check passed");
}

fn repeated_calls_do_not_grow_memory() {
    // Start every worker of rayon's global pool before anything is measured,
    // so that no worker's start-up (its queues and thread locals) can fall
    // inside a measured stretch.
    #[cfg(feature = "rayon")]
    rayon::broadcast(|_| ());
    repeated_optimization_does_not_grow_memory();
    let lights = [
        Light::directional(DVec3::new(0.5, -1.0, -0.2)),
        Light::point(DVec3::new(2.0, 6.0, -3.0)),
        Light::spot(DVec3::new(-1.0, 5.0, -2.0), DVec3::new(0.1, -1.0, -0.4), 40f64.to_radians()),
    ];
    let (problems, readback) = common::setup(&lights);
    let readback = readback.as_readback(false);
    steady_state_with_slack("all-lights extraction (fresh samples)", RAYON_SLACK, || {
        std::hint::black_box(Samples::from_readback_all(&problems, &readback, &SampleOptions::default()).unwrap());
    });
    // Into reused samples and workspace: nothing, but for rayon's own
    // scheduling when the `rayon` feature computes the bodies in parallel.
    let (mut out, mut workspace) = (Vec::new(), SampleWorkspace::new());
    let per_call = steady_state_with_slack("all-lights extraction into reused samples", RAYON_SLACK, || {
        Samples::from_readback_all_into(&problems, &readback, &SampleOptions::default(), &mut out, &mut workspace)
            .unwrap();
        std::hint::black_box(&out);
    });
    // Rayon's job queue allocates a block now and then (measured: 3 in 200
    // calls idle, above 20 in 200 once in twenty runs on an overloaded
    // machine); a per-call allocation of the extraction would be >= 1.
    let allowed = if cfg!(feature = "rayon") { 0.25 } else { 0.0 };
    assert!(per_call <= allowed, "all-lights extraction into reused buffers allocates {per_call} per call");
    let mut one = Samples::from_readback(&problems[1], &readback, 1, &SampleOptions::default()).unwrap();
    let per_call = steady_state("one-light extraction into reused samples", || {
        for (bit, problem) in problems.iter().enumerate() {
            one.from_readback_into(problem, &readback, bit as u32, &SampleOptions::default(), &mut workspace).unwrap();
            std::hint::black_box(&one);
        }
    });
    assert_eq!(per_call, 0.0, "one-light extraction into reused buffers allocates after warm-up");
    // Every classical method, after warm-up: no allocation at all, neither
    // for a frame's lights on one camera (the camera cache hits) nor with the
    // camera changing on every call (it misses and rebuilds in place).
    let (other_camera, _) = common::setup_with_eye(&lights, DVec3::new(3.0, 2.5, 6.0));
    for parameterization in Parameterization::ALL_DEFAULT {
        let name = parameterization.method().name();
        let per_call = steady_state(&format!("{name}, 3 lights, one camera"), || {
            for problem in &problems {
                std::hint::black_box(problem.solve(&parameterization).ok());
            }
        });
        assert_eq!(per_call, 0.0, "{name} allocates after warm-up");
        let per_call = steady_state(&format!("{name}, camera changing every call"), || {
            for problem in problems.iter().zip(&other_camera).flat_map(|(a, b)| [a, b]) {
                std::hint::black_box(problem.solve(&parameterization).ok());
            }
        });
        assert_eq!(per_call, 0.0, "{name} allocates after warm-up when the camera changes");
        // Through the workspace API: one workspace for all (its caster cache
        // misses between lights), one per light (every cache hits), and an
        // uncached one (everything rebuilt in its buffers).
        let mut shared = SolveWorkspace::new();
        let per_call = steady_state(&format!("{name}, solve_with, one workspace, cameras alternating"), || {
            for problem in problems.iter().zip(&other_camera).flat_map(|(a, b)| [a, b]) {
                std::hint::black_box(problem.solve_with(&parameterization, &mut shared).ok());
            }
        });
        assert_eq!(per_call, 0.0, "{name} allocates through solve_with after warm-up");
        let mut per_light: Vec<SolveWorkspace> = problems.iter().map(|_| SolveWorkspace::new()).collect();
        let per_call = steady_state(&format!("{name}, solve_with, a workspace per light"), || {
            for (problem, workspace) in problems.iter().zip(&mut per_light) {
                std::hint::black_box(problem.solve_with(&parameterization, workspace).ok());
            }
        });
        assert_eq!(per_call, 0.0, "{name} allocates through per-light workspaces after warm-up");
        let mut uncached = SolveWorkspace::uncached();
        let per_call = steady_state(&format!("{name}, solve_with, uncached workspace"), || {
            for problem in &problems {
                std::hint::black_box(problem.solve_with(&parameterization, &mut uncached).ok());
            }
        });
        assert_eq!(per_call, 0.0, "{name} allocates through an uncached workspace after warm-up");
    }
}

fn repeated_optimization_does_not_grow_memory() {
    let lights = [Light::directional(DVec3::new(0.5, -1.0, -0.2))];
    let (problems, readback) = common::setup(&lights);
    let samples =
        Samples::from_readback(&problems[0], &readback.as_readback(false), 0, &SampleOptions::default()).unwrap();
    let mut optimizer = Optimizer::new(OptimizeOptions::default());
    let mut prev = None;
    // Warm up: the reusable buffers grow to the largest candidate set once.
    for _ in 0..50 {
        prev = Some(optimizer.optimize(&samples, prev.as_ref()).unwrap().matrix);
    }
    let baseline = LIVE.load(Ordering::Relaxed);
    for _ in 0..200 {
        prev = Some(optimizer.optimize(&samples, prev.as_ref()).unwrap().matrix);
    }
    let after = LIVE.load(Ordering::Relaxed);
    assert!(after <= baseline, "live heap grew from {baseline} to {after} bytes over 200 calls");
    // `optimize` allocates one vector per call, the answer's: the report's
    // list of the angles tried (reserved once at its final size).
    let per_call = steady_state("optimizer", || {
        prev = Some(optimizer.optimize(&samples, prev.as_ref()).unwrap().matrix);
    });
    assert!(per_call <= 1.0, "the optimizer allocates {per_call} times per call after warm-up");
    // `optimize_into` reuses the report: nothing.
    let mut report = OptimizeReport::default();
    let per_call = steady_state("optimizer, optimize_into", || {
        prev = Some(optimizer.optimize_into(&samples, prev.as_ref(), &mut report).unwrap());
        std::hint::black_box(&report);
    });
    assert_eq!(per_call, 0.0, "optimize_into allocates after warm-up");
}
