// requires: common/pool_reset.wgsl
//
// Twin of src/systems/autoreset.rs (stage `autoreset`): what happens to an environment whose
// episode ended at this step. SAME_STEP keeps the final observation, interactions and info aside
// and resets at once; NEXT_STEP marks the environment so that `begin_step` resets it at the next
// step; DISABLED leaves it to the caller.
//
// Rare work out of the hot pass (backend::wgsl::RARE_WORK_STAGES): `queue_work`, over every
// environment, marks NEXT_STEP's and queues SAME_STEP's finished environments; `main` keeps the
// finals of one queued environment per lane and resets it.

@compute @workgroup_size(WORKGROUP_SIZE)
fn queue_work(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= batch.n_envs || su[batch.c_stepping + e] == 0u || su[batch.c_done + e] == 0u) {
        return;
    }
    if (params.autoreset == AUTORESET_SAME_STEP) {
        rare_push(RARE_AUTORESET, e);
    } else if (params.autoreset == AUTORESET_NEXT_STEP) {
        su[batch.c_pending_reset + e] = 1u;
    }
}

// SAME_STEP's finals and reset of one queued environment per lane.
@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = rare_env(RARE_AUTORESET, gid.x);
    if (e == NONE) {
        return;
    }
    for (var k = 0u; k < batch.so_obs; k++) {
        outf[batch.co_final_obs + e * batch.so_obs + k] = outf[batch.co_obs + e * batch.so_obs + k];
    }
    for (var k = 0u; k < batch.so_info; k++) {
        outf[batch.co_final_info + e * batch.so_info + k] = outf[batch.co_info + e * batch.so_info + k];
    }
    for (var k = 0u; k < batch.so_obs_count; k++) {
        outu[batch.co_final_obs_count + e * batch.so_obs_count + k] = outu[batch.co_obs_count + e * batch.so_obs_count + k];
    }
    for (var k = 0u; k < batch.so_hh_pairs; k++) {
        outu[batch.co_final_hh_pairs + e * batch.so_hh_pairs + k] = outu[batch.co_hh_pairs + e * batch.so_hh_pairs + k];
    }
    for (var k = 0u; k < batch.so_hl_pairs; k++) {
        outu[batch.co_final_hl_pairs + e * batch.so_hl_pairs + k] = outu[batch.co_hl_pairs + e * batch.so_hl_pairs + k];
    }
    for (var k = 0u; k < batch.so_pair_count; k++) {
        outu[batch.co_final_pair_count + e * batch.so_pair_count + k] = outu[batch.co_pair_count + e * batch.so_pair_count + k];
    }
    outu[batch.co_has_final + e] = 1u;
    reset_and_observe_keep_step_outputs(e);
}
