//! A ring of staging buffers for reading GPU results back without ever
//! waiting for them.
//!
//! A frame that wants data back [`acquire`](ReadbackRing::acquire)s a free
//! slot (or, when all are in flight, skips its readback: the frame is never
//! held up), records a copy into the slot's buffer, submits, and calls
//! [`submitted`](ReadbackRing::submitted), which requests the mapping. Later
//! frames call [`try_take`](ReadbackRing::try_take): one non-blocking
//! `device.poll(PollType::Poll)` and, if a mapping has completed, the bytes
//! with the latency in frames and milliseconds. This is the pixel-buffer-
//! object scheme of the paper's section 2.4 ("two ongoing asynchronous
//! readbacks"), with the depth of the pipeline a parameter.

use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

/// How late a readback arrived.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReadbackLatency {
    /// Frames between the submitting frame and the one that took the data.
    pub frames: u64,
    /// From submission to the mapping callback (the data was ready then).
    pub ready: Duration,
    /// From submission to [`ReadbackRing::try_take`] handing it out.
    pub taken: Duration,
}

/// Bytes read back, with what the submitter attached.
#[derive(Clone, Debug)]
pub struct Readback<M> {
    /// The submitter's description of the data.
    pub meta: M,
    /// Frame index the data was submitted in.
    pub frame: u64,
    /// The buffer's contents.
    pub bytes: Vec<u8>,
    /// How late it arrived.
    pub latency: ReadbackLatency,
}

/// Set once by the mapping callback.
type MapSignal = Arc<OnceLock<(Result<(), wgpu::BufferAsyncError>, Instant)>>;

enum SlotState<M> {
    Free,
    /// Handed out by `acquire`, copy not yet submitted.
    Reserved,
    /// Mapping requested.
    Pending {
        meta: M,
        frame: u64,
        submitted_at: Instant,
        signal: MapSignal,
    },
}

struct Slot<M> {
    buffer: wgpu::Buffer,
    state: SlotState<M>,
}

/// Counters of a ring's life.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RingStats {
    /// Readbacks submitted.
    pub submitted: u64,
    /// Readbacks handed out by `try_take`.
    pub taken: u64,
    /// Acquire attempts refused because every slot was in flight.
    pub refused: u64,
    /// Readbacks discarded: superseded by a newer one, or failed to map.
    pub discarded: u64,
}

/// `N` staging buffers of one size, used round-robin.
pub struct ReadbackRing<M> {
    slots: Vec<Slot<M>>,
    slot_size: u64,
    /// Newest frame handed out; older data arriving later is discarded.
    newest_taken: Option<u64>,
    stats: RingStats,
}

impl<M> std::fmt::Debug for ReadbackRing<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ReadbackRing")
            .field("slots", &self.slots.len())
            .field("slot_size", &self.slot_size)
            .field("in_flight", &self.in_flight())
            .field("stats", &self.stats)
            .finish()
    }
}

impl<M> ReadbackRing<M> {
    /// `slot_count` (at least 1) staging buffers of `slot_size` bytes each.
    #[must_use]
    pub fn new(device: &wgpu::Device, label: &str, slot_count: usize, slot_size: u64) -> Self {
        let slots = (0..slot_count.max(1))
            .map(|i| Slot {
                buffer: device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(&format!("{label} staging {i}")),
                    size: slot_size,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
                state: SlotState::Free,
            })
            .collect();
        Self { slots, slot_size, newest_taken: None, stats: RingStats::default() }
    }

    /// Size of each slot in bytes.
    #[must_use]
    pub fn slot_size(&self) -> u64 {
        self.slot_size
    }

    /// Number of slots.
    #[must_use]
    pub fn slot_count(&self) -> usize {
        self.slots.len()
    }

    /// Slots reserved or waiting for their data.
    #[must_use]
    pub fn in_flight(&self) -> usize {
        self.slots.iter().filter(|s| !matches!(s.state, SlotState::Free)).count()
    }

    /// Counters so far.
    #[must_use]
    pub fn stats(&self) -> RingStats {
        self.stats
    }

    /// Reserves a free slot and returns its index and buffer (to copy into),
    /// or `None` when every slot is in flight: the caller skips this readback
    /// rather than wait.
    pub fn acquire(&mut self) -> Option<(usize, &wgpu::Buffer)> {
        let Some(index) = self.slots.iter().position(|s| matches!(s.state, SlotState::Free)) else {
            self.stats.refused += 1;
            return None;
        };
        let slot = &mut self.slots[index];
        slot.state = SlotState::Reserved;
        Some((index, &slot.buffer))
    }

    /// The buffer of slot `slot`.
    #[must_use]
    pub fn buffer(&self, slot: usize) -> Option<&wgpu::Buffer> {
        self.slots.get(slot).map(|s| &s.buffer)
    }

    /// Gives back a reserved slot whose copy was never submitted.
    pub fn release(&mut self, slot: usize) {
        if let Some(s) = self.slots.get_mut(slot) {
            if matches!(s.state, SlotState::Reserved) {
                s.state = SlotState::Free;
            }
        }
    }

    /// Call right after the queue submission that holds the copy into
    /// `slot`: requests the mapping (never blocks). Ignored for a slot that
    /// was not reserved.
    pub fn submitted(&mut self, slot: usize, frame: u64, meta: M) {
        let Some(s) = self.slots.get_mut(slot) else { return };
        if !matches!(s.state, SlotState::Reserved) {
            return;
        }
        let signal: MapSignal = Arc::new(OnceLock::new());
        let callback_signal = Arc::clone(&signal);
        s.buffer.map_async(wgpu::MapMode::Read, .., move |result| {
            let _ = callback_signal.set((result, Instant::now()));
        });
        s.state = SlotState::Pending { meta, frame, submitted_at: Instant::now(), signal };
        self.stats.submitted += 1;
    }

    /// Polls the device once without blocking and hands out the newest
    /// readback whose data has arrived, if any. Readbacks older than one
    /// already handed out are discarded as they arrive; so are failed
    /// mappings. `current_frame` is the caller's frame index (for latency).
    pub fn try_take(&mut self, device: &wgpu::Device, current_frame: u64) -> Option<Readback<M>> {
        // Non-blocking: runs the callbacks of mappings that have completed.
        let _ = device.poll(wgpu::PollType::Poll);
        self.take_ready(current_frame)
    }

    /// Like [`try_take`](Self::try_take) without polling the device: only
    /// mappings that completed during earlier polls (or submissions) count.
    pub fn take_ready(&mut self, current_frame: u64) -> Option<Readback<M>> {
        self.discard_stale();
        let newest = self
            .slots
            .iter()
            .enumerate()
            .filter_map(|(i, s)| match &s.state {
                SlotState::Pending { frame, signal, .. } if matches!(signal.get(), Some((Ok(()), _))) => {
                    Some((i, *frame))
                }
                _ => None,
            })
            .max_by_key(|&(_, frame)| frame)?
            .0;
        let slot = &mut self.slots[newest];
        let SlotState::Pending { meta, frame, submitted_at, signal } =
            std::mem::replace(&mut slot.state, SlotState::Free)
        else {
            unreachable!("selected slot is pending");
        };
        let bytes = match slot.buffer.get_mapped_range(..) {
            Ok(view) => view.to_vec(),
            Err(_) => {
                slot.buffer.unmap();
                self.stats.discarded += 1;
                return None;
            }
        };
        slot.buffer.unmap();
        let ready_at = signal.get().map_or_else(Instant::now, |(_, at)| *at);
        self.newest_taken = Some(frame);
        self.stats.taken += 1;
        self.discard_stale();
        Some(Readback {
            meta,
            frame,
            bytes,
            latency: ReadbackLatency {
                frames: current_frame.saturating_sub(frame),
                ready: ready_at.saturating_duration_since(submitted_at),
                taken: submitted_at.elapsed(),
            },
        })
    }

    /// Frees slots whose mapping failed, and completed slots older than the
    /// newest readback handed out.
    fn discard_stale(&mut self) {
        for slot in &mut self.slots {
            let SlotState::Pending { frame, signal, .. } = &slot.state else { continue };
            let stale = match signal.get() {
                Some((Err(_), _)) => true,
                Some((Ok(()), _)) => self.newest_taken.is_some_and(|newest| *frame < newest),
                None => false,
            };
            if stale {
                if matches!(signal.get(), Some((Ok(()), _))) {
                    slot.buffer.unmap();
                }
                slot.state = SlotState::Free;
                self.stats.discarded += 1;
            }
        }
    }
}
