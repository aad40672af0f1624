// Twin of src/systems/reset.rs: the reset of one environment inside a step or on request.
//
// Scenario generation stays on the host (the same Rust code, so a reset is bit-identical by
// construction): the host keeps in the reset pool (binding `pool`, one row per environment, layout
// in `backend::wgsl::pool_row_words`) the state that environment's next episode starts with and
// that state's first observation, produced by `reset_and_observe` on a one-environment table. A
// reset here copies the row; the host notices the consumed row by the environment's episode
// counter, which it reads back with the outputs, and refills it before the next step.
// `pool_copy_state` and `pool_copy_observation` are generated with the prelude.

// Reset environment `e` and write its first observation; reward 0, flags cleared, info zeroed.
fn reset_and_observe(e: u32) {
    outf[batch.co_reward + e] = 0.0;
    outu[batch.co_terminated + e] = 0u;
    outu[batch.co_truncated + e] = 0u;
    reset_and_observe_keep_step_outputs(e);
}

// Reset environment `e` and write its first observation and a zeroed info, keeping this step's
// reward and flags (SAME_STEP autoreset returns those of the finishing step).
fn reset_and_observe_keep_step_outputs(e: u32) {
    pool_copy_state(e);
    for (var k = 0u; k < batch.so_info; k++) {
        outf[batch.co_info + e * batch.so_info + k] = 0.0;
    }
    pool_copy_observation(e);
}
