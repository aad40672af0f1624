//! CPU/GPU parity of each stage that has a shader (DESIGN.md section 4): from the same state,
//! parameters and actions, the stage's WGSL shader must leave the state and the outputs
//! bit-identical to its Rust twin on lavapipe (and on any adapter that rounds like it).
//!
//! States come from real rollouts (random actions, resets and social events included); each
//! stage then runs many times on both sides, either chained (each side from its own last state)
//! or from states perturbed to reach the cases the stage decides between, and every column is
//! compared after every run (the harness: `tests/common/gpu.rs`).

use crate::common;

use common::gpu::*;
use socnav::backend::gpu::GpuStages;
use socnav::config::{ContactShape, Kinematics};
use socnav::geometry::{Disc, Rect, disc_disc, disc_rect, poly64_disc_disc, poly64_disc_rect};
use socnav::outputs::Outputs;
use socnav::rng::RngStream;
use socnav::spec::{INFO_KEYS, N_INFO, info};
use socnav::state::BatchState;
use socnav::{AutoresetMode, StepParams};

use std::sync::atomic::{AtomicUsize, Ordering};

/// Robots (and shadow robots) anywhere in and just outside the room, some at their goal, ticks
/// around the episode length, shadow outcomes cleared: every branch of `termination`.
fn scatter_robots(s: &mut BatchState, _: &mut Outputs, p: &StepParams, rng: &mut RngStream) {
    for e in 0..s.n_envs {
        let (hx, hy) = (0.6 * s.map_x[e], 0.6 * s.map_y[e]);
        s.robot_x[e] = uniform(rng, -hx, hx);
        s.robot_y[e] = uniform(rng, -hy, hy);
        s.shadow_x[e] = uniform(rng, -hx, hx);
        s.shadow_y[e] = uniform(rng, -hy, hy);
        if rng.next_f32() < 0.2 {
            s.goal_x[e] = s.robot_x[e] + uniform(rng, -0.6, 0.6);
            s.goal_y[e] = s.robot_y[e];
        }
        s.tick[e] = p.episode_length - 1 + (rng.next_u32() % 3);
        s.done[e] = 0;
        s.shadow_collided[e] = u32::from(rng.next_f32() < 0.1);
        s.shadow_reached[e] = 0;
    }
}
/// Contract: `robot_motion` (diff-drive): command clipping, rotation first, then translation.
#[test]
fn robot_motion_diff_drive() {
    check_parity("robot_motion", config("exp1"), 256, 50, None);
}

/// Contract: `robot_motion` (holonomic): the lateral command and its θ + π/2 terms, with a time
/// step other than 1 s (at dt = 1 a misplaced factor of dt would go unseen).
#[test]
fn robot_motion_holonomic() {
    let mut c = config("exp2");
    c.robot.kinematics = Kinematics::Holonomic;
    c.episode.time_step = 0.3;
    check_parity("robot_motion", c, 256, 50, None);
}

/// Contract: `termination` in every config kind (walls, plants, tables, laptops, groups): the
/// outcome flags, terminated/truncated, `done` and the shadow robot's outcome.
#[test]
fn termination() {
    for name in ["exp1", "exp2", "exp3", "lroom_mixed"] {
        let Some(raised) = check_parity("termination", config(name), 256, 20, Some(scatter_robots))
        else {
            return;
        };
        // Every outcome, collisions of each kind included, was decided on both sides.
        for (k, n) in raised.iter().enumerate() {
            assert!(*n > 0, "{name}: info flag {} never raised", INFO_KEYS[k]);
        }
    }
}

/// Robots scattered as for `termination`, moving at random world velocities and commands, with
/// random previous goal distances (or none) and an outcome drawn for a quarter of them: every
/// branch and term of `reward`.
fn scatter_for_reward(s: &mut BatchState, o: &mut Outputs, p: &StepParams, rng: &mut RngStream) {
    scatter_robots(s, o, p, rng);
    for e in 0..s.n_envs {
        s.robot_wvx[e] = uniform(rng, -0.2, 0.2);
        s.robot_wvy[e] = uniform(rng, -0.2, 0.2);
        let stalled = rng.next_f32() < 0.2;
        s.robot_vx[e] = if stalled {
            0.0
        } else {
            uniform(rng, -0.1, 0.1)
        };
        s.m_prev_vx[e] = uniform(rng, -0.1, 0.1);
        s.r_has_prev[e] = u32::from(rng.next_f32() < 0.8);
        s.r_prev_dist[e] = uniform(rng, 0.0, 10.0);
        let row = &mut o.info[e * N_INFO..e * N_INFO + 7];
        row.fill(0.0);
        if rng.next_f32() < 0.25 {
            row[(rng.next_u32() % 7) as usize] = 1.0;
        }
    }
}

/// Contract: `reward`: terminal constants, distance and discomfort terms (pseudo-humans of
/// groups and laptop users included), the persisting info values, and the weighted terms.
#[test]
fn reward() {
    for name in ["exp1", "exp2", "exp3"] {
        check_parity("reward", config(name), 256, 20, Some(scatter_for_reward));
    }
    let mut c = config("exp2");
    c.reward.personal_space_weight = -1.0;
    c.reward.personal_space_distance = 2.0;
    c.reward.obstacle_weight = -0.5;
    c.reward.obstacle_distance = 1.0;
    c.reward.stalled_weight = -0.1;
    c.reward.acceleration_weight = -0.3;
    c.episode.time_step = 0.3;
    check_parity("reward", c, 256, 20, Some(scatter_for_reward));
}

/// As for `reward`, plus a random reward, episodes ending for a third of the robots, and shadow
/// robots arrived at random ticks: every metric and the episode statistics of `metrics`.
fn scatter_for_metrics(s: &mut BatchState, o: &mut Outputs, p: &StepParams, rng: &mut RngStream) {
    scatter_for_reward(s, o, p, rng);
    for e in 0..s.n_envs {
        o.reward[e] = uniform(rng, -1.0, 1.0);
        s.done[e] = u32::from(rng.next_f32() < 0.3);
        s.shadow_reached[e] = u32::from(rng.next_f32() < 0.5);
        s.shadow_reach_tick[e] = 1 + rng.next_u32() % s.tick[e];
        s.shadow_path_length[e] = uniform(rng, 0.0, 20.0);
        s.m_path_length[e] = uniform(rng, 0.0, 20.0);
        s.robot_vy[e] = if p.holonomic != 0 {
            uniform(rng, -0.1, 0.1)
        } else {
            0.0
        };
    }
}

/// Contract: `metrics`: the info metrics, their running accumulators, and the statistics of the
/// episodes that end (time to collision, obstacle distances, STL/SPL included).
#[test]
fn metrics() {
    for name in ["exp1", "exp2", "exp3", "lroom_mixed"] {
        check_parity("metrics", config(name), 256, 20, Some(scatter_for_metrics));
    }
    let mut c = config("exp2");
    c.robot.kinematics = Kinematics::Holonomic;
    c.episode.time_step = 0.3;
    check_parity("metrics", c, 256, 20, Some(scatter_for_metrics));
}

/// Contract: `group_motion`: moving groups walk with their (divided) velocity plus Gaussian
/// noise from the counter-based stream (experiment 2's groups have none: the noisy L room's do),
/// and their centres follow; replayed noise when the config asks for it.
#[test]
fn group_motion() {
    for name in ["exp2", "exp3", "lroom_mixed", "corridor_mixed"] {
        check_parity("group_motion", config(name), 256, 30, None);
    }
    let mut c = config("lroom_mixed");
    c.episode.time_step = 0.3;
    check_parity("group_motion", c, 256, 30, None);
}

/// Humans scattered over the room (and into its objects), half of them walking: every kind of
/// contact `contacts` resolves.
fn scatter_humans(s: &mut BatchState, _: &mut Outputs, _: &StepParams, rng: &mut RngStream) {
    for e in 0..s.n_envs {
        let (hx, hy) = (0.5 * s.map_x[e], 0.5 * s.map_y[e]);
        let hb = e * s.strides.humans;
        for i in hb..hb + s.n_humans[e] as usize {
            s.h_x[i] = uniform(rng, -hx, hx);
            s.h_y[i] = uniform(rng, -hy, hy);
        }
    }
}

/// Contract: `contacts`: humans pushed out of plants, walls (mirror images), tables and free
/// laptops; static humans only take the push's speed.
#[test]
fn contacts() {
    for name in ["exp1", "exp2", "exp3", "lroom_mixed", "corridor_mixed"] {
        check_parity("contacts", config(name), 256, 10, Some(scatter_humans));
    }
    let mut c = config("exp2");
    c.episode.time_step = 0.3;
    check_parity("contacts", c, 256, 10, Some(scatter_humans));
}

/// Placements inside the 64-gon's inset by [`near_contact`]: decisions that exact discs and
/// 64-gons make differently.
static INSET_PLACEMENTS: AtomicUsize = AtomicUsize::new(0);

/// A point at t x the contact distance of a disc of radius `r` from a random entity of
/// environment `e` (a human when `humans`, a plant, a table, a laptop or a wall), t in
/// [0.997, 1.002] around the 64-gon's inset (cos(π/64) = 0.9988), in a random direction: off a
/// disc's centre, or off a random point of a rectangle's edge or corner region. Counts the
/// placements whose exact and 64-gon verdicts differ in [`INSET_PLACEMENTS`].
fn near_contact(
    s: &BatchState,
    p: &StepParams,
    e: usize,
    r: f32,
    humans: bool,
    rng: &mut RngStream,
) -> Option<(f32, f32)> {
    let mut discs: Vec<Disc> = Vec::new();
    if humans {
        let hb = e * s.strides.humans;
        discs.extend((hb..hb + s.n_humans[e] as usize).map(|i| Disc {
            x: s.h_x[i],
            y: s.h_y[i],
            r: p.human_radius,
        }));
    }
    let pb = e * s.strides.plants;
    discs.extend((pb..pb + s.n_plants[e] as usize).map(|i| Disc {
        x: s.p_x[i],
        y: s.p_y[i],
        r: p.plant_radius,
    }));
    let mut rects: Vec<Rect> = Vec::new();
    let tb = e * s.strides.tables;
    rects.extend((tb..tb + s.n_tables[e] as usize).map(|i| {
        Rect::with_trig(
            s.t_x[i],
            s.t_y[i],
            s.t_cos[i],
            s.t_sin[i],
            p.table_length,
            p.table_width,
        )
    }));
    let lb = e * s.strides.laptops;
    rects.extend((lb..lb + s.n_laptops[e] as usize).map(|i| {
        Rect::with_trig(
            s.l_x[i],
            s.l_y[i],
            s.l_cos[i],
            s.l_sin[i],
            p.laptop_length,
            p.laptop_width,
        )
    }));
    let wb = e * s.strides.walls;
    rects.extend((wb..wb + s.n_walls[e] as usize).map(|i| {
        Rect::with_trig(
            s.w_x[i],
            s.w_y[i],
            s.w_cos[i],
            s.w_sin[i],
            s.w_length[i],
            p.wall_thickness,
        )
    }));
    let n = discs.len() + rects.len();
    if n == 0 {
        return None;
    }
    let k = rng.next_u32() as usize % n;
    let t = uniform(rng, 0.997, 1.002);
    let angle = uniform(rng, -std::f32::consts::PI, std::f32::consts::PI);
    let (sn, c) = socnav::math::sin_cos(angle);
    let (x, y, differs) = if k < discs.len() {
        let o = discs[k];
        let dist = t * (r + o.r);
        let (x, y) = (o.x + dist * c, o.y + dist * sn);
        let d = Disc { x, y, r };
        (x, y, disc_disc(&d, &o) != poly64_disc_disc(&d, &o))
    } else {
        let o = rects[k - discs.len()];
        // A boundary point in the local frame (on an edge, or a corner), then outwards by t·r
        // along the edge normal, or along `angle` folded into the corner's quarter.
        let (sx, sy) = (c.signum(), sn.signum());
        let (lx, ly) = match rng.next_u32() % 3 {
            0 => (sx * (o.hl + t * r), uniform(rng, -o.hw, o.hw)),
            1 => (uniform(rng, -o.hl, o.hl), sy * (o.hw + t * r)),
            _ => (
                sx * (o.hl + t * r * c.abs()),
                sy * (o.hw + t * r * sn.abs()),
            ),
        };
        let (x, y) = (o.x + (lx * o.c - ly * o.s), o.y + (lx * o.s + ly * o.c));
        let d = Disc { x, y, r };
        (x, y, disc_rect(&d, &o) != poly64_disc_rect(&d, &o))
    };
    INSET_PLACEMENTS.fetch_add(usize::from(differs), Ordering::Relaxed);
    Some((x, y))
}

/// Every walking human placed at a contact distance around the 64-gon's inset from an object.
fn humans_near_objects(s: &mut BatchState, _: &mut Outputs, p: &StepParams, rng: &mut RngStream) {
    for e in 0..s.n_envs {
        let hb = e * s.strides.humans;
        for i in hb..hb + s.n_humans[e] as usize {
            if let Some((x, y)) = near_contact(s, p, e, p.human_radius, false, rng) {
                (s.h_x[i], s.h_y[i]) = (x, y);
            }
        }
    }
}

/// The robot and the shadow robot each placed at a contact distance around the 64-gon's inset
/// from a human or an object, outcomes cleared, ticks before the episode's end.
fn robots_near_contacts(s: &mut BatchState, _: &mut Outputs, p: &StepParams, rng: &mut RngStream) {
    for e in 0..s.n_envs {
        if let Some((x, y)) = near_contact(s, p, e, p.robot_radius, true, rng) {
            (s.robot_x[e], s.robot_y[e]) = (x, y);
        }
        if let Some((x, y)) = near_contact(s, p, e, p.robot_radius, true, rng) {
            (s.shadow_x[e], s.shadow_y[e]) = (x, y);
        }
        s.tick[e] = 1;
        s.done[e] = 0;
        s.shadow_collided[e] = 0;
        s.shadow_reached[e] = 0;
    }
}

/// Contract: with `contact_shape = "polygon64"` (the 64-gon tests of common/geometry.wgsl), the
/// human push-out of `contacts` and the robot's and shadow robot's collisions of `termination`
/// are bit-identical, on states whose contacts lie around the 64-gon's inset: walls, plants,
/// tables and laptops (L rooms with corridors' mixed counts), a few hundred placements decided
/// differently by exact discs among them.
#[test]
fn polygon64_contacts_and_termination() {
    let mut c = config("lroom_mixed");
    c.model.contact_shape = ContactShape::Polygon64;
    INSET_PLACEMENTS.store(0, Ordering::Relaxed);
    if check_parity("contacts", c.clone(), 256, 8, Some(humans_near_objects)).is_none() {
        return;
    }
    let raised = check_parity("termination", c, 256, 8, Some(robots_near_contacts))
        .expect("the device opened once");
    for k in [
        info::COLLISION_HUMAN,
        info::COLLISION_OBJECT,
        info::COLLISION_WALL,
    ] {
        assert!(raised[k] > 0, "info flag {} never raised", INFO_KEYS[k]);
    }
    let inset = INSET_PLACEMENTS.load(Ordering::Relaxed);
    println!("{inset} placements inside the 64-gon's inset");
    assert!(inset >= 200, "only {inset} placements inside the inset");
}

/// The state and the outputs survive the trip to the device and back bit for bit, every column.
#[test]
fn state_round_trip() {
    let Some(dev) = device() else { return };
    let env = rolled_out(config("exp3"), 64, 60);
    let state = env.state().clone();
    let outputs = env.outputs().clone();
    let gpu = GpuStages::new(dev, env.params(), &state, &outputs, &[]).expect("GPU stages");
    let mut back = BatchState::zeroed(state.n_envs, state.strides);
    assert!(!state.differing_columns(&back).is_empty());
    gpu.download_state(&mut back).expect("readback");
    assert!(
        state.differing_columns(&back).is_empty(),
        "state columns changed on the way: {:?}",
        state.differing_columns(&back)
    );
    let mut back = Outputs::zeroed(outputs.n_envs, outputs.strides);
    assert!(!outputs.differing_columns(&back).is_empty());
    gpu.download_outputs(&mut back).expect("readback");
    assert!(
        outputs.differing_columns(&back).is_empty(),
        "output columns changed on the way: {:?}",
        outputs.differing_columns(&back)
    );
}

/// Episodes ending, pending resets and stale per-step outputs at random: every branch of
/// `begin_step` and `autoreset`.
fn scatter_ends(s: &mut BatchState, o: &mut Outputs, _: &StepParams, rng: &mut RngStream) {
    for e in 0..s.n_envs {
        s.done[e] = u32::from(rng.next_f32() < 0.4);
        s.pending_reset[e] = u32::from(rng.next_f32() < 0.3);
        s.stepping[e] = u32::from(rng.next_f32() < 0.8);
        o.has_final[e] = u32::from(rng.next_f32() < 0.5);
        o.episode_done[e] = u32::from(rng.next_f32() < 0.5);
        o.reward[e] = uniform(rng, -1.0, 1.0);
        o.terminated[e] = s.done[e];
        for v in &mut o.events[e * socnav::spec::N_EVENTS..(e + 1) * socnav::spec::N_EVENTS] {
            *v = rng.next_u32() % 2;
        }
    }
}

/// Contract: `begin_step`: flags cleared, ticks counted, and NEXT_STEP resets copied from the
/// reset pool equal the CPU's in-place resets (state, first observation, zeroed info).
#[test]
fn begin_step() {
    for name in ["exp1", "exp3", "lroom_mixed"] {
        check_parity("begin_step", config(name), 256, 10, Some(scatter_ends));
    }
}

/// Contract: `autoreset` in each mode: SAME_STEP keeps the final observation, pairs and info
/// and resets from the pool keeping the step's reward and flags; NEXT_STEP marks the reset.
#[test]
fn autoreset() {
    for mode in [
        AutoresetMode::SameStep,
        AutoresetMode::NextStep,
        AutoresetMode::Disabled,
    ] {
        for name in ["exp2", "corridor_mixed"] {
            check_parity_mode("autoreset", config(name), mode, 256, 10, Some(scatter_ends));
        }
    }
}

/// Contract: the masked reset pass (`shaders/reset.wgsl`) equals `CpuBackend::reset` over about
/// half the environments, chained so that reset environments reset again from their next row.
#[test]
fn masked_reset() {
    for name in ["exp2", "stress"] {
        check_parity("reset", config(name), 256, 6, None);
    }
}
