//! The ORCA core in WGSL (`shaders/common/orca.wgsl`) against its Rust twin (`socnav::orca`),
//! bit for bit: for every agent of every scene, the new velocity, whether LP3 ran, the number
//! of ORCA lines (obstacle lines among them), both neighbour lists and every line (as an FNV-1a
//! hash of their bits) must equal what `agent_neighbors` + `compute_new_velocity` (the
//! brute-force core the GPU mirrors) give on the CPU.
//!
//! A test kernel, built here, runs one agent per invocation from its own storage buffers through
//! the library's building blocks reading storage, as the stage shaders do. Scenes: RVO2's reference data
//! (the one-step cases, the edge-split scenes, crossing4, corridor and every sampled Circle250
//! state; `SOCNAV_REF_DIR` or `tests/data/ref/orca_sfm`, as in tests/suite/orca/reference.rs) and
//! thousands of seeded random scenes with agents and polygon obstacles, crowded ones included so
//! that LP3 runs often.
//!
//! The capacities of the shipped configs are checked against the library's list limits too
//! (`shipped_capacities_fit_the_orca_lists`).
//!
//! Needs a GPU adapter (lavapipe will do). Without one the tests print why and pass, unless
//! `REQUIRE_GPU=1`. Bit-identity is the contract on lavapipe; on other adapters the shader may
//! legally round differently (docs/spec.md, bit parity), so there
//! (`common::gpu::parity_mode`) an agent agrees when its velocity is within
//! `common::gpu::TOLERANCE` and its overflow flag is the CPU's (the lines' bits and the decisions
//! within rounding of a threshold may differ), and at most `common::gpu::MAX_DIVERGED` of the
//! agents may disagree.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::common;

use common::gpu::{MAX_DIVERGED, Parity, TOLERANCE, config, device, floats_agree, parity_mode};
use common::reference::Table;
use socnav::backend::gpu::GpuDevice;
use socnav::backend::wgsl;
use socnav::orca::{
    ObstacleScratch, ObstacleSet, OrcaAgent, OrcaNeighbor, OrcaScratch, agent_neighbors,
    compute_new_velocity, process_obstacles,
};
use socnav::rng::RngStream;
use socnav::state::Caps;

// ---------------------------------------------------------------------------------------------
// The test kernel
// ---------------------------------------------------------------------------------------------

/// Floats per agent in `agent_f`.
const AGENT_F: usize = 12;
/// Words per scene in `scene_u`: agent offset, agent count, vertex offset, vertex count,
/// time step (bits).
const SCENE_U: usize = 5;
/// Words per agent in the output (see [`Expected`]).
const OUT: usize = 11;

/// Bindings and the entry point. Everything ORCA comes from the library; this only loads
/// the data, selects the agent neighbours by brute force and writes what the test compares.
const KERNEL: &str = r"
@group(0) @binding(0) var<storage, read> scene_u: array<u32>;
@group(0) @binding(1) var<storage, read> agent_f: array<f32>;
@group(0) @binding(2) var<storage, read> agent_u: array<u32>;
@group(0) @binding(3) var<storage, read> vert_f: array<f32>;
@group(0) @binding(4) var<storage, read> vert_u: array<u32>;
@group(0) @binding(5) var<storage, read_write> out: array<u32>;

const AGENT_F: u32 = 12u;
const SCENE_U: u32 = 5u;
const OUT: u32 = 11u;

struct Scene {
    agent_offset: u32,
    agent_count: u32,
    vert_offset: u32,
    vert_count: u32,
    time_step: f32,
}

fn load_scene(a: u32) -> Scene {
    let s = agent_u[2u * a] * SCENE_U;
    return Scene(scene_u[s], scene_u[s + 1u], scene_u[s + 2u], scene_u[s + 3u], bitcast<f32>(scene_u[s + 4u]));
}

fn agent_pos(a: u32) -> vec2<f32> {
    return vec2<f32>(agent_f[AGENT_F * a], agent_f[AGENT_F * a + 1u]);
}

fn load_agent(a: u32) -> OrcaAgent {
    let b = AGENT_F * a;
    return OrcaAgent(
        agent_pos(a),
        vec2<f32>(agent_f[b + 2u], agent_f[b + 3u]),
        vec2<f32>(agent_f[b + 4u], agent_f[b + 5u]),
        agent_f[b + 6u],
        agent_f[b + 7u],
        agent_f[b + 8u],
        agent_u[2u * a + 1u],
        agent_f[b + 9u],
        agent_f[b + 10u],
    );
}

fn load_neighbor(a: u32) -> OrcaNeighbor {
    let b = AGENT_F * a;
    return OrcaNeighbor(agent_pos(a), vec2<f32>(agent_f[b + 2u], agent_f[b + 3u]), agent_f[b + 6u]);
}

fn vert_point(g: u32) -> vec2<f32> {
    return vec2<f32>(vert_f[4u * g], vert_f[4u * g + 1u]);
}

fn vert_dir(g: u32) -> vec2<f32> {
    return vec2<f32>(vert_f[4u * g + 2u], vert_f[4u * g + 3u]);
}

fn vert_next(g: u32) -> u32 {
    return vert_u[3u * g];
}

// Vertex i (scene-local) of the scene whose vertices start at `base`, read from storage.
fn load_vertex(base: u32, i: u32) -> OrcaVertex {
    let g = base + i;
    return orca_vertex(i, vert_point(g), vert_dir(g), vert_dir(base + vert_u[3u * g + 1u]), vert_u[3u * g + 2u]);
}

// Rust `agent_neighbors` over the scene's agents, in index order.
fn select_agents(a: u32, sc: Scene, agent: OrcaAgent, list: ptr<function, OrcaAgentNeighbors>) {
    var range_sq = orca_agent_range_sq(agent.neighbor_dist);
    let local = a - sc.agent_offset;
    for (var j = 0u; j < sc.agent_count; j = j + 1u) {
        if (j == local) {
            continue;
        }
        orca_agent_neighbor_candidate(list, agent.max_neighbors, agent.pos, j, agent_pos(sc.agent_offset + j), &range_sq);
    }
}

fn fnv(h: u32, x: u32) -> u32 {
    return (h ^ x) * 16777619u;
}

fn write_out(
    a: u32,
    r: OrcaResult,
    nb: ptr<function, OrcaAgentNeighbors>,
    onb: ptr<function, OrcaObstacleNeighbors>,
    lines: ptr<function, OrcaLines>,
) {
    var h_lines = 2166136261u;
    for (var k = 0u; k < (*lines).len; k = k + 1u) {
        let l = (*lines).items[k];
        h_lines = fnv(h_lines, bitcast<u32>(l.point.x));
        h_lines = fnv(h_lines, bitcast<u32>(l.point.y));
        h_lines = fnv(h_lines, bitcast<u32>(l.direction.x));
        h_lines = fnv(h_lines, bitcast<u32>(l.direction.y));
    }
    var h_obst = 2166136261u;
    for (var k = 0u; k < (*onb).len; k = k + 1u) {
        h_obst = fnv(h_obst, (*onb).items[k].index);
    }
    var h_agents = 2166136261u;
    for (var k = 0u; k < (*nb).len; k = k + 1u) {
        h_agents = fnv(h_agents, (*nb).items[k].index);
    }
    let o = OUT * a;
    out[o] = bitcast<u32>(r.velocity.x);
    out[o + 1u] = bitcast<u32>(r.velocity.y);
    out[o + 2u] = r.used_lp3;
    out[o + 3u] = r.overflow;
    out[o + 4u] = (*lines).len;
    out[o + 5u] = (*lines).num_obstacle_lines;
    out[o + 6u] = (*nb).len;
    out[o + 7u] = (*onb).len;
    out[o + 8u] = h_lines;
    out[o + 9u] = h_obst;
    out[o + 10u] = h_agents;
}

// The building blocks over storage, as a stage shader uses them.
@compute @workgroup_size(64)
fn main_blocks(@builtin(global_invocation_id) gid: vec3<u32>) {
    let a = gid.x;
    if (a >= arrayLength(&agent_u) / 2u) {
        return;
    }
    let sc = load_scene(a);
    let agent = load_agent(a);
    var nb: OrcaAgentNeighbors;
    orca_agent_neighbors_clear(&nb);
    select_agents(a, sc, agent, &nb);

    var onb: OrcaObstacleNeighbors;
    orca_obstacle_neighbors_clear(&onb);
    let range_sq = orca_obstacle_range_sq(agent.time_horizon_obst, agent.max_speed, agent.radius);
    for (var v = 0u; v < sc.vert_count; v = v + 1u) {
        let g = sc.vert_offset + v;
        orca_obstacle_neighbor_candidate(&onb, agent.pos, range_sq, v, vert_point(g), vert_point(sc.vert_offset + vert_next(g)));
    }

    var lines: OrcaLines;
    orca_lines_clear(&lines);
    for (var k = 0u; k < onb.len; k = k + 1u) {
        let o1 = onb.items[k].index;
        let o2 = vert_next(sc.vert_offset + o1);
        orca_push_obstacle_line(agent, load_vertex(sc.vert_offset, o1), load_vertex(sc.vert_offset, o2), &lines);
    }
    lines.num_obstacle_lines = lines.len;
    for (var k = 0u; k < nb.len; k = k + 1u) {
        orca_push_agent_line(agent, load_neighbor(sc.agent_offset + nb.items[k].index), sc.time_step, &lines);
    }
    var r = orca_solve(agent, &lines);
    r.overflow = r.overflow | nb.overflow | onb.overflow;
    write_out(a, r, &nb, &onb, &lines);
}
";

/// The kernel's WGSL: the constants the step's shaders share with Rust, the library with its
/// requirements, then [`KERNEL`].
fn kernel_source() -> String {
    let mut src = wgsl::shared_head();
    for p in wgsl::resolve("common/orca.wgsl").expect("orca.wgsl is embedded") {
        let _ = writeln!(src, "// ---- shaders/{p}");
        src.push_str(wgsl::source(p).expect("resolved files are embedded"));
        src.push('\n');
    }
    src.push_str(KERNEL);
    src
}

/// The entry points of the test kernel (one: the form the stages use).
const ENTRY_POINTS: [&str; 1] = ["main_blocks"];

/// The compiled kernel: one pipeline per entry point.
struct Kernel {
    dev: GpuDevice,
    /// The kernel's one bind group: bindings 0-4 read, 5 written (`KERNEL`).
    bindings: wgpu::BindGroupLayout,
    pipelines: Vec<(&'static str, wgpu::ComputePipeline)>,
}

/// The layout of the kernel's bind group, spelled out: a module built from SPIR-V carries no
/// bindings for wgpu to derive one from.
fn kernel_bindings(d: &wgpu::Device) -> wgpu::BindGroupLayout {
    let entries: Vec<wgpu::BindGroupLayoutEntry> = (0u32..6)
        .map(|binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage {
                    read_only: binding < 5,
                },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        })
        .collect();
    d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("gpu_orca"),
        entries: &entries,
    })
}

impl Kernel {
    fn new(dev: GpuDevice) -> Self {
        let source = kernel_source();
        let bindings = kernel_bindings(&dev.device);
        let layout = dev
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("gpu_orca"),
                bind_group_layouts: &[Some(&bindings)],
                immediate_size: 0,
            });
        let pipelines = ENTRY_POINTS
            .iter()
            .map(|&entry| {
                // Built as the stages' modules are (on Vulkan, socnav's SPIR-V: no multiply-add
                // fused), so that the kernel runs the ORCA code the stages run.
                let module = dev
                    .compute_module("gpu_orca", &source, entry)
                    .unwrap_or_else(|e| panic!("the test kernel's {entry}: {e}"));
                let p = dev
                    .device
                    .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(entry),
                        layout: Some(&layout),
                        module: &module,
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
                        cache: None,
                    });
                // Each entry point checked on its own, so that a driver that cannot compile
                // one (and loses the device) names it.
                if let Err(e) = dev.take_errors() {
                    panic!(
                        "the test kernel's entry point {entry} compiles on {}: {e}",
                        dev.adapter
                    );
                }
                (entry, p)
            })
            .collect();
        Self {
            dev,
            bindings,
            pipelines,
        }
    }

    /// Runs entry point `entry` over every agent of `batch`; returns [`OUT`] words per agent.
    fn run(&self, entry: &str, batch: &Batch) -> Vec<u32> {
        use wgpu::util::DeviceExt as _;
        let d = &self.dev.device;
        let (_, pipeline) = self
            .pipelines
            .iter()
            .find(|(e, _)| *e == entry)
            .expect("entry point");
        let storage = |label: &str, bytes: &[u8]| {
            // A binding may not be empty.
            let contents = if bytes.is_empty() {
                &[0u8; 4][..]
            } else {
                bytes
            };
            d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let n_agents = batch.agent_u.len() / 2;
        let out_bytes = (n_agents * OUT * 4) as u64;
        let inputs = [
            storage("scene_u", bytemuck::cast_slice(&batch.scene_u)),
            storage("agent_f", bytemuck::cast_slice(&batch.agent_f)),
            storage("agent_u", bytemuck::cast_slice(&batch.agent_u)),
            storage("vert_f", bytemuck::cast_slice(&batch.vert_f)),
            storage("vert_u", bytemuck::cast_slice(&batch.vert_u)),
        ];
        let out = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("out"),
            size: out_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: out_bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let entries: Vec<wgpu::BindGroupEntry<'_>> = inputs
            .iter()
            .chain([&out])
            .zip(0u32..)
            .map(|(buf, binding)| wgpu::BindGroupEntry {
                binding,
                resource: buf.as_entire_binding(),
            })
            .collect();
        let bind_group = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(entry),
            layout: &self.bindings,
            entries: &entries,
        });
        let mut enc =
            d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(entry) });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(entry),
                timestamp_writes: None,
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.dispatch_workgroups((n_agents as u32).div_ceil(64), 1, 1);
        }
        enc.copy_buffer_to_buffer(&out, 0, &readback, 0, out_bytes);
        self.dev.queue.submit([enc.finish()]);
        let slice = readback.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        d.poll(wgpu::PollType::wait_indefinitely())
            .expect("device poll");
        rx.recv().expect("map callback").expect("map readback");
        let words = {
            let view = slice.get_mapped_range().expect("mapped range");
            bytemuck::cast_slice::<u8, u32>(&view).to_vec()
        };
        readback.unmap();
        self.dev.take_errors().expect("no device errors");
        words
    }
}

// ---------------------------------------------------------------------------------------------
// Scenes, packed for the kernel, with the CPU's answers
// ---------------------------------------------------------------------------------------------

/// An obstacle polygon: vertices (m), counter-clockwise; 2 vertices make a two-sided segment.
type Polygon = Vec<[f32; 2]>;

/// One agent's position (m), velocity and preferred velocity (m/s) in a trajectory file.
type AgentState = ([f32; 2], [f32; 2], [f32; 2]);

/// FNV-1a over 32-bit words, as the kernel's `fnv`.
fn fnv(words: impl IntoIterator<Item = u32>) -> u32 {
    words
        .into_iter()
        .fold(2_166_136_261, |h, w| (h ^ w).wrapping_mul(16_777_619))
}

/// What the kernel writes per agent, computed on the CPU: velocity bits, LP3 used, overflow
/// (always 0 here), line count, obstacle line count, agent and obstacle neighbour counts, and
/// the hashes of the lines' bits, the obstacle neighbours' and the agent neighbours' indices.
type Expected = [u32; OUT];

const FIELDS: [&str; OUT] = [
    "velocity x",
    "velocity y",
    "used LP3",
    "overflow",
    "lines",
    "obstacle lines",
    "agent neighbours",
    "obstacle neighbours",
    "line bits",
    "obstacle neighbour order",
    "agent neighbour order",
];

/// Many scenes in the kernel's buffers, with the CPU's answer for every agent.
#[derive(Default)]
struct Batch {
    scene_u: Vec<u32>,
    agent_f: Vec<f32>,
    agent_u: Vec<u32>,
    vert_f: Vec<f32>,
    vert_u: Vec<u32>,
    expected: Vec<Expected>,
    /// (scene label, agent index in the scene) per agent.
    who: Vec<(String, usize)>,
    lp3: usize,
    obstacle_lines: usize,
    scenes: usize,
    scratch: OrcaScratch,
}

impl Batch {
    /// Adds a scene: packs it and solves every agent on the CPU (brute-force neighbours).
    fn add(&mut self, label: &str, agents: &[OrcaAgent], set: &ObstacleSet, time_step: f32) {
        let scene = (self.scene_u.len() / SCENE_U) as u32;
        let view = set.as_view();
        self.scene_u.extend([
            (self.agent_u.len() / 2) as u32,
            agents.len() as u32,
            (self.vert_f.len() / 4) as u32,
            view.len() as u32,
            time_step.to_bits(),
        ]);
        for i in 0..view.len() {
            self.vert_f
                .extend([view.x[i], view.y[i], view.dir_x[i], view.dir_y[i]]);
            self.vert_u
                .extend([view.next[i], view.prev[i], view.convex[i]]);
        }
        let xs: Vec<f32> = agents.iter().map(|a| a.pos[0]).collect();
        let ys: Vec<f32> = agents.iter().map(|a| a.pos[1]).collect();
        let mut nb = Vec::new();
        for (i, a) in agents.iter().enumerate() {
            let row: [f32; AGENT_F] = [
                a.pos[0],
                a.pos[1],
                a.vel[0],
                a.vel[1],
                a.pref_vel[0],
                a.pref_vel[1],
                a.radius,
                a.max_speed,
                a.neighbor_dist,
                a.time_horizon,
                a.time_horizon_obst,
                0.0,
            ];
            self.agent_f.extend(row);
            self.agent_u.extend([scene, a.max_neighbors]);

            agent_neighbors(i, &xs, &ys, a.neighbor_dist, a.max_neighbors, &mut nb);
            let gathered: Vec<OrcaNeighbor> = nb
                .iter()
                .map(|n| {
                    let o = &agents[n.index as usize];
                    OrcaNeighbor {
                        pos: o.pos,
                        vel: o.vel,
                        radius: o.radius,
                    }
                })
                .collect();
            let s = &mut self.scratch;
            let v = compute_new_velocity(a, &gathered, &view, time_step, s);
            let lines = s.lines();
            self.expected.push([
                v[0].to_bits(),
                v[1].to_bits(),
                u32::from(s.used_lp3()),
                0,
                lines.len() as u32,
                s.num_obstacle_lines() as u32,
                nb.len() as u32,
                s.obstacle_neighbors().len() as u32,
                fnv(lines.iter().flat_map(|l| {
                    [l.point.x, l.point.y, l.direction.x, l.direction.y].map(f32::to_bits)
                })),
                fnv(s.obstacle_neighbors().iter().map(|n| n.index)),
                fnv(nb.iter().map(|n| n.index)),
            ]);
            self.who.push((label.to_owned(), i));
            self.lp3 += usize::from(s.used_lp3());
            self.obstacle_lines += s.num_obstacle_lines();
        }
        self.scenes += 1;
    }

    fn agents(&self) -> usize {
        self.expected.len()
    }
}

fn obstacles(polygons: &[Polygon]) -> ObstacleSet {
    let mut set = ObstacleSet::new();
    process_obstacles(polygons, &mut ObstacleScratch::new(), &mut set).expect("valid obstacles");
    set
}

/// Whether an agent's result `got` is the CPU's `want` under `mode`: every word (`Parity::Exact`),
/// or the velocity within [`TOLERANCE`] and the same overflow flag (`Parity::Lockstep`).
fn agrees(want: &Expected, got: &[u32], mode: Parity) -> bool {
    match mode {
        Parity::Exact => want[..] == *got,
        Parity::Lockstep => {
            let close =
                |f: usize| floats_agree(f32::from_bits(want[f]), f32::from_bits(got[f]), TOLERANCE);
            close(0) && close(1) && want[3] == got[3]
        }
    }
}

/// Runs the entry points over `batch` and compares every agent with the CPU; panics listing
/// the first mismatches. `name` labels the printed counts.
fn check(kernel: &Kernel, name: &str, batch: &Batch) {
    assert!(batch.agents() > 0, "{name}: no agents");
    let mode = parity_mode(&kernel.dev.adapter);
    let mut report = String::new();
    let mut mismatches = 0;
    let mut nan = 0;
    for entry in ENTRY_POINTS {
        let got = kernel.run(entry, batch);
        assert_eq!(got.len(), batch.agents() * OUT, "{name}: output size");
        for (k, (want, got)) in batch.expected.iter().zip(got.chunks(OUT)).enumerate() {
            if agrees(want, got, mode) {
                nan += usize::from(f32::from_bits(want[0]).is_nan());
                continue;
            }
            mismatches += 1;
            if mismatches <= 40 {
                let (label, i) = &batch.who[k];
                let fields: Vec<String> = (0..OUT)
                    .filter(|&f| want[f] != got[f])
                    .map(|f| format!("{} cpu {:#x} gpu {:#x}", FIELDS[f], want[f], got[f]))
                    .collect();
                let _ = writeln!(
                    report,
                    "  {entry}: {label} agent {i} ({}): {}",
                    if want[2] == 1 { "LP3" } else { "LP2" },
                    fields.join("; ")
                );
            }
        }
    }
    println!(
        "{name}: {} scenes, {} agents x {} entry points compared on {}; LP3 for {} agents, {} \
         obstacle lines; {mismatches} mismatches; {nan} NaN velocities (equal bits)",
        batch.scenes,
        batch.agents(),
        ENTRY_POINTS.len(),
        kernel.dev.adapter,
        batch.lp3,
        batch.obstacle_lines,
    );
    let allowed = match mode {
        Parity::Exact => 0,
        Parity::Lockstep => (MAX_DIVERGED * (batch.agents() * ENTRY_POINTS.len()) as f64) as usize,
    };
    assert!(
        mismatches <= allowed,
        "{name}: {mismatches} agent results differ between the WGSL and the Rust ORCA core on \
         {} ({mode:?}; {allowed} allowed):\n{report}",
        kernel.dev.adapter
    );
}

// ---------------------------------------------------------------------------------------------
// Reference scenes (RVO2 2.0.3 data, as tests/suite/orca/reference.rs reads them)
// ---------------------------------------------------------------------------------------------

/// `(pos, vel, pref_vel)` per agent per step of a trajectory file.
fn states(t: &Table) -> BTreeMap<usize, Vec<AgentState>> {
    t.group_by("step")
        .into_iter()
        .map(|(step, rows)| {
            let states = rows
                .iter()
                .map(|r| {
                    let f = |n: &str| t.f32(r, n);
                    (
                        [f("px"), f("py")],
                        [f("vx"), f("vy")],
                        [f("pref_vx"), f("pref_vy")],
                    )
                })
                .collect();
            (step, states)
        })
        .collect()
}

/// The one-step cases: 2542 agents with random parameters, many among polygons.
fn add_onestep(batch: &mut Batch) {
    let t = Table::load("rvo2_onestep_obstacles.csv");
    let mut polygons: BTreeMap<usize, Vec<Polygon>> = BTreeMap::new();
    for r in &t.rows {
        let polys = polygons.entry(t.usize(r, "case")).or_default();
        let o = t.usize(r, "obstacle");
        if polys.len() <= o {
            polys.resize(o + 1, Vec::new());
        }
        polys[o].push([t.f32(r, "x"), t.f32(r, "y")]);
    }
    let t = Table::load("rvo2_onestep_agents.csv");
    for (case, rows) in t.group_by("case") {
        let agents: Vec<OrcaAgent> = rows
            .iter()
            .map(|r| {
                let f = |n: &str| t.f32(r, n);
                OrcaAgent {
                    pos: [f("px"), f("py")],
                    vel: [f("vx"), f("vy")],
                    pref_vel: [f("pref_vx"), f("pref_vy")],
                    radius: f("radius"),
                    max_speed: f("max_speed"),
                    neighbor_dist: f("neighbor_dist"),
                    max_neighbors: t.usize(r, "max_neighbors") as u32,
                    time_horizon: f("time_horizon"),
                    time_horizon_obst: f("time_horizon_obst"),
                }
            })
            .collect();
        let set = obstacles(polygons.get(&case).map_or(&[][..], Vec::as_slice));
        let dt = t.f32(rows[0], "time_step");
        batch.add(&format!("onestep case {case}"), &agents, &set, dt);
    }
}

/// The edge-split scenes of tests/data/orca_split_reference.txt (polygons whose tree build
/// splits edges).
fn add_split_scenes(batch: &mut Batch) {
    let text = include_str!("../../data/orca_split_reference.txt");
    let f = |s: &str| s.parse::<f32>().expect("f32");
    let mut scenes: Vec<(Vec<Polygon>, Vec<OrcaAgent>)> = Vec::new();
    for line in text.lines() {
        let c: Vec<&str> = line.split(',').collect();
        match c[0] {
            "scene" => scenes.push(Default::default()),
            "polygon" => {
                let xy: Vec<f32> = c[2..].iter().map(|s| f(s)).collect();
                let scene = scenes.last_mut().expect("scene header first");
                scene.0.push(xy.chunks(2).map(|p| [p[0], p[1]]).collect());
            }
            "agent" => {
                let v: Vec<f32> = c[2..11].iter().map(|s| f(s)).collect();
                let scene = scenes.last_mut().expect("scene header first");
                scene.1.push(OrcaAgent {
                    pos: [v[0], v[1]],
                    vel: [v[2], v[3]],
                    pref_vel: [v[4], v[5]],
                    radius: v[6],
                    max_speed: v[7],
                    neighbor_dist: v[8],
                    max_neighbors: c[11].parse().expect("u32"),
                    time_horizon: f(c[12]),
                    time_horizon_obst: f(c[13]),
                });
            }
            _ => {}
        }
    }
    assert_eq!(scenes.len(), 13);
    for (s, (polygons, agents)) in scenes.iter().enumerate() {
        batch.add(
            &format!("split scene {s}"),
            agents,
            &obstacles(polygons),
            0.25,
        );
    }
}

/// The pedestrian-scale agent of crossing4 and corridor.
fn pedestrian(pos: [f32; 2], vel: [f32; 2], pref_vel: [f32; 2]) -> OrcaAgent {
    OrcaAgent {
        pos,
        vel,
        pref_vel,
        radius: 0.3,
        max_speed: 1.0,
        neighbor_dist: 10.0,
        max_neighbors: 10,
        time_horizon: 5.0,
        time_horizon_obst: 5.0,
    }
}

/// Every state of a trajectory file as a scene.
fn add_trajectory(
    batch: &mut Batch,
    name: &str,
    polygons: &[Polygon],
    agent: fn([f32; 2], [f32; 2], [f32; 2]) -> OrcaAgent,
) {
    let set = obstacles(polygons);
    for (step, states) in states(&Table::load(name)) {
        let agents: Vec<OrcaAgent> = states.iter().map(|&(p, v, pv)| agent(p, v, pv)).collect();
        batch.add(&format!("{name} step {step}"), &agents, &set, 0.25);
    }
}

/// The RVO2 Circle example's agent (Circle250).
fn circle250(pos: [f32; 2], vel: [f32; 2], pref_vel: [f32; 2]) -> OrcaAgent {
    OrcaAgent {
        radius: 1.5,
        max_speed: 2.0,
        neighbor_dist: 15.0,
        time_horizon: 10.0,
        time_horizon_obst: 10.0,
        ..pedestrian(pos, vel, pref_vel)
    }
}

/// Contract: on RVO2's reference scenes the WGSL core gives the Rust core's bits for every
/// agent: velocity, LP3 path, neighbour lists in order and every ORCA line.
#[test]
fn reference_scenes_bit_identical() {
    if !common::reference::present("reference_scenes_bit_identical") {
        return;
    }
    let Some(dev) = device() else { return };
    let kernel = Kernel::new(dev);

    let mut batch = Batch::default();
    add_onestep(&mut batch);
    check(&kernel, "one-step cases", &batch);

    let mut batch = Batch::default();
    add_split_scenes(&mut batch);
    add_trajectory(&mut batch, "rvo2_crossing4.csv", &[], pedestrian);
    add_trajectory(&mut batch, "rvo2_crossing4_perturbed.csv", &[], pedestrian);
    let walls = [
        vec![[-10.0, 1.5], [10.0, 1.5]],
        vec![[10.0, -1.5], [-10.0, -1.5]],
    ];
    add_trajectory(&mut batch, "rvo2_corridor.csv", &walls, pedestrian);
    check(&kernel, "split scenes, crossing4, corridor", &batch);

    let mut batch = Batch::default();
    add_trajectory(&mut batch, "rvo2_circle250_sampled.csv.gz", &[], circle250);
    // The published data's sampled states; other data sets of the format hold their own.
    assert!(
        batch.agents() >= 170_000 || !common::reference::is_own_copy(),
        "{} agents",
        batch.agents()
    );
    check(&kernel, "circle250 sampled states", &batch);
}

// ---------------------------------------------------------------------------------------------
// Random scenes
// ---------------------------------------------------------------------------------------------

/// A point uniform in the square of half-side `h` around the origin.
fn point(rng: &mut RngStream, h: f32) -> [f32; 2] {
    [rng.uniform(-h, h), rng.uniform(-h, h)]
}

/// A vector of length up to `len` in a uniform direction.
fn vector(rng: &mut RngStream, len: f32) -> [f32; 2] {
    let (s, c) = socnav::math::sin_cos(rng.uniform(0.0, socnav::math::TAU));
    let l = rng.uniform(0.0, len);
    [l * c, l * s]
}

/// A random obstacle around a point of the square of half-side `h`: a star-shaped polygon
/// (often non-convex), a rotated rectangle or a two-sided segment, counter-clockwise.
fn polygon(rng: &mut RngStream, h: f32) -> Polygon {
    let c = point(rng, h);
    let kind = rng.below(3);
    if kind == 2 {
        let d = vector(rng, 3.0);
        return vec![c, [c[0] + d[0] + 0.05, c[1] + d[1]]];
    }
    let (n, star) = if kind == 0 {
        (rng.randint(3, 8) as usize, true)
    } else {
        (4, false)
    };
    let (hx, hy) = (rng.uniform(0.1, 1.5), rng.uniform(0.1, 1.5));
    let theta0 = rng.uniform(0.0, socnav::math::TAU);
    (0..n)
        .map(|k| {
            let (x, y) = if star {
                let a = (k as f32 + rng.uniform(0.15, 0.85)) * socnav::math::TAU / n as f32;
                let r = rng.uniform(0.15, 1.5);
                let (s, c) = socnav::math::sin_cos(a);
                (r * c, r * s)
            } else {
                let corners = [(hx, -hy), (hx, hy), (-hx, hy), (-hx, -hy)];
                corners[k]
            };
            let (s, co) = socnav::math::sin_cos(theta0);
            [c[0] + x * co - y * s, c[1] + x * s + y * co]
        })
        .collect()
}

/// Scene `k` of a seeded family: every fourth one crowded (agents overlapping, LP3 often), one
/// in four obstacle-heavy (agents among and inside overlapping polygons); parameters, speeds and
/// time steps vary widely, and some agents have `max_neighbors` 0.
fn random_scene(rng: &mut RngStream, k: usize) -> (Vec<OrcaAgent>, Vec<Polygon>, f32) {
    let (h, n_agents, n_polygons) = match k % 4 {
        0 => (6.0, rng.randint(1, 16), rng.randint(0, 4)),
        1 => (1.5, rng.randint(6, 30), rng.randint(0, 3)),
        2 => (3.0, rng.randint(2, 12), rng.randint(3, 8)),
        _ => (4.0, rng.randint(2, 20), rng.randint(1, 5)),
    };
    let polygons: Vec<Polygon> = (0..n_polygons).map(|_| polygon(rng, h)).collect();
    let agents = (0..n_agents)
        .map(|_| {
            let max_speed = rng.uniform(0.1, 2.0);
            OrcaAgent {
                pos: point(rng, h),
                vel: vector(rng, 1.3 * max_speed),
                pref_vel: vector(rng, 2.0 * max_speed),
                radius: rng.uniform(0.1, 0.6),
                max_speed,
                neighbor_dist: rng.uniform(0.5, 12.0),
                max_neighbors: if rng.chance(0.1) {
                    0
                } else {
                    rng.randint(1, 20) as u32
                },
                time_horizon: rng.uniform(0.3, 8.0),
                time_horizon_obst: rng.uniform(0.3, 8.0),
            }
        })
        .collect();
    (agents, polygons, rng.uniform(0.05, 0.5))
}

/// A scene on a lattice: agents on distinct points of a 0.5 m grid, axis-aligned velocities,
/// preferred velocities towards the centre, squares and segments on the grid shifted by 0.25 m.
/// Exact coordinates make exact ties (neighbour order), touching discs (`dist_sq ==
/// combined_radius_sq`), parallel and opposite lines in the linear programs and zero components.
fn lattice_scene(rng: &mut RngStream) -> (Vec<OrcaAgent>, Vec<Polygon>, f32) {
    let mut free: Vec<[f32; 2]> = (-4..=4)
        .flat_map(|i| (-4..=4).map(move |j| [i as f32 * 0.5, j as f32 * 0.5]))
        .collect();
    let velocities = [
        [0.0, 0.0],
        [0.5, 0.0],
        [-0.5, 0.0],
        [0.0, 0.5],
        [0.0, -0.5],
        [0.25, 0.25],
    ];
    let radius = [0.2, 0.25, 0.3][rng.below(3) as usize];
    let agents = (0..rng.randint(2, 16))
        .map(|_| {
            let pos = free.swap_remove(rng.below(free.len() as u32) as usize);
            OrcaAgent {
                pos,
                vel: velocities[rng.below(velocities.len() as u32) as usize],
                pref_vel: [-0.5 * pos[0], -0.5 * pos[1]],
                radius,
                max_speed: 1.0,
                neighbor_dist: [2.0, 10.0][rng.below(2) as usize],
                max_neighbors: 10,
                time_horizon: 2.0,
                time_horizon_obst: 2.0,
            }
        })
        .collect();
    let polygons = (0..rng.randint(0, 3))
        .map(|_| {
            let x = rng.randint(-4, 3) as f32 * 0.5 + 0.25;
            let y = rng.randint(-4, 3) as f32 * 0.5 + 0.25;
            let w = [0.5, 1.0][rng.below(2) as usize];
            if rng.chance(0.3) {
                vec![[x, y], [x + w, y]]
            } else {
                vec![[x, y], [x + w, y], [x + w, y + w], [x, y + w]]
            }
        })
        .collect();
    (agents, polygons, 0.25)
}

/// Contract: on thousands of random scenes (agents among polygon obstacles, crowds that force
/// LP3, edge splits) the WGSL core gives the Rust core's bits for every agent.
#[test]
fn random_scenes_bit_identical() {
    let Some(dev) = device() else { return };
    let kernel = Kernel::new(dev);
    let mut rng = RngStream::new(2024, 7);
    let mut batch = Batch::default();
    for k in 0..20000 {
        let (agents, polygons, dt) = random_scene(&mut rng, k);
        batch.add(
            &format!("random scene {k}"),
            &agents,
            &obstacles(&polygons),
            dt,
        );
    }
    for k in 0..5000 {
        let (agents, polygons, dt) = lattice_scene(&mut rng);
        batch.add(
            &format!("lattice scene {k}"),
            &agents,
            &obstacles(&polygons),
            dt,
        );
    }
    assert!(
        batch.lp3 >= 20_000 && batch.obstacle_lines >= 100_000,
        "the random scenes exercise LP3 ({}) and obstacle lines ({})",
        batch.lp3,
        batch.obstacle_lines
    );
    check(&kernel, "random scenes", &batch);
}

/// Past the library's list limits the result is flagged instead of silently differing: an
/// agent with more neighbours in range than ORCA_MAX_AGENT_NEIGHBORS (64) allows.
#[test]
fn list_limits_are_flagged() {
    let Some(dev) = device() else { return };
    let kernel = Kernel::new(dev);
    let mut batch = Batch::default();
    let agents: Vec<OrcaAgent> = (0..80)
        .map(|i| OrcaAgent {
            max_neighbors: if i == 0 { 79 } else { 10 },
            neighbor_dist: 15.0,
            ..pedestrian([(i % 10) as f32, (i / 10) as f32], [0.0, 0.0], [1.0, 0.0])
        })
        .collect();
    batch.add("crowd of 80", &agents, &ObstacleSet::new(), 0.25);
    for entry in ENTRY_POINTS {
        let got = kernel.run(entry, &batch);
        let overflow: Vec<u32> = got.chunks(OUT).map(|o| o[3]).collect();
        assert_eq!(
            overflow[0], 1,
            "{entry}: agent 0 (79 neighbours) is flagged"
        );
        assert!(
            overflow[1..].iter().all(|&o| o == 0),
            "{entry}: agents with 10 neighbours are not flagged"
        );
        // Within the limits, the results are the CPU's (within rounding off lavapipe).
        let mode = parity_mode(&kernel.dev.adapter);
        for (k, (want, got)) in batch
            .expected
            .iter()
            .zip(got.chunks(OUT))
            .enumerate()
            .skip(1)
        {
            assert!(
                agrees(want, got, mode),
                "{entry}: agent {k} ({mode:?}): cpu {want:x?} gpu {got:x?}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The shipped configs against the list limits
// ---------------------------------------------------------------------------------------------

/// The shipped configs whose capacities are checked against the ORCA list limits.
const CONFIGS: [&str; 5] = ["exp1", "exp2", "exp3", "lroom_mixed", "corridor_mixed"];

/// Contract: the capacities of every shipped config keep the agent neighbour list of
/// `common/orca_world.wgsl` within its limit (every human and group plus the robot fit), so it
/// never overflows. The obstacle neighbour list is bounded by the edges within the obstacle range
/// of one agent, not by the capacities: where the vertex capacity exceeds its limit (the configs
/// listed here) an overflow is possible in principle, and the shaders would then write NaN (a
/// loud difference from the CPU, never a silent one).
#[test]
fn shipped_capacities_fit_the_orca_lists() {
    const ORCA_MAX_AGENT_NEIGHBORS: usize = 64;
    const ORCA_MAX_OBSTACLE_NEIGHBORS: usize = 128;
    let src = socnav::backend::wgsl::source("common/orca.wgsl").expect("embedded");
    assert!(src.contains("const ORCA_MAX_AGENT_NEIGHBORS: u32 = 64u;"));
    assert!(src.contains("const ORCA_MAX_OBSTACLE_NEIGHBORS: u32 = 128u;"));
    let mut unbounded = Vec::new();
    for name in CONFIGS.iter().chain(&["stress"]) {
        let caps = Caps::from_config(&config(name));
        println!("{name}: {caps:?}");
        assert!(
            caps.humans + caps.groups < ORCA_MAX_AGENT_NEIGHBORS,
            "{name}: {caps:?}"
        );
        if caps.obstacle_vertices > ORCA_MAX_OBSTACLE_NEIGHBORS {
            unbounded.push(*name);
        }
    }
    assert_eq!(unbounded, OBSTACLE_LIST_NOT_BOUNDED_BY_CAPS);
}

/// The shipped configs whose obstacle vertex capacity exceeds ORCA_MAX_OBSTACLE_NEIGHBORS.
const OBSTACLE_LIST_NOT_BOUNDED_BY_CAPS: &[&str] = &["lroom_mixed", "corridor_mixed", "stress"];
