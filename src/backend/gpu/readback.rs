//! The step readback: what a step hands the host, and no more.
//!
//! A step writes some output columns for every environment (observation, counts, pairs, reward,
//! flags, info, events) and the [`FINISHED_ONLY_COLUMNS`] (SAME_STEP finals, episode statistics and
//! seed) only for the environments whose episode ended; every other environment keeps those as they
//! were, on the device and in the host's copy alike. So the submit that runs a step also runs the
//! finished-rows pass ([`wgsl::finished_rows_shader`]), which packs the finished environments' rows
//! behind a counter, and copies into the mapped readback buffer the counter and the first
//! [`StepReadback::rows_hint`] rows, and the per-step columns into up to [`MOST_PIECES`] buffers of
//! their own, the first in the step's submit and each other in a submit of its own, right after the
//! step's on a hardware GPU and after the host's work that overlaps the passes on a software one,
//! whose driver may hold a submit until the one before it has finished
//! (`GpuPaths::readback_before_host_work`): while the host copies one piece into its outputs, the
//! device copies the next to host memory. When more environments finished than that, a second copy
//! fetches the rest and the hint grows; the hint follows twice the most environments that finished
//! in recent steps. Rows come in the order the device's atomic counter gave them; each carries its
//! environment, where the host writes it, so the host's outputs are the same bits whatever that
//! order.
//!
//! The caller can leave optional per-step columns out ([`StepOutputs`]: info, interactions,
//! events); those are then not read back at all ([`StepReadback::select`]).
//!
//! The device's observation rows (`obs`, and `final_obs` in the finished rows) lack their entity
//! records' one-hot floats ([`obs_payload`]); the host writes them from the counts as it copies
//! the rows, so the u32 columns, the counts among them, are read before the f32 ones.
//!
//! Device work that is not read back (a pass run alone, the device-only timing) can change the
//! finished-only columns without the host seeing which environments finished, so the read after
//! it copies the whole output table ([`StepReadback::whole_table_next`]).

use std::ops::Range;

use rayon::prelude::*;

use crate::backend::HostPath;
use crate::backend::obs_payload;
use crate::backend::wgsl::{self, Columns};
use crate::error::SimError;
use crate::outputs::{FINISHED_ONLY_COLUMNS, Outputs, StepOutputs};
use crate::spec::ObsLayout;
use crate::state::columns::Elem;

use super::GpuDevice;
use super::kit::{bind_buffers, bytes_of, check_binding, map_and_read_after};
use super::pipelines::Binding;
use super::timeline::Timeline;

/// Most pieces the per-step columns are read back in, each a buffer and a submit of its own: the
/// host copies piece `k` into its outputs while the device copies piece `k + 1` to host memory,
/// so only the last piece's copy is not overlapped. A batch takes one piece per
/// `GpuPaths::readback_piece_bytes` of its per-step columns, at least one and at most these
/// (a submit costs some tens of microseconds: small reads stay whole).
pub(crate) const MOST_PIECES: usize = 4;
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

/// A run of per-step columns that lie back to back in their table: one device copy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Run {
    u32s: bool,
    at: usize,
    words: usize,
}

/// The per-step columns as runs of neighbours in their tables, in order: each run is one copy
/// command (every copy has a fixed cost besides its bytes; exp2's 12 per-step columns are 4 runs).
fn runs_of(spans: &[Span]) -> Vec<Run> {
    let mut runs: Vec<Run> = Vec::new();
    for s in spans {
        match runs.last_mut() {
            Some(r) if r.u32s == s.u32s && r.at + r.words == s.at => r.words += s.words,
            _ => runs.push(Run {
                u32s: s.u32s,
                at: s.at,
                words: s.words,
            }),
        }
    }
    runs
}

/// The finished-rows pass, the per-step columns and the hint of one batch.
pub(crate) struct StepReadback {
    /// Every per-step column, in table order.
    every: Vec<Span>,
    /// The per-step columns the caller takes (`StepOutputs`), in table order: what is read back.
    spans: Vec<Span>,
    /// The spans' copies ([`runs_of`]).
    runs: Vec<Run>,
    span_words: usize,
    /// Where the spans are read back: piece `k` of `n` holds their words from `span_words * k /
    /// n` on ([`piece_range`]).
    pieces: Vec<wgpu::Buffer>,
    /// The finished-only columns in row order, with their strides on the device.
    columns: Vec<(&'static str, usize)>,
    /// Where a finished row holds `final_obs_count` (from its first word, the environment's).
    final_counts_at: usize,
    /// The observation's layout (the host's rows hold the one-hot floats the device leaves out).
    layout: ObsLayout,
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
        layout: ObsLayout,
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
        // Table by table, in table order, so that neighbours make one copy ([`runs_of`]); the
        // u32 table first, so that the counts are in the host's outputs before the
        // observation rows whose one-hot floats they give ([`obs_payload::expand`]).
        spans.sort_by_key(|s| (!s.u32s, s.at));
        let columns: Vec<(&'static str, usize)> = wgsl::finished_columns(outputs)
            .into_iter()
            .map(|&(name, _, stride)| (name, stride))
            .collect();
        let final_counts_at = row_offset(&columns, "final_obs_count");
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
        let group = vec![
            read,
            read,
            Binding::Uniform,
            Binding::Storage { read_only: false },
        ];
        let (pipeline, bind_layout, compiled) = dev.pipelines.one_group_pipeline(
            dev,
            wgsl::FINISHED_ROWS_PASS,
            group,
            &wgsl::finished_rows_shader(state, outputs),
        )?;
        let bind_group = bind_buffers(
            dev,
            "finished rows",
            &bind_layout,
            &[tables.f32s, tables.u32s, tables.batch, &finished],
        );
        let span_words: usize = spans.iter().map(|s| s.words).sum();
        let pieces = piece_buffers(dev, span_words);
        let this = Self {
            runs: runs_of(&spans),
            every: spans.clone(),
            spans,
            span_words,
            pieces,
            columns,
            final_counts_at,
            layout,
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

    /// Read back only the per-step columns `which` delivers from the next step on (new pieces
    /// for the new sizes).
    pub(crate) fn select(&mut self, dev: &GpuDevice, which: StepOutputs) {
        self.spans = self
            .every
            .iter()
            .filter(|s| which.delivers(s.name))
            .copied()
            .collect();
        self.runs = runs_of(&self.spans);
        self.span_words = self.spans.iter().map(|s| s.words).sum();
        self.pieces = piece_buffers(dev, self.span_words);
    }

    /// Words of the readback buffer a step's finished rows need at most (the counter, then a
    /// row per environment); the per-step columns have their pieces.
    pub(crate) fn most_words(&self) -> usize {
        1 + self.n_envs * self.row_words
    }

    /// Bytes of its buffers: the finished rows on the device and the readback pieces.
    pub(crate) fn device_bytes(&self) -> u64 {
        self.finished.size() + self.pieces.iter().map(wgpu::Buffer::size).sum::<u64>()
    }

    /// Pieces the per-step columns are read back in, each a submit and a map of its own.
    pub(crate) fn pieces(&self) -> usize {
        self.pieces.len()
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

    /// Copy the counter and the first [`Self::rows_hint`] rows into `rb` from its start; the
    /// bytes copied.
    pub(crate) fn copy_rows(&self, enc: &mut wgpu::CommandEncoder, rb: &wgpu::Buffer) -> u64 {
        let rows = words_to_bytes(1 + self.rows_hint * self.row_words);
        enc.copy_buffer_to_buffer(&self.finished, 0, rb, 0, rows);
        rows
    }

    /// Copy the first piece of the per-step columns in `step` (the step's encoder, which the
    /// caller submits); the bytes it copies. With `timeline`, a timestamp follows the copy, and
    /// when there is no other piece the timestamps are resolved.
    pub(crate) fn copy_first_piece(
        &self,
        step: &mut wgpu::CommandEncoder,
        tables: &Tables<'_>,
        timeline: Option<&Timeline>,
    ) -> u64 {
        self.copy_piece_timed(step, tables, timeline, 0)
    }

    /// Copy each piece after the first in a submit of its own, so that the host can read a
    /// piece while the device copies the next ([`Self::read_pieces`]); the submits in piece
    /// order, and the bytes they copy. With `timeline`, a timestamp follows each copy and the
    /// last submit resolves them.
    ///
    /// A driver may hold a submit until the one before it has finished (lavapipe does, in
    /// `vkQueueSubmit`: wgpu chains its submits with semaphores), so on such a device the caller
    /// makes these submits after the host's work that overlaps the step's passes, and on one that
    /// takes submits as they come right after the step's
    /// ([`GpuPaths::readback_before_host_work`]).
    pub(crate) fn submit_other_pieces(
        &self,
        dev: &GpuDevice,
        tables: &Tables<'_>,
        timeline: Option<&Timeline>,
    ) -> (Vec<wgpu::SubmissionIndex>, u64) {
        let mut submits = Vec::with_capacity(self.pieces.len());
        let mut bytes = 0;
        for k in 1..self.pieces.len() {
            let mut enc = dev
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("step readback piece"),
                });
            bytes += self.copy_piece_timed(&mut enc, tables, timeline, k);
            submits.push(dev.queue.submit([enc.finish()]));
        }
        (submits, bytes)
    }

    /// Copy piece `k` into its buffer in `enc`, with its timestamp and, for the last piece, the
    /// timestamps' resolve; the bytes copied.
    fn copy_piece_timed(
        &self,
        enc: &mut wgpu::CommandEncoder,
        tables: &Tables<'_>,
        timeline: Option<&Timeline>,
        k: usize,
    ) -> u64 {
        let bytes = self.copy_piece(enc, tables, k);
        if let Some(t) = timeline {
            t.after_copy(enc, k);
            if k + 1 == self.pieces.len() {
                t.resolve(enc);
            }
        }
        bytes
    }

    /// Read each piece into the per-step columns of `out` as soon as its submit (`submits`: the
    /// step's, then [`Self::submit_other_pieces`]') has finished, long stretches on every thread
    /// of `pool`; the seconds spent copying.
    pub(crate) fn read_pieces(
        &self,
        dev: &GpuDevice,
        submits: Vec<wgpu::SubmissionIndex>,
        out: &mut Outputs,
        pool: Option<&rayon::ThreadPool>,
    ) -> Result<f64, SimError> {
        let mut copy_s = 0.0;
        for (k, submit) in submits.into_iter().enumerate() {
            let words = piece_range(self.span_words, k, self.pieces.len()).len();
            if words == 0 {
                continue;
            }
            let mut piece = Ok(());
            map_and_read_after(
                dev,
                &self.pieces[k],
                words_to_bytes(words),
                Some(submit),
                |w| {
                    let copying = std::time::Instant::now();
                    piece = self.read_piece(k, w, out, pool);
                    copy_s += copying.elapsed().as_secs_f64();
                },
            )?;
            piece?;
        }
        Ok(copy_s)
    }

    /// Copy piece `k` of the per-step columns into its buffer; the bytes copied.
    fn copy_piece(&self, enc: &mut wgpu::CommandEncoder, tables: &Tables<'_>, k: usize) -> u64 {
        let piece = piece_range(self.span_words, k, self.pieces.len());
        for (r, start, part) in parts_in(self.runs.iter().map(|r| r.words), piece.clone()) {
            let r = &self.runs[r];
            let src = if r.u32s { tables.u32s } else { tables.f32s };
            enc.copy_buffer_to_buffer(
                src,
                words_to_bytes(r.at + part.start - start),
                &self.pieces[k],
                words_to_bytes(part.start - piece.start),
                words_to_bytes(part.len()),
            );
        }
        words_to_bytes(piece.len())
    }

    /// The words of the finished rows from row `first` on, where a second copy starts.
    pub(crate) fn rest_at(&self, first: usize) -> (&wgpu::Buffer, u64) {
        (&self.finished, words_to_bytes(1 + first * self.row_words))
    }

    /// Write piece `k` of the per-step columns (`words`, what [`Self::copy_piece`] copied)
    /// into their columns of `out`, long stretches on every thread of `pool`.
    fn read_piece(
        &self,
        k: usize,
        words: &[u32],
        out: &mut Outputs,
        pool: Option<&rayon::ThreadPool>,
    ) -> Result<(), SimError> {
        let piece = piece_range(self.span_words, k, self.pieces.len());
        for (s, start, part) in parts_in(self.spans.iter().map(|s| s.words), piece.clone()) {
            let name = self.spans[s].name;
            let src = &words[part.start - piece.start..part.end - piece.start];
            if let Some((counts, rows)) = obs_payload::observation_mut(out, name) {
                // Its counts were read first (the u32 spans lead).
                obs_payload::expand(&self.layout, part.start - start, src, counts, rows, pool);
            } else {
                let dst = &mut column(out, name)?[part.start - start..part.end - start];
                copy_words(dst, src, pool);
            }
        }
        Ok(())
    }

    /// Write the rows that [`Self::copy_rows`] copied (`words`, from its start) into `out`.
    /// Returns how many environments finished; rows beyond the hint are for [`Self::scatter`]
    /// after a second copy.
    pub(crate) fn read_rows(&self, words: &[u32], out: &mut Outputs) -> Result<usize, SimError> {
        let count = words[0] as usize;
        if count > self.n_envs {
            return Err(SimError::Internal(format!(
                "the finished-rows pass counted {count} rows for {} environments",
                self.n_envs
            )));
        }
        let held = count.min(self.rows_hint);
        self.scatter(&words[1..1 + held * self.row_words], out)?;
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
                let src = &row[w..w + stride];
                if let Some((_, rows)) = obs_payload::observation_mut(out, name) {
                    // The row's own counts (the host's are written after this column, or not).
                    let counts = &row[self.final_counts_at..self.final_counts_at + 5];
                    let dim = self.layout.dim;
                    obs_payload::expand(
                        &self.layout,
                        0,
                        src,
                        counts,
                        &mut rows[e * dim..(e + 1) * dim],
                        None,
                    );
                } else {
                    column(out, name)?[e * stride..(e + 1) * stride].copy_from_slice(src);
                }
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

/// The mapped buffers of the pieces of `span_words` words of per-step columns: one piece per
/// `GpuPaths::readback_piece_bytes`, at least one, at most [`MOST_PIECES`].
fn piece_buffers(dev: &GpuDevice, span_words: usize) -> Vec<wgpu::Buffer> {
    let n = bytes_of::<u32>(span_words)
        .div_ceil(dev.paths.readback_piece_bytes.max(1))
        .clamp(1, MOST_PIECES as u64) as usize;
    (0..n)
        .map(|k| {
            dev.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("step readback piece"),
                size: bytes_of::<u32>(piece_range(span_words, k, n).len()),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        })
        .collect()
}

/// The words of the per-step columns (`span_words` of them, back to back in span order) that
/// piece `k` of `n` holds.
fn piece_range(span_words: usize, k: usize, n: usize) -> Range<usize> {
    span_words * k / n..span_words * (k + 1) / n
}

/// For stretches of `lengths` words laid back to back, the part of each that lies in `piece`:
/// the stretch's index, its first word and the part (stretches outside `piece` left out).
fn parts_in(
    lengths: impl Iterator<Item = usize>,
    piece: Range<usize>,
) -> impl Iterator<Item = (usize, usize, Range<usize>)> {
    lengths
        .enumerate()
        .scan(0, move |next, (i, words)| {
            let start = *next;
            *next += words;
            Some((
                i,
                start,
                start.max(piece.start)..(start + words).min(piece.end),
            ))
        })
        .filter(|(_, _, part)| !part.is_empty())
}

/// Where column `name` starts in a finished row of `columns` (after the row's environment word).
#[expect(
    clippy::expect_used,
    reason = "the finished rows hold every finished-only column (FINISHED_ONLY_COLUMNS)"
)]
fn row_offset(columns: &[(&'static str, usize)], name: &str) -> usize {
    let k = columns
        .iter()
        .position(|c| c.0 == name)
        .expect("a finished-only column");
    1 + columns[..k].iter().map(|c| c.1).sum::<usize>()
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

#[cfg(test)]
mod tests {
    use super::*;

    fn span(u32s: bool, at: usize, words: usize) -> Span {
        Span {
            name: "",
            u32s,
            at,
            words,
        }
    }

    /// Neighbours in one table make one run; a gap, or the other table, starts the next.
    #[test]
    fn neighbouring_spans_make_one_copy() {
        let spans = [
            span(false, 0, 10),
            span(false, 10, 2),
            span(false, 20, 4),
            span(true, 24, 3),
            span(true, 27, 1),
        ];
        let run = |u32s, at, words| Run { u32s, at, words };
        assert_eq!(
            runs_of(&spans),
            [run(false, 0, 12), run(false, 20, 4), run(true, 24, 4)]
        );
        assert_eq!(runs_of(&[]), []);
    }

    /// The pieces cover the words once, in order; each stretch's parts are where the pieces cut
    /// it.
    #[test]
    fn pieces_cut_the_stretches_where_they_meet() {
        let total = 103;
        for n in 1..=MOST_PIECES {
            let pieces: Vec<Range<usize>> = (0..n).map(|k| piece_range(total, k, n)).collect();
            assert_eq!(pieces[0].start, 0);
            assert_eq!(pieces[n - 1].end, total);
            assert!(pieces.windows(2).all(|w| w[0].end == w[1].start));
        }
        let lengths = [10, 0, 50, 43];
        let parts: Vec<_> = parts_in(lengths.into_iter(), 20..60).collect();
        assert_eq!(parts, [(2, 10, 20..60)]);
        let parts: Vec<_> = parts_in(lengths.into_iter(), 5..61).collect();
        assert_eq!(parts, [(0, 0, 5..10), (2, 10, 10..60), (3, 60, 60..61)]);
    }
}
