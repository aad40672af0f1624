//! The live viewer's parts that need no screen (`socnav play` without a display fails clearly)
//! and SocNavGym 0.1.1's JSON recordings (`socnav::recording`). The window itself is tested for
//! real under a virtual display by `scripts/test-viewer` (python/tests/test_viewer.py).

use std::process::Command;

use serde_json::Value;
use socnav::recording::{RecordingDir, Step, episode_json};
use socnav::spec::{ENTITY_KEYS, ObsLayout, RECORD};
use socnav::{Actions, AutoresetMode, BatchEnv, Config, EnvOptions};

#[test]
fn play_without_a_display_says_so_and_fails() {
    let o = Command::new(env!("CARGO_BIN_EXE_socnav"))
        .args(["play", "--config", "exp1"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("socnav runs");
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("no display") && err.contains("xvfb-run"),
        "{err}"
    );
    let o = Command::new(env!("CARGO_BIN_EXE_socnav"))
        .args(["play", "--speed", "NaN"])
        .output()
        .expect("socnav runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("--speed NaN"), "{err}");
}

/// A few steps of lroom_mixed (every entity kind; fewer humans than the observation's capacity,
/// so the blocks hold padding).
fn steps_of_lroom(n: usize) -> (BatchEnv, Vec<Vec<f32>>, Vec<f32>) {
    let options = EnvOptions {
        n_envs: 1,
        seed: 5,
        autoreset: AutoresetMode::Disabled,
        threads: Some(1),
        ..Default::default()
    };
    let mut env =
        BatchEnv::new(Config::from_name_or_path("lroom_mixed").unwrap(), options).unwrap();
    env.reset(Some(5)).unwrap();
    let (mut rows, mut rewards) = (Vec::new(), Vec::new());
    for _ in 0..n {
        env.step(Actions::Continuous(&[1.0, 0.0, 0.5])).unwrap();
        let dim = env.layout().dim;
        rows.push(env.outputs().obs[..dim].to_vec());
        rewards.push(env.outputs().reward[0]);
    }
    (env, rows, rewards)
}

#[test]
fn recordings_have_0_1_1s_layout() {
    let (env, rows, rewards) = steps_of_lroom(3);
    let layout = *env.layout();
    let steps: Vec<Step<'_>> = rows
        .iter()
        .zip(&rewards)
        .map(|(obs, &reward)| Step {
            obs,
            action: [1.0, 0.0, 0.5],
            reward,
        })
        .collect();
    let doc: Value = serde_json::from_str(&episode_json(&layout, &steps).unwrap()).unwrap();
    let doc = doc.as_object().unwrap();
    assert_eq!(doc.keys().collect::<Vec<_>>(), ["0", "1", "2"]);
    for (t, row) in rows.iter().enumerate() {
        let step = &doc[&t.to_string()];
        let floats = |key: &str| -> Vec<f32> {
            step[key]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap() as f32)
                .collect()
        };
        assert_eq!(floats("robot"), row[..layout.robot]);
        assert_eq!(floats("action"), [1.0, 0.0, 0.5]);
        assert_eq!(floats("reward"), [rewards[t]]);
        // The entities present, in slot order (socnav packs them first and pads after them), and
        // nothing of the padding: 14 floats for each human, laptop, table and plant of the scene.
        let st = env.state().unwrap();
        let counts = [
            st.n_humans[0],
            st.n_laptops[0],
            st.n_tables[0],
            st.n_plants[0],
        ];
        for (k, key) in ENTITY_KEYS.iter().take(4).enumerate() {
            let n = counts[k] as usize;
            let start = layout.offset[k];
            assert_eq!(
                floats(key),
                row[start..start + n * RECORD],
                "step {t} {key}"
            );
        }
        assert_eq!(floats("walls").len() % RECORD, 0);
        assert!(!floats("humans").is_empty() && !floats("tables").is_empty());
    }
    let short = Step {
        obs: &rows[0][1..],
        action: [0.0; 3],
        reward: 0.0,
    };
    let err = episode_json(&layout, &[short]).unwrap_err().to_string();
    assert!(
        err.contains("step 0") && err.contains(&layout.dim.to_string()),
        "{err}"
    );
    // A layout whose blocks reach past its rows is refused by name, whatever the rows.
    let step = Step {
        obs: &rows[0],
        action: [0.0; 3],
        reward: 0.0,
    };
    let refused = |broken: ObsLayout, names: &[&str]| {
        let err = episode_json(&broken, &[step]).unwrap_err().to_string();
        assert!(names.iter().all(|n| err.contains(n)), "{names:?}: {err}");
    };
    refused(
        ObsLayout {
            robot: layout.dim + 1,
            ..layout
        },
        &["robot record", &(layout.dim + 1).to_string()],
    );
    let mut walls_past = layout;
    walls_past.offset[4] = layout.dim - RECORD * layout.capacity[4] + 1;
    refused(walls_past, &["`walls`", "past the layout's"]);
    let mut huge = layout;
    huge.capacity[0] = usize::MAX / 2;
    refused(huge, &["`humans`", "2^64 or more"]);
}

#[test]
fn recording_files_are_numbered_after_the_largest() {
    let dir = std::env::temp_dir().join(format!("socnav-recording-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("00000041.json"), "{}").unwrap();
    std::fs::write(dir.join("notes.json"), "{}").unwrap();
    let mut rec = RecordingDir::open(&dir).unwrap();
    let first = rec.write("{}", Some("{\"seed\": 1}")).unwrap();
    let second = rec.write("{}", None).unwrap();
    assert_eq!(first.file_name().unwrap(), "00000042.json");
    assert_eq!(second.file_name().unwrap(), "00000043.json");
    assert!(dir.join("00000042.socnav.json").exists());
    // A sidecar does not advance the numbering of a directory opened again.
    assert_eq!(
        RecordingDir::open(&dir)
            .unwrap()
            .write("{}", None)
            .unwrap()
            .file_name()
            .unwrap(),
        "00000044.json"
    );
    let no_dir = RecordingDir::open(&dir.join("00000041.json"))
        .unwrap_err()
        .to_string();
    assert!(no_dir.contains("00000041.json"), "{no_dir}");
    // The temporary file a recording is written through is named after it: a user's
    // `00000044.part` is not touched.
    std::fs::write(dir.join("00000044.part"), "mine").unwrap();
    RecordingDir::open(&dir).unwrap().write("{}", None).unwrap();
    assert_eq!(
        std::fs::read_to_string(dir.join("00000044.part")).unwrap(),
        "mine"
    );
    // A file numbered u64::MAX leaves no number after it: an error naming it, not an overflow.
    std::fs::write(dir.join(format!("{}.json", u64::MAX)), "{}").unwrap();
    let full = RecordingDir::open(&dir).unwrap_err().to_string();
    assert!(full.contains(&u64::MAX.to_string()), "{full}");
    std::fs::remove_dir_all(&dir).unwrap();
}
