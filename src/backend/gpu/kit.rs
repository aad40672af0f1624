//! The device kit every GPU pass builds on: buffers, their bindings to a pass, the checks of
//! their sizes, writes split over threads, and readback. The pipelines and their layouts are
//! `super::pipelines`'.

use super::GpuDevice;
use super::pipelines::Binding;
use crate::error::SimError;

/// Bytes of `n` elements of `T` (at least one element: a binding may not be empty).
pub(crate) fn bytes_of<T>(n: usize) -> u64 {
    (n.max(1) * std::mem::size_of::<T>()) as u64
}

/// `SimError::OutOfMemory` unless `bytes` of `what` fit one buffer and one storage binding of
/// `dev` (`what` names the batch and the data, e.g. "the state's f32 columns of 20000
/// environments").
pub(crate) fn check_binding(dev: &GpuDevice, what: &str, bytes: u64) -> Result<(), SimError> {
    let max = dev
        .limits
        .max_storage_buffer_binding_size
        .min(dev.limits.max_buffer_size);
    if bytes <= max {
        return Ok(());
    }
    Err(SimError::OutOfMemory {
        bytes,
        device: Some(dev.adapter.name.clone()),
        message: format!(
            "{what} need {bytes} bytes in one buffer, more than {} allows in one binding ({max} \
             bytes): use fewer environments",
            dev.adapter.name
        ),
    })
}

/// The device's errors while a batch's buffers and pipelines are made on this thread (wgpu's
/// error scopes are per thread): a batch that does not fit the device's memory fails with
/// `SimError::OutOfMemory`, and no error of its making reaches the device's shared error list,
/// where it would fail the next call of another batch on the same device.
pub(crate) struct CreationScope {
    oom: wgpu::ErrorScopeGuard,
    invalid: wgpu::ErrorScopeGuard,
    adapter: String,
}

impl CreationScope {
    /// Start catching the errors of `dev`'s work on this thread.
    pub(crate) fn push(dev: &GpuDevice) -> Self {
        let oom = dev.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let invalid = dev.device.push_error_scope(wgpu::ErrorFilter::Validation);
        Self {
            oom,
            invalid,
            adapter: dev.adapter.name.clone(),
        }
    }

    /// `built`, unless the device ran out of memory while making it (`OutOfMemory`, with the
    /// `bytes` of the buffers it holds) or reported it invalid (`Device`).
    pub(crate) fn finish<T>(
        self,
        what: &str,
        built: Result<T, SimError>,
        bytes: impl FnOnce(&T) -> u64,
    ) -> Result<T, SimError> {
        // Scopes pop in the reverse order of their pushes.
        let invalid = pollster::block_on(self.invalid.pop());
        let oom = pollster::block_on(self.oom.pop());
        if let Some(e) = oom {
            let bytes = built.as_ref().map_or(0, bytes);
            return Err(SimError::OutOfMemory {
                bytes,
                device: Some(self.adapter.clone()),
                message: format!(
                    "{} is out of memory for {what} ({bytes} bytes of buffers): {e}; use fewer \
                     environments, or free the device's memory (other batches, a trainer's \
                     cached tensors)",
                    self.adapter
                ),
            });
        }
        let built = built?;
        match invalid {
            Some(e) => Err(SimError::Device(format!(
                "the GPU device reported, while making {what}: {e}"
            ))),
            None => Ok(built),
        }
    }
}

/// A storage buffer the host writes and reads back.
pub(crate) fn storage_buffer(dev: &GpuDevice, label: &str, size: u64) -> wgpu::Buffer {
    dev.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

/// Bytes from which a queue write is copied into its staging memory on every thread of a pool
/// ([`write_buffer_split`]): below, one thread's copy costs less than handing it out.
pub(crate) const SPLIT_WRITE_BYTES: usize = 256 << 10;

/// Bytes each thread copies at a time in [`write_buffer_split`].
const SPLIT_WRITE_CHUNK: usize = 64 << 10;

/// `queue.write_buffer(buffer, offset, bytes)`, its copy into wgpu's staging memory split over
/// `pool`'s threads where the write is large ([`SPLIT_WRITE_BYTES`]).
///
/// That staging memory is what wgpu's allocator picks for a buffer the host writes and the
/// device reads: device memory the host can map first (`HOST_VISIBLE | DEVICE_LOCAL`), which
/// on a discrete GPU is written across the bus, uncached, at what one core's stores push
/// through (a few GB/s), where several cores' stores fill more of the bus. A step's actions
/// (exp2 at 65,536 environments: 786 KB, before the step's submit) and its reset-pool rows
/// (about 1.9 MB) are such writes.
pub(crate) fn write_buffer_split(
    dev: &GpuDevice,
    buffer: &wgpu::Buffer,
    offset: u64,
    bytes: &[u8],
    pool: Option<&rayon::ThreadPool>,
) {
    use rayon::prelude::*;
    let (Some(pool), Some(size)) = (
        pool.filter(|_| bytes.len() >= SPLIT_WRITE_BYTES),
        wgpu::BufferSize::new(bytes.len() as u64),
    ) else {
        dev.queue.write_buffer(buffer, offset, bytes);
        return;
    };
    // `None` where the write is invalid: `write_buffer` then reports why, as for a small one.
    let Some(mut view) = dev.queue.write_buffer_with(buffer, offset, size) else {
        dev.queue.write_buffer(buffer, offset, bytes);
        return;
    };
    // Whole chunks as arrays, which (unlike a slice's `WriteOnly`) may go to another thread.
    let (chunks, mut tail) = view.slice(..).into_chunks::<SPLIT_WRITE_CHUNK>();
    let chunks: Vec<wgpu::WriteOnly<'_, [u8; SPLIT_WRITE_CHUNK]>> = chunks.into_iter().collect();
    let (whole, rest) = bytes.split_at(chunks.len() * SPLIT_WRITE_CHUNK);
    pool.install(|| {
        chunks
            .into_par_iter()
            .zip(whole.par_chunks_exact(SPLIT_WRITE_CHUNK))
            .for_each(|(chunk, src)| wgpu::WriteOnly::<'_, [u8]>::from(chunk).copy_from_slice(src));
    });
    tail.copy_from_slice(rest);
}

/// A uniform buffer holding `words`.
pub(crate) fn uniform_buffer(dev: &GpuDevice, label: &str, words: &[u32]) -> wgpu::Buffer {
    let buffer = dev.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes_of::<u32>(words.len()),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    dev.queue
        .write_buffer(&buffer, 0, bytemuck::cast_slice(words));
    buffer
}

/// A bind group of `layout` with `buffers`, whole, at bindings 0, 1, ...
pub(crate) fn bind_buffers(
    dev: &GpuDevice,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let bound: Vec<(&wgpu::Buffer, Binding)> = buffers
        .iter()
        .map(|&b| (b, Binding::Storage { read_only: false }))
        .collect();
    bind_kinds(dev, label, layout, &bound)
}

/// A bind group of `layout` with `bound` at bindings 0, 1, ..., each bound as its kind says
/// ([`Binding::resource`]).
pub(crate) fn bind_kinds(
    dev: &GpuDevice,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    bound: &[(&wgpu::Buffer, Binding)],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry<'_>> = (0u32..)
        .zip(bound)
        .map(|(binding, &(buf, kind))| wgpu::BindGroupEntry {
            binding,
            resource: kind.resource(buf),
        })
        .collect();
    dev.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// Map the first `bytes` of `buffer` (after the work submitted so far), hand its words to
/// `read`, and unmap it; then report any validation error of the device.
pub(crate) fn map_and_read(
    dev: &GpuDevice,
    buffer: &wgpu::Buffer,
    bytes: u64,
    read: impl FnOnce(&[u32]),
) -> Result<(), SimError> {
    map_and_read_after(dev, buffer, bytes, None, read)
}

/// How long a failed readback waits for the submits before it, so that a destroyed device's
/// loss is recorded (`map_and_read_after`): far longer than any one step takes.
const LOST_DEVICE_WAIT: std::time::Duration = std::time::Duration::from_secs(10);

/// [`map_and_read`] waiting only for the submit `after` (with `None`, for the work submitted so
/// far): the submits after it go on while `read` runs.
pub(crate) fn map_and_read_after(
    dev: &GpuDevice,
    buffer: &wgpu::Buffer,
    bytes: u64,
    after: Option<wgpu::SubmissionIndex>,
    read: impl FnOnce(&[u32]),
) -> Result<(), SimError> {
    let failed = |e: &dyn std::fmt::Display| SimError::Device(format!("GPU readback failed: {e}"));
    let slice = buffer.slice(..bytes);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        // The receiver lives until the poll below has delivered this.
        let _ = tx.send(r);
    });
    let waited = dev.device.poll(wgpu::PollType::Wait {
        submission_index: after,
        timeout: None,
    });
    if let Err(e) = waited {
        // A wait for one submit fails before wgpu's maintenance, which is where a destroyed
        // device's loss is recorded (`GpuDevice::lost`, through the lost callback), and only
        // once no submit is in flight: wait for those made before the failure (a step leaves its
        // queued obstacle rebuild running when it returns), for a bounded time, so that the
        // batch's next call says the device was lost.
        let _ = dev.device.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: Some(LOST_DEVICE_WAIT),
        });
        return Err(failed(&e));
    }
    rx.recv().map_err(|e| failed(&e))?.map_err(|e| failed(&e))?;
    {
        let view = slice.get_mapped_range().map_err(|e| failed(&e))?;
        let words = bytemuck::try_cast_slice::<u8, u32>(&view).map_err(|e| failed(&e))?;
        read(words);
    }
    buffer.unmap();
    dev.take_errors()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shared device, or `None` (after saying why) when there is none and none is required
    /// (`REQUIRE_GPU=1`, as CI sets).
    fn device() -> Option<GpuDevice> {
        match GpuDevice::open(super::super::AdapterPolicy::Any) {
            Ok(d) => Some(d),
            Err(e) if std::env::var("REQUIRE_GPU").is_ok_and(|v| v == "1") => {
                panic!("REQUIRE_GPU=1 but no GPU adapter: {e}")
            }
            Err(e) => {
                eprintln!("SKIPPED: no GPU adapter ({e})");
                None
            }
        }
    }

    /// A write split over threads puts every byte where one write puts it: whole chunks and a
    /// tail, at an offset, around bytes it leaves alone; and a write too small to split.
    #[test]
    fn a_write_split_over_threads_lands_as_one_write() {
        let Some(dev) = device() else { return };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        let words = 3 * SPLIT_WRITE_CHUNK / 4 + 17 + SPLIT_WRITE_BYTES / 4;
        let before: Vec<u32> = vec![0xDEAD_BEEF; words + 2];
        let buffer = dev.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("split write"),
            size: bytes_of::<u32>(before.len()),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = dev.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("split write readback"),
            size: bytes_of::<u32>(before.len()),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let read = || {
            let mut enc = dev.device.create_command_encoder(&Default::default());
            enc.copy_buffer_to_buffer(&buffer, 0, &readback, 0, readback.size());
            dev.queue.submit([enc.finish()]);
            let mut got = Vec::new();
            map_and_read(&dev, &readback, readback.size(), |w| got = w.to_vec()).unwrap();
            got
        };
        for (len, threads) in [(words, Some(&pool)), (words, None), (100, Some(&pool))] {
            dev.queue
                .write_buffer(&buffer, 0, bytemuck::cast_slice(&before));
            let data: Vec<u32> = (0..len as u32)
                .map(|k| k.wrapping_mul(2_654_435_761))
                .collect();
            write_buffer_split(&dev, &buffer, 4, bytemuck::cast_slice(&data), threads);
            let mut want = before.clone();
            want[1..=len].copy_from_slice(&data);
            assert_eq!(
                read(),
                want,
                "{len} words, {} threads",
                threads.map_or(0, |p| p.current_num_threads())
            );
        }
    }
}
