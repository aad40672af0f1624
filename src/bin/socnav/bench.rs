//! `socnav bench`: env-steps/s of the step, in total and per stage, for a table of batch sizes.
//! Actions are fixed (forward and turning) so the policy costs nothing. On a GPU it also times
//! the simulation on the device alone (issue 4's first target); `--padded` delivers 0.1.1's
//! padded observations (walls omitted; the second target) instead of the full ones; `--halves`
//! also steps each batch size as two halves on two host threads; `--step-outputs` chooses the
//! optional per-step outputs delivered (every one by default); `--lane-paths` takes a software
//! adapter's paths on the GPU (every one, or those named), for comparison; `--leave-out` makes
//! shader functions return at once, to time a pass without them (diagnosis: the results are
//! wrong).

use std::time::Instant;

use serde_json::json;
use socnav::{Actions, Config};

use crate::args::BenchArgs;
use crate::run::make_env;

/// Steps run before timing, so every environment has reset at least once and caches are warm.
const WARMUP_STEPS: usize = 50;

pub fn bench(a: &BenchArgs) -> Result<(), Box<dyn std::error::Error>> {
    if chosen_device(a) && a.backend != crate::args::BackendChoice::Gpu {
        return Err(format!(
            "--lane-paths, --leave-out and --readback-piece-bytes change the GPU backend: give \
             --backend gpu (not {:?})",
            a.backend
        )
        .into());
    }
    let mut config = Config::from_name_or_path(&a.config)?;
    if a.padded {
        // 0.1.1's `get_padded_observations`: every type padded to its capacity, walls omitted.
        config.observation.padded = true;
    }
    let mut rows = Vec::new();
    let (mut device, mut backend) = (String::new(), "");
    for (i, &n) in a.envs.iter().enumerate() {
        let (mut env, actions) = warmed_up(a, &config, n, 0)?;
        // Throughput with stage timing off (it costs two clock reads per stage and chunk)...
        let path_before = env.host_path();
        let (steps, secs) = timed_steps(&mut env, &actions, a.seconds)?;
        let host_path = host_path_per_step(path_before, env.host_path(), steps, secs);
        // On a GPU, the simulation alone: the same steps with nothing delivered to the host.
        let device_only = env
            .time_device_steps(Actions::Continuous(&actions), steps)?
            .map(|s| (n * steps) as f64 / s);
        // A short run with the delivered step's timestamps: its wait on the device's clock.
        env.set_step_timeline(true);
        // One step first: the step after device work that was not read back reads the whole
        // output table.
        env.step(Actions::Continuous(&actions))?;
        let before_timeline = env.host_path();
        let (timeline_steps, _) = timed_steps(&mut env, &actions, 0.25 * a.seconds)?;
        let timeline = step_timeline(before_timeline, env.host_path(), timeline_steps);
        env.set_step_timeline(false);
        // ...then the stage shares from a shorter timed run.
        env.set_stage_timing(true);
        let before: Vec<f64> = env.stage_seconds().iter().map(|s| s.1).collect();
        let (timed, _) = timed_steps(&mut env, &actions, 0.5 * a.seconds)?;
        let stages: Vec<(&str, f64)> = env
            .stage_seconds()
            .iter()
            .zip(&before)
            .map(|((name, s), b)| (*name, s - b))
            .collect();
        let stage_total: f64 = stages.iter().map(|s| s.1).sum();
        let stage_clock = env.stage_clock();
        let parallelism = stage_parallelism(&env);
        let (state_bytes, obs_floats) = (env.state()?.bytes_per_env(), env.layout().dim);
        device = env.device();
        backend = env.backend_name();
        // The whole batch's buffers go before the halves take theirs.
        drop(env);
        let (halves, halves_host_path) = if a.halves && n >= 2 {
            let (rate, paths) = halves_env_steps_per_s(a, &config, n)?;
            (Some(rate), paths)
        } else {
            (None, Vec::new())
        };
        rows.push(json!({
            "envs": n,
            "steps": steps,
            "seconds": secs,
            "env_steps_per_s": (n * steps) as f64 / secs,
            "device_only_env_steps_per_s": device_only,
            // `--halves`: the same environments as two batches stepped on two host threads.
            "halves_env_steps_per_s": halves,
            // GPU: each half's host path per step, as `host_path` (where two halves lose).
            "halves_host_path": halves_host_path,
            // GPU: the host path's time and bytes per step over the timed steps.
            "host_path": host_path,
            // GPU with timestamps: a shorter run's passes and readback copies on the device's
            // clock, per step, beside its host path.
            "timeline": timeline,
            "state_bytes_per_env": state_bytes,
            "obs_floats_per_env": obs_floats,
            // CPU stage time is summed over threads: each stage's share of the step's CPU time.
            // GPU stages are timed one submit each, in wall time.
            "stage_clock": stage_clock,
            "stage_share": stages.iter().map(|(k, s)| (k.to_string(), json!(s / stage_total))).collect::<serde_json::Map<_, _>>(),
            "stage_env_steps_per_s": stages.iter().map(|(k, s)| (k.to_string(), json!((n * timed) as f64 / s * parallelism as f64))).collect::<serde_json::Map<_, _>>(),
        }));
        if let Some(row) = rows.last().filter(|_| !a.json) {
            print_row(row, i == 0, backend, &device);
        }
    }
    if a.json {
        let out = json!({"config": a.config, "padded": a.padded, "step_outputs": format!("{:?}", a.step_outputs).to_lowercase(), "backend": backend, "device": device, "threads": a.threads, "rows": rows});
        println!("{}", serde_json::to_string_pretty(&out)?);
    }
    Ok(())
}

/// Threads a stage's measured time is summed over: the CPU backend's threads, 1 for the GPU's
/// wall-clock stage timing.
fn stage_parallelism(env: &socnav::BatchEnv) -> usize {
    if env.backend_name() == "cpu" {
        env.threads()
    } else {
        1
    }
}

/// A batch of `n` environments of `config` whose environment i plays the episode of seed
/// `seed + i`, after [`WARMUP_STEPS`] steps with the benchmark's fixed actions; with them.
fn warmed_up(
    a: &BenchArgs,
    config: &Config,
    n: usize,
    seed: u64,
) -> Result<(socnav::BatchEnv, Vec<f32>), socnav::SimError> {
    let mut env = if chosen_device(a) {
        on_chosen_device(config, n, a)?
    } else {
        make_env(config.clone(), n, 0, a.backend, a.threads)?
    };
    env.set_step_outputs(a.step_outputs.into());
    env.reset(Some(seed))?;
    let actions: Vec<f32> = [0.8f32, 0.0, 0.3].repeat(n);
    for _ in 0..WARMUP_STEPS {
        env.step(Actions::Continuous(&actions))?;
    }
    Ok((env, actions))
}

/// Whether the arguments change the GPU device's settings (so the batch is made on a device of
/// [`on_chosen_device`]'s).
fn chosen_device(a: &BenchArgs) -> bool {
    a.lane_paths.is_some() || !a.leave_out.is_empty() || a.readback_piece_bytes.is_some()
}

/// A batch of `n` environments of `config` on the GPU backend with the paths of a software adapter
/// that `--lane-paths` names (every one without a name), the functions of `--leave-out`
/// returning at once and the readback pieces of `--readback-piece-bytes`.
#[cfg(feature = "gpu")]
fn on_chosen_device(
    config: &Config,
    n: usize,
    a: &BenchArgs,
) -> Result<socnav::BatchEnv, socnav::SimError> {
    use crate::args::LanePath;
    use socnav::backend::gpu::{AdapterPolicy, GpuDevice};
    let mut dev = GpuDevice::open(AdapterPolicy::Any)?;
    match a.lane_paths.as_deref() {
        None => {}
        Some([]) => dev = dev.with_lane_paths(),
        Some(paths) => {
            for path in paths {
                match path {
                    LanePath::Staging => dev.paths.stage_observations = false,
                    LanePath::Resets => dev.paths.resets_in_workgroups = false,
                    LanePath::Regroups => dev.paths.regroups_in_workgroups = false,
                    LanePath::Obstacles => dev.paths.obstacles_in_workgroups = false,
                    LanePath::Records => dev.paths.records_in_lanes = false,
                    LanePath::ResetObstacles => dev.paths.obstacles_after_resets = false,
                    LanePath::ReadbackAfterHostWork => dev.paths.readback_before_host_work = false,
                }
            }
        }
    }
    dev.paths.leave_out.clone_from(&a.leave_out);
    if let Some(bytes) = a.readback_piece_bytes {
        dev.paths.readback_piece_bytes = bytes;
    }
    let options = socnav::EnvOptions {
        n_envs: n,
        threads: a.threads,
        ..Default::default()
    };
    socnav::BatchEnv::on_device(config.clone(), options, dev)
}

#[cfg(not(feature = "gpu"))]
fn on_chosen_device(
    _: &Config,
    _: usize,
    _: &BenchArgs,
) -> Result<socnav::BatchEnv, socnav::SimError> {
    Err(socnav::SimError::BackendUnavailable(
        "--lane-paths, --leave-out and --readback-piece-bytes need the GPU backend, and this \
         build has none"
            .into(),
    ))
}

/// `n` environments as two batches of about `n / 2`, each stepped on a host thread of its own
/// for `a.seconds` after the warm-up: their env-steps per second together, and on the GPU backend
/// each half's host path per step.
fn halves_env_steps_per_s(
    a: &BenchArgs,
    config: &Config,
    n: usize,
) -> Result<(f64, Vec<serde_json::Value>), Box<dyn std::error::Error>> {
    let sizes = [n / 2, n - n / 2];
    let mut halves = Vec::with_capacity(2);
    for (k, &size) in sizes.iter().enumerate() {
        // The second half's environments play the episodes the whole batch's second half would.
        halves.push(warmed_up(a, config, size, (k * sizes[0]) as u64)?);
    }
    type Timed = Result<(usize, f64, Option<serde_json::Value>), socnav::SimError>;
    let timed: Vec<Timed> = std::thread::scope(|s| {
        let running: Vec<_> = halves
            .iter_mut()
            .map(|(env, actions)| {
                s.spawn(|| {
                    let before = env.host_path();
                    let (steps, secs) = timed_steps(env, actions, a.seconds)?;
                    Ok((
                        steps,
                        secs,
                        host_path_per_step(before, env.host_path(), steps, secs),
                    ))
                })
            })
            .collect();
        running
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect()
    });
    let (mut env_steps, mut longest, mut paths) = (0usize, 0.0f64, Vec::new());
    for (size, result) in sizes.iter().zip(timed) {
        let (steps, secs, path) = result?;
        env_steps += size * steps;
        longest = longest.max(secs);
        paths.extend(path);
    }
    Ok((env_steps as f64 / longest, paths))
}

fn print_row(row: &serde_json::Value, header: bool, backend: &str, device: &str) {
    if header {
        println!(
            "{backend} backend on {device}; per-stage figures are env-steps/s if the stage ran alone ({})",
            row["stage_clock"].as_str().unwrap_or("")
        );
    }
    println!(
        "envs {:>6}: {:>12.0} env-steps/s   ({} steps in {:.2} s; state {} B/env; obs {} floats/env)",
        row["envs"],
        row["env_steps_per_s"].as_f64().unwrap_or(0.0),
        row["steps"],
        row["seconds"].as_f64().unwrap_or(0.0),
        row["state_bytes_per_env"],
        row["obs_floats_per_env"]
    );
    if let Some(d) = row["device_only_env_steps_per_s"].as_f64() {
        println!(
            "    simulation on the device alone: {d:.0} env-steps/s (no outputs to the host, no reset rows refilled)"
        );
    }
    if let Some(h) = row["halves_env_steps_per_s"].as_f64() {
        println!("    as two halves on two host threads: {h:.0} env-steps/s");
    }
    if let Some(p) = row["host_path"].as_object() {
        print_host_path("host path per step", p);
    }
    let halves = row["halves_host_path"].as_array().into_iter().flatten();
    for (k, p) in halves.filter_map(|p| p.as_object()).enumerate() {
        print_host_path(
            &format!("half {} of the two, its host path per step", k + 1),
            p,
        );
    }
    if let Some(t) = row["timeline"].as_object() {
        let ms = |k: &str| {
            t[k].as_f64()
                .map_or("-".into(), |s| format!("{:.2}", 1e3 * s))
        };
        println!(
            "    on the device's clock ({} steps): {} ms before the passes, passes {} ms, readback copies {} ms a step; meanwhile the host waited {} ms and made rows ahead {} ms, then copied {} ms: {} ms beyond the device's part (submits, wake-ups, maps, the last piece's copy; the copies too where they are not timed, '-')",
            t["steps"],
            ms("before_passes_s"),
            ms("passes_s"),
            ms("readback_s"),
            ms("wait_s"),
            ms("refill_ahead_s"),
            ms("copy_s"),
            ms("host_beyond_s")
        );
    }
    if let Some(stages) = row["stage_env_steps_per_s"].as_object() {
        let cells: Vec<String> = stages
            .iter()
            .map(|(k, v)| {
                format!(
                    "{k} {:.2e} ({:.0} %)",
                    v.as_f64().unwrap_or(0.0),
                    100.0 * row["stage_share"][k].as_f64().unwrap_or(0.0)
                )
            })
            .collect();
        println!("    {}", cells.join(" | "));
    }
}

/// One line of a host path's figures per step (`host_path_per_step`'s), after `label`.
fn print_host_path(label: &str, p: &serde_json::Map<String, serde_json::Value>) {
    let ms = |k: &str| 1e3 * p[k].as_f64().unwrap_or(0.0);
    println!(
        "    {label}: {:.2} ms refilling the reset pool ({:.2} ms more while the device works, {:.1} rows), {:.2} ms waiting for the device ({:.2} of them submitting), {:.2} ms copying out, {:.2} ms else; {:.1} MB read back ({:.1} finished rows)",
        ms("refill_s"),
        ms("refill_ahead_s"),
        p["ahead_rows"].as_f64().unwrap_or(0.0),
        ms("wait_s"),
        ms("submit_s"),
        ms("copy_s"),
        ms("other_s"),
        p["bytes"].as_f64().unwrap_or(0.0) / 1e6,
        p["finished_rows"].as_f64().unwrap_or(0.0)
    );
}

/// The host path's figures per step between two totals over `steps` steps that took `secs`
/// (`None` on the CPU backend); `other_s` is the step's time outside the four parts.
fn host_path_per_step(
    before: Option<socnav::backend::HostPath>,
    after: Option<socnav::backend::HostPath>,
    steps: usize,
    secs: f64,
) -> Option<serde_json::Value> {
    let (b, a) = (before?, after?);
    let per = |x: f64| x / steps.max(1) as f64;
    let parts = a.refill_s - b.refill_s + a.refill_ahead_s - b.refill_ahead_s + a.wait_s - b.wait_s
        + a.copy_s
        - b.copy_s;
    Some(json!({
        "refill_s": per(a.refill_s - b.refill_s),
        "refill_ahead_s": per(a.refill_ahead_s - b.refill_ahead_s),
        "ahead_rows": per((a.ahead_rows - b.ahead_rows) as f64),
        "wait_s": per(a.wait_s - b.wait_s),
        "submit_s": per(a.submit_s - b.submit_s),
        "copy_s": per(a.copy_s - b.copy_s),
        "other_s": per(secs - parts),
        "bytes": per((a.bytes - b.bytes) as f64),
        "finished_rows": per((a.finished_rows - b.finished_rows) as f64),
        "second_reads": per((a.second_reads - b.second_reads) as f64),
    }))
}

/// The delivered step on the device's clock between two totals over `steps` steps, beside the
/// host's wait, rows ahead and copy in those steps (`None` without a device that has timestamp
/// queries); `before_passes_s` and `readback_s` are `null` where the adapter cannot time copies.
fn step_timeline(
    before: Option<socnav::backend::HostPath>,
    after: Option<socnav::backend::HostPath>,
    steps: usize,
) -> Option<serde_json::Value> {
    let (b, a) = (before?, after?);
    let timed = a.timed_reads - b.timed_reads;
    if timed == 0 {
        return None;
    }
    let per = |x: f64| x / steps.max(1) as f64;
    let copies = a.timed_copies - b.timed_copies;
    let passes = (a.device_s - b.device_s) / timed as f64;
    let copied = |x: f64| (copies > 0).then(|| x / copies as f64);
    let before = copied(a.before_passes_s - b.before_passes_s);
    let readback = copied(a.readback_s - b.readback_s);
    // The host's time from the submit to its outputs filled, less the device's part of it
    // (without timed copies, the copies stay in the host's part).
    let host = per(a.wait_s - b.wait_s + a.refill_ahead_s - b.refill_ahead_s + a.copy_s - b.copy_s);
    let device = passes + before.unwrap_or(0.0) + readback.unwrap_or(0.0);
    Some(json!({
        "steps": steps,
        "before_passes_s": before,
        "passes_s": passes,
        "readback_s": readback,
        "wait_s": per(a.wait_s - b.wait_s),
        "refill_ahead_s": per(a.refill_ahead_s - b.refill_ahead_s),
        "copy_s": per(a.copy_s - b.copy_s),
        "host_beyond_s": host - device,
    }))
}

/// Step for at least `seconds` (and 10 steps); the steps taken and the seconds they took.
fn timed_steps(
    env: &mut socnav::BatchEnv,
    actions: &[f32],
    seconds: f64,
) -> Result<(usize, f64), socnav::SimError> {
    let start = Instant::now();
    let mut steps = 0usize;
    while steps < 10 || start.elapsed().as_secs_f64() < seconds {
        env.step(Actions::Continuous(actions))?;
        steps += 1;
    }
    Ok((steps, start.elapsed().as_secs_f64()))
}
