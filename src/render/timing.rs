//! GPU timestamps per frame, read back through their own ring (never waited
//! for).

use std::time::Duration;

use super::readback::ReadbackRing;

/// The timed stages of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Stage {
    Shadow = 0,
    Camera = 1,
    Analysis = 2,
}

/// Two timestamps (begin, end) per stage.
const QUERIES: u32 = 6;
/// Frames of timestamps in flight.
const SLOTS: usize = 8;

/// GPU durations of one frame's stages.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GpuFrameTimes {
    /// The frame they belong to.
    pub frame: u64,
    /// All shadow passes, first begin to last end; `None` without lights.
    pub shadow: Option<Duration>,
    /// The camera pass.
    pub camera: Option<Duration>,
    /// The analysis pass; `None` when the frame had none.
    pub analysis: Option<Duration>,
    /// From the first stage's begin to the last stage's end.
    pub total: Option<Duration>,
}

/// The query set of one frame in the making.
pub(crate) struct FrameQueries {
    slot: usize,
}

pub(crate) struct GpuTimer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    /// Meta: (the frame had shadow passes, the frame had an analysis pass).
    ring: ReadbackRing<(bool, bool)>,
    period_ns: f64,
}

impl GpuTimer {
    pub(crate) fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Self {
        Self {
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("lixel frame timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: QUERIES,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("lixel timestamp resolve"),
                size: u64::from(QUERIES) * 8,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            ring: ReadbackRing::new(device, "lixel timestamps", SLOTS, u64::from(QUERIES) * 8),
            period_ns: f64::from(queue.get_timestamp_period()),
        }
    }

    /// Reserves a readback slot for this frame's timestamps; `None` (no
    /// timing this frame) when all are in flight.
    pub(crate) fn begin_frame(&mut self) -> Option<FrameQueries> {
        let (slot, _) = self.ring.acquire()?;
        Some(FrameQueries { slot })
    }

    /// Timestamp writes for a stage's pass: the stage's begin on its first
    /// pass and its end on its last.
    pub(crate) fn pass_writes<'a>(
        &'a self,
        _frame: &FrameQueries,
        stage: Stage,
        first: bool,
        last: bool,
    ) -> Option<wgpu::RenderPassTimestampWrites<'a>> {
        let base = 2 * stage as u32;
        Some(wgpu::RenderPassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: first.then_some(base),
            end_of_pass_write_index: last.then_some(base + 1),
        })
        .filter(|_| first || last)
    }

    /// Timestamp writes of a compute pass that ends `stage` (the SGSM sweep
    /// ends the shadow stage).
    pub(crate) fn compute_end_writes(&self, stage: Stage) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: None,
            end_of_pass_write_index: Some(2 * stage as u32 + 1),
        }
    }

    /// Resolves the queries and copies them into the frame's slot.
    pub(crate) fn resolve(&self, encoder: &mut wgpu::CommandEncoder, frame: &FrameQueries) {
        encoder.resolve_query_set(&self.queries, 0..QUERIES, &self.resolve, 0);
        if let Some(buffer) = self.ring.buffer(frame.slot) {
            encoder.copy_buffer_to_buffer(&self.resolve, 0, buffer, 0, u64::from(QUERIES) * 8);
        }
    }

    pub(crate) fn submitted(&mut self, frame: FrameQueries, index: u64, had_shadow: bool, had_analysis: bool) {
        self.ring.submitted(frame.slot, index, (had_shadow, had_analysis));
    }

    pub(crate) fn try_take(&mut self, device: &wgpu::Device, current_frame: u64) -> Option<GpuFrameTimes> {
        let readback = self.ring.try_take(device, current_frame)?;
        let stamps: &[u64] = bytemuck::cast_slice(&readback.bytes);
        let span = |stage: Stage| {
            let (begin, end) = (stamps[2 * stage as usize], stamps[2 * stage as usize + 1]);
            (end > begin && begin != 0).then_some((begin, end))
        };
        let to_duration = |ticks: u64| Duration::from_nanos((ticks as f64 * self.period_ns).round() as u64);
        let (had_shadow, had_analysis) = readback.meta;
        // The query set is reused every frame: a frame without shadow or
        // analysis passes still holds an older frame's stamps. Ignore them.
        let shadow = span(Stage::Shadow).filter(|_| had_shadow);
        let camera = span(Stage::Camera);
        let analysis = span(Stage::Analysis).filter(|_| had_analysis);
        let spans = [shadow, camera, analysis];
        let first = spans.iter().flatten().map(|s| s.0).min();
        let last = spans.iter().flatten().map(|s| s.1).max();
        Some(GpuFrameTimes {
            frame: readback.frame,
            shadow: shadow.map(|(b, e)| to_duration(e - b)),
            camera: camera.map(|(b, e)| to_duration(e - b)),
            analysis: analysis.map(|(b, e)| to_duration(e - b)),
            total: first.zip(last).map(|(b, e)| to_duration(e.saturating_sub(b))),
        })
    }
}
