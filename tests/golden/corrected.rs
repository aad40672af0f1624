//! Independent f64 computations, from a golden snapshot, of the fields where socnav fixes a 0.1.1
//! bug (docs/fidelity.md): the DSRNN discomfort term, with 0.1.1's double heading advance
//! (`buggy`, to check this reconstruction against the recording) and without it (`fixed`).

use serde_json::Value;

use super::num;

/// DSRNN discomfort constants of the paper configs (docs/spec.md 6.2).
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

/// TIME_TO_COLLISION of a post-motion snapshot (docs/spec.md 8.2): the fewest steps until the robot
/// and a human touch at constant velocities, −1 if none. `bug` reproduces 0.1.1's leaked loop
/// variable, which re-evaluates an already counted human in place of each laptop user, so laptop
/// users never count; socnav evaluates them (standing still).
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

/// What one human can contribute to TIME_TO_COLLISION once rounding is taken into account.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outcome {
    /// No collision predicted (receding, or passing by).
    Missed,
    /// A predicted collision in this many steps, anywhere in the closed range (`f64::INFINITY`
    /// as the upper end when the approach speed may be arbitrarily small).
    Steps(f64, f64),
}

/// Bounds (vector norms) on how far the inputs of one human's time-to-collision test may be
/// from the snapshot's values on the side being checked, beyond the f32 rounding that
/// [`time_to_collision_outcomes`] adds itself: relative position (m) and relative velocity
/// (m/s).
#[derive(Clone, Copy, Debug, Default)]
pub struct Perturbation {
    pub position: f64,
    pub velocity: f64,
}

/// Every outcome per human (snapshot order; laptop users skipped with `bug`, as in
/// [`time_to_collision`]) that inputs within `perturb(k)` of human k's, plus f32 rounding,
/// can give: the time-to-collision decisions of docs/spec.md 8.2 each flip where they are ill-
/// conditioned. 0.1.1 evaluates them in float32 (`compute_time_to_collision` rounds positions
/// and velocities to f32) and socnav in f32 from its own state.
///
/// Inputs: p = p_r − p_h, v = v_h − v_r, R = r_r + r_h. Both sides round the positions (half an
/// ulp of `extent` each) and subtract (half an ulp): p is known to δp = perturbation +
/// 2√2·ulp(extent) as a vector; v likewise to δv = perturbation + 2√2·ulp(max speed) (nothing
/// where both velocities are exactly zero, as they are on both sides). Norms,
/// dot products and quotients add a relative 4u. Decisions:
/// * |p| ≤ R (0 steps): may hold if |p| − δp ≤ R, surely if |p| + δp ≤ R;
/// * s = v·p̂ ≤ 0 (missed): p̂ moves by ≤ 2δp/|p|, so s by e_s = δv + |v|·2δp/|p| (+ 4u|v|);
///   the sign is decided only where |s| > e_s;
/// * t = |p|/s lies in [(|p| − δp)/(s + e_s), (|p| + δp)/(s − e_s)], unbounded above when
///   s − e_s ≤ 0: ⌈t/dt⌉ steps;
/// * accepted if the miss distance |v·t − p| ≤ R. At t = |p|/s it is exactly t·|v⊥| (v⊥ the
///   part of v across p), and |v⊥| moves by ≤ e_s as s does. The f32 evaluation
///   (p_h + v_h·t) − (p_r + v_r·t) rounds positions that grow to |extent| + |v|·t: 2√2·ulp
///   of `extent` and of R, plus 4√2·u·(|v_h| + |v_r|)·t. The miss distance thus lies in
///   [t_lo·(|v⊥| − e_s − g) − c, t_hi·(|v⊥| + e_s + g) + c]; the test may pass if the low end
///   is ≤ R and fail if the high end is > R.
pub fn time_to_collision_outcomes(
    state: &Value,
    dt: f64,
    (robot_radius, human_radius): (f64, f64),
    bug: bool,
    extent: f64,
    perturb: &dyn Fn(usize) -> Perturbation,
) -> Vec<Vec<Outcome>> {
    use super::conditioning::{U, ulp};
    use std::f64::consts::SQRT_2;
    let robot = &state["robot"];
    let (rx, ry, theta) = (num(&robot["x"]), num(&robot["y"]), num(&robot["theta"]));
    let vel = &robot["vel"];
    let (vx, vy) = (num(&vel[0]), num(&vel[1]));
    let (s, c) = theta.sin_cos();
    let (vrx, vry) = (vx * c - vy * s, vx * s + vy * c);
    let reach = robot_radius + human_radius;
    let rel = 4.0 * U;
    let mut all = Vec::new();
    for (k, h) in state["humans"]
        .as_array()
        .expect("humans")
        .iter()
        .enumerate()
    {
        if bug && h["role"] == "hl" {
            continue;
        }
        let (hx, hy) = (num(&h["x"]), num(&h["y"]));
        let (speed, th) = (num(&h["speed"]), num(&h["theta"]));
        let (vhx, vhy) = (speed * th.cos(), speed * th.sin());
        let (px, py) = (rx - hx, ry - hy);
        let dist = px.hypot(py);
        let (vx, vy) = (vhx - vrx, vhy - vry);
        let v = vx.hypot(vy);
        let fastest = speed.max(vrx.hypot(vry));
        let dp = perturb(k).position + 2.0 * SQRT_2 * ulp(extent) + rel * dist;
        // A velocity that is exactly zero (a standing human, a robot not translating) is zero on
        // both sides.
        let rounding = if fastest > 0.0 { ulp(fastest) } else { 0.0 };
        let dv = perturb(k).velocity + 2.0 * SQRT_2 * rounding;
        let contact = ulp(reach);
        let mut out = Vec::new();
        if dist - dp <= reach + contact {
            out.push(Outcome::Steps(0.0, 0.0));
        }
        if dist + dp <= reach - contact {
            all.push(out);
            continue;
        }
        let approach = (vx * px + vy * py) / dist;
        let across = (vx * py - vy * px).abs() / dist;
        let e_s = dv + v * 2.0 * dp / dist + rel * v;
        if approach - e_s <= 0.0 {
            out.push(Outcome::Missed);
        }
        if approach + e_s > 0.0 {
            let t_lo = (dist - dp) / (approach + e_s) * (1.0 - rel);
            let t_hi = if approach - e_s > 0.0 {
                (dist + dp) / (approach - e_s) * (1.0 + rel)
            } else {
                f64::INFINITY
            };
            let growth = 4.0 * SQRT_2 * U * (speed + vrx.hypot(vry));
            let rounding = 2.0 * SQRT_2 * ulp(extent) + contact;
            let slow = across - e_s - growth;
            let miss_lo = if slow > 0.0 {
                t_lo * slow - rounding
            } else {
                f64::NEG_INFINITY
            };
            let miss_hi = t_hi * (across + e_s + growth) + rounding;
            if miss_lo <= reach {
                out.push(Outcome::Steps((t_lo / dt).ceil(), (t_hi / dt).ceil()));
            }
            if miss_hi > reach && !out.contains(&Outcome::Missed) {
                out.push(Outcome::Missed);
            }
        }
        all.push(out);
    }
    all
}

/// Whether `value` (steps, −1 for none) is a TIME_TO_COLLISION that some choice of one outcome
/// per human gives: the minimum over the predicted collisions, −1 if every human is missed.
/// `value` ≥ 0 is possible iff some human's outcome contains it and every other human has an
/// outcome that does not undercut it (missed, or a range reaching up to `value`).
pub fn time_to_collision_possible(outcomes: &[Vec<Outcome>], value: f64) -> bool {
    if value < 0.0 {
        return outcomes.iter().all(|o| o.contains(&Outcome::Missed));
    }
    let contains = |o: &Outcome| matches!(*o, Outcome::Steps(lo, hi) if lo <= value && value <= hi);
    let not_below = |o: &Outcome| match *o {
        Outcome::Missed => true,
        Outcome::Steps(_, hi) => hi >= value,
    };
    outcomes.iter().enumerate().any(|(i, oi)| {
        oi.iter().any(contains)
            && outcomes
                .iter()
                .enumerate()
                .all(|(j, oj)| j == i || oj.iter().any(not_below))
    })
}
