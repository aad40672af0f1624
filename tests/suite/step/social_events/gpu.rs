//! CPU/GPU parity of the social-structure stages (`social_events`, `formation`) and of the
//! libraries under them (`common/regroup.wgsl`: the slot sorts, permutations and remapping;
//! `common/orca_obstacles.wgsl`: the ORCA obstacle rebuild with RVO2's edge splits;
//! `common/goal_sampling.wgsl`, `common/place.wgsl`): from the same state, parameters and actions, both
//! backends must leave every state and output column bit-identical on lavapipe.
//!
//! States are rolled out on the CPU with raised event probabilities, then perturbed before every
//! run (new tick, so new draws; formations cleared, started, brought to their slots or held
//! together; spawn areas blocked) and uploaded as the GPU's. The processed obstacle columns are
//! overwritten with garbage before each run, so an environment that regroups must rebuild them on
//! the GPU exactly as on the CPU. The CPU side counts every event kind and the rebuilds that split
//! edges, and the tests require each to have happened.
//!
//! This module holds the harness of both stages and `social_events`'s test; `formation`'s is in
//! `step/formation.rs`.

use crate::common;

use common::gpu::*;
use socnav::backend::gpu::GpuStages;
use socnav::outputs::Outputs;
use socnav::rng::RngStream;
use socnav::spec::{EVENT_KEYS, N_EVENTS, event};
use socnav::state::{BatchState, forming, role};
use socnav::systems::orca_obstacles;
use socnav::{Config, StepParams};

/// What the CPU side saw over the runs.
#[derive(Default, Debug)]
pub(crate) struct Seen {
    pub(crate) events: [usize; N_EVENTS],
    /// Obstacle rebuilds (environments whose `ov_*` columns were rewritten) ...
    pub(crate) rebuilds: usize,
    /// ... of which produced split vertices.
    pub(crate) rebuilds_with_splits: usize,
    /// The most rebuilds in one run.
    pub(crate) most_rebuilds_in_a_run: usize,
    /// Rebuilds whose processed set did not fit the capacity (`obstacles_dirty` left at
    /// `orca_obstacles::OBSTACLES_FAILED`).
    pub(crate) failed_rebuilds: usize,
}

/// `name` with every event probability set to `prob` (and its capacities grown to match).
pub(crate) fn eventful(name: &str, prob: f32) -> Config {
    let mut c = config(name);
    c.events.crowd_dispersal_probability = prob;
    c.events.laptop_dispersal_probability = prob;
    c.events.crowd_formation_probability = prob;
    c.events.laptop_formation_probability = prob;
    c
}

/// A marker in the obstacle columns: a rebuild overwrites it.
const GARBAGE: f32 = -1234.5;

/// Overwrite every processed obstacle column with garbage (see the module docs).
fn scramble_obstacles(s: &mut BatchState, rng: &mut RngStream) {
    for v in s.ov_x.iter_mut() {
        *v = GARBAGE;
    }
    for v in s.ov_y.iter_mut() {
        *v = uniform(rng, -5.0, 5.0);
    }
    for v in s.ov_dir_x.iter_mut().chain(s.ov_dir_y.iter_mut()) {
        *v = uniform(rng, -1.0, 1.0);
    }
    for v in s.ov_next.iter_mut().chain(s.ov_prev.iter_mut()) {
        *v = rng.next_u32() % 7;
    }
    for v in s.ov_convex.iter_mut() {
        *v = rng.next_u32() % 2;
    }
}

/// No formation in progress in environment `e` (its walkers become ordinary walkers).
fn clear_formations(s: &mut BatchState, e: usize) {
    let mut ch = s.env_chunk(e);
    socnav::systems::formation::clear_crowd_formation(&mut ch, 0);
    socnav::systems::formation::clear_laptop_formation(&mut ch, 0);
    let hb = e * s.strides.humans;
    for i in hb..hb + s.n_humans[e] as usize {
        s.h_forming[i] = forming::NONE;
    }
}

/// Local slots of the free lone walkers of environment `e`.
pub(crate) fn free_walkers(s: &BatchState, e: usize) -> Vec<u32> {
    let hb = e * s.strides.humans;
    (0..s.n_humans[e])
        .filter(|&k| {
            let i = hb + k as usize;
            s.h_role[i] == role::DYNAMIC && s.h_forming[i] == forming::NONE
        })
        .collect()
}

/// Common part of the perturbations: a new tick (new draws), most environments stepping and not
/// done, and the obstacle columns scrambled.
pub(crate) fn next_run(s: &mut BatchState, rng: &mut RngStream) {
    for e in 0..s.n_envs {
        s.tick[e] += 1;
        s.stepping[e] = u32::from(rng.next_f32() < 0.95);
        s.done[e] = u32::from(rng.next_f32() < 0.05);
    }
    scramble_obstacles(s, rng);
}

/// For `social_events`: formations cleared in a third of the environments (so that new ones can
/// start).
///
/// Not covered: a sampler that exhausts its 2000 tries (a crowd formation that gives up, a
/// dispersed walker that keeps its goal because no spot is free). On lavapipe that cannot be
/// bit-identical: llvmpipe (Mesa 22.3, `LP_MAX_TGSI_LOOP_ITERATIONS`) ends every loop of an
/// invocation once 65535 loop iterations have run in it (one budget for all the loops of the
/// shader, shared by the lanes of a SIMD batch), and 2000 tries over the room's entities exceed it.
/// (Blocking every spot with a room-sized spawn blocker showed it: every loop after the sampler
/// ran once.) Hardware drivers have no such limit.
fn perturb_events(s: &mut BatchState, _: &mut Outputs, _: &StepParams, rng: &mut RngStream) {
    next_run(s, rng);
    for e in 0..s.n_envs {
        if rng.next_f32() < 0.35 {
            clear_formations(s, e);
        }
    }
}

/// Run `stage` `runs` times on both backends from the rolled-out state of `config`, perturbing
/// and uploading the CPU's state before each run, comparing every column after it; what the CPU
/// side saw, or `None` without a device.
pub(crate) fn parity(
    stage: &'static str,
    config: Config,
    n_envs: usize,
    runs: usize,
    perturb: Perturb,
) -> Option<Seen> {
    parity_on(device()?, stage, config, n_envs, runs, perturb)
}

/// [`parity`] on device `dev`.
pub(crate) fn parity_on(
    dev: socnav::backend::gpu::GpuDevice,
    stage: &'static str,
    config: Config,
    n_envs: usize,
    runs: usize,
    perturb: Perturb,
) -> Option<Seen> {
    let env = rolled_out(config, n_envs, 40);
    let p = *env.params();
    let mut cpu = env.state().unwrap().clone();
    let mut cpu_out = env.outputs().clone();
    let mut gpu = GpuStages::new(dev, &p, &cpu, &cpu_out, &[stage]).expect("GPU stages");
    let mut from_gpu = cpu.clone();
    let mut from_gpu_out = cpu_out.clone();
    let mut rng = RngStream::new(9, 2);
    let mut seen = Seen::default();
    let mode = parity_mode(gpu.adapter());
    let mut lockstep = Lockstep::default();
    for run in 0..runs {
        perturb(&mut cpu, &mut cpu_out, &p, &mut rng);
        gpu.upload_state(&cpu);
        gpu.upload_outputs(&cpu_out);
        let before = cpu_out.events.clone();
        let actions = random_actions(&mut rng, n_envs, p.holonomic != 0);
        cpu_stage(stage, &p, &mut cpu, &mut cpu_out, &actions);
        gpu.upload_actions(&actions);
        gpu.run(stage).expect("GPU stage");
        gpu.download_state(&mut from_gpu).expect("readback");
        gpu.download_outputs(&mut from_gpu_out).expect("readback");
        for (k, (a, b)) in cpu_out.events.iter().zip(&before).enumerate() {
            seen.events[k % N_EVENTS] += (a - b) as usize;
        }
        let cap = cpu.strides.obstacle_vertices;
        let mut chunk = cpu.clone();
        let chunk = chunk.chunk();
        let mut rebuilds = 0;
        for e in 0..n_envs {
            if cap > 0 && cpu.ov_x[e * cap] != GARBAGE {
                rebuilds += 1;
                let mut inputs = 0;
                orca_obstacles::for_each_polygon(&p, &chunk, e, |_, _| inputs += 4);
                seen.rebuilds_with_splits += usize::from(cpu.n_obstacle_vertices[e] > inputs);
                seen.failed_rebuilds +=
                    usize::from(cpu.obstacles_dirty[e] == orca_obstacles::OBSTACLES_FAILED);
            }
        }
        seen.rebuilds += rebuilds;
        seen.most_rebuilds_in_a_run = seen.most_rebuilds_in_a_run.max(rebuilds);
        if mode == Parity::Lockstep {
            lockstep.add(n_envs, (&cpu, &from_gpu), Some((&cpu_out, &from_gpu_out)));
            continue;
        }
        let differ_envs: Vec<usize> = (0..n_envs)
            .filter(|&e| cpu.fingerprint_env(e, 0) != from_gpu.fingerprint_env(e, 0))
            .collect();
        let differ = cpu.differing_columns(&from_gpu);
        let differ_out = cpu_out.differing_columns(&from_gpu_out);
        assert!(
            differ.is_empty() && differ_out.is_empty(),
            "{stage} on {}, run {run}: state columns {differ:?} and output columns {differ_out:?} \
             differ between CPU and GPU in environments {differ_envs:?}; first differences: {}; {}",
            gpu.adapter(),
            first_differences(
                &cpu.columns(),
                |f, u| cpu.pack(f, u),
                |f, u| from_gpu.pack(f, u)
            ),
            first_differences(
                &cpu_out.columns(),
                |f, u| cpu_out.pack(f, u),
                |f, u| from_gpu_out.pack(f, u)
            ),
        );
    }
    if mode == Parity::Lockstep {
        lockstep.check(stage, gpu.adapter());
        println!("{stage}: {seen:?}");
        return Some(seen);
    }
    println!(
        "{stage}: {runs} runs over {n_envs} environments bit-identical on {}; {seen:?}",
        gpu.adapter()
    );
    Some(seen)
}

/// Whether config `name` runs: all of them, unless `GPU_SOCIAL_ONLY` names one (for debugging;
/// the coverage assertions then do not apply).
pub(crate) fn selected(name: &str) -> bool {
    std::env::var("GPU_SOCIAL_ONLY").map_or(true, |only| only == name)
}

pub(crate) fn add(total: &mut Seen, s: Seen) {
    for (t, n) in total.events.iter_mut().zip(s.events) {
        *t += n;
    }
    total.rebuilds += s.rebuilds;
    total.rebuilds_with_splits += s.rebuilds_with_splits;
    total.most_rebuilds_in_a_run = total.most_rebuilds_in_a_run.max(s.most_rebuilds_in_a_run);
    total.failed_rebuilds += s.failed_rebuilds;
}

/// [`perturb_events`], and every environment's tables laid across each other at the room's
/// centre, a star: their edges split each other's (and the walls') more often than the
/// config's obstacle capacity allows for.
fn perturb_into_a_star(s: &mut BatchState, o: &mut Outputs, p: &StepParams, rng: &mut RngStream) {
    perturb_events(s, o, p, rng);
    for e in 0..s.n_envs {
        let n = s.n_tables[e] as usize;
        for k in 0..n {
            let t = e * s.strides.tables + k;
            let theta = 0.1 + k as f32 * std::f32::consts::PI / n as f32;
            let (sin, cos) = socnav::math::sin_cos(theta);
            (s.t_x[t], s.t_y[t], s.t_theta[t], s.t_sin[t], s.t_cos[t]) =
                (0.0, 0.0, theta, sin, cos);
        }
    }
}

/// Contract: a regrouping's obstacle rebuild whose processed set does not fit the capacity (a
/// state with tables across each other, such as `BatchEnv::set_state` now refuses, but a state
/// edited through `state_mut` can hold) leaves on the device what it leaves on the CPU, bit for
/// bit: every slot of the capacity NaN in one ring, the count at the capacity, the flag at
/// `OBSTACLES_FAILED`. In one lane and on a workgroup's lanes
/// (`GpuPaths::obstacles_in_workgroups`), with the dispersals and formations of exp2 with seven
/// tables and standing groups that disperse.
#[test]
fn a_rebuild_beyond_the_capacity_poisons_as_the_cpu() {
    let Some(dev) = device() else { return };
    let mut c = eventful("exp2", 0.5);
    c.counts.tables = [7, 7];
    c.counts.laptops = [0, 0];
    c.counts.dynamic_humans = [3, 3];
    c.counts.standing_groups = [1, 1];
    c.counts.standing_groups_non_dispersing = [0, 0];
    for in_workgroups in [false, true] {
        let mut d = dev.clone();
        d.paths.obstacles_in_workgroups = in_workgroups;
        let seen = parity_on(d, "social_events", c.clone(), 32, 8, perturb_into_a_star);
        let seen = seen.expect("a device");
        assert!(
            seen.failed_rebuilds > 0,
            "in workgroups: {in_workgroups}: {seen:?}"
        );
    }
}

/// Contract: the obstacle rebuilds after a regrouping give the same bits with their working
/// memory in workgroup memory, a workgroup at a time (`GpuPaths::obstacles_in_workgroups`,
/// the hardware adapters' way), as the CPU's: `formation` in exp3 and `social_events` in stress
/// (the largest obstacle region). That memory is not zeroed (`backend::gpu::spirv`), so it is
/// poisoned before every rebuild here (`GpuPaths::poison_orca_lists`): a word read before it is
/// written would change the result. exp3 runs twice: with a workgroup per environment, and with
/// 64 workgroups in all (`GpuPaths::rebuild_workgroups`), each rebuilding every 64th queued
/// environment in turn (two or three each here), as a batch with more rebuilds in a step than that
/// bound does on hardware. (Not fewer: llvmpipe ends an invocation's loops after 65,535
/// iterations in all, about 18 of exp3's rebuilds; a GPU has no such limit.)
#[test]
fn rebuilds_in_workgroup_memory_match_the_cpu() {
    let Some(mut dev) = device() else { return };
    dev.paths.obstacles_in_workgroups = true;
    dev.paths.poison_orca_lists = true;
    let mut total = Seen::default();
    let mut exp3 = eventful("exp3", 0.3);
    exp3.episode.time_step = 0.3;
    let perturb = crate::step::formation::perturb_formation;
    let seen = parity_on(dev.clone(), "formation", exp3.clone(), 256, 6, perturb);
    add(&mut total, seen.expect("a device"));
    let mut few = dev.clone();
    few.paths.rebuild_workgroups = 64;
    let seen = parity_on(few, "formation", exp3, 256, 6, perturb);
    let seen = seen.expect("a device");
    assert!(
        seen.most_rebuilds_in_a_run > 64,
        "{seen:?}: too few rebuilds in a run for 64 workgroups to take several each"
    );
    add(&mut total, seen);
    let stress = eventful("stress", 0.5);
    let seen = parity_on(dev, "social_events", stress, 64, 6, perturb_events);
    add(&mut total, seen.expect("a device"));
    assert!(
        total.rebuilds > 0 && total.rebuilds_with_splits > 0,
        "{total:?}"
    );
}

/// Contract: the regroupings of `formation` and `social_events` give the same bits with each
/// queued environment on all the lanes of a workgroup (`GpuPaths::regroups_in_workgroups`, the
/// hardware adapters' way: lane 0 runs the pass's logic, every lane takes slots of the four
/// kinds' sorts and permutations, the remaps and the list positions), as the CPU's: crowd and
/// laptop-use formations completing in exp3, and the dispersals of exp3, corridor_mixed (the
/// largest crowds) and stress. The one-lane way is lavapipe's default, which the other parity
/// tests take.
#[test]
fn regroupings_on_a_workgroups_lanes_match_the_cpu() {
    let Some(mut dev) = device() else { return };
    dev.paths.regroups_in_workgroups = true;
    let mut exp3 = eventful("exp3", 0.3);
    exp3.episode.time_step = 0.3;
    let perturb = crate::step::formation::perturb_formation;
    let formed = parity_on(dev.clone(), "formation", exp3, 256, 6, perturb).expect("a device");
    assert!(
        formed.events[event::CROWD_FORMATION_COMPLETE] > 0
            && formed.events[event::LAPTOP_FORMATION_COMPLETE] > 0,
        "{formed:?}"
    );
    let mut total = Seen::default();
    for (name, n) in [("exp3", 256), ("corridor_mixed", 256), ("stress", 64)] {
        let seen = parity_on(
            dev.clone(),
            "social_events",
            eventful(name, 0.5),
            n,
            6,
            perturb_events,
        );
        add(&mut total, seen.expect("a device"));
    }
    assert!(
        total.events[event::CROWD_DISPERSAL] > 0 && total.events[event::LAPTOP_DISPERSAL] > 0,
        "{total:?}"
    );
}

/// Contract: `social_events` (dispersal of standing and moving groups, with and without
/// dissolution; laptop-use dispersal; crowd and laptop-use formation starts, and laptop-use
/// formations blocked; the regrouping and obstacle rebuild after each; see `perturb_events` for
/// what lavapipe cannot cover) in square, L-shaped and corridor rooms
/// and the stress config, one at dt = 0.3 s.
#[test]
fn social_events_parity() {
    let mut total = Seen::default();
    let mut exp3 = eventful("exp3", 0.5);
    exp3.episode.time_step = 0.3;
    let configs = [
        ("exp2", eventful("exp2", 0.5), 256),
        ("exp3", exp3, 256),
        ("lroom_mixed", eventful("lroom_mixed", 0.5), 256),
        ("corridor_mixed", eventful("corridor_mixed", 0.5), 256),
        ("stress", eventful("stress", 0.5), 256),
    ];
    for (name, c, n) in configs {
        if !selected(name) {
            continue;
        }
        let Some(seen) = parity("social_events", c, n, 12, perturb_events) else {
            return;
        };
        add(&mut total, seen);
    }
    println!("social_events overall: {total:?}");
    if std::env::var("GPU_SOCIAL_ONLY").is_ok() {
        return;
    }
    for k in [
        event::CROWD_DISPERSAL,
        event::LAPTOP_DISPERSAL,
        event::CROWD_FORMATION_START,
        event::LAPTOP_FORMATION_START,
        event::LAPTOP_FORMATION_BLOCKED,
    ] {
        assert!(total.events[k] > 0, "{} never happened", EVENT_KEYS[k]);
    }
    assert!(
        total.rebuilds > 0 && total.rebuilds_with_splits > 0,
        "{total:?}"
    );
}

/// The environments whose obstacles a CPU stage rebuilt: those whose first obstacle vertex is no
/// longer the marker the state was given (`scramble_obstacles`).
fn rebuilt_envs(s: &BatchState) -> Vec<u32> {
    let cap = s.strides.obstacle_vertices;
    (0..s.n_envs)
        .filter(|&e| cap > 0 && s.ov_x[e * cap] != GARBAGE)
        .map(|e| e as u32)
        .collect()
}

/// Zero the obstacle slots past each environment's count, as every real state holds them
/// (`crate::state`), which `scramble_obstacles` does not: a rebuild zeroes only the slots from its
/// set's end to the old count, so two rebuilds in a row leave what one does only where the slots
/// past the count hold zeros.
fn zero_unused_obstacle_slots(s: &mut BatchState) {
    let cap = s.strides.obstacle_vertices;
    for e in 0..s.n_envs {
        for i in e * cap + s.n_obstacle_vertices[e] as usize..(e + 1) * cap {
            s.ov_x[i] = 0.0;
            s.ov_y[i] = 0.0;
            s.ov_dir_x[i] = 0.0;
            s.ov_dir_y[i] = 0.0;
            s.ov_next[i] = 0;
            s.ov_prev[i] = 0;
            s.ov_convex[i] = 0;
        }
    }
}

/// Contract: `formation`, `social_events` and `autoreset` (SAME_STEP) in one submit, as a step
/// runs them, leave the CPU's columns, though the device rebuilds the obstacles of each
/// environment that regrouped or reset from a row that leaves them to it once, after all three
/// (`schedule::queues_rebuilds`, `schedule::REBUILD_QUEUE`): its queue holds exactly the
/// environments whose obstacles the CPU's three stages rebuilt, each once, some regrouped by both
/// regrouping stages and some regrouped and then reset. Rebuilt in workgroup memory (the hardware
/// adapters' way, where an environment queued twice would be rebuilt by two workgroups at once),
/// poisoned before each rebuild.
#[test]
fn regroupings_and_resets_in_one_submit_rebuild_each_environment_once() {
    const STAGES: [&str; 3] = ["formation", "social_events", "autoreset"];
    let Some(mut dev) = device() else { return };
    dev.paths.obstacles_in_workgroups = true;
    dev.paths.obstacles_after_resets = true;
    dev.paths.poison_orca_lists = true;
    let mut config = eventful("exp3", 0.5);
    config.episode.time_step = 0.3;
    let n_envs = 256;
    let env = rolled_out_mode(config, socnav::AutoresetMode::SameStep, n_envs, 40);
    let (p, layout) = (*env.params(), *env.layout());
    let mut cpu = env.state().unwrap().clone();
    let mut cpu_out = env.outputs().clone();
    let mut gpu = GpuStages::new(dev, &p, &cpu, &cpu_out, &STAGES).expect("GPU stages");
    let (mut from_gpu, mut from_gpu_out) = (cpu.clone(), cpu_out.clone());
    let mode = parity_mode(gpu.adapter());
    let mut lockstep = Lockstep::default();
    let mut rng = RngStream::new(11, 2);
    let (mut both, mut regrouped_and_reset, mut queued) = (0, 0, 0);
    for run in 0..4 {
        crate::step::formation::perturb_formation(&mut cpu, &mut cpu_out, &p, &mut rng);
        zero_unused_obstacle_slots(&mut cpu);
        for e in 0..n_envs {
            cpu.done[e] |= u32::from(rng.next_f32() < 0.3);
        }
        gpu.upload_state(&cpu);
        gpu.upload_outputs(&cpu_out);
        fill_pool(&mut gpu, &p, &cpu, layout);
        let actions = random_actions(&mut rng, n_envs, p.holonomic != 0);
        // Which environments each CPU stage rebuilt: the marker again before each.
        let mut rebuilt = Vec::new();
        for stage in STAGES {
            let mut marked = cpu.clone();
            let cap = marked.strides.obstacle_vertices;
            for e in 0..n_envs {
                marked.ov_x[e * cap] = GARBAGE;
            }
            cpu_stage(stage, &p, &mut marked, &mut cpu_out.clone(), &actions);
            rebuilt.push(rebuilt_envs(&marked));
            cpu_stage(stage, &p, &mut cpu, &mut cpu_out, &actions);
        }
        gpu.upload_actions(&actions);
        gpu.run_stages(&STAGES, None, |_| {}).expect("GPU stages");
        let mut expected: Vec<u32> = rebuilt.concat();
        expected.sort_unstable();
        expected.dedup();
        let mut got = gpu.queued_rebuilds().expect("the rebuild queue");
        got.sort_unstable();
        assert_eq!(got, expected, "run {run}: the queued rebuilds");
        let [by_formation, by_events, by_reset] = &rebuilt[..] else {
            unreachable!("three stages")
        };
        both += by_formation
            .iter()
            .filter(|e| by_events.contains(e))
            .count();
        regrouped_and_reset += by_reset
            .iter()
            .filter(|e| by_formation.contains(e) || by_events.contains(e))
            .count();
        queued += got.len();
        gpu.download_state(&mut from_gpu).expect("readback");
        gpu.download_outputs(&mut from_gpu_out).expect("readback");
        let what = format!(
            "formation + social_events + autoreset on {}, run {run}",
            gpu.adapter()
        );
        agree_or_tally(
            &what,
            mode,
            &mut lockstep,
            (&cpu, &from_gpu),
            (&cpu_out, &from_gpu_out),
        );
    }
    if mode == Parity::Lockstep {
        lockstep.check("formation + social_events + autoreset", gpu.adapter());
    }
    assert!(
        both > 0 && regrouped_and_reset > 0,
        "{both} environments regrouped by both stages and {regrouped_and_reset} regrouped and \
         reset ({queued} queued in all)"
    );
    println!(
        "{queued} rebuilds queued: {both} of environments regrouped by both stages, \
         {regrouped_and_reset} regrouped and reset"
    );
}
