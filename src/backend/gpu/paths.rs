//! The paths a batch takes on the device ([`GpuPaths`]): where two ways give the same bits, which
//! one runs (a hardware GPU's or a software adapter's), and the knobs of the step's readback,
//! rebuilds and tests. A value, separate from the device: `GpuDevice::paths` holds the adapter's
//! defaults (or a software adapter's everywhere with `SOCNAV_GPU_PATHS=lane`), and a batch made
//! with a handle takes that handle's paths.

/// The per-step output bytes of one readback piece ([`GpuPaths::readback_piece_bytes`]): 4 MiB,
/// about 0.1 ms of DMA at 36 GB/s, several times a submit's cost. exp2 at 65,536 environments
/// (207 MB a step; padded 60 MB) reads four pieces, at 256 environments (0.9 MB) one.
pub const DEFAULT_READBACK_PIECE_BYTES: u64 = 4 << 20;

/// Most workgroups an obstacle rebuild dispatch in workgroup memory takes
/// ([`GpuPaths::rebuild_workgroups`]): more than an H100 holds at once (132 SMs, 14 workgroups of
/// 16 KiB of workgroup memory each), and more than exp2's rebuilds a step at 65,536 environments
/// (about 190 after formation, 490 after social events).
pub const DEFAULT_REBUILD_WORKGROUPS: u32 = 2048;

/// The paths of a batch on the device. Every path gives the same bits as the other way; the
/// parity tests run both.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GpuPaths {
    /// Whether the batch stage their observations (`shaders/observation.wgsl`:
    /// values stored slot-major, then moved into rows through workgroup memory, which coalesces
    /// a GPU's stores) instead of writing each environment's row in place. On by default on a
    /// hardware GPU; off on a software one (lavapipe), where the tile's barrier made the pass
    /// five times slower. Both give the same bits; a clone with the other setting is how a
    /// caller (or a test) chooses.
    pub stage_observations: bool,
    /// Whether the resets of a step (`begin_step`, `autoreset`) run each queued environment on
    /// all the lanes of a workgroup (`backend::wgsl::with_resets_in_workgroups`) instead of one
    /// lane: a reset copies about 1,500 words from the pool, a chain of loads and stores one
    /// lane runs at memory latency. On by default on a hardware GPU; off on a software one
    /// (lavapipe), which runs a workgroup's lanes as SIMD loops on one core and so does more work
    /// for one reset shared than for one reset per lane. Both give the same bits; a caller (or a test)
    /// chooses by setting it.
    pub resets_in_workgroups: bool,
    /// Whether the passes that regroup (`formation`, `social_events`) take each queued
    /// environment on all the lanes of a workgroup, its regroupings shared out among them
    /// (`backend::wgsl::with_regroups_in_workgroups`: lane 0 runs the pass's logic, the lanes take
    /// a slot each of the sorts, permutations, remaps and list positions), instead of one
    /// lane: a regrouping is a chain of dependent memory round trips in one lane (up to 0.15-0.18
    /// ms of each pass on an H100). On by default on a hardware GPU; off on a software one, as
    /// [`Self::resets_in_workgroups`]. Both give the same bits; a clone with the other setting is
    /// how a caller (or a test) chooses.
    pub regroups_in_workgroups: bool,
    /// Whether the passes that regroup (`backend::schedule::regroups`) rebuild the ORCA
    /// obstacles of each regrouped environment in a workgroup of its own, the rebuild's working
    /// memory in workgroup memory (`backend::wgsl::REBUILD_IN_WORKGROUPS_ENTRY`), instead of one
    /// per lane over the `scratch` buffer, a chain of dependent storage-buffer accesses (2.4 of
    /// exp2's 5.1 ms a step on an H100). On by default on a hardware GPU; off on a software one.
    /// Both give the same bits; a clone with the other setting is how a caller (or a test)
    /// chooses.
    pub obstacles_in_workgroups: bool,
    /// Whether the batch write the observation's entity records in a dispatch
    /// of their own, a lane per environment and record (`backend::wgsl::OBS_RECORDS_ENTRY`),
    /// where the view is whole, instead of in the observing lane's loops over every record (exp2:
    /// 49, 40 of them wall segments, serial in one lane). On by default on a hardware GPU; off on
    /// a software one, where each of those lanes would compute the robot's frame again on a CPU
    /// core. Both give the same bits; a clone with the other setting is how a caller (or a test)
    /// chooses.
    pub records_in_lanes: bool,
    /// Whether the reset pool's rows leave their ORCA obstacles to the device
    /// (`systems::reset::ObstacleBuild::Deferred`), which rebuilds them after each reset's copy
    /// (a step's in the one rebuild after its stages, the reset pass's after its `main`:
    /// `backend::schedule::rebuilds_resets`; in workgroup memory where
    /// [`Self::obstacles_in_workgroups`] says so), instead of building them
    /// on the host into each row: the build is about two thirds of a row's instructions, and the
    /// host's rows made ahead are what the delivered step waits on once the device's step is
    /// short. On by default on a hardware GPU; off on a software one, where the device's
    /// rebuild is a lane's serial work on the same cores. Both give the same bits; a caller (or a test)
    /// chooses by setting it.
    pub obstacles_after_resets: bool,
    /// Whether a step that is read back submits its readback's other pieces and its queued
    /// obstacle rebuild right after its own submit, before the host's work that overlaps its
    /// passes (the reset pool's rows made ahead), instead of after that work. On a driver that
    /// takes submits as they come (the H200's did) the pieces' copies then follow the passes on
    /// the device whatever the host is doing; and where two batches share the device (`socnav
    /// bench --halves`, Python's `send`/`recv`), they are queued before the other batch's next
    /// step, not behind its passes. A driver that holds a submit until the one before it has
    /// finished (lavapipe) would hold the host there instead, and its rows ahead would wait for
    /// the passes. On by default on a hardware GPU; off on a software one. Both give the same
    /// bits; a caller (or a test) chooses by setting it.
    pub readback_before_host_work: bool,
    /// Most workgroups a rebuild dispatch in workgroup memory takes: each workgroup rebuilds the
    /// queued environments its index and every this-many-th after it. A workgroup per environment
    /// of the batch (65,536 of them, each holding 16 KiB of workgroup memory, all but a few
    /// hundred leaving at once) took dozens of waves of launches. [`DEFAULT_REBUILD_WORKGROUPS`] by default; 0 counts as 1.
    pub rebuild_workgroups: u32,
    /// Bytes of a step's per-step outputs per readback piece (`backend::gpu::readback`): a batch
    /// reads them back in one piece per this many bytes, at most four, so that the host copies
    /// one piece while the device copies the next. [`DEFAULT_READBACK_PIECE_BYTES`] unless a
    /// clone says otherwise.
    pub readback_piece_bytes: u64,
    /// For tests: whether the batches made on this device fill the ORCA lists with NaN at every
    /// clear (`backend::wgsl::with_poisoned_orca_lists`). The lists are not zeroed
    /// (`super::spirv`) and no entry is read before it is written, so the results are the same
    /// bits either way; a test compares them. Off by default.
    pub poison_orca_lists: bool,
    /// For tests: whether the pool scatter pass (`backend::wgsl::pool_scatter_shader`) gives its
    /// workgroups the staged copies last first, as a GPU whose workgroups finish in another
    /// order than they start would, so that a test on a driver that runs them in order sees what
    /// such a GPU does with copies that depend on their order (none may). Off unless a clone
    /// says otherwise.
    pub scatter_last_first: bool,
    /// For diagnosis only: functions of the stage shaders that return at once, with their type's
    /// zero value (`backend::wgsl::with_functions_returning_at_once`), so that a pass timed
    /// without one says what that function costs on this device (`socnav bench --leave-out`).
    /// The results are wrong; a batch refuses a name that none of its shaders defines. Empty
    /// by default.
    pub leave_out: Vec<String>,
}

impl GpuPaths {
    /// The paths of an adapter: a hardware GPU's (every workgroup path on) or a software one's
    /// (every path a lane's), with the default readback and rebuild sizes and no test knob.
    pub fn of_adapter(hardware: bool) -> Self {
        Self {
            stage_observations: hardware,
            resets_in_workgroups: hardware,
            regroups_in_workgroups: hardware,
            obstacles_in_workgroups: hardware,
            records_in_lanes: hardware,
            obstacles_after_resets: hardware,
            readback_before_host_work: hardware,
            rebuild_workgroups: DEFAULT_REBUILD_WORKGROUPS,
            readback_piece_bytes: DEFAULT_READBACK_PIECE_BYTES,
            poison_orca_lists: false,
            scatter_last_first: false,
            leave_out: Vec::new(),
        }
    }

    /// These paths with a software adapter's way everywhere it differs from a hardware GPU's:
    /// observations written in place, each reset and regrouping on one lane, each obstacle
    /// rebuild over `scratch`, the entity records in the observing lane, each reset's obstacles
    /// built on the host, the readback submitted after the host's work.
    #[must_use]
    pub fn lane(self) -> Self {
        Self {
            stage_observations: false,
            resets_in_workgroups: false,
            regroups_in_workgroups: false,
            obstacles_in_workgroups: false,
            records_in_lanes: false,
            obstacles_after_resets: false,
            readback_before_host_work: false,
            ..self
        }
    }
}
