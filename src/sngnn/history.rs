//! The SNGNN frame history of each environment and the rule that picks a graph's frames from it
//! (docs/spec.md 7.4).
//!
//! 0.1.1 prepends the frame of every non-terminal step to a list that grows for the whole
//! episode; a graph takes the newest frame, then walks back and takes a frame whenever its
//! timestamp lies at least [`FRAMES_INTERVAL`] from the last one taken, until it holds
//! [`MAX_GRAPH_FRAMES`]. Only the newest few frames can ever be taken, so socnav keeps a ring of
//! [`capacity_for`]`(dt)` frames (F) per environment in the state's columns:
//!
//! | kind | capacity per environment | columns |
//! |---|---|---|
//! | `sngnn` | 1 | `sn_frame_count`, `sn_newest` |
//! | `frame` | F | tick, robot pose, goal, command, counts (`sf_*`) |
//! | `frame_person` | F × P | `fp_*` (P = `Caps::frame_people`) |
//! | `frame_object` | F × O | `fo_*` (O = `Caps::frame_objects`) |
//! | `frame_link` | F × L | `fl_*` (L = `Caps::frame_links`) |
//!
//! every one of capacity 0 without the SNGNN reward. Ring slot f of environment e holds its
//! frame columns at e·F + f and its person j at (e·F + f)·P + j (objects and links likewise).
//!
//! Invariants: `sn_frame_count[e]` ≤ F frames are held, the newest in ring slot `sn_newest[e]`,
//! each older one in the slot before (mod F); rows a frame does not use and slots that hold no
//! frame are zero. Frames are appended only on non-terminal steps (0.1.1 does not call SNGNN on
//! terminal ones); the history is emptied at reset, and `set_state` replaces it with the
//! document's `state.sngnn_frames`.
//!
//! Walls are not stored: they are static within an episode, so a frame keeps the robot pose it
//! was taken from and the graph places the state's walls with it.

mod view;
mod write;

pub use view::{Frame, History};
pub use write::{begin_frame, clear, push_link, push_object, push_person};

/// Seconds between the frames a graph stacks (0.1.1's `FRAMES_INTERVAL`).
pub const FRAMES_INTERVAL: f64 = 1.0;
// The history's capacity is a capacity of the state's columns, computed with the others.
pub use crate::state::caps::{MAX_GRAPH_FRAMES, capacity_for};

/// The time step (s) as 0.1.1 holds it: the config's decimal value as an f64 (`time_step: 0.2`
/// is the f64 0.2, not the f32 0.2000000030), recovered as the decimal with the fewest digits
/// after the point that rounds to `dt` (at most 12; otherwise `dt` itself).
pub fn decimal_time_step(dt: f32) -> f64 {
    let x = f64::from(dt);
    let mut scale = 1.0f64;
    for _ in 0..=12 {
        let decimal = (x * scale).round() / scale;
        if decimal as f32 == dt {
            return decimal;
        }
        scale *= 10.0;
    }
    x
}

/// The spacing rule of [`select`] in whole ticks, for devices without f64: taking frames newest
/// first, the frame after one at tick `last` is the newest at least [`TickGaps::gap_after`]
/// (`last`) ticks older. 0.1.1's rule is `|t · dt − last · dt| ≥ 1 s` on f64 timestamps, which
/// is monotone in `t`, so this is the same rule exactly, tick by tick. For dt ≥ 1 s (gap 1) and
/// dyadic time steps (0.5, 0.25 s, ...: the products are exact) the gap is one constant; for
/// others (0.1, 0.2 s) rounding makes some ticks need one tick more, which `extra` marks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TickGaps {
    /// The gap (ticks) of most ticks, and the smallest.
    pub base: u32,
    /// Bit `t % 32` of word `t / 32` set: a frame at tick t needs `base + 1` ticks back. Empty
    /// when every tick needs `base`.
    pub extra: Vec<u32>,
}

impl TickGaps {
    /// The gaps of time step `dt` (s) for frames of ticks `0..=max_tick` (a recorded frame's tick
    /// never exceeds the episode length). `None` if some tick would need more than `base + 1`
    /// (not the case for any positive time step: the f64 rounding moves a timestamp difference
    /// by far less than one tick).
    pub fn new(dt: f32, max_tick: u32) -> Option<Self> {
        let step = decimal_time_step(dt);
        if !(step > 0.0 && step.is_finite()) {
            return None;
        }
        // Smallest g with last·dt − (last − g)·dt ≥ 1 s in f64 (as 0.1.1 subtracts timestamps).
        let gap = |last: u32| {
            let stamp = |tick: i64| tick as f64 * step;
            let newest = stamp(i64::from(last));
            let mut g = ((FRAMES_INTERVAL / step).floor() as i64 - 1).max(1);
            while (newest - stamp(i64::from(last) - g)).abs() < FRAMES_INTERVAL {
                g += 1;
            }
            u32::try_from(g).ok()
        };
        let gaps: Vec<u32> = (0..=max_tick).map(gap).collect::<Option<_>>()?;
        let base = *gaps.iter().min()?;
        if gaps.iter().any(|&g| g > base + 1) {
            return None;
        }
        let mut extra = vec![0u32; gaps.len().div_ceil(32)];
        for (t, &g) in gaps.iter().enumerate() {
            extra[t / 32] |= u32::from(g > base) << (t % 32);
        }
        if extra.iter().all(|&w| w == 0) {
            extra.clear();
        }
        Some(Self { base, extra })
    }

    /// Ticks back from a frame at tick `last` to the next frame the selection may take (`base`
    /// beyond the ticks the gaps were made for).
    pub fn gap_after(&self, last: u32) -> u32 {
        let bit = self
            .extra
            .get(last as usize / 32)
            .map_or(0, |w| (w >> (last % 32)) & 1);
        self.base + bit
    }

    /// Ticks covered by `extra` (0 when the gap is one constant).
    pub fn ticks(&self) -> usize {
        32 * self.extra.len()
    }

    /// The table as the GPU's frame selection reads it (`sn_gaps` of
    /// `backend::wgsl::sngnn_prelude`): `base`, [`TickGaps::ticks`], then `extra`.
    ///
    /// # Panics
    /// If the table covers more than `u32::MAX` ticks (the GPU backend bounds it far below).
    #[expect(
        clippy::expect_used,
        reason = "the GPU backend bounds the table far below u32::MAX ticks"
    )]
    pub fn words(&self) -> Vec<u32> {
        let ticks = u32::try_from(self.ticks()).expect("a tick count fits a u32");
        let mut words = vec![self.base, ticks];
        words.extend_from_slice(&self.extra);
        words
    }
}

/// The timestamp (s) of a frame taken at `tick`: tick · dt in f64, as 0.1.1 computes it.
pub fn timestamp(dt: f32, tick: u32) -> f64 {
    f64::from(tick) * decimal_time_step(dt)
}

/// A person of a frame (docs/spec.md 7.2): entity id, position (m) and angle (rad) in SNGNN's axes
/// (x right, y ahead of the robot; angle −(π/2 + relative heading)), and the backward
/// differences of the robot-frame pose per 0.2 s (m, m, rad; robot-frame axes, not SNGNN's).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Person {
    /// Entity id (its node index in the graph).
    pub id: u32,
    /// x (m, SNGNN axes).
    pub x: f32,
    /// y (m, SNGNN axes).
    pub y: f32,
    /// Angle (rad, SNGNN convention, not wrapped).
    pub a: f32,
    /// (previous − current) robot-frame x per 0.2 s (m).
    pub vx: f32,
    /// (previous − current) robot-frame y per 0.2 s (m).
    pub vy: f32,
    /// (previous − current) relative heading per 0.2 s (rad, not wrapped).
    pub va: f32,
}

/// An object of a frame: a person's fields plus its size (m).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Object {
    /// Pose and velocities, as for a person.
    pub pose: Person,
    /// Size along the object's x (m).
    pub size_x: f32,
    /// Size along the object's y (m).
    pub size_y: f32,
}

/// An interaction entry of a frame: the graph links `src` → `dst` and back.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Link {
    /// Source entity id.
    pub src: u32,
    /// Destination entity id.
    pub dst: u32,
}

/// What a frame holds besides its entities.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameHead {
    /// Tick of the step it was taken at.
    pub tick: u32,
    /// Robot pose (m, m, rad; world frame) it was taken from.
    pub robot: [f32; 3],
    /// Goal (m, SNGNN axes).
    pub goal: [f32; 2],
    /// Command: advance, lateral advance, rotation (SNGNN units, docs/spec.md 7.2).
    pub command: [f32; 3],
}

/// The ring slots of the frames one graph stacks, newest first (docs/spec.md 7.4).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Selection {
    slots: [usize; MAX_GRAPH_FRAMES],
    len: usize,
}

impl Selection {
    /// The slots, newest first.
    pub fn slots(&self) -> &[usize] {
        &self.slots[..self.len]
    }

    fn push(&mut self, slot: usize) {
        self.slots[self.len] = slot;
        self.len += 1;
    }
}

/// 0.1.1's choice of frames at time step `dt` (s): the newest, then walking back, every frame
/// whose timestamp is at least [`FRAMES_INTERVAL`] from the last one taken, up to
/// [`MAX_GRAPH_FRAMES`]. With dt = 1 s: the frames of steps t, t − 1, t − 2 (fewer at the start
/// of an episode). Empty if no frame is held.
pub fn select(dt: f32, h: &History<'_>) -> Selection {
    let mut selection = Selection::default();
    if h.is_empty() {
        return selection;
    }
    let step = decimal_time_step(dt);
    let stamp = |age: usize| f64::from(h.frame(age).head().tick) * step;
    selection.push(h.frame(0).slot());
    let mut last = stamp(0);
    for age in 1..h.len() {
        let t = stamp(age);
        if (t - last).abs() < FRAMES_INTERVAL {
            continue;
        }
        selection.push(h.frame(age).slot());
        last = t;
        if selection.len == MAX_GRAPH_FRAMES {
            break;
        }
    }
    selection
}
