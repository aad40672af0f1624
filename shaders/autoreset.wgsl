// requires: common/pool_reset.wgsl
//
// Twin of src/systems/autoreset.rs (stage `autoreset`): what happens to an environment whose
// episode ended at this step. SAME_STEP keeps the final observation, interactions and info aside
// and resets at once; NEXT_STEP marks the environment so that `begin_step` resets it at the next
// step; DISABLED leaves it to the caller.
//
// Rare work out of the hot pass (the stage's GpuPlan: backend::schedule::has_rare_work):
// `queue_work`, over every environment, marks NEXT_STEP's and queues the pool rows of SAME_STEP's
// finished environments (and the environments for the submit's one obstacle rebuild:
// `pool_reset_queue_rebuild`); `main` keeps the finals of each queued environment and resets it
// with a team of lanes (common/pool_reset.wgsl): a lane keeps the slots of the finals that it then
// overwrites, so no lane reads what another writes.

@compute @workgroup_size(WORKGROUP_SIZE)
fn queue_work(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= batch.n_envs || su[batch.c_stepping + e] == 0u || su[batch.c_done + e] == 0u) {
        return;
    }
    if (params.autoreset == AUTORESET_SAME_STEP) {
        pool_reset_queue_rebuild(e);
        rare_push(RARE_AUTORESET, pool_row_of(e));
    } else if (params.autoreset == AUTORESET_NEXT_STEP) {
        su[batch.c_pending_reset + e] = 1u;
    }
}

// Environment e's `n` words of f32 output column `src` copied into column `dst` (Rust
// `copy_from_slice` of the row): lane `lane`'s slots `lane, lane + RESET_LANES, ...`.
fn keep_f32(e: u32, src: u32, dst: u32, n: u32, lane: u32) {
    for (var k = lane; k < n; k += RESET_LANES) {
        outf[dst + e * n + k] = outf[src + e * n + k];
    }
}

// `keep_f32` for u32 output columns.
fn keep_u32(e: u32, src: u32, dst: u32, n: u32, lane: u32) {
    for (var k = lane; k < n; k += RESET_LANES) {
        outu[dst + e * n + k] = outu[src + e * n + k];
    }
}

// SAME_STEP's finals and reset of the queued environments, each by a team of RESET_LANES lanes
// (common/pool_reset.wgsl).
@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let lane = gid.x % RESET_LANES;
    for (var k = gid.x / RESET_LANES; ; k += reset_teams(groups.x)) {
        let row = rare_env(RARE_AUTORESET, k);
        if (row == NONE) {
            break;
        }
        let e = pool_env_of(row);
        keep_f32(e, batch.co_obs, batch.co_final_obs, batch.so_obs, lane);
        keep_f32(e, batch.co_info, batch.co_final_info, batch.so_info, lane);
        keep_u32(e, batch.co_obs_count, batch.co_final_obs_count, batch.so_obs_count, lane);
        keep_u32(e, batch.co_hh_pairs, batch.co_final_hh_pairs, batch.so_hh_pairs, lane);
        keep_u32(e, batch.co_hl_pairs, batch.co_final_hl_pairs, batch.so_hl_pairs, lane);
        keep_u32(e, batch.co_pair_count, batch.co_final_pair_count, batch.so_pair_count, lane);
        if (lane == 0u) {
            outu[batch.co_has_final + e] = 1u;
        }
        reset_and_observe_keep_step_outputs(e, row, lane, RESET_LANES);
    }
}
