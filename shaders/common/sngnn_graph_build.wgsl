// requires: common/sngnn_frame.wgsl
//
// Twin of src/sngnn/graph.rs and history::select: the graph SNGNN-v2 sees for one environment
// (docs/spec.md 7.3-7.4), built into its packed regions (src/sngnn/packed.rs: `sn_gu` words nodes,
// edges, src[], dst[], rel[]; `sn_gf` features[batch.sn_max_nodes x SN_NODE_FEATURES], dist[]), nodes
// and edges in the CPU's order with the CPU's float operations, so that lavapipe writes
// exactly what `PackedLayout::pack` writes for `graph::build`'s graph. Unused words are zeroed.
// Change both in the same commit.
//
// Loop budget (llvmpipe stops every loop after 65535 iterations per invocation): zeroing the
// regions costs (batch.sn_u32_stride + batch.sn_f32_stride) / 8 iterations, a frame about 3 x nodes
// + 2 x people x segments; tests/suite/step/sngnn_graph/cpu.rs bounds the total for every shipped
// config.
//
// The SNGNN prelude defines graph.rs's constants from their Rust values: SN_POSITION_SCALE (/10
// positions), SN_MAX_HUMANS (0.1.1's MAX_HUMANS) and SN_MAX_HUMANS_SQ (its square, as Rust folds
// it), SN_SEGMENT_CM (97 cm segments), SN_HUMAN_WALL_THRESHOLD (1.5 m wall links).

// graph::Layout: where one frame's nodes go (the same for every frame of a graph).
struct SnLayout {
    nodes: u32,
    people: u32,
    objects: u32,
    goal: u32,
    walls: u32,
}

// graph::Segment: node within the frame, midpoint (m, SNGNN axes), sin and cos of its direction.
struct SnSegment {
    node: u32,
    x: f32,
    y: f32,
    s: f32,
    c: f32,
}

// Segments per wall of the graph being built (counted on the newest frame).
var<private> sn_wall_segments: array<u32, ARRAY_SN_WALLS>;

// The identity, opaque to the compiler (`params.pad[0]` is always 0, Rust `StepParams::_pad`):
// keeps Mesa's NIR from rewriting an expression around it.
fn sn_keep(x: f32) -> f32 {
    return bitcast<f32>(bitcast<u32>(x) ^ params.pad[0]);
}

// ---- packed regions ----

fn sn_ubase(e: u32) -> u32 {
    return e * batch.sn_u32_stride;
}

fn sn_fbase(e: u32) -> u32 {
    return e * batch.sn_f32_stride;
}

// Eight stores per loop iteration, written out: zeroing the regions is the pass's largest loop,
// and llvmpipe counts iterations, not stores, against its budget. The tail loops take the rest.
fn sn_zero_graph(e: u32) {
    let u_end = sn_ubase(e) + batch.sn_u32_stride;
    var i = sn_ubase(e);
    for (; i + 8u <= u_end; i += 8u) {
        sn_gu[i] = 0u;
        sn_gu[i + 1u] = 0u;
        sn_gu[i + 2u] = 0u;
        sn_gu[i + 3u] = 0u;
        sn_gu[i + 4u] = 0u;
        sn_gu[i + 5u] = 0u;
        sn_gu[i + 6u] = 0u;
        sn_gu[i + 7u] = 0u;
    }
    for (; i < u_end; i++) {
        sn_gu[i] = 0u;
    }
    let f_end = sn_fbase(e) + batch.sn_f32_stride;
    var j = sn_fbase(e);
    for (; j + 8u <= f_end; j += 8u) {
        sn_gf[j] = 0.0;
        sn_gf[j + 1u] = 0.0;
        sn_gf[j + 2u] = 0.0;
        sn_gf[j + 3u] = 0.0;
        sn_gf[j + 4u] = 0.0;
        sn_gf[j + 5u] = 0.0;
        sn_gf[j + 6u] = 0.0;
        sn_gf[j + 7u] = 0.0;
    }
    for (; j < f_end; j++) {
        sn_gf[j] = 0.0;
    }
}

// Feature `k` of graph node `node`.
fn sn_feature_at(e: u32, node: u32, k: u32) -> u32 {
    return sn_fbase(e) + node * SN_NODE_FEATURES + k;
}

fn sn_set_feature(e: u32, node: u32, k: u32, v: f32) {
    if (node < batch.sn_max_nodes) {
        sn_gf[sn_feature_at(e, node, k)] = v;
    }
}

// Append the edge src -> dst (graph nodes); an edge beyond batch.sn_max_edges is dropped (never for a
// config's own `graph::capacity`).
fn sn_push_edge(e: u32, src: u32, dst: u32, relation: u32, dist: f32) {
    let ub = sn_ubase(e);
    let k = sn_gu[ub + SN_WORD_EDGES];
    if (k >= batch.sn_max_edges) {
        return;
    }
    sn_gu[ub + SN_WORD_SRC + k] = src;
    sn_gu[ub + SN_WORD_SRC + batch.sn_max_edges + k] = dst;
    sn_gu[ub + SN_WORD_SRC + 2u * batch.sn_max_edges + k] = relation;
    sn_gf[sn_fbase(e) + SN_NODE_FEATURES * batch.sn_max_nodes + k] = dist;
    sn_gu[ub + SN_WORD_EDGES] = k + 1u;
}

// ---- history::select ----

struct SnSelection {
    slots: array<u32, SN_MAX_GRAPH_FRAMES>,
    len: u32,
}

fn sn_tick_gap(a: u32, b: u32) -> u32 {
    return select(b - a, a - b, a >= b);
}

// Ticks back from a frame at tick `last` to the next frame the selection may take
// (`history::TickGaps::gap_after`, with the table of `TickGaps::words` in `sn_gaps`): the base
// gap, one more where the extra bits mark the tick (0.1.1's f64 timestamps at time steps such as
// 0.1 s).
fn sn_gap_after(last: u32) -> u32 {
    let base = sn_gaps[0];
    if (last >= sn_gaps[1]) {
        return base;
    }
    return base + ((sn_gaps[2u + last / 32u] >> (last % 32u)) & 1u);
}

// The newest frame, then walking back every frame at least one second (`sn_gap_after`) from
// the last one taken, up to SN_MAX_GRAPH_FRAMES.
fn sn_select(e: u32) -> SnSelection {
    var out: SnSelection;
    out.len = 0u;
    let count = su[batch.c_sn_frame_count + at_sngnn(e, 0u)];
    if (count == 0u) {
        return out;
    }
    out.slots[0] = sn_slot_of_age(e, 0u);
    out.len = 1u;
    var last = su[batch.c_sf_tick + sn_frame_row(e, out.slots[0])];
    for (var age = 1u; age < count; age++) {
        let slot = sn_slot_of_age(e, age);
        let t = su[batch.c_sf_tick + sn_frame_row(e, slot)];
        if (sn_tick_gap(t, last) < sn_gap_after(last)) {
            continue;
        }
        out.slots[out.len] = slot;
        out.len += 1u;
        last = t;
        if (out.len == SN_MAX_GRAPH_FRAMES) {
            break;
        }
    }
    return out;
}

// ---- walls ----

// frame::wall_ends: wall w's end points (x1, y1, x2, y2) (m, SNGNN axes) seen from `robot`.
fn sn_wall_ends(e: u32, w: u32, robot: SnRobot) -> vec4<f32> {
    let i = at_wall(e, w);
    let half = 0.5 * sf[batch.c_w_length + i];
    let dx = half * sf[batch.c_w_cos + i];
    let dy = half * sf[batch.c_w_sin + i];
    let p1 = sn_axes(robot, sf[batch.c_w_x + i] - dx, sf[batch.c_w_y + i] - dy);
    let p2 = sn_axes(robot, sf[batch.c_w_x + i] + dx, sf[batch.c_w_y + i] + dy);
    // Opaque: NIR would factor the difference of two end points, (c·a − s·b) − (c·d − s·f),
    // into c·(a − d) − s·(b − f), which rounds differently from Rust.
    return vec4<f32>(sn_keep(p1.x), sn_keep(p1.y), sn_keep(p2.x), sn_keep(p2.y));
}

// graph::segment_count: floor(|p2 - p1| (cm) / 97) + 1.
fn sn_segment_count(ends: vec4<f32>) -> u32 {
    let dx = (ends.x - ends.z) * 100.0;
    let dy = (ends.y - ends.w) * 100.0;
    return u32(sqrt(dx * dx + dy * dy) / SN_SEGMENT_CM) + 1u;
}

// A wall's split as `graph::segments` computes it once per wall: its first end point (m, SNGNN
// axes), the step between midpoints (m), and the sin and cos of atan2(dx, dy).
struct SnWallSplit {
    x1: f32,
    y1: f32,
    dx: f32,
    dy: f32,
    s: f32,
    c: f32,
}

fn sn_wall_split(ends: vec4<f32>, n: u32) -> SnWallSplit {
    let dx = (ends.z - ends.x) / f32(n);
    let dy = (ends.w - ends.y) / f32(n);
    // Opaque, so that NIR cannot turn `dx / sqrt(..)` into `dx * rsq(..)` (inexact).
    let length = sn_keep(sqrt(dx * dx + dy * dy));
    // sin and cos of atan2(dx, dy), exactly (atan2(0, 0) = 0).
    var s = 0.0;
    var c = 1.0;
    if (length > 0.0) {
        s = dx / length;
        c = dy / length;
    }
    return SnWallSplit(ends.x, ends.y, dx, dy, s, c);
}

// Segment i of a wall split (node `node` within the frame).
fn sn_segment(w: SnWallSplit, i: u32, node: u32) -> SnSegment {
    let along = f32(i) + 0.5;
    return SnSegment(node, w.x1 + along * w.dx, w.y1 + along * w.dy, w.s, w.c);
}

// graph::Layout::of: the newest frame's entities and the walls' segment counts.
fn sn_layout(e: u32, newest: u32) -> SnLayout {
    let f = sn_frame_row(e, newest);
    let robot = sn_robot(sf[batch.c_sf_robot_x + f], sf[batch.c_sf_robot_y + f], sf[batch.c_sf_robot_theta + f]);
    let walls = min(su[batch.c_n_walls + e], batch.sn_walls);
    var total = 0u;
    for (var w = 0u; w < walls; w++) {
        sn_wall_segments[w] = sn_segment_count(sn_wall_ends(e, w, robot));
        total += sn_wall_segments[w];
    }
    let people = su[batch.c_sf_n_people + f];
    let objects = su[batch.c_sf_n_objects + f];
    let goal = 1u + people + objects;
    return SnLayout(goal + 1u + total, people, objects, goal, walls);
}

// ---- nodes ----

// √(x² + y²) of the /10 position.
fn sn_scaled_distance(x: f32, y: f32) -> f32 {
    let sx = x / SN_POSITION_SCALE;
    let sy = y / SN_POSITION_SCALE;
    return sqrt(sx * sx + sy * sy);
}

// A person or object record of a frame: id, then x, y, a, vx, vy, va.
struct SnEntity {
    id: u32,
    x: f32,
    y: f32,
    a: f32,
    vx: f32,
    vy: f32,
    va: f32,
}

// Person `j` of ring slot `slot` of environment e.
fn sn_person_of(e: u32, slot: u32, j: u32) -> SnEntity {
    let i = at_frame_person(e, slot * batch.sn_frame_people + j);
    return SnEntity(su[batch.c_fp_id + i], sf[batch.c_fp_x + i], sf[batch.c_fp_y + i], sf[batch.c_fp_a + i],
        sf[batch.c_fp_vx + i], sf[batch.c_fp_vy + i], sf[batch.c_fp_va + i]);
}

// Object `j` of ring slot `slot` of environment e.
fn sn_object_of(e: u32, slot: u32, j: u32) -> SnEntity {
    let i = at_frame_object(e, slot * batch.sn_frame_objects + j);
    return SnEntity(su[batch.c_fo_id + i], sf[batch.c_fo_x + i], sf[batch.c_fo_y + i], sf[batch.c_fo_a + i],
        sf[batch.c_fo_vx + i], sf[batch.c_fo_vy + i], sf[batch.c_fo_va + i]);
}

// FrameGraph::kinematics: the nine position and velocity features from `at` on; returns rho.
fn sn_kinematics(e: u32, node: u32, at: u32, p: SnEntity, dist_at: u32) -> f32 {
    let rho = sn_scaled_distance(p.x, p.y);
    let sc = math_sin_cos(math_wrap_angle(p.a));
    sn_set_feature(e, node, at, p.x / SN_POSITION_SCALE);
    sn_set_feature(e, node, at + 1u, p.y / SN_POSITION_SCALE);
    sn_set_feature(e, node, at + 2u, p.va / SN_POSITION_SCALE);
    sn_set_feature(e, node, at + 3u, p.vx / SN_POSITION_SCALE);
    sn_set_feature(e, node, at + 4u, p.vy / SN_POSITION_SCALE);
    sn_set_feature(e, node, at + 5u, sc.x);
    sn_set_feature(e, node, at + 6u, sc.y);
    sn_set_feature(e, node, dist_at, rho);
    sn_set_feature(e, node, dist_at + 1u, 1.0 - rho);
    return rho;
}

fn sn_room(e: u32, base: u32, f: u32) {
    let people = f32(su[batch.c_sf_n_people + f]);
    sn_set_feature(e, base, SN_F_ROOM, 1.0);
    sn_set_feature(e, base, SN_F_ROOM_HUMANS, people / SN_MAX_HUMANS);
    sn_set_feature(e, base, SN_F_ROOM_HUMANS + 1u, people * people / SN_MAX_HUMANS_SQ);
    sn_set_feature(e, base, SN_F_ROBOT, sf[batch.c_sf_advance + f] / SN_MAX_ADVANCE);
    sn_set_feature(e, base, SN_F_ROBOT + 1u, sf[batch.c_sf_rotation + f] / SN_MAX_ROTATION);
}

fn sn_person(e: u32, base: u32, p: SnEntity) {
    let node = base + p.id;
    sn_set_feature(e, node, SN_F_HUMAN, 1.0);
    let rho = sn_kinematics(e, node, SN_F_PERSON, p, SN_F_PERSON + 7u);
    sn_push_edge(e, node, base, SN_REL_P_R, rho);
    sn_push_edge(e, base, node, SN_REL_R_P, rho);
}

fn sn_object(e: u32, base: u32, o: SnEntity, size: vec2<f32>) {
    let node = base + o.id;
    let at = SN_F_OBJECT_BASE;
    let rho = sn_kinematics(e, node, at, o, at + 9u);
    sn_set_feature(e, node, SN_F_OBJECT, 1.0);
    sn_set_feature(e, node, at + 7u, size.x);
    sn_set_feature(e, node, at + 8u, size.y);
    sn_push_edge(e, node, base, SN_REL_O_R, rho);
    sn_push_edge(e, base, node, SN_REL_R_O, rho);
}

fn sn_goal(e: u32, base: u32, f: u32, lay: SnLayout) {
    let x = sf[batch.c_sf_goal_x + f];
    let y = sf[batch.c_sf_goal_y + f];
    let rho = sn_scaled_distance(x, y);
    let node = base + lay.goal;
    let at = SN_F_GOAL_BASE;
    sn_set_feature(e, node, SN_F_GOAL, 1.0);
    sn_set_feature(e, node, at, x / SN_POSITION_SCALE);
    sn_set_feature(e, node, at + 1u, y / SN_POSITION_SCALE);
    sn_set_feature(e, node, at + 2u, rho);
    sn_set_feature(e, node, at + 3u, 1.0 - rho);
    sn_push_edge(e, node, base, SN_REL_G_R, rho);
    sn_push_edge(e, base, node, SN_REL_R_G, rho);
}

fn sn_wall(e: u32, base: u32, seg: SnSegment) {
    let rho = sn_scaled_distance(seg.x, seg.y);
    let node = base + seg.node;
    let at = SN_F_WALL_BASE;
    sn_set_feature(e, node, SN_F_WALL, 1.0);
    sn_set_feature(e, node, at, seg.x / SN_POSITION_SCALE);
    sn_set_feature(e, node, at + 1u, seg.y / SN_POSITION_SCALE);
    sn_set_feature(e, node, at + 2u, seg.s);
    sn_set_feature(e, node, at + 3u, seg.c);
    sn_set_feature(e, node, at + 4u, rho);
    sn_set_feature(e, node, at + 5u, 1.0 - rho);
    sn_push_edge(e, node, base, SN_REL_W_R, rho);
    sn_push_edge(e, base, node, SN_REL_R_W, rho);
}

// graph::metres: distance (m) between a person and a segment midpoint.
fn sn_metres(p: SnEntity, seg: SnSegment) -> f32 {
    let dx = p.x - seg.x;
    let dy = p.y - seg.y;
    return sqrt(dx * dx + dy * dy);
}

// ---- one frame ----

// Every wall segment of the frame taken from `robot`, in node order: features and room edges.
fn sn_walls(e: u32, base: u32, lay: SnLayout, robot: SnRobot) {
    var node = lay.goal + 1u;
    for (var w = 0u; w < lay.walls; w++) {
        let n = sn_wall_segments[w];
        let split = sn_wall_split(sn_wall_ends(e, w, robot), n);
        for (var i = 0u; i < n; i++) {
            sn_wall(e, base, sn_segment(split, i, node));
            node += 1u;
        }
    }
}

// FrameGraph::wall_person_edges, first half: segment -> person for each person, then segment.
fn sn_wall_to_person_edges(e: u32, base: u32, slot: u32, lay: SnLayout, robot: SnRobot) {
    for (var j = 0u; j < lay.people; j++) {
        let p = sn_person_of(e, slot, j);
        var node = lay.goal + 1u;
        for (var w = 0u; w < lay.walls; w++) {
            let n = sn_wall_segments[w];
            let split = sn_wall_split(sn_wall_ends(e, w, robot), n);
            for (var i = 0u; i < n; i++) {
                let d = sn_metres(p, sn_segment(split, i, node));
                if (d < SN_HUMAN_WALL_THRESHOLD) {
                    sn_push_edge(e, base + node, base + p.id, SN_REL_W_P, d);
                }
                node += 1u;
            }
        }
    }
}

// Second half: person -> segment for each segment, then person.
fn sn_person_to_wall_edges(e: u32, base: u32, slot: u32, lay: SnLayout, robot: SnRobot) {
    var node = lay.goal + 1u;
    for (var w = 0u; w < lay.walls; w++) {
        let n = sn_wall_segments[w];
        let split = sn_wall_split(sn_wall_ends(e, w, robot), n);
        for (var i = 0u; i < n; i++) {
            let seg = sn_segment(split, i, node);
            for (var j = 0u; j < lay.people; j++) {
                let p = sn_person_of(e, slot, j);
                let d = sn_metres(p, seg);
                if (d < SN_HUMAN_WALL_THRESHOLD) {
                    sn_push_edge(e, base + p.id, base + node, SN_REL_P_W, d);
                }
            }
            node += 1u;
        }
    }
}

// graph::Endpoint: the person or object `id` of ring slot `slot` of environment e: its /10
// position and whether it is a person (w = 1). The CPU panics on an unknown id; the device takes
// the origin.
fn sn_endpoint(e: u32, slot: u32, id: u32) -> vec3<f32> {
    let f = sn_frame_row(e, slot);
    for (var j = 0u; j < su[batch.c_sf_n_people + f]; j++) {
        let p = sn_person_of(e, slot, j);
        if (p.id == id) {
            return vec3<f32>(p.x / SN_POSITION_SCALE, p.y / SN_POSITION_SCALE, 1.0);
        }
    }
    for (var j = 0u; j < su[batch.c_sf_n_objects + f]; j++) {
        let o = sn_object_of(e, slot, j);
        if (o.id == id) {
            return vec3<f32>(o.x / SN_POSITION_SCALE, o.y / SN_POSITION_SCALE, 0.0);
        }
    }
    return vec3<f32>(0.0, 0.0, 0.0);
}

// graph::relation by the types of an interaction edge's ends.
fn sn_relation(src_person: bool, dst_person: bool) -> u32 {
    if (src_person && dst_person) {
        return SN_REL_P_P;
    }
    if (src_person) {
        return SN_REL_P_O;
    }
    return SN_REL_O_P;
}

// FrameGraph::interaction_edges: each entry src -> dst and back.
fn sn_interaction_edges(e: u32, base: u32, slot: u32) {
    let f = sn_frame_row(e, slot);
    for (var k = 0u; k < su[batch.c_sf_n_links + f]; k++) {
        let i = at_frame_link(e, slot * batch.sn_frame_links + k);
        let src = su[batch.c_fl_src + i];
        let dst = su[batch.c_fl_dst + i];
        let a = sn_endpoint(e, slot, src);
        let b = sn_endpoint(e, slot, dst);
        let dx = a.x - b.x;
        let dy = a.y - b.y;
        let d = sqrt(dx * dx + dy * dy);
        sn_push_edge(e, base + src, base + dst, sn_relation(a.z != 0.0, b.z != 0.0), d);
        sn_push_edge(e, base + dst, base + src, sn_relation(b.z != 0.0, a.z != 0.0), d);
    }
}

// The object sizes as frame records hold them (object `j` of ring slot `slot` of environment e).
fn sn_object_size(e: u32, slot: u32, j: u32) -> vec2<f32> {
    let i = at_frame_object(e, slot * batch.sn_frame_objects + j);
    return vec2<f32>(sf[batch.c_fo_size_x + i], sf[batch.c_fo_size_y + i]);
}

// FrameGraph::add: frame k (ring slot `slot`) at nodes k * lay.nodes.., in 0.1.1's order.
fn sn_add_frame(e: u32, slot: u32, k: u32, lay: SnLayout) {
    let base = k * lay.nodes;
    let f = sn_frame_row(e, slot);
    sn_room(e, base, f);
    for (var j = 0u; j < su[batch.c_sf_n_people + f]; j++) {
        sn_person(e, base, sn_person_of(e, slot, j));
    }
    for (var j = 0u; j < su[batch.c_sf_n_objects + f]; j++) {
        sn_object(e, base, sn_object_of(e, slot, j), sn_object_size(e, slot, j));
    }
    sn_goal(e, base, f, lay);
    let robot = sn_robot(sf[batch.c_sf_robot_x + f], sf[batch.c_sf_robot_y + f], sf[batch.c_sf_robot_theta + f]);
    sn_walls(e, base, lay, robot);
    sn_wall_to_person_edges(e, base, slot, lay, robot);
    sn_person_to_wall_edges(e, base, slot, lay, robot);
    sn_interaction_edges(e, base, slot);
    for (var n = 0u; n < lay.nodes; n++) {
        sn_push_edge(e, base + n, base + n, SN_REL_SELF, 0.0);
        sn_set_feature(e, base + n, SN_F_IS_T + k, 1.0);
    }
}

// graph::temporal_edges between frames k - 1 (newer) and k.
fn sn_temporal_edges(e: u32, lay: SnLayout, k: u32) {
    let forward = SN_REL_TEMPORAL + 2u * (k - 1u);
    let newer = (k - 1u) * lay.nodes;
    let older = k * lay.nodes;
    for (var n = 0u; n < lay.nodes; n++) {
        sn_push_edge(e, newer + n, older + n, forward, 0.0);
        sn_push_edge(e, older + n, newer + n, forward + 1u, 0.0);
    }
}

// graph::build + PackedLayout::pack: environment e's graph into its packed regions (empty, all
// zero, without frames).
fn sn_build_graph(e: u32) {
    sn_zero_graph(e);
    let selection = sn_select(e);
    if (selection.len == 0u) {
        return;
    }
    let lay = sn_layout(e, selection.slots[0]);
    sn_gu[sn_ubase(e) + SN_WORD_NODES] = lay.nodes * selection.len;
    for (var k = 0u; k < selection.len; k++) {
        sn_add_frame(e, selection.slots[k], k, lay);
        if (k > 0u) {
            sn_temporal_edges(e, lay, k);
        }
    }
}
