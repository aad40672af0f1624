//! CPU/GPU parity of stage `human_motion` (docs/spec.md, determinism): its shader
//! (`shaders/human_motion.wgsl`, over `common/perception.wgsl`, `common/sfm.wgsl`,
//! `common/orca_world.wgsl` and `common/orca.wgsl`) must leave the state and the outputs
//! bit-identical to the Rust twin on lavapipe: lone walkers in slot order, ORCA (zero and actual
//! neighbour velocities) and SFM, the per-step robot-avoidance draw, the speed threshold (and its
//! forming-crowd exception), and restricted fields of view (wider and narrower than π) that
//! filter the humans, groups and obstacles each walker meets, at dt = 1 and 0.3 s. Runs chain
//! (each side from its own last state) so walkers travel, and about half of the environments are
//! scattered before each run to reach every branch; the branches are counted on the CPU side.
//! The harness: `tests/common/gpu.rs`.

use crate::common;

use std::cell::Cell;

use common::gpu::*;
use socnav::config::{HumanPolicy, OrcaNeighbourVelocity};
use socnav::geometry::Shape;
use socnav::math::PI;
use socnav::orca::obstacle_range_sq;
use socnav::outputs::Outputs;
use socnav::rng::{RngStream, stream_id};
use socnav::state::{BatchState, forming, policy};
use socnav::systems::human_motion::STREAM_AVOID_ROBOT;
use socnav::systems::orca_obstacles::for_each_polygon;
use socnav::systems::perception::View;
use socnav::{Config, StepParams};

/// What the walkers of the runs so far met, counted on the CPU before each run.
#[derive(Debug, Default, Clone, Copy)]
struct Seen {
    /// Walkers moved by ORCA / by SFM.
    orca: usize,
    sfm: usize,
    /// Walkers that avoid the robot this step (the stage's draw, reproduced).
    avoiding: usize,
    /// ORCA walkers with a view: every obstacle seen (cached set), none seen near, a subset.
    fov_cached: usize,
    fov_none_near: usize,
    fov_subset: usize,
    /// SFM walkers with a view that miss some obstacle polygon.
    sfm_partial: usize,
    /// Walkers standing after a run (speed 0: thresholded or at the goal), and walkers marked
    /// as heading to a forming crowd.
    standing: usize,
    forming: usize,
}

thread_local! {
    // Per test thread: the perturbation runs on the thread of the test that checks the counts.
    static SEEN: Cell<Seen> = Cell::new(Seen::default());
}

/// Squared distance from `pos` to the bounding box of `polygon` (`orca_obstacles::box_distance_sq`).
fn box_distance_sq(pos: [f32; 2], polygon: &[[f32; 2]; 4]) -> f32 {
    let gap = |k: usize| {
        let lo = polygon[1..].iter().fold(polygon[0][k], |m, v| m.min(v[k]));
        let hi = polygon[1..].iter().fold(polygon[0][k], |m, v| m.max(v[k]));
        (lo - pos[k]).max(pos[k] - hi).max(0.0)
    };
    let (dx, dy) = (gap(0), gap(1));
    dx * dx + dy * dy
}

/// Count what the walkers of `s` meet this run (see [`Seen`]).
fn count(s: &mut BatchState, p: &StepParams) {
    let mut seen = SEEN.get();
    let chunk = s.chunk();
    for e in 0..chunk.n_static.len() {
        if chunk.stepping[e] == 0 {
            continue;
        }
        let mut rng = RngStream::new(
            socnav::systems::episode_seed(&chunk, e),
            stream_id(STREAM_AVOID_ROBOT, chunk.tick[e]),
        );
        let first = e * chunk.strides.humans + chunk.n_static[e] as usize;
        for i in first..first + chunk.n_dynamic[e] as usize {
            seen.standing += usize::from(chunk.h_speed[i] == 0.0);
            seen.forming += usize::from(chunk.h_forming[i] == forming::CROWD);
            if p.prob_avoid_robot > 0.0 && rng.chance(p.prob_avoid_robot) {
                seen.avoiding += 1;
            }
            let orca = chunk.h_policy[i] == policy::ORCA;
            if orca {
                seen.orca += 1;
            } else {
                seen.sfm += 1;
            }
            let Some(view) = View::of_human(p, &chunk, i) else {
                continue;
            };
            let pos = [chunk.h_x[i], chunk.h_y[i]];
            let range_sq = obstacle_range_sq(
                chunk.orca_time_horizon_obst[e],
                chunk.orca_max_speed[e],
                p.human_radius,
            ) * (1.0 + 1e-3);
            let (mut all, mut visible, mut near) = (0, 0, false);
            for_each_polygon(p, &chunk, e, |shape: Shape, polygon| {
                all += 1;
                if view.sees(&shape) {
                    visible += 1;
                    near |= box_distance_sq(pos, &polygon) <= range_sq;
                }
            });
            if !orca {
                seen.sfm_partial += usize::from(visible < all);
            } else if visible == all {
                seen.fov_cached += 1;
            } else if !near {
                seen.fov_none_near += 1;
            } else {
                seen.fov_subset += 1;
            }
        }
    }
    SEEN.set(seen);
}

/// About half of the environments get their lone humans (static and walking) scattered over the
/// room (into each other and the obstacles too), with random headings (what a view sees) and
/// velocities, some goals under the walker (zero preferred velocity), some walkers marked as
/// heading to a forming crowd, and the robot among them; the others chain on.
fn scatter_walkers(s: &mut BatchState, _: &mut Outputs, p: &StepParams, rng: &mut RngStream) {
    for e in 0..s.n_envs {
        if rng.next_f32() < 0.5 {
            continue;
        }
        let (hx, hy) = (0.5 * s.map_x[e], 0.5 * s.map_y[e]);
        s.robot_x[e] = uniform(rng, -hx, hx);
        s.robot_y[e] = uniform(rng, -hy, hy);
        s.robot_wvx[e] = uniform(rng, -0.2, 0.2);
        s.robot_wvy[e] = uniform(rng, -0.2, 0.2);
        let hb = e * s.strides.humans;
        for i in hb..hb + (s.n_static[e] + s.n_dynamic[e]) as usize {
            s.h_x[i] = uniform(rng, -hx, hx);
            s.h_y[i] = uniform(rng, -hy, hy);
            s.h_theta[i] = uniform(rng, -PI, PI);
            s.h_vx[i] = uniform(rng, -1.0, 1.0);
            s.h_vy[i] = uniform(rng, -1.0, 1.0);
            if rng.next_f32() < 0.05 {
                s.h_goal_x[i] = s.h_x[i];
                s.h_goal_y[i] = s.h_y[i];
            }
            if s.h_forming[i] == forming::NONE && rng.next_f32() < 0.05 {
                s.h_forming[i] = forming::CROWD;
            }
        }
    }
    count(s, p);
}

/// Runs per config (each chained on the last one's state and, for about half of the
/// environments, scattered).
const RUNS: usize = 30;

/// `human_motion` on `c` over 256 environments; what the walkers met.
fn check(name: &str, c: Config) -> Option<Seen> {
    SEEN.set(Seen::default());
    check_parity("human_motion", c, 256, RUNS, Some(scatter_walkers))?;
    let seen = SEEN.get();
    println!("{name}: {seen:?}");
    assert!(seen.standing > 0 && seen.forming > 0, "{name}: {seen:?}");
    Some(seen)
}

fn with_policy(mut c: Config, policy: HumanPolicy) -> Config {
    c.human.policy = policy;
    c
}

/// `c` with neighbours at their actual velocities, half the walkers avoiding the robot, faster
/// walkers (they travel further) and a 0.3 s step.
fn varied(mut c: Config) -> Config {
    c.model.orca_neighbour_velocity = OrcaNeighbourVelocity::Actual;
    c.human.prob_to_avoid_robot = 0.5;
    c.human.max_speed = 0.5;
    c.episode.time_step = 0.3;
    c
}

fn with_fov(mut c: Config, fov: f32) -> Config {
    c.human.fov_angle = fov;
    c
}

/// Contract: the paper's experiments (random policy: ORCA and SFM walkers among plants, tables,
/// laptops, laptop users and groups, everything seen, nobody avoiding the robot).
#[test]
fn experiments() {
    for name in ["exp1", "exp2", "exp3"] {
        let Some(seen) = check(name, config(name)) else {
            return;
        };
        assert!(seen.orca > 0 && seen.sfm > 0, "{name}: {seen:?}");
        assert_eq!(seen.avoiding, 0, "{name}");
    }
}

/// Contract: every walker on ORCA, then every walker on SFM, with 0.1.1's model on experiment 2
/// and with actual neighbour velocities, robot avoidance (p = 0.5), faster walkers and dt = 0.3 s
/// on experiment 3.
#[test]
fn forced_policies() {
    for policy in [HumanPolicy::Orca, HumanPolicy::Sfm] {
        for (name, c) in [
            ("exp2", with_policy(config("exp2"), policy)),
            ("exp3 varied", varied(with_policy(config("exp3"), policy))),
        ] {
            let Some(seen) = check(name, c) else {
                return;
            };
            // Humans that social events turn into walkers always take ORCA (as in 0.1.1).
            match policy {
                HumanPolicy::Orca => assert_eq!(seen.sfm, 0, "{name}"),
                _ => assert!(seen.sfm > seen.orca, "{name}: {seen:?}"),
            }
            if name.ends_with("varied") {
                assert!(seen.avoiding > 0, "{name}: {seen:?}");
            }
        }
    }
}

/// Contract: restricted fields of view, 2.0 rad (narrower than π: the wedge is convex) and
/// 4.0 rad (wider), on experiment 2 and in the L room with every entity kind: each walker meets
/// only the humans, groups and obstacles it sees; an ORCA walker's obstacles are the cached set
/// when it sees them all, none when none it sees is near, else the visible subset processed
/// afresh. Random policies, the L room with actual velocities, avoidance and dt = 0.3 s.
#[test]
fn field_of_view() {
    for fov in [2.0, 4.0] {
        for (name, c) in [
            ("exp2", with_fov(config("exp2"), fov)),
            (
                "lroom_mixed varied",
                with_fov(varied(config("lroom_mixed")), fov),
            ),
        ] {
            let Some(seen) = check(name, c) else {
                return;
            };
            assert!(
                seen.fov_cached > 0 && seen.fov_none_near > 0 && seen.fov_subset > 0,
                "{name}, fov {fov}: {seen:?}"
            );
            assert!(seen.sfm_partial > 0, "{name}, fov {fov}: {seen:?}");
        }
    }
}
