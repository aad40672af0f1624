//! A delivered step on the device's clock ([`Timeline`]): GPU timestamps at the start and the end
//! of the step's compute pass and after each of its readback copies, so that the host's wait
//! (`HostPath::wait_s`, the submit to the mapped readback) splits into the passes, the readback
//! copies and what neither explains (submission and wake-up latency, the device idle between
//! the readback's submits). `socnav bench --backend gpu` turns it on for a short run of its own
//! (`Backend::set_step_timeline`); off, a step records no timestamps.

use crate::backend::HostPath;
use crate::error::SimError;

use super::GpuDevice;
use super::kit::map_and_read;
use super::readback::MOST_PIECES;

/// Timestamp 0: the step's compute pass begins; 1: it ends; `2 + k`: readback copy `k` is done.
const AFTER_PASSES: u32 = 1;
const SLOTS: u32 = 2 + MOST_PIECES as u32;

/// The query set and buffers of the step timeline.
pub(crate) struct Timeline {
    set: wgpu::QuerySet,
    /// Where the timestamps are resolved, and the mapped copy of them.
    resolved: wgpu::Buffer,
    read: wgpu::Buffer,
    /// The adapter writes timestamps between commands (`TIMESTAMP_QUERY_INSIDE_ENCODERS`), so
    /// the readback's copies are timed too; else only the passes are.
    copies_timed: bool,
    /// Nanoseconds per timestamp tick.
    period_ns: f64,
}

impl Timeline {
    /// The timeline on `dev`, or `None` where the adapter has no timestamp queries.
    pub(crate) fn new(dev: &GpuDevice) -> Option<Self> {
        let features = dev.device.features();
        if !features.contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        let set = dev.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("step timeline"),
            ty: wgpu::QueryType::Timestamp,
            count: SLOTS,
        });
        let bytes = 8 * u64::from(SLOTS);
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
        })
    }

    /// The step's compute pass writes timestamps 0 and 1 at its beginning and end.
    pub(crate) fn pass_writes(&self) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(0),
            end_of_pass_write_index: Some(AFTER_PASSES),
        }
    }

    /// After readback copy `k` (`k < MOST_PIECES`) in `enc`: its timestamp, where copies are
    /// timed.
    pub(crate) fn after_copy(&self, enc: &mut wgpu::CommandEncoder, k: usize) {
        if self.copies_timed && k < MOST_PIECES {
            enc.write_timestamp(&self.set, AFTER_PASSES + 1 + k as u32);
        }
    }

    /// At the end of the step's last submit, after its last copy: resolve the timestamps and
    /// copy them where [`Self::read`] maps them.
    pub(crate) fn resolve(&self, enc: &mut wgpu::CommandEncoder) {
        enc.resolve_query_set(&self.set, 0..SLOTS, &self.resolved, 0);
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
            let last_copy = AFTER_PASSES + copies.min(MOST_PIECES) as u32;
            let readback =
                (self.copies_timed && copies > 0).then(|| seconds(AFTER_PASSES, last_copy));
            times = Some((seconds(0, AFTER_PASSES), readback));
        })?;
        if let Some((passes, readback)) = times {
            stats.timed_reads += 1;
            stats.device_s += passes;
            if let Some(r) = readback {
                stats.timed_copies += 1;
                stats.readback_s += r;
            }
        }
        Ok(())
    }
}
