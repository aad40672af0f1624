//! Gaussian sensor noise, as 0.1.1's `NoisyObservations`: an independent N(mean, std) sample per
//! value, added to the robot record's goal x and y (indices 6, 7; not the radius, nor the pose
//! and command of the world-frame record) and to every non-one-hot field (indices 6-13: position,
//! sin, cos, radius, speeds, gaze) of every record of a type whose noise is on.
//!
//! Which records: in padded mode (`observation.padded`), every record of the type's capacity,
//! the all-zero padding included, as 0.1.1 does (the walls, omitted in padded mode, never);
//! unpadded, the records present (0.1.1's vectors have no padding records then), so socnav's
//! padding past the counts stays zero.
//!
//! Draws: one stream per environment and step (kind [`STREAM_OBS_NOISE`], sub-index the tick, so
//! a reset's observation uses tick 0 of the new episode). The noise of the value at index `i` of
//! the environment's observation row takes draws 2i and 2i + 1 (one Box–Muller normal), so every
//! value's noise is a pure function of its position, computable in any order (one GPU thread per
//! value).

use crate::params::{NOISE_ROBOT, StepParams};
use crate::rng::RngStream;
use crate::spec::{ObsLayout, RECORD};
use crate::state::StateChunk;

/// RNG stream kind of the observation noise (`sub` = tick). Kinds 1-6 are the scenario, goals,
/// avoid-robot, group-noise, formation and social-event streams.
pub const STREAM_OBS_NOISE: u32 = 7;

/// Add the configured noise to the observation `row` of environment `e` whose per-type record
/// counts are `counts`.
pub(super) fn add_noise(
    p: &StepParams,
    s: &StateChunk,
    e: usize,
    layout: &ObsLayout,
    counts: &[u32; 5],
    row: &mut [f32],
) {
    let base = super::super::step_stream(s, e, STREAM_OBS_NOISE).base;
    let [mean, std] = p.obs_noise[NOISE_ROBOT];
    if mean != 0.0 || std != 0.0 {
        perturb(&mut row[6..8], 6, base, mean, std);
    }
    for (t, &[mean, std]) in p.obs_noise[..5].iter().enumerate() {
        if mean == 0.0 && std == 0.0 {
            continue;
        }
        let records = if p.obs_padded != 0 {
            layout.capacity[t]
        } else {
            counts[t] as usize
        };
        let first = layout.offset[t];
        for k in 0..records {
            let at = first + k * RECORD + 6;
            perturb(&mut row[at..at + RECORD - 6], at, base, mean, std);
        }
    }
}

/// Add noise to `values`, the row's values from index `first` on.
#[inline]
fn perturb(values: &mut [f32], first: usize, base: u32, mean: f32, std: f32) {
    for (v, i) in values.iter_mut().zip(first..) {
        *v += sample(base, i, mean, std);
    }
}

/// The noise of the value at row index `i`: N(mean, std) from draws 2i and 2i + 1 of the
/// environment's step stream `base`.
#[inline]
fn sample(base: u32, i: usize, mean: f32, std: f32) -> f32 {
    let mut rng = RngStream {
        base,
        draw: 2 * i as u32,
    };
    rng.gauss(mean, std)
}
