// requires: common/math.wgsl
// requires: common/geometry.wgsl
//
// Stage `sngnn_score` (twin of src/systems/sngnn_score.rs; SNGNN-v2 inference, `Tables::forward`,
// src/sngnn/pieces.rs and src/sngnn/model.rs): graphs packed per environment
// (src/sngnn/packed.rs), edge weights W(e) from the flat piecewise-linear tables
// (`Tables::flat_layer`), one layer per dispatch.
//
// A stage, but not a batch shader (`pipeline::Shader::Network`): it has its own bindings
// (src/backend/gpu/sngnn_net.rs builds them) and no prelude, only the standalone head (below).
// Entry points:
// - `sort`: one invocation per environment groups its edges by destination with a stable
//   counting sort (CSR), so that each node can sum its messages alone, in build order.
// - `layer`: one invocation per (environment, node, output o) sums the messages into o over
//   the node's incoming edges (build order) and inputs i (ascending, zero inputs skipped),
//   exactly the CPU's order, then divides by the in-degree, adds the bias and applies the
//   activation. Layers ping-pong between two node-feature buffers.
//
// A graph of no nodes is not scored (STATUS_EMPTY, not an error): the GPU step empties the graphs
// of the environments its reward does not score, and their outputs are left as they were.
//
// The edge network itself does not exist here: an edge whose distance lies outside the tables
// (beyond `max_dist`, not finite, or non-zero on a relation whose distance is always 0) only
// sets STATUS_UNSUPPORTED, and the host reports an error. `sngnn::table_range` covers every
// distance of the config's rooms.
//
// llvmpipe stops every loop of an invocation after 65535 iterations in all (docs/gpu-backend.md):
// `sort` runs about 3 nodes + 3 edges iterations, `layer` about (inputs + 14) per incoming edge,
// far below it for SNGNN's graphs.
//
// The standalone head (`backend::wgsl::standalone_head`) defines, from the Rust values: the graph
// words G_NODES, G_EDGES, G_SRC (src/sngnn/packed.rs `words`); NODE_FEATURES (features per node
// in the packed graph, and the stride of node rows everywhere); RELATIONS (relations with a table
// entry); the words of a relation's entry in a layer's index T_ZERO, T_KNOTS, T_AT, T_VALUES,
// T_WORDS (src/sngnn/pieces.rs `flat`); an environment's status bits STATUS_UNSUPPORTED,
// STATUS_BAD_GRAPH, STATUS_EMPTY (`backend::wgsl::sngnn_status`).

// One layer's constants (src/sngnn/gpu.rs `LayerParams`, the same order).
struct NetParams {
    n_envs: u32,
    max_nodes: u32,
    max_edges: u32,
    u32_stride: u32,
    f32_stride: u32,
    inputs: u32,
    outputs: u32,
    relu: u32,
    // Floats per environment of `h_in` (the packed graph's stride at the first layer).
    h_in_stride: u32,
    // Offset of the bias in `tf`.
    bias: u32,
    // 1 at the last layer: node 0's values are the output.
    last: u32,
    max_dist: f32,
    // Where the last layer writes the room node's first `q_outputs` values: environment e's from
    // q[q_at + e * q_stride] on (a buffer of the net's own, or a state column of the GPU step).
    q_at: u32,
    q_stride: u32,
    q_outputs: u32,
}

@group(0) @binding(0) var<storage, read> p: NetParams;
@group(0) @binding(1) var<storage, read> gu: array<u32>;
@group(0) @binding(2) var<storage, read> gf: array<f32>;
// Per environment: `start[max_nodes + 1]` (node v's incoming edges are order[start[v]..start[v + 1]]),
// then `order[max_edges]` (edge indices).
@group(0) @binding(3) var<storage, read_write> csr: array<u32>;
@group(0) @binding(4) var<storage, read> tf: array<f32>;
@group(0) @binding(5) var<storage, read> ti: array<u32>;
@group(0) @binding(6) var<storage, read> h_in: array<f32>;
@group(0) @binding(7) var<storage, read_write> h_out: array<f32>;
@group(0) @binding(8) var<storage, read_write> q: array<f32>;
@group(0) @binding(9) var<storage, read_write> status: array<atomic<u32>>;

fn csr_base(e: u32) -> u32 {
    return e * (p.max_nodes + 1u + p.max_edges);
}

// Whether a non-empty graph fits its layout and names only its own nodes and relations: the
// kernels then stay inside the environment's regions.
fn graph_is_valid(g: u32, nodes: u32, edges: u32) -> bool {
    if (nodes > p.max_nodes || edges > p.max_edges) {
        return false;
    }
    var ok = true;
    for (var k = 0u; k < edges; k = k + 1u) {
        let src = gu[g + G_SRC + k];
        let dst = gu[g + G_SRC + p.max_edges + k];
        let rel = gu[g + G_SRC + 2u * p.max_edges + k];
        ok = ok && src < nodes && dst < nodes && rel < RELATIONS;
    }
    return ok;
}

@compute @workgroup_size(64)
fn sort(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= p.n_envs) {
        return;
    }
    let g = e * p.u32_stride;
    let nodes = gu[g + G_NODES];
    let edges = gu[g + G_EDGES];
    let c = csr_base(e);
    let order = c + p.max_nodes + 1u;
    for (var v = 0u; v <= p.max_nodes; v = v + 1u) {
        csr[c + v] = 0u;
    }
    if (nodes == 0u) {
        atomicStore(&status[e], STATUS_EMPTY);
        return;
    }
    if (!graph_is_valid(g, nodes, edges)) {
        atomicStore(&status[e], STATUS_BAD_GRAPH);
        return;
    }
    atomicStore(&status[e], 0u);
    // Counts at start[dst + 1], prefix sums: start[v] is where node v's edges begin.
    for (var k = 0u; k < edges; k = k + 1u) {
        let dst = gu[g + G_SRC + p.max_edges + k];
        csr[c + dst + 1u] = csr[c + dst + 1u] + 1u;
    }
    for (var v = 0u; v < nodes; v = v + 1u) {
        csr[c + v + 1u] = csr[c + v + 1u] + csr[c + v];
    }
    // Scatter in edge order (stable), using start[dst] as the cursor: afterwards start[v]
    // holds node v's end, which is node v + 1's start, so shifting by one restores the starts.
    for (var k = 0u; k < edges; k = k + 1u) {
        let dst = gu[g + G_SRC + p.max_edges + k];
        let at = csr[c + dst];
        csr[order + at] = k;
        csr[c + dst] = at + 1u;
    }
    for (var v = nodes; v > 0u; v = v - 1u) {
        csr[c + v] = csr[c + v - 1u];
    }
    csr[c] = 0u;
}

// `sum + h·W[·][o]` over the inputs of one edge whose W is the stored matrix at `w`
// (`add_message`).
fn add_constant(sum: f32, hb: u32, w: u32, o: u32) -> f32 {
    var s = sum;
    for (var i = 0u; i < p.inputs; i = i + 1u) {
        let h = h_in[hb + i];
        if (h != 0.0) {
            s = s + h * tf[w + i * p.outputs + o];
        }
    }
    return s;
}

// `sum + h·((1 − t)·lo + t·hi)[·][o]`, the interpolated matrix never formed
// (`add_interpolated_message`).
fn add_interpolated(sum: f32, hb: u32, lo: u32, hi: u32, t: f32, o: u32) -> f32 {
    var s = sum;
    for (var i = 0u; i < p.inputs; i = i + 1u) {
        let h = h_in[hb + i];
        if (h != 0.0) {
            let a = h * (1.0 - t);
            let b = h * t;
            // Rust's `s + (a·lo + b·hi)`: NIR would otherwise reassociate the sum of products.
            s = geo_add_sum(s, a * tf[lo + i * p.outputs + o] + b * tf[hi + i * p.outputs + o]);
        }
    }
    return s;
}

// The knot interval holding `d` (`Knots::locate`): the first knot after `d` by binary search
// (`partition_point`), clamped to an interval.
fn knot_interval(at: u32, knots: u32, d: f32) -> u32 {
    var lo = 0u;
    var hi = knots;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (tf[at + mid] <= d) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return clamp(lo, 1u, knots - 1u) - 1u;
}

fn activate(x: f32) -> f32 {
    if (p.relu != 0u) {
        return max(x, 0.0);
    }
    // ELU with α = 1.
    if (x > 0.0) {
        return x;
    }
    return math_exp(x) - 1.0;
}

@compute @workgroup_size(64)
fn layer(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.y;
    let v = gid.x / p.outputs;
    let o = gid.x % p.outputs;
    if (e >= p.n_envs || v >= p.max_nodes) {
        return;
    }
    let out_at = (e * p.max_nodes + v) * NODE_FEATURES + o;
    let g = e * p.u32_stride;
    let nodes = gu[g + G_NODES];
    if (v >= nodes || (atomicLoad(&status[e]) & STATUS_BAD_GRAPH) != 0u) {
        h_out[out_at] = 0.0;
        return;
    }
    let c = csr_base(e);
    let begin = csr[c + v];
    let end = csr[c + v + 1u];
    let dists = e * p.f32_stride + NODE_FEATURES * p.max_nodes;
    let len = p.inputs * p.outputs;
    var sum = 0.0;
    var unsupported = false;
    for (var k = begin; k < end; k = k + 1u) {
        let edge = csr[c + p.max_nodes + 1u + k];
        let src = gu[g + G_SRC + edge];
        let rel = gu[g + G_SRC + 2u * p.max_edges + edge];
        let dist = gf[dists + edge];
        let hb = e * p.h_in_stride + src * NODE_FEATURES;
        let entry = rel * T_WORDS;
        if (dist == 0.0) {
            sum = add_constant(sum, hb, ti[entry + T_ZERO], o);
            continue;
        }
        let knots = ti[entry + T_KNOTS];
        // Also true for NaN: such an edge takes the edge network on the CPU.
        if (knots < 2u || !(dist > 0.0 && dist < p.max_dist)) {
            unsupported = true;
            continue;
        }
        let at = ti[entry + T_AT];
        let kk = knot_interval(at, knots, dist);
        let a = tf[at + kk];
        let b = tf[at + kk + 1u];
        let t = (dist - a) / (b - a);
        let lo = ti[entry + T_VALUES] + kk * len;
        sum = add_interpolated(sum, hb, lo, lo + len, t, o);
    }
    if (unsupported) {
        atomicOr(&status[e], STATUS_UNSUPPORTED);
    }
    let y = activate(sum / f32(end - begin) + tf[p.bias + o]);
    h_out[out_at] = y;
    if (p.last != 0u && v == 0u && o < p.q_outputs) {
        q[p.q_at + e * p.q_stride + o] = y;
    }
}
