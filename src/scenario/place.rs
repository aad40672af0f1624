//! Rejection sampling of entity poses against the spawn list (docs/spec.md 3.4). 0.1.1 retries
//! until a 30 s wall-clock timeout; socnav bounds the number of attempts instead, so a scenario
//! depends only on the episode seed.

use crate::fixed::Fixed;
use crate::geometry::{Disc, Rect, Shape};
use crate::math::{self, PI};
use crate::params::StepParams;
use crate::rng::RngStream;

/// Attempts per rejection-sampling loop before the scenario is regenerated from a new stream.
pub const MAX_TRIES: u32 = 2000;

/// Most shapes in a spawn list (walls, blockers and every entity).
pub const MAX_SPAWN: usize = 512;

/// What a spawn-list entry is, for the checks that only look at some kinds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Kind {
    /// Walls, blockers, robot, humans, plants, tables.
    #[default]
    Solid,
    /// Laptops (on tables they are checked against laptops only).
    Laptop,
}

/// Everything placed so far, and the goal discs drawn so far.
#[derive(Debug, Clone, Default)]
pub struct SpawnList {
    shapes: Fixed<(Kind, Shape), MAX_SPAWN>,
    goals: Fixed<Disc, MAX_SPAWN>,
}

impl Default for Shape {
    fn default() -> Self {
        Shape::Disc(Disc {
            x: 0.0,
            y: 0.0,
            r: 0.0,
        })
    }
}

impl Default for Disc {
    fn default() -> Self {
        Disc {
            x: 0.0,
            y: 0.0,
            r: 0.0,
        }
    }
}

impl SpawnList {
    /// Forget everything.
    pub fn clear(&mut self) {
        self.shapes.clear();
        self.goals.clear();
    }

    /// Add a placed shape.
    pub fn add(&mut self, kind: Kind, shape: Shape) {
        self.shapes.push((kind, shape));
    }

    /// Add a goal disc.
    pub fn add_goal(&mut self, goal: Disc) {
        self.goals.push(goal);
    }

    /// Does `shape` intersect anything placed?
    pub fn blocked(&self, shape: &Shape) -> bool {
        self.shapes
            .as_slice()
            .iter()
            .any(|(_, s)| s.intersects(shape))
    }

    /// Does `shape` intersect a placed laptop?
    pub fn blocked_by_laptop(&self, shape: &Shape) -> bool {
        self.shapes
            .as_slice()
            .iter()
            .any(|(k, s)| *k == Kind::Laptop && s.intersects(shape))
    }

    /// Does the goal disc intersect anything placed or another goal?
    pub fn goal_blocked(&self, goal: &Disc) -> bool {
        let shape = Shape::Disc(*goal);
        self.blocked(&shape)
            || self
                .goals
                .as_slice()
                .iter()
                .any(|g| crate::geometry::disc_disc(g, goal))
    }
}

/// The sampling box: [-X/2 + margin, X/2 - margin] × [-Y/2 + margin, Y/2 - margin] (m).
#[derive(Debug, Clone, Copy)]
pub struct SamplingBox {
    /// Half extent of the box along x.
    pub hx: f32,
    /// Half extent along y.
    pub hy: f32,
}

impl SamplingBox {
    /// The box of an `x` by `y` room (m).
    pub fn new(p: &StepParams, x: f32, y: f32) -> Self {
        Self {
            hx: 0.5 * x - p.margin,
            hy: 0.5 * y - p.margin,
        }
    }

    /// A uniform point of the box.
    pub fn point(&self, rng: &mut RngStream) -> (f32, f32) {
        let x = rng.uniform(-self.hx, self.hx);
        let y = rng.uniform(-self.hy, self.hy);
        (x, y)
    }
}

pub use crate::limits::MAX_GROUP;

/// A pose (m, m, rad).
pub type Pose = (f32, f32, f32);

/// The member poses of a group of `n` around (cx, cy) (docs/spec.md 4.4): member k at angle
/// φ_k = 2πk/n (wrapped) on the circle of radius `group_radius`, each coordinate's angle jittered
/// by U(−π/14, π/14) independently; standing members face the centre (φ_k − π, jittered), moving
/// members share one heading drawn first.
pub fn group_layout(
    p: &StepParams,
    rng: &mut RngStream,
    cx: f32,
    cy: f32,
    n: usize,
    standing: bool,
    out: &mut [Pose; MAX_GROUP],
) {
    assert!(
        n <= MAX_GROUP,
        "a group of {n} members exceeds the {MAX_GROUP} a group may have"
    );
    let jitter = PI / 14.0;
    let shared_theta = heading(rng);
    for (k, pose) in out.iter_mut().enumerate().take(n) {
        let phi = math::wrap_angle(2.0 * PI * k as f32 / n as f32);
        let d1 = rng.uniform(-jitter, jitter);
        let d2 = rng.uniform(-jitter, jitter);
        let x = cx + p.group_radius * math::cos(phi + d1);
        let y = cy + p.group_radius * math::sin(phi + d2);
        let theta = if standing {
            phi - PI + rng.uniform(-jitter, jitter)
        } else {
            shared_theta
        };
        *pose = (x, y, theta);
    }
}

/// A uniform heading in [-π, π).
pub fn heading(rng: &mut RngStream) -> f32 {
    rng.uniform(-PI, PI)
}

/// Sample a free disc of radius `r`; `None` after [`MAX_TRIES`] attempts.
pub fn free_disc(
    rng: &mut RngStream,
    area: &SamplingBox,
    spawn: &SpawnList,
    r: f32,
) -> Option<Disc> {
    (0..MAX_TRIES).find_map(|_| {
        let (x, y) = area.point(rng);
        let d = Disc { x, y, r };
        (!spawn.blocked(&Shape::Disc(d))).then_some(d)
    })
}

/// Sample a free goal disc of radius `r` (free of placed shapes and other goals).
pub fn free_goal(
    rng: &mut RngStream,
    area: &SamplingBox,
    spawn: &SpawnList,
    r: f32,
) -> Option<Disc> {
    (0..MAX_TRIES).find_map(|_| {
        let (x, y) = area.point(rng);
        let d = Disc { x, y, r };
        (!spawn.goal_blocked(&d)).then_some(d)
    })
}

/// Sample a free rectangle with a uniform heading.
pub fn free_rect(
    rng: &mut RngStream,
    area: &SamplingBox,
    spawn: &SpawnList,
    length: f32,
    width: f32,
) -> Option<(f32, f32, f32)> {
    (0..MAX_TRIES).find_map(|_| {
        let (x, y) = area.point(rng);
        let theta = heading(rng);
        let r = Rect::new(x, y, theta, length, width);
        (!spawn.blocked(&Shape::Rect(r))).then_some((x, y, theta))
    })
}

/// Pose of a laptop on edge `edge` (0..4) of a table (docs/spec.md 3.4 step 6): centred
/// (table_width - laptop_width)/2 from the table centre along ±local y, or
/// (table_length - laptop_length)/2 along ±local x, turned so that its −y axis points away from
/// the table (where its user sits).
pub fn laptop_on_table(
    p: &StepParams,
    tx: f32,
    ty: f32,
    ttheta: f32,
    edge: u32,
) -> (f32, f32, f32) {
    let across = 0.5 * (p.table_width - p.laptop_width);
    let along = 0.5 * (p.table_length - p.laptop_length);
    let (lx, ly, turn) = match edge {
        0 => (0.0, across, PI),
        1 => (-along, 0.0, -0.5 * PI),
        2 => (0.0, -across, 0.0),
        _ => (along, 0.0, 0.5 * PI),
    };
    let (s, c) = math::sin_cos(ttheta);
    (
        tx + (lx * c - ly * s),
        ty + (lx * s + ly * c),
        ttheta + turn,
    )
}

/// Seat of a laptop's user (docs/spec.md 3.4 step 8): `laptop_width + human_laptop_distance` from
/// the laptop centre along its −y axis, facing the laptop (heading = laptop heading + π/2).
pub fn seat(p: &StepParams, lx: f32, ly: f32, ltheta: f32) -> (f32, f32, f32) {
    let d = p.laptop_width + p.human_laptop_distance;
    let (s, c) = math::sin_cos(ltheta);
    (lx + d * s, ly - d * c, ltheta + 0.5 * PI)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn laptop_and_seat_match_golden_pose() {
        // lroom_mixed seed 1: table (4.512035648, -3.411652980, θ -1.356166696); its laptop user's
        // laptop on edge 3 at (4.767618335, -4.584119393, θ 0.214629631) and the user at
        // (4.916708235, -5.268058134, θ 1.785425958).
        let p = StepParams::new(&crate::config::Config::default(), Default::default());
        let (x, y, t) = laptop_on_table(&p, 4.512_035_6, -3.411_653, -1.356_166_7, 3);
        // 1e-5: the golden values are f64, ours f32.
        assert!(
            (x - 4.767_618).abs() < 1e-5
                && (y + 4.584_119_4).abs() < 1e-5
                && (t - 0.214_629_63).abs() < 1e-5
        );
        let (hx, hy, ht) = seat(&p, x, y, t);
        assert!(
            (hx - 4.916_708).abs() < 1e-5
                && (hy + 5.268_058).abs() < 1e-5
                && (ht - 1.785_426).abs() < 1e-5
        );
        // The free laptop of the same scene sits on edge 2 of the same table.
        let (x, y, t) = laptop_on_table(&p, 4.512_035_6, -3.411_653, -1.356_166_7, 2);
        assert!(
            (x - 3.974_655_2).abs() < 1e-5
                && (y + 3.528_795).abs() < 1e-5
                && (t + 1.356_166_7).abs() < 1e-6
        );
    }
}
