//! RVO2's linear programs (docs/spec.md orca-sfm 1.6), expression for expression.
//!
//! * [`lp1`]: optimise along one line inside the speed disc, subject to the earlier lines.
//! * [`lp2`]: incremental 2-D LP over all lines (deterministic order, no shuffling). Returns the
//!   index of the first line it could not satisfy (`lines.len()` on success).
//! * [`lp3`]: when LP2 fails, minimise the largest violation of the agent lines while keeping the
//!   obstacle lines hard. Uses a caller-provided projection buffer instead of allocating.

use super::lines::Line;
use super::obstacles::RVO_EPSILON;
use super::vector::{Vec2, det};

/// Solves along line `line_no` within the disc of radius `radius` (m/s), subject to lines
/// `0..line_no`. Returns `None` when infeasible (RVO2 returns `false`).
///
/// With `direction_opt`, `opt` is a unit direction and the extreme point along it is taken;
/// otherwise the point closest to `opt`.
#[must_use]
pub fn lp1(
    lines: &[Line],
    line_no: usize,
    radius: f32,
    opt: Vec2,
    direction_opt: bool,
) -> Option<Vec2> {
    let line = lines[line_no];
    let dot = line.point.dot(line.direction);
    let discriminant = dot * dot + radius * radius - line.point.abs_sq();
    if discriminant < 0.0 {
        // The speed disc fully invalidates line `line_no`.
        return None;
    }
    let sqrt_disc = discriminant.sqrt();
    let mut t_left = -dot - sqrt_disc;
    let mut t_right = -dot + sqrt_disc;

    for other in &lines[..line_no] {
        let denominator = det(line.direction, other.direction);
        let numerator = det(other.direction, line.point - other.point);
        if denominator.abs() <= RVO_EPSILON {
            // (Almost) parallel lines.
            if numerator < 0.0 {
                return None;
            }
            continue;
        }
        let t = numerator / denominator;
        // `std::min`/`std::max` semantics (`b < a ? b : a`, `a < b ? b : a`), written out so
        // signed zeros and NaN behave as in RVO2 (`f32::min`/`max` treat them differently).
        if denominator >= 0.0 {
            if t < t_right {
                t_right = t;
            }
        } else if t_left < t {
            t_left = t;
        }
        if t_left > t_right {
            return None;
        }
    }

    let t = if direction_opt {
        if opt.dot(line.direction) > 0.0 {
            t_right
        } else {
            t_left
        }
    } else {
        let t = line.direction.dot(opt - line.point);
        if t < t_left {
            t_left
        } else if t > t_right {
            t_right
        } else {
            t
        }
    };
    Some(line.point + t * line.direction)
}

/// Incremental LP over `lines` within the disc of radius `radius` (m/s).
///
/// Returns `(fail, result)`: `fail == lines.len()` on success; otherwise the first line whose
/// LP1 failed, with `result` the partial solution from before that line.
#[must_use]
pub fn lp2(lines: &[Line], radius: f32, opt: Vec2, direction_opt: bool) -> (usize, Vec2) {
    let mut result = if direction_opt {
        // opt is a unit vector here.
        opt * radius
    } else if opt.abs_sq() > radius * radius {
        opt.normalize() * radius
    } else {
        opt
    };
    for i in 0..lines.len() {
        if det(lines[i].direction, lines[i].point - result) > 0.0 {
            // `result` violates line i: re-optimise on it.
            match lp1(lines, i, radius, opt, direction_opt) {
                Some(r) => result = r,
                None => return (i, result),
            }
        }
    }
    (lines.len(), result)
}

/// RVO2's `linearProgram3`: starting from LP2's partial `result` and its failure index
/// `begin_line`, minimises the maximum violation of lines `num_obst_lines..`, keeping lines
/// `..num_obst_lines` hard. `proj` is working memory (cleared and refilled, capacity kept).
#[must_use]
pub fn lp3(
    lines: &[Line],
    num_obst_lines: usize,
    begin_line: usize,
    radius: f32,
    mut result: Vec2,
    proj: &mut Vec<Line>,
) -> Vec2 {
    let mut distance = 0.0_f32;
    for i in begin_line..lines.len() {
        let li = lines[i];
        if det(li.direction, li.point - result) > distance {
            // `result` violates line i by more than the current maximum.
            proj.clear();
            proj.extend_from_slice(&lines[..num_obst_lines]);
            // RVO2 loops j from numObstLines to i: empty when LP2 failed on an obstacle line
            // (an agent inside overlapping obstacles), so i may be below num_obst_lines.
            for lj in &lines[num_obst_lines.min(i)..i] {
                let determinant = det(li.direction, lj.direction);
                let point = if determinant.abs() <= RVO_EPSILON {
                    // Parallel lines.
                    if li.direction.dot(lj.direction) > 0.0 {
                        // Same direction: nothing to add.
                        continue;
                    }
                    // Opposite directions: the mid-line.
                    0.5 * (li.point + lj.point)
                } else {
                    li.point + (det(lj.direction, li.point - lj.point) / determinant) * li.direction
                };
                proj.push(Line {
                    point,
                    direction: (lj.direction - li.direction).normalize(),
                });
            }
            let opt = Vec2::new(-li.direction.y, li.direction.x);
            let (fail, r) = lp2(proj, radius, opt, true);
            // A failure here is float round-off only: RVO2 keeps the previous result.
            if fail >= proj.len() {
                result = r;
            }
            distance = det(li.direction, li.point - result);
        }
    }
    result
}
