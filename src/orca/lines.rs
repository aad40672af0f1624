//! ORCA half-planes in velocity space (docs/spec.md orca-sfm 1.4 and 1.5): obstacle lines first (in
//! obstacle-neighbour order), then one line per agent neighbour (in neighbour order).
//!
//! A line is a point `p` and a unit direction `d` (m/s); the permitted side is
//! `{ v : det(d, p - v) <= 0 }`, to the left of `d`. The code follows RVO2's `Agent.cc`
//! expression by expression (see the float rules in the module docs of [`crate::orca`]).

use super::obstacles::{ObstacleVerts, RVO_EPSILON};
use super::vector::{Vec2, det};
use super::{Neighbor, OrcaAgent, OrcaNeighbor};

/// One ORCA constraint: velocities left of `direction` through `point` are permitted (m/s).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Line {
    /// A point on the line (m/s).
    pub point: Vec2,
    /// Unit direction; the permitted half-plane is on its left.
    pub direction: Vec2,
}

/// Direction of the left leg of the cone from the origin tangent to a disc of radius `r` at
/// `rel` (`q = |rel|²`, `leg = sqrt(q - r²)`), as RVO2 writes it.
#[inline]
fn left_leg(rel: Vec2, leg: f32, r: f32, q: f32) -> Vec2 {
    Vec2::new(rel.x * leg - rel.y * r, rel.x * r + rel.y * leg).div_scalar(q)
}

/// Direction of the right leg (see [`left_leg`]).
#[inline]
fn right_leg(rel: Vec2, leg: f32, r: f32, q: f32) -> Vec2 {
    Vec2::new(rel.x * leg + rel.y * r, -rel.x * r + rel.y * leg).div_scalar(q)
}

/// Appends the obstacle ORCA lines of `agent` for the edges `neighbors` (start vertices, nearest
/// first) to `lines`, which must hold no agent lines yet (the "already covered" test reads every
/// line in it).
pub fn push_obstacle_lines(
    agent: &OrcaAgent,
    obstacles: &ObstacleVerts<'_>,
    neighbors: &[Neighbor],
    lines: &mut Vec<Line>,
) {
    let inv_to = 1.0 / agent.time_horizon_obst;
    let pos = Vec2::from_array(agent.pos);
    let vel = Vec2::from_array(agent.vel);
    let r = agent.radius;
    for nb in neighbors {
        let o1 = nb.index as usize;
        let o2 = obstacles.next(o1);
        let rel1 = obstacles.point(o1) - pos;
        let rel2 = obstacles.point(o2) - pos;
        if already_covered(lines, inv_to, rel1, rel2, r) {
            continue;
        }
        if let Some(line) = obstacle_line(obstacles, o1, o2, rel1, rel2, pos, vel, r, inv_to) {
            lines.push(line);
        }
    }
}

/// RVO2's check whether earlier lines already cover the velocity obstacle of this edge.
#[inline]
fn already_covered(lines: &[Line], inv_to: f32, rel1: Vec2, rel2: Vec2, r: f32) -> bool {
    lines.iter().any(|l| {
        det(inv_to * rel1 - l.point, l.direction) - inv_to * r >= -RVO_EPSILON
            && det(inv_to * rel2 - l.point, l.direction) - inv_to * r >= -RVO_EPSILON
    })
}

/// The line for one obstacle edge `o1 -> o2`, or `None` when RVO2 adds none for it.
#[expect(
    clippy::too_many_arguments,
    reason = "mirrors the local variables of RVO2's loop body; bundling them hides the data flow"
)]
fn obstacle_line(
    obst: &ObstacleVerts<'_>,
    mut o1: usize,
    mut o2: usize,
    rel1: Vec2,
    rel2: Vec2,
    pos: Vec2,
    vel: Vec2,
    r: f32,
    inv_to: f32,
) -> Option<Line> {
    let dist_sq1 = rel1.abs_sq();
    let dist_sq2 = rel2.abs_sq();
    let radius_sq = r * r;
    let obstacle_vector = obst.point(o2) - obst.point(o1);
    let s = (-rel1).dot(obstacle_vector) / obstacle_vector.abs_sq();
    let dist_sq_line = (-rel1 - s * obstacle_vector).abs_sq();

    // Current collision with the left vertex, the right vertex or the segment.
    if s < 0.0 && dist_sq1 <= radius_sq {
        return obst.is_convex(o1).then(|| Line {
            point: Vec2::ZERO,
            direction: rel1.perp_l().normalize(),
        });
    }
    if s > 1.0 && dist_sq2 <= radius_sq {
        let add = obst.is_convex(o2) && det(rel2, obst.dir(o2)) >= 0.0;
        return add.then(|| Line {
            point: Vec2::ZERO,
            direction: rel2.perp_l().normalize(),
        });
    }
    if (0.0..=1.0).contains(&s) && dist_sq_line <= radius_sq {
        return Some(Line {
            point: Vec2::ZERO,
            direction: -obst.dir(o1),
        });
    }

    // No collision: legs. Seen obliquely, a single vertex defines both legs.
    let (mut left_dir, mut right_dir);
    if s < 0.0 && dist_sq_line <= radius_sq {
        if !obst.is_convex(o1) {
            return None;
        }
        o2 = o1;
        let leg1 = (dist_sq1 - radius_sq).sqrt();
        left_dir = left_leg(rel1, leg1, r, dist_sq1);
        right_dir = right_leg(rel1, leg1, r, dist_sq1);
    } else if s > 1.0 && dist_sq_line <= radius_sq {
        if !obst.is_convex(o2) {
            return None;
        }
        o1 = o2;
        let leg2 = (dist_sq2 - radius_sq).sqrt();
        left_dir = left_leg(rel2, leg2, r, dist_sq2);
        right_dir = right_leg(rel2, leg2, r, dist_sq2);
    } else {
        left_dir = if obst.is_convex(o1) {
            let leg1 = (dist_sq1 - radius_sq).sqrt();
            left_leg(rel1, leg1, r, dist_sq1)
        } else {
            -obst.dir(o1)
        };
        right_dir = if obst.is_convex(o2) {
            let leg2 = (dist_sq2 - radius_sq).sqrt();
            right_leg(rel2, leg2, r, dist_sq2)
        } else {
            obst.dir(o1)
        };
    }

    // Legs that point into the neighbouring edge become "foreign".
    let left_neighbor = obst.prev(o1);
    let mut left_foreign = false;
    let mut right_foreign = false;
    if obst.is_convex(o1) && det(left_dir, -obst.dir(left_neighbor)) >= 0.0 {
        left_dir = -obst.dir(left_neighbor);
        left_foreign = true;
    }
    if obst.is_convex(o2) && det(right_dir, obst.dir(o2)) <= 0.0 {
        right_dir = obst.dir(o2);
        right_foreign = true;
    }

    // Project the current velocity on the truncated velocity obstacle.
    let left_cutoff = inv_to * (obst.point(o1) - pos);
    let right_cutoff = inv_to * (obst.point(o2) - pos);
    let cutoff_vec = right_cutoff - left_cutoff;
    let same = o1 == o2;
    let t = if same {
        0.5
    } else {
        (vel - left_cutoff).dot(cutoff_vec) / cutoff_vec.abs_sq()
    };
    let t_left = (vel - left_cutoff).dot(left_dir);
    let t_right = (vel - right_cutoff).dot(right_dir);
    let r_inv_to = r * inv_to;

    if (t < 0.0 && t_left < 0.0) || (same && t_left < 0.0 && t_right < 0.0) {
        let unit_w = (vel - left_cutoff).normalize();
        return Some(Line {
            direction: Vec2::new(unit_w.y, -unit_w.x),
            point: left_cutoff + r_inv_to * unit_w,
        });
    }
    if t > 1.0 && t_right < 0.0 {
        let unit_w = (vel - right_cutoff).normalize();
        return Some(Line {
            direction: Vec2::new(unit_w.y, -unit_w.x),
            point: right_cutoff + r_inv_to * unit_w,
        });
    }

    #[expect(
        clippy::manual_range_contains,
        reason = "RVO2's `t < 0 || t > 1` is false for NaN; `!contains` would be true"
    )]
    let dist_sq_cutoff = if t < 0.0 || t > 1.0 || same {
        f32::INFINITY
    } else {
        (vel - (left_cutoff + t * cutoff_vec)).abs_sq()
    };
    let dist_sq_left = if t_left < 0.0 {
        f32::INFINITY
    } else {
        (vel - (left_cutoff + t_left * left_dir)).abs_sq()
    };
    let dist_sq_right = if t_right < 0.0 {
        f32::INFINITY
    } else {
        (vel - (right_cutoff + t_right * right_dir)).abs_sq()
    };

    if dist_sq_cutoff <= dist_sq_left && dist_sq_cutoff <= dist_sq_right {
        let direction = -obst.dir(o1);
        return Some(Line {
            direction,
            point: left_cutoff + r_inv_to * direction.perp_l(),
        });
    }
    if dist_sq_left <= dist_sq_right {
        if left_foreign {
            return None;
        }
        return Some(Line {
            direction: left_dir,
            point: left_cutoff + r_inv_to * left_dir.perp_l(),
        });
    }
    if right_foreign {
        return None;
    }
    let direction = -right_dir;
    Some(Line {
        direction,
        point: right_cutoff + r_inv_to * direction.perp_l(),
    })
}

/// Appends one ORCA line per agent neighbour (in the given order) to `lines`.
///
/// `time_step` (s) sets the cut-off used when two agents already overlap.
pub fn push_agent_lines(
    agent: &OrcaAgent,
    neighbors: &[OrcaNeighbor],
    time_step: f32,
    lines: &mut Vec<Line>,
) {
    let inv_t = 1.0 / agent.time_horizon;
    let pos = Vec2::from_array(agent.pos);
    let vel = Vec2::from_array(agent.vel);
    for other in neighbors {
        lines.push(agent_line(pos, vel, agent.radius, other, inv_t, time_step));
    }
}

/// RVO2's reciprocal ORCA line of an agent against one neighbour.
#[inline]
fn agent_line(
    pos: Vec2,
    vel: Vec2,
    radius: f32,
    other: &OrcaNeighbor,
    inv_t: f32,
    time_step: f32,
) -> Line {
    let rel_pos = Vec2::from_array(other.pos) - pos;
    let rel_vel = vel - Vec2::from_array(other.vel);
    let dist_sq = rel_pos.abs_sq();
    let combined_radius = radius + other.radius;
    let combined_radius_sq = combined_radius * combined_radius;

    let (direction, u);
    if dist_sq > combined_radius_sq {
        // No collision. w: from the cut-off centre to the relative velocity.
        let w = rel_vel - inv_t * rel_pos;
        let w_length_sq = w.abs_sq();
        let dot1 = w.dot(rel_pos);
        if dot1 < 0.0 && dot1 * dot1 > combined_radius_sq * w_length_sq {
            // Project on the cut-off circle.
            let w_length = w_length_sq.sqrt();
            let unit_w = w.div_scalar(w_length);
            direction = Vec2::new(unit_w.y, -unit_w.x);
            u = (combined_radius * inv_t - w_length) * unit_w;
        } else {
            // Project on a leg; det == 0 (symmetric set-ups) takes the right leg.
            let leg = (dist_sq - combined_radius_sq).sqrt();
            direction = if det(rel_pos, w) > 0.0 {
                left_leg(rel_pos, leg, combined_radius, dist_sq)
            } else {
                -right_leg(rel_pos, leg, combined_radius, dist_sq)
            };
            let dot2 = rel_vel.dot(direction);
            u = dot2 * direction - rel_vel;
        }
    } else {
        // Collision: project on the cut-off circle of time `time_step`.
        let inv_time_step = 1.0 / time_step;
        let w = rel_vel - inv_time_step * rel_pos;
        let w_length = w.abs();
        let unit_w = w.div_scalar(w_length);
        direction = Vec2::new(unit_w.y, -unit_w.x);
        u = (combined_radius * inv_time_step - w_length) * unit_w;
    }
    Line {
        point: vel + 0.5 * u,
        direction,
    }
}
