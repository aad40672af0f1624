// requires: common/pool_reset.wgsl
//
// Twin of `CpuBackend::reset` (src/backend/cpu.rs): reset the environments the caller asked for
// and write their first observations. Not a stage of the step: the GPU backend runs it alone for
// `Backend::reset`. A reset runs without actions, so the mask travels in the action buffer: an
// environment resets when the first of its three action floats is non-zero.

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= batch.n_envs || actions[3u * e] == 0.0) {
        return;
    }
    su[batch.c_pending_reset + e] = 0u;
    outu[batch.co_has_final + e] = 0u;
    outu[batch.co_episode_done + e] = 0u;
    // One lane per environment: the pass runs only for `Backend::reset`, off the step.
    reset_and_observe(e, pool_row_of(e), 0u, 1u);
}
