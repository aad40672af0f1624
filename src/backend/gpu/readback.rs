//! The step readback: what a step hands the host, and no more.
//!
//! A step writes some output columns for every environment (observation, counts, pairs, reward,
//! flags, info, events) and the [`FINISHED_ONLY_COLUMNS`] (SAME_STEP finals, episode statistics
//! and seed) only for the environments whose episode ended; every other environment keeps those
//! as they were, on the device and in the host's copy alike. So the submit that runs a step
//! also runs the finished-rows pass ([`wgsl::finished_rows_shader`]), which packs the finished
//! environments' rows behind a counter, and copies into the mapped readback buffer the per-step
//! columns, the counter and the first [`StepReadback::rows_hint`] rows. When more environments
//! finished than that, a second copy fetches the rest and the hint grows; the hint follows twice
//! the most environments that finished in recent steps. Rows come in the order the device's
//! atomic counter gave them; each carries its environment, where the host writes it, so the
//! host's outputs are the same bits whatever that order.
//!
//! Device work that is not read back (a pass run alone, the device-only timing) can change the
//! finished-only columns without the host seeing which environments finished, so the read after
//! it copies the whole output table ([`StepReadback::whole_table_next`]).

use rayon::prelude::*;

use crate::backend::HostPath;
use crate::backend::wgsl::{self, Columns};
use crate::error::SimError;
use crate::outputs::{FINISHED_ONLY_COLUMNS, Outputs};
use crate::state::columns::Elem;

use super::GpuDevice;
use super::kit::{Binding, bind_buffers, bytes_of, check_binding};

/// Rows the first copy always has room for.
const MIN_ROWS: usize = 16;
/// Steps whose finished counts set the hint.
const RECENT: usize = 8;
/// Columns longer than this (words) are copied into the outputs by every host thread.
const PARALLEL_WORDS: usize = 1 << 16;

/// One per-step output column: where it lies in its packed table.
#[derive(Debug, Clone, Copy)]
struct Span {
    name: &'static str,
    /// In the u32 table (else the f32 table).
    u32s: bool,
    /// First word in its table.
    at: usize,
    words: usize,
}

/// The finished-rows pass, the per-step columns and the hint of one batch.
pub(crate) struct StepReadback {
    spans: Vec<Span>,
    span_words: usize,
    /// The finished-only columns in row order, with their strides.
    columns: Vec<(&'static str, usize)>,
    row_words: usize,
    n_envs: usize,
    /// The counter, then up to one row per environment.
    finished: wgpu::Buffer,
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    /// Rows the next step's first copy takes.
    rows_hint: usize,
    recent: [usize; RECENT],
    next_recent: usize,
    /// The next read copies the whole output table (device work ran unread since the last).
    pub(crate) whole_table_next: bool,
    /// Totals so far (`GpuBackend` adds the refill's time).
    pub(crate) stats: HostPath,
}

/// The output tables on the device and the batch layout they are read through.
pub(crate) struct Tables<'a> {
    pub(crate) f32s: &'a wgpu::Buffer,
    pub(crate) u32s: &'a wgpu::Buffer,
    pub(crate) batch: &'a wgpu::Buffer,
}

impl StepReadback {
    /// The readback of a batch of `n_envs` environments with these state and output columns,
    /// and whether getting its pipeline compiled it.
    pub(crate) fn new(
        dev: &GpuDevice,
        n_envs: usize,
        state: Columns<'_>,
        outputs: Columns<'_>,
        tables: Tables<'_>,
    ) -> Result<(Self, bool), SimError> {
        let mut spans = Vec::new();
        let mut next = [0usize; 2];
        for &(name, elem, stride) in outputs {
            let k = usize::from(elem == Elem::U32);
            let words = n_envs * stride;
            if !FINISHED_ONLY_COLUMNS.contains(&name) && words > 0 {
                spans.push(Span {
                    name,
                    u32s: k == 1,
                    at: next[k],
                    words,
                });
            }
            next[k] += words;
        }
        let columns = wgsl::finished_columns(outputs)
            .into_iter()
            .map(|&(name, _, stride)| (name, stride))
            .collect();
        let row_words = wgsl::finished_row_words(outputs);
        let bytes = bytes_of::<u32>(1 + n_envs * row_words);
        check_binding(
            dev,
            &format!("the finished rows of {n_envs} environments"),
            bytes,
        )?;
        let finished = dev.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("finished rows"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let read = Binding::Storage { read_only: true };
        let groups = vec![vec![
            read,
            read,
            Binding::Uniform,
            Binding::Storage { read_only: false },
        ]];
        let source = wgsl::finished_rows_shader(state, outputs);
        let (pipeline, compiled) =
            dev.pipelines
                .pipeline(dev, wgsl::FINISHED_ROWS_PASS, &groups, &source, "main")?;
        let (layouts, _) = dev.pipelines.layout(dev, &groups);
        let bind_group = bind_buffers(
            dev,
            "finished rows",
            &layouts[0],
            &[tables.f32s, tables.u32s, tables.batch, &finished],
        );
        let span_words = spans.iter().map(|s| s.words).sum();
        let this = Self {
            spans,
            span_words,
            columns,
            row_words,
            n_envs,
            finished,
            pipeline,
            bind_group,
            rows_hint: MIN_ROWS.min(n_envs),
            recent: [0; RECENT],
            next_recent: 0,
            whole_table_next: false,
            stats: HostPath::default(),
        };
        Ok((this, compiled))
    }

    /// Words of the readback buffer a step's selective copy needs at most.
    pub(crate) fn most_words(&self) -> usize {
        self.span_words + 1 + self.n_envs * self.row_words
    }

    /// Bytes of the device buffer of the finished rows.
    pub(crate) fn device_bytes(&self) -> u64 {
        self.finished.size()
    }

    /// Rows the next step's first copy takes.
    pub(crate) fn rows_hint(&self) -> usize {
        self.rows_hint
    }

    /// Words of one finished environment's row (its index, then its finished-only words).
    pub(crate) fn row_words(&self) -> usize {
        self.row_words
    }

    /// Zero the counter; before the step's compute pass.
    pub(crate) fn clear(&self, enc: &mut wgpu::CommandEncoder) {
        enc.clear_buffer(&self.finished, 0, Some(4));
    }

    /// Record the finished-rows pass, after the step's passes.
    pub(crate) fn record(&self, pass: &mut wgpu::ComputePass<'_>) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.dispatch_workgroups((self.n_envs as u32).div_ceil(wgsl::WORKGROUP_SIZE), 1, 1);
    }

    /// Copy the per-step columns, the counter and the first [`Self::rows_hint`] rows into `rb`
    /// from its start; the bytes copied.
    pub(crate) fn copy(
        &self,
        enc: &mut wgpu::CommandEncoder,
        tables: &Tables<'_>,
        rb: &wgpu::Buffer,
    ) -> u64 {
        let mut at = 0u64;
        for s in &self.spans {
            let src = if s.u32s { tables.u32s } else { tables.f32s };
            let bytes = words_to_bytes(s.words);
            enc.copy_buffer_to_buffer(src, words_to_bytes(s.at), rb, at, bytes);
            at += bytes;
        }
        let rows = words_to_bytes(1 + self.rows_hint * self.row_words);
        enc.copy_buffer_to_buffer(&self.finished, 0, rb, at, rows);
        at + rows
    }

    /// The words of the finished rows from row `first` on, where a second copy starts.
    pub(crate) fn rest_at(&self, first: usize) -> (&wgpu::Buffer, u64) {
        (&self.finished, words_to_bytes(1 + first * self.row_words))
    }

    /// Write what [`Self::copy`] copied (`words`, from its start) into `out`: the per-step
    /// columns (large ones on every thread of `pool`) and the rows it holds. Returns how many
    /// environments finished; rows beyond the hint are for [`Self::scatter`] after a second
    /// copy.
    pub(crate) fn read(
        &self,
        words: &[u32],
        out: &mut Outputs,
        pool: Option<&rayon::ThreadPool>,
    ) -> Result<usize, SimError> {
        let mut at = 0;
        for s in &self.spans {
            let dst = column(out, s.name)?;
            copy_words(dst, &words[at..at + s.words], pool);
            at += s.words;
        }
        let count = words[at] as usize;
        if count > self.n_envs {
            return Err(SimError::Internal(format!(
                "the finished-rows pass counted {count} rows for {} environments",
                self.n_envs
            )));
        }
        let held = count.min(self.rows_hint);
        self.scatter(&words[at + 1..at + 1 + held * self.row_words], out)?;
        Ok(count)
    }

    /// Write finished rows (whole rows, back to back) into their environments' columns.
    pub(crate) fn scatter(&self, rows: &[u32], out: &mut Outputs) -> Result<(), SimError> {
        for row in rows.chunks_exact(self.row_words) {
            let e = row[0] as usize;
            if e >= self.n_envs {
                return Err(SimError::Internal(format!(
                    "a finished row names environment {e} of {}",
                    self.n_envs
                )));
            }
            let mut w = 1;
            for &(name, stride) in &self.columns {
                column(out, name)?[e * stride..(e + 1) * stride]
                    .copy_from_slice(&row[w..w + stride]);
                w += stride;
            }
        }
        Ok(())
    }

    /// Account for a step in which `count` environments finished: the next hint is twice the
    /// most of the recent steps', at least [`MIN_ROWS`], at most every environment.
    pub(crate) fn note_finished(&mut self, count: usize) {
        self.recent[self.next_recent] = count;
        self.next_recent = (self.next_recent + 1) % RECENT;
        let most = self.recent.iter().copied().max().unwrap_or(0);
        self.rows_hint = (2 * most).max(MIN_ROWS).min(self.n_envs);
    }
}

/// Bytes of `words` 32-bit words: an offset or a copy's size (`kit::bytes_of` is a buffer's
/// size, never below one element).
pub(crate) fn words_to_bytes(words: usize) -> u64 {
    4 * words as u64
}

/// Output column `name`'s words, or the internal error of a column list out of step with
/// [`Outputs`].
fn column<'a>(out: &'a mut Outputs, name: &str) -> Result<&'a mut [u32], SimError> {
    out.column_words_mut(name)
        .ok_or_else(|| SimError::Internal(format!("no output column {name:?}")))
}

/// `dst.copy_from_slice(src)`, split over `pool`'s threads when it is long.
fn copy_words(dst: &mut [u32], src: &[u32], pool: Option<&rayon::ThreadPool>) {
    match pool {
        Some(pool) if dst.len() > PARALLEL_WORDS => {
            let chunk = dst.len().div_ceil(pool.current_num_threads().max(1));
            pool.install(|| {
                dst.par_chunks_mut(chunk)
                    .zip(src.par_chunks(chunk))
                    .for_each(|(d, s)| d.copy_from_slice(s));
            });
        }
        _ => dst.copy_from_slice(src),
    }
}
