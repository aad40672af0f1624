//! SNGNN-v2 inference on the device: [`GpuNet`] scores a batch of graphs packed per environment
//! ([`PackedLayout`]) with `shaders/sngnn_score.wgsl`, the twin of [`Tables::forward`].
//!
//! One forward is one submit: a dispatch that sorts each environment's edges by destination
//! (stable, so build order is kept), then one dispatch per layer with one invocation per
//! (environment, node, output), which sums its messages in the CPU's order; lavapipe therefore
//! computes the CPU's bits. Each layer's tables live in their own buffers (the first layer's
//! are the largest: 54 of 88 MB for exp1/exp2), so one binding never has to hold all of them.
//!
//! An environment whose graph has no nodes is not scored: the GPU backend's step empties the
//! graphs of the environments its reward does not score this step, and their outputs are left
//! as they were. The device has no edge network: an edge the tables do not cover makes
//! [`GpuNet::forward`] (and the step) fail with `SimError::Sngnn` (the CPU would take the edge
//! network). The tables of [`crate::sngnn::table_range`] cover every distance of the config's rooms.
//!
//! A net built by [`GpuNet::new`] owns its graph and output buffers (tests, benchmarks); the GPU
//! backend's step builds one with `GpuNet::in_step` over its own packed graphs, writing the
//! room node's first output straight into a state column, and records it in the step's compute
//! pass (`GpuNet::record`).

use super::kit::{
    CreationScope, bind_buffers, bytes_of, check_binding, map_and_read, storage_buffer,
};
use super::pipelines::{Binding, storage_bindings};
use super::{AdapterSummary, GpuDevice};
use crate::backend::wgsl;
use crate::backend::wgsl::sngnn_status::{
    BAD_GRAPH as STATUS_BAD_GRAPH, EMPTY as STATUS_EMPTY, UNSUPPORTED as STATUS_UNSUPPORTED,
};
use crate::error::SimError;
use crate::sngnn::model::{MAX_WIDTH, Model, Output};
use crate::sngnn::packed::PackedLayout;
use crate::sngnn::pieces::Tables;

/// Invocations per workgroup of both entry points.
const WORKGROUP: u32 = 64;
/// Storage bindings of the shader, in order: params, graph u32, graph f32, CSR, table floats,
/// table index, h in, h out, outputs, status; `true` where read-only.
const BINDINGS: [bool; 10] = [
    true, true, true, false, true, true, true, false, false, false,
];

/// A layer's constants, `NetParams` in the shader (same order; `max_dist` as bits).
#[derive(Debug, Clone, Copy)]
struct LayerParams {
    inputs: usize,
    outputs: usize,
    relu: bool,
    h_in_stride: usize,
    bias: usize,
    last: bool,
}

/// Where the last layer writes the room node's outputs: `outputs` values (1 or 2) of
/// environment e from float `at + e·stride` of the output buffer on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct ScoreTarget {
    at: usize,
    stride: usize,
    outputs: usize,
}

/// The buffers a GPU step shares with its net (`GpuNet::in_step`).
#[derive(Debug)]
pub(crate) struct StepBuffers {
    /// The packed graphs: u32 regions, f32 regions.
    pub buffers: [wgpu::Buffer; 2],
    /// The buffer the scores go to (the state's f32 columns).
    pub scores: wgpu::Buffer,
    /// Float offset of environment 0's score in it.
    pub score_at: usize,
}

/// A net's graph inputs and output.
struct Io {
    graphs: [wgpu::Buffer; 2],
    q: wgpu::Buffer,
    target: ScoreTarget,
}

/// Both outputs of every environment, back to back, in a buffer of the net's own.
const OWN_OUTPUTS: ScoreTarget = ScoreTarget {
    at: 0,
    stride: 2,
    outputs: 2,
};

/// SNGNN-v2 on a device for a batch of `n_envs` graphs of one layout: buffers, pipelines and
/// bind groups built once.
pub struct GpuNet {
    dev: GpuDevice,
    layout: PackedLayout,
    n_envs: usize,
    target: ScoreTarget,
    graph_u32: wgpu::Buffer,
    graph_f32: wgpu::Buffer,
    q: wgpu::Buffer,
    status: wgpu::Buffer,
    readback: wgpu::Buffer,
    sort: wgpu::ComputePipeline,
    layer: wgpu::ComputePipeline,
    /// How many of `sort` and `layer` this net compiled rather than found on its device.
    compiled: usize,
    /// Per layer: its bind group and the workgroups along x.
    groups: Vec<(wgpu::BindGroup, u32)>,
}

impl std::fmt::Debug for GpuNet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuNet")
            .field("adapter", &self.dev.adapter)
            .field("layout", &self.layout)
            .field("n_envs", &self.n_envs)
            .finish_non_exhaustive()
    }
}

/// `BackendUnavailable` unless a batch of `n_envs` fits one dispatch dimension of `dev`.
fn check_batch(dev: &GpuDevice, n_envs: usize) -> Result<(), SimError> {
    let max_groups = dev.limits.max_compute_workgroups_per_dimension as usize;
    if n_envs == 0 || n_envs > max_groups {
        return Err(SimError::BackendUnavailable(format!(
            "SNGNN-v2 on {} scores 1 to {max_groups} environments per batch, not {n_envs}",
            dev.adapter.name
        )));
    }
    Ok(())
}

/// A storage buffer holding `data`, after checking that it fits.
fn filled_buffer<T: bytemuck::Pod>(
    dev: &GpuDevice,
    what: &str,
    data: &[T],
) -> Result<wgpu::Buffer, SimError> {
    let bytes = bytes_of::<T>(data.len());
    check_binding(dev, &format!("SNGNN-v2's {what}"), bytes)?;
    let buffer = storage_buffer(dev, what, bytes);
    dev.queue
        .write_buffer(&buffer, 0, bytemuck::cast_slice(data));
    Ok(buffer)
}

/// An empty storage buffer of `n` elements of `T`, after checking that it fits.
fn empty_buffer<T>(dev: &GpuDevice, what: &str, n: usize) -> Result<wgpu::Buffer, SimError> {
    let bytes = bytes_of::<T>(n);
    check_binding(dev, &format!("SNGNN-v2's {what}"), bytes)?;
    Ok(storage_buffer(dev, what, bytes))
}

#[expect(
    clippy::expect_used,
    reason = "sizes are checked against the adapter's binding limits, which are u32"
)]
fn word(n: usize) -> u32 {
    u32::try_from(n).expect("SNGNN-v2 sizes fit in 32 bits (checked against the buffer limits)")
}

impl GpuNet {
    /// The network of `model` with `tables` on `dev`, for `n_envs` graphs packed in `layout`,
    /// with graph and output buffers of its own ([`GpuNet::upload`], [`GpuNet::forward`]).
    ///
    /// # Errors
    /// `SimError::OutOfMemory` when a buffer exceeds the adapter's limits or memory (the tables'
    /// largest layer is about 54 MB), there are more environments than one dispatch dimension
    /// holds, or the shader fails to build.
    pub fn new(
        dev: GpuDevice,
        model: &Model,
        tables: &Tables,
        layout: PackedLayout,
        n_envs: usize,
    ) -> Result<Self, SimError> {
        check_batch(&dev, n_envs)?;
        let graphs = [
            empty_buffer::<u32>(&dev, "packed graphs", n_envs * layout.u32_stride())?,
            empty_buffer::<f32>(&dev, "packed graphs", n_envs * layout.f32_stride())?,
        ];
        let io = Io {
            graphs,
            q: empty_buffer::<f32>(&dev, "outputs", 2 * n_envs)?,
            target: OWN_OUTPUTS,
        };
        Self::build(dev, model, tables, layout, n_envs, io)
    }

    /// The network of a GPU step: it scores the packed graphs of `n_envs` environments in
    /// `graphs.buffers` (u32 and f32 regions at `layout`'s strides) and writes the room node's
    /// first output of environment e to float `graphs.score_at + e` of `graphs.scores` (a state
    /// column); environments whose graph has no nodes are skipped. `GpuNet::record` puts it
    /// in a compute pass.
    ///
    /// # Errors
    /// As [`GpuNet::new`].
    pub(crate) fn in_step(
        dev: GpuDevice,
        model: &Model,
        tables: &Tables,
        layout: PackedLayout,
        n_envs: usize,
        graphs: StepBuffers,
    ) -> Result<Self, SimError> {
        check_batch(&dev, n_envs)?;
        let io = Io {
            graphs: graphs.buffers,
            q: graphs.scores,
            target: ScoreTarget {
                at: graphs.score_at,
                stride: 1,
                outputs: 1,
            },
        };
        Self::build(dev, model, tables, layout, n_envs, io)
    }

    /// [`GpuNet::build_in_scope`], with the device's errors on the way caught ([`CreationScope`]).
    fn build(
        dev: GpuDevice,
        model: &Model,
        tables: &Tables,
        layout: PackedLayout,
        n_envs: usize,
        io: Io,
    ) -> Result<Self, SimError> {
        let scope = CreationScope::push(&dev);
        let built = Self::build_in_scope(dev, model, tables, layout, n_envs, io);
        scope.finish(
            &format!("SNGNN-v2's network over {n_envs} environments"),
            built,
            |net| {
                [
                    &net.graph_u32,
                    &net.graph_f32,
                    &net.q,
                    &net.status,
                    &net.readback,
                ]
                .iter()
                .map(|b| b.size())
                .sum()
            },
        )
    }

    fn build_in_scope(
        dev: GpuDevice,
        model: &Model,
        tables: &Tables,
        layout: PackedLayout,
        n_envs: usize,
        io: Io,
    ) -> Result<Self, SimError> {
        let Io {
            graphs: [graph_u32, graph_f32],
            q,
            target,
        } = io;
        let csr_words = n_envs * (layout.max_nodes + 1 + layout.max_edges);
        let csr = empty_buffer::<u32>(&dev, "edge order", csr_words)?;
        let h_len = n_envs * layout.max_nodes * MAX_WIDTH;
        let h = [
            empty_buffer::<f32>(&dev, "node features", h_len)?,
            empty_buffer::<f32>(&dev, "node features", h_len)?,
        ];
        let status = empty_buffer::<u32>(&dev, "status", n_envs)?;
        let readback = dev.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("SNGNN readback"),
            size: bytes_of::<u32>(3 * n_envs),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let groups_of_net = [storage_bindings(&BINDINGS)];
        let (bind_layouts, _) = dev.pipelines.layout(&dev, &groups_of_net);
        let ((sort, sort_compiled), (layer, layer_compiled)) = pipelines(&dev, &groups_of_net)?;
        let mut groups = Vec::with_capacity(model.layers.len());
        for (l, mlp_layer) in model.layers.iter().enumerate() {
            let flat = tables.flat_layer(l);
            let (inputs, outputs) = (mlp_layer.mlp.inputs, mlp_layer.mlp.outputs);
            let mut floats = flat.floats;
            let bias = floats.len();
            floats.extend_from_slice(&mlp_layer.bias);
            let params = LayerParams {
                inputs,
                outputs,
                relu: l + 1 == model.layers.len(),
                h_in_stride: if l == 0 {
                    layout.f32_stride()
                } else {
                    layout.max_nodes * MAX_WIDTH
                },
                bias,
                last: l + 1 == model.layers.len(),
            };
            let params = filled_buffer(
                &dev,
                "layer constants",
                &params.words(&layout, n_envs, tables.max_dist(), target),
            )?;
            let tf = filled_buffer(&dev, "edge-weight tables", &floats)?;
            let ti = filled_buffer(&dev, "edge-weight table index", &flat.index)?;
            // Layer l reads the packed features (l = 0) or the previous layer's output, and
            // writes the other buffer of the pair.
            let h_in = if l == 0 { &graph_f32 } else { &h[(l + 1) % 2] };
            let bound = [
                &params,
                &graph_u32,
                &graph_f32,
                &csr,
                &tf,
                &ti,
                h_in,
                &h[l % 2],
                &q,
                &status,
            ];
            let group = bind_buffers(&dev, "SNGNN bindings", &bind_layouts[0], &bound);
            let x = word(layout.max_nodes * outputs).div_ceil(WORKGROUP);
            groups.push((group, x));
        }
        dev.take_errors()?;
        Ok(GpuNet {
            dev,
            layout,
            n_envs,
            target,
            graph_u32,
            graph_f32,
            q,
            status,
            readback,
            sort,
            layer,
            compiled: usize::from(sort_compiled) + usize::from(layer_compiled),
            groups,
        })
    }

    /// How many pipelines building this net compiled (0 when its device had them already).
    pub fn pipelines_compiled(&self) -> usize {
        self.compiled
    }

    /// The graph layout the batch was built for.
    pub fn layout(&self) -> PackedLayout {
        self.layout
    }

    /// The adapter it runs on.
    pub fn adapter(&self) -> &AdapterSummary {
        &self.dev.adapter
    }

    /// The device buffers of the packed graphs (u32 words, f32 values), for a producer on the
    /// device to write into.
    pub fn graph_buffers(&self) -> (&wgpu::Buffer, &wgpu::Buffer) {
        (&self.graph_u32, &self.graph_f32)
    }

    /// Upload the packed graphs of the whole batch: `n_envs` strides of each region, as
    /// [`PackedLayout::pack`] writes them.
    ///
    /// # Errors
    /// `SimError::Shape` when the slices have the wrong length.
    pub fn upload(&mut self, u32s: &[u32], f32s: &[f32]) -> Result<(), SimError> {
        let (wu, wf) = (
            self.n_envs * self.layout.u32_stride(),
            self.n_envs * self.layout.f32_stride(),
        );
        if u32s.len() != wu || f32s.len() != wf {
            return Err(SimError::shape(
                "SNGNN graphs",
                format!(
                    "packed SNGNN graphs of {} u32 and {} f32 values, expected {wu} and {wf}",
                    u32s.len(),
                    f32s.len()
                ),
            ));
        }
        let q = &self.dev.queue;
        q.write_buffer(&self.graph_u32, 0, bytemuck::cast_slice(u32s));
        q.write_buffer(&self.graph_f32, 0, bytemuck::cast_slice(f32s));
        Ok(())
    }

    /// Score every environment's graph into `out` (one per environment; NaN for a graph of no
    /// nodes): one submit, one readback, nothing allocated.
    ///
    /// # Errors
    /// `SimError::Shape` when `out` has the wrong length or the net writes into a step's state
    /// (`GpuNet::in_step`); `SimError::Sngnn` when a graph does not fit its layout or has an
    /// edge outside the tables; `Device` when the device fails.
    pub fn forward(&mut self, out: &mut [Output]) -> Result<(), SimError> {
        if out.len() != self.n_envs {
            return Err(SimError::shape(
                "SNGNN graphs",
                format!("{} SNGNN outputs for a batch of {}", out.len(), self.n_envs),
            ));
        }
        if self.target != OWN_OUTPUTS {
            return Err(SimError::Usage(
                "this SNGNN net writes into a GPU step's state; it has no outputs to read".into(),
            ));
        }
        let mut enc = self
            .dev
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("SNGNN forward"),
            });
        self.encode(&mut enc);
        let q_bytes = bytes_of::<f32>(2 * self.n_envs);
        let s_bytes = bytes_of::<u32>(self.n_envs);
        enc.copy_buffer_to_buffer(&self.q, 0, &self.readback, 0, q_bytes);
        enc.copy_buffer_to_buffer(&self.status, 0, &self.readback, q_bytes, s_bytes);
        self.dev.queue.submit([enc.finish()]);
        let mut failed = None;
        map_and_read(&self.dev, &self.readback, q_bytes + s_bytes, |words| {
            let (q, status) = words.split_at(2 * self.n_envs);
            for ((o, w), &s) in out.iter_mut().zip(q.chunks_exact(2)).zip(status) {
                *o = if s == STATUS_EMPTY {
                    [f32::NAN; 2]
                } else {
                    [f32::from_bits(w[0]), f32::from_bits(w[1])]
                };
            }
            failed = failure(status);
        })?;
        failed.map_or(Ok(()), Err)
    }

    /// Record the sort and the layers into `pass` (which then has the net's bind group set).
    pub(crate) fn record(&self, pass: &mut wgpu::ComputePass<'_>) {
        let envs = word(self.n_envs);
        pass.set_pipeline(&self.sort);
        pass.set_bind_group(0, &self.groups[0].0, &[]);
        pass.dispatch_workgroups(envs.div_ceil(WORKGROUP), 1, 1);
        pass.set_pipeline(&self.layer);
        for (group, x) in &self.groups {
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(*x, envs, 1);
        }
    }

    /// Each environment's status word after a forward pass ([`failure`] reads them).
    pub(crate) fn status_buffer(&self) -> &wgpu::Buffer {
        &self.status
    }

    /// Wall time of one [`GpuNet::forward`] (readback included), the mean of `reps` after one
    /// warm-up run: a benchmark helper.
    ///
    /// # Errors
    /// As [`GpuNet::forward`].
    pub fn time_forward(
        &mut self,
        out: &mut [Output],
        reps: u32,
    ) -> Result<std::time::Duration, SimError> {
        self.forward(out)?;
        let start = std::time::Instant::now();
        for _ in 0..reps.max(1) {
            self.forward(out)?;
        }
        Ok(start.elapsed() / reps.max(1))
    }

    /// The sort and the layers, one compute pass.
    fn encode(&self, enc: &mut wgpu::CommandEncoder) {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("SNGNN forward"),
            timestamp_writes: None,
        });
        self.record(&mut pass);
    }
}

/// The error of the first environment whose forward failed, from the status words of a batch
/// (a graph of no nodes is not a failure).
pub(crate) fn failure(status: &[u32]) -> Option<SimError> {
    let e = status
        .iter()
        .position(|&s| s & (STATUS_UNSUPPORTED | STATUS_BAD_GRAPH) != 0)?;
    Some(SimError::Sngnn(status_message(e, status[e])))
}

/// Why environment `e`'s forward failed, from its status bits.
fn status_message(e: usize, status: u32) -> String {
    if status & STATUS_BAD_GRAPH != 0 {
        format!(
            "environment {e}: the SNGNN graph exceeds its packed layout, or names a node or \
             relation that does not exist"
        )
    } else {
        debug_assert_eq!(status, STATUS_UNSUPPORTED);
        format!(
            "environment {e}: an SNGNN edge distance lies outside the edge-weight tables, and \
             the device has no edge network (score it on the CPU)"
        )
    }
}

impl LayerParams {
    /// `NetParams` of the shader.
    fn words(
        &self,
        layout: &PackedLayout,
        n_envs: usize,
        max_dist: f32,
        target: ScoreTarget,
    ) -> [u32; 15] {
        [
            word(n_envs),
            word(layout.max_nodes),
            word(layout.max_edges),
            word(layout.u32_stride()),
            word(layout.f32_stride()),
            word(self.inputs),
            word(self.outputs),
            u32::from(self.relu),
            word(self.h_in_stride),
            word(self.bias),
            u32::from(self.last),
            max_dist.to_bits(),
            word(target.at),
            word(target.stride),
            word(target.outputs),
        ]
    }
}

/// A pipeline, and whether getting it compiled it.
type Built = (wgpu::ComputePipeline, bool);

/// The `sort` and `layer` pipelines of `shaders/sngnn_score.wgsl` (compiled once per device).
fn pipelines(dev: &GpuDevice, groups: &[Vec<Binding>]) -> Result<(Built, Built), SimError> {
    let src = wgsl::assemble_standalone("sngnn_score.wgsl").map_err(SimError::Usage)?;
    let sort = dev
        .pipelines
        .pipeline(dev, "sngnn sort", groups, &src, "sort")?;
    let layer = dev
        .pipelines
        .pipeline(dev, "sngnn layer", groups, &src, "layer")?;
    Ok((sort, layer))
}
