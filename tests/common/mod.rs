//! Helpers shared by the test crates: the suite (`tests/suite/main.rs`, whose modules reach this
//! one as `crate::common`), `golden_replay`, `step_no_alloc` and `orca_no_alloc`, each of which
//! includes it as its own module (`mod common;`, or `#[path]` from the suite).

#![allow(
    dead_code,
    reason = "each test crate that includes this module uses a different part of it"
)]

#[cfg(feature = "gpu")]
pub mod gpu;
pub mod npz;
pub mod reference;
pub mod scene;
pub mod skip;
pub mod sngnn;
pub mod sngnn_rollout;
pub mod torch_zip;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use socnav::outputs::Outputs;

/// The outputs a caller may read, as bits (NaN equals NaN), interaction pairs included:
/// everything but the buffers whose flag says they hold nothing (`final_*` without `has_final`, `episode` without
/// `episode_done`), which keep whatever an earlier step left there.
pub fn valid_outputs(o: &Outputs) -> Vec<u32> {
    let mut v: Vec<u32> = o
        .obs
        .iter()
        .chain(&o.reward)
        .chain(&o.info)
        .map(|x| x.to_bits())
        .collect();
    v.extend(
        o.obs_count
            .iter()
            .chain(&o.hh_pairs)
            .chain(&o.hl_pairs)
            .chain(&o.pair_count)
            .chain(&o.terminated)
            .chain(&o.truncated)
            .chain(&o.has_final)
            .chain(&o.episode_done),
    );
    let (obs, info, episode) = (o.strides.obs(), o.strides.info(), o.strides.episode());
    for e in 0..o.n_envs {
        if o.has_final[e] != 0 {
            v.extend(
                o.final_obs[e * obs..(e + 1) * obs]
                    .iter()
                    .map(|x| x.to_bits()),
            );
            v.extend(
                o.final_info[e * info..(e + 1) * info]
                    .iter()
                    .map(|x| x.to_bits()),
            );
            let (hh, hl, pairs) = (o.strides.hh(), o.strides.hl(), o.strides.pairs());
            v.extend(&o.final_hh_pairs[e * hh..(e + 1) * hh]);
            v.extend(&o.final_hl_pairs[e * hl..(e + 1) * hl]);
            v.extend(&o.final_pair_count[e * pairs..(e + 1) * pairs]);
        }
        if o.episode_done[e] != 0 {
            v.extend(
                o.episode[e * episode..(e + 1) * episode]
                    .iter()
                    .map(|x| x.to_bits()),
            );
        }
    }
    v
}

/// Allocations made through [`Counting`] since the process started.
pub static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

/// A global allocator that counts allocations and forwards everything to the system allocator.
/// Install it in a test crate with `#[global_allocator] static GLOBAL: common::Counting = common::Counting;`.
pub struct Counting;

#[expect(
    unsafe_code,
    reason = "a GlobalAlloc impl is unsafe by definition; it only counts"
)]
// SAFETY: forwards every call unchanged to the system allocator.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// The names of the shipped configs (`configs/*.toml`) with the DSRNN reward, sorted; the
/// SNGNN-v2 ones are [`sngnn_config_names`].
pub fn config_names() -> Vec<String> {
    all_config_names()
        .into_iter()
        .filter(|n| !n.ends_with("_sngnn"))
        .collect()
}

/// The shipped configs with the SNGNN-v2 reward (their batches need the weight file).
pub fn sngnn_config_names() -> Vec<String> {
    all_config_names()
        .into_iter()
        .filter(|n| n.ends_with("_sngnn"))
        .collect()
}

fn all_config_names() -> Vec<String> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("configs");
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("configs/")
        .map(|e| e.expect("configs/ entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| {
            p.file_stem()
                .expect("a file name")
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    names.sort();
    names
}

/// A shipped config by name.
pub fn load_config(name: &str) -> socnav::Config {
    socnav::Config::from_name_or_path(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}
