//! Several configurations at once (`--jobs N`, [`ExperimentConfig::jobs`]).
//!
//! Why: on a machine without a GPU, lavapipe encodes and vertex-shades each
//! submission on one queue thread (vertex shading, clipping and binning of
//! the 1.14 M-triangle shadow pass are half of a method render's CPU time)
//! while its raster threads wait, so one renderer leaves about a third of
//! two cores idle. A second device has its own queue thread. On a real GPU
//! the same workers overlap one configuration's CPU work (the ray-cast
//! truth, the solves, the comparisons) with another's rendering.
//!
//! Each worker is a [`Runner`] with its own device and renderer; the scene,
//! the ray caster and the camera's primary rays are shared read-only. A
//! configuration's result depends only on its index (its light is seeded
//! by it, and every frame is a pure function of its inputs, kept maps
//! included), never on which worker ran it or what ran before, so the rows
//! are the same for every `N`; the journal takes them as they finish and
//! the report sorts them. The resolution equivalence also spreads its
//! configurations over the workers and sums in configuration order.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use super::{ExperimentConfig, ExperimentError, Runner};
use crate::render::device::Gpu;

/// The workers a run uses by default: the machine's cores, at most 2 (two
/// devices hold two copies of the scene's vertex buffers and maps; on two
/// cores a third worker has nothing left to fill).
#[must_use]
pub fn default_jobs() -> usize {
    std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get).min(2)
}

/// `jobs` runners: the first on `device`, the others each on a device of
/// its own opened on the same adapter ([`Gpu::open_like`]). A worker whose
/// device cannot be opened is left out, with a warning.
///
/// # Errors
/// The first runner's failures ([`Runner::new`]).
pub(super) fn runners<'a>(
    config: &'a ExperimentConfig,
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    jobs: usize,
    warnings: &mut Vec<String>,
) -> Result<Vec<Runner<'a>>, ExperimentError> {
    let first = Runner::new(config, device, queue)?;
    let info = device.adapter_info();
    let mut runners = vec![first];
    for k in 1..jobs {
        let worker = Gpu::open_like(&info, "lixel experiment worker")
            .map_err(ExperimentError::from)
            .and_then(|gpu| runners[0].worker(&gpu.device, &gpu.queue));
        match worker {
            Ok(runner) => runners.push(runner),
            Err(e) => {
                warnings.push(format!("ran {k} configurations at once, not {jobs}: worker {k}: {e}"));
                break;
            }
        }
    }
    Ok(runners)
}

/// Runs `work` on every item, each runner on its own thread taking the
/// next item when it is free (one runner: on this thread), and hands the
/// results to `done` on this thread in item order, each as soon as it and
/// every earlier one are in (so progress, warnings and the journal come in
/// the order of one worker). The first error (of `work` or `done`) stops
/// the workers from taking more items and is returned once every worker
/// stopped.
///
/// # Errors
/// The first error.
pub(super) fn for_each<'a, T, R>(
    runners: &mut [Runner<'a>],
    items: &[T],
    work: impl Fn(&mut Runner<'a>, T) -> Result<R, ExperimentError> + Sync,
    mut done: impl FnMut(&T, R) -> Result<(), ExperimentError>,
) -> Result<(), ExperimentError>
where
    T: Copy + Sync,
    R: Send,
{
    if let [runner] = runners {
        for item in items {
            done(item, work(runner, *item)?)?;
        }
        return Ok(());
    }
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    std::thread::scope(|scope| {
        let (sender, results) = mpsc::channel();
        for runner in runners.iter_mut() {
            let (sender, next, stop, work) = (sender.clone(), &next, &stop, &work);
            scope.spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&item) = items.get(i) else { break };
                    let result = work(runner, item);
                    let failed = result.is_err();
                    if sender.send((i, result)).is_err() || failed {
                        break;
                    }
                }
            });
        }
        drop(sender);
        let mut first_error = None;
        // Results that came before an earlier one, by item index.
        let mut waiting = BTreeMap::new();
        let mut expected = 0;
        for (i, result) in results {
            match result {
                Ok(r) => {
                    waiting.insert(i, r);
                }
                Err(e) => {
                    stop.store(true, Ordering::Relaxed);
                    first_error.get_or_insert(e);
                }
            }
            while first_error.is_none() {
                let Some(r) = waiting.remove(&expected) else { break };
                if let Err(e) = done(&items[expected], r) {
                    stop.store(true, Ordering::Relaxed);
                    first_error = Some(e);
                }
                expected += 1;
            }
        }
        first_error.map_or(Ok(()), Err)
    })
}

/// Folds every worker's stage times into the first runner's, which the
/// report reads, with the configurations' wall time `wall`.
pub(super) fn gather_stages(runners: &mut [Runner<'_>], wall: Duration) {
    let workers = runners.len();
    let Some((first, rest)) = runners.split_first_mut() else { return };
    for other in rest.iter() {
        first.stages.absorb(&other.stages);
    }
    first.stages.set_workers(workers, wall);
}
