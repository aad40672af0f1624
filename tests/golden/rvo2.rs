//! The RVO2 problem SocNavGym 0.1.1 solved for one agent of a golden step, rebuilt from the
//! recorded state as 0.1.1 builds it (docs/spec.md 4.3, 4.4, 8.2): a fresh simulator (every agent
//! at zero velocity) holding the agent, the other lone humans (walkers that moved earlier in the
//! step where they now are), the moving groups as super-agents, and the obstacles (tables, free
//! laptops, plants as squares, walls, laptop users as squares of half-side 2 × human diameter,
//! standing groups as squares of half-side the interaction radius), every input computed in f64
//! and rounded to f32 where it enters RVO2.
//!
//! socnav's ORCA is bit-exact with RVO2 on equal f32 inputs (`tests/suite/orca/reference.rs`), so
//! solving the rebuilt problem with it gives 0.1.1's ORCA lines, which `conditioning.rs` needs to
//! know which of them bind the recorded velocity and at what angle they meet. The published
//! episodes all have a full field of view: a narrower one is refused (the problem would depend
//! on what the walker saw). Whether a walker avoided the robot is drawn and not recorded: where
//! it may have, [`problems`] gives both problems.

use std::f64::consts::TAU;

use serde_json::Value;
use socnav::orca::{
    Line, ObstacleScratch, ObstacleSet, OrcaAgent, OrcaNeighbor, OrcaScratch, agent_neighbors,
    compute_new_velocity_tree, process_obstacles,
};

use super::{Step, num};

/// Which agent of a step.
#[derive(Clone, Copy, Debug)]
pub enum Who<'a> {
    /// A lone walker, by its pre-step record.
    Walker(&'a Value),
    /// Moving group `index` of the pre-step `groups` list.
    Group(usize),
    /// The shadow robot.
    Shadow,
}

/// One agent's RVO2 problem and what RVO2 makes of it.
pub struct Problem {
    /// The agent (velocity zero, as in 0.1.1's fresh simulator).
    pub agent: OrcaAgent,
    /// Its agent neighbours, nearest first, as RVO2 selects them.
    pub neighbors: Vec<OrcaNeighbor>,
    /// The obstacle polygons, in 0.1.1's order.
    pub polygons: Vec<[[f32; 2]; 4]>,
    /// The processed obstacles.
    pub obstacles: ObstacleSet,
    /// The simulator's time step (s).
    pub dt: f32,
    /// The ORCA lines, obstacle lines first.
    pub lines: Vec<Line>,
    /// How many of `lines` are obstacle lines.
    pub num_obstacle_lines: usize,
    /// Whether RVO2's LP2 failed and LP3 gave the velocity.
    pub lp3: bool,
    /// RVO2's new velocity.
    pub velocity: [f32; 2],
}

fn list(v: &Value) -> Vec<Value> {
    v.as_array().cloned().unwrap_or_default()
}

fn f32s(x: f64, y: f64) -> [f32; 2] {
    [x as f32, y as f32]
}

/// max_speed·unit(goal − position) in f64, rounded (zero at the goal).
fn preferred(pos: (f64, f64), goal: (f64, f64), speed: f64) -> [f32; 2] {
    let (dx, dy) = (goal.0 - pos.0, goal.1 - pos.1);
    let n = dx.hypot(dy);
    if n > 0.0 {
        f32s(speed * dx / n, speed * dy / n)
    } else {
        [0.0, 0.0]
    }
}

/// The rectangle's corners, counter-clockwise from local (+L/2, +W/2), in f64 then rounded.
fn rect(o: &Value, width: &str) -> [[f32; 2]; 4] {
    let (x, y, th) = (num(&o["x"]), num(&o["y"]), num(&o["theta"]));
    let (l, w) = (num(&o["length"]) / 2.0, num(&o[width]) / 2.0);
    let (s, c) = th.sin_cos();
    [(l, w), (-l, w), (-l, -w), (l, -w)]
        .map(|(lx, ly)| f32s(x + lx * c - ly * s, y + lx * s + ly * c))
}

/// The axis-aligned square of half-side `h` around (x, y), counter-clockwise from (+h, +h).
fn square(x: f64, y: f64, h: f64) -> [[f32; 2]; 4] {
    [
        f32s(x + h, y + h),
        f32s(x - h, y + h),
        f32s(x - h, y - h),
        f32s(x + h, y - h),
    ]
}

/// 0.1.1's RVO2 problems of `who` in `step`, whose pre-step state is `prev`, solved: one, or,
/// for a walker that avoids the robot with a probability strictly between 0 and 1 (the draw is
/// not recorded), the problem without the robot and the one with it.
pub fn problems(header: &Value, prev: &Value, step: &Step<'_>, who: Who<'_>) -> Vec<Problem> {
    let p_avoid = match who {
        Who::Walker(h) => num(&h["p_avoid_robot"]),
        _ => 0.0,
    };
    let mut out = Vec::new();
    if p_avoid < 1.0 {
        out.push(problem(header, prev, step, who, false));
    }
    if p_avoid > 0.0 {
        out.push(problem(header, prev, step, who, true));
    }
    out
}

/// 0.1.1's RVO2 problem of `who` in `step`, whose pre-step state is `prev`, solved, with the
/// robot among the agents if `robot` (a walker that avoids it this step).
pub fn problem(
    header: &Value,
    prev: &Value,
    step: &Step<'_>,
    who: Who<'_>,
    robot: bool,
) -> Problem {
    let cfg = &header["config"];
    let hp = &header["human_params"];
    let dt = num(&cfg["episode"]["time_step"]);
    let diameter = num(&cfg["human"]["human_diameter"]);
    let interaction = num(&cfg["human-human-interaction"]["interaction_radius"]);
    let human_speed = num(&cfg["env"]["max_advance_human"]);
    let threshold = num(&cfg["env"]["speed_threshold"]);
    let humans = list(&prev["humans"]);
    let groups = list(&prev["groups"]);
    let pos = |v: &Value| (num(&v["x"]), num(&v["y"]));
    let pair = |v: &Value| (num(&v[0]), num(&v[1]));

    let mut polygons = Vec::new();
    for t in list(&prev["tables"]) {
        polygons.push(rect(&t, "width"));
    }
    for l in list(&prev["laptops"]).iter().filter(|l| l["hl"].is_null()) {
        polygons.push(rect(l, "width"));
    }
    let plant_radius = num(&cfg["plant"]["plant_radius"]);
    for p in list(&prev["plants"]) {
        let r = p.get("radius").map_or(plant_radius, num);
        polygons.push(square(num(&p["x"]), num(&p["y"]), r));
    }
    for w in list(&header["walls"]) {
        polygons.push(rect(&w, "thickness"));
    }
    for h in humans.iter().filter(|h| h["role"] == "hl") {
        polygons.push(square(num(&h["x"]), num(&h["y"]), 2.0 * diameter));
    }
    for g in groups.iter().filter(|g| g["kind"] == "standing") {
        let c = pair(&g["centre"]);
        polygons.push(square(c.0, c.1, interaction));
    }
    let mut obstacles = ObstacleSet::new();
    process_obstacles(&polygons, &mut ObstacleScratch::new(), &mut obstacles)
        .unwrap_or_else(|e| panic!("golden obstacles: {e}"));

    // Walkers that moved before `who` (0.1.1 moves the lone walkers one after another, in list
    // order): where their recorded velocity took them.
    let moved = |h: &Value| -> (f64, f64) {
        let (x, y) = pos(h);
        let v = &step.v["diag"]["human_vel"][h["id"].to_string()];
        if !v.is_array() {
            return (x, y);
        }
        let (vx, vy) = (num(&v[1]), num(&v[2]));
        let mut speed = vx.hypot(vy);
        if speed < threshold && h["forming_crowd"] != true {
            speed = 0.0;
        }
        let th = vy.atan2(vx);
        (x + speed * th.cos() * dt, y + speed * th.sin() * dt)
    };
    let (first, skip_id, skip_group, moved_before) = match who {
        Who::Walker(h) => {
            let fov = num(&h["fov"]);
            assert!(
                (fov - TAU).abs() < 1e-6,
                "walker {}: its field of view {fov} is not a full one; the rebuilt problem would \
                 depend on what it saw",
                h["id"]
            );
            let p = pos(h);
            let goal = pair(&h["goal"]);
            let order = humans.iter().position(|o| o["id"] == h["id"]);
            let radius = diameter / 2.0;
            (
                (
                    p,
                    preferred(p, goal, human_speed),
                    radius,
                    num(&hp["orca_neighborDist"]),
                ),
                Some(h["id"].clone()),
                None,
                order,
            )
        }
        Who::Group(g) => {
            let grp = &groups[g];
            let c = pair(&grp["centre"]);
            let radius = interaction + diameter;
            let pref = preferred(c, pair(&grp["goal"]), human_speed);
            ((c, pref, radius, 2.0 * radius), None, Some(g), None)
        }
        Who::Shadow => {
            let p = pos(&prev["shadow_robot"]);
            let goal = pair(&prev["robot"]["goal"]);
            let speed = num(&cfg["env"]["max_advance_robot"]);
            let pref = preferred(p, goal, speed);
            (
                (p, pref, diameter / 2.0, num(&hp["orca_neighborDist"])),
                None,
                None,
                None,
            )
        }
    };
    let (p, pref_vel, radius, neighbor_dist) = first;
    let agent = OrcaAgent {
        pos: f32s(p.0, p.1),
        vel: [0.0, 0.0],
        pref_vel,
        radius: radius as f32,
        max_speed: num(&hp["orca_maxSpeed"]) as f32,
        neighbor_dist: neighbor_dist as f32,
        max_neighbors: humans.len() as u32,
        time_horizon: num(&hp["orca_timeHorizon"]).max(0.1) as f32,
        time_horizon_obst: num(&hp["orca_timeHorizonObst"]).max(0.1) as f32,
    };

    // The simulator's agents: the first one, the other lone humans, the moving groups.
    let mut agents = vec![OrcaNeighbor {
        pos: agent.pos,
        vel: [0.0, 0.0],
        radius: agent.radius,
    }];
    for (k, h) in humans.iter().enumerate() {
        let lone = h["role"] == "static" || h["role"] == "dynamic";
        if !lone || skip_id.as_ref() == Some(&h["id"]) {
            continue;
        }
        let at = match moved_before {
            Some(me) if k < me && h["role"] == "dynamic" => moved(h),
            _ => pos(h),
        };
        agents.push(OrcaNeighbor {
            pos: f32s(at.0, at.1),
            vel: [0.0, 0.0],
            radius: (diameter / 2.0) as f32,
        });
    }
    if robot {
        // The robot has moved before the humans: where the step left it.
        let r = &step.state_after_motion()["robot"];
        agents.push(OrcaNeighbor {
            pos: f32s(num(&r["x"]), num(&r["y"])),
            vel: [0.0, 0.0],
            radius: num(&cfg["robot"]["robot_radius"]) as f32,
        });
    }
    for (g, grp) in groups.iter().enumerate() {
        if grp["kind"] != "moving" || skip_group == Some(g) {
            continue;
        }
        let c = pair(&grp["centre"]);
        agents.push(OrcaNeighbor {
            pos: f32s(c.0, c.1),
            vel: [0.0, 0.0],
            radius: (interaction + diameter) as f32,
        });
    }
    let xs: Vec<f32> = agents.iter().map(|a| a.pos[0]).collect();
    let ys: Vec<f32> = agents.iter().map(|a| a.pos[1]).collect();
    let mut selected = Vec::new();
    agent_neighbors(
        0,
        &xs,
        &ys,
        agent.neighbor_dist,
        agent.max_neighbors,
        &mut selected,
    );
    let neighbors: Vec<OrcaNeighbor> = selected.iter().map(|n| agents[n.index as usize]).collect();

    let mut scratch = OrcaScratch::new();
    let velocity =
        compute_new_velocity_tree(&agent, &neighbors, &obstacles, dt as f32, &mut scratch);
    Problem {
        agent,
        neighbors,
        polygons,
        obstacles,
        dt: dt as f32,
        lines: scratch.lines().to_vec(),
        num_obstacle_lines: scratch.num_obstacle_lines(),
        lp3: scratch.used_lp3(),
        velocity,
    }
}
