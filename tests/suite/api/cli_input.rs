//! The command-line tool's bad input: refused with a message naming it and exit status 1 (2 for
//! what the argument parser refuses), never a panic, and nothing of the user's overwritten.

use std::path::PathBuf;
use std::process::{Command, Output};

fn socnav(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_socnav"))
        .args(args)
        .output()
        .expect("socnav runs")
}

/// The output's standard error, checked to be a refusal (no panic) with status `code`.
fn refused(out: &Output, code: i32) -> String {
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(code), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("socnav-cli-input-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Contract: `soak --record` resumes only a soak record of the same batch; any other file is
/// refused and left byte for byte, and the temporary file it writes through replaces nothing.
#[test]
fn soak_resumes_only_its_own_record_and_overwrites_nothing_else() {
    let dir = scratch("soak");
    let record = dir.join("s.json");
    let soak = |envs: &str, steps: &str| {
        let path = record.to_str().unwrap();
        socnav(&[
            "soak",
            "--configs",
            "exp1",
            "--chunk",
            "4",
            "--envs",
            envs,
            "--steps",
            steps,
            "--record",
            path,
        ])
    };
    for foreign in [
        r#"{"name": "my-package", "version": "1.0"}"#,
        "[1, 2, 3]",
        r#"{"format": "socnav-soak/2", "configs": {}}"#,
    ] {
        std::fs::write(&record, foreign).unwrap();
        let err = refused(&soak("2", "4"), 1);
        assert!(err.contains("not a soak record to resume"), "{err}");
        assert_eq!(std::fs::read_to_string(&record).unwrap(), foreign);
    }
    std::fs::remove_file(&record).unwrap();
    std::fs::write(dir.join("s.part"), "precious").unwrap();
    let out = soak("2", "4");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("s.part")).unwrap(),
        "precious"
    );
    let first = std::fs::read_to_string(&record).unwrap();
    // Another batch would add its tallies to this one's: refused, the record kept.
    let err = refused(&soak("4", "4"), 1);
    assert!(
        err.contains("--envs 2") && err.contains("--envs 4"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&record).unwrap(), first);
    // The same batch resumes: its steps go on from the record's.
    let longer = soak("2", "8");
    assert!(
        longer.status.success(),
        "{}",
        String::from_utf8_lossy(&longer.stderr)
    );
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&record).unwrap()).unwrap();
    assert_eq!(doc["configs"]["exp1"]["env_steps"], 8, "{doc}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Contract: output that cannot be written (a full disk) is an error line and status 1, not a
/// panic.
#[test]
fn output_that_cannot_be_written_is_an_error_not_a_panic() {
    let Ok(full) = std::fs::File::create("/dev/full") else {
        crate::common::skip::skip(None, "no /dev/full here");
        return;
    };
    let out = Command::new(env!("CARGO_BIN_EXE_socnav"))
        .args(["check-config", "exp1"])
        .stdout(full)
        .output()
        .expect("socnav runs");
    let err = refused(&out, 1);
    assert!(err.contains("error: failed printing to stdout"), "{err}");
}

/// Contract: numbers outside what a command can do are refused before it starts, by name.
#[test]
fn out_of_range_numbers_are_refused_up_front() {
    for (args, needle) in [
        (&["bench", "--envs", "2", "--seconds", "nan"][..], "nan"),
        (&["bench", "--envs", "2", "--seconds=-1"], "-1"),
        (&["bench", "--envs", "2", "--seconds", "inf"], "inf"),
        (&["bench", "--envs", "2,0", "--seconds", "0.1"], "--envs"),
        (&["soak", "--chunk", "0"], "--chunk"),
        (&["soak", "--check-every", "0"], "--check-every"),
        (&["play", "--episodes", "0"], "--episodes"),
    ] {
        let err = refused(&socnav(args), 2);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    // Checked before the window is opened: no display is needed to be refused.
    let err = refused(&socnav(&["play", "--speed", "1000"]), 1);
    assert!(
        err.contains("--speed 1000") && err.contains("1/16 to 16"),
        "{err}"
    );
    // Checked before the SNGNN-v2 weights load (they need not be installed to be refused).
    for (args, needle) in [
        (&["--heading", "nan"][..], "heading NaN rad"),
        (&["--heading", "3e6"], "heading 3000000 rad"),
        (&["--size", "0"], "--size 0"),
    ] {
        let out = socnav(&[&["heatmap", "--out", "never.png"][..], args].concat());
        let err = refused(&out, 1);
        assert!(
            err.contains(needle) && !err.contains("SNGNN-v2 ready"),
            "{args:?}: {err}"
        );
    }
}

/// Contract: a SocNavGym 0.1.1 YAML file is a `--config` like a TOML file: `run` rolls out the
/// same episodes as its shipped twin, `check-config` prints the converted TOML, and a bad key in it
/// is refused by name.
#[test]
fn socnavgym_yaml_configs_run_as_their_shipped_twins() {
    let yaml = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/golden/socnavgym/configs/exp2_no_sngnn.yaml");
    let yaml = yaml.to_str().unwrap();
    let outcome = |config: &str| {
        let args = ["run", "--config", config, "--envs", "8", "--steps", "60"];
        let out = socnav(&[&args[..], &["--backend", "cpu", "--json"]].concat());
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let mut v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let o = v.as_object_mut().unwrap();
        for timing in ["config", "env_steps_per_s", "seconds"] {
            o.remove(timing).unwrap();
        }
        v
    };
    assert_eq!(outcome(yaml), outcome("exp2"));
    let text = |args: &[&str]| String::from_utf8(socnav(args).stdout).unwrap();
    let skip_title = |s: String| s.lines().skip(1).collect::<Vec<_>>().join("\n");
    assert_eq!(
        skip_title(text(&["check-config", yaml])),
        skip_title(text(&["check-config", "exp2"]))
    );
    let dir = scratch("yaml");
    let bad = dir.join("later.yaml");
    let source = std::fs::read_to_string(yaml).unwrap();
    std::fs::write(
        &bad,
        source.replace("env:\n", "env:\n  max_rotation_human: 1.57\n"),
    )
    .unwrap();
    let err = refused(&socnav(&["check-config", bad.to_str().unwrap()]), 1);
    assert!(
        err.contains("`env.max_rotation_human` belongs to a later SocNavGym version"),
        "{err}"
    );
}
