//! How closely a golden step determines the values that 0.1.1 and socnav both compute in float32
//! from slightly different inputs (docs/fidelity.md, "Approximations and representation").
//!
//! One fact runs through every bound here: rounding a value x to f32 moves it by at most half
//! an ulp of x ([`ulp`]), and an f32 operation on values of magnitude x adds at most another
//! half ulp. 0.1.1 rounds its f64 state to f32 where it enters RVO2 or its float32 helpers;
//! socnav rounds the recorded state once when it loads it and computes in f32 from there. The
//! bounds below propagate those roundings, to first order, to the quantities the replay
//! compares; each function states its derivation.

use std::f64::consts::{PI, SQRT_2};

use serde_json::Value;

use super::contact::rectangle_distance;
use super::rvo2::{Problem, Who, problems};
use super::{Step, num};

/// Unit roundoff of f32 (2⁻²⁴): an f32 operation has a relative error of at most this.
pub const U: f64 = 5.960_464_477_539_063e-8;

/// The spacing of the f32 values at magnitude |x| (one ulp): rounding x to f32, or an f32
/// operation whose result has magnitude ≤ |x|, moves it by at most half of this.
pub fn ulp(x: f64) -> f64 {
    let f = (x.abs() as f32).max(f32::MIN_POSITIVE);
    f64::from(f32::from_bits(f.to_bits() + 1) - f)
}

/// The largest coordinate magnitude (m) of anything RVO2 or the social forces see in a step:
/// the robot and the shadow robot, humans (with the 2·diameter laptop-user squares around
/// them), group centres (with their obstacle squares), plants, tables and laptops (with their
/// ORCA squares or circumradius) and the walls' corners. Every position such a simulation holds
/// in f32 is rounded at this magnitude or below.
pub fn extent(header: &Value, states: &[&Value], human_radius: f64) -> f64 {
    let list = |v: &Value| v.as_array().cloned().unwrap_or_default();
    let mut x: f64 = 0.0;
    let at = |v: &Value| (num(&v["x"]), num(&v["y"]));
    for w in list(&header["walls"]) {
        let (s, c) = num(&w["theta"]).sin_cos();
        let (l, t) = (num(&w["length"]) / 2.0, num(&w["thickness"]) / 2.0);
        let (cx, cy) = at(&w);
        x = x
            .max(cx.abs() + (l * c).abs() + (t * s).abs())
            .max(cy.abs() + (l * s).abs() + (t * c).abs());
    }
    let mut reach = |c: (f64, f64), r: f64| x = x.max(c.0.abs() + r).max(c.1.abs() + r);
    for state in states {
        reach(at(&state["robot"]), 0.0);
        reach(at(&state["shadow_robot"]), 0.0);
        for h in list(&state["humans"]) {
            reach(at(&h), SQRT_2 * 4.0 * human_radius);
        }
        for g in list(&state["groups"]) {
            let c = (num(&g["centre"][0]), num(&g["centre"][1]));
            reach(c, SQRT_2 * (num(&g["radius"]) + 2.0 * human_radius));
        }
        for key in ["tables", "laptops"] {
            for o in list(&state[key]) {
                reach(at(&o), num(&o["length"]).hypot(num(&o["width"])) / 2.0);
            }
        }
        for p in list(&state["plants"]) {
            reach(at(&p), SQRT_2 * num(&p["radius"]));
        }
    }
    x
}

/// Bound (m/s) on the difference, as a vector, between 0.1.1's and socnav's preferred velocity
/// `speed`·unit(goal − position) of an agent `distance` metres from its goal.
///
/// 0.1.1 subtracts in f64 and rounds the difference (half an ulp of `distance` per component);
/// socnav subtracts the rounded goal and position (half an ulp of `extent` each) and rounds the
/// difference again: the two difference vectors differ by ≤ √2·(ulp(extent) + ulp(distance)),
/// so their directions by that over `distance` (rad), and the unit vectors scaled by `speed` by
/// `speed` times that angle, at most 2·`speed` (opposite directions). The normalisation and the
/// scaling round each component by half an ulp of `speed` on each side: 4 ulp in all. Near its
/// goal (a walker arriving at its slot of a forming crowd) the direction is ill-conditioned.
pub fn preferred_velocity_error(extent: f64, speed: f64, distance: f64) -> f64 {
    if speed == 0.0 {
        return 0.0;
    }
    let angle = SQRT_2 * (ulp(extent) + ulp(distance)) / distance;
    speed * angle.min(2.0) + 4.0 * ulp(speed)
}

/// Bound (m/s) on the difference, as a vector, between 0.1.1's and socnav's RVO2 velocity of one
/// agent (a lone ORCA walker, a moving group, the shadow robot), from the agent's own RVO2
/// problem `p` ([`super::rvo2::problem`]: 0.1.1's ORCA lines and solution, rebuilt from the
/// recorded state).
///
/// socnav's ORCA is bit-exact with RVO2 on equal f32 inputs (`tests/suite/orca/reference.rs`), so
/// the two velocities differ only through their inputs:
/// * relative positions: every position or obstacle vertex is within half an ulp of `extent`
///   of its exact value on 0.1.1's side (rounded from f64) and within 1.5 ulp on socnav's (its
///   own rounding, plus the f32 motion of a walker moved earlier in the step, or the f32
///   arithmetic of a vertex); a relative position therefore differs by ≤ 2 ulp per component,
///   δ = 2√2·ulp(`extent`) as a vector. Each ORCA line moves accordingly ([`line_errors`]);
/// * the preferred velocity ([`preferred_velocity_error`]), which moves the solution by at most
///   its own error (the solution is a projection of it, or, at a vertex or in LP3, independent
///   of it).
///
/// How far the lines' shifts move the solution depends on which constraints bind there
/// ([`binding_error`]): one line moves it by its shift, but two lines that meet at a small angle
/// φ move their intersection by (s₁ + s₂)/sin φ. A walker pressed against a wall by a moving
/// group that stands between it and the wall's far side (exp2, `tests/data/fixtures/`, t = 130:
/// sin φ = 0.0118) moves 85 times as far as the lines.
pub fn rvo2_velocity_error(extent: f64, p: &Problem, pref_speed: f64, goal: f64) -> f64 {
    let delta = 2.0 * SQRT_2 * ulp(extent);
    let lines = line_errors(p, delta);
    binding_error(p, &lines) + preferred_velocity_error(extent, pref_speed, goal)
}

/// [`rvo2_velocity_error`] of the problems an agent may have solved (with and without the robot
/// for a walker whose avoidance draw is not recorded): the largest.
pub fn rvo2_velocity_errors(extent: f64, ps: &[Problem], pref_speed: f64, goal: f64) -> f64 {
    ps.iter()
        .map(|p| rvo2_velocity_error(extent, p, pref_speed, goal))
        .fold(0.0, f64::max)
}

/// How one ORCA line of a problem may differ between 0.1.1 and socnav, to first order in δ.
#[derive(Clone, Copy, Debug)]
pub struct LineError {
    /// Bound (m/s) on the line's displacement, along its normal, at the solution v*.
    pub shift: f64,
    /// Bound (rad) on the rotation of its direction.
    pub turn: f64,
}

/// [`LineError`] of each line of `p`, the relative positions being known to `delta` (m).
///
/// Agents all start at zero velocity (0.1.1's fresh simulator), so every line is n·v ≤ c with n
/// a unit vector from the agent towards what it avoids, and RVO2's branches reduce to:
/// * agent neighbour at distance ρ, radii sum R: c = (ρ − R)/(2τ), or (ρ − R)/(2·dt) once they
///   overlap (the cut-off circle of the time step): c moves by δ/(2τ) (δ/(2dt)), n by δ/ρ, which
///   moves the line at v* by |v*|·δ/ρ: shift δ/(2τ) + |v*|·δ/ρ, turn δ/ρ;
/// * obstacle vertex at distance ρ (the cut-off circle of a vertex seen end-on): c = (ρ − R)/τ_o,
///   so ρ = R + τ_o·|point|: shift δ/τ_o + |v*|·δ/ρ, turn δ/ρ; a vertex already inside the disc
///   (RVO2's vertex "collision" line, through the origin, ρ ≤ R): shift |v*|·δ/ρ, turn δ/ρ;
/// * obstacle edge A→B of length L (its cut-off segment, direction −(B − A)/L): the line is
///   the edge's line, offset by R and scaled by 1/τ_o; A and B each move by δ relative to the
///   agent, so the edge's line moves by (|1 − t| + |t|)·δ at the point of parameter t, where
///   t* = ((pos + τ_o·v*) − A)·(B − A)/L² is the point v* stands for: shift (|1 − t*| + |t*|)·δ/τ_o,
///   turn 2δ/L; an edge already inside the disc (the line through the origin along the edge):
///   shift |v*|·2δ/L, turn 2δ/L. A split edge keeps the direction of its polygon's edge, whose
///   ends A, B are taken.
///
/// Within δ of the branch boundary (distance ≈ R) the two sides may take different branches.
/// The lines agree in the limit (c → 0; the normal is the same), and the other side's line is
/// offset by at most what its distance, within δ of R, gives: δ/τ_o for an obstacle (the line
/// through the origin then shifts by δ/τ_o, not 0: a walker 5e-7 m into a wall face is, on the
/// other side, up to 4.5e-7 m outside it), δ/(2·min(τ, dt)) for an agent. A vertex seen at the
/// edge's end has the edge's normal, so that boundary costs nothing.
pub fn line_errors(p: &Problem, delta: f64) -> Vec<LineError> {
    let a = &p.agent;
    let pos = (f64::from(a.pos[0]), f64::from(a.pos[1]));
    let v = (f64::from(p.velocity[0]), f64::from(p.velocity[1]));
    let speed = v.0.hypot(v.1);
    let r = f64::from(a.radius);
    let (tau, tau_o, dt) = (
        f64::from(a.time_horizon),
        f64::from(a.time_horizon_obst),
        f64::from(p.dt),
    );
    // The offset of the other side's line where this side's, through the origin, stands for a
    // distance `rho` ≤ R to the obstacle: 0 unless the other side's may exceed R.
    let boundary = |rho: f64| if r - rho > delta { 0.0 } else { delta / tau_o };
    let view = p.obstacles.as_view();
    let edges: Vec<((f64, f64), (f64, f64))> = p
        .polygons
        .iter()
        .flat_map(|poly| {
            (0..poly.len()).map(move |i| {
                let (s, e) = (poly[i], poly[(i + 1) % poly.len()]);
                (
                    (f64::from(s[0]), f64::from(s[1])),
                    (f64::from(e[0]), f64::from(e[1])),
                )
            })
        })
        .collect();
    p.lines
        .iter()
        .enumerate()
        .map(|(k, line)| {
            let d = (f64::from(line.direction.x), f64::from(line.direction.y));
            let point = (f64::from(line.point.x), f64::from(line.point.y));
            let through_origin = line.point.x == 0.0 && line.point.y == 0.0;
            if k >= p.num_obstacle_lines {
                let nb = &p.neighbors[k - p.num_obstacle_lines];
                let rel = (f64::from(nb.pos[0]) - pos.0, f64::from(nb.pos[1]) - pos.1);
                let rho = rel.0.hypot(rel.1);
                let sum = r + f64::from(nb.radius);
                let horizon = if rho - sum > delta {
                    tau
                } else if sum - rho > delta {
                    dt
                } else {
                    tau.min(dt)
                };
                let turn = delta / rho;
                return LineError {
                    shift: delta / (2.0 * horizon) + speed * turn,
                    turn,
                };
            }
            // An edge line carries the (negated) direction RVO2 stored for the edge, bit for bit.
            let edge_line = (0..view.len()).any(|o| {
                let e = view.dir(o);
                -e.x == line.direction.x && -e.y == line.direction.y
            });
            if edge_line {
                // The polygon edge along −d whose line lies where this line says: at R (inside
                // the disc: at most R) plus τ_o·c from the agent.
                let offset = (d.0 * point.1 - d.1 * point.0).abs();
                let ((ax, ay), (bx, by)) = edges
                    .iter()
                    .copied()
                    .filter(|((ax, ay), (bx, by))| {
                        let l = (bx - ax).hypot(by - ay);
                        ((bx - ax) / l + d.0).abs() < 1e-6 && ((by - ay) / l + d.1).abs() < 1e-6
                    })
                    .min_by(|x, y| {
                        let miss = |((ax, ay), (bx, by)): ((f64, f64), (f64, f64))| {
                            let l = (bx - ax).hypot(by - ay);
                            let gap =
                                ((bx - ax) * (pos.1 - ay) - (by - ay) * (pos.0 - ax)).abs() / l;
                            (gap - r - tau_o * offset).abs()
                        };
                        miss(*x).total_cmp(&miss(*y))
                    })
                    .expect("an edge line comes from a polygon edge");
                let (ex, ey) = (bx - ax, by - ay);
                let l2 = ex * ex + ey * ey;
                let turn = 2.0 * delta / l2.sqrt();
                if through_origin {
                    let gap = (ex * (pos.1 - ay) - ey * (pos.0 - ax)).abs() / l2.sqrt();
                    return LineError {
                        shift: speed * turn + boundary(gap),
                        turn,
                    };
                }
                let t = ((pos.0 + tau_o * v.0 - ax) * ex + (pos.1 + tau_o * v.1 - ay) * ey) / l2;
                return LineError {
                    shift: ((1.0 - t).abs() + t.abs()) * delta / tau_o,
                    turn,
                };
            }
            if through_origin {
                // The vertex inside the disc whose direction is the line's normal.
                let rho = (0..view.len())
                    .map(|o| {
                        let q = view.point(o);
                        (f64::from(q.x) - pos.0, f64::from(q.y) - pos.1)
                    })
                    .filter(|rel| rel.0.hypot(rel.1) <= r * (1.0 + 1e-5))
                    .min_by(|x, y| {
                        let along = |rel: (f64, f64)| {
                            (rel.0 * d.0 + rel.1 * d.1).abs() / rel.0.hypot(rel.1)
                        };
                        along(*x).total_cmp(&along(*y))
                    })
                    .map(|rel| rel.0.hypot(rel.1))
                    .expect("a vertex collision line comes from a vertex inside the disc");
                let turn = delta / rho;
                return LineError {
                    shift: speed * turn + boundary(rho),
                    turn,
                };
            }
            let rho = r + tau_o * point.0.hypot(point.1);
            let turn = delta / rho;
            LineError {
                shift: delta / tau_o + speed * turn,
                turn,
            }
        })
        .collect()
}

/// Bound (m/s) on how far the lines' errors `lines` (first order) move the solution v* of `p`.
///
/// v* is the optimum of a linear program over the lines and the speed disc |v| ≤ v_max (LP2:
/// the point nearest the preferred velocity; LP3, when the lines leave nothing feasible: the
/// point of least largest violation of the agent lines, the obstacle lines kept). Under small
/// changes the optimum moves linearly with the constraints that bind at it, so its movement is
/// bounded by the largest over the structures those constraints can form:
/// * one line k, v* the projection onto it: a line turned by α about v* and moved by s moves
///   the projection by s + α·|pref − v*|;
/// * two lines i, j meeting at v* at angle φ (sin φ = |det(dᵢ, dⱼ)|): moving line i by sᵢ slides
///   the intersection along line j by sᵢ/sin φ (turns about v* do not move it): (sᵢ + sⱼ)/sin φ.
///   RVO2's LP1 takes |det| ≤ RVO_EPSILON (1e-5) for parallel and never intersects such lines;
/// * a line meeting the speed circle at v*, at angle ψ to its tangent (sin ψ = |d·v̂*|): s/sin ψ,
///   and at most √(2·v_max·s + s²) + s (a chord's end as its line moves by s);
/// * in LP3 the binding agent lines have equal violation t*: two of them, i and j, bind along
///   the line where their violations are equal, of normal nⱼ − nᵢ (length |dᵢ − dⱼ|), which
///   moves by (sᵢ + sⱼ)/|dᵢ − dⱼ|; these lines and the binding obstacle lines form the vertices
///   and circle crossings above. One binding agent line alone: v* = v_max·(−nᵢ) turns with it
///   (v_max·α).
///
/// A constraint binds if its distance from v* is within what the perturbation can close: its
/// own shift, the bound itself (found by iterating from the constraints that pass through v*
/// to a fixed point), in LP3 also the largest shift (which moves t*), and the f32 rounding of the
/// solve (4 ulp of the line's point and of v_max). Neighbour selection, the obstacle range and
/// RVO2's "already covered" test are discrete choices this first-order bound leaves aside.
pub fn binding_error(p: &Problem, lines: &[LineError]) -> f64 {
    let v = (f64::from(p.velocity[0]), f64::from(p.velocity[1]));
    let speed = v.0.hypot(v.1);
    let r = f64::from(p.agent.max_speed);
    let pref = (
        f64::from(p.agent.pref_vel[0]),
        f64::from(p.agent.pref_vel[1]),
    );
    let to_pref = (pref.0 - v.0).hypot(pref.1 - v.1);
    let dir = |k: usize| {
        let d = p.lines[k].direction;
        (f64::from(d.x), f64::from(d.y))
    };
    // det(d, point − v): > 0 violates the line.
    let violation = |k: usize| {
        let (l, d) = (&p.lines[k], dir(k));
        d.0 * (f64::from(l.point.y) - v.1) - d.1 * (f64::from(l.point.x) - v.0)
    };
    let rounding = |k: usize| {
        let l = &p.lines[k];
        4.0 * (ulp(f64::from(l.point.x).hypot(f64::from(l.point.y))) + ulp(r))
    };
    let det = |a: (f64, f64), b: (f64, f64)| a.0 * b.1 - a.1 * b.0;
    let tangent = if speed > 0.0 {
        (v.0 / speed, v.1 / speed)
    } else {
        (0.0, 0.0)
    };
    // A line along unit direction u whose offset is known to w, crossing the speed circle at v*.
    let on_circle = |u: (f64, f64), w: f64| {
        let sin = (u.0 * tangent.0 + u.1 * tangent.1).abs();
        (w / sin).min((2.0 * r * w + w * w).sqrt() + w)
    };
    let n = p.lines.len();
    let agent_lines = p.num_obstacle_lines..n;
    let t_star = agent_lines.clone().map(violation).fold(0.0, f64::max);
    let s_max = agent_lines
        .clone()
        .map(|k| lines[k].shift)
        .fold(0.0, f64::max);
    let mut bound: f64 = 0.0;
    loop {
        let disc = (r - speed).abs() <= 4.0 * ulp(r) + bound;
        let mut worst: f64 = 0.0;
        // Effective lines: (unit direction, offset error).
        let mut effective: Vec<((f64, f64), f64)> = Vec::new();
        if p.lp3 {
            let binding: Vec<usize> = agent_lines
                .clone()
                .filter(|&k| {
                    (violation(k) - t_star).abs()
                        <= rounding(k) + lines[k].shift + s_max + 2.0 * bound
                })
                .collect();
            for (x, &i) in binding.iter().enumerate() {
                if disc {
                    worst = worst.max(r * lines[i].turn);
                }
                for &j in &binding[x + 1..] {
                    let (di, dj) = (dir(i), dir(j));
                    let m = (dj.0 - di.0, dj.1 - di.1);
                    let len = m.0.hypot(m.1);
                    if len > 0.0 {
                        effective.push((
                            (m.0 / len, m.1 / len),
                            (lines[i].shift + lines[j].shift) / len,
                        ));
                    }
                }
            }
            for (k, line) in lines.iter().enumerate().take(p.num_obstacle_lines) {
                if violation(k).abs() <= rounding(k) + line.shift + bound {
                    effective.push((dir(k), line.shift));
                }
            }
        } else {
            for (k, line) in lines.iter().enumerate() {
                if violation(k).abs() <= rounding(k) + line.shift + bound {
                    worst = worst.max(line.shift + line.turn * to_pref);
                    effective.push((dir(k), line.shift));
                }
            }
        }
        for (x, &(a, wa)) in effective.iter().enumerate() {
            worst = worst.max(wa);
            if disc {
                worst = worst.max(on_circle(a, wa));
            }
            for &(b, wb) in &effective[x + 1..] {
                let sin = det(a, b).abs();
                if sin > f64::from(socnav::orca::RVO_EPSILON) {
                    worst = worst.max((wa + wb) / sin);
                }
            }
        }
        if worst <= bound {
            return bound;
        }
        bound = worst;
    }
}

/// Bound (rad) on the difference of the directions of two velocities whose vector difference is
/// at most `error`, one of them of magnitude `speed`: asin(error/speed), or any direction (π)
/// once the error reaches the speed (a body at rest has no direction).
pub fn direction_error(speed: f64, error: f64) -> f64 {
    if error >= speed {
        PI
    } else {
        (error / speed).asin()
    }
}

/// Social-force parameters of an episode (golden header `human_params`).
struct Sfm {
    r0: f64,
    gamma: f64,
    n: f64,
    n_prime: f64,
    lambda: f64,
}

/// Constants of a step that the velocity bounds need.
pub struct Kinematics {
    pub dt: f64,
    pub human_radius: f64,
    pub human_max_speed: f64,
    pub robot_max_speed: f64,
}

/// Bound (m/s) on the difference, as a vector, between 0.1.1's and socnav's social-force
/// velocity of lone walker `h` (its pre-step record), docs/spec.md 4.3:
/// v = dt·w·(f_d + Σ f_o + Σ f_ij), w = 1/√3, scaled down to the maximum speed if longer (a
/// projection onto a disc, which does not increase differences). Relative positions differ by
/// δ = 2√2·ulp(extent) (as in [`rvo2_velocity_error`]). Per term:
/// * desired force: [`preferred_velocity_error`];
/// * obstacle force exp(−g/r0)·unit(p − q), g the surface gap, ρ = |p − q|: the factor moves by
///   F·δ/r0 (and by F·|g|/r0·u for r0 rounded to f32), the unit vector by 2δ/ρ;
/// * pedestrian force −m·(k₁t + k₂n), m = exp(−d/B), B = γ|D|, D = λ·v_ij + e,
///   kᵢ = exp(−(aᵢθ)²), a = n′B or nB, θ = acos(e·t): with |v_ij| ≤ 2·v_max, |D| ≥ 1 − 2λv_max
///   and θ ≤ asin(2λv_max). d is taken from the pre-step state ± v_max·dt (earlier walkers
///   move first). e moves by 2δ/d, D by that (plus the f32 rounding of the velocities, 4 ulp
///   of v_max times λ), t by 2ΔD/|D|, B by γΔD, m by m·(δ/B + d·ΔB/B²); c = e·t by
///   Δe + Δt + 4u (socnav's f32 dot product). kᵢ as a function of c has slope
///   2a²·θ/sin θ ≤ 2a²·θmax/sin θmax — bounded although acos is not Lipschitz at 1, which is why
///   θ ≈ 0 (f32 acos of a rounded cosine near 1 is off by ~√(8u)) costs nothing — and as a
///   function of a the slope 2aθ² ≤ 2a·θmax², with Δa = nΔB. Whence
///   |Δf_ij| ≤ 2Δm + m·(Δk₁ + Δk₂ + Δt + Δn).
/// * 0.1.1 accumulates the force in float32: half an ulp of the running sum per term.
///
/// Velocities of earlier walkers differ between the sides by the bounds computed here
/// (≲ 1e-6 m/s), which moves D by λ times that; it is of the order of the terms kept and left
/// out.
pub fn sfm_velocity_error(
    header: &Value,
    prev: &Value,
    h: &Value,
    k: &Kinematics,
    extent: f64,
) -> f64 {
    let hp = &header["human_params"];
    let sfm = Sfm {
        r0: num(&hp["sfm_r0"]),
        gamma: num(&hp["sfm_gamma"]),
        n: num(&hp["sfm_n"]),
        n_prime: num(&hp["sfm_n_prime"]),
        lambda: num(&hp["sfm_lambda"]),
    };
    let delta = 2.0 * SQRT_2 * ulp(extent);
    let (x, y) = (num(&h["x"]), num(&h["y"]));
    let r = k.human_radius;
    let v_max = k.human_max_speed;
    let goal = (num(&h["goal"][0]) - x).hypot(num(&h["goal"][1]) - y);
    let mut error = preferred_velocity_error(extent, v_max, goal);
    let mut magnitude = v_max;
    let mut terms = 1.0;
    let mut obstacle = |rho: f64, gap: f64| {
        let f = (-gap / sfm.r0).exp();
        error += f * (delta / sfm.r0 + 2.0 * delta / rho + U * gap.abs() / sfm.r0);
        magnitude += f;
        terms += 1.0;
    };
    let list = |v: &Value| v.as_array().cloned().unwrap_or_default();
    for p in list(&prev["plants"]) {
        let rho = (num(&p["x"]) - x).hypot(num(&p["y"]) - y);
        obstacle(rho, rho - num(&p["radius"]) - r);
    }
    for w in list(&header["walls"]) {
        let rho = rectangle_distance(&w, "thickness", x, y);
        obstacle(rho, rho - r);
    }
    let free_laptops = list(&prev["laptops"])
        .into_iter()
        .filter(|l| l["hl"].is_null());
    for o in list(&prev["tables"]).into_iter().chain(free_laptops) {
        let rho = rectangle_distance(&o, "width", x, y);
        obstacle(rho, rho - r);
    }
    for g in list(&prev["groups"]) {
        if g["kind"] == "standing" {
            let rho = (num(&g["centre"][0]) - x).hypot(num(&g["centre"][1]) - y);
            obstacle(rho, rho - num(&g["radius"]) - r);
        }
    }
    let spread = 2.0 * sfm.lambda * v_max;
    assert!(
        spread < 1.0,
        "SFM bound: λ·|v_ij| must stay below 1 (|D| > 0)"
    );
    let (b_lo, b_hi) = (sfm.gamma * (1.0 - spread), sfm.gamma * (1.0 + spread));
    let theta_max = spread.asin();
    let slope = theta_max / theta_max.sin();
    let n_max = sfm.n.max(sfm.n_prime);
    let a_max = n_max * b_hi;
    for o in list(&prev["humans"]) {
        if o["id"] == h["id"] || o["role"] == "standing_group" {
            continue;
        }
        let d = (num(&o["x"]) - x).hypot(num(&o["y"]) - y);
        let (d_lo, d_hi) = ((d - v_max * k.dt).max(r), d + v_max * k.dt);
        let m = (-d_lo / b_hi).exp();
        let de = 2.0 * delta / d_lo;
        let d_d = de + sfm.lambda * 4.0 * ulp(v_max);
        let d_b = sfm.gamma * d_d;
        let dm = m * (delta / b_lo + d_hi * d_b / (b_lo * b_lo));
        let dt_dir = 2.0 * d_d / (1.0 - spread);
        let dc = de + dt_dir + 4.0 * U;
        let dk = 2.0 * a_max * a_max * slope * dc + 2.0 * a_max * theta_max.powi(2) * n_max * d_b;
        error += 2.0 * dm + m * (2.0 * dk + dt_dir + de);
        magnitude += 2.0 * m;
        terms += 1.0;
    }
    error += terms * ulp(magnitude) / 2.0;
    k.dt * error / 3f64.sqrt()
}

/// How far the replay may widen the comparison of one body's velocity-derived values.
#[derive(Clone, Copy, Debug, Default)]
pub struct Widen {
    /// Bound (m/s) on the vector difference of its velocity: on its speed, and, times dt, on
    /// its position.
    pub velocity: f64,
    /// Bound (rad) on the difference of its heading, where the heading follows the velocity.
    pub heading: f64,
}

impl Widen {
    fn of(speed: f64, velocity: f64) -> Self {
        Self {
            velocity,
            heading: direction_error(speed, velocity),
        }
    }
}

/// The widening of the shadow robot and of every human of `step`'s post-motion state
/// (observation order), from its velocity's conditioning: lone walkers by their ORCA
/// ([`rvo2_velocity_error`]) or social-force ([`sfm_velocity_error`]) velocity as recorded in
/// `diag.human_vel`, moving-group members by their group's RVO2 velocity divided by the member
/// count (member velocity v_group/n + noise), the shadow robot by its RVO2 velocity. Humans
/// pushed out of an object this step (`diag.contacts`) take speed and heading from the contact
/// force instead ([`contact_push_error`]), and standing humans do not move: none.
pub fn widening(
    header: &Value,
    prev: &Value,
    step: &Step<'_>,
    k: &Kinematics,
) -> (Widen, Vec<Widen>) {
    let post = step.state_after_motion();
    let diag = &step.v["diag"];
    let x = extent(header, &[prev, post], k.human_radius);
    let distance = |p: &Value, g: &Value| (num(&g[0]) - num(&p[0])).hypot(num(&g[1]) - num(&p[1]));
    let pose = |v: &Value| serde_json::json!([v["x"], v["y"]]);
    let shadow_v = &diag["shadow_orca_vel"];
    let shadow = if shadow_v.is_array() {
        let goal = distance(&pose(&prev["shadow_robot"]), &prev["robot"]["goal"]);
        let e = rvo2_velocity_errors(
            x,
            &problems(header, prev, step, Who::Shadow),
            k.robot_max_speed,
            goal,
        );
        Widen::of(num(&shadow_v[0]).hypot(num(&shadow_v[1])), e)
    } else {
        Widen::default()
    };
    let pushed: Vec<&Value> = diag["contacts"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|c| &c[0])
        .collect();
    let before = |id: &Value| {
        prev["humans"]
            .as_array()
            .and_then(|hs| hs.iter().find(|h| h["id"] == *id))
    };
    let groups = prev["groups"].as_array().map_or(&[][..], |g| &g[..]);
    // The widening of a human's own motion (before any contact push).
    let motion = |h: &Value| {
        if h["role"] == "dynamic" {
            let v = &diag["human_vel"][h["id"].to_string()];
            let Some(b) = before(&h["id"]).filter(|_| v.is_array()) else {
                return Widen::default();
            };
            let e = if v[0] == "sfm" {
                sfm_velocity_error(header, prev, b, k, x)
            } else {
                let goal = distance(&pose(b), &b["goal"]);
                let rvo2 = problems(header, prev, step, Who::Walker(b));
                rvo2_velocity_errors(x, &rvo2, k.human_max_speed, goal)
            };
            return Widen::of(num(&v[1]).hypot(num(&v[2])), e);
        }
        if h["role"] != "moving_group" {
            return Widen::default();
        }
        let Some((index, g)) = h["group"]
            .as_u64()
            .and_then(|g| Some((g as usize, groups.get(g as usize)?)))
        else {
            return Widen::default();
        };
        let rvo2 = problems(header, prev, step, Who::Group(index));
        let e = rvo2_velocity_errors(
            x,
            &rvo2,
            k.human_max_speed,
            distance(&g["centre"], &g["goal"]),
        );
        let n = g["members"].as_array().map_or(1, Vec::len) as f64;
        Widen::of(num(&h["speed"]), e / n)
    };
    let humans = post["humans"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|h| {
            let motion = motion(h);
            let pushes = pushed.iter().filter(|&&id| *id == h["id"]).count();
            if pushes == 0 {
                return motion;
            }
            // The position error at the push: the relative position to the object as in
            // `rvo2_velocity_error` (2√2 ulp of the extent) plus the motion's own error.
            let at_push = 2.0 * SQRT_2 * ulp(x) + motion.velocity * k.dt;
            contact_push_error(num(&h["speed"]), pushes, at_push, k)
        })
        .collect();
    (shadow, humans)
}

/// Contact push-out (docs/spec.md 4.6, MPE's soft contact): stiffness and margin (m).
const CONTACT_STIFFNESS: f64 = 100.0;
const CONTACT_MARGIN: f64 = 1e-3;

/// The widening of a human pushed `pushes` times out of objects this step, ending at `speed`
/// (m/s), whose position before the first push is known to `at_push` (m).
///
/// One push: speed = min(K·k·softplus(−(dist − R)/k)·dt, max speed), K = 100, k = 1e-3, dist the
/// distance to the object's centre (or, for a wall, to the human's mirror image: twice the gap,
/// so dist moves by up to twice the position), heading the direction of the separation, and the
/// human moves by speed·dt along it. d speed/d dist = K·dt·σ(−(dist − R)/k), up to K·dt
/// = 100 m/s per metre: the push amplifies the position error δp a hundredfold, to
/// δs = K·dt·σ·2δp, unless the speed is capped (then the derivative is 0; it is kept at its
/// bound where the recorded speed is the cap, socnav's may be just below it). The recorded
/// (last) push gives σ itself: softplus(x) = speed/(K·k·dt), σ(x) = 1 − exp(−softplus(x));
/// earlier pushes (not recorded) take σ ≤ 1 and speed ≤ max speed. The heading moves by the
/// separation's direction error, ≤ 2δp/dist with dist ≥ the human radius for a contact within
/// the margin (centre-to-centre distance of a touching disc or rectangle, or twice the gap
/// across a wall, whose direction is the wall's normal and does not move at all). After the
/// push the position error is δp + (δs + speed·δθ)·dt; the next push starts from there.
/// Returned: velocity = the final position error over dt (it covers the speed's δs and, times
/// dt, the position), heading = the last push's δθ.
pub fn contact_push_error(speed: f64, pushes: usize, at_push: f64, k: &Kinematics) -> Widen {
    let unit = CONTACT_STIFFNESS * CONTACT_MARGIN * k.dt;
    let mut position = at_push;
    let mut heading = 0.0;
    for push in 1..=pushes {
        let last = push == pushes;
        let (sigma, v) = if last && speed < k.human_max_speed {
            (1.0 - (-speed / unit).exp(), speed)
        } else {
            (1.0, k.human_max_speed)
        };
        let ds = CONTACT_STIFFNESS * k.dt * sigma * 2.0 * position;
        heading = direction_error(k.human_radius, 2.0 * position);
        position += (ds + v * heading) * k.dt;
    }
    Widen {
        velocity: position / k.dt,
        heading,
    }
}

/// Bound (m) on the error of socnav's f32 change of the robot's goal distance,
/// d_t − d_{t−1}, against 0.1.1's f64 one (FAILURE_TO_PROGRESS counts d_t > d_{t−1}).
///
/// socnav evaluates d = √(dx² + dy²), dx = goal − robot, for the loaded pose (its previous
/// distance, recomputed on load) and for the moved one. Per evaluation: the robot's and the
/// goal's coordinates are rounded to f32 (half an ulp each, and |∂d/∂coordinate| ≤ 1); dx, dy
/// are rounded (half an ulp each); the squares, the sum and the root add a relative 2u,
/// < 2 ulp(d). The move adds the rounding of the new coordinates (half an ulp each) and the
/// f32 error of v·cos θ·dt: 4u of the displacement, plus the displacement times the f32
/// rounding of θ (≤ ulp(π)). A previous distance taken from the document unchanged carries its
/// own rounding (half an ulp). None of this is assumed to cancel between the two evaluations.
pub fn goal_distance_change_error(before: (f64, f64), after: (f64, f64), goal: (f64, f64)) -> f64 {
    let evaluation = |(x, y): (f64, f64)| {
        let (dx, dy) = (goal.0 - x, goal.1 - y);
        (ulp(x) + ulp(goal.0) + ulp(y) + ulp(goal.1)) / 2.0
            + (ulp(dx) + ulp(dy)) / 2.0
            + 2.0 * ulp(dx.hypot(dy))
    };
    let displacement = (after.0 - before.0).hypot(after.1 - before.1);
    let d_before = (goal.0 - before.0).hypot(goal.1 - before.1);
    evaluation(before)
        + evaluation(after)
        + (ulp(after.0) + ulp(after.1)) / 2.0
        + displacement * (4.0 * U + ulp(PI))
        + ulp(d_before) / 2.0
}
