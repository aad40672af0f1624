// requires: common/reset.wgsl
//
// Twin of src/systems/autoreset.rs (stage `autoreset`): what happens to an environment whose
// episode ended at this step. SAME_STEP keeps the final observation, interactions and info aside
// and resets at once; NEXT_STEP marks the environment so that `begin_step` resets it at the next
// step; DISABLED leaves it to the caller.

@compute @workgroup_size(WORKGROUP_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= N_ENVS || su[C_STEPPING + e] == 0u || su[C_DONE + e] == 0u) {
        return;
    }
    if (params.autoreset == AUTORESET_SAME_STEP) {
        for (var k = 0u; k < SO_OBS; k++) {
            outf[CO_FINAL_OBS + e * SO_OBS + k] = outf[CO_OBS + e * SO_OBS + k];
        }
        for (var k = 0u; k < SO_INFO; k++) {
            outf[CO_FINAL_INFO + e * SO_INFO + k] = outf[CO_INFO + e * SO_INFO + k];
        }
        for (var k = 0u; k < SO_OBS_COUNT; k++) {
            outu[CO_FINAL_OBS_COUNT + e * SO_OBS_COUNT + k] = outu[CO_OBS_COUNT + e * SO_OBS_COUNT + k];
        }
        for (var k = 0u; k < SO_HH_PAIRS; k++) {
            outu[CO_FINAL_HH_PAIRS + e * SO_HH_PAIRS + k] = outu[CO_HH_PAIRS + e * SO_HH_PAIRS + k];
        }
        for (var k = 0u; k < SO_HL_PAIRS; k++) {
            outu[CO_FINAL_HL_PAIRS + e * SO_HL_PAIRS + k] = outu[CO_HL_PAIRS + e * SO_HL_PAIRS + k];
        }
        for (var k = 0u; k < SO_PAIR_COUNT; k++) {
            outu[CO_FINAL_PAIR_COUNT + e * SO_PAIR_COUNT + k] = outu[CO_PAIR_COUNT + e * SO_PAIR_COUNT + k];
        }
        outu[CO_HAS_FINAL + e] = 1u;
        reset_and_observe_keep_step_outputs(e);
    } else if (params.autoreset == AUTORESET_NEXT_STEP) {
        su[C_PENDING_RESET + e] = 1u;
    }
}
