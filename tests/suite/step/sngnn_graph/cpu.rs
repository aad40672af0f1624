//! SNGNN-v2 input against SocNavGym 0.1.1: the frames socnav records (docs/spec.md 7.2) and the
//! graphs it builds from them (docs/spec.md 7.3-7.4), on the golden `exp1_with_sngnn` and
//! `exp2_with_sngnn` episodes (golden README section 7).
//!
//! Every episode is replayed as the golden README (section 8) says: before each step the
//! reference state is loaded through a state document whose `sngnn_frames` are socnav's own
//! frames of the earlier steps and the recorded action is taken through the stages with the
//! SNGNN-v2 reward, whose stage `sngnn_graph` records the frame where 0.1.1 called SNGNN
//! (`steps[i].sngnn` not null, i.e. non-terminal steps), from the state after the motion. The
//! network (`sngnn_score`) does not run: the frames do not need the weights.
//!
//! - Frames: every field of socnav's frame against `steps[i].sngnn.frame` (ids, order, positions,
//!   angles, velocities, sizes, interaction entries, goal, command, timestamp, wall end points).
//! - Graphs: for the dumped steps (1, 2, 25: one, two and three frames), the graph built from the
//!   recorded frames (loaded through the document with their step's tick and robot pose) and the
//!   graph built from socnav's own frames against the dump, node for node (42 features) and edge
//!   for edge (source, destination, relation, the 18 edge features); frames stacked, nodes and
//!   edges on every step.
//!
//! Failure messages name the episode, step, node or edge and field. Tolerances sit next to their
//! reason below; the largest error of each kind is printed.

use crate::thread_allocations;
use crate::{common, golden};

use std::collections::BTreeMap;

use serde_json::{Value, json};
use socnav::config::RewardKind;
use socnav::document;
use socnav::outputs::Outputs;
use socnav::pipeline::{Batch, STAGES};
use socnav::sngnn::frame::{RobotPose, wall_ends};
use socnav::sngnn::history::{self, History};
use socnav::sngnn::{EDGE_FEATURES, Graph, NODE_FEATURES, feature as graph_feature, graph};
use socnav::spec::ObsLayout;
use socnav::state::{BatchState, Caps};
use socnav::{AutoresetMode, Config, StepParams};

use common::npz::{self, Array};
use common::sngnn_rollout::SngnnRollout;
use golden::{Episode, Step, load_episodes, num, published_dir};

/// The golden configs with the SNGNN reward.
const CONFIGS: [&str; 2] = ["exp1_with_sngnn", "exp2_with_sngnn"];

/// Positions (m) in a frame: goal, people, objects, wall end points. Both sides transform
/// f32-rounded world positions of up to ~7 m into the robot frame in f32 (0.1.1's observation
/// and socnav's), a few ulp of ~10 m each (1e-6); 0.1.1's goal and walls go through f64 as well.
const FRAME_POSITION: f64 = 4e-6;
/// Angles (rad): −(π/2 + θ) of the wrapped relative heading; 0.1.1 takes atan2 of the f32 sin and
/// cos of the observation, socnav wraps the f32 difference: a few ulp of π.
const FRAME_ANGLE: f64 = 2e-6;
/// Velocities per 0.2 s (m or rad): differences of two such positions or angles over dt / 0.2
/// = 5 steps, so the position and angle errors above divided by 5 (and added).
const FRAME_VELOCITY: f64 = 1e-6;
/// Sizes and the command: f32 of the same config values and command, relative.
const FRAME_RELATIVE: f64 = 1e-6;
/// Node features of the graph of the recorded frames: 0.1.1 computes them in f64 from the
/// frame's values and stores f32; socnav computes in f32 from the f32-rounded frame (values of
/// order 1, a few ulp), wall midpoints from the state's walls and the frame's robot pose.
const GRAPH_FEATURE: f64 = 1e-6;
/// Edge distances (index 17): ρ as above; person-wall distances in metres (up to 1.5 m).
const GRAPH_DISTANCE: f64 = 2e-6;
/// Features and distances of the graph of socnav's own frames: its frames differ from the
/// recorded ones within the frame tolerances above, which the /10 scaling shrinks; angles keep
/// theirs (sin and cos of the angle).
const OWN_FEATURE: f64 = 2e-6;
const OWN_DISTANCE: f64 = 2e-6;

/// What a comparison found: failures (shown up to a limit) and the largest error per kind.
#[derive(Default)]
struct Check {
    compared: u64,
    failures: Vec<String>,
    failure_count: usize,
    max: BTreeMap<&'static str, (f64, String)>,
}

impl Check {
    fn fail(&mut self, msg: String) {
        self.failure_count += 1;
        if self.failures.len() < 40 {
            self.failures.push(msg);
        }
    }

    /// `ours` within `tol` of `theirs`; `kind` buckets the largest error.
    fn close(&mut self, kind: &'static str, at: &str, ours: f64, theirs: f64, tol: f64) {
        self.compared += 1;
        let err = (ours - theirs).abs();
        let slot = self.max.entry(kind).or_insert((0.0, String::new()));
        if err > slot.0 || slot.1.is_empty() {
            *slot = (err, at.to_string());
        }
        // A NaN on either side must fail, hence no `err > tol`.
        let within = err.partial_cmp(&tol).is_some_and(|o| o.is_le());
        if !within {
            self.fail(format!(
                "{at}: socnav {ours} vs 0.1.1 {theirs} (|err| {err:.2e} > {tol:.0e})"
            ));
        }
    }

    fn equal<T: PartialEq + std::fmt::Debug>(&mut self, at: &str, ours: T, theirs: T) -> bool {
        self.compared += 1;
        if ours != theirs {
            self.fail(format!("{at}: socnav {ours:?} vs 0.1.1 {theirs:?}"));
            return false;
        }
        true
    }

    fn assert_ok(&self, what: &str) {
        for (kind, (err, at)) in &self.max {
            println!("{what}: max |err| {kind} {err:.2e} at {at}");
        }
        println!("{what}: {} values compared", self.compared);
        assert!(self.compared > 0, "{what}: nothing was compared");
        assert!(
            self.failure_count == 0,
            "{what}: {} mismatches:\n{}",
            self.failure_count,
            self.failures.join("\n")
        );
    }
}

/// One environment of an SNGNN config, stepped stage by stage.
struct Sim {
    p: StepParams,
    s: BatchState,
    o: Outputs,
}

impl Sim {
    fn new(config: &Config) -> Self {
        let caps = Caps::from_config(config);
        let mut p = StepParams::new(config, AutoresetMode::NextStep);
        // The recorded social events are applied by loading the next reference state.
        p.replay = 1;
        Self {
            p,
            s: BatchState::new(1, caps),
            o: Outputs::new(1, ObsLayout::new(&caps, &config.observation)),
        }
    }

    /// Load a state document as `BatchEnv::set_state` does: import, then rebuild the ORCA
    /// obstacles the import marked dirty.
    fn load(&mut self, doc: &Value, at: &str) {
        document::import(&self.p, &mut self.s, 0, doc)
            .unwrap_or_else(|e| panic!("{at}: loading the state document: {e}"));
        let mut chunk = self.s.env_chunk(0);
        socnav::systems::orca_obstacles::rebuild_if_dirty(&self.p, &mut chunk, 0);
    }

    /// Take `action` through every stage but the network (`sngnn_score`) with the SNGNN-v2
    /// reward; returns whether stage `sngnn_graph` recorded a frame (the reward scores the step
    /// with its terms).
    fn step(&mut self, action: &[f32]) -> bool {
        let mut b = Batch {
            s: self.s.chunk(),
            o: self.o.chunk(),
            actions: action,
            sngnn: None,
            error: None,
        };
        let mut recorded = false;
        for stage in &STAGES {
            match stage.name {
                "sngnn_score" => continue,
                "sngnn_graph" => recorded = socnav::systems::reward::scores_terms(&b, 0),
                _ => {}
            }
            (stage.run)(&self.p, &mut b, 0);
        }
        assert!(b.error.is_none(), "step failed: {:?}", b.error);
        recorded
    }

    fn graph(&mut self, out: &mut Graph) -> usize {
        graph::build(&self.p, &self.s.env_chunk(0), 0, out)
    }

    /// The history as a document's `sngnn_frames`.
    fn exported_frames(&self) -> Value {
        document::export(&self.p, &self.s, 0)["state"]["sngnn_frames"].clone()
    }
}

/// The golden SNGNN episodes with their config.
fn episodes() -> Vec<(String, Episode, Config)> {
    let dir = published_dir();
    let mut out = Vec::new();
    for prefix in CONFIGS {
        for (name, ep) in load_episodes(&dir, Some(&format!("{prefix}_seed"))) {
            let config = Config::from_socnavgym(&ep.header()["config"])
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(config.reward.kind, RewardKind::Sngnn, "{name}");
            out.push((name, ep, config));
        }
    }
    assert_eq!(
        out.len(),
        6,
        "expected the 6 SNGNN episodes in {}",
        dir.display()
    );
    out
}

/// Replay `ep` with socnav's own frame history carried from step to step; `visit` sees each
/// step after it ran (with whether a frame was recorded).
fn replay(name: &str, ep: &Episode, config: &Config, mut visit: impl FnMut(Step<'_>, &mut Sim)) {
    let mut sim = Sim::new(config);
    let mut prev = ep.initial_state();
    let mut own_frames = json!([]);
    for step in ep.steps() {
        let mut doc = ep.step_document(prev, &step);
        doc["state"]["sngnn_frames"] = own_frames;
        sim.load(&doc, &format!("{name} step {}", step.t()));
        let recorded = sim.step(&step.action());
        assert_eq!(
            recorded,
            !step.v["sngnn"].is_null(),
            "{name} step {}: socnav recorded a frame: {recorded}, 0.1.1 called SNGNN: {}",
            step.t(),
            !step.v["sngnn"].is_null()
        );
        visit(step, &mut sim);
        own_frames = sim.exported_frames();
        prev = step.state();
    }
}

#[test]
fn frames_match_the_recorded_ones() {
    let mut check = Check::default();
    let mut frames = 0;
    for (name, ep, config) in episodes() {
        replay(&name, &ep, &config, |step, sim| {
            let golden = &step.v["sngnn"]["frame"];
            if golden.is_null() || !step.replayable() {
                return;
            }
            frames += 1;
            compare_frame(
                &mut check,
                &format!("{name} step {}", step.t()),
                sim,
                golden,
            );
        });
    }
    println!("{frames} frames");
    check.assert_ok("frames");
}

/// The newest frame of `sim` against 0.1.1's record.
fn compare_frame(check: &mut Check, at: &str, sim: &mut Sim, golden: &Value) {
    let chunk = sim.s.env_chunk(0);
    let h = History::of_chunk(&chunk, 0);
    let frame = h.frame(0);
    let head = frame.head();
    check.close(
        "timestamp",
        &format!("{at} timestamp"),
        history::timestamp(sim.p.dt, head.tick),
        num(&golden["timestamp"]),
        0.0,
    );
    for (k, key) in ["x", "y"].iter().enumerate() {
        let theirs = num(&golden["goal"][0][key]);
        let at = format!("{at} goal.{key}");
        check.close("position", &at, head.goal[k].into(), theirs, FRAME_POSITION);
    }
    for (k, &ours) in head.command.iter().enumerate() {
        let theirs = num(&golden["command"][k]);
        let tol = FRAME_RELATIVE * theirs.abs().max(1.0);
        check.close(
            "command",
            &format!("{at} command[{k}]"),
            ours.into(),
            theirs,
            tol,
        );
    }
    let people = golden["people"].as_array().expect("people");
    if check.equal(
        &format!("{at} people count"),
        frame.n_people(),
        people.len(),
    ) {
        for (j, g) in people.iter().enumerate() {
            compare_entity(check, &format!("{at} people[{j}]"), &frame.person(j), g);
        }
    }
    let objects = golden["objects"].as_array().expect("objects");
    if check.equal(
        &format!("{at} objects count"),
        frame.n_objects(),
        objects.len(),
    ) {
        for (j, g) in objects.iter().enumerate() {
            let o = frame.object(j);
            let at = format!("{at} objects[{j}]");
            compare_entity(check, &at, &o.pose, g);
            for (key, ours) in [("size_x", o.size_x), ("size_y", o.size_y)] {
                let theirs = num(&g[key]);
                let tol = FRAME_RELATIVE * theirs.abs();
                check.close("size", &format!("{at}.{key}"), ours.into(), theirs, tol);
            }
        }
    }
    let links: Vec<(u64, u64)> = golden["interaction"]
        .as_array()
        .expect("interaction")
        .iter()
        .map(|l| (l["src"].as_u64().unwrap(), l["dst"].as_u64().unwrap()))
        .collect();
    let ours: Vec<(u64, u64)> = frame
        .links()
        .map(|l| (l.src.into(), l.dst.into()))
        .collect();
    check.equal(&format!("{at} interaction (src, dst)"), ours, links);
    let walls = golden["walls"].as_array().expect("walls");
    let robot = RobotPose::new(head.robot);
    if check.equal(
        &format!("{at} walls count"),
        chunk.n_walls[0] as usize,
        walls.len(),
    ) {
        for (w, g) in walls.iter().enumerate() {
            let ends = wall_ends(&chunk, 0, w, &robot);
            for (k, key) in ["x1", "y1", "x2", "y2"].iter().enumerate() {
                let at = format!("{at} walls[{w}].{key}");
                check.close(
                    "position",
                    &at,
                    ends[k].into(),
                    num(&g[key]),
                    FRAME_POSITION,
                );
            }
        }
    }
}

fn compare_entity(check: &mut Check, at: &str, ours: &history::Person, g: &Value) {
    check.equal(
        &format!("{at}.id"),
        u64::from(ours.id),
        g["id"].as_u64().unwrap(),
    );
    let fields = [
        ("x", ours.x, "position", FRAME_POSITION),
        ("y", ours.y, "position", FRAME_POSITION),
        ("a", ours.a, "angle", FRAME_ANGLE),
        ("vx", ours.vx, "velocity", FRAME_VELOCITY),
        ("vy", ours.vy, "velocity", FRAME_VELOCITY),
        ("va", ours.va, "velocity", FRAME_VELOCITY),
    ];
    for (key, value, kind, tol) in fields {
        check.close(
            kind,
            &format!("{at}.{key}"),
            value.into(),
            num(&g[key]),
            tol,
        );
    }
}

/// The node feature names (docs/spec.md 7.3), for messages.
const FEATURE_NAMES: [&str; NODE_FEATURES] = [
    "human",
    "object",
    "room",
    "wall",
    "goal",
    "is_t_0",
    "is_t_m1",
    "is_t_m2",
    "hum_x_pos",
    "hum_y_pos",
    "human_a_vel",
    "human_x_vel",
    "human_y_vel",
    "hum_orientation_sin",
    "hum_orientation_cos",
    "hum_dist",
    "hum_inv_dist",
    "robot_adv_vel",
    "robot_rot_vel",
    "obj_x_pos",
    "obj_y_pos",
    "obj_a_vel",
    "obj_x_vel",
    "obj_y_vel",
    "obj_orientation_sin",
    "obj_orientation_cos",
    "obj_x_size",
    "obj_y_size",
    "obj_dist",
    "obj_inv_dist",
    "room_humans",
    "room_humans2",
    "wall_x_pos",
    "wall_y_pos",
    "wall_orientation_sin",
    "wall_orientation_cos",
    "wall_dist",
    "wall_inv_dist",
    "goal_x_pos",
    "goal_y_pos",
    "goal_dist",
    "goal_inv_dist",
];

/// One step's graph from the npz dump.
struct Dump<'a> {
    arrays: &'a BTreeMap<String, Array>,
    t: u64,
}

impl Dump<'_> {
    fn get(&self, what: &str) -> &Array {
        let key = format!("step{}_{what}", self.t);
        self.arrays
            .get(&key)
            .unwrap_or_else(|| panic!("no {key} in the dump"))
    }
}

/// Compare `g` with the dumped graph, node for node and edge for edge.
fn compare_graph(check: &mut Check, at: &str, g: &Graph, dump: &Dump<'_>, tol: [f64; 2]) {
    let feats = dump.get("node_feats");
    if !check.equal(&format!("{at} nodes"), g.nodes, feats.shape[0]) {
        return;
    }
    for n in 0..g.nodes {
        for (k, name) in FEATURE_NAMES.iter().enumerate() {
            let i = n * NODE_FEATURES + k;
            let at = format!("{at} node {n} feature {k} ({name})");
            check.close(
                "node feature",
                &at,
                g.features[i].into(),
                feats.data[i],
                tol[0],
            );
        }
    }
    let (src, dst, rel) = (dump.get("src"), dump.get("dst"), dump.get("rel_type"));
    let edge_feats = dump.get("edge_feats");
    if !check.equal(&format!("{at} edges"), g.src.len(), src.data.len()) {
        return;
    }
    for i in 0..g.src.len() {
        let ours = (g.src[i], g.dst[i], g.rel[i]);
        let theirs = (src.data[i] as u32, dst.data[i] as u32, rel.data[i] as u8);
        if !check.equal(&format!("{at} edge {i} (src, dst, rel)"), ours, theirs) {
            // Every later edge is shifted: one message says where the order parts.
            return;
        }
        let feature = g.edge_feature(i);
        for (k, &ours) in feature.iter().enumerate() {
            let theirs = edge_feats.data[i * EDGE_FEATURES + k];
            let tol = if k == EDGE_FEATURES - 1 { tol[1] } else { 0.0 };
            let at = format!("{at} edge {i} feature {k}");
            check.close("edge feature", &at, ours.into(), theirs, tol);
        }
    }
}

#[test]
fn graphs_match_the_dumps() {
    let mut recorded = Check::default();
    let mut own = Check::default();
    let mut dumped = 0;
    for (name, ep, config) in episodes() {
        let path = published_dir().join(format!("{name}_graphs.npz"));
        let arrays = npz::read_npz(&path);
        let dumped_steps: Vec<u64> = arrays["steps"].data.iter().map(|&t| t as u64).collect();
        let steps: Vec<Step<'_>> = ep.steps().collect();
        let mut from_recorded = Sim::new(&config);
        let mut g = Graph::default();
        replay(&name, &ep, &config, |step, sim| {
            let golden = &step.v["sngnn"];
            if golden.is_null() {
                return;
            }
            let t = step.t();
            let at = format!("{name} step {t}");
            // The graph of 0.1.1's own frames, loaded with the state after the motion.
            let mut doc = ep.document(step.state_after_motion());
            let frames: Vec<Value> = steps[..t as usize]
                .iter()
                .rev()
                .filter_map(Step::sngnn_frame)
                .collect();
            doc["state"]["sngnn_frames"] = Value::Array(frames);
            from_recorded.load(&doc, &at);
            let n = from_recorded.graph(&mut g);
            compare_sizes(
                &mut recorded,
                &format!("{at} (recorded frames)"),
                &g,
                n,
                golden,
            );
            if dumped_steps.contains(&t) {
                dumped += 1;
                let dump = Dump { arrays: &arrays, t };
                let tol = [GRAPH_FEATURE, GRAPH_DISTANCE];
                compare_graph(
                    &mut recorded,
                    &format!("{at} (recorded frames)"),
                    &g,
                    &dump,
                    tol,
                );
            }
            // The graph of socnav's own frames (all replayable so far: a crowd formed at random
            // would make its frame differ from 0.1.1's).
            let own_frames_replayable = steps[..t as usize]
                .iter()
                .rev()
                .take(3)
                .all(Step::replayable);
            if !own_frames_replayable {
                println!("{at}: own frames include a non-replayable step, not compared");
                return;
            }
            let n = sim.graph(&mut g);
            compare_sizes(&mut own, &format!("{at} (own frames)"), &g, n, golden);
            if dumped_steps.contains(&t) {
                let dump = Dump { arrays: &arrays, t };
                let tol = [OWN_FEATURE, OWN_DISTANCE];
                compare_graph(&mut own, &format!("{at} (own frames)"), &g, &dump, tol);
            }
        });
    }
    assert_eq!(dumped, 18, "3 dumped steps in each of the 6 episodes");
    recorded.assert_ok("graphs of the recorded frames");
    own.assert_ok("graphs of socnav's frames");
}

/// Frames stacked, nodes and edges against the step's record.
fn compare_sizes(check: &mut Check, at: &str, g: &Graph, frames: usize, golden: &Value) {
    let size = |key: &str| golden[key].as_u64().expect(key) as usize;
    check.equal(
        &format!("{at} frames_in_graph"),
        frames,
        size("frames_in_graph"),
    );
    check.equal(&format!("{at} n_nodes"), g.nodes, size("n_nodes"));
    check.equal(&format!("{at} n_edges"), g.src.len(), size("n_edges"));
}

/// `graph::capacity` holds every graph of the golden episodes: 0.1.1's sizes as recorded on
/// every SNGNN step, and socnav's graph of its own frames.
#[test]
fn golden_graphs_fit_the_capacity() {
    let mut checked = 0;
    for (name, ep, config) in episodes() {
        let cap = graph::capacity(&config);
        let mut g = Graph::default();
        replay(&name, &ep, &config, |step, sim| {
            let golden = &step.v["sngnn"];
            if golden.is_null() {
                return;
            }
            let size = |key: &str| golden[key].as_u64().expect(key) as usize;
            let at = format!("{name} step {}", step.t());
            assert!(
                size("n_nodes") <= cap.max_nodes && size("n_edges") <= cap.max_edges,
                "{at}: 0.1.1's graph of {} nodes and {} edges exceeds {cap:?}",
                size("n_nodes"),
                size("n_edges")
            );
            sim.graph(&mut g);
            assert!(
                g.nodes <= cap.max_nodes && g.src.len() <= cap.max_edges,
                "{at}: socnav's graph of {} nodes and {} edges exceeds {cap:?}",
                g.nodes,
                g.src.len()
            );
            checked += 1;
        });
    }
    assert!(checked > 0);
    println!("{checked} golden graphs fit their config's capacity");
}

/// `graph::capacity` holds every graph of rolled-out batches of the shipped SNGNN configs
/// (random actions, resets and social events included; `pack` fails on a graph too large),
/// at their 1 s time step and at 0.5 s (a history of 7 frames).
#[test]
fn rolled_out_graphs_fit_the_capacity() {
    for name in ["exp1_sngnn", "exp2_sngnn", "exp3_sngnn"] {
        for dt in [1.0, 0.5] {
            let mut config = Config::from_name_or_path(name).expect(name);
            config.episode.time_step = dt;
            let mut r = SngnnRollout::new(&config, 32, 3);
            let mut rng = socnav::rng::RngStream::new(5, 0);
            let mut scored = 0;
            for _ in 0..80 {
                let actions = r.random_actions(&mut rng);
                r.step_to_reward(&actions);
                scored += r.score();
                r.finish_step(&actions);
            }
            let (nodes, edges, frames) = r.largest;
            println!(
                "{name} at dt {dt} s: {scored} graphs, largest {nodes} nodes and {edges} edges \
                 ({frames} frames) within {:?}",
                r.graphs
            );
            assert!(
                scored > 0 && frames == 3,
                "{name}: three-frame graphs were built"
            );
        }
    }
}

/// llvmpipe ends every loop of an invocation after 65,535 iterations in all (docs/ARCHITECTURE.md):
/// the device pass `sngnn_graph` must stay below that for every shipped config with the SNGNN
/// reward. Its loops, bounded from the capacities: zeroing the packed regions (eight words per
/// iteration, plus the tails); clearing the
/// ring slot and recording (people, objects, links, the previous poses); per frame of the graph,
/// the selection, the nodes and room edges, both wall-person loops (people × segments each, and
/// the walls' loops around them),
/// the interaction ends' searches (links × (people + objects)) and the self-loops and temporal
/// edges (2 N).
#[test]
fn the_device_pass_stays_within_llvmpipes_loop_budget() {
    const BUDGET: usize = 65_535;
    for name in Config::shipped_names() {
        let mut config = Config::from_name_or_path(name).expect(name);
        config.reward.kind = RewardKind::Sngnn;
        let caps = Caps::from_config(&config);
        let l = graph::capacity(&config);
        let (people, objects, links) = (caps.frame_people, caps.frame_objects, caps.frame_links);
        let segments = graph::wall_bounds(&config).segments;
        let nodes = l.max_nodes / history::MAX_GRAPH_FRAMES;
        let record = 2 * (people + objects + links) + caps.sngnn_entities;
        let frame = caps.frames
            + nodes
            + caps.walls
            + 2 * people * (segments + caps.walls)
            + 2 * links * (people + objects)
            + 2 * nodes;
        let zeroing = (l.u32_stride() + l.f32_stride()) / 8 + 14;
        let total = zeroing + record + history::MAX_GRAPH_FRAMES * frame;
        println!("{name}: at most {total} loop iterations per environment ({l:?})");
        assert!(total < BUDGET, "{name}: {total} loop iterations");
    }
}

/// A one-environment SNGNN state of `config` with time step `dt` (s) whose history holds
/// frames at ticks 1..=`ticks` (no entities).
fn history_of_ticks(dt: f32, ticks: u32) -> (StepParams, BatchState) {
    let mut config = socnav::Config::from_name_or_path("exp1").unwrap();
    config.reward.kind = RewardKind::Sngnn;
    config.episode.time_step = dt;
    let caps = Caps::from_config(&config);
    let p = StepParams::new(&config, AutoresetMode::NextStep);
    let mut s = BatchState::new(1, caps);
    let mut chunk = s.chunk();
    for tick in 1..=ticks {
        let head = history::FrameHead {
            tick,
            ..Default::default()
        };
        history::begin_frame(&mut chunk, 0, &head);
    }
    (p, s)
}

/// 0.1.1's choice over its unbounded list of frames at ticks 1..=`newest`, with the time step as
/// its YAML gives it (an f64 decimal).
fn reference_selection(time_step: f64, newest: u32) -> Vec<u32> {
    let mut taken = vec![newest];
    for tick in (1..newest).rev() {
        let last = *taken.last().unwrap();
        if (f64::from(tick) * time_step - f64::from(last) * time_step).abs() < 1.0 {
            continue;
        }
        taken.push(tick);
        if taken.len() == 3 {
            break;
        }
    }
    taken
}

/// The device's whole-tick spacing rule (`history::TickGaps`) takes the frames 0.1.1's f64
/// timestamps take, at every time step and tick: one constant gap where rounding never decides
/// (dt ≥ 1 s, dyadic dt, or 1 s / dt far from a whole number), a per-tick table where it does
/// (0.05, 0.1, 0.2 s).
#[test]
fn tick_gaps_select_as_the_f64_timestamps() {
    for (time_step, constant) in [
        (0.05, None),
        (0.1, None),
        (0.2, None),
        (0.3, Some(4)),
        (0.7, Some(2)),
        (0.25, Some(4)),
        (0.5, Some(2)),
        (0.75, Some(2)),
        (1.0, Some(1)),
        (1.5, Some(1)),
        (2.0, Some(1)),
    ] {
        let dt = time_step as f32;
        let gaps = history::TickGaps::new(dt, 300).expect("gaps");
        match constant {
            Some(gap) => assert_eq!(
                gaps,
                history::TickGaps {
                    base: gap,
                    extra: vec![]
                },
                "dt {time_step} s"
            ),
            None => assert!(gaps.ticks() > 300, "dt {time_step} s: {gaps:?}"),
        }
        for newest in 1..=300u32 {
            let mut taken = vec![newest];
            for tick in (1..newest).rev() {
                let last = *taken.last().unwrap();
                if taken.len() < 3 && last - tick >= gaps.gap_after(last) {
                    taken.push(tick);
                }
            }
            assert_eq!(
                taken,
                reference_selection(time_step, newest),
                "dt {time_step} s, newest tick {newest}"
            );
        }
    }
}

#[test]
fn the_history_holds_every_frame_the_selection_takes() {
    for time_step in [0.1, 0.2, 0.25, 0.3, 0.35, 0.5, 0.7, 1.0, 2.0] {
        let dt = time_step as f32;
        let capacity = history::capacity_for(dt);
        for newest in 1..=120 {
            let (p, mut s) = history_of_ticks(dt, newest);
            let chunk = s.env_chunk(0);
            let h = History::of_chunk(&chunk, 0);
            assert_eq!(h.len(), (newest as usize).min(capacity), "dt {time_step}");
            let ours: Vec<u32> = history::select(p.dt, &h)
                .slots()
                .iter()
                .map(|&slot| h.at_slot(slot).head().tick)
                .collect();
            assert_eq!(
                ours,
                reference_selection(time_step, newest),
                "dt {time_step} s, newest tick {newest}, history of {capacity} frames"
            );
        }
    }
    assert_eq!(history::capacity_for(1.0), 3, "dt = 1 s: t, t − 1, t − 2");
}

#[test]
fn configs_without_the_sngnn_reward_carry_no_sngnn_columns() {
    for name in common::config_names() {
        let config = common::load_config(&name);
        if config.reward.kind == RewardKind::Sngnn {
            continue;
        }
        let state = BatchState::new(2, Caps::from_config(&config));
        let kinds = BatchState::COLUMN_KINDS;
        for ((column, _, stride), (_, kind)) in state.columns().iter().zip(kinds) {
            if kind.starts_with("sngnn") || kind.starts_with("frame") {
                assert_eq!(*stride, 0, "{name}: column {column} of kind {kind}");
            }
        }
    }
}

#[test]
fn state_documents_round_trip_the_history() {
    let (name, ep, config) = episodes().remove(3);
    let mut sim = Sim::new(&config);
    let mut replayed = 0;
    replay(&name, &ep, &config, |step, s| {
        if step.t() == 5 {
            sim.load(&document::export(&s.p, &s.s, 0), &format!("{name} step 5"));
            // The ring may start elsewhere: compare frame by frame, newest first.
            let (ours, theirs) = (History::of_batch(&sim.s, 0), History::of_batch(&s.s, 0));
            assert_eq!(ours.len(), 3, "{name} step 5: frames held");
            assert_eq!(ours.len(), theirs.len(), "{name} step 5: frames held");
            for age in 0..ours.len() {
                let (a, b) = (ours.frame(age), theirs.frame(age));
                let at = format!("{name} step 5: frame {age} after export and import");
                assert_eq!(a.head(), b.head(), "{at}");
                assert!(a.people().eq(b.people()), "{at}: people");
                assert!(a.objects().eq(b.objects()), "{at}: objects");
                assert!(a.links().eq(b.links()), "{at}: interaction entries");
            }
            replayed += 1;
        }
    });
    assert_eq!(replayed, 1);
}

#[test]
fn sngnn_documents_need_the_entity_ids_1_to_n() {
    let (name, ep, config) = episodes().remove(0);
    let mut sim = Sim::new(&config);
    let mut doc = ep.document(ep.initial_state());
    let humans = doc["state"]["humans"].as_array_mut().unwrap();
    humans[0]["id"] = json!(99);
    let err = document::import(&sim.p, &mut sim.s, 0, &doc)
        .expect_err("an id beyond the entities must be refused")
        .to_string();
    assert!(
        err.contains("id 99") && err.contains("1..="),
        "{name}: unexpected message {err}"
    );
}

/// 0.1.1 counts the segments of each wall once per process (docs/spec.md 14); socnav counts them on
/// every graph's newest frame, so the same batch gives a 7 m room its 8 segments per wall
/// (⌊700 / 97⌋ + 1) after a 10 m room's 11, and back.
#[test]
fn wall_segments_are_counted_per_graph() {
    let (name, ep, config) = episodes().remove(0);
    let steps: Vec<Step<'_>> = ep.steps().collect();
    let mut sim = Sim::new(&config);
    let mut g = Graph::default();
    for (side, per_wall) in [(10.0, 11), (7.0, 8), (10.0, 11)] {
        let mut doc = ep.document(steps[0].state_after_motion());
        let inner = 0.5 * side - 0.1;
        for (wall, (x, y)) in doc["walls"].as_array_mut().unwrap().iter_mut().zip([
            (inner, 0.0),
            (0.0, -inner),
            (-inner, 0.0),
            (0.0, inner),
        ]) {
            wall["x"] = json!(x);
            wall["y"] = json!(y);
            wall["length"] = json!(side);
        }
        doc["room"]["map_x"] = json!(side);
        doc["room"]["map_y"] = json!(side);
        doc["state"]["sngnn_frames"] = json!([steps[0].sngnn_frame().expect("a frame at step 1")]);
        sim.load(&doc, &format!("{name}, {side} m room"));
        sim.graph(&mut g);
        let wall_nodes = (0..g.nodes)
            .filter(|&n| g.features[n * NODE_FEATURES + graph_feature::WALL] == 1.0)
            .count();
        assert_eq!(wall_nodes, 4 * per_wall, "{name}: a {side} m room");
    }
}

#[test]
fn a_warm_build_allocates_nothing() {
    let (name, ep, config) = episodes().remove(4);
    let mut g = Graph::default();
    let mut warm = None;
    replay(&name, &ep, &config, |step, sim| {
        if step.t() == 3 {
            sim.graph(&mut g);
        }
        if step.t() == 4 {
            let before = thread_allocations();
            let frames = sim.graph(&mut g);
            warm = Some((frames, thread_allocations() - before));
        }
    });
    let (frames, allocations) = warm.expect("step 4 replayed");
    assert_eq!(frames, 3);
    assert_eq!(allocations, 0, "{name}: graph::build allocated when warm");
}

/// Run the stages of `STAGES` that `which` selects over every environment of `r`, with `p`.
fn run_stages(r: &mut SngnnRollout, p: &StepParams, actions: &[f32], which: impl Fn(&str) -> bool) {
    let n = r.s.n_envs;
    let mut b = Batch {
        s: r.s.chunk(),
        o: r.o.chunk(),
        actions,
        sngnn: None,
        error: None,
    };
    for stage in STAGES.iter().filter(|s| which(s.name)) {
        for e in 0..n {
            (stage.run)(p, &mut b, e);
        }
    }
    assert!(b.error.is_none(), "step: {:?}", b.error);
}

/// Contract: the SNGNN-v2 stages change nothing without the SNGNN-v2 reward, and with it
/// `sngnn_graph` records a frame for exactly the environments the reward scores with its terms
/// (stepping, not terminal), as the test rollout's own rule (`SngnnRollout::scores`) does it.
#[test]
fn sngnn_stages_record_exactly_the_scored_steps() {
    let config = Config::from_name_or_path("exp2_sngnn").expect("exp2_sngnn");
    let mut a = SngnnRollout::new(&config, 32, 5);
    let mut b = SngnnRollout::new(&config, 32, 5);
    let mut dsrnn = a.p;
    dsrnn.reward_kind = 0;
    let before_reward = |name: &str| {
        let reward = STAGES
            .iter()
            .position(|s| s.name == "reward")
            .expect("reward");
        STAGES.iter().position(|s| s.name == name).expect("a stage") < reward
    };
    let mut rng = socnav::rng::RngStream::new(11, 0);
    let mut scored = 0;
    for step in 0..40 {
        let actions = a.random_actions(&mut rng);
        // Both up to the reward with the DSRNN reward (the SNGNN stages included, as no-ops).
        run_stages(&mut a, &dsrnn, &actions, before_reward);
        run_stages(&mut b, &dsrnn, &actions, before_reward);
        assert!(
            a.s.differing_columns(&b.s).is_empty(),
            "step {step}: the SNGNN stages changed the state without the SNGNN reward"
        );
        // a: frames recorded where the rollout's rule says; b: stage sngnn_graph with the SNGNN
        // reward.
        for e in 0..a.s.n_envs {
            if a.scores(e) {
                scored += 1;
                socnav::sngnn::frame::record(&a.p, &mut a.s.env_chunk(e), 0);
            }
        }
        let p = b.p;
        run_stages(&mut b, &p, &actions, |name| name == "sngnn_graph");
        let differ = a.s.differing_columns(&b.s);
        assert!(differ.is_empty(), "step {step}: columns {differ:?} differ");
        a.finish_step(&actions);
        b.finish_step(&actions);
    }
    assert!(scored > 32 * 20, "only {scored} scored steps");
}

/// Contract: the reward clips the raw score stage `sngnn_score` leaves in `r_discomfort_sngnn`
/// to [0, 1] (docs/spec.md 6.3): discomfort = clip(q1), the SNGNN term discomfort − 1, and the
/// reward (discomfort − 1)·1 + distance + alive.
#[test]
fn reward_clips_the_raw_sngnn_score() {
    let config = Config::from_name_or_path("exp2_sngnn").expect("exp2_sngnn");
    let mut r = SngnnRollout::new(&config, 3, 2);
    let p = r.p;
    let actions = vec![0.0; 9];
    let reward = STAGES
        .iter()
        .position(|s| s.name == "reward")
        .expect("reward");
    let names: Vec<&str> = STAGES[..reward].iter().map(|s| s.name).collect();
    run_stages(&mut r, &p, &actions, |name| {
        names.contains(&name) && !name.starts_with("sngnn")
    });
    for e in 0..3 {
        assert!(r.scores(e), "environment {e} is scored on its first step");
    }
    let raw = [1.7_f32, -0.3, 0.25];
    r.s.r_discomfort_sngnn.copy_from_slice(&raw);
    run_stages(&mut r, &p, &actions, |name| name == "reward");
    for (e, (q1, discomfort)) in raw.iter().zip([1.0_f32, 0.0, 0.25]).enumerate() {
        let info = |k: usize| r.o.info[e * socnav::spec::N_INFO + k];
        assert_eq!(
            info(socnav::spec::info::DISCOMFORT_SNGNN),
            discomfort,
            "q1 = {q1}"
        );
        assert_eq!(
            info(socnav::spec::info::SNGNN_REWARD),
            discomfort - 1.0,
            "q1 = {q1}"
        );
        let expected =
            (discomfort - 1.0) + info(socnav::spec::info::DISTANCE_REWARD) + p.reward_alive;
        assert_eq!(r.o.reward[e], expected, "q1 = {q1}");
    }
}
