//! The device kit every GPU pass builds on: buffers, bind group layouts, readback, and the
//! compiled pipelines a device keeps for the whole process ([`PipelineCache`]).
//!
//! A shader's text holds no batch size and, through `backend::wgsl::SizeClasses`, the same text
//! serves most configs; a pipeline is therefore compiled once per device and source, and every
//! later batch on that device (another size, another config of the same size classes) reuses it.
//! Across processes, the driver's own shader cache (Mesa's on lavapipe, the vendor's on a real
//! GPU) keeps what it compiled.

use std::collections::HashMap;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

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
}

impl Binding {
    fn ty(self) -> wgpu::BindingType {
        let ty = match self {
            Self::Storage { read_only } => wgpu::BufferBindingType::Storage { read_only },
            Self::Uniform => wgpu::BufferBindingType::Uniform,
        };
        wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
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
    pipelines: Mutex<HashMap<PipelineKey, wgpu::ComputePipeline>>,
    builds: AtomicUsize,
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
        if let Some(p) = lock(&self.pipelines).get(&key) {
            return Ok((p.clone(), false));
        }
        let (_, layout) = self.layout(dev, groups);
        let module = dev
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            });
        let pipeline = dev
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            });
        dev.take_errors()?;
        self.builds.fetch_add(1, Ordering::Relaxed);
        // Two threads may have compiled the same source at once: either result serves.
        Ok((
            lock(&self.pipelines).entry(key).or_insert(pipeline).clone(),
            true,
        ))
    }

    /// Pipelines compiled so far.
    pub(crate) fn builds(&self) -> usize {
        self.builds.load(Ordering::Relaxed)
    }
}

/// Bytes of `n` elements of `T` (at least one element: a binding may not be empty).
pub(crate) fn bytes_of<T>(n: usize) -> u64 {
    (n.max(1) * std::mem::size_of::<T>()) as u64
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
    let entries: Vec<wgpu::BindGroupEntry<'_>> = (0u32..)
        .zip(buffers)
        .map(|(binding, buf)| wgpu::BindGroupEntry {
            binding,
            resource: buf.as_entire_binding(),
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
    let failed = |e: &dyn std::fmt::Display| {
        SimError::BackendUnavailable(format!("GPU readback failed: {e}"))
    };
    let slice = buffer.slice(..bytes);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        // The receiver lives until the poll below has delivered this.
        let _ = tx.send(r);
    });
    dev.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| failed(&e))?;
    rx.recv().map_err(|e| failed(&e))?.map_err(|e| failed(&e))?;
    {
        let view = slice.get_mapped_range().map_err(|e| failed(&e))?;
        let words = bytemuck::try_cast_slice::<u8, u32>(&view).map_err(|e| failed(&e))?;
        read(words);
    }
    buffer.unmap();
    dev.take_errors()
}
