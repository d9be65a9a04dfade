//! Where a substep's GPU time goes: a timestamp after every stage's dispatches (and after every
//! dispatch of the implicit solve), summed per label. Off unless a context was opened with
//! timestamps (`GpuContext::open_with_timestamps`) and the solver asked to profile
//! (`GpuSolver::start_profile`).
//!
//! Timestamps are written inside the compute pass at the bottom of the pipe (wgpu's Vulkan
//! backend), so an interval runs from the end of the previous stage to the end of this one: on a
//! GPU that overlaps dispatches, a stage's time includes whatever of it did not overlap the stage
//! before. The intervals of one substep add up to its GPU time.

use super::context::GpuContext;
use crate::error::Error;

/// Queries per submission: wgpu's most per query set. A profiled submission holds one substep.
const QUERIES: u32 = wgpu::QUERY_SET_MAX_QUERIES;

/// GPU time of one label, summed over the profiled substeps.
#[derive(Clone, Debug, PartialEq)]
pub struct StageTime {
    /// The stage (a plan pass) or solve kernel, with its multigrid level where it has one.
    pub label: String,
    /// Dispatches summed into it.
    pub dispatches: u64,
    /// GPU seconds.
    pub seconds: f64,
}

/// Timestamps of the submission being encoded, and the sums so far.
pub struct Profiler {
    set: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    readback: wgpu::Buffer,
    /// Nanoseconds per timestamp tick.
    period_ns: f64,
    /// The label of the interval that ends at query `k + 1`, and its dispatches.
    pending: Vec<(String, u32)>,
    /// Sums per label, in first-seen order.
    totals: Vec<StageTime>,
    /// Substeps `advance` ran while profiling.
    substeps: u64,
    /// Marks dropped because a substep had more than `QUERIES - 1` dispatch groups.
    dropped: u64,
}

impl Profiler {
    /// A profiler on `ctx`, which must have been opened with timestamps.
    pub fn new(ctx: &GpuContext) -> Result<Self, Error> {
        if !ctx.has_timestamps() {
            return Err(Error::Gpu(format!(
                "{} was opened without timestamp queries: profiling needs a context from \
                 GpuContext::open_with_timestamps",
                ctx.info.name
            )));
        }
        let set = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("profile"),
            ty: wgpu::QueryType::Timestamp,
            count: QUERIES,
        });
        let bytes = QUERIES as u64 * wgpu::QUERY_SIZE as u64;
        let buffer = |label, usage| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        Ok(Profiler {
            set,
            resolved: buffer("profile resolved", U::QUERY_RESOLVE | U::COPY_SRC),
            readback: buffer("profile readback", U::MAP_READ | U::COPY_DST),
            period_ns: ctx.queue.get_timestamp_period() as f64,
            pending: Vec::new(),
            totals: Vec::new(),
            substeps: 0,
            dropped: 0,
        })
    }

    /// Starts a substep's timestamps (query 0).
    pub fn begin(&mut self, cpass: &mut wgpu::ComputePass) {
        self.pending.clear();
        cpass.write_timestamp(&self.set, 0);
    }

    /// Ends the interval of `dispatches` dispatches labelled `label` (built only when it fits).
    pub fn mark(
        &mut self,
        cpass: &mut wgpu::ComputePass,
        dispatches: u32,
        label: impl FnOnce() -> String,
    ) {
        let index = self.pending.len() as u32 + 1;
        if index >= QUERIES {
            self.dropped += 1;
            return;
        }
        cpass.write_timestamp(&self.set, index);
        self.pending.push((label(), dispatches));
    }

    /// Copies the substep's timestamps where `collect` reads them (after the pass ends).
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        let count = self.pending.len() as u32 + 1;
        encoder.resolve_query_set(&self.set, 0..count, &self.resolved, 0);
        let bytes = count as u64 * wgpu::QUERY_SIZE as u64;
        encoder.copy_buffer_to_buffer(&self.resolved, 0, &self.readback, 0, bytes);
    }

    /// Waits for the submitted substep and adds its intervals to the sums.
    pub fn collect(&mut self, ctx: &GpuContext) -> Result<(), Error> {
        let count = self.pending.len() + 1;
        let slice = self
            .readback
            .slice(..(count * wgpu::QUERY_SIZE as usize) as u64);
        let ticks: Vec<u64> = ctx.map_read(slice, |b| bytemuck::cast_slice(b).to_vec())?;
        for (k, (label, dispatches)) in self.pending.drain(..).enumerate() {
            // Timestamps may wrap; an interval is never longer than the counter's range.
            let seconds = ticks[k + 1].wrapping_sub(ticks[k]) as f64 * self.period_ns * 1e-9;
            match self.totals.iter_mut().find(|t| t.label == label) {
                Some(t) => {
                    t.dispatches += dispatches as u64;
                    t.seconds += seconds;
                }
                None => self.totals.push(StageTime {
                    label,
                    dispatches: dispatches as u64,
                    seconds,
                }),
            }
        }
        Ok(())
    }

    /// Counts `n` substeps run (`advance`; a frame's health check is timed but is none).
    pub fn add_substeps(&mut self, n: usize) {
        self.substeps += n as u64;
    }

    /// The sums per label, in the order the stages first ran.
    pub fn totals(&self) -> &[StageTime] {
        &self.totals
    }

    /// Substeps profiled.
    pub fn substeps(&self) -> u64 {
        self.substeps
    }

    /// Dispatch groups left untimed (past the `QUERIES - 1` marks a substep can hold).
    pub fn dropped(&self) -> u64 {
        self.dropped
    }
}
