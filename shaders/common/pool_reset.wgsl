// Twin of src/systems/reset.rs: the reset of one environment inside a step or on request.
//
// Scenario generation stays on the host (the same Rust code, so a reset is bit-identical by
// construction): the host keeps in the reset pool (binding `pool`, layout in
// `backend::wgsl::pool_row_words`) the state that an environment's next episode starts with and
// that state's first observation, produced by `reset_and_observe` on a one-environment table, and
// the same for the episode after it: two rows per environment, in the halves of the pool that the
// parity of their episode counters chooses (`pool_row_of`). A reset here copies the next
// episode's row; the host notices the consumed row by the environment's episode counter, which it
// reads back with the outputs, and writes the row two episodes ahead into the freed place while
// the device runs the following step. `pool_row_of`, `pool_copy_state` and
// `pool_copy_observation` are generated with the prelude.

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
    // Chosen before the copy, which moves the episode counter on.
    let row = pool_row_of(e);
    pool_copy_state(e, row);
    for (var k = 0u; k < batch.so_info; k++) {
        outf[batch.co_info + e * batch.so_info + k] = 0.0;
    }
    pool_copy_observation(e, row);
}
