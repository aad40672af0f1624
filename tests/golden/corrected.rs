//! Independent f64 computations, from a golden snapshot, of the fields where socnav fixes a 0.1.1
//! bug (docs/fidelity.md): the DSRNN discomfort term, with 0.1.1's double heading advance
//! (`buggy`, to check this reconstruction against the recording) and without it (`fixed`).

use serde_json::Value;

use super::num;

/// DSRNN discomfort constants of the paper configs (spec 6.2).
const DISCOMFORT_DISTANCE: f64 = 0.6;
const DISCOMFORT_FACTOR: f64 = 0.5;

/// The discomfort term of a step whose post-motion snapshot is `state`.
/// `bug` reproduces 0.1.1's robot velocity at heading θ + ω·dt; groups and laptop users count as
/// pseudo-humans at their centres (the modelling choice kept by default) with their own heading.
pub fn dsrnn_discomfort(
    state: &Value,
    dt: f64,
    robot_radius: f64,
    human_radius: f64,
    bug: bool,
) -> f64 {
    let robot = &state["robot"];
    let (rx, ry, theta) = (num(&robot["x"]), num(&robot["y"]), num(&robot["theta"]));
    let vel = &robot["vel"];
    let (vx, vy, w) = (num(&vel[0]), num(&vel[1]), num(&vel[2]));
    let heading = if bug { theta + w * dt } else { theta };
    let half_pi = std::f64::consts::FRAC_PI_2;
    let vrx = vx * heading.cos() + vy * (heading + half_pi).cos();
    let vry = vx * heading.sin() + vy * (heading + half_pi).sin();
    let clearance = |x: f64, y: f64, speed: f64, th: f64| {
        let (px, py) = (x - rx, y - ry);
        let (qx, qy) = (speed * th.cos() - vrx, speed * th.sin() - vry);
        let (ex, ey) = (qx * dt, qy * dt);
        let len_sq = ex * ex + ey * ey;
        let t = if len_sq > 0.0 {
            (-(px * ex + py * ey) / len_sq).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (cx, cy) = (px + t * ex, py + t * ey);
        (cx * cx + cy * cy).sqrt() - human_radius - robot_radius
    };
    let humans = state["humans"].as_array().expect("humans");
    let mut d_min = f64::INFINITY;
    for h in humans {
        d_min = d_min.min(clearance(
            num(&h["x"]),
            num(&h["y"]),
            num(&h["speed"]),
            num(&h["theta"]),
        ));
    }
    for g in state["groups"].as_array().into_iter().flatten() {
        let members: Vec<&Value> = g["members"]
            .as_array()
            .expect("members")
            .iter()
            .map(|id| humans.iter().find(|h| h["id"] == *id).expect("member"))
            .collect();
        let mean_speed =
            members.iter().map(|h| num(&h["speed"])).sum::<f64>() / members.len() as f64;
        let centre = &g["centre"];
        d_min = d_min.min(clearance(
            num(&centre[0]),
            num(&centre[1]),
            mean_speed,
            num(&members[0]["theta"]),
        ));
    }
    for u in state["hl_interactions"].as_array().into_iter().flatten() {
        let centre = &u["centre"];
        d_min = d_min.min(clearance(num(&centre[0]), num(&centre[1]), 0.0, 0.0));
    }
    if d_min < DISCOMFORT_DISTANCE {
        (d_min - DISCOMFORT_DISTANCE) * DISCOMFORT_FACTOR * dt
    } else {
        0.0
    }
}

/// The relative angular speed 0.1.1 observes, with its heading difference wrapped (socnav's fix).
pub fn wrapped_angular_speed(recorded: f64, dt: f64) -> f64 {
    let a = recorded * dt;
    a.sin().atan2(a.cos()) / dt
}

/// TIME_TO_COLLISION of a post-motion snapshot (spec 8.2): the fewest steps until the robot and a
/// human touch at constant velocities, −1 if none. `bug` reproduces 0.1.1's leaked loop variable,
/// which re-evaluates an already counted human in place of each laptop user, so laptop users
/// never count; socnav evaluates them (standing still).
pub fn time_to_collision(
    state: &Value,
    dt: f64,
    robot_radius: f64,
    human_radius: f64,
    bug: bool,
) -> f64 {
    let robot = &state["robot"];
    let (rx, ry, theta) = (num(&robot["x"]), num(&robot["y"]), num(&robot["theta"]));
    let vel = &robot["vel"];
    let (vx, vy) = (num(&vel[0]), num(&vel[1]));
    let (s, c) = theta.sin_cos();
    let (vrx, vry) = (vx * c - vy * s, vx * s + vy * c);
    let reach = robot_radius + human_radius;
    let mut best = f64::INFINITY;
    for h in state["humans"].as_array().expect("humans") {
        if bug && h["role"] == "hl" {
            continue;
        }
        let (hx, hy) = (num(&h["x"]), num(&h["y"]));
        let (speed, th) = (num(&h["speed"]), num(&h["theta"]));
        let (vhx, vhy) = (speed * th.cos(), speed * th.sin());
        let (px, py) = (rx - hx, ry - hy);
        let dist = px.hypot(py);
        if dist <= reach {
            best = 0.0;
            continue;
        }
        let approach = ((vhx - vrx) * px + (vhy - vry) * py) / dist;
        if approach <= 0.0 {
            continue;
        }
        let t = dist / approach;
        let gap = ((hx + vhx * t) - (rx + vrx * t)).hypot((hy + vhy * t) - (ry + vry * t));
        if gap <= reach {
            best = best.min((t / dt).ceil());
        }
    }
    if best.is_finite() { best } else { -1.0 }
}
