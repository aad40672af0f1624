//! RVO2's agent k-d tree (`buildAgentTree` / `queryAgentTreeRecursive`), kept only to reproduce
//! RVO2's neighbour order for **exact distance ties** with more than 10 agents.
//!
//! The tree owns a permutation of agent indices that persists across builds: each build
//! partitions it in place, starting from the previous order, so the visiting order (and with it
//! the winner of a tie) depends on the history of positions. A fresh tree starts from the
//! identity order, which is what a new `RVOSimulator` does on its first `doStep`. For generic
//! states with no exact ties, [`crate::orca::agent_neighbors`] (brute force in index order)
//! gives the same lists and is what a GPU kernel should mirror.

use super::neighbors::{Neighbor, insert_agent_neighbor};

/// RVO2's `MAX_LEAF_SIZE`: nodes with at most this many agents are leaves.
const MAX_LEAF_SIZE: usize = 10;

#[derive(Clone, Copy, Debug, Default)]
struct Node {
    begin: usize,
    end: usize,
    left: usize,
    right: usize,
    min_x: f32,
    max_x: f32,
    min_y: f32,
    max_y: f32,
}

/// The agent k-d tree with its persistent permutation (see the module docs).
#[derive(Clone, Debug, Default)]
pub struct AgentKdTree {
    order: Vec<u32>,
    nodes: Vec<Node>,
}

impl AgentKdTree {
    /// An empty tree with the identity order to come.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Rebuilds the tree over agents at `pos_x`/`pos_y` (m).
    ///
    /// Agents appended since the last build join the end of the order, as in RVO2. If there are
    /// fewer agents than before (RVO2 never removes agents), the order restarts from identity.
    pub fn build(&mut self, pos_x: &[f32], pos_y: &[f32]) {
        let n = pos_x.len();
        assert_eq!(n, pos_y.len(), "position columns differ in length");
        if n < self.order.len() {
            self.order.clear();
        }
        if self.order.len() < n {
            self.order.extend(self.order.len() as u32..n as u32);
            self.nodes.resize(2 * n - 1, Node::default());
        }
        if n > 0 {
            self.build_node(pos_x, pos_y, 0, n, 0);
        }
    }

    fn build_node(&mut self, px: &[f32], py: &[f32], begin: usize, end: usize, node: usize) {
        let first = self.order[begin] as usize;
        let (mut min_x, mut max_x, mut min_y, mut max_y) =
            (px[first], px[first], py[first], py[first]);
        for &a in &self.order[begin + 1..end] {
            let (x, y) = (px[a as usize], py[a as usize]);
            // std::max(m, x) = (m < x) ? x : m ; std::min(m, x) = (x < m) ? x : m.
            if max_x < x {
                max_x = x;
            }
            if x < min_x {
                min_x = x;
            }
            if max_y < y {
                max_y = y;
            }
            if y < min_y {
                min_y = y;
            }
        }
        self.nodes[node] = Node {
            begin,
            end,
            min_x,
            max_x,
            min_y,
            max_y,
            ..Node::default()
        };
        if end - begin <= MAX_LEAF_SIZE {
            return;
        }
        let vertical = max_x - min_x > max_y - min_y;
        let split = if vertical {
            0.5 * (max_x + min_x)
        } else {
            0.5 * (max_y + min_y)
        };
        let key = |a: u32| {
            if vertical {
                px[a as usize]
            } else {
                py[a as usize]
            }
        };
        let (mut left, mut right) = (begin, end);
        while left < right {
            while left < right && key(self.order[left]) < split {
                left += 1;
            }
            while right > left && key(self.order[right - 1]) >= split {
                right -= 1;
            }
            if left < right {
                self.order.swap(left, right - 1);
                left += 1;
                right -= 1;
            }
        }
        if left == begin {
            left += 1;
        }
        let left_node = node + 1;
        let right_node = node + 2 * (left - begin);
        self.nodes[node].left = left_node;
        self.nodes[node].right = right_node;
        self.build_node(px, py, begin, left, left_node);
        self.build_node(px, py, left, end, right_node);
    }

    /// RVO2's `computeAgentNeighbors` for agent `self_index`: clears `out` and fills it with the
    /// `<= max_neighbors` nearest agents within `neighbor_dist` (m), in RVO2's exact order.
    ///
    /// Call [`AgentKdTree::build`] with the same positions first.
    pub fn agent_neighbors(
        &self,
        self_index: usize,
        pos_x: &[f32],
        pos_y: &[f32],
        neighbor_dist: f32,
        max_neighbors: u32,
        out: &mut Vec<Neighbor>,
    ) {
        out.clear();
        if max_neighbors == 0 || self.order.is_empty() {
            return;
        }
        let mut range_sq = neighbor_dist * neighbor_dist;
        let query = Query {
            tree: self,
            self_index,
            px: pos_x,
            py: pos_y,
            max_neighbors: max_neighbors as usize,
        };
        query.visit(0, &mut range_sq, out);
    }
}

struct Query<'a> {
    tree: &'a AgentKdTree,
    self_index: usize,
    px: &'a [f32],
    py: &'a [f32],
    max_neighbors: usize,
}

impl Query<'_> {
    /// Squared distance from the agent to a node's bounding box.
    fn box_dist_sq(&self, node: usize) -> f32 {
        let n = &self.tree.nodes[node];
        let (x, y) = (self.px[self.self_index], self.py[self.self_index]);
        // sqr(std::max(0.0F, a)) with std::max(0, a) = (0 < a) ? a : 0.
        let pos_sq = |a: f32| if 0.0 < a { a * a } else { 0.0 };
        pos_sq(n.min_x - x) + pos_sq(x - n.max_x) + pos_sq(n.min_y - y) + pos_sq(y - n.max_y)
    }

    fn visit(&self, node: usize, range_sq: &mut f32, out: &mut Vec<Neighbor>) {
        let n = self.tree.nodes[node];
        if n.end - n.begin <= MAX_LEAF_SIZE {
            let (x, y) = (self.px[self.self_index], self.py[self.self_index]);
            for &a in &self.tree.order[n.begin..n.end] {
                let j = a as usize;
                if j == self.self_index {
                    continue;
                }
                let (dx, dy) = (x - self.px[j], y - self.py[j]);
                let candidate = Neighbor {
                    dist_sq: dx * dx + dy * dy,
                    index: a,
                };
                insert_agent_neighbor(out, self.max_neighbors, candidate, range_sq);
            }
            return;
        }
        let dist_left = self.box_dist_sq(n.left);
        let dist_right = self.box_dist_sq(n.right);
        let (near, d_near, far, d_far) = if dist_left < dist_right {
            (n.left, dist_left, n.right, dist_right)
        } else {
            (n.right, dist_right, n.left, dist_left)
        };
        if d_near < *range_sq {
            self.visit(near, range_sq, out);
            if d_far < *range_sq {
                self.visit(far, range_sq, out);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::orca::neighbors::agent_neighbors;

    #[test]
    fn matches_brute_force_without_ties() {
        // 40 agents at pseudo-random positions (a small LCG): no exact distance ties.
        let n = 40;
        let mut state = 12345_u32;
        let mut next = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1 << 24) as f32 * 20.0
        };
        let (mut px, mut py) = (Vec::new(), Vec::new());
        for _ in 0..n {
            px.push(next());
            py.push(next());
        }
        let mut tree = AgentKdTree::new();
        tree.build(&px, &py);
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for i in 0..n {
            tree.agent_neighbors(i, &px, &py, 6.0, 7, &mut a);
            agent_neighbors(i, &px, &py, 6.0, 7, &mut b);
            assert_eq!(a, b, "agent {i}");
        }
    }
}
