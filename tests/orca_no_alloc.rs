//! The ORCA core must not allocate once its buffers are warm (docs/spec.md, style rule 4: `step`
//! does not allocate). A counting global allocator checks a full per-agent pass and an obstacle
//! rebuild.

mod common;

use std::sync::atomic::Ordering;

use common::ALLOCATIONS;

use socnav::orca::{
    Neighbor, ObstacleScratch, ObstacleSet, OrcaAgent, OrcaNeighbor, OrcaScratch, agent_neighbors,
    compute_new_velocity, process_obstacles,
};

#[global_allocator]
static GLOBAL: common::Counting = common::Counting;

/// One Jacobi pass over all agents with the core API, writing into `out`.
#[expect(
    clippy::too_many_arguments,
    reason = "test helper threading every buffer through"
)]
fn pass(
    agents: &[OrcaAgent],
    xs: &[f32],
    ys: &[f32],
    set: &ObstacleSet,
    nb: &mut Vec<Neighbor>,
    gathered: &mut Vec<OrcaNeighbor>,
    scratch: &mut OrcaScratch,
    out: &mut Vec<[f32; 2]>,
) -> (usize, usize) {
    out.clear();
    let (mut lp3, mut obstacle_lines) = (0, 0);
    for (i, a) in agents.iter().enumerate() {
        agent_neighbors(i, xs, ys, a.neighbor_dist, a.max_neighbors, nb);
        gathered.clear();
        gathered.extend(nb.iter().map(|n| {
            let o = &agents[n.index as usize];
            OrcaNeighbor {
                pos: o.pos,
                vel: o.vel,
                radius: o.radius,
            }
        }));
        out.push(compute_new_velocity(
            a,
            gathered,
            &set.as_view(),
            0.25,
            scratch,
        ));
        lp3 += usize::from(scratch.used_lp3());
        obstacle_lines += scratch.num_obstacle_lines();
    }
    (lp3, obstacle_lines)
}

#[test]
fn core_does_not_allocate_when_warm() {
    // A dense crowd inside a walled room with a pillar, so obstacle lines, agent lines and LP3
    // all run.
    let polygons = vec![
        vec![[-4.0, -3.0], [4.0, -3.0]],
        vec![[4.0, 3.0], [-4.0, 3.0]],
        vec![[0.5, -0.5], [1.5, -0.5], [1.5, 0.5], [0.5, 0.5]],
    ];
    let agents: Vec<OrcaAgent> = (0..40)
        .map(|i| {
            let (x, y) = ((i % 8) as f32 * 0.9 - 3.3, (i / 8) as f32 * 1.1 - 2.3);
            OrcaAgent {
                pos: [x, y],
                vel: [0.3 * (i % 3) as f32 - 0.3, 0.2],
                pref_vel: [-x, -y],
                radius: 0.3,
                max_speed: 1.0,
                neighbor_dist: 10.0,
                max_neighbors: 10,
                time_horizon: 5.0,
                time_horizon_obst: 5.0,
            }
        })
        .collect();
    let xs: Vec<f32> = agents.iter().map(|a| a.pos[0]).collect();
    let ys: Vec<f32> = agents.iter().map(|a| a.pos[1]).collect();
    let (mut set, mut obstacle_scratch) = (ObstacleSet::new(), ObstacleScratch::new());
    let (mut nb, mut gathered) = (Vec::new(), Vec::new());
    let (mut scratch, mut out) = (OrcaScratch::new(), Vec::new());

    // Warm-up: buffers grow to their working size.
    process_obstacles(&polygons, &mut obstacle_scratch, &mut set).expect("valid obstacles");
    pass(
        &agents,
        &xs,
        &ys,
        &set,
        &mut nb,
        &mut gathered,
        &mut scratch,
        &mut out,
    );
    let warm = out.clone();

    let before = ALLOCATIONS.load(Ordering::Relaxed);
    process_obstacles(&polygons, &mut obstacle_scratch, &mut set).expect("valid obstacles");
    pass(
        &agents,
        &xs,
        &ys,
        &set,
        &mut nb,
        &mut gathered,
        &mut scratch,
        &mut out,
    );
    let allocations = ALLOCATIONS.load(Ordering::Relaxed) - before;

    assert_eq!(
        allocations, 0,
        "the warm core allocated {allocations} times"
    );
    assert_eq!(out, warm, "the second pass must repeat the first");
    assert!(out.iter().all(|v| v[0].is_finite() && v[1].is_finite()));
}
