//! `socnav run --backend gpu` reports exactly what `--backend cpu` reports for the same config,
//! seed and policy (issue 4), apart from the fields that time the run or name the backend: the
//! GPU backend is bit-identical to the CPU backend, so every outcome, metric and event count
//! matches. Needs a GPU adapter (lavapipe will do); skips loudly without one unless
//! `REQUIRE_GPU=1`. Also: the tool ends quietly when its reader closes the pipe.

use crate::common;

use std::process::Command;

use serde_json::Value;

/// `socnav run --json` with `args`, parsed.
fn run_json(args: &[&str]) -> Value {
    json_of("run", args)
}

/// `socnav <command> --json` with `args`, which must succeed, its report parsed.
fn json_of(command: &str, args: &[&str]) -> Value {
    let out = Command::new(env!("CARGO_BIN_EXE_socnav"))
        .args([command, "--json"])
        .args(args)
        .output()
        .expect("socnav runs");
    assert!(
        out.status.success(),
        "socnav {command} {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON on stdout")
}

/// The report without the fields that time the run or name what ran it.
fn comparable(mut v: Value) -> Value {
    let map = v.as_object_mut().expect("a JSON object");
    for key in ["seconds", "env_steps_per_s", "backend", "device", "threads"] {
        assert!(map.remove(key).is_some(), "report field {key} missing");
    }
    v
}

/// Contract: the JSON reports of the two backends are equal for exp2 and exp3 (random policy,
/// goal policy), autoresets and social events included. 100 environments (not a multiple of the
/// workgroup) over 300 steps: every environment ends an episode at least once.
#[test]
fn run_reports_match() {
    if common::gpu::device().is_none() {
        return;
    }
    for (config, policy) in [("exp2", "random"), ("exp3", "goal")] {
        let base = [
            "--config", config, "--envs", "100", "--steps", "300", "--seed", "5", "--policy",
            policy,
        ];
        let cpu = run_json(&[&base[..], &["--backend", "cpu"]].concat());
        let gpu = run_json(&[&base[..], &["--backend", "gpu"]].concat());
        assert_eq!(gpu["backend"], "gpu");
        assert!(
            cpu["episodes"].as_u64().unwrap_or(0) > 0,
            "{config}: no episode ended"
        );
        assert_eq!(
            comparable(cpu),
            comparable(gpu),
            "{config} ({policy}): reports differ"
        );
    }
}

/// A reader that closes the pipe early (`socnav check-config ... | head -1`) ends the tool as it
/// ends Unix tools, by SIGPIPE, never with a panic ("failed printing to stdout").
#[cfg(unix)]
#[test]
fn a_closed_pipe_ends_the_tool_quietly() {
    use std::os::unix::process::ExitStatusExt;
    use std::process::{Command, Stdio};
    // A pipe whose reader is gone before the tool starts, so its first write fails.
    let (reader, writer) = std::io::pipe().expect("a pipe");
    drop(reader);
    let out = Command::new(env!("CARGO_BIN_EXE_socnav"))
        .args(["check-config", "configs/exp2.toml"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(writer)
        .stderr(Stdio::piped())
        .output()
        .expect("socnav runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(
        out.status.signal(),
        Some(13),
        "ended by SIGPIPE: {:?}",
        out.status
    );
}

/// `socnav bench --lane-paths` takes a software adapter's paths on the GPU backend (every one, or
/// those named) and `--readback-piece-bytes` the readback pieces given, and the device line says
/// so; without `--backend gpu` either is refused with an error naming the backend given, and a
/// path it does not know with one naming it.
#[test]
fn bench_lane_paths_names_the_paths_it_took() {
    let bench = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_socnav"))
            .args([
                "bench",
                "--json",
                "--config",
                "exp1",
                "--envs",
                "3",
                "--seconds",
                "0.1",
            ])
            .args(args)
            .output()
            .expect("socnav runs")
    };
    let refused = bench(&["--lane-paths", "--backend", "cpu"]);
    assert!(!refused.status.success(), "--lane-paths on the CPU ran");
    let why = String::from_utf8_lossy(&refused.stderr);
    assert!(
        why.contains("--lane-paths") && why.contains("Cpu"),
        "unclear refusal: {why}"
    );
    let refused = bench(&["--readback-piece-bytes", "64"]);
    assert!(
        !refused.status.success(),
        "--readback-piece-bytes on auto ran"
    );
    let why = String::from_utf8_lossy(&refused.stderr);
    assert!(
        why.contains("--readback-piece-bytes") && why.contains("Auto"),
        "unclear refusal: {why}"
    );
    let unknown = bench(&["--lane-paths", "records,walls", "--backend", "gpu"]);
    assert!(!unknown.status.success(), "--lane-paths walls ran");
    let why = String::from_utf8_lossy(&unknown.stderr);
    assert!(why.contains("'walls'"), "unclear refusal: {why}");
    if common::gpu::device().is_none() {
        return;
    }
    let device_line = |lane_paths: &[&str]| -> String {
        let out = bench(&[&["--backend", "gpu", "--lane-paths"], lane_paths].concat());
        assert!(
            out.status.success(),
            "socnav bench --lane-paths {lane_paths:?} failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let report: Value = serde_json::from_slice(&out.stdout).expect("JSON on stdout");
        report["device"].as_str().expect("a device line").to_owned()
    };
    // exp1's rows have entity records, so the line says where they are written. Three
    // environments' per-step outputs (about 8 KB) in pieces of 64 bytes: the most pieces, four.
    let device = device_line(&[
        "records,readback-after-host-work",
        "--readback-piece-bytes",
        "64",
    ]);
    assert!(
        device.contains("entity records in the observing lane")
            && device.contains("read back in 4 pieces")
            && device.contains("submitted after the host's work"),
        "{device}"
    );
    let device = device_line(&[]);
    assert!(
        device.contains("observations written in place")
            && device.contains("entity records in the observing lane")
            && device.contains("resets on one lane each")
            && device.contains("regroupings on one lane each")
            && device.contains("obstacle rebuilds over the scratch buffer")
            && device.contains("a reset's obstacles built on the host")
            && device.contains("read back in one piece")
            && device.contains("submitted after the host's work"),
        "{device}"
    );
}

/// `socnav bench --halves` steps the batch as two halves on two host threads and reports their
/// env-steps per second together; on the GPU backend each half's host path per step besides (where
/// two halves lose against one batch), on the CPU backend none.
#[test]
fn bench_halves_report_each_half_host_path_on_the_gpu() {
    let halves = |backend: &str| -> Value {
        let args = [
            "--config",
            "exp1",
            "--envs",
            "5",
            "--seconds",
            "0.1",
            "--halves",
        ];
        json_of("bench", &[&args[..], &["--backend", backend]].concat())["rows"][0].clone()
    };
    let cpu = halves("cpu");
    assert!(cpu["halves_env_steps_per_s"].as_f64() > Some(0.0), "{cpu}");
    assert_eq!(cpu["halves_host_path"], serde_json::json!([]), "{cpu}");
    if common::gpu::device().is_none() {
        return;
    }
    let gpu = halves("gpu");
    assert!(gpu["halves_env_steps_per_s"].as_f64() > Some(0.0), "{gpu}");
    let paths = gpu["halves_host_path"].as_array().expect("a list");
    assert_eq!(paths.len(), 2, "{gpu}");
    for path in paths {
        // Every step reads back its outputs: 2 and 3 environments' observations at least.
        assert!(path["bytes"].as_f64() > Some(2.0 * 4.0 * 37.0), "{path}");
        assert!(path["wait_s"].as_f64() > Some(0.0), "{path}");
    }
}

/// `scripts/bench-gpu` with `DRY_RUN=1` in a tree whose `scripts/bench-gpu` is `script` and
/// whose `shaders` and `benches` are the repository's: its exit status and output.
fn bench_gpu_dry_run(test: &str, script: &str) -> (bool, String) {
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let tree = std::env::temp_dir().join(format!("socnav-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tree);
    std::fs::create_dir_all(tree.join("scripts")).expect("a temporary tree");
    for dir in ["shaders", "benches"] {
        std::os::unix::fs::symlink(repo.join(dir), tree.join(dir)).expect("a link");
    }
    std::fs::write(tree.join("scripts/bench-gpu"), script).expect("the script written");
    let out = Command::new("bash")
        .arg(tree.join("scripts/bench-gpu"))
        .env("DRY_RUN", "1")
        .env("SOCNAV", env!("CARGO_BIN_EXE_socnav"))
        .env("OUT_DIR", tree.join("out"))
        .output()
        .expect("bash runs");
    let _ = std::fs::remove_dir_all(&tree);
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    (out.status.success(), text)
}

/// Every row of `scripts/bench-gpu`, the script a GPU machine runs for issue 19's figures, is
/// one `socnav bench` takes (its flags and their values), names functions of the shaders in
/// `--leave-out` and groups of the bench `step` (its dry run: a typo found here, not on a GPU
/// machine's scarce time); and the dry run refuses a row with an unknown flag, an unknown lane
/// path, a function no shader defines and a criterion group the bench lacks, naming each.
#[test]
fn every_row_of_bench_gpu_is_taken() {
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let script = std::fs::read_to_string(repo.join("scripts/bench-gpu")).expect("the script");
    let (ok, out) = bench_gpu_dry_run("bench-gpu-dry", &script);
    assert!(ok, "{out}");
    let taken = out.matches("its arguments are taken").count();
    assert!(taken >= 20, "only {taken} rows checked:\n{out}");
    assert!(
        out.contains("== obs_rows: a group of the bench step"),
        "{out}"
    );

    let last = "measure exp2-cpu ";
    let bad_rows = "measure bad-flag --config exp2 --backend gpu --paded\n\
                    measure bad-path --config exp2 --backend gpu --lane-paths regrup\n\
                    measure bad-function --config exp2 --backend gpu --leave-out regroup_sort\n\
                    criterion obs_rowz\n";
    let broken = script.replacen(last, &format!("{bad_rows}{last}"), 1);
    assert_ne!(broken, script, "the script has no row `{last}`");
    let (ok, out) = bench_gpu_dry_run("bench-gpu-dry-broken", &broken);
    assert!(!ok, "a dry run with bad rows passed:\n{out}");
    for name in ["bad-flag", "bad-path", "bad-function", "obs_rowz"] {
        assert!(
            out.lines()
                .any(|l| l.contains("FAILED") && l.contains(name)),
            "{name} not refused:\n{out}"
        );
    }
    assert!(out.contains("dry run: 4 rows not taken"), "{out}");
}
