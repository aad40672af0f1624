// requires: common/pool_reset.wgsl
//
// Twin of src/systems/begin_step.rs (stage `begin_step`): clear the per-step output flags, reset
// an environment that finished at the previous step under NEXT_STEP (it returns its first
// observation with reward 0 and takes no dynamics this step), and count the tick of every
// environment that steps, first, as 0.1.1 does.
//
// Rare work out of the hot pass (the stage's GpuPlan: backend::schedule::has_rare_work):
// `queue_work`, over every environment, clears the flags, counts the tick and queues the pool row
// of each environment that resets (`pool_row_of`, chosen before the reset moves the episode counter
// on) and, where the rows leave the ORCA obstacles to the device, the environment for the submit's
// one rebuild (`pool_reset_queue_rebuild`: a reset environment takes no dynamics this step, so
// nothing reads its obstacles before then); `main` resets each queued environment with a team of
// lanes (a reset copies a whole state row and observation: common/pool_reset.wgsl). Each
// environment's operations keep their order.

@compute @workgroup_size(WORKGROUP_SIZE)
fn queue_work(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= batch.n_envs) {
        return;
    }
    outu[batch.co_has_final + e] = 0u;
    outu[batch.co_episode_done + e] = 0u;
    for (var k = 0u; k < batch.so_events; k++) {
        outu[batch.co_events + e * batch.so_events + k] = 0u;
    }
    if (su[batch.c_pending_reset + e] != 0u) {
        su[batch.c_stepping + e] = 0u;
        pool_reset_queue_rebuild(e);
        rare_push(RARE_BEGIN_STEP, pool_row_of(e));
    } else {
        let stepping = select(0u, 1u, su[batch.c_done + e] == 0u);
        su[batch.c_stepping + e] = stepping;
        su[batch.c_tick + e] += stepping;
    }
}

// The queued resets, each by a team of RESET_LANES lanes (common/pool_reset.wgsl).
@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let lane = gid.x % RESET_LANES;
    for (var k = gid.x / RESET_LANES; ; k += reset_teams(groups.x)) {
        let row = rare_env(RARE_BEGIN_STEP, k);
        if (row == NONE) {
            break;
        }
        reset_and_observe(pool_env_of(row), row, lane, RESET_LANES);
    }
}
