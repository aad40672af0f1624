//! The reset pool's rows reaching the device: written in place, or staged and scattered by a
//! generated pass (`wgsl::pool_scatter_shader`) in the next submit.

use super::GpuStages;
use super::device::GpuDevice;
use super::kernels::workgroup_grid;
use super::kit::{bind_buffers, bytes_of, storage_buffer, write_buffer_split};
use super::pipelines::Binding;
use super::readback::words_to_bytes;
use crate::backend::wgsl;
use crate::error::SimError;
use crate::systems::reset::ObstacleBuild;

/// Pool rows the staging buffer first has room for ([`GpuStages::stage_pool_rows`]; it grows).
pub const POOL_STAGING_ROWS: usize = 64;

/// How the reset pool's rows hold their ORCA obstacles on a device that rebuilds them after each
/// reset (`after_resets`, `GpuPaths::obstacles_after_resets`) or not.
pub(super) fn obstacle_build(after_resets: bool) -> ObstacleBuild {
    if after_resets {
        ObstacleBuild::Deferred
    } else {
        ObstacleBuild::Now
    }
}

/// A buffer the host writes rows into and the device copies from, of `words` words.
pub(super) fn staging_buffer(dev: &GpuDevice, words: usize) -> wgpu::Buffer {
    storage_buffer(dev, "pool staging", bytes_of::<u32>(words))
}

/// The pool scatter pass (`wgsl::pool_scatter_shader`): its pipeline, its bind group layout, and
/// the list of runs it reads, which grows as a step's runs need.
pub(super) struct PoolScatter {
    pub(super) pipeline: wgpu::ComputePipeline,
    pub(super) layout: wgpu::BindGroupLayout,
    pub(super) runs: wgpu::Buffer,
    /// The list's words on the host, kept between steps.
    pub(super) list: Vec<u32>,
}

impl PoolScatter {
    /// The pass on `dev` (compiled once per device), with whether this call compiled it.
    pub(super) fn new(dev: &GpuDevice) -> Result<(Self, bool), SimError> {
        let read = Binding::Storage { read_only: true };
        let group = vec![read, read, Binding::Storage { read_only: false }];
        let (pipeline, layout, compiled) = dev.pipelines.one_group_pipeline(
            dev,
            wgsl::POOL_SCATTER_PASS,
            group,
            &wgsl::pool_scatter_shader(dev.paths.scatter_last_first),
        )?;
        // Room for a staging buffer's first rows in runs of one; it grows past that as needed.
        let runs = storage_buffer(
            dev,
            "pool runs",
            bytes_of::<u32>(1 + POOL_STAGING_ROWS * wgsl::POOL_RUN_WORDS),
        );
        let this = Self {
            pipeline,
            layout,
            runs,
            list: Vec::new(),
        };
        Ok((this, compiled))
    }

    /// Record into `enc` the copies `copies` ((from, to, bytes): from `staged` into `pool`) as
    /// one dispatch, its list of runs written to the device before the submit's work.
    pub(super) fn record(
        &mut self,
        dev: &GpuDevice,
        enc: &mut wgpu::CommandEncoder,
        (staged, pool): (&wgpu::Buffer, &wgpu::Buffer),
        copies: &[(u64, u64, u64)],
    ) {
        // Word offsets within one storage binding, which WGSL indexes with a u32, as every
        // shader of the batch does.
        let word = |bytes: u64| u32::try_from(bytes / 4).unwrap_or(u32::MAX);
        self.list.clear();
        self.list
            .push(u32::try_from(copies.len()).unwrap_or(u32::MAX));
        for &(from, to, size) in copies {
            self.list.extend([word(from), word(to), word(size)]);
        }
        let bytes = words_to_bytes(self.list.len());
        if bytes > self.runs.size() {
            self.runs = storage_buffer(dev, "pool runs", bytes.next_power_of_two());
        }
        dev.queue
            .write_buffer(&self.runs, 0, bytemuck::cast_slice(&self.list));
        let group = bind_buffers(
            dev,
            "pool scatter",
            &self.layout,
            &[staged, &self.runs, pool],
        );
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(wgsl::POOL_SCATTER_PASS),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        let (x, y) = workgroup_grid(
            copies.len(),
            dev.limits.max_compute_workgroups_per_dimension,
        );
        pass.dispatch_workgroups(x, y, 1);
    }
}

impl GpuStages {
    /// Words of one reset-pool row ([`wgsl::pool_row_words`]).
    pub fn pool_row_words(&self) -> usize {
        self.pool_row_words
    }

    /// How the rows written into the reset pool must hold their ORCA obstacles: left to the
    /// device, which rebuilds them after each reset, where the device asks for it
    /// (`GpuPaths::obstacles_after_resets`), else built
    /// (`crate::backend::reset_pool::RowScratch::new`).
    pub fn pool_obstacles(&self) -> ObstacleBuild {
        obstacle_build(self.dev.paths.obstacles_after_resets)
    }

    /// Write `rows` (whole pool rows) into the reset pool from environment `first_env` on, in the
    /// half of the pool for episode counters of parity `half` (0 or 1): the rows that start
    /// episodes after counters of the other parity, since a reset moves the counter on
    /// (`pool_row_of` in `shaders/common/pool_reset.wgsl`). A place whose row
    /// [`GpuStages::stage_pool_rows`] staged and the next submit has not copied yet takes that
    /// row after this one (queue writes land before a submit's work).
    pub fn write_pool_rows(&mut self, half: usize, first_env: usize, rows: &[u32]) {
        assert!(half < 2, "the pool has two halves");
        assert_eq!(
            rows.len() % self.pool_row_words.max(1),
            0,
            "whole pool rows"
        );
        let offset = self.pool_row_at(half, first_env);
        self.dev
            .queue
            .write_buffer(&self.pool, offset, bytemuck::cast_slice(rows));
    }

    /// Write `rows` (whole pool rows, back to back) to the device in one queue write, to be
    /// copied into the pool before the next submitted work: `runs` lists, in order, each run of
    /// consecutive environments of one half (as [`GpuStages::write_pool_rows`] takes them) and
    /// its number of rows. A queue write per run costs several microseconds of the host's time
    /// each, and the rows of a step are scattered; one write, and one dispatch that moves every
    /// run into place (`wgsl::pool_scatter_shader`), cost less (a copy command per run cost about
    /// 0.7 µs each). A run is copied in pieces of at most `wgsl::POOL_SCATTER_PIECE_WORDS`, a
    /// workgroup each.
    ///
    /// The dispatch's workgroups copy in no particular order, so a place staged again while its
    /// earlier row still waits (a state loaded, new seeds or constants make the host generate a
    /// place's row anew) would race with it: the copies still waiting are then made first, in a
    /// submit of their own, as they are before the staging buffer grows.
    pub fn stage_pool_rows(&mut self, rows: &[u32], runs: &[(usize, usize, usize)]) {
        let bytes = words_to_bytes(rows.len());
        let grows = self.pool_staged + bytes > self.pool_staging.size();
        let restaged = runs
            .iter()
            .any(|&(half, env, n)| self.places(half, env, n).any(|at| self.pending(at)));
        if (grows || restaged) && !self.pool_copies.is_empty() {
            let mut enc = self
                .dev
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("pool rows"),
                });
            self.flush_pool_copies(&mut enc);
            self.dev.queue.submit([enc.finish()]);
        }
        if grows {
            // No larger than the pool (which fits one storage binding) unless the rows are:
            // the pool scatter pass binds the staging buffer whole.
            let words = (2 * self.pool_staging.size() / 4)
                .min(self.pool.size() / 4)
                .max(rows.len() as u64) as usize;
            self.pool_staging = staging_buffer(&self.dev, words);
        }
        write_buffer_split(
            &self.dev,
            &self.pool_staging,
            self.pool_staged,
            bytemuck::cast_slice(rows),
            self.host_threads.as_deref(),
        );
        let piece = words_to_bytes(wgsl::POOL_SCATTER_PIECE_WORDS);
        let mut from = self.pool_staged;
        for &(half, env, n) in runs {
            let to = self.pool_row_at(half, env);
            let size = words_to_bytes(n * self.pool_row_words);
            for at in (0..size).step_by(piece as usize) {
                self.pool_copies
                    .push((from + at, to + at, piece.min(size - at)));
            }
            for at in self.places(half, env, n) {
                self.pool_pending[at / 64] |= 1 << (at % 64);
            }
            from += size;
        }
        self.pool_staged += bytes;
    }

    /// The place of environment `env`'s row in half `half` of the pool: its index among the
    /// pool's rows.
    pub(super) fn place(&self, half: usize, env: usize) -> usize {
        half * self.n_envs + env
    }

    /// The places of `n` rows from environment `env` on in half `half`.
    pub(super) fn places(&self, half: usize, env: usize, n: usize) -> std::ops::Range<usize> {
        let first = self.place(half, env);
        first..first + n
    }

    /// Whether place `at` holds a staged row that waits for its copy.
    pub(super) fn pending(&self, at: usize) -> bool {
        self.pool_pending[at / 64] & (1 << (at % 64)) != 0
    }

    /// Byte offset in the pool of environment `env`'s row in half `half`.
    pub(super) fn pool_row_at(&self, half: usize, env: usize) -> u64 {
        words_to_bytes(self.place(half, env) * self.pool_row_words)
    }

    /// Record the staged pool rows' copies into `enc` (before its passes): one dispatch of the
    /// pool scatter pass.
    pub(super) fn flush_pool_copies(&mut self, enc: &mut wgpu::CommandEncoder) {
        if !self.pool_copies.is_empty() {
            let buffers = (&self.pool_staging, &self.pool);
            self.pool_scatter
                .record(&self.dev, enc, buffers, &self.pool_copies);
            self.pool_copies.clear();
            self.pool_pending.fill(0);
        }
        self.pool_staged = 0;
    }
}
