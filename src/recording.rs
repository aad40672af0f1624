//! SocNavGym 0.1.1's episode recordings (its `manual_control_js.py -r`, docs/spec.md 9.2): one JSON
//! file per episode, `NNNNNNNN.json` in a directory, numbered on from the largest file already
//! there. A file is a dict from the step index (`"0"` for the observation the first step returned)
//! to `{"robot": [...], "humans": [...], "laptops": [...], "tables": [...], "plants": [...],
//! "walls": [...], "action": [a0, a1, a2], "reward": [r]}`: each observation key a flat list of
//! the entities present (0.1.1's unpadded robot-frame observation: socnav's zero-padded records
//! dropped), the action as three continuous values. `socnav play --record` and Python's
//! `socnav.datasets.JsonWriter` both write through [`episode_json`].

use std::fs;
use std::path::{Path, PathBuf};

use serde_json::{Map, Value};

use crate::error::SimError;
use crate::spec::{ENTITY_KEYS, ObsLayout, RECORD};

/// One step of an episode as recorded: the observation the step returned (a row of
/// `layout.dim` floats), the continuous action taken and the reward received.
#[derive(Debug, Clone, Copy)]
pub struct Step<'a> {
    /// Observation row.
    pub obs: &'a [f32],
    /// `[forward, lateral, rotation]`.
    pub action: [f32; 3],
    /// Reward of the step.
    pub reward: f32,
}

fn floats(values: &[f32]) -> Value {
    Value::Array(values.iter().map(|&v| Value::from(f64::from(v))).collect())
}

/// The observation keys of one row, 0.1.1's way (see the module docs).
fn observation(layout: &ObsLayout, row: &[f32], out: &mut Map<String, Value>) {
    out.insert("robot".into(), floats(&row[..layout.robot]));
    for (t, key) in ENTITY_KEYS.iter().enumerate() {
        let block = &row[layout.offset[t]..layout.offset[t] + layout.capacity[t] * RECORD];
        let present: Vec<f32> = block
            .chunks_exact(RECORD)
            .filter(|r| r.iter().any(|&v| v != 0.0))
            .flatten()
            .copied()
            .collect();
        out.insert((*key).into(), floats(&present));
    }
}

/// Refuse a layout whose robot record or entity blocks reach past its rows (one handed in from
/// Python, say), naming the block.
fn check_layout(layout: &ObsLayout) -> Result<(), SimError> {
    let past = |what: String, end: Option<usize>| {
        SimError::shape(
            "recording",
            format!(
                "recording: {what} ends at float {}, past the layout's {} a row",
                end.map_or_else(|| "2^64 or more".to_owned(), |e| e.to_string()),
                layout.dim
            ),
        )
    };
    if layout.robot > layout.dim {
        return Err(past(
            format!("the robot record of {} floats", layout.robot),
            Some(layout.robot),
        ));
    }
    for (t, key) in ENTITY_KEYS.iter().enumerate() {
        let (offset, capacity) = (layout.offset[t], layout.capacity[t]);
        let end = capacity
            .checked_mul(RECORD)
            .and_then(|n| n.checked_add(offset));
        if end.is_none_or(|end| end > layout.dim) {
            return Err(past(
                format!("`{key}` (offset {offset}, {capacity} records of {RECORD})"),
                end,
            ));
        }
    }
    Ok(())
}

/// The JSON text of one episode's recording.
///
/// # Errors
/// [`SimError::Shape`] when an observation row is not `layout.dim` floats long, or the layout's
/// blocks reach past its rows.
pub fn episode_json(layout: &ObsLayout, steps: &[Step<'_>]) -> Result<String, SimError> {
    check_layout(layout)?;
    // Written by hand at the top level: a serde_json map would order the step keys as strings
    // ("10" before "2"), and 0.1.1's files list the steps in order.
    let mut doc = String::from("{");
    for (t, step) in steps.iter().enumerate() {
        if step.obs.len() != layout.dim {
            return Err(SimError::shape(
                "recording",
                format!(
                    "recording: step {t} has an observation of {} floats, the layout {}",
                    step.obs.len(),
                    layout.dim
                ),
            ));
        }
        let mut entry = Map::new();
        observation(layout, step.obs, &mut entry);
        entry.insert("action".into(), floats(&step.action));
        entry.insert("reward".into(), floats(&[step.reward]));
        if t > 0 {
            doc.push(',');
        }
        doc.push_str(&format!("\"{t}\":{}", Value::Object(entry)));
    }
    doc.push('}');
    Ok(doc)
}

/// A directory of recordings, numbered as 0.1.1 numbers them.
#[derive(Debug)]
pub struct RecordingDir {
    dir: PathBuf,
    next: u64,
}

impl RecordingDir {
    /// Open (and create) `dir`; the next file is numbered after the largest `NNNNNNNN.json` there.
    ///
    /// # Errors
    /// [`SimError::Io`] naming the directory when it cannot be created or read.
    pub fn open(dir: &Path) -> Result<Self, SimError> {
        let io = |e: std::io::Error| SimError::io("recording directory", dir, &e);
        fs::create_dir_all(dir).map_err(io)?;
        let mut next = 0;
        for entry in fs::read_dir(dir).map_err(io)? {
            let name = entry.map_err(io)?.file_name();
            let name = name.to_string_lossy();
            if let Some(n) = name
                .strip_suffix(".json")
                .and_then(|s| s.parse::<u64>().ok())
            {
                // A file numbered u64::MAX leaves no number after it.
                next = next.max(n.checked_add(1).ok_or_else(|| {
                    SimError::io_other(
                        Some(dir),
                        format!(
                            "recording directory {}: {name} leaves no number after it",
                            dir.display()
                        ),
                    )
                })?);
            }
        }
        Ok(Self {
            dir: dir.to_path_buf(),
            next,
        })
    }

    /// Write `json` as the next file (whole or not at all: written aside, then renamed) and
    /// `sidecar` (socnav's own record of the episode, if any) as `NNNNNNNN.socnav.json`; the
    /// recording's path.
    ///
    /// # Errors
    /// [`SimError::Io`] naming the file (a full disk, a vanished directory).
    pub fn write(&mut self, json: &str, sidecar: Option<&str>) -> Result<PathBuf, SimError> {
        let path = self.dir.join(format!("{:08}.json", self.next));
        if let Some(side) = sidecar {
            write_whole(
                &self.dir.join(format!("{:08}.socnav.json", self.next)),
                side,
            )?;
        }
        write_whole(&path, json)?;
        self.next += 1;
        Ok(path)
    }
}

fn write_whole(path: &Path, text: &str) -> Result<(), SimError> {
    // Named after the whole file, so that it replaces nothing else of the directory's.
    let mut part = path.as_os_str().to_owned();
    part.push(".part");
    let part = PathBuf::from(part);
    let io = |e: std::io::Error| SimError::io("cannot write", path, &e);
    fs::write(&part, text).map_err(io)?;
    fs::rename(&part, path).map_err(io)
}
