//! Processed obstacles as columns (docs/spec.md orca-sfm 1.3), filled by
//! [`super::process_obstacles`].
//!
//! Input polygons list their vertices counter-clockwise (agents stay outside); a 2-vertex polygon
//! is a two-sided segment. Every vertex starts an edge to its `next` vertex and stores a unit
//! `direction` along that edge and a convexity flag. The processed list is the input vertices
//! followed by the vertices created by edge splits during the tree build, in creation order; it
//! is what the ORCA lines read. The static tree is kept too, so that
//! [`super::obstacle_neighbors_tree`] can visit edges in RVO2's order.
//!
//! Invariant: vertex columns all have the same length; tree columns all have one entry per node;
//! [`NONE`] marks a missing child. Rebuilding into the same [`ObstacleSet`] with the same
//! [`ObstacleScratch`] does not allocate once their capacity has grown.

use super::vector::Vec2;

/// Sentinel for "no node" in the obstacle tree columns.
pub const NONE: u32 = u32::MAX;

/// RVO2's `RVO_EPSILON`, used by the split classification, the "already covered" test and the
/// parallel-line tests of the linear programs.
pub const RVO_EPSILON: f32 = 1e-5;

/// Borrowed view of processed obstacle vertices as columns (the layout a GPU buffer gets).
///
/// Vertex `i` starts the edge `i -> next[i]`. `dir` is the unit direction of that edge (for a
/// split vertex: the direction of the edge it was split from). `convex` is 1 for a convex vertex,
/// 0 otherwise (`u32`, not `bool`, so the column can be uploaded as is). Positions in metres.
#[derive(Clone, Copy, Debug)]
pub struct ObstacleVerts<'a> {
    /// Vertex x (m).
    pub x: &'a [f32],
    /// Vertex y (m).
    pub y: &'a [f32],
    /// x of the unit edge direction.
    pub dir_x: &'a [f32],
    /// y of the unit edge direction.
    pub dir_y: &'a [f32],
    /// Index of the next vertex (end of this vertex's edge).
    pub next: &'a [u32],
    /// Index of the previous vertex.
    pub prev: &'a [u32],
    /// 1 if the vertex is convex, else 0.
    pub convex: &'a [u32],
}

impl ObstacleVerts<'_> {
    /// An empty view (no obstacles).
    pub const EMPTY: ObstacleVerts<'static> = ObstacleVerts {
        x: &[],
        y: &[],
        dir_x: &[],
        dir_y: &[],
        next: &[],
        prev: &[],
        convex: &[],
    };

    /// Number of vertices (= number of edges).
    #[inline]
    #[must_use]
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True if there are no obstacle vertices.
    #[inline]
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Position of vertex `i` (m).
    #[inline]
    #[must_use]
    pub fn point(&self, i: usize) -> Vec2 {
        Vec2::new(self.x[i], self.y[i])
    }

    /// Unit direction of the edge that starts at vertex `i`.
    #[inline]
    #[must_use]
    pub fn dir(&self, i: usize) -> Vec2 {
        Vec2::new(self.dir_x[i], self.dir_y[i])
    }

    /// Index of the vertex after `i`.
    #[inline]
    #[must_use]
    pub fn next(&self, i: usize) -> usize {
        self.next[i] as usize
    }

    /// Index of the vertex before `i`.
    #[inline]
    #[must_use]
    pub fn prev(&self, i: usize) -> usize {
        self.prev[i] as usize
    }

    /// True if vertex `i` is convex.
    #[inline]
    #[must_use]
    pub fn is_convex(&self, i: usize) -> bool {
        self.convex[i] != 0
    }
}

/// Borrowed view of the static obstacle k-d tree built by [`super::process_obstacles`].
///
/// Node 0 is the root (if any). `vertex[n]` is the start vertex of node `n`'s splitting edge;
/// `left[n]`/`right[n]` are child nodes or [`NONE`].
#[derive(Clone, Copy, Debug)]
pub struct ObstacleTree<'a> {
    /// Start vertex of each node's edge.
    pub vertex: &'a [u32],
    /// Left child of each node (edges left of the node's edge), or [`NONE`].
    pub left: &'a [u32],
    /// Right child of each node, or [`NONE`].
    pub right: &'a [u32],
}

/// Owned processed obstacles: vertex columns plus the static k-d tree.
///
/// Fill it with [`super::process_obstacles`]; read it through [`ObstacleSet::as_view`] and
/// [`ObstacleSet::tree`].
#[derive(Clone, Debug, Default)]
pub struct ObstacleSet {
    pub(super) x: Vec<f32>,
    pub(super) y: Vec<f32>,
    pub(super) dir_x: Vec<f32>,
    pub(super) dir_y: Vec<f32>,
    pub(super) next: Vec<u32>,
    pub(super) prev: Vec<u32>,
    pub(super) convex: Vec<u32>,
    pub(super) node_vertex: Vec<u32>,
    pub(super) node_left: Vec<u32>,
    pub(super) node_right: Vec<u32>,
    pub(super) num_input_vertices: usize,
}

impl ObstacleSet {
    /// An empty set (no obstacles).
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Make room for `vertices` processed vertices (and as many tree nodes) now, so that no later
    /// [`super::process_obstacles`] of at most that many vertices allocates.
    pub fn reserve(&mut self, vertices: usize) {
        for column in [&mut self.x, &mut self.y, &mut self.dir_x, &mut self.dir_y] {
            column.reserve(vertices.saturating_sub(column.len()));
        }
        for column in [&mut self.next, &mut self.prev, &mut self.convex] {
            column.reserve(vertices.saturating_sub(column.len()));
        }
        for column in [
            &mut self.node_vertex,
            &mut self.node_left,
            &mut self.node_right,
        ] {
            column.reserve(vertices.saturating_sub(column.len()));
        }
    }

    /// The processed vertex columns.
    #[must_use]
    pub fn as_view(&self) -> ObstacleVerts<'_> {
        ObstacleVerts {
            x: &self.x,
            y: &self.y,
            dir_x: &self.dir_x,
            dir_y: &self.dir_y,
            next: &self.next,
            prev: &self.prev,
            convex: &self.convex,
        }
    }

    /// The static k-d tree over the processed edges.
    #[must_use]
    pub fn tree(&self) -> ObstacleTree<'_> {
        ObstacleTree {
            vertex: &self.node_vertex,
            left: &self.node_left,
            right: &self.node_right,
        }
    }

    /// Number of processed vertices (input vertices plus split vertices).
    #[must_use]
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True if there are no obstacles.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Number of vertices given in the input polygons.
    #[must_use]
    pub fn num_input_vertices(&self) -> usize {
        self.num_input_vertices
    }

    /// Number of vertices created by edge splits during the tree build.
    #[must_use]
    pub fn num_split_vertices(&self) -> usize {
        self.x.len() - self.num_input_vertices
    }

    pub(super) fn clear(&mut self) {
        self.x.clear();
        self.y.clear();
        self.dir_x.clear();
        self.dir_y.clear();
        self.next.clear();
        self.prev.clear();
        self.convex.clear();
        self.node_vertex.clear();
        self.node_left.clear();
        self.node_right.clear();
        self.num_input_vertices = 0;
    }

    pub(super) fn push_vertex(&mut self, p: Vec2, dir: Vec2, next: u32, prev: u32, convex: bool) {
        self.x.push(p.x);
        self.y.push(p.y);
        self.dir_x.push(dir.x);
        self.dir_y.push(dir.y);
        self.next.push(next);
        self.prev.push(prev);
        self.convex.push(u32::from(convex));
    }

    #[inline]
    pub(super) fn point(&self, i: u32) -> Vec2 {
        Vec2::new(self.x[i as usize], self.y[i as usize])
    }
}

/// Reusable working memory for [`super::process_obstacles`] (the per-node edge lists of the build,
/// and the end points of the edges a node chooses its split among).
#[derive(Clone, Debug, Default)]
pub struct ObstacleScratch {
    pub(super) arena: Vec<u32>,
    pub(super) ends: Vec<[Vec2; 2]>,
}

impl ObstacleScratch {
    /// Empty scratch; it grows on first use and keeps its capacity.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Make room for a build over `vertices` vertices now. The build keeps the edge lists of every
    /// level of the tree: at most `vertices` per level, and a level per vertex in the worst case.
    pub fn reserve(&mut self, vertices: usize) {
        let worst = vertices * (vertices + 1);
        self.arena.reserve(worst.saturating_sub(self.arena.len()));
        // One node's list at a time, every vertex at most.
        self.ends.reserve(vertices.saturating_sub(self.ends.len()));
    }
}
