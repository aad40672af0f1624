//! A delivered step on the device's clock ([`Timeline`]): GPU timestamps at the start of the step's
//! commands, at the start and the end of its compute pass, and after each of its readback copies.
//! The host's time from the submit to its outputs filled (`HostPath`'s `wait_s`, `refill_ahead_s`
//! and `copy_s`, which run one after the other) then splits into the device's part: the copies
//! recorded before the passes (the reset pool's new rows, the queue counters), the passes, and the
//! readback's copies with any idle time between their submits (where the other pieces are
//! submitted after the host's rows ahead, `GpuPaths::readback_before_host_work` off, and those
//! outlast the passes, the device's wait for them counts here); and what the device's part does not explain: recording and submitting, waking up and
//! mapping, and the copy of the last piece. `socnav bench --backend gpu` turns it on for a short
//! run of its own (`Backend::set_step_timeline`); off, a step records no timestamps.

use crate::backend::HostPath;
use crate::error::SimError;

use super::GpuDevice;
use super::kit::map_and_read;

/// Timestamp slots: the step's commands start, its compute pass begins, it ends; readback copy
/// `k` is done at `AFTER_PASSES + 1 + k` (of the timeline's `copies`).
const START: u32 = 0;
const PASSES: u32 = 1;
const AFTER_PASSES: u32 = 2;

/// The query set and buffers of the step timeline.
pub(crate) struct Timeline {
    set: wgpu::QuerySet,
    /// Where the timestamps are resolved, and the mapped copy of them.
    resolved: wgpu::Buffer,
    read: wgpu::Buffer,
    /// The adapter writes timestamps between commands (`TIMESTAMP_QUERY_INSIDE_ENCODERS`), so
    /// the copies before the passes and the readback's are timed too; else only the passes are.
    copies_timed: bool,
    /// Nanoseconds per timestamp tick.
    period_ns: f64,
    /// Readback copies a step may time (the readback's most pieces).
    copies: usize,
}

impl Timeline {
    /// The timeline on `dev` of a step with at most `copies` readback copies, or `None` where the
    /// adapter has no timestamp queries.
    pub(crate) fn new(dev: &GpuDevice, copies: usize) -> Option<Self> {
        let features = dev.device.features();
        if !features.contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        let slots = AFTER_PASSES + 1 + copies as u32;
        let set = dev.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("step timeline"),
            ty: wgpu::QueryType::Timestamp,
            count: slots,
        });
        let bytes = 8 * u64::from(slots);
        let buffer = |label, usage| {
            dev.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage,
                mapped_at_creation: false,
            })
        };
        Some(Self {
            set,
            resolved: buffer(
                "step timeline",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            read: buffer(
                "step timeline readback",
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            ),
            copies_timed: features.contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS),
            period_ns: f64::from(dev.queue.get_timestamp_period()),
            copies,
        })
    }

    /// At the start of the step's encoder, before anything is recorded: its timestamp, where
    /// copies are timed.
    pub(crate) fn at_start(&self, enc: &mut wgpu::CommandEncoder) {
        if self.copies_timed {
            enc.write_timestamp(&self.set, START);
        }
    }

    /// The step's compute pass writes its timestamps at its beginning and end.
    pub(crate) fn pass_writes(&self) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(PASSES),
            end_of_pass_write_index: Some(AFTER_PASSES),
        }
    }

    /// After readback copy `k` (`k` below the timeline's `copies`) in `enc`: its timestamp, where copies are
    /// timed.
    pub(crate) fn after_copy(&self, enc: &mut wgpu::CommandEncoder, k: usize) {
        if self.copies_timed && k < self.copies {
            enc.write_timestamp(&self.set, AFTER_PASSES + 1 + k as u32);
        }
    }

    /// At the end of the step's last submit, after its last copy: resolve the timestamps and
    /// copy them where [`Self::read`] maps them.
    pub(crate) fn resolve(&self, enc: &mut wgpu::CommandEncoder) {
        let slots = AFTER_PASSES + 1 + self.copies as u32;
        enc.resolve_query_set(&self.set, 0..slots, &self.resolved, 0);
        enc.copy_buffer_to_buffer(&self.resolved, 0, &self.read, 0, self.read.size());
    }

    /// Read the step's timestamps (its `copies` readback copies done) into `stats`, after the
    /// submit that resolved them.
    pub(crate) fn read(
        &self,
        dev: &GpuDevice,
        copies: usize,
        stats: &mut HostPath,
    ) -> Result<(), SimError> {
        let mut times = None;
        map_and_read(dev, &self.read, self.read.size(), |words| {
            let tick = |i: u32| {
                let i = 2 * i as usize;
                u64::from(words[i]) | (u64::from(words[i + 1]) << 32)
            };
            let seconds = |from: u32, to: u32| {
                tick(to).saturating_sub(tick(from)) as f64 * self.period_ns * 1e-9
            };
            let last_copy = AFTER_PASSES + copies.min(self.copies) as u32;
            let copied = (self.copies_timed && copies > 0)
                .then(|| (seconds(START, PASSES), seconds(AFTER_PASSES, last_copy)));
            times = Some((seconds(PASSES, AFTER_PASSES), copied));
        })?;
        if let Some((passes, copied)) = times {
            stats.timed_reads += 1;
            stats.device_s += passes;
            if let Some((before, readback)) = copied {
                stats.timed_copies += 1;
                stats.before_passes_s += before;
                stats.readback_s += readback;
            }
        }
        Ok(())
    }
}
