//! The GPU backend outside the stages (docs/spec.md, determinism): the state's and the outputs'
//! trip to the device and back, and the masked reset pass (`shaders/reset.wgsl`, the twin of
//! `CpuBackend::reset`) against the CPU's, bit for bit on lavapipe (the harness:
//! `tests/common/gpu.rs`), episode seeds through the reset pool, and two batches stepped at once
//! on one device.

use crate::common::gpu::*;
use socnav::backend::gpu::GpuStages;
use socnav::outputs::Outputs;
use socnav::state::BatchState;

/// The state and the outputs survive the trip to the device and back bit for bit, every column.
#[test]
fn state_round_trip() {
    let Some(dev) = device() else { return };
    let env = rolled_out(config("exp3"), 64, 60);
    let state = env.state().unwrap().clone();
    let outputs = env.outputs().clone();
    let gpu = GpuStages::new(dev, env.params(), &state, &outputs, &[]).expect("GPU stages");
    let mut back = BatchState::zeroed(state.n_envs, state.strides);
    assert!(!state.differing_columns(&back).is_empty());
    gpu.download_state(&mut back).expect("readback");
    assert!(
        state.differing_columns(&back).is_empty(),
        "state columns changed on the way: {:?}",
        state.differing_columns(&back)
    );
    let mut back = Outputs::zeroed(outputs.n_envs, outputs.strides);
    assert!(!outputs.differing_columns(&back).is_empty());
    gpu.download_outputs(&mut back).expect("readback");
    assert!(
        outputs.differing_columns(&back).is_empty(),
        "output columns changed on the way: {:?}",
        outputs.differing_columns(&back)
    );
}

/// The device names the memory its step readback is mapped from and the memory its queue writes
/// are staged in (diagnoses of the copies out of and into them on hardware): on Vulkan
/// host-visible, coherent memory types, and a batch's device line says the same.
#[test]
fn the_readback_and_staging_memory_are_named() {
    let Some(dev) = device() else { return };
    if dev.adapter.backend != "Vulkan" {
        println!("skipped: {} is not a Vulkan adapter", dev.adapter);
        return;
    }
    let memory = dev
        .readback_memory()
        .expect("a Vulkan device names its readback memory")
        .to_owned();
    let staging = dev
        .staging_memory()
        .expect("a Vulkan device names its staging memory")
        .to_owned();
    for m in [&memory, &staging] {
        assert!(
            m.starts_with("memory type ")
                && m.contains("HOST_VISIBLE")
                && m.contains("HOST_COHERENT"),
            "{m}"
        );
    }
    let env = rolled_out(config("exp1"), 4, 1);
    let state = env.state().unwrap().clone();
    let gpu = GpuStages::new(dev, env.params(), &state, env.outputs(), &[]).expect("GPU stages");
    let line = gpu.device_description();
    assert!(line.contains(&format!("mapped from {memory}")), "{line}");
    assert!(line.contains(&format!("staged in {staging}")), "{line}");
}

/// Contract: the masked reset pass (`shaders/reset.wgsl`) equals `CpuBackend::reset` over about
/// half the environments, chained so that reset environments reset again from their next row.
#[test]
fn masked_reset() {
    for name in ["exp2", "stress"] {
        check_parity("reset", config(name), 256, 6, None);
    }
}

/// The same batch of `config` (`n` environments, seed `seed`, autoreset `mode`) on the CPU and
/// on the GPU backend, reset.
fn cpu_and_gpu(
    config: &socnav::Config,
    n: usize,
    seed: u64,
    mode: socnav::AutoresetMode,
) -> (socnav::BatchEnv, socnav::BatchEnv) {
    use socnav::backend::BackendChoice;
    let make = |backend| {
        let mut env = socnav::BatchEnv::new(
            config.clone(),
            socnav::EnvOptions {
                n_envs: n,
                seed,
                autoreset: mode,
                backend,
                ..Default::default()
            },
        )
        .expect("batch");
        env.reset(None).expect("reset");
        env
    };
    (make(BackendChoice::Cpu), make(BackendChoice::Gpu))
}

/// Contract: episode seeds on the GPU backend (which follows each environment's seed sequence on
/// the host as the device consumes reset-pool rows): autoresets, a seeded reset and seeds named
/// for the next autoreset of some environments give the CPU's episodes, outputs and reported
/// seeds, bit for bit on lavapipe ([`Twins`]; in lockstep elsewhere, where the host's following
/// of the seeds is re-synchronised from the CPU's state every step).
#[test]
fn episode_seeds_match_the_cpu() {
    use socnav::AutoresetMode;
    if device().is_none() {
        return;
    }
    let mut c = config("exp1");
    c.episode.length = 12;
    let n = 67;
    let (cpu, gpu) = cpu_and_gpu(&c, n, 5, AutoresetMode::NextStep);
    let mut twins = Twins::new(cpu, gpu);
    let named: Vec<Option<u64>> = (0..n as u64)
        .map(|e| (e % 3 == 0).then_some(u64::MAX - e))
        .collect();
    let mut rng = socnav::rng::RngStream::new(17, 0);
    let mut reported = std::collections::HashSet::new();
    for t in 0..52 {
        if t == 15 {
            twins.cpu.reset(Some(1 << 40)).expect("reset");
            twins.gpu.reset(Some(1 << 40)).expect("reset");
            twins.compare();
        }
        if t == 20 {
            twins.cpu.set_next_seeds(&named).expect("seeds");
            twins.gpu.set_next_seeds(&named).expect("seeds");
        }
        // Episode ends and the seeds they report are outputs, next seeds state: compared here.
        twins.step(&random_actions(&mut rng, n, false));
        let og = twins.gpu.outputs();
        for e in (0..n).filter(|&e| og.episode_done[e] != 0) {
            reported.insert(socnav::seeds::seed_from_words(
                og.episode_seed_lo[e],
                og.episode_seed_hi[e],
            ));
        }
    }
    twins.finish("episode seeds");
    // Each named episode was played to its end (the episode running at step 20 ends within 13
    // steps, the named one within 13 more), as were the seeded reset's s + i.
    for seed in named.iter().flatten() {
        assert!(reported.contains(seed), "named seed {seed} never ended");
    }
    assert!(
        reported.contains(&((1 << 40) + 1)),
        "the seeded reset's environment 1"
    );
}

/// Contract (issue 19): a step reads back what it hands the host and no more: every per-step
/// output column, the episode counters, and the finished-only columns
/// (`socnav::outputs::FINISHED_ONLY_COLUMNS`) of the environments that finished, within the rows
/// the readback's hint had room for (twice the most recent finishers, at least 16); more finishers
/// than that (here: every environment times out at once) take a second copy. The host's outputs
/// stay the CPU's bit for bit through it all, and the first read after device work that was not
/// read back copies the whole table. On the device's default paths (here one readback piece) and
/// on the others (`device_other_paths`: four pieces, the other observation path). With optional
/// per-step columns left out (`StepOutputs`), those are not read back: their bytes are not moved
/// and the host's copy keeps what it held, while every delivered column stays the CPU's.
#[test]
fn a_step_reads_back_only_what_it_hands_the_host() {
    use socnav::outputs::StepOutputs;
    let Some(other) = device_other_paths() else {
        return;
    };
    reads_back_only_what_it_hands_the_host(None, StepOutputs::ALL);
    reads_back_only_what_it_hands_the_host(Some(other), StepOutputs::ALL);
    reads_back_only_what_it_hands_the_host(None, StepOutputs::LEAN);
    let info_only = StepOutputs {
        info: true,
        ..StepOutputs::LEAN
    };
    reads_back_only_what_it_hands_the_host(None, info_only);
}

/// [`a_step_reads_back_only_what_it_hands_the_host`] with the GPU batch on `dev` (`None`: the
/// shared device), delivering `which`.
fn reads_back_only_what_it_hands_the_host(
    dev: Option<socnav::backend::gpu::GpuDevice>,
    which: socnav::outputs::StepOutputs,
) {
    use socnav::outputs::FINISHED_ONLY_COLUMNS;
    use socnav::{Actions, AutoresetMode};
    let mut c = config("exp2");
    c.episode.length = 10;
    let n = 200;
    let (cpu, mut gpu) = cpu_and_gpu(&c, n, 9, AutoresetMode::SameStep);
    if let Some(dev) = dev {
        let options = socnav::EnvOptions {
            n_envs: n,
            seed: 9,
            autoreset: AutoresetMode::SameStep,
            ..Default::default()
        };
        gpu = socnav::BatchEnv::on_device(c.clone(), options, dev).expect("batch");
        gpu.reset(None).expect("reset");
    }
    gpu.set_step_outputs(which);
    assert_eq!(gpu.step_outputs(), which);
    // What the host holds of the columns left out, which no step may change.
    let held = gpu.outputs().clone();
    let mut twins = Twins::new(cpu, gpu);
    let columns = twins.cpu.outputs().columns();
    // The device keeps an observation row without its entity records' one-hot floats, which the
    // host writes from the counts read back beside it (src/backend/obs_payload.rs).
    let one_hots = socnav::spec::ONE_HOT * twins.cpu.layout().entity_records();
    let device_words = |c: &(&str, socnav::state::columns::Elem, usize)| -> u64 {
        let observation = c.0 == "obs" || c.0 == "final_obs";
        (if observation { c.2 - one_hots } else { c.2 }) as u64
    };
    let words = |finished: bool| -> u64 {
        columns
            .iter()
            .filter(|c| FINISHED_ONLY_COLUMNS.contains(&c.0) == finished)
            .filter(|c| which.delivers(c.0))
            .map(device_words)
            .sum()
    };
    let every_column_words: u64 = columns.iter().map(device_words).sum();
    let n64 = n as u64;
    // Per-step columns and the episode counters, then the counter of finished rows.
    let fixed = 4 * (n64 * words(false) + n64 + 1);
    let row = 4 * (1 + words(true));
    let whole_table = 4 * n64 * every_column_words;
    let mut rng = socnav::rng::RngStream::new(3, 0);
    let mut recent: Vec<u64> = Vec::new();
    let (mut second_reads, mut finished_total) = (0, 0);
    let mut left_out_changed = false;
    for t in 0..40 {
        let before = twins.gpu.host_path().expect("the GPU backend's host path");
        // The delivered columns are compared with the CPU's here.
        twins.step(&random_actions(&mut rng, n, false));
        let (cpu, gpu) = (&twins.cpu, &twins.gpu);
        let after = gpu.host_path().expect("host path");
        // The GPU batch's own finishers (the CPU's on lavapipe) are those it read rows of.
        let finished = (0..n)
            .filter(|&e| gpu.outputs().has_final[e] != 0 || gpu.outputs().episode_done[e] != 0)
            .count() as u64;
        let moved = after.bytes - before.bytes;
        let hint = recent
            .iter()
            .rev()
            .take(8)
            .max()
            .map_or(16, |&m| (2 * m).max(16))
            .min(n64);
        assert_eq!(
            after.finished_rows - before.finished_rows,
            finished,
            "step {t}"
        );
        assert_eq!(
            moved,
            fixed + row * hint.max(finished),
            "step {t}: {finished} finished, room for {hint}"
        );
        if t == 0 {
            // Nothing finished yet: the per-step columns (about half of exp2's table) and room
            // for 16 rows of 200.
            assert!(
                10 * moved < 6 * whole_table,
                "{moved} bytes read of a {whole_table}-byte table"
            );
        }
        second_reads += after.second_reads - before.second_reads;
        finished_total += finished;
        recent.push(finished);
        let changed: Vec<_> = held
            .differing_columns(gpu.outputs())
            .into_iter()
            .filter(|c| !which.delivers(c))
            .collect();
        assert!(
            changed.is_empty(),
            "step {t}: columns left out were read back: {changed:?}"
        );
        left_out_changed |= held
            .differing_columns(cpu.outputs())
            .into_iter()
            .any(|c| !which.delivers(c));
    }
    // The columns left out did change on the device: the check above could fail.
    assert_eq!(
        left_out_changed,
        which != socnav::outputs::StepOutputs::ALL,
        "the columns left out never changed in 40 steps"
    );
    assert!(
        second_reads >= 1,
        "no step overflowed the hint: the second copy is untested"
    );
    assert!(finished_total > n64, "only {finished_total} episodes ended");
    twins.finish(&format!("the readback delivering {which:?}"));
    let gpu = &mut twins.gpu;
    // Device work the host did not read (the benchmark's device-only timing) is followed by a
    // read of the whole table, after which the host's outputs are the device's again.
    let a = random_actions(&mut rng, n, false);
    gpu.time_device_steps(Actions::Continuous(&a), 3)
        .expect("device steps");
    let full = gpu.host_path().expect("host path").full_reads;
    gpu.step(Actions::Continuous(&a)).expect("step");
    assert_eq!(gpu.host_path().expect("host path").full_reads, full + 1);
}

/// exp2 with episodes of `length` steps and its laptop events (0.01 a step each) made frequent,
/// so that environments finish and regroup within a short run.
fn regrouping_exp2(length: u32) -> socnav::Config {
    let mut c = config("exp2");
    c.episode.length = length;
    c.events.laptop_dispersal_probability = 0.2;
    c.events.laptop_formation_probability = 0.2;
    c
}

/// A CPU batch of `c` (`n` environments, seed `seed`, SAME_STEP autoresets) and its twin on
/// `dev`, both reset.
fn same_step_twins(
    c: &socnav::Config,
    n: usize,
    seed: u64,
    dev: socnav::backend::gpu::GpuDevice,
) -> Twins {
    let options = socnav::EnvOptions {
        n_envs: n,
        seed,
        autoreset: socnav::AutoresetMode::SameStep,
        ..Default::default()
    };
    let mut cpu = socnav::BatchEnv::new(c.clone(), options.clone()).expect("CPU batch");
    let mut gpu = socnav::BatchEnv::on_device(c.clone(), options, dev).expect("GPU batch");
    cpu.reset(None).expect("reset");
    gpu.reset(None).expect("reset");
    Twins::new(cpu, gpu)
}

/// Contract: whole steps on the other paths than the device's defaults (the observation staged
/// slot-major and moved into rows through workgroup memory, or written into the rows in place;
/// the resets and the obstacle rebuilds on a workgroup's lanes, or on one lane each:
/// `common::gpu::device_other_paths`; a reset's obstacles built on the host, or rebuilt on the
/// device), read back in four pieces (submitted on the other side of the host's work), hand the
/// host the CPU's outputs and state bit for bit, SAME_STEP finals (copied from the rows after the
/// move) included, over episodes that end, social events that regroup and a caller's masked
/// reset.
#[test]
fn the_other_observation_path_steps_as_the_cpu() {
    use socnav::spec::{N_EVENTS, event};
    let Some(other) = device_other_paths() else {
        return;
    };
    let n = 67;
    let mut twins = same_step_twins(&regrouping_exp2(10), n, 5, other);
    let mut rng = socnav::rng::RngStream::new(4, 0);
    let (mut finals, mut regroupings) = (0, 0);
    // The events after which an environment regroups, and its obstacles are rebuilt.
    let regrouping = [
        event::CROWD_DISPERSAL,
        event::LAPTOP_DISPERSAL,
        event::CROWD_FORMATION_COMPLETE,
        event::CROWD_FORMATION_APPROXIMATE,
        event::LAPTOP_FORMATION_COMPLETE,
    ];
    for _ in 0..30 {
        twins.step(&random_actions(&mut rng, n, false));
        let out = twins.cpu.outputs();
        finals += out.has_final.iter().filter(|&&f| f != 0).count();
        regroupings += out
            .events
            .chunks_exact(N_EVENTS)
            .map(|ev| regrouping.iter().map(|&k| ev[k] as usize).sum::<usize>())
            .sum::<usize>();
    }
    // The reset pass alone, on every other environment (on these paths a reset's obstacles are
    // built where the defaults do not build them).
    let mask: Vec<bool> = (0..n).map(|e| e % 2 == 0).collect();
    twins.reset_envs(&mask);
    twins.step(&random_actions(&mut rng, n, false));
    twins.finish("the other paths");
    assert!(finals > n, "only {finals} SAME_STEP finals");
    assert!(regroupings > 0, "no regrouping: the rebuilds went untested");
}

/// Two batches on one device, stepped at once on two threads (what `socnav bench --halves` and
/// Python's `send`/`recv` on two batches do), each hand the host the CPU's outputs and state bit
/// for bit, with their readback submitted after the host's work and before it
/// (`GpuPaths::readback_before_host_work`: with it, a batch's other pieces and queued rebuild
/// are submitted while the other batch may be submitting its step), over episodes that end and
/// social events that regroup.
#[test]
fn two_batches_stepped_at_once_on_one_device_step_as_the_cpu() {
    let Some(dev) = device() else {
        return;
    };
    let c = regrouping_exp2(8);
    for before in [false, true] {
        let mut dev = dev.clone();
        dev.paths.readback_before_host_work = before;
        // Four pieces a step, so that there are other pieces to submit.
        dev.paths.readback_piece_bytes = 1 << 10;
        let twins: Vec<Twins> = [(33, 5), (34, 6)]
            .into_iter()
            .map(|(n, seed)| same_step_twins(&c, n, seed, dev.clone()))
            .collect();
        let finals: usize = std::thread::scope(|scope| {
            let runs: Vec<_> = twins
                .into_iter()
                .enumerate()
                .map(|(k, mut twins)| {
                    scope.spawn(move || {
                        let mut rng = socnav::rng::RngStream::new(7 + k as u64, 0);
                        let n = twins.cpu.n_envs();
                        let mut finals = 0;
                        for _ in 0..20 {
                            twins.step(&random_actions(&mut rng, n, false));
                            let out = twins.cpu.outputs();
                            finals += out.has_final.iter().filter(|&&f| f != 0).count();
                        }
                        twins.finish(&format!(
                            "batch {k}, readback before the host's work: {before}"
                        ));
                        finals
                    })
                })
                .collect();
            runs.into_iter()
                .map(|run| run.join().expect("a batch's thread"))
                .sum()
        });
        assert!(finals > 67, "only {finals} SAME_STEP finals");
    }
}

/// Stage timing on the GPU backend (what `socnav bench`'s per-stage shares come from): every
/// stage of the step gets a positive time (GPU timestamps around each stage run alone, members
/// of a fused pass included, where the device has them,
/// as lavapipe does), those only the SNGNN-v2 reward runs none, and the steps so timed (their
/// outputs read back whole) stay the CPU's bit for bit.
#[test]
fn stage_timing_times_every_pass_and_changes_nothing() {
    use socnav::AutoresetMode;
    if device().is_none() {
        return;
    }
    let n = 64;
    let (cpu, mut gpu) = cpu_and_gpu(&config("exp2"), n, 4, AutoresetMode::SameStep);
    gpu.set_stage_timing(true);
    let mut twins = Twins::new(cpu, gpu);
    let mut rng = socnav::rng::RngStream::new(8, 0);
    for _ in 0..20 {
        twins.step(&random_actions(&mut rng, n, false));
    }
    twins.finish("steps with stage timing");
    let gpu = &twins.gpu;
    for (name, seconds) in gpu.stage_seconds() {
        let sngnn_only = socnav::pipeline::stage(name).is_some_and(|s| s.sngnn_reward_only);
        assert_eq!(
            seconds > 0.0,
            !sngnn_only,
            "{name}: {seconds} s ({})",
            gpu.stage_clock()
        );
    }
}

/// Contract: with the step timeline on (`BatchEnv::set_step_timeline`), every delivered step
/// times its passes on the device's clock, and its readback copies and the copies before its
/// passes exactly where the adapter writes timestamps between commands (lavapipe does); the
/// device's part of a step fits inside the host's time from the submit to the last piece
/// copied; the steps stay the CPU's bit for bit (exp2 with full observations, read back in 1 KiB
/// pieces, so four a step); and off, nothing more is timed.
#[test]
fn the_step_timeline_times_the_wait_on_the_devices_clock() {
    use socnav::backend::BackendChoice;
    let Some(mut dev) = device() else { return };
    dev.paths.readback_piece_bytes = 1 << 10;
    let copies_timed = dev
        .device
        .features()
        .contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);
    let n = 64;
    let options = socnav::EnvOptions {
        n_envs: n,
        seed: 6,
        ..Default::default()
    };
    let cpu_options = socnav::EnvOptions {
        backend: BackendChoice::Cpu,
        ..options.clone()
    };
    let mut cpu = socnav::BatchEnv::new(config("exp2"), cpu_options).expect("CPU batch");
    let mut gpu = socnav::BatchEnv::on_device(config("exp2"), options, dev).expect("GPU batch");
    cpu.reset(None).expect("reset");
    gpu.reset(None).expect("reset");
    gpu.set_step_timeline(true);
    let start = gpu.host_path().expect("host path");
    let mut twins = Twins::new(cpu, gpu);
    let mut rng = socnav::rng::RngStream::new(9, 0);
    let steps = 12;
    for _ in 0..steps {
        twins.step(&random_actions(&mut rng, n, false));
    }
    twins.finish("steps with the timeline on");
    let mut gpu = twins.gpu;
    let timed = gpu.host_path().expect("host path");
    assert_eq!(timed.timed_reads - start.timed_reads, steps as u64);
    let passes = timed.device_s - start.device_s;
    let before = timed.before_passes_s - start.before_passes_s;
    let readback = timed.readback_s - start.readback_s;
    assert!(passes > 0.0, "passes {passes} s");
    let copies = timed.timed_copies - start.timed_copies;
    assert_eq!(copies, if copies_timed { steps as u64 } else { 0 });
    if copies_timed {
        assert!(readback > 0.0, "readback copies {readback} s");
        assert!(before >= 0.0, "before the passes {before} s");
    }
    let host = (timed.wait_s - start.wait_s)
        + (timed.copy_s - start.copy_s)
        + (timed.refill_ahead_s - start.refill_ahead_s);
    assert!(
        before + passes + readback <= host,
        "the device's {before} s before the passes, {passes} s of passes and {readback} s of copies outlast the host's {host} s from submit to the last piece"
    );
    gpu.set_step_timeline(false);
    gpu.step(socnav::Actions::Continuous(&[0.0; 3 * 64]))
        .expect("a step");
    let after = gpu.host_path().expect("host path");
    assert_eq!(after.timed_reads, timed.timed_reads);
    assert_eq!(after.device_s, timed.device_s);
}

/// The state and first outputs after the reset pass on `dev` over exp1's 100 environments 30
/// steps in, every one reset from the next pool row that `stage` hands the device (given every
/// environment's row and its half); and the state before.
fn reset_from_rows(
    dev: &socnav::backend::gpu::GpuDevice,
    stage: impl Fn(&mut GpuStages, &HalfRows),
) -> ((BatchState, Outputs), BatchState, Outputs) {
    use socnav::backend::schedule::RESET_PASS;
    let env = rolled_out(config("exp1"), 100, 30);
    let (p, state, out) = (*env.params(), env.state().unwrap().clone(), env.outputs());
    let mut gpu = GpuStages::new(dev.clone(), &p, &state, out, &[RESET_PASS]).expect("GPU stages");
    let rows = next_pool_rows(&gpu, &p, &state, out.strides.layout);
    stage(&mut gpu, &rows);
    gpu.upload_actions(&vec![1.0f32; 3 * state.n_envs]);
    gpu.run(RESET_PASS).expect("reset pass");
    let mut back = BatchState::zeroed(state.n_envs, state.strides);
    gpu.download_state(&mut back).expect("readback");
    let mut first = Outputs::zeroed(out.n_envs, out.strides);
    gpu.download_outputs(&mut first).expect("readback");
    ((back, first), state, out.clone())
}

/// Every row of `rows` written in place, one queue write each.
fn written_in_place(gpu: &mut GpuStages, rows: &HalfRows) {
    for (e, (half, row)) in rows.iter().enumerate() {
        gpu.write_pool_rows(*half, e, row);
    }
}

/// Environments `envs`'s rows staged in one queue write (`GpuStages::stage_pool_rows`), a run
/// each, each at environment `place(e)`'s place.
fn stage_rows(
    gpu: &mut GpuStages,
    rows: &HalfRows,
    envs: std::ops::Range<usize>,
    place: impl Fn(usize) -> usize,
) {
    let words: Vec<u32> = envs.clone().flat_map(|e| rows[e].1.clone()).collect();
    let runs: Vec<(usize, usize, usize)> = envs.map(|e| (rows[place(e)].0, place(e), 1)).collect();
    gpu.stage_pool_rows(&words, &runs);
}

/// `a` and `b` hold the same bits in every state and output column.
fn same_reset(what: &str, a: &(BatchState, Outputs), b: &(BatchState, Outputs)) {
    assert!(
        a.0.differing_columns(&b.0).is_empty(),
        "{what}: the state differs in {:?}",
        a.0.differing_columns(&b.0)
    );
    // A row's observation (its last words) too.
    assert!(
        a.1.differing_columns(&b.1).is_empty(),
        "{what}: the first observations differ in {:?}",
        a.1.differing_columns(&b.1)
    );
}

/// Pool rows staged in one queue write each and copied into place before the next submit
/// (`GpuStages::stage_pool_rows`, how `GpuBackend` writes them) reset environments exactly as
/// rows written in place do, their first observations included, also when the staging buffer
/// must grow while copies of an earlier write are still pending (10 rows, then 90).
#[test]
fn staged_pool_rows_land_where_written_ones_do() {
    let Some(dev) = device() else { return };
    let (written, state, out) = reset_from_rows(&dev, written_in_place);
    let (staged, _, _) = reset_from_rows(&dev, |gpu, rows| {
        for range in [0..10, 10..rows.len()] {
            stage_rows(gpu, rows, range, |e| e);
        }
    });
    assert!(
        written.0.differing_columns(&state).contains(&"episode"),
        "the pass reset nothing"
    );
    assert!(
        written.1.differing_columns(&out).contains(&"obs"),
        "the pass wrote no first observation"
    );
    same_reset("staged rows", &written, &staged);
}

/// Contract: a place of the pool staged again while its earlier row still waits to be copied (as
/// a state loaded, new seeds or new constants make the host do) takes the later row, whatever
/// order the device's workgroups copy the staged rows in: here the scatter takes them last first
/// (`GpuPaths::scatter_last_first`), and 30 places first get their neighbour's row, then their
/// own, in two queue writes before one submit (within the staging buffer's first room, so that
/// no growth orders them).
#[test]
fn a_place_staged_twice_before_a_submit_takes_the_later_row() {
    let Some(mut dev) = device() else { return };
    dev.paths.scatter_last_first = true;
    let (written, _, _) = reset_from_rows(&dev, written_in_place);
    let (staged, _, _) = reset_from_rows(&dev, |gpu, rows| {
        written_in_place(gpu, rows);
        // The stale rows: environment e's row at environment e - 1's place.
        stage_rows(gpu, rows, 1..31, |e| e - 1);
        stage_rows(gpu, rows, 0..30, |e| e);
    });
    same_reset("rows staged twice", &written, &staged);
}

/// Contract: a document loaded between steps (here environment 0's into environment 1, whose
/// next episodes then differ from the ones the pool was filled for) steps on as the CPU's, bit for
/// bit, through the resets that follow, with the reset pool's staged rows copied last first
/// (`GpuPaths::scatter_last_first`): the rows the load makes the host generate go to places
/// whose earlier rows still wait for their copy.
#[test]
fn a_loaded_document_steps_as_the_cpu_whatever_the_copies_order() {
    let Some(mut dev) = device() else { return };
    dev.paths.scatter_last_first = true;
    let mut c = config("exp1");
    c.episode.length = 4;
    let mut twins = same_step_twins(&c, 8, 3, dev);
    let mut rng = socnav::rng::RngStream::new(29, 0);
    for t in 0..14 {
        if t % 5 == 0 {
            for env in [&mut twins.cpu, &mut twins.gpu] {
                let doc = env.get_state(0).expect("a document");
                env.set_state(1, &doc).expect("loaded");
            }
            twins.compare();
        }
        twins.step(&random_actions(&mut rng, 8, false));
    }
    twins.finish("documents loaded between steps");
}
