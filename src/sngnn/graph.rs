//! The graph SNGNN-v2 sees for one environment (docs/spec.md 7.3-7.4): 0.1.1's `initializeAlt1` for
//! each frame [`history::select`] picks, stacked as its `merge_graphs` does, nodes and edges in the
//! original's order (checked against the golden dumps by `tests/suite/step/sngnn_graph/cpu.rs`).
//!
//! One frame of N nodes: the room (0), each person and object at its entity id, the goal
//! (1 + people + objects), then the wall segments. Its edges, in order: person ↔ room, object
//! ↔ room, goal ↔ room, wall segment ↔ room (each pair as x → room, room → x, both with the
//! node's distance ρ); wall segment → person for each person and segment closer than 1.5 m,
//! then person → wall segment for each segment and person (distance in metres); both
//! directions of every interaction entry; one self-loop per node. Frame k (0 newest) occupies
//! nodes k·N..(k + 1)·N with its `is_t` flag set; after its own edges come, for every node n,
//! (n of frame k − 1) → (n of frame k) with relation 14 + 2(k − 1) and the reverse with 15 +
//! 2(k − 1), distance 0.
//!
//! Walls are split into ⌊length (cm) / 97⌋ + 1 equal segments, counted on the newest frame and
//! used for all frames (0.1.1 instead keeps the counts of the first graph of the process, a bug:
//! docs/fidelity.md).

use super::frame::{MAX_ADVANCE, MAX_ROTATION, RobotPose, wall_ends};
use super::history::{self, Frame, History, MAX_GRAPH_FRAMES, Person};
use super::packed::PackedLayout;
use super::{Graph, NODE_FEATURES, feature, rel};
use crate::config::Config;
use crate::math;
use crate::params::StepParams;
use crate::state::{Caps, StateChunk, caps};

/// Positions are divided by this (m) for the node features (0.1.1: /10, walls cm/1000).
pub const POSITION_SCALE: f32 = 10.0;
/// 0.1.1's `MAX_HUMANS`, the room's normaliser.
pub const MAX_HUMANS: f32 = 15.0;
/// Wall segment length (cm) the split aims at.
pub const WALL_SEGMENT_CM: f32 = 97.0;
/// A person and a wall segment closer than this (m) are linked.
pub const HUMAN_WALL_THRESHOLD: f32 = 1.5;
/// Walls an environment can have (`Caps::walls` is at most 12).
pub const MAX_WALLS: usize = 16;

/// The most nodes and edges a graph of config `c` can have: the packed layout every
/// environment's graph fits (zero without the SNGNN reward).
///
/// A frame has N = 1 + people + objects + 1 + segments nodes (room, entities, goal, wall
/// segments). Its edges: 2 (N − 1) with the room, 2 per ordered person-segment pair closer
/// than 1.5 m ([`wall_bounds`]), 2 per interaction entry, N self-loops; frames 1 and 2 add
/// 2 N temporal edges each.
pub fn capacity(c: &Config) -> PackedLayout {
    let caps = Caps::from_config(c);
    if caps.frames == 0 {
        return PackedLayout {
            max_nodes: 0,
            max_edges: 0,
        };
    }
    let walls = wall_bounds(c);
    let (people, objects) = (caps.frame_people, caps.frame_objects);
    let nodes = 1 + people + objects + 1 + walls.segments;
    let near = people * walls.near_per_person.min(walls.segments);
    let frame_edges = 2 * (nodes - 1) + 2 * near + 2 * caps.frame_links + nodes;
    let frames = MAX_GRAPH_FRAMES.min(caps.frames);
    PackedLayout {
        max_nodes: frames * nodes,
        max_edges: frames * frame_edges + 2 * nodes * (frames - 1),
    }
}

/// Bounds on a config's wall segments (97 cm splits, not the observation's).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WallBounds {
    /// The most segments of one room.
    pub segments: usize,
    /// The most segments whose midpoints lie within 1.5 m of one point.
    pub near_per_person: usize,
}

/// [`WallBounds`] over every room the config can build (each size, shape and L location, as
/// `Caps` enumerates them). A wall of length L splits into n = ⌊L / 0.97 m⌋ + 1 segments whose
/// midpoints lie L / n apart on a line; a disc of radius 1.5 m covers less than 3 m of that line,
/// so at most ⌊3 n / L⌋ + 1 of them (and at most n). Each bound takes a relative margin of 1e-5
/// for the f32 rounding of the robot-frame wall ends. Corridor walls (doors are continuous
/// draws) add ⌈L / 0.97 m⌉ + 2 segments per corridor line, all counted as near.
pub fn wall_bounds(c: &Config) -> WallBounds {
    const MARGIN: f64 = 1.0 + 1e-5;
    let segment_m = f64::from(WALL_SEGMENT_CM) / 100.0;
    let reach = 2.0 * f64::from(HUMAN_WALL_THRESHOLD);
    let mut most = WallBounds {
        segments: 0,
        near_per_person: 0,
    };
    caps::for_each_room(c, |room, x, y| {
        let (mut segments, mut near_per_person) = (0, 0);
        for w in room.walls.as_slice() {
            let length = f64::from(w.length);
            let n = (length * MARGIN / segment_m).floor() as usize + 1;
            let near = (reach * n as f64 * MARGIN / length).floor() as usize + 1;
            segments += n;
            near_per_person += near.min(n);
        }
        if c.room.corridors {
            let line = f64::from(x.max(y));
            let n = 2 * ((line / segment_m).ceil() as usize + 2);
            segments += n;
            near_per_person += n;
        }
        most.segments = most.segments.max(segments);
        most.near_per_person = most.near_per_person.max(near_per_person);
    });
    most
}

/// Build the graph of local environment `e` from its history into `out` (cleared first; no
/// allocation once `out` has grown to the environment's size). Returns the number of frames
/// stacked (0, and an empty graph, when no frame is held).
pub fn build(p: &StepParams, s: &StateChunk, e: usize, out: &mut Graph) -> usize {
    out.clear();
    let h = History::of_chunk(s, e);
    let selection = history::select(p.dt, &h);
    let Some(&newest) = selection.slots().first() else {
        return 0;
    };
    let layout = Layout::of(s, e, &h.at_slot(newest));
    out.nodes = layout.nodes * selection.slots().len();
    out.features.resize(out.nodes * NODE_FEATURES, 0.0);
    for (k, &slot) in selection.slots().iter().enumerate() {
        let frame = h.at_slot(slot);
        layout.check(&frame, k);
        let mut g = FrameGraph {
            out: &mut *out,
            base: k * layout.nodes,
            layout: &layout,
        };
        g.add(s, e, &frame, k);
        if k > 0 {
            temporal_edges(out, &layout, k);
        }
    }
    selection.slots().len()
}

/// Where the nodes of one frame go: the same for every frame of a graph.
struct Layout {
    /// Nodes per frame.
    nodes: usize,
    people: usize,
    objects: usize,
    /// The goal's node; wall segments follow it.
    goal: usize,
    /// Segments per wall.
    segments: [u32; MAX_WALLS],
    walls: usize,
}

impl Layout {
    /// The layout of the newest frame: its entities and its wall segments.
    fn of(s: &StateChunk, e: usize, newest: &Frame<'_>) -> Self {
        let walls = s.n_walls[e] as usize;
        assert!(walls <= MAX_WALLS, "{walls} walls, more than {MAX_WALLS}");
        let robot = RobotPose::new(newest.head().robot);
        let mut segments = [0; MAX_WALLS];
        for (w, n) in segments[..walls].iter_mut().enumerate() {
            *n = segment_count(wall_ends(s, e, w, &robot));
        }
        let (people, objects) = (newest.n_people(), newest.n_objects());
        let goal = 1 + people + objects;
        let total: u32 = segments.iter().sum();
        Self {
            nodes: goal + 1 + total as usize,
            people,
            objects,
            goal,
            segments,
            walls,
        }
    }

    /// Frames of one episode show the same entities (totals are constant within an episode,
    /// and `set_state` checks loaded frames), so they share the newest frame's layout.
    fn check(&self, frame: &Frame<'_>, k: usize) {
        assert!(
            frame.n_people() == self.people && frame.n_objects() == self.objects,
            "SNGNN frame {k} holds {} people and {} objects, the newest {} and {}",
            frame.n_people(),
            frame.n_objects(),
            self.people,
            self.objects
        );
    }
}

/// ⌊|p2 − p1| (cm) / 97⌋ + 1 segments for a wall with end points `[x1, y1, x2, y2]` (m).
fn segment_count([x1, y1, x2, y2]: [f32; 4]) -> u32 {
    let dx = (x1 - x2) * 100.0;
    let dy = (y1 - y2) * 100.0;
    ((dx * dx + dy * dy).sqrt() / WALL_SEGMENT_CM) as u32 + 1
}

/// A wall segment of a frame: its node (within the frame), midpoint (m, SNGNN axes), and the
/// sin and cos of atan2(Δx, Δy) of its direction (0.1.1's swapped arguments).
#[derive(Debug, Clone, Copy)]
struct Segment {
    node: usize,
    x: f32,
    y: f32,
    sin: f32,
    cos: f32,
}

/// The wall segments of a frame taken from `robot`, in node order.
fn segments<'a>(
    s: &'a StateChunk,
    e: usize,
    layout: &'a Layout,
    robot: RobotPose,
) -> impl Iterator<Item = Segment> + 'a {
    (0..layout.walls)
        .flat_map(move |w| {
            let [x1, y1, x2, y2] = wall_ends(s, e, w, &robot);
            let n = layout.segments[w];
            let (dx, dy) = ((x2 - x1) / n as f32, (y2 - y1) / n as f32);
            let length = (dx * dx + dy * dy).sqrt();
            // sin and cos of atan2(dx, dy), exactly: dx / |d|, dy / |d| (atan2(0, 0) = 0).
            let (sin, cos) = if length > 0.0 {
                (dx / length, dy / length)
            } else {
                (0.0, 1.0)
            };
            (0..n).map(move |i| {
                let along = i as f32 + 0.5;
                (x1 + along * dx, y1 + along * dy, sin, cos)
            })
        })
        .enumerate()
        .map(|(k, (x, y, sin, cos))| Segment {
            node: layout.goal + 1 + k,
            x,
            y,
            sin,
            cos,
        })
}

/// √(x² + y²) of the /10 position (0.1.1's `dist` of every node but the wall edges).
#[inline]
fn scaled_distance(x: f32, y: f32) -> f32 {
    let (x, y) = (x / POSITION_SCALE, y / POSITION_SCALE);
    (x * x + y * y).sqrt()
}

/// Distance (m) between a person and a segment midpoint.
#[inline]
fn metres(p: &Person, seg: &Segment) -> f32 {
    let (dx, dy) = (p.x - seg.x, p.y - seg.y);
    (dx * dx + dy * dy).sqrt()
}

/// One frame's part of the graph.
struct FrameGraph<'g> {
    out: &'g mut Graph,
    /// Its first node.
    base: usize,
    layout: &'g Layout,
}

impl FrameGraph<'_> {
    /// Frame `k`'s nodes and edges, in 0.1.1's order.
    fn add(&mut self, s: &StateChunk, e: usize, frame: &Frame<'_>, k: usize) {
        self.room(frame);
        for person in frame.people() {
            self.person(&person);
        }
        for object in frame.objects() {
            self.object(&object);
        }
        self.goal(frame);
        let robot = RobotPose::new(frame.head().robot);
        for seg in segments(s, e, self.layout, robot) {
            self.wall(&seg);
        }
        self.wall_person_edges(s, e, frame, robot);
        self.interaction_edges(frame);
        for node in 0..self.layout.nodes {
            self.edge(node, node, rel::SELF, 0.0);
            self.row(node)[feature::IS_T + k] = 1.0;
        }
    }

    /// Segment → person for each person and segment closer than 1.5 m, then person → segment
    /// for each segment and person; the distance in metres.
    fn wall_person_edges(&mut self, s: &StateChunk, e: usize, frame: &Frame<'_>, robot: RobotPose) {
        for person in frame.people() {
            for seg in segments(s, e, self.layout, robot) {
                let d = metres(&person, &seg);
                if d < HUMAN_WALL_THRESHOLD {
                    self.edge(seg.node, person.id as usize, rel::W_P, d);
                }
            }
        }
        for seg in segments(s, e, self.layout, robot) {
            for person in frame.people() {
                let d = metres(&person, &seg);
                if d < HUMAN_WALL_THRESHOLD {
                    self.edge(person.id as usize, seg.node, rel::P_W, d);
                }
            }
        }
    }

    /// Each interaction entry src → dst and back, with the distance of the /10 positions.
    fn interaction_edges(&mut self, frame: &Frame<'_>) {
        for link in frame.links() {
            let (a, b) = (Endpoint::of(frame, link.src), Endpoint::of(frame, link.dst));
            let (dx, dy) = (a.x - b.x, a.y - b.y);
            let d = (dx * dx + dy * dy).sqrt();
            self.edge(a.node, b.node, relation(a.person, b.person), d);
            self.edge(b.node, a.node, relation(b.person, a.person), d);
        }
    }

    /// The feature row of frame node `node`.
    fn row(&mut self, node: usize) -> &mut [f32] {
        let at = (self.base + node) * NODE_FEATURES;
        &mut self.out.features[at..at + NODE_FEATURES]
    }

    /// The edge `src` → `dst` between frame nodes.
    fn edge(&mut self, src: usize, dst: usize, relation: u8, dist: f32) {
        self.out.src.push((self.base + src) as u32);
        self.out.dst.push((self.base + dst) as u32);
        self.out.rel.push(relation);
        self.out.dist.push(dist);
    }

    /// The node of entity `id`, which must lie between the room and the goal.
    fn entity_node(&self, id: u32) -> usize {
        let node = id as usize;
        assert!(
            (1..self.layout.goal).contains(&node),
            "SNGNN frame entity id {id} outside 1..{}: the graph needs the ids of humans and \
             objects to be 1..=N (docs/spec.md 7.3)",
            self.layout.goal
        );
        node
    }

    fn room(&mut self, frame: &Frame<'_>) {
        let people = frame.n_people() as f32;
        let command = frame.head().command;
        let f = self.row(0);
        f[feature::ROOM] = 1.0;
        f[feature::ROOM_HUMANS] = people / MAX_HUMANS;
        f[feature::ROOM_HUMANS + 1] = people * people / (MAX_HUMANS * MAX_HUMANS);
        f[feature::ROBOT] = command[0] / MAX_ADVANCE;
        f[feature::ROBOT + 1] = command[2] / MAX_ROTATION;
    }

    /// The nine position and velocity features of a person or object from `at` on; returns ρ.
    fn kinematics(&mut self, node: usize, at: usize, p: &Person, dist_at: usize) -> f32 {
        let rho = scaled_distance(p.x, p.y);
        let (sin, cos) = math::sin_cos(math::wrap_angle(p.a));
        let f = self.row(node);
        f[at] = p.x / POSITION_SCALE;
        f[at + 1] = p.y / POSITION_SCALE;
        f[at + 2] = p.va / POSITION_SCALE;
        f[at + 3] = p.vx / POSITION_SCALE;
        f[at + 4] = p.vy / POSITION_SCALE;
        f[at + 5] = sin;
        f[at + 6] = cos;
        f[dist_at] = rho;
        f[dist_at + 1] = 1.0 - rho;
        rho
    }

    fn person(&mut self, p: &Person) {
        let node = self.entity_node(p.id);
        self.row(node)[feature::HUMAN] = 1.0;
        let rho = self.kinematics(node, feature::PERSON, p, feature::PERSON + 7);
        self.edge(node, 0, rel::P_R, rho);
        self.edge(0, node, rel::R_P, rho);
    }

    fn object(&mut self, o: &history::Object) {
        let node = self.entity_node(o.pose.id);
        let at = feature::OBJECT_BASE;
        let rho = self.kinematics(node, at, &o.pose, at + 9);
        let f = self.row(node);
        f[feature::OBJECT] = 1.0;
        f[at + 7] = o.size_x;
        f[at + 8] = o.size_y;
        self.edge(node, 0, rel::O_R, rho);
        self.edge(0, node, rel::R_O, rho);
    }

    fn goal(&mut self, frame: &Frame<'_>) {
        let [x, y] = frame.head().goal;
        let rho = scaled_distance(x, y);
        let node = self.layout.goal;
        let f = self.row(node);
        let at = feature::GOAL_BASE;
        f[feature::GOAL] = 1.0;
        f[at] = x / POSITION_SCALE;
        f[at + 1] = y / POSITION_SCALE;
        f[at + 2] = rho;
        f[at + 3] = 1.0 - rho;
        self.edge(node, 0, rel::G_R, rho);
        self.edge(0, node, rel::R_G, rho);
    }

    fn wall(&mut self, seg: &Segment) {
        let rho = scaled_distance(seg.x, seg.y);
        let f = self.row(seg.node);
        let at = feature::WALL_BASE;
        f[feature::WALL] = 1.0;
        f[at] = seg.x / POSITION_SCALE;
        f[at + 1] = seg.y / POSITION_SCALE;
        f[at + 2] = seg.sin;
        f[at + 3] = seg.cos;
        f[at + 4] = rho;
        f[at + 5] = 1.0 - rho;
        self.edge(seg.node, 0, rel::W_R, rho);
        self.edge(0, seg.node, rel::R_W, rho);
    }
}

/// An interaction end: its node, whether it is a person, and its /10 position.
struct Endpoint {
    node: usize,
    person: bool,
    x: f32,
    y: f32,
}

impl Endpoint {
    /// The person or object `id` of `frame` (0.1.1 raises on an id that is neither).
    #[expect(
        clippy::panic,
        reason = "socnav builds the frames, every interaction between its own entities"
    )]
    fn of(frame: &Frame<'_>, id: u32) -> Self {
        let found = frame
            .people()
            .map(|p| (p, true))
            .chain(frame.objects().map(|o| (o.pose, false)))
            .find(|(p, _)| p.id == id);
        let (p, person) = found.unwrap_or_else(|| {
            panic!("SNGNN frame interaction names id {id}, which is no person or object of it")
        });
        Self {
            node: id as usize,
            person,
            x: p.x / POSITION_SCALE,
            y: p.y / POSITION_SCALE,
        }
    }
}

/// The relation of an interaction edge by the types of its ends (0.1.1 raises on o_o).
#[expect(clippy::panic, reason = "an interaction always involves a person")]
fn relation(src_person: bool, dst_person: bool) -> u8 {
    match (src_person, dst_person) {
        (true, true) => rel::P_P,
        (true, false) => rel::P_O,
        (false, true) => rel::O_P,
        (false, false) => panic!("an SNGNN interaction between two objects has no relation"),
    }
}

/// The temporal edges between frames k − 1 and k: for every node n, n of k − 1 → n of k and
/// back, distance 0 (the reverse edges of k = 2, relation 17, thus get an all-zero feature).
fn temporal_edges(out: &mut Graph, layout: &Layout, k: usize) {
    let forward = rel::TEMPORAL + 2 * (k as u8 - 1);
    // Frame k − 1 is the newer one (frame 0 is the newest).
    let (from, to) = ((k - 1) * layout.nodes, k * layout.nodes);
    for n in 0..layout.nodes {
        for (src, dst, relation) in [(from + n, to + n, forward), (to + n, from + n, forward + 1)] {
            out.src.push(src as u32);
            out.dst.push(dst as u32);
            out.rel.push(relation);
            out.dist.push(0.0);
        }
    }
}
