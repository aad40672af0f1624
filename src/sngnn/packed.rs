//! SNGNN-v2 graphs packed at a fixed stride per environment: the layout the GPU's graph builder
//! writes and its network kernels read, and that host code packs CPU-built [`Graph`]s into (for
//! tests, and for anything that feeds the device graphs built elsewhere).
//!
//! Per environment, two regions:
//! - u32, [`PackedLayout::u32_stride`] words: `nodes`, `edges`, then `src[max_edges]`,
//!   `dst[max_edges]`, `rel[max_edges]`;
//! - f32, [`PackedLayout::f32_stride`] floats: `features[max_nodes × NODE_FEATURES]` (row-major,
//!   unused rows zero), then `dist[max_edges]`.
//!
//! Edges keep the order [`super::graph::build`] gives them; a kernel that needs them grouped
//! by destination sorts them stably, so that each node sums its messages in that order.

use super::{Graph, NODE_FEATURES};
use crate::error::SimError;

/// The capacities a packed graph is laid out for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PackedLayout {
    /// Most nodes of one environment's graph.
    pub max_nodes: usize,
    /// Most edges of one environment's graph.
    pub max_edges: usize,
}

/// Word offsets inside an environment's u32 region.
pub mod words {
    /// Number of nodes.
    pub const NODES: usize = 0;
    /// Number of edges.
    pub const EDGES: usize = 1;
    /// Where `src` starts; `dst` and `rel` follow at `max_edges` strides.
    pub const SRC: usize = 2;
}

impl PackedLayout {
    /// u32 words per environment.
    pub fn u32_stride(&self) -> usize {
        words::SRC + 3 * self.max_edges
    }

    /// f32 values per environment.
    pub fn f32_stride(&self) -> usize {
        NODE_FEATURES * self.max_nodes + self.max_edges
    }

    /// The smallest layout that holds every graph of `graphs`.
    pub fn fitting<'a>(graphs: impl IntoIterator<Item = &'a Graph>) -> Self {
        graphs.into_iter().fold(
            PackedLayout {
                max_nodes: 0,
                max_edges: 0,
            },
            |l, g| PackedLayout {
                max_nodes: l.max_nodes.max(g.nodes),
                max_edges: l.max_edges.max(g.src.len()),
            },
        )
    }

    /// Pack `g` into one environment's regions (`u32s`, `f32s`: exactly one stride each),
    /// zeroing what it does not use.
    ///
    /// # Errors
    /// `SimError::Shape` when the graph exceeds the layout or the regions have the wrong size.
    pub fn pack(&self, g: &Graph, u32s: &mut [u32], f32s: &mut [f32]) -> Result<(), SimError> {
        let edges = g.src.len();
        if g.nodes > self.max_nodes || edges > self.max_edges {
            return Err(SimError::shape(
                "SNGNN graphs",
                format!(
                    "an SNGNN graph of {} nodes and {edges} edges exceeds the packed layout ({} nodes, {} edges)",
                    g.nodes, self.max_nodes, self.max_edges
                ),
            ));
        }
        if u32s.len() != self.u32_stride() || f32s.len() != self.f32_stride() {
            return Err(SimError::shape(
                "SNGNN graphs",
                format!(
                    "packed SNGNN graph regions of {} u32 and {} f32 values, expected {} and {}",
                    u32s.len(),
                    f32s.len(),
                    self.u32_stride(),
                    self.f32_stride()
                ),
            ));
        }
        u32s.fill(0);
        f32s.fill(0.0);
        u32s[words::NODES] = g.nodes as u32;
        u32s[words::EDGES] = edges as u32;
        let m = self.max_edges;
        let (src, rest) = u32s[words::SRC..].split_at_mut(m);
        let (dst, rel) = rest.split_at_mut(m);
        src[..edges].copy_from_slice(&g.src);
        dst[..edges].copy_from_slice(&g.dst);
        for (r, &x) in rel.iter_mut().zip(&g.rel) {
            *r = u32::from(x);
        }
        let features = g.nodes * NODE_FEATURES;
        f32s[..features].copy_from_slice(&g.features[..features]);
        let dist = NODE_FEATURES * self.max_nodes;
        f32s[dist..dist + edges].copy_from_slice(&g.dist);
        Ok(())
    }

    /// The graph packed in one environment's regions.
    pub fn unpack(&self, u32s: &[u32], f32s: &[f32]) -> Graph {
        let nodes = u32s[words::NODES] as usize;
        let edges = u32s[words::EDGES] as usize;
        let m = self.max_edges;
        let at = |k: usize| &u32s[words::SRC + k * m..words::SRC + k * m + edges];
        let dist = NODE_FEATURES * self.max_nodes;
        Graph {
            nodes,
            features: f32s[..nodes * NODE_FEATURES].to_vec(),
            src: at(0).to_vec(),
            dst: at(1).to_vec(),
            rel: at(2).iter().map(|&r| r as u8).collect(),
            dist: f32s[dist..dist + edges].to_vec(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn graph() -> Graph {
        Graph {
            nodes: 2,
            features: (0..2 * NODE_FEATURES).map(|i| i as f32).collect(),
            src: vec![0, 1, 1],
            dst: vec![0, 1, 0],
            rel: vec![11, 11, 5],
            dist: vec![0.0, 0.0, 0.25],
        }
    }

    #[test]
    fn pack_then_unpack_is_the_identity() {
        let g = graph();
        let l = PackedLayout {
            max_nodes: 3,
            max_edges: 5,
        };
        let mut u = vec![7; l.u32_stride()];
        let mut f = vec![7.0; l.f32_stride()];
        l.pack(&g, &mut u, &mut f).unwrap();
        assert_eq!(l.unpack(&u, &f), g);
        assert_eq!(u[words::SRC + 3], 0, "unused edge slots are zeroed");
        assert_eq!(f[2 * NODE_FEATURES], 0.0, "unused node rows are zeroed");
    }

    #[test]
    fn too_large_a_graph_is_an_error() {
        let l = PackedLayout {
            max_nodes: 1,
            max_edges: 5,
        };
        let mut u = vec![0; l.u32_stride()];
        let mut f = vec![0.0; l.f32_stride()];
        let e = l.pack(&graph(), &mut u, &mut f).unwrap_err();
        assert!(e.to_string().contains("2 nodes"), "{e}");
        assert_eq!(
            PackedLayout::fitting([&graph()]),
            PackedLayout {
                max_nodes: 2,
                max_edges: 3
            }
        );
    }
}
