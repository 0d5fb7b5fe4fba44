//! The optimizer's memory use across repeated calls (its own test binary:
//! the allocation counter is global, so no other test may run beside it).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicIsize, Ordering};

use glam::DVec3;
use lixel::optimize::{OptimizeOptions, Optimizer, SampleOptions};
use lixel::{Light, Samples};

mod common;

/// Counts live heap bytes (this test binary only).
struct Counting;

static LIVE: AtomicIsize = AtomicIsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LIVE.fetch_add(layout.size() as isize, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size() as isize, Ordering::Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

#[test]
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
}
