//! The device kit every GPU pass builds on: buffers, bind group layouts, readback, and the
//! compiled pipelines a device keeps for the whole process ([`PipelineCache`]).
//!
//! A shader's text holds no batch size and, through `backend::wgsl::SizeClasses`, the same text
//! serves every shipped config; a pipeline is therefore compiled once per device and source, and every
//! later batch on that device (another size, another config of the same size classes) reuses it.
//! Across processes, wgpu's pipeline cache keeps what the driver compiled where the backend
//! offers one (Vulkan: [`DiskCache`], a file per adapter in socnav's cache directory), and so do
//! the drivers' own shader caches (Mesa's on lavapipe, the vendor's on a real GPU).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use super::GpuDevice;
use crate::error::SimError;

/// The kind of one binding of a bind group layout (bindings are numbered 0, 1, ... in order).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum Binding {
    /// A storage buffer, read-only or read-write.
    Storage {
        /// Whether the shaders only read it.
        read_only: bool,
    },
    /// A uniform buffer.
    Uniform,
    /// A uniform of [`DYNAMIC_UNIFORM_BYTES`] at an offset given with each `set_bind_group`.
    DynamicUniform,
}

/// Bytes of a [`Binding::DynamicUniform`] (a `vec4<u32>`).
pub(crate) const DYNAMIC_UNIFORM_BYTES: u64 = 16;

impl Binding {
    fn ty(self) -> wgpu::BindingType {
        let (ty, has_dynamic_offset) = match self {
            Self::Storage { read_only } => (wgpu::BufferBindingType::Storage { read_only }, false),
            Self::Uniform => (wgpu::BufferBindingType::Uniform, false),
            Self::DynamicUniform => (wgpu::BufferBindingType::Uniform, true),
        };
        wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset,
            min_binding_size: None,
        }
    }

    /// What binds `buffer` as this kind of binding: the whole buffer, or a dynamic uniform's
    /// window.
    pub(crate) fn resource(self, buffer: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
        match self {
            Self::DynamicUniform => wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                buffer,
                offset: 0,
                size: wgpu::BufferSize::new(DYNAMIC_UNIFORM_BYTES),
            }),
            Self::Storage { .. } | Self::Uniform => buffer.as_entire_binding(),
        }
    }
}

/// Storage bindings, read-only where `read_only` says so.
pub(crate) fn storage_bindings(read_only: &[bool]) -> Vec<Binding> {
    read_only
        .iter()
        .map(|&read_only| Binding::Storage { read_only })
        .collect()
}

/// The bind groups of a pipeline layout: group 0, 1, ..., each a list of bindings.
pub(crate) type Groups = Vec<Vec<Binding>>;

/// What a compiled pipeline is found by: its bind groups, its WGSL source and its entry point.
type PipelineKey = (Groups, String, String);

/// The compiled compute pipelines of one device, shared by every batch that uses it, with the
/// bind group and pipeline layouts they were compiled against.
#[derive(Default)]
pub(crate) struct PipelineCache {
    layouts: Mutex<HashMap<Groups, (Vec<wgpu::BindGroupLayout>, wgpu::PipelineLayout)>>,
    /// Each pipeline behind a lock of its own, held while it compiles: a thread asking for a
    /// pipeline another thread is compiling waits for it instead of compiling it again.
    pipelines: Mutex<HashMap<PipelineKey, Arc<Mutex<Option<wgpu::ComputePipeline>>>>>,
    builds: AtomicUsize,
    disk: Option<DiskCache>,
}

/// Environment variable that turns the pipeline cache file off (`0`).
pub const PIPELINE_CACHE_ENV: &str = "SOCNAV_PIPELINE_CACHE";

/// wgpu's pipeline cache of one device, kept in a file so that the next process on the same
/// machine and adapter starts from what this one compiled: `pipelines/<key>` in socnav's cache
/// directory (`sngnn::cache_dir`), `<key>` being wgpu's name for the adapter
/// (`wgpu::util::pipeline_cache_key`: vendor and device). Only Vulkan offers one; wgpu checks
/// that a file's data came from the same adapter, driver and wgpu version, and otherwise starts
/// empty. Writing is best effort: a failed write costs the next process its compiles, nothing
/// else.
pub(crate) struct DiskCache {
    cache: wgpu::PipelineCache,
    path: PathBuf,
}

impl DiskCache {
    /// The cache of `device` (opened with the features `features`) on the adapter `info`, loaded
    /// from its file if there is one; `None` where the backend has no pipeline cache or
    /// `SOCNAV_PIPELINE_CACHE=0`.
    pub(crate) fn open(
        device: &wgpu::Device,
        features: wgpu::Features,
        info: &wgpu::AdapterInfo,
    ) -> Option<Self> {
        if std::env::var(PIPELINE_CACHE_ENV).is_ok_and(|v| v == "0")
            || !features.contains(wgpu::Features::PIPELINE_CACHE)
        {
            return None;
        }
        let path = crate::sngnn::cache_dir()
            .join("pipelines")
            .join(wgpu::util::pipeline_cache_key(info)?);
        let data = std::fs::read(&path).ok();
        let cache = create_pipeline_cache(device, data.as_deref());
        Some(Self { cache, path })
    }

    /// Write the cache's data to its file (through a temporary file in the same directory, so
    /// that a reader never sees half a file).
    fn save(&self) {
        let Some(data) = self.cache.get_data() else {
            return;
        };
        let write = |path: &Path| -> std::io::Result<()> {
            let dir = path.parent().unwrap_or(Path::new("."));
            std::fs::create_dir_all(dir)?;
            let temp = path.with_extension(format!("{}.tmp", std::process::id()));
            std::fs::write(&temp, &data)?;
            std::fs::rename(&temp, path)
        };
        // Best effort (see the type's docs): a read-only cache directory is not an error.
        let _ = write(&self.path);
    }
}

/// wgpu's pipeline cache of `device`, started from `data`.
#[expect(
    unsafe_code,
    reason = "wgpu::Device::create_pipeline_cache is unsafe; sound here, see below"
)]
fn create_pipeline_cache(device: &wgpu::Device, data: Option<&[u8]>) -> wgpu::PipelineCache {
    // SAFETY: `data` is what `PipelineCache::get_data` returned in an earlier process (the only
    // writer of the file is `DiskCache::save`). wgpu validates the data's header (magic, wgpu
    // version, backend, adapter and driver, size, checksum) before handing it to the driver, and
    // with `fallback` it starts an empty cache when the data does not match.
    unsafe {
        device.create_pipeline_cache(&wgpu::PipelineCacheDescriptor {
            label: Some("socnav pipelines"),
            data,
            fallback: true,
        })
    }
}

/// A lock that survives a panic elsewhere (the maps stay consistent: each insert is one call).
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// The bind group layout of `bindings`, numbered 0, 1, ...
fn group_layout(dev: &GpuDevice, bindings: &[Binding]) -> wgpu::BindGroupLayout {
    let entries: Vec<wgpu::BindGroupLayoutEntry> = (0u32..)
        .zip(bindings)
        .map(|(binding, kind)| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: kind.ty(),
            count: None,
        })
        .collect();
    dev.device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("socnav bindings"),
            entries: &entries,
        })
}

impl PipelineCache {
    /// An empty cache, backed by `disk` where the device has one.
    pub(crate) fn new(disk: Option<DiskCache>) -> Self {
        Self {
            disk,
            ..Self::default()
        }
    }

    /// The file wgpu's pipeline cache is kept in, where the device has one.
    pub(crate) fn disk_path(&self) -> Option<&Path> {
        self.disk.as_ref().map(|d| d.path.as_path())
    }

    /// The bind group layouts of `groups` and the pipeline layout of them all, made once per
    /// device.
    pub(crate) fn layout(
        &self,
        dev: &GpuDevice,
        groups: &[Vec<Binding>],
    ) -> (Vec<wgpu::BindGroupLayout>, wgpu::PipelineLayout) {
        let mut layouts = lock(&self.layouts);
        layouts
            .entry(groups.to_vec())
            .or_insert_with(|| {
                let bind: Vec<wgpu::BindGroupLayout> =
                    groups.iter().map(|g| group_layout(dev, g)).collect();
                let refs: Vec<Option<&wgpu::BindGroupLayout>> = bind.iter().map(Some).collect();
                let pipeline = dev
                    .device
                    .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                        label: Some("socnav pipelines"),
                        bind_group_layouts: &refs,
                        immediate_size: 0,
                    });
                (bind, pipeline)
            })
            .clone()
    }

    /// The pipeline of entry point `entry` of WGSL `source` over bind groups `groups`, compiled
    /// on the first request and shared afterwards; `label` names it in wgpu's errors. With it,
    /// whether this call compiled it.
    pub(crate) fn pipeline(
        &self,
        dev: &GpuDevice,
        label: &str,
        groups: &[Vec<Binding>],
        source: &str,
        entry: &str,
    ) -> Result<(wgpu::ComputePipeline, bool), SimError> {
        let key = (groups.to_vec(), source.to_owned(), entry.to_owned());
        let slot = Arc::clone(lock(&self.pipelines).entry(key).or_default());
        let mut slot = lock(&slot);
        if let Some(p) = slot.as_ref() {
            return Ok((p.clone(), false));
        }
        let (_, layout) = self.layout(dev, groups);
        let module = shader_module(dev, label, source, entry)?;
        let pipeline = dev
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: self.disk.as_ref().map(|d| &d.cache),
            });
        dev.take_errors().map_err(|e| match e {
            SimError::Device(msg) if dev.own_spirv => SimError::Device(format!(
                "{msg} (pipeline {label} built from socnav's SPIR-V; {}=wgsl builds it from \
                 the WGSL through wgpu instead, and {}=lane takes a software adapter's paths)",
                super::device::SHADERS_VAR,
                super::device::PATHS_VAR
            )),
            SimError::Device(msg) => SimError::Device(format!(
                "{msg} (pipeline {label}; {}=lane takes a software adapter's paths)",
                super::device::PATHS_VAR
            )),
            e => e,
        })?;
        self.builds.fetch_add(1, Ordering::Relaxed);
        if let Some(disk) = &self.disk {
            disk.save();
        }
        *slot = Some(pipeline.clone());
        Ok((pipeline, true))
    }

    /// [`Self::pipeline`] of a pass with one bind group (`group`), with that group's layout, for
    /// the pass's bind group: the pipeline, the layout, and whether this call compiled it.
    pub(crate) fn one_group_pipeline(
        &self,
        dev: &GpuDevice,
        label: &str,
        group: Vec<Binding>,
        source: &str,
    ) -> Result<(wgpu::ComputePipeline, wgpu::BindGroupLayout, bool), SimError> {
        let groups = [group];
        let (pipeline, compiled) = self.pipeline(dev, label, &groups, source, "main")?;
        let (mut layouts, _) = self.layout(dev, &groups);
        Ok((pipeline, layouts.swap_remove(0), compiled))
    }

    /// Pipelines compiled so far.
    pub(crate) fn builds(&self) -> usize {
        self.builds.load(Ordering::Relaxed)
    }
}

/// The shader module of entry point `entry` of WGSL `source`: from the backend's own SPIR-V
/// where the device takes it ([`super::spirv`]), else from the WGSL through wgpu.
#[expect(
    unsafe_code,
    reason = "wgpu::Device::create_shader_module_passthrough is unsafe; sound here, see below"
)]
pub(crate) fn shader_module(
    dev: &GpuDevice,
    label: &str,
    source: &str,
    entry: &str,
) -> Result<wgpu::ShaderModule, SimError> {
    if !dev.own_spirv {
        return Ok(dev
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            }));
    }
    let buffers = if dev.driver_checks_buffers {
        super::spirv::BufferBounds::Driver
    } else {
        super::spirv::BufferBounds::Clamped
    };
    let words = super::spirv::compute_spirv(source, entry, buffers, dev.contraction)
        .map_err(|e| SimError::Internal(format!("shader {label}, entry point {entry}: {e}")))?;
    let desc =
        super::spirv::passthrough(label, entry, crate::backend::wgsl::WORKGROUP_SIZE, &words);
    // SAFETY: the words are naga's SPIR-V of a module naga validated, written with the bounds
    // checks and loop bounding wgpu would add; the changes leave variables uninitialised that the
    // shaders write before they read (`spirv::without_zero_initialisers`) and forbid fusing
    // arithmetic (`spirv::without_contraction`), which changes no memory access.
    Ok(unsafe { dev.device.create_shader_module_passthrough(desc) })
}

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
