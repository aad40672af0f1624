//! Stage `observation` (docs/spec.md 5): the robot record and one 14-float record per entity,
//! laid out as [`crate::spec::ObsLayout`] says, plus the interaction pairs of
//! `info["interactions"]`; with the options of 0.1.1's observation wrappers (docs/spec.md 9.1)
//! applied inside the step, for the whole batch.
//!
//! Conventions are 0.1.1's: in the robot frame (x forward, y left) sin/cos of the unwrapped
//! relative heading; humans' relative speed is |v_h − v_r| (non-negative), every other entity
//! carries −|v_r| and −ω; walls are split into segments of `wall_segment_size` from their "left"
//! end. One 0.1.1 bug is fixed (docs/fidelity.md): the relative angular speed wraps the heading
//! difference, so it never jumps by ±2π/dt.
//!
//! The wrappers, in the order they are applied (0.1.1 composes them as the user wraps; this is
//! `NoisyObservations(PartialObservations(env))`, with the frame chosen underneath):
//! 1. `WorldFrameObservations` (`frame = "world"`, module `records`): world positions and headings,
//!    humans' world velocity at indices 11-12 (0, 0 for everything else), a 16-float robot record.
//! 2. `PartialObservations` (`fov`, `range`, `Sensor`): a record is kept only if its centre,
//!    in the robot frame whatever frame is written, has bearing within ±fov/2 and distance within
//!    the range; kept records are compacted to the front of their block in order, the counts
//!    count them, and the interaction pairs index the visible records.
//! 3. `NoisyObservations` (`noise`, module `noise`): Gaussian noise on the true values of what is
//!    visible, so noise never decides visibility.
//!
//! Every option off (the default) takes the plain path: no visibility test, no noise draw.

mod interactions;
mod noise;
mod records;

use crate::math;
use crate::outputs::OutChunk;
use crate::params::StepParams;
use crate::spec::{RECORD, entity};
use crate::state::StateChunk;

use super::Batch;

pub use noise::STREAM_OBS_NOISE;

/// Write the observation of environment `e` and cache the humans' relative headings.
pub fn observation(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    if b.s.stepping[e] == 0 {
        return;
    }
    write_observation(p, &mut b.s, &mut b.o, e);
}

/// The robot's sensor of 0.1.1's `PartialObservations`: field of view and range.
#[derive(Debug, Clone, Copy)]
struct Sensor {
    /// Half the field of view (rad).
    half_fov: f32,
    /// Range (m); `f32::MAX` when unlimited.
    range: f32,
}

impl Sensor {
    /// Whether a centre at robot-frame (`lx`, `ly`) (m) is observed: bearing atan2(ly, lx) in
    /// [−fov/2, fov/2] and distance √(lx² + ly²) ≤ range, both bounds inclusive as in 0.1.1.
    fn within(&self, lx: f32, ly: f32) -> bool {
        let bearing = math::atan2(ly, lx);
        bearing >= -self.half_fov
            && bearing <= self.half_fov
            && (lx * lx + ly * ly).sqrt() <= self.range
    }
}

/// The robot pose and velocities an observation is relative to, and how records are written:
/// in the world frame when `WORLD`, keeping only what the sensor sees when `PARTIAL`. The two
/// options are type parameters so that the record writers are compiled once per combination
/// and the default (robot frame, everything visible) runs no test for either.
#[derive(Debug, Clone, Copy)]
struct Frame<const WORLD: bool, const PARTIAL: bool> {
    x: f32,
    y: f32,
    theta: f32,
    sin: f32,
    cos: f32,
    /// Robot world velocity (m/s).
    vx: f32,
    vy: f32,
    /// Heading subtracted from entity headings: the robot's, or 0 in the world frame.
    ref_theta: f32,
    /// Indices 11 and 12 of non-human records: −|v| and −ω in the robot frame, 0 in the world frame.
    object_v: f32,
    object_w: f32,
    /// The field of view and range (read only when `PARTIAL`).
    sensor: Sensor,
}

impl<const WORLD: bool, const PARTIAL: bool> Frame<WORLD, PARTIAL> {
    fn of(p: &StepParams, s: &StateChunk, e: usize) -> Self {
        let theta = s.robot_theta[e];
        let (sin, cos) = math::sin_cos(theta);
        let (vx, vy) = super::robot_motion::robot_world_velocity(s, e);
        let (cx, cy) = (s.robot_vx[e], s.robot_vy[e]);
        let (ref_theta, object_v, object_w) = if WORLD {
            (0.0, 0.0, 0.0)
        } else {
            (theta, -(cx * cx + cy * cy).sqrt(), -s.robot_w[e])
        };
        Self {
            x: s.robot_x[e],
            y: s.robot_y[e],
            theta,
            sin,
            cos,
            vx,
            vy,
            ref_theta,
            object_v,
            object_w,
            sensor: Sensor {
                half_fov: 0.5 * p.obs_fov,
                range: p.obs_range,
            },
        }
    }

    /// World point → robot frame.
    #[inline]
    fn local(&self, x: f32, y: f32) -> (f32, f32) {
        let dx = x - self.x;
        let dy = y - self.y;
        (self.cos * dx + self.sin * dy, self.cos * dy - self.sin * dx)
    }

    /// Whether the sensor sees a centre at robot-frame (`lx`, `ly`) (m).
    #[inline]
    fn sees(&self, lx: f32, ly: f32) -> bool {
        !PARTIAL || self.sensor.within(lx, ly)
    }

    /// Whether the sensor sees the world point (x, y) (m).
    #[inline]
    fn sees_point(&self, x: f32, y: f32) -> bool {
        if !PARTIAL {
            return true;
        }
        let (lx, ly) = self.local(x, y);
        self.sensor.within(lx, ly)
    }

    /// The written position of a world point (x, y) whose robot-frame position is (lx, ly).
    #[inline]
    fn written(&self, x: f32, y: f32, lx: f32, ly: f32) -> (f32, f32) {
        if WORLD { (x, y) } else { (lx, ly) }
    }
}

/// Write the full observation row of environment `e` (records past the counts are zeroed), its
/// interaction pairs, and update the relative-heading cache of its humans.
pub fn write_observation(p: &StepParams, s: &mut StateChunk, o: &mut OutChunk, e: usize) {
    match (p.obs_world_frame != 0, p.obs_partial != 0) {
        (false, false) => write::<false, false>(p, s, o, e),
        (false, true) => write::<false, true>(p, s, o, e),
        (true, false) => write::<true, false>(p, s, o, e),
        (true, true) => write::<true, true>(p, s, o, e),
    }
}

/// [`write_observation`] for one combination of the frame and sensor options.
fn write<const WORLD: bool, const PARTIAL: bool>(
    p: &StepParams,
    s: &mut StateChunk,
    o: &mut OutChunk,
    e: usize,
) {
    let layout = o.strides.layout;
    let row = &mut o.obs[e * layout.dim..(e + 1) * layout.dim];
    let f = Frame::<WORLD, PARTIAL>::of(p, s, e);
    records::robot(p, s, e, &f, &mut row[..layout.robot]);
    let mut counts = [0u32; 5];
    let at = |t: usize| layout.offset[t];
    counts[entity::HUMANS] = records::humans(p, s, e, &f, &mut row[at(entity::HUMANS)..]);
    counts[entity::LAPTOPS] = records::laptops(p, s, e, &f, &mut row[at(entity::LAPTOPS)..]);
    counts[entity::TABLES] = records::tables(p, s, e, &f, &mut row[at(entity::TABLES)..]);
    counts[entity::PLANTS] = records::plants(p, s, e, &f, &mut row[at(entity::PLANTS)..]);
    if layout.capacity[entity::WALLS] > 0 {
        counts[entity::WALLS] = records::walls(p, s, e, &f, &mut row[at(entity::WALLS)..]);
    }
    for (t, &n) in counts.iter().enumerate() {
        let from = layout.offset[t] + n as usize * RECORD;
        let to = layout.offset[t] + layout.capacity[t] * RECORD;
        // Most blocks are full or empty: skip the call rather than zero nothing.
        if from < to {
            row[from..to].fill(0.0);
        }
    }
    if p.obs_noise_on != 0 {
        noise::add_noise(p, s, e, &layout, &counts, row);
    }
    o.obs_count[e * 5..e * 5 + 5].copy_from_slice(&counts);
    let (hh, hl) = (o.strides.hh(), o.strides.hl());
    let pairs = interactions::write_interactions(
        s,
        e,
        &f,
        &mut o.hh_pairs[e * hh..(e + 1) * hh],
        &mut o.hl_pairs[e * hl..(e + 1) * hl],
    );
    o.pair_count[e * 2..e * 2 + 2].copy_from_slice(&pairs);
}
