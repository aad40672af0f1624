//! Discomfort heatmaps (the SocNavGym paper's figure of discomfort around people): one scene,
//! the robot placed at every point of an N × N grid over the room, and for each placement the
//! two discomfort terms of the reward: SNGNN-v2's score (docs/spec.md 6.3) and the DSRNN term
//! (docs/spec.md 6.2).
//!
//! The scene and what each placement sees:
//!
//! - **Scene.** Environment 0 of a batch of the config is reset with the seed and stepped once
//!   with the zero action (the robot stays at rest where it spawned; the humans walk one step,
//!   avoiding the robot where the config makes them). The heatmap shows the state after that
//!   step: one step is what gives the humans velocities.
//! - **Placement.** The robot is moved to the cell's centre with the fixed heading, at rest (zero
//!   command, zero velocity), as if it had stood there during the step; the goal, the humans and
//!   the objects stay as they are. Humans are not re-simulated for each placement.
//! - **SNGNN-v2.** The frame is the one the reward would record for that placement on that step
//!   ([`crate::sngnn::frame::record`]): positions and headings in the placed robot's frame,
//!   velocities the backward differences from each entity's pose before the step (seen from the
//!   same placement, since the robot did not move), command zero. The history holds only this frame,
//!   so the graph is a single-frame graph (as on an episode's first step). The value is the
//!   room node's q1 clipped to [0, 1], the reward's `DISCOMFORT_SNGNN`; the SNGNN reward term
//!   is q1 − 1, so 1 is "no discomfort" and lower values are worse.
//! - **DSRNN.** [`crate::systems::reward::min_predicted_clearance`] with the robot at rest and
//!   the humans' velocities of the step, turned into the discomfort term
//!   [`crate::systems::reward::dsrnn_discomfort`]: (d − 0.6)·0.5·dt when d < 0.6 m, else 0.
//! - **Masked cells** (NaN in both fields, their reason in [`Heatmap::mask`]): the robot's disc
//!   touches a human, or an object or wall (the collision test of the termination stage), or its
//!   centre lies in an L room's removed block (outside the room).
//!
//! Cells are independent: they are evaluated in parallel on rayon's pool, each thread with two
//! one-environment states it reuses (no state per cell), so the fields do not depend on the
//! thread count.
//!
//! A tool over the whole simulator (it runs a `BatchEnv`, loads state documents and calls the
//! reward's terms), so it sits at the top beside `render`, not inside `sngnn`.

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use crate::config::{Config, RewardKind};
use crate::document;
use crate::geometry::Disc;
use crate::sngnn::{self, Scorer};
use crate::state::{BatchState, Caps, StateChunk, blocker_kind};
use crate::systems::{reward, sngnn_score, world};
use crate::{Actions, BatchEnv, SimError, StepParams};

/// Smallest grid side.
pub const MIN_GRID: usize = 2;
/// Largest grid side: 400² = 160,000 placements, minutes of SNGNN-v2 on two cores.
pub const MAX_GRID: usize = 400;

/// Why a cell is not scored (values of [`Heatmap::mask`]).
pub mod cell {
    /// Scored.
    pub const FREE: u8 = 0;
    /// The robot's disc touches a human.
    pub const HUMAN: u8 = 1;
    /// The robot's disc touches an object or a wall.
    pub const OBSTACLE: u8 = 2;
    /// The robot's centre is outside the room (an L room's removed block).
    pub const OUTSIDE: u8 = 3;
}

/// The two discomfort fields of one scene. Cell (row, col) is index `row * n + col`; row 0 is the
/// lowest y, column 0 the lowest x; its centre is [`Heatmap::centre`].
#[derive(Debug, Clone, PartialEq)]
pub struct Heatmap {
    /// Grid side.
    pub n: usize,
    /// Room size (m) along x and y: the grid covers `[-map_x/2, map_x/2] × [-map_y/2, map_y/2]`.
    pub map: (f32, f32),
    /// The robot's heading at every placement (rad, world frame).
    pub heading: f32,
    /// [`cell`] code per cell.
    pub mask: Vec<u8>,
    /// SNGNN-v2's q1 clipped to [0, 1] per cell (1 = no discomfort); NaN where masked. Empty
    /// when the field was not asked for.
    pub sngnn: Vec<f32>,
    /// The DSRNN discomfort term per cell (≤ 0; 0 beyond 0.6 m of predicted clearance); NaN where
    /// masked.
    pub dsrnn: Vec<f32>,
}

impl Heatmap {
    /// World position (m) of the centre of cell (row, col).
    pub fn centre(&self, row: usize, col: usize) -> (f32, f32) {
        cell_centre(self.n, self.map, row, col)
    }
}

fn cell_centre(n: usize, (mx, my): (f32, f32), row: usize, col: usize) -> (f32, f32) {
    let x = -0.5 * mx + (col as f32 + 0.5) * mx / n as f32;
    let y = -0.5 * my + (row as f32 + 0.5) * my / n as f32;
    (x, y)
}

/// One scene, ready to be evaluated at any placement of the robot.
#[derive(Debug)]
pub struct Scene {
    params: StepParams,
    /// The scene before its step (for the backward-difference velocities) and after it, each a
    /// one-environment state with the SNGNN frame columns.
    before: BatchState,
    after: BatchState,
}

impl Scene {
    /// Environment 0 of `config` reset with `seed` and stepped once at rest (module docs). Needs
    /// no weights: the scene's batch runs with the DSRNN reward (the reward does not change the
    /// motion), and the states kept carry the SNGNN frame columns whatever the config's reward.
    ///
    /// # Errors
    /// An invalid config or a scenario that cannot be generated.
    pub fn new(config: &Config, seed: u64) -> Result<Self, SimError> {
        let mut stepping = config.clone();
        stepping.reward.kind = RewardKind::Dsrnn;
        let mut env = BatchEnv::single(stepping, seed)?;
        let before = env.get_state(0)?;
        env.step(Actions::Continuous(&[0.0; 3]))?;
        let after = env.get_state(0)?;
        let mut framed = config.clone();
        framed.reward.kind = RewardKind::Sngnn;
        let caps = Caps::from_config(&framed);
        let params = *env.params();
        let load = |mut doc: serde_json::Value| -> Result<BatchState, SimError> {
            doc["state"]["sngnn_frames"] = serde_json::json!([]);
            let mut s = BatchState::new(1, caps);
            document::import(&params, &mut s, 0, &doc)?;
            Ok(s)
        };
        Ok(Self {
            params,
            before: load(before)?,
            after: load(after)?,
        })
    }

    /// The step constants.
    pub fn params(&self) -> &StepParams {
        &self.params
    }

    /// The scene's state (after its step; one environment), for drawing.
    pub fn state(&self) -> &BatchState {
        &self.after
    }

    /// The robot's heading in the scene (rad, world frame).
    pub fn robot_heading(&self) -> f32 {
        self.after.robot_theta[0]
    }

    /// The heatmap of an `n` × `n` grid with the robot's heading `heading` (rad, world frame);
    /// the SNGNN-v2 field only with a scorer. `progress` is called with the number of cells
    /// done so far (from any thread, in no particular order).
    ///
    /// # Errors
    /// A grid side outside `MIN_GRID..=MAX_GRID` or a heading that is not finite.
    pub fn heatmap(
        &self,
        n: usize,
        heading: f32,
        scorer: Option<&Scorer>,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<Heatmap, SimError> {
        check_grid(n)?;
        check_heading(heading)?;
        let map = (self.after.map_x[0], self.after.map_y[0]);
        let mut scene = self.after.clone();
        let c = scene.chunk();
        let mask: Vec<u8> = (0..n * n)
            .map(|k| {
                let (x, y) = cell_centre(n, map, k / n, k % n);
                placement_mask(&self.params, &c, x, y)
            })
            .collect();
        let done = AtomicUsize::new(0);
        let values: Vec<(f32, f32)> = (0..n * n)
            .into_par_iter()
            .map_init(
                || (self.before.clone(), self.after.clone()),
                |(before, after), k| {
                    let v = if mask[k] == cell::FREE {
                        let (x, y) = cell_centre(n, map, k / n, k % n);
                        self.evaluate(before, after, [x, y, heading], scorer)
                    } else {
                        (f32::NAN, f32::NAN)
                    };
                    progress(done.fetch_add(1, Ordering::Relaxed) + 1);
                    v
                },
            )
            .collect();
        let sngnn = if scorer.is_some() {
            values.iter().map(|v| v.0).collect()
        } else {
            Vec::new()
        };
        Ok(Heatmap {
            n,
            map,
            heading,
            mask,
            sngnn,
            dsrnn: values.iter().map(|v| v.1).collect(),
        })
    }

    /// (SNGNN-v2 q1 clipped, DSRNN term) with the robot at rest at `pose` (m, m, rad); the first
    /// is NaN without a scorer. `before` and `after` are the caller's copies of the scene's
    /// states: their robot, previous poses and history are overwritten.
    fn evaluate(
        &self,
        before: &mut BatchState,
        after: &mut BatchState,
        [x, y, theta]: [f32; 3],
        scorer: Option<&Scorer>,
    ) -> (f32, f32) {
        let p = &self.params;
        for s in [&mut *before, &mut *after] {
            s.robot_x[0] = x;
            s.robot_y[0] = y;
            s.robot_theta[0] = theta;
            s.robot_vx[0] = 0.0;
            s.robot_vy[0] = 0.0;
            s.robot_w[0] = 0.0;
            s.robot_wvx[0] = 0.0;
            s.robot_wvy[0] = 0.0;
        }
        let dsrnn =
            reward::dsrnn_discomfort(p, reward::min_predicted_clearance(p, &after.chunk(), 0));
        let Some(scorer) = scorer else {
            return (f32::NAN, dsrnn);
        };
        // The entities' poses before the step, seen from the placement, are the previous poses
        // behind the frame's velocities.
        sngnn::frame::remember_poses(&mut before.chunk(), 0);
        after.sn_prev_x.copy_from_slice(&before.sn_prev_x);
        after.sn_prev_y.copy_from_slice(&before.sn_prev_y);
        after.sn_prev_theta.copy_from_slice(&before.sn_prev_theta);
        let mut c = after.chunk();
        sngnn::history::clear(&mut c, 0);
        (sngnn_score::discomfort(p, &mut c, scorer, 0), dsrnn)
    }
}

/// Why the robot cannot stand at (x, y) (m) in environment 0 of `c`, or [`cell::FREE`].
fn placement_mask(p: &StepParams, c: &StateChunk, x: f32, y: f32) -> u8 {
    let d = Disc {
        x,
        y,
        r: p.robot_radius,
    };
    let t = world::touches(p, c, 0, &d);
    if t.human {
        return cell::HUMAN;
    }
    if t.object {
        return cell::OBSTACLE;
    }
    let outside = (0..c.n_blockers[0] as usize).any(|b| {
        c.b_kind[b] == blocker_kind::L_BLOCK
            && world::blocker_rect(c, 0, b).distance_sq(x, y) == 0.0
    });
    if outside { cell::OUTSIDE } else { cell::FREE }
}

/// `heading` (rad) as the robot's heading, or why not: beyond a million radians an f32 angle
/// keeps no fraction of a turn (and `sin_cos` gives NaN past 2^20).
///
/// # Errors
/// `SimError::Shape` naming the heading.
pub fn check_heading(heading: f32) -> Result<(), SimError> {
    if heading.is_finite() && heading.abs() <= 1e6 {
        Ok(())
    } else {
        Err(SimError::shape(
            "heatmap",
            format!("heatmap: heading {heading} rad is not a finite angle within ±1e6 rad"),
        ))
    }
}

/// `n` as a grid side, or why not.
///
/// # Errors
/// `SimError::Shape` naming the accepted range.
pub fn check_grid(n: usize) -> Result<(), SimError> {
    if (MIN_GRID..=MAX_GRID).contains(&n) {
        Ok(())
    } else {
        Err(SimError::shape(
            "heatmap",
            format!("heatmap: grid size {n} is outside {MIN_GRID}..={MAX_GRID}"),
        ))
    }
}

/// The error for a config whose reward is not SNGNN-v2 (`name`: how the user named it), naming
/// the key to change.
///
/// # Errors
/// `SimError::Config` when `config.reward.kind` is not SNGNN-v2.
pub fn require_sngnn(config: &Config, name: &str) -> Result<(), SimError> {
    if config.reward.kind == RewardKind::Sngnn {
        return Ok(());
    }
    Err(SimError::config([format!(
        "{name}: the heatmap compares SNGNN-v2 with DSRNN, but this config's reward is DSRNN; \
         set `reward.kind = \"sngnn\"` in it, or use a shipped SNGNN config (exp1_sngnn, \
         exp2_sngnn, exp3_sngnn)"
    )]))
}
