//! The compiled compute pipelines a device keeps for the whole process ([`PipelineCache`]), the
//! bind group layouts they are compiled against ([`Binding`]), and the shader modules they are
//! built from ([`shader_module`]: socnav's own SPIR-V, or the WGSL through wgpu).
//!
//! A shader's text holds no batch size and, through `backend::wgsl::SizeClasses`, the same text
//! serves every shipped config; a pipeline is therefore compiled once per device and source, and
//! every later batch on that device (another size, another config of the same size classes)
//! reuses it. Across processes, wgpu's pipeline cache keeps what the driver compiled where the
//! backend offers one (Vulkan: [`DiskCache`], a file per adapter in socnav's cache directory), and
//! so do the drivers' own shader caches (Mesa's on lavapipe, the vendor's on a real GPU).
//!
//! The device that owns the cache (`device::GpuDevice`) is reached through [`Compiler`], so this
//! module sits below it.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use super::spirv::{BufferBounds, Contraction};
use crate::error::SimError;

/// What building shaders and pipelines needs of a device: `device::GpuDevice`, which owns the
/// device's [`PipelineCache`], is the one implementation.
pub(crate) trait Compiler {
    /// The wgpu device the pipelines are compiled on.
    fn wgpu(&self) -> &wgpu::Device;
    /// How shaders are built from socnav's own SPIR-V (`super::spirv`): its buffer bounds and
    /// whether products and sums may fuse; `None` where they are built from the WGSL through wgpu.
    fn own_spirv(&self) -> Option<(BufferBounds, Contraction)>;
    /// The errors the device reported since the last call, as one error that says how pipeline
    /// `label` was built and which setting builds it otherwise.
    fn pipeline_errors(&self, label: &str) -> Result<(), SimError>;
}

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

impl From<crate::backend::wgsl::Access> for Binding {
    /// The binding kind of a binding declared with `access` (`backend::wgsl::BATCH_BINDINGS`).
    fn from(access: crate::backend::wgsl::Access) -> Self {
        use crate::backend::wgsl::Access;
        match access {
            Access::Read => Self::Storage { read_only: true },
            Access::ReadWrite => Self::Storage { read_only: false },
            Access::Uniform => Self::Uniform,
            Access::DynamicUniform => Self::DynamicUniform,
        }
    }
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
fn group_layout(dev: &dyn Compiler, bindings: &[Binding]) -> wgpu::BindGroupLayout {
    let entries: Vec<wgpu::BindGroupLayoutEntry> = (0u32..)
        .zip(bindings)
        .map(|(binding, kind)| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: kind.ty(),
            count: None,
        })
        .collect();
    dev.wgpu()
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
        dev: &dyn Compiler,
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
                    .wgpu()
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
        dev: &dyn Compiler,
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
            .wgpu()
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: self.disk.as_ref().map(|d| &d.cache),
            });
        dev.pipeline_errors(label)?;
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
        dev: &dyn Compiler,
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
    dev: &dyn Compiler,
    label: &str,
    source: &str,
    entry: &str,
) -> Result<wgpu::ShaderModule, SimError> {
    let Some((buffers, contraction)) = dev.own_spirv() else {
        return Ok(dev
            .wgpu()
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            }));
    };
    let words = super::spirv::compute_spirv(source, entry, buffers, contraction)
        .map_err(|e| SimError::Internal(format!("shader {label}, entry point {entry}: {e}")))?;
    let desc =
        super::spirv::passthrough(label, entry, crate::backend::wgsl::WORKGROUP_SIZE, &words);
    // SAFETY: the words are naga's SPIR-V of a module naga validated, written with the bounds
    // checks and loop bounding wgpu would add; the changes leave variables uninitialised that the
    // shaders write before they read (`spirv::without_zero_initialisers`) and forbid fusing
    // arithmetic (`spirv::without_contraction`), which changes no memory access.
    Ok(unsafe { dev.wgpu().create_shader_module_passthrough(desc) })
}
