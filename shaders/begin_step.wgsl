// requires: common/reset.wgsl
//
// Twin of src/systems/begin_step.rs (stage `begin_step`): clear the per-step output flags, reset
// an environment that finished at the previous step under NEXT_STEP (it returns its first
// observation with reward 0 and takes no dynamics this step), and count the tick of every
// environment that steps, first, as 0.1.1 does.

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= N_ENVS) {
        return;
    }
    outu[CO_HAS_FINAL + e] = 0u;
    outu[CO_EPISODE_DONE + e] = 0u;
    for (var k = 0u; k < SO_EVENTS; k++) {
        outu[CO_EVENTS + e * SO_EVENTS + k] = 0u;
    }
    if (su[C_PENDING_RESET + e] != 0u) {
        su[C_STEPPING + e] = 0u;
        reset_and_observe(e);
    } else {
        let stepping = select(0u, 1u, su[C_DONE + e] == 0u);
        su[C_STEPPING + e] = stepping;
        su[C_TICK + e] += stepping;
    }
}
