//! Neighbour selection (docs/spec.md orca-sfm 1.3): which agents and obstacle edges an agent reacts
//! to, and in which order. The order sets the order of the ORCA lines, and so the float result.
//!
//! * Agents: the `<= max_neighbors` nearest others with squared centre distance strictly below
//!   `neighbor_dist²`, sorted ascending by RVO2's insertion rule (a new entry moves before
//!   strictly larger keys only, so ties keep visiting order; once the list is full the range
//!   shrinks to the last key and a candidate tied with it is rejected). [`agent_neighbors`]
//!   visits candidates in index order, which is RVO2's order whenever there are no exact ties or
//!   N <= 10; [`crate::orca::AgentKdTree`] reproduces RVO2's tree order exactly.
//! * Obstacles: every edge with the agent strictly on its right (`left_of < 0`) within
//!   `(time_horizon_obst * max_speed + radius)²` (line and segment distance), sorted ascending
//!   with the same insertion rule, no length limit. [`obstacle_neighbors`] visits edges in
//!   vertex order (GPU-friendly brute force); [`obstacle_neighbors_tree`] walks RVO2's static tree
//!   and so also reproduces its order for exactly tied distances (e.g. two edges that meet at the
//!   nearest corner).

use super::obstacles::{NONE, ObstacleTree, ObstacleVerts};
use super::vector::{Vec2, dist_sq_point_segment, left_of};

/// Margin factor of the bounding-box prefilter of obstacle edges (`1.0 + 1e-3`, folded in f32):
/// a squared box distance above `range_sq` times this rejects the edge. It keeps f32 rounding of
/// the box distance from rejecting an edge the exact test would accept.
pub const OBSTACLE_REJECT_FACTOR: f32 = 1.0 + 1e-3;

/// One selected neighbour: the sort key and the index of the agent (or the start vertex of
/// the obstacle edge).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbor {
    /// Squared distance (m²): centre to centre for agents, agent centre to segment for edges.
    pub dist_sq: f32,
    /// Agent index, or the start vertex of the obstacle edge.
    pub index: u32,
}

/// RVO2's `insertAgentNeighbor` for one candidate that is not the agent itself.
///
/// `list` holds at most `max_neighbors` entries sorted ascending; `range_sq` (m²) is the current
/// search range and shrinks to the last key once the list is full. Does nothing if
/// `max_neighbors == 0`. Never grows `list` past `max_neighbors`.
#[inline]
pub fn insert_agent_neighbor(
    list: &mut Vec<Neighbor>,
    max_neighbors: usize,
    candidate: Neighbor,
    range_sq: &mut f32,
) {
    let in_range = candidate.dist_sq < *range_sq;
    if max_neighbors == 0 || !in_range {
        return;
    }
    if list.len() < max_neighbors {
        list.push(candidate);
    }
    let mut i = list.len() - 1;
    while i != 0 && candidate.dist_sq < list[i - 1].dist_sq {
        list[i] = list[i - 1];
        i -= 1;
    }
    list[i] = candidate;
    if list.len() == max_neighbors {
        *range_sq = list[list.len() - 1].dist_sq;
    }
}

/// RVO2's `insertObstacleNeighbor`: inserts edge `vertex -> next(vertex)` if its segment
/// distance² to `pos` is below `range_sq` (m²), keeping `list` sorted ascending (stable).
#[inline]
pub fn insert_obstacle_neighbor(
    list: &mut Vec<Neighbor>,
    obstacles: &ObstacleVerts<'_>,
    vertex: usize,
    pos: Vec2,
    range_sq: f32,
) {
    let a = obstacles.point(vertex);
    let b = obstacles.point(obstacles.next(vertex));
    let dist_sq = dist_sq_point_segment(a, b, pos);
    if dist_sq < range_sq {
        let candidate = Neighbor {
            dist_sq,
            index: vertex as u32,
        };
        list.push(candidate);
        let mut i = list.len() - 1;
        while i != 0 && dist_sq < list[i - 1].dist_sq {
            list[i] = list[i - 1];
            i -= 1;
        }
        list[i] = candidate;
    }
}

/// Selects agent `self_index`'s agent neighbours by brute force over all agents in index order.
///
/// `pos_x`/`pos_y` are the positions (m) of all agents; `neighbor_dist` (m) and
/// `max_neighbors` are the agent's parameters. `out` is cleared and receives the neighbours,
/// nearest first. Equals RVO2 unless two candidates tie exactly with N > 10 (then RVO2 breaks the
/// tie by its k-d tree order; see [`crate::orca::AgentKdTree`]). No allocation once `out` has
/// capacity `max_neighbors`.
pub fn agent_neighbors(
    self_index: usize,
    pos_x: &[f32],
    pos_y: &[f32],
    neighbor_dist: f32,
    max_neighbors: u32,
    out: &mut Vec<Neighbor>,
) {
    out.clear();
    if max_neighbors == 0 {
        return;
    }
    let pos = Vec2::new(pos_x[self_index], pos_y[self_index]);
    let mut range_sq = neighbor_dist * neighbor_dist;
    for (j, (&x, &y)) in pos_x.iter().zip(pos_y).enumerate() {
        if j == self_index {
            continue;
        }
        let candidate = Neighbor {
            dist_sq: (pos - Vec2::new(x, y)).abs_sq(),
            index: j as u32,
        };
        insert_agent_neighbor(out, max_neighbors as usize, candidate, &mut range_sq);
    }
}

/// Distance (m) from `p` to the interval between `a` and `b` on one axis (0 inside). Branch-free
/// comparisons (`maxss`/`minss`): `f32::min`/`max` add NaN fix-ups, and branches on the side of `p`
/// mispredict in this hot loop.
#[inline]
fn gap(p: f32, a: f32, b: f32) -> f32 {
    let lo = if a < b { a } else { b };
    let hi = if a > b { a } else { b };
    let below = lo - p;
    let above = p - hi;
    let d = if below > above { below } else { above };
    if d > 0.0 { d } else { 0.0 }
}

/// The obstacle search range RVO2 uses: `(time_horizon_obst * max_speed + radius)²` (m²).
#[inline]
#[must_use]
pub fn obstacle_range_sq(time_horizon_obst: f32, max_speed: f32, radius: f32) -> f32 {
    let range = time_horizon_obst * max_speed + radius;
    range * range
}

/// Selects the obstacle edges an agent at `pos` (m) reacts to, by brute force over all
/// processed vertices in index order; `range_sq` from [`obstacle_range_sq`].
///
/// `out` is cleared and receives the edges' start vertices, nearest first; exact ties keep
/// vertex order. An edge counts if the agent is strictly on its right, and both the line
/// distance² (`left_of² / |edge|²`, RVO2's tree pruning test) and the segment distance² are
/// below `range_sq`. This equals RVO2's tree query except for the order of exactly tied
/// distances; use [`obstacle_neighbors_tree`] where that matters.
pub fn obstacle_neighbors(
    pos: [f32; 2],
    range_sq: f32,
    obstacles: &ObstacleVerts<'_>,
    out: &mut Vec<Neighbor>,
) {
    out.clear();
    let pos = Vec2::from_array(pos);
    // Edges whose bounding box is out of range cannot be within range: the box contains the
    // segment. The margin keeps f32 rounding of the box distance from rejecting an edge the exact
    // test below would accept, so the prefilter changes no result, only skips work.
    let reject_sq = range_sq * OBSTACLE_REJECT_FACTOR;
    for v in 0..obstacles.len() {
        let a = obstacles.point(v);
        let b = obstacles.point(obstacles.next(v));
        let dx = gap(pos.x, a.x, b.x);
        if dx * dx > reject_sq {
            continue;
        }
        let dy = gap(pos.y, a.y, b.y);
        if dx * dx + dy * dy > reject_sq {
            continue;
        }
        let s = left_of(a, b, pos);
        if s < 0.0 && s * s / (b - a).abs_sq() < range_sq {
            insert_obstacle_neighbor(out, obstacles, v, pos, range_sq);
        }
    }
}

/// Selects the obstacle edges an agent at `pos` (m) reacts to by walking RVO2's static k-d tree
/// (`queryObstacleTreeRecursive`), so the order equals RVO2's also for exactly tied distances.
///
/// `out` is cleared and receives the edges' start vertices, nearest first. Recursion depth is
/// the tree depth.
pub fn obstacle_neighbors_tree(
    pos: [f32; 2],
    range_sq: f32,
    obstacles: &ObstacleVerts<'_>,
    tree: &ObstacleTree<'_>,
    out: &mut Vec<Neighbor>,
) {
    out.clear();
    if !tree.vertex.is_empty() {
        query_node(Vec2::from_array(pos), range_sq, obstacles, tree, 0, out);
    }
}

fn query_node(
    pos: Vec2,
    range_sq: f32,
    obstacles: &ObstacleVerts<'_>,
    tree: &ObstacleTree<'_>,
    node: u32,
    out: &mut Vec<Neighbor>,
) {
    if node == NONE {
        return;
    }
    let n = node as usize;
    let v = tree.vertex[n] as usize;
    let a = obstacles.point(v);
    let b = obstacles.point(obstacles.next(v));
    let s = left_of(a, b, pos);
    let (near, far) = if s >= 0.0 {
        (tree.left[n], tree.right[n])
    } else {
        (tree.right[n], tree.left[n])
    };
    query_node(pos, range_sq, obstacles, tree, near, out);
    let dist_sq_line = s * s / (b - a).abs_sq();
    if dist_sq_line < range_sq {
        if s < 0.0 {
            insert_obstacle_neighbor(out, obstacles, v, pos, range_sq);
        }
        query_node(pos, range_sq, obstacles, tree, far, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn insertion_keeps_nearest_and_rejects_ties_when_full() {
        let mut list = Vec::new();
        let mut range_sq = 100.0;
        for (i, d) in [5.0, 3.0, 4.0, 3.0, 1.0].into_iter().enumerate() {
            let c = Neighbor {
                dist_sq: d,
                index: i as u32,
            };
            insert_agent_neighbor(&mut list, 3, c, &mut range_sq);
        }
        let idx: Vec<u32> = list.iter().map(|n| n.index).collect();
        // 3.0 (index 1) then 3.0 (index 3): equal keys keep visiting order.
        assert_eq!(idx, vec![4, 1, 3]);
        assert_eq!(range_sq, 3.0);
        insert_agent_neighbor(
            &mut list,
            3,
            Neighbor {
                dist_sq: 3.0,
                index: 9,
            },
            &mut range_sq,
        );
        assert_eq!(list.len(), 3);
        assert!(list.iter().all(|n| n.index != 9));
    }

    #[test]
    fn brute_force_agent_neighbors_strict_range() {
        let px = [0.0, 1.0, 2.0, 0.0];
        let py = [0.0, 0.0, 0.0, 1.5];
        let mut out = Vec::new();
        agent_neighbors(0, &px, &py, 2.0, 10, &mut out);
        let idx: Vec<u32> = out.iter().map(|n| n.index).collect();
        // Agent 2 is at distance² 4 = range²: excluded (strict).
        assert_eq!(idx, vec![1, 3]);
    }
}
