//! socnav's integration tests, one crate (`cargo test --release --test suite`; a module's tests
//! alone: `cargo test --release --test suite step::observation`). Four tests stay binaries of
//! their own (five test binaries in all): `golden_replay` (the replay of the golden episodes,
//! which other checks run by that name), `step_no_alloc` / `orca_no_alloc` (each installs a
//! global allocator that counts the allocations of every thread, which tests running beside them
//! would move) and `gpu_device_lost` (it destroys the process's shared GPU device, which would
//! fail every other GPU test). The helpers shared with them are `tests/common/` and
//! `tests/golden/`.
//!
//! `step/`: one module per stage of `socnav::pipeline::STAGES`, named as the stage (as are
//! `src/systems/<stage>.rs` and `shaders/<stage>.wgsl`): its hand-computed CPU cases (`cpu`, and
//! further CPU files where a stage has more) beside its CPU/GPU parity check (`gpu`), or one file
//! for a stage with one kind of test. `step/mod.rs` holds the scene helpers of the hand-computed
//! cases.
//!
//! `orca/`: ORCA itself (RVO2 2.0.3's algorithm, `src/orca/` and `shaders/common/orca.wgsl`)
//! against the RVO2 reference data, on the device, and its regression cases.
//!
//! `whole_step/`: the step and the reset as a whole: CPU/GPU parity of whole trajectories, the
//! GPU batch layout and the GPU backend outside the stages, determinism, generated scenarios and
//! the reset pool, and properties checked on the golden episodes (conditioning, perturbed states,
//! fidelity regressions).
//!
//! `api/`: what users touch: error reporting of the public API, config validation, the
//! command-line tool's backends, rendering, the heatmap figure and the SNGNN-v2 weight file.
//!
//! `fuzz/`: property-based fuzzing (proptest) of what users feed in: configs so far.
//!
//! `foundations/`: the pieces under everything: the counter-based random streams, the accuracy of
//! `socnav::math`, the shaders' validation and generated parts, and the module graph.
//!
//! The process shares one GPU device (`GpuDevice::open`) and its compiled pipelines between the
//! GPU tests, which run concurrently: a batch of another size or config compiles nothing again.

#[path = "../common/mod.rs"]
mod common;
#[path = "../golden/mod.rs"]
mod golden;

mod api;
mod foundations;
mod fuzz;
mod orca;
mod step;
mod whole_step;

// A global allocator that counts allocations per thread (the test harness runs tests on several
// threads at once, so a process-wide count would see theirs): `thread_allocations` before and
// after a call on the test's own thread counts what that call allocated
// (`step::sngnn_graph::cpu::a_warm_build_allocates_nothing`).
std::thread_local! {
    static THREAD_ALLOCATIONS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// Allocations made by the calling thread so far.
fn thread_allocations() -> usize {
    THREAD_ALLOCATIONS.with(|c| c.get())
}

struct CountingPerThread;

#[expect(
    unsafe_code,
    reason = "a GlobalAlloc impl is unsafe by definition; it only counts"
)]
// SAFETY: forwards every call unchanged to the system allocator.
unsafe impl std::alloc::GlobalAlloc for CountingPerThread {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        THREAD_ALLOCATIONS.with(|c| c.set(c.get() + 1));
        // SAFETY: same contract as the caller's.
        unsafe { std::alloc::System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { std::alloc::System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, new_size: usize) -> *mut u8 {
        THREAD_ALLOCATIONS.with(|c| c.set(c.get() + 1));
        // SAFETY: same contract as the caller's.
        unsafe { std::alloc::System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: CountingPerThread = CountingPerThread;
