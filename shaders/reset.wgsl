// requires: common/reset.wgsl
//
// Twin of `CpuBackend::reset` (src/backend/cpu.rs): reset the environments the caller asked for
// and write their first observations. Not a stage of the step: the GPU backend runs it alone for
// `Backend::reset`. A reset runs without actions, so the mask travels in the action buffer: an
// environment resets when the first of its three action floats is non-zero.

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= N_ENVS || actions[3u * e] == 0.0) {
        return;
    }
    su[C_PENDING_RESET + e] = 0u;
    outu[CO_HAS_FINAL + e] = 0u;
    outu[CO_EPISODE_DONE + e] = 0u;
    reset_and_observe(e);
}
