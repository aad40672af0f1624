//! CPU/GPU parity of stage `goals` (docs/spec.md, determinism): its shader (`shaders/goals.wgsl`,
//! over `common/world.wgsl` and `common/rng.wgsl`) must leave the state and the outputs
//! bit-identical to the Rust twin on lavapipe: lone walkers and moving groups that reach their
//! goals get new ones, rejection-sampled in the margin box against every entity, wall and spawn
//! blocker and every current goal, from the step's goal stream in the Rust order. Walkers and
//! groups are put onto their goals before most runs so that re-sampling happens often (counted on
//! the CPU side), including walkers heading to a forming crowd (never re-sampled). The harness:
//! `tests/common/gpu.rs`.

use crate::common;

use std::cell::Cell;

use common::gpu::*;
use socnav::outputs::Outputs;
use socnav::rng::RngStream;
use socnav::state::{BatchState, forming, group_kind};
use socnav::{Config, StepParams};

/// What the runs so far asked of the stage, counted on the CPU before each run.
#[derive(Debug, Default, Clone, Copy)]
struct Reached {
    /// Lone walkers within reach of their goal (re-sampled).
    walkers: usize,
    /// Walkers within reach but heading to a forming crowd or a laptop (left alone).
    forming: usize,
    /// Moving groups whose members are all within reach of the group goal (re-sampled).
    groups: usize,
    /// Of those, groups whose members test arrival with the human goal radius (formed crowds).
    formed_groups: usize,
}

thread_local! {
    // Per test thread: the perturbation runs on the thread of the test that checks the counts.
    static REACHED: Cell<Reached> = Cell::new(Reached::default());
}

fn distance(ax: f32, ay: f32, bx: f32, by: f32) -> f32 {
    ((ax - bx) * (ax - bx) + (ay - by) * (ay - by)).sqrt()
}

/// Count what the stage will find in `s` (see [`Reached`]).
fn count(s: &BatchState, p: &StepParams) {
    let mut r = REACHED.get();
    for e in 0..s.n_envs {
        if s.stepping[e] == 0 {
            continue;
        }
        let hb = e * s.strides.humans;
        let first = hb + s.n_static[e] as usize;
        for i in first..first + s.n_dynamic[e] as usize {
            let reach = p.human_radius + p.human_goal_radius;
            if distance(s.h_x[i], s.h_y[i], s.h_goal_x[i], s.h_goal_y[i]) < reach {
                if s.h_forming[i] == 0 {
                    r.walkers += 1;
                } else {
                    r.forming += 1;
                }
            }
        }
        let gb = e * s.strides.groups;
        for g in gb..gb + s.n_groups[e] as usize {
            if s.g_kind[g] != group_kind::MOVING {
                continue;
            }
            let reach = p.human_radius + s.g_member_goal_radius[g];
            let m = hb + s.g_first[g] as usize..hb + (s.g_first[g] + s.g_count[g]) as usize;
            if m.into_iter()
                .all(|i| distance(s.h_x[i], s.h_y[i], s.g_goal_x[g], s.g_goal_y[g]) < reach)
            {
                r.groups += 1;
                r.formed_groups += usize::from(s.g_member_goal_radius[g] == p.human_goal_radius);
            }
        }
    }
    REACHED.set(r);
}

/// About a third of the walkers get their goal moved to within reach (a tenth of them marked as
/// heading to a forming crowd, the others as ordinary walkers), and about half of the moving groups get their goal moved next
/// to their centre (all members within reach of the group goal radius, some of the human goal
/// radius, which half of the groups test with, as crowds formed during the episode do); the ticks are varied so the goal streams differ.
fn onto_goals(s: &mut BatchState, _: &mut Outputs, p: &StepParams, rng: &mut RngStream) {
    for e in 0..s.n_envs {
        s.tick[e] = rng.next_u32() % p.episode_length;
        let hb = e * s.strides.humans;
        let first = hb + s.n_static[e] as usize;
        for i in first..first + s.n_dynamic[e] as usize {
            if rng.next_f32() < 0.35 {
                let d = 0.9 * (p.human_radius + p.human_goal_radius);
                s.h_goal_x[i] = s.h_x[i] + uniform(rng, -d, d) * 0.7;
                s.h_goal_y[i] = s.h_y[i] + uniform(rng, -d, d) * 0.7;
                s.h_forming[i] = if rng.next_f32() < 0.1 {
                    forming::CROWD
                } else {
                    forming::NONE
                };
            }
        }
        let gb = e * s.strides.groups;
        for g in gb..gb + s.n_groups[e] as usize {
            if s.g_kind[g] == group_kind::MOVING && rng.next_f32() < 0.5 {
                s.g_member_goal_radius[g] = if rng.next_f32() < 0.5 {
                    p.human_goal_radius
                } else {
                    p.group_goal_radius
                };
                s.g_goal_x[g] = s.g_x[g] + uniform(rng, -0.3, 0.3);
                s.g_goal_y[g] = s.g_y[g] + uniform(rng, -0.3, 0.3);
            }
        }
    }
    count(s, p);
}

/// `goals` on `c`: 40 runs over 256 environments; what the runs asked for.
fn check(name: &str, c: Config) -> Option<Reached> {
    REACHED.set(Reached::default());
    check_parity("goals", c, 256, 40, Some(onto_goals))?;
    let r = REACHED.get();
    println!("{name}: {r:?}");
    assert!(r.walkers > 1000 && r.forming > 0, "{name}: {r:?}");
    Some(r)
}

/// Contract: walkers re-sampled in experiment 1 (a plant) and the L room (every entity kind, a
/// spawn blocker, moving groups), the latter at dt = 0.3 s.
#[test]
fn walkers_and_groups() {
    let Some(_) = check("exp1", config("exp1")) else {
        return;
    };
    let mut c = config("lroom_mixed");
    c.episode.time_step = 0.3;
    let r = check("lroom_mixed", c).expect("device");
    assert!(r.groups > 100, "lroom_mixed: {r:?}");
}

/// Contract: experiments 2 and 3 (tables, laptops, laptop users, standing and moving groups that
/// may disperse or form): walkers and moving groups re-sampled.
#[test]
fn experiments() {
    for name in ["exp2", "exp3"] {
        let Some(r) = check(name, config(name)) else {
            return;
        };
        assert!(r.groups > 100 && r.formed_groups > 0, "{name}: {r:?}");
    }
}
