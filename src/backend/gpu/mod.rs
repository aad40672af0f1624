//! The GPU backend (in construction; issue 4): the batch state in device storage buffers and the
//! stages of [`crate::pipeline::STAGES`] as WGSL compute shaders (`shaders/<stage>.wgsl`).
//!
//! What exists so far:
//! - [`device`]: finding and opening an adapter under the policy of DESIGN.md section 8.
//! - [`GpuStages`]: the state packed into two storage buffers (every f32 column back to back,
//!   every u32 column likewise, in declaration order; offsets and strides reach the shaders as
//!   generated constants, [`crate::backend::wgsl::prelude`]), the step parameters and the actions,
//!   and one compute pipeline per stage shader, built once. It runs single stages, which is what
//!   the CPU/GPU parity tests of each stage need (`tests/gpu_stages.rs`).
//!
//! Still to build before `--backend gpu` can step a batch: the shaders of the other stages, the
//! output buffers and their per-step readback, and resets off the host's critical path.

pub mod device;

pub use device::{AdapterPolicy, AdapterSummary, GpuDevice, list_adapters};

use crate::backend::wgsl;
use crate::error::SimError;
use crate::params::StepParams;
use crate::state::BatchState;

/// The stages that have a shader so far, in [`crate::pipeline::STAGES`] order.
pub const STAGES_WITH_SHADERS: &[&str] = &["robot_motion"];

/// A batch's state, parameters and actions on the device, and a pipeline per stage shader.
pub struct GpuStages {
    dev: GpuDevice,
    n_envs: usize,
    sf: wgpu::Buffer,
    su: wgpu::Buffer,
    actions: wgpu::Buffer,
    readback: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    pipelines: Vec<(&'static str, wgpu::ComputePipeline)>,
    packed_f32: Vec<f32>,
    packed_u32: Vec<u32>,
}

impl std::fmt::Debug for GpuStages {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuStages")
            .field("adapter", &self.dev.adapter)
            .field("n_envs", &self.n_envs)
            .finish_non_exhaustive()
    }
}

fn bytes_of<T>(n: usize) -> u64 {
    // A binding may not be empty: at least one element.
    (n.max(1) * std::mem::size_of::<T>()) as u64
}

impl GpuStages {
    /// Upload `state` and `params` and build the pipelines of `stages` (names from
    /// [`STAGES_WITH_SHADERS`]).
    pub fn new(
        dev: GpuDevice,
        params: &StepParams,
        state: &BatchState,
        stages: &[&'static str],
    ) -> Result<Self, SimError> {
        let n_envs = state.n_envs;
        let (mut packed_f32, mut packed_u32) = (Vec::new(), Vec::new());
        state.pack(&mut packed_f32, &mut packed_u32);
        let max = dev.limits.max_storage_buffer_binding_size;
        for (what, bytes) in [
            ("f32 state columns", bytes_of::<f32>(packed_f32.len())),
            ("u32 state columns", bytes_of::<u32>(packed_u32.len())),
        ] {
            if bytes > max {
                return Err(SimError::BackendUnavailable(format!(
                    "{n_envs} environments need {bytes} bytes of {what}, more than {} allows in \
                     one binding ({max} bytes): use fewer environments",
                    dev.adapter.name
                )));
            }
        }
        let storage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC;
        let buffer = |label: &str, size: u64| {
            dev.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: storage,
                mapped_at_creation: false,
            })
        };
        let params_buf = buffer("step params", std::mem::size_of::<StepParams>() as u64);
        dev.queue
            .write_buffer(&params_buf, 0, bytemuck::bytes_of(params));
        let sf = buffer("state f32", bytes_of::<f32>(packed_f32.len()));
        let su = buffer("state u32", bytes_of::<u32>(packed_u32.len()));
        let actions = buffer("actions", bytes_of::<f32>(3 * n_envs));
        let readback = dev.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: bytes_of::<u32>(packed_f32.len().max(packed_u32.len())),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let entry = |binding: u32, read_only: bool| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = dev
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("stage bindings"),
                entries: &[
                    entry(0, true),
                    entry(1, false),
                    entry(2, false),
                    entry(3, true),
                ],
            });
        let bind_group = dev.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("stage bindings"),
            layout: &layout,
            entries: &[(0, &params_buf), (1, &sf), (2, &su), (3, &actions)].map(
                |(binding, buf)| wgpu::BindGroupEntry {
                    binding,
                    resource: buf.as_entire_binding(),
                },
            ),
        });
        let pipeline_layout = dev
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("stages"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
        let prelude = wgsl::prelude(n_envs, &state.columns());
        let mut pipelines = Vec::new();
        for &stage in stages {
            if !STAGES_WITH_SHADERS.contains(&stage) {
                return Err(SimError::BackendUnavailable(format!(
                    "stage {stage:?} has no shader yet (stages with shaders: {STAGES_WITH_SHADERS:?})"
                )));
            }
            let src = wgsl::assemble(stage, &prelude).map_err(SimError::BackendUnavailable)?;
            let module = dev
                .device
                .create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some(stage),
                    source: wgpu::ShaderSource::Wgsl(src.into()),
                });
            let pipeline = dev
                .device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(stage),
                    layout: Some(&pipeline_layout),
                    module: &module,
                    entry_point: Some("main"),
                    compilation_options: Default::default(),
                    cache: None,
                });
            dev.take_errors()?;
            pipelines.push((stage, pipeline));
        }
        let mut this = Self {
            dev,
            n_envs,
            sf,
            su,
            actions,
            readback,
            bind_group,
            pipelines,
            packed_f32,
            packed_u32,
        };
        this.write_packed();
        Ok(this)
    }

    /// The adapter the stages run on.
    pub fn adapter(&self) -> &AdapterSummary {
        &self.dev.adapter
    }

    fn write_packed(&mut self) {
        let q = &self.dev.queue;
        q.write_buffer(&self.sf, 0, bytemuck::cast_slice(&self.packed_f32));
        q.write_buffer(&self.su, 0, bytemuck::cast_slice(&self.packed_u32));
    }

    /// Replace the device's state with `state` (same batch size and capacities).
    pub fn upload_state(&mut self, state: &BatchState) {
        self.packed_f32.clear();
        self.packed_u32.clear();
        state.pack(&mut self.packed_f32, &mut self.packed_u32);
        self.write_packed();
    }

    /// Set the actions of the next stages: 3 floats per environment.
    pub fn upload_actions(&mut self, actions: &[f32]) {
        assert_eq!(actions.len(), 3 * self.n_envs, "3 actions per environment");
        self.dev
            .queue
            .write_buffer(&self.actions, 0, bytemuck::cast_slice(actions));
    }

    /// Run stage `stage` over every environment (one dispatch, one submit).
    pub fn run(&mut self, stage: &str) -> Result<(), SimError> {
        let Some((_, pipeline)) = self.pipelines.iter().find(|(s, _)| *s == stage) else {
            return Err(SimError::BackendUnavailable(format!(
                "stage {stage:?} was not built for this batch"
            )));
        };
        let mut enc = self
            .dev
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(stage) });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(stage),
                timestamp_writes: None,
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            pass.dispatch_workgroups((self.n_envs as u32).div_ceil(wgsl::WORKGROUP_SIZE), 1, 1);
        }
        self.dev.queue.submit([enc.finish()]);
        self.dev.take_errors()
    }

    /// Read the device's state back into `state` (same batch size and capacities).
    pub fn download_state(&mut self, state: &mut BatchState) -> Result<(), SimError> {
        let (nf, nu) = (self.packed_f32.len(), self.packed_u32.len());
        let f = self.read_words(&self.sf, nf)?;
        self.packed_f32.copy_from_slice(bytemuck::cast_slice(&f));
        let u = self.read_words(&self.su, nu)?;
        self.packed_u32.copy_from_slice(&u);
        state.unpack(&self.packed_f32, &self.packed_u32);
        Ok(())
    }

    /// The first `n` 32-bit words of `src`.
    fn read_words(&self, src: &wgpu::Buffer, n: usize) -> Result<Vec<u32>, SimError> {
        let bytes = (n * 4) as u64;
        let mut enc = self
            .dev
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("readback"),
            });
        enc.copy_buffer_to_buffer(src, 0, &self.readback, 0, bytes);
        self.dev.queue.submit([enc.finish()]);
        let slice = self.readback.slice(..bytes);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            // The receiver lives until the poll below has delivered this.
            let _ = tx.send(r);
        });
        self.dev
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| SimError::BackendUnavailable(format!("GPU readback failed: {e}")))?;
        rx.recv()
            .map_err(|e| SimError::BackendUnavailable(format!("GPU readback failed: {e}")))?
            .map_err(|e| SimError::BackendUnavailable(format!("GPU readback failed: {e}")))?;
        let words = {
            let view = slice
                .get_mapped_range()
                .map_err(|e| SimError::BackendUnavailable(format!("GPU readback failed: {e}")))?;
            bytemuck::cast_slice::<u8, u32>(&view).to_vec()
        };
        self.readback.unmap();
        self.dev.take_errors()?;
        Ok(words)
    }
}
