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
// the device runs the following step. `pool_row_of`, `pool_env_of`, `pool_copy_state` and
// `pool_copy_observation` are generated with the prelude. Where the device asks for it
// (`GpuPaths::obstacles_after_resets`), a row leaves the ORCA obstacles dirty and out of the row
// (`batch.pool_obstacles` 0, `backend::wgsl::POOL_OBSTACLE_COLUMNS`: the copy leaves the old ones
// and their count in place), and they are rebuilt in entry points generated with the obstacle
// library (`backend::wgsl::assemble_pass_rebuilding_resets`), which zero the old tail past the
// new count as every rebuild does: a step's resets queue their environments
// (`pool_reset_queue_rebuild`) for the submit's one rebuild after its stages, with the
// regroupings' (backend::schedule::queues_rebuilds); the reset pass rebuilds after `main`.

// Queue environment e, about to reset from its pool row, for the submit's one obstacle rebuild
// (RARE_REBUILD) where the rows leave the obstacles to the device, unless a regrouping queued it
// already this submit: its obstacles are then dirty, which no environment is at a submit's start.
// Called before `main` copies the row (which sets the flag).
fn pool_reset_queue_rebuild(e: u32) {
    if (batch.pool_obstacles == 0u && su[batch.c_obstacles_dirty + e] != 1u) {
        rare_push(RARE_REBUILD, e);
    }
}

// Resets by many lanes. A reset is about 1,500 words (exp2) copied from the pool, a chain of
// loads and stores that one lane runs at memory latency. The queued resets of a step
// (`begin_step`, `autoreset`) run on teams of RESET_LANES lanes (generated: 1, or
// WORKGROUP_SIZE on a GPU, `GpuPaths::resets_in_workgroups`): a team takes the queue's entries
// `team, team + reset_teams(...), ...` and its lanes share each reset (`first` = the lane in the
// team, `stride` = RESET_LANES), each lane reading and writing the same slots `first,
// first + stride, ...` of every column. No lane reads a word another lane writes, so they need
// no barrier: the queue holds pool rows, chosen by `queue_work` before any reset (`pool_row_of`
// reads the episode counter, which the copy moves on), and a caller that reads outputs the reset
// overwrites (autoreset's finals) reads them in the same slots.

// Teams of RESET_LANES lanes in a dispatch of `workgroups` workgroups.
fn reset_teams(workgroups: u32) -> u32 {
    return workgroups * (WORKGROUP_SIZE / RESET_LANES);
}

// Reset environment `e` from pool row `row` and write its first observation; reward 0, flags
// cleared, info zeroed: this lane's share (`first`, `stride`).
fn reset_and_observe(e: u32, row: u32, first: u32, stride: u32) {
    if (first == 0u) {
        outf[batch.co_reward + e] = 0.0;
        outu[batch.co_terminated + e] = 0u;
        outu[batch.co_truncated + e] = 0u;
    }
    reset_and_observe_keep_step_outputs(e, row, first, stride);
}

// Reset environment `e` from pool row `row` and write its first observation and a zeroed info,
// keeping this step's reward and flags (SAME_STEP autoreset returns those of the finishing
// step): this lane's share.
fn reset_and_observe_keep_step_outputs(e: u32, row: u32, first: u32, stride: u32) {
    pool_copy_state(e, row, first, stride);
    for (var k = first; k < batch.so_info; k += stride) {
        outf[batch.co_info + e * batch.so_info + k] = 0.0;
    }
    pool_copy_observation(e, row, first, stride);
}
