//! Running passes on the device: the plan of a sequence of stages as dispatches (a fused pass's
//! consecutive members in one), their recording into one submit with the rare work's queues and
//! the queued obstacle rebuilds, the readback of a step, and the passes timed one by one.

use super::kernels::{Rebuild, workgroup_grid};
use super::kit::{bytes_of, map_and_read, map_and_read_after};
use super::readback::words_to_bytes;
use super::timeline::Timeline;
use super::{GpuStages, StepRead, readback};
use crate::backend::{obs_payload, schedule, wgsl};
use crate::error::SimError;

/// How a step is read back: `timed` on the device's clock (the step timeline is on and the step
/// runs passes), `selective` (only the finished environments' rows of the columns that change
/// rarely, `readback::StepReadback`) or the whole output table.
#[derive(Debug, Clone, Copy)]
pub(super) struct ReadHow {
    pub(super) timed: bool,
    pub(super) selective: bool,
}

/// What the step's own submit copies for the readback (bytes, words of the f32 table).
struct Copied {
    f_words: usize,
    table_bytes: u64,
    total: u64,
    /// Whether the network's status is among them.
    scored: bool,
    /// Bytes of the readback's pieces copied so far.
    piece_bytes: u64,
}

/// When a read-back step started, and the host's time in it: the work that overlaps the passes,
/// and recording and submitting.
struct StepTimes {
    started: std::time::Instant,
    host_work_s: f64,
    submit_s: f64,
}

/// One dispatch of a step: the pass that runs it (`schedule::pass_of`), and for a fused pass the mask
/// of the members it runs (`schedule::fused_passes`); `first` names its first stage in errors.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct Dispatch<'a> {
    pub(super) pass: &'a str,
    pub(super) members: Option<u32>,
    pub(super) first: &'a str,
}

impl Dispatch<'_> {
    /// Whether this dispatch runs stage `stage`.
    pub(super) fn runs(&self, stage: &str) -> bool {
        match (self.members, schedule::fused_pass_of(stage)) {
            (Some(members), Some((pass, bit))) => pass == self.pass && members & (1 << bit) != 0,
            (None, None) => self.pass == stage,
            _ => false,
        }
    }
}

/// The dispatches that run `stages` in order: consecutive members of one fused pass, in the
/// pass's order, share a dispatch; any other stage is one of its own.
pub(super) fn plan<'a>(stages: &[&'a str]) -> Vec<Dispatch<'a>> {
    let mut out: Vec<Dispatch<'a>> = Vec::with_capacity(stages.len());
    for &stage in stages {
        let Some((pass, bit)) = schedule::fused_pass_of(stage) else {
            out.push(Dispatch {
                pass: stage,
                members: None,
                first: stage,
            });
            continue;
        };
        if let Some(Dispatch {
            pass: last,
            members: Some(members),
            ..
        }) = out.last_mut()
            && *last == pass
            && *members >> bit == 0
        {
            *members |= 1 << bit;
            continue;
        }
        out.push(Dispatch {
            pass,
            members: Some(1 << bit),
            first: stage,
        });
    }
    out
}

impl GpuStages {
    /// Run stage `stage` over every environment (one dispatch, one submit).
    pub fn run(&mut self, stage: &str) -> Result<(), SimError> {
        self.run_stages(&[stage], None, |_| {})
    }

    /// Run `stages` in order over every environment, one dispatch each, in one submit; with
    /// `read`, the same submit then copies what the step hands the host
    /// (`backend::gpu::readback`: the per-step output columns and the rows of the environments
    /// that finished, or the whole output table after device work that was not read back) and
    /// the episode counters into the step readback buffer, which is read into `read`'s outputs
    /// and counters. The host runs `while_device_works` between the submit and the wait for the
    /// readback; it may stage pool rows ([`GpuStages::stage_pool_rows`]), which reach the pool at
    /// the start of the next submit. Where `stages` regroup or reset, the obstacles of the
    /// environments they queued for it are rebuilt once after them (`record_queued_rebuild`),
    /// with a read in a submit of its own after the readback's.
    pub fn run_stages(
        &mut self,
        stages: &[&str],
        read: Option<StepRead<'_>>,
        while_device_works: impl FnOnce(&mut Self),
    ) -> Result<(), SimError> {
        let started = std::time::Instant::now();
        // The queued rebuilds' one dispatch: at the end of the submit, or where the step is read
        // back, in a submit of its own after the readback's (the host waits for those alone, and
        // copies while the device rebuilds), made before any wait so that no error on the way
        // leaves a queued environment dirty. A driver that holds a submit until the one before it
        // has finished (lavapipe) holds the host there until the readback is done; the H200's did
        // not hold the pieces' submits.
        let queueing = self.last_queueing(stages);
        let mut enc = self
            .dev
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("step"),
            });
        // The step timeline times a step read back whose passes run here (not the read after
        // passes timed alone, `time_passes`).
        let how = ReadHow {
            timed: read.is_some() && !stages.is_empty(),
            selective: read.is_some() && !self.step_read.whole_table_next,
        };
        let rebuild_in_pass = if read.is_none() { queueing } else { None };
        self.record_passes(&mut enc, stages, how, rebuild_in_pass)?;
        let Some(read) = read else {
            self.dev.queue.submit([enc.finish()]);
            while_device_works(self);
            self.step_read.whole_table_next = true;
            return self.dev.take_errors();
        };
        let mut copied = self.record_first_copies(&mut enc, how);
        let mut submits = vec![self.dev.queue.submit([enc.finish()])];
        // The readback's other pieces and the queued rebuild, each in a submit of its own: right
        // after the step's where the driver takes submits as they come; after the host's work
        // that overlaps the step's passes where it may hold a submit until the one before it
        // has finished (`GpuPaths::readback_before_host_work`).
        let early = self.dev.paths.readback_before_host_work;
        if early {
            copied.piece_bytes += self.submit_after_step(how, queueing, &mut submits)?;
        }
        let working = std::time::Instant::now();
        while_device_works(self);
        let host_work_s = working.elapsed().as_secs_f64();
        if !early {
            copied.piece_bytes += self.submit_after_step(how, queueing, &mut submits)?;
        }
        let times = StepTimes {
            started,
            host_work_s,
            submit_s: started.elapsed().as_secs_f64() - host_work_s,
        };
        self.read_step(read, how, &copied, submits, times)
    }

    /// Record the step's compute pass into `enc`: the timeline's first timestamp, the submit's
    /// clears, every dispatch of `stages`, the queued rebuild where it runs in the step's submit
    /// (`rebuild`), and the finished rows' pass of a selective read.
    fn record_passes(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        stages: &[&str],
        how: ReadHow,
        rebuild: Option<&str>,
    ) -> Result<(), SimError> {
        if let Some(t) = self.timeline.as_ref().filter(|_| how.timed) {
            t.at_start(enc);
        }
        self.begin_submit(enc);
        if how.selective {
            self.step_read.clear(enc);
        }
        let timeline = self.timeline.as_ref().filter(|_| how.timed);
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("step"),
            timestamp_writes: timeline.map(Timeline::pass_writes),
        });
        self.bind(&mut pass);
        let mut scored = false;
        for dispatch in plan(stages) {
            scored |= self.record(&mut pass, &dispatch)?;
        }
        if let Some(of) = rebuild {
            self.record_queued_rebuild(&mut pass, of)?;
        }
        if how.selective {
            self.step_read.record(&mut pass);
        }
        drop(pass);
        self.sngnn_unread |= scored;
        Ok(())
    }

    /// Record the readback's copies of the step's own submit into `enc`: the output table (its
    /// first rows and piece where the read is selective, else whole), the episode counters, the
    /// network's status where it ran since the last read, and the timeline's resolve.
    fn record_first_copies(&mut self, enc: &mut wgpu::CommandEncoder, how: ReadHow) -> Copied {
        let f_words = self.outputs.packed_f32.len();
        let table_bytes = if how.selective {
            self.step_read.copy_rows(enc, &self.step_readback)
        } else {
            let (f_bytes, u_bytes) = (
                words_to_bytes(f_words),
                words_to_bytes(self.outputs.packed_u32.len()),
            );
            let rb = &self.step_readback;
            enc.copy_buffer_to_buffer(&self.outputs.f32s, 0, rb, 0, f_bytes);
            enc.copy_buffer_to_buffer(&self.outputs.u32s, 0, rb, f_bytes, u_bytes);
            f_bytes + u_bytes
        };
        let e_bytes = words_to_bytes(self.n_envs);
        let episode_at = words_to_bytes(self.episode_offset);
        let rb = &self.step_readback;
        enc.copy_buffer_to_buffer(&self.state.u32s, episode_at, rb, table_bytes, e_bytes);
        let mut total = table_bytes + e_bytes;
        // Stage timing runs the passes without a read (`time_passes`, or a submit per pass) and
        // reads back after them: the network's status is read if it ran since the last read.
        let scored = std::mem::take(&mut self.sngnn_unread);
        if let (true, Some(net)) = (scored, &self.sngnn_net) {
            enc.copy_buffer_to_buffer(net.status_buffer(), 0, rb, total, e_bytes);
            total += e_bytes;
        }
        let timeline = self.timeline.as_ref().filter(|_| how.timed);
        let mut piece_bytes = 0;
        if how.selective {
            let tables = self.output_tables();
            piece_bytes = self.step_read.copy_first_piece(enc, &tables, timeline);
        } else if let Some(t) = timeline {
            t.after_copy(enc, 0);
            t.resolve(enc);
        }
        Copied {
            f_words,
            table_bytes,
            total,
            scored,
            piece_bytes,
        }
    }

    /// Wait for the step's readback and copy it into `read`: the first submit's mapped words
    /// (the table, the episode counters, the network's status), then the other pieces, then the
    /// finished rows past the first copy's room; and the host path's statistics.
    fn read_step(
        &mut self,
        read: StepRead<'_>,
        how: ReadHow,
        copied: &Copied,
        submits: Vec<wgpu::SubmissionIndex>,
        times: StepTimes,
    ) -> Result<(), SimError> {
        let copies = submits.len();
        let mut bytes = copied.total + copied.piece_bytes;
        let rb = &self.step_readback;
        let (status, step_read) = (&mut self.sngnn_status, &self.step_read);
        let StepRead { out, episode, pool } = read;
        let table_words = (copied.table_bytes / 4) as usize;
        let mut copy_s = 0.0;
        let mut finished = Ok(0);
        map_and_read_after(
            &self.dev,
            rb,
            copied.total,
            Some(submits[0].clone()),
            |words| {
                let copying = std::time::Instant::now();
                let (table, rest) = words.split_at(table_words);
                let (ep, st) = rest.split_at(episode.len());
                if how.selective {
                    finished = step_read.read_rows(table, out);
                } else {
                    let (f, u) = table.split_at(copied.f_words);
                    obs_payload::unpack(out, bytemuck::cast_slice(f), u);
                }
                episode.copy_from_slice(ep);
                if copied.scored {
                    status.copy_from_slice(st);
                } else {
                    status.fill(0);
                }
                copy_s += copying.elapsed().as_secs_f64();
            },
        )?;
        if how.selective {
            copy_s += step_read.read_pieces(&self.dev, submits, out, pool)?;
        }
        let mut second = false;
        if how.selective {
            let count = finished?;
            let held = self.step_read.rows_hint();
            if count > held {
                let copying = std::time::Instant::now();
                let (src, at) = self.step_read.rest_at(held);
                let rows =
                    self.read_words_at(src, at, (count - held) * self.step_read.row_words())?;
                self.step_read.scatter(&rows, out)?;
                copy_s += copying.elapsed().as_secs_f64();
                bytes += words_to_bytes(rows.len());
                second = true;
            }
            self.step_read.note_finished(count);
            self.step_read.stats.finished_rows += count as u64;
        } else {
            self.step_read.whole_table_next = false;
            self.step_read.stats.full_reads += 1;
        }
        // The timeline's own readback is not the step's: its time stays out of the wait.
        let timing = std::time::Instant::now();
        if let Some(t) = self.timeline.as_ref().filter(|_| how.timed) {
            t.read(&self.dev, copies, &mut self.step_read.stats)?;
        }
        let timeline_s = timing.elapsed().as_secs_f64();
        let stats = &mut self.step_read.stats;
        stats.reads += 1;
        stats.bytes += bytes;
        stats.second_reads += u64::from(second);
        stats.copy_s += copy_s;
        stats.submit_s += times.submit_s;
        stats.wait_s +=
            times.started.elapsed().as_secs_f64() - copy_s - times.host_work_s - timeline_s;
        Ok(())
    }

    /// Record `dispatch` into `pass` (whose bind groups are the batch's): its pass's dispatches,
    /// or the network's. Returns whether the network ran.
    pub(super) fn record(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        dispatch: &Dispatch<'_>,
    ) -> Result<bool, SimError> {
        let stage = dispatch.first;
        let Some((_, pipeline)) = self.pipelines.iter().find(|(p, _)| *p == dispatch.pass) else {
            return Err(SimError::Usage(format!(
                "stage {stage:?} was not built for this batch"
            )));
        };
        let Some(pipeline) = pipeline else {
            let Some(net) = &self.sngnn_net else {
                return Err(SimError::Usage(format!(
                    "stage {stage:?} needs SNGNN-v2's network (GpuStages::attach_sngnn_net)"
                )));
            };
            net.record(pass);
            self.bind(pass);
            return Ok(true);
        };
        let workgroups = (self.n_envs as u32).div_ceil(wgsl::WORKGROUP_SIZE);
        if let Some(queue) = &pipeline.queue {
            pass.set_pipeline(queue);
            pass.dispatch_workgroups(workgroups, 1, 1);
        }
        pass.set_pipeline(&pipeline.main);
        if let Some(members) = dispatch.members {
            pass.set_bind_group(0, &self.bind_groups[0], &[members * self.mask_stride]);
        }
        pass.dispatch_workgroups(workgroups, 1, 1);
        // A queueing pass's rebuild waits for the submit's end (`record_queued_rebuild`).
        if let Some(rebuild) = &pipeline.rebuild
            && !schedule::queues_rebuilds(dispatch.pass)
        {
            self.dispatch_rebuild(pass, rebuild);
        }
        if let Some(records) = &pipeline.records
            && self.whole_view
            && dispatch.runs(wgsl::OBS_ROWS_STAGE)
        {
            pass.set_pipeline(records);
            pass.dispatch_workgroups(workgroups, self.entity_records, 1);
        }
        if let Some(rows) = &pipeline.rows
            && dispatch.runs(wgsl::OBS_ROWS_STAGE)
        {
            pass.set_pipeline(rows);
            pass.dispatch_workgroups(workgroups, self.obs_row_tiles, 1);
        }
        Ok(false)
    }

    /// Record a rebuild entry point's dispatch into `pass`.
    pub(super) fn dispatch_rebuild(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        (pipeline, how): &(wgpu::ComputePipeline, Rebuild),
    ) {
        pass.set_pipeline(pipeline);
        match how {
            Rebuild::PerLane => {
                pass.dispatch_workgroups((self.n_envs as u32).div_ceil(wgsl::WORKGROUP_SIZE), 1, 1);
            }
            Rebuild::InWorkgroups => {
                // A workgroup per environment of the batch, at most the device's
                // `rebuild_workgroups` (each then takes every so-many-th queued environment), in
                // rows of at most the device's workgroups per dimension.
                let per_dimension = self.dev.limits.max_compute_workgroups_per_dimension;
                let most =
                    usize::try_from(self.dev.paths.rebuild_workgroups.max(1)).unwrap_or(usize::MAX);
                let (x, y) = workgroup_grid(self.n_envs.min(most), per_dimension);
                pass.dispatch_workgroups(x, y, 1);
            }
        }
    }

    /// The last of `stages` whose rebuilds wait in the queue (`schedule::queues_rebuilds`, with
    /// a rebuild pipeline on this batch: `begin_step` and `autoreset` only where the pool's rows
    /// leave their obstacles to the device), whose pipeline then rebuilds the queue.
    pub(super) fn last_queueing<'a>(&self, stages: &[&'a str]) -> Option<&'a str> {
        stages.iter().rev().copied().find(|stage| {
            schedule::queues_rebuilds(stage)
                && self.pipelines.iter().any(|(pass, pipelines)| {
                    pass == stage && pipelines.as_ref().is_some_and(|p| p.rebuild.is_some())
                })
        })
    }

    /// Record into `pass` the one rebuild of the ORCA obstacles of every environment that the
    /// submit's regroupings and resets queued (`schedule::REBUILD_QUEUE`), with queueing pass `of`'s
    /// rebuild pipeline (the same entry point in each). It follows the submit's last stage:
    /// nothing in a step reads the obstacles of an environment after it regrouped or reset
    /// (`schedule::queues_rebuilds`), so the rebuild costs the step's latency nothing where it
    /// follows the readback ([`Self::run_stages`]).
    pub(super) fn record_queued_rebuild(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        of: &str,
    ) -> Result<(), SimError> {
        let rebuild = self
            .pipelines
            .iter()
            .find(|(p, _)| *p == of)
            .and_then(|(_, pipelines)| pipelines.as_ref())
            .and_then(|p| p.rebuild.as_ref())
            .ok_or_else(|| SimError::Internal(format!("pass {of} has no rebuild pipeline")))?;
        self.dispatch_rebuild(pass, rebuild);
        Ok(())
    }

    /// What a step read back submits after its own submit: the readback's other pieces where
    /// the read is `selective` (appended to `submits`, with a timestamp each where `timed`),
    /// then the rebuilds the stages queued, where one of them (`queueing`) did. The bytes the
    /// pieces copy.
    pub(super) fn submit_after_step(
        &self,
        how: ReadHow,
        queueing: Option<&str>,
        submits: &mut Vec<wgpu::SubmissionIndex>,
    ) -> Result<u64, SimError> {
        let mut bytes = 0;
        if how.selective {
            let tables = self.output_tables();
            let timeline = self.timeline.as_ref().filter(|_| how.timed);
            let (others, copied) = self
                .step_read
                .submit_other_pieces(&self.dev, &tables, timeline);
            submits.extend(others);
            bytes = copied;
        }
        if let Some(of) = queueing {
            self.submit_queued_rebuild(of)?;
        }
        Ok(bytes)
    }

    /// The queued rebuilds' dispatch (`record_queued_rebuild`) in a submit of its own, after the
    /// submits made so far.
    pub(super) fn submit_queued_rebuild(&self, of: &str) -> Result<(), SimError> {
        let mut enc = self
            .dev
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("queued obstacle rebuilds"),
            });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("queued obstacle rebuilds"),
                timestamp_writes: None,
            });
            self.bind(&mut pass);
            self.record_queued_rebuild(&mut pass, of)?;
        }
        self.dev.queue.submit([enc.finish()]);
        Ok(())
    }

    /// The output tables and the batch's layout, as the readback copies from them.
    pub(super) fn output_tables(&self) -> readback::Tables<'_> {
        readback::Tables {
            f32s: &self.outputs.f32s,
            u32s: &self.outputs.u32s,
            batch: &self.batch,
        }
    }

    /// What every submit of stages starts with: the pool rows staged since the last one copied
    /// into their places, and the rare work's queues emptied.
    pub(super) fn begin_submit(&mut self, enc: &mut wgpu::CommandEncoder) {
        self.flush_pool_copies(enc);
        let counters = bytes_of::<u32>(schedule::RARE_QUEUES);
        enc.clear_buffer(&self.rare, 0, Some(counters));
    }

    /// Seconds of device time each of `stages` takes, in order: each stage runs in a compute pass
    /// of its own with a timestamp written at its start and end, all in one submit (nothing is
    /// read back, so the next read copies the whole output table). `None` where the device has
    /// no timestamp queries (`wgpu::Features::TIMESTAMP_QUERY`); then time each stage as a submit
    /// of its own.
    pub fn time_passes(&mut self, stages: &[&str]) -> Result<Option<Vec<f64>>, SimError> {
        if !self.has_timestamps() || stages.is_empty() {
            return Ok(None);
        }
        let device = &self.dev.device;
        let count = 2 * stages.len() as u32;
        let set = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass times"),
            ty: wgpu::QueryType::Timestamp,
            count,
        });
        let bytes = 8 * u64::from(count);
        let buffer = |label, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage,
                mapped_at_creation: false,
            })
        };
        let resolved = buffer(
            "pass times",
            wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        );
        let read = buffer(
            "pass times readback",
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        );
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("timed passes"),
        });
        self.begin_submit(&mut enc);
        // The queued rebuilds' one dispatch is timed with the last queueing stage timed.
        let queueing = self
            .last_queueing(stages)
            .and_then(|of| stages.iter().rposition(|s| *s == of));
        for (k, &stage) in (0u32..).zip(stages) {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(stage),
                timestamp_writes: Some(wgpu::ComputePassTimestampWrites {
                    query_set: &set,
                    beginning_of_pass_write_index: Some(2 * k),
                    end_of_pass_write_index: Some(2 * k + 1),
                }),
            });
            self.bind(&mut pass);
            for dispatch in plan(&[stage]) {
                self.sngnn_unread |= self.record(&mut pass, &dispatch)?;
            }
            if queueing == Some(k as usize) {
                self.record_queued_rebuild(&mut pass, stage)?;
            }
        }
        enc.resolve_query_set(&set, 0..count, &resolved, 0);
        enc.copy_buffer_to_buffer(&resolved, 0, &read, 0, bytes);
        self.dev.queue.submit([enc.finish()]);
        self.step_read.whole_table_next = true;
        // Nanoseconds per tick.
        let period = f64::from(self.dev.queue.get_timestamp_period());
        let mut seconds = Vec::with_capacity(stages.len());
        map_and_read(&self.dev, &read, bytes, |words| {
            let ticks = |i: usize| u64::from(words[2 * i]) | (u64::from(words[2 * i + 1]) << 32);
            for k in 0..stages.len() {
                let span = ticks(2 * k + 1).saturating_sub(ticks(2 * k));
                seconds.push(span as f64 * period * 1e-9);
            }
        })?;
        Ok(Some(seconds))
    }
}

#[cfg(test)]
mod tests {
    use super::super::backend::step_stages as step;
    use super::{Dispatch, plan};
    use crate::backend::schedule;

    fn passes<'a>(dispatches: &[Dispatch<'a>]) -> Vec<(&'a str, Option<u32>)> {
        dispatches.iter().map(|d| (d.pass, d.members)).collect()
    }

    /// A grid of `n` workgroups (the rebuild's: one per environment, at most the device's
    /// `rebuild_workgroups`), in rows of at most the device's workgroups per dimension: never
    /// fewer workgroups than `n`, less than a row more, never a dimension past the limit.
    #[test]
    fn a_workgroup_grid_covers_the_batch_within_the_limit() {
        use super::workgroup_grid;
        assert_eq!(workgroup_grid(65_536, 65_535), (32_768, 2));
        assert_eq!(workgroup_grid(100, 65_535), (100, 1));
        assert_eq!(workgroup_grid(0, 65_535), (1, 1));
        for (n, limit) in [(1_000_001, 65_535), (7, 3), (9, 3), (131_071, 65_535)] {
            let (x, y) = workgroup_grid(n, limit);
            assert!(x <= limit && y <= limit, "{n}, {limit}: {x} x {y}");
            let total = (x as usize) * (y as usize);
            assert!(
                total >= n && total < n + y as usize,
                "{n}, {limit}: {x} x {y}"
            );
        }
    }

    /// A step without SNGNN-v2 runs each fused pass in one dispatch with every member; eleven
    /// stages become three dispatches.
    #[test]
    fn a_step_runs_each_fused_pass_once() {
        let stages = step(false);
        let planned = plan(&stages);
        assert_eq!(
            passes(&planned),
            [
                ("begin_step", None),
                ("motion", Some(0b111)),
                ("crowd", Some(0b111)),
                ("formation", None),
                ("outcome", Some(0b1_1111)),
                ("social_events", None),
                ("autoreset", None),
            ]
        );
        assert_eq!(stages.len() - planned.len(), 11 - 3);
        for stage in stages {
            assert_eq!(
                planned.iter().filter(|d| d.runs(stage)).count(),
                1,
                "{stage}"
            );
        }
    }

    /// With SNGNN-v2's graph and network between `termination` and `reward`, the outcome pass
    /// runs twice, each time with the members on its side of them.
    #[test]
    fn stages_between_members_split_the_dispatch() {
        let planned = plan(&step(true));
        let outcome: Vec<Option<u32>> = planned
            .iter()
            .filter(|d| d.pass == "outcome")
            .map(|d| d.members)
            .collect();
        assert_eq!(outcome, [Some(0b11), Some(0b1_1100)]);
        let at = |pass: &str, first: &str| {
            planned
                .iter()
                .position(|d| d.pass == pass && d.first == first)
                .unwrap()
        };
        assert!(at("outcome", "contacts") < at("sngnn_graph", "sngnn_graph"));
        assert!(at("sngnn_score", "sngnn_score") < at("outcome", "reward"));
    }

    /// Members asked for out of their pass's order, or one stage alone, keep the order asked for.
    #[test]
    fn a_dispatch_never_reorders_stages() {
        assert_eq!(
            passes(&plan(&["group_velocities", "robot_motion", "shadow_robot"])),
            [("motion", Some(0b100)), ("motion", Some(0b11))]
        );
        assert_eq!(passes(&plan(&["metrics"])), [("outcome", Some(0b1000))]);
        assert_eq!(passes(&plan(&["reset"])), [("reset", None)]);
        let alone = plan(&["observation"]);
        assert!(alone[0].runs("observation") && !alone[0].runs("metrics"));
        assert_eq!(schedule::pass_of("observation"), "outcome");
    }
}
