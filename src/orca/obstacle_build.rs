//! RVO2's `addObstacle` + `processObstacles` (docs/spec.md orca-sfm 1.3): polygons in, processed
//! vertices and the static obstacle k-d tree out.
//!
//! Each tree node picks the edge that minimises `(max(L, R), min(L, R))` over the edges of its
//! list (first best wins, with RVO2's early exit), classifying edge j as left if both end points
//! have `left_of >= -RVO_EPSILON`, right if both are `<= RVO_EPSILON`, else both. A straddling
//! edge is split at `t = det(Bi-Ai, Aj-Ai) / det(Bi-Ai, Aj-Bj)`; the new vertex gets the next id,
//! copies the direction of Aj, is convex and is linked between Aj and Bj. The left subtree is
//! built completely before the right one, so split vertices get RVO2's ids.

use super::error::OrcaError;
use super::obstacles::{NONE, ObstacleScratch, ObstacleSet, RVO_EPSILON};
use super::vector::{Vec2, det, left_of};

/// Validates `polygons`, links their vertices and builds the obstacle tree into `out`, exactly as
/// RVO2's `addObstacle` (once per polygon, in order) followed by `processObstacles`.
///
/// Each polygon is a list of `[x, y]` vertices in metres, counter-clockwise; 2 vertices make a
/// segment that blocks from both sides. On error `out` is left empty.
///
/// Like RVO2, it takes a zero-length edge (a repeated vertex) or one whose squared length
/// over- or underflows `f32`: the edge's unit direction is then NaN (or zero), its vertex
/// convex, and RVO2's arithmetic carries on (such an edge is never an obstacle neighbour, since
/// its distance is NaN, and a line uses its direction only where RVO2's does).
/// [`first_zero_length_edge`] finds one, for callers that build their own polygons.
///
/// # Errors
/// [`OrcaError::TooFewVertices`] for a polygon with fewer than 2 vertices, and
/// [`OrcaError::NonFiniteVertex`] for NaN/infinite coordinates: what RVO2 cannot take.
pub fn process_obstacles<P: AsRef<[[f32; 2]]>>(
    polygons: &[P],
    scratch: &mut ObstacleScratch,
    out: &mut ObstacleSet,
) -> Result<(), OrcaError> {
    out.clear();
    validate_polygons(polygons)?;
    for polygon in polygons {
        add_polygon(out, polygon.as_ref());
    }
    out.num_input_vertices = out.len();

    let ObstacleScratch { arena, ends } = scratch;
    arena.clear();
    arena.extend(0..out.len() as u32);
    let len = arena.len();
    build_node(out, arena, ends, 0, len);
    arena.clear();
    Ok(())
}

fn validate_polygons<P: AsRef<[[f32; 2]]>>(polygons: &[P]) -> Result<(), OrcaError> {
    for (polygon, verts) in polygons.iter().enumerate() {
        let verts = verts.as_ref();
        if verts.len() < 2 {
            return Err(OrcaError::TooFewVertices {
                polygon,
                count: verts.len(),
            });
        }
        for (vertex, &[x, y]) in verts.iter().enumerate() {
            if !x.is_finite() || !y.is_finite() {
                return Err(OrcaError::NonFiniteVertex {
                    polygon,
                    vertex,
                    x,
                    y,
                });
            }
        }
    }
    Ok(())
}

/// The first edge `(polygon, vertex)` (from `vertex` to the next) with no direction: zero
/// length, or a squared length that is not a positive finite `f32`. [`process_obstacles`] takes
/// such edges as RVO2 does; a caller whose polygons must have a direction on every edge (the
/// simulation's own obstacles) checks with this.
pub fn first_zero_length_edge<P: AsRef<[[f32; 2]]>>(polygons: &[P]) -> Option<(usize, usize)> {
    polygons.iter().enumerate().find_map(|(polygon, verts)| {
        let verts = verts.as_ref();
        (0..verts.len())
            .find(|&vertex| {
                let a = Vec2::from_array(verts[vertex]);
                let b = Vec2::from_array(verts[(vertex + 1) % verts.len()]);
                let len_sq = (b - a).abs_sq();
                !(len_sq > 0.0 && len_sq.is_finite())
            })
            .map(|vertex| (polygon, vertex))
    })
}

/// RVO2's `addObstacle`: appends one polygon's vertices, linked in a ring.
fn add_polygon(out: &mut ObstacleSet, verts: &[[f32; 2]]) {
    let n = verts.len();
    let first = out.len() as u32;
    for i in 0..n {
        let prev_i = if i == 0 { n - 1 } else { i - 1 };
        let next_i = if i == n - 1 { 0 } else { i + 1 };
        let p = Vec2::from_array(verts[i]);
        let p_prev = Vec2::from_array(verts[prev_i]);
        let p_next = Vec2::from_array(verts[next_i]);
        let dir = (p_next - p).normalize();
        let convex = n == 2 || left_of(p_prev, p, p_next) >= 0.0;
        out.push_vertex(p, dir, first + next_i as u32, first + prev_i as u32, convex);
    }
}

/// Which side of the splitting edge an edge lies on (RVO2's classification with `RVO_EPSILON`).
#[derive(Clone, Copy, PartialEq)]
enum Side {
    Left,
    Right,
    Both,
}

#[inline]
fn classify(s1: f32, s2: f32) -> Side {
    if s1 >= -RVO_EPSILON && s2 >= -RVO_EPSILON {
        Side::Left
    } else if s1 <= RVO_EPSILON && s2 <= RVO_EPSILON {
        Side::Right
    } else {
        Side::Both
    }
}

/// Side classification of edge `j` against the line of edge `i` (vertex ids).
#[inline]
fn edge_sides(set: &ObstacleSet, i1: u32, j1: u32) -> (f32, f32) {
    let a = set.point(i1);
    let b = set.point(set.next[i1 as usize]);
    let s1 = left_of(a, b, set.point(j1));
    let s2 = left_of(a, b, set.point(set.next[j1 as usize]));
    (s1, s2)
}

/// Chooses the splitting edge of the list `edges`: the first that minimises
/// `(max(L, R), min(L, R))`, with RVO2's early exit. Returns (position in list, L, R).
///
/// Every candidate classifies every other edge, so the edges' end points are gathered into
/// `ends` once (no vertex moves while a node chooses), and the candidate's own line is taken
/// out of the inner loop: the same `left_of` values as [`edge_sides`], read from one array.
fn choose_split(
    set: &ObstacleSet,
    edges: &[u32],
    ends: &mut Vec<[Vec2; 2]>,
) -> (usize, usize, usize) {
    ends.clear();
    ends.extend(
        edges
            .iter()
            .map(|&j1| [set.point(j1), set.point(set.next[j1 as usize])]),
    );
    let n = edges.len();
    let (mut best, mut min_left, mut min_right) = (0, n, n);
    for (i, &[a, b]) in ends.iter().enumerate() {
        let best_key = (min_left.max(min_right), min_left.min(min_right));
        let (mut left, mut right) = (0usize, 0usize);
        for (j, &[p, q]) in ends.iter().enumerate() {
            if i == j {
                continue;
            }
            match classify(left_of(a, b, p), left_of(a, b, q)) {
                Side::Left => left += 1,
                Side::Right => right += 1,
                Side::Both => {
                    left += 1;
                    right += 1;
                }
            }
            if (left.max(right), left.min(right)) >= best_key {
                break;
            }
        }
        if (left.max(right), left.min(right)) < best_key {
            (best, min_left, min_right) = (i, left, right);
        }
    }
    (best, min_left, min_right)
}

/// Builds the subtree for the edge list `arena[start..start + len]` and returns its node id.
///
/// The child lists are appended to `arena` (left list, then right list), the left subtree is
/// built completely before the right one (so split vertices get RVO2's ids), and `arena` is
/// truncated back to its length on entry before returning.
fn build_node(
    set: &mut ObstacleSet,
    arena: &mut Vec<u32>,
    ends: &mut Vec<[Vec2; 2]>,
    start: usize,
    len: usize,
) -> u32 {
    if len == 0 {
        return NONE;
    }
    let node = set.node_vertex.len();
    let (split, n_left, n_right) = choose_split(set, &arena[start..start + len], ends);
    let i1 = arena[start + split];
    set.node_vertex.push(i1);
    set.node_left.push(NONE);
    set.node_right.push(NONE);

    let left_start = arena.len();
    let right_start = left_start + n_left;
    arena.resize(right_start + n_right, NONE);
    let (mut lc, mut rc) = (0usize, 0usize);
    for j in 0..len {
        if j == split {
            continue;
        }
        let j1 = arena[start + j];
        let (s1, s2) = edge_sides(set, i1, j1);
        let (to_left, to_right) = match classify(s1, s2) {
            Side::Left => (Some(j1), None),
            Side::Right => (None, Some(j1)),
            Side::Both => {
                let new = split_edge(set, i1, j1);
                if s1 > 0.0 {
                    (Some(j1), Some(new))
                } else {
                    (Some(new), Some(j1))
                }
            }
        };
        if let Some(v) = to_left {
            arena[left_start + lc] = v;
            lc += 1;
        }
        if let Some(v) = to_right {
            arena[right_start + rc] = v;
            rc += 1;
        }
    }
    assert!(
        lc == n_left && rc == n_right,
        "obstacle tree build: split counts changed between passes"
    );

    let left = build_node(set, arena, ends, left_start, n_left);
    arena.truncate(right_start + n_right);
    let right = build_node(set, arena, ends, right_start, n_right);
    arena.truncate(left_start);
    set.node_left[node] = left;
    set.node_right[node] = right;
    node as u32
}

/// Splits edge `j1 -> next(j1)` where it crosses the line of edge `i1 -> next(i1)`; returns the
/// new vertex id. The new vertex copies `j1`'s direction and is convex.
fn split_edge(set: &mut ObstacleSet, i1: u32, j1: u32) -> u32 {
    let j2 = set.next[j1 as usize];
    let a = set.point(i1);
    let b = set.point(set.next[i1 as usize]);
    let pj1 = set.point(j1);
    let pj2 = set.point(j2);
    let t = det(b - a, pj1 - a) / det(b - a, pj1 - pj2);
    let split_point = pj1 + t * (pj2 - pj1);
    let new = set.len() as u32;
    let dir = Vec2::new(set.dir_x[j1 as usize], set.dir_y[j1 as usize]);
    set.push_vertex(split_point, dir, j2, j1, true);
    set.next[j1 as usize] = new;
    set.prev[j2 as usize] = new;
    new
}

#[cfg(test)]
mod tests {
    use super::*;

    fn build(polys: &[Vec<[f32; 2]>]) -> ObstacleSet {
        let mut set = ObstacleSet::new();
        process_obstacles(polys, &mut ObstacleScratch::new(), &mut set).unwrap();
        set
    }

    #[test]
    fn segment_gives_two_convex_opposite_edges() {
        let set = build(&[vec![[0.0, 0.0], [2.0, 0.0]]]);
        let v = set.as_view();
        assert_eq!(v.len(), 2);
        assert_eq!((v.next(0), v.prev(0), v.next(1), v.prev(1)), (1, 1, 0, 0));
        assert_eq!(v.dir(0), Vec2::new(1.0, 0.0));
        assert_eq!(v.dir(1), Vec2::new(-1.0, 0.0));
        assert!(v.is_convex(0) && v.is_convex(1));
        assert_eq!(set.num_split_vertices(), 0);
    }

    #[test]
    fn concave_vertex_is_flagged() {
        // CCW "L" shape: vertex 3 (1,1) is the reflex corner.
        let set = build(&[vec![
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, 2.0],
            [0.0, 2.0],
        ]]);
        // The reflex corner also forces a split; split vertices are convex.
        let convex: Vec<u32> = set.as_view().convex.to_vec();
        assert_eq!(convex[..6], [1, 1, 1, 0, 1, 1]);
        assert!(convex[6..].iter().all(|&c| c == 1));
    }

    #[test]
    fn straddling_edge_is_split_and_relinked() {
        // A long segment whose line cuts a square, and a square whose edges cross the
        // segment's line: whichever edge the root picks, something straddles.
        let polys = vec![
            vec![[-5.0, 0.5], [5.0, 0.5]],
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        ];
        let set = build(&polys);
        let v = set.as_view();
        assert!(set.num_split_vertices() > 0, "expected at least one split");
        // Every ring stays consistent, and each split vertex lies on its original edge.
        for i in 0..v.len() {
            assert_eq!(v.prev(v.next(i)), i);
            assert_eq!(v.next(v.prev(i)), i);
        }
        for s in set.num_input_vertices()..v.len() {
            assert!(v.is_convex(s));
            let (a, b) = (v.point(v.prev(s)), v.point(v.next(s)));
            let p = v.point(s);
            assert!(left_of(a, b, p).abs() < 1e-5);
            assert_eq!(v.dir(s), v.dir(v.prev(s)));
        }
        // Each node's edges are on its side: the tree has one node per processed edge.
        assert_eq!(set.tree().vertex.len(), v.len());
    }

    /// RVO2 takes a repeated vertex: the zero-length edge's direction is NaN, its vertices
    /// convex, and the other edges are linked and directed as usual.
    #[test]
    fn a_repeated_vertex_is_taken_as_rvo2_takes_it() {
        let polys = vec![vec![[0.0_f32, 0.0], [1.0, 0.0], [1.0, 0.0], [1.0, 1.0]]];
        assert_eq!(first_zero_length_edge(&polys), Some((0, 1)));
        let mut set = ObstacleSet::new();
        process_obstacles(&polys, &mut ObstacleScratch::new(), &mut set).unwrap();
        let v = set.as_view();
        assert_eq!(v.len(), 4);
        assert!(v.dir(1).x.is_nan() && v.dir(1).y.is_nan());
        assert_eq!(v.dir(2), Vec2::new(0.0, 1.0));
        assert!(v.convex[1] == 1 && v.convex[2] == 1);
        assert_eq!((v.next(1), v.prev(2)), (2, 1));
        let fine = vec![vec![[0.0_f32, 0.0], [1.0, 0.0], [1.0, 1.0]]];
        assert_eq!(first_zero_length_edge(&fine), None);
        let overflow = vec![vec![[-3e19_f32, 0.0], [3e19, 0.0]]];
        assert_eq!(first_zero_length_edge(&overflow), Some((0, 0)));
    }

    #[test]
    fn degenerate_inputs_are_errors() {
        let mut set = ObstacleSet::new();
        let mut scratch = ObstacleScratch::new();
        let one = vec![vec![[0.0_f32, 0.0]]];
        assert!(matches!(
            process_obstacles(&one, &mut scratch, &mut set),
            Err(OrcaError::TooFewVertices {
                polygon: 0,
                count: 1
            })
        ));
        assert!(set.is_empty());
        let nan = vec![vec![[0.0, 0.0], [f32::NAN, 1.0], [1.0, 1.0]]];
        assert!(matches!(
            process_obstacles(&nan, &mut scratch, &mut set),
            Err(OrcaError::NonFiniteVertex {
                polygon: 0,
                vertex: 1,
                ..
            })
        ));
    }
}
