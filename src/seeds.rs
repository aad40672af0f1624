//! Episode seeds (docs/spec.md, determinism), host-side: every episode is named by one u64 seed,
//! which keys all its draws ([`crate::rng::RngStream::new`]). A batch seeded with s gives
//! environment i the seed s + i; each later episode of an environment takes [`next_episode_seed`]
//! of the previous one, a Weyl sequence (add the odd 64-bit golden-ratio constant): environment i's
//! k-th episode has the seed s + i + k·G, distinct for every (i, k) of any practical batch (k·G mod
//! 2^64 is never a small number for small k ≠ 0). Resets run on the host (the GPU copies
//! reset-pool rows), so the sequence has no WGSL twin; state columns and the GPU hold a seed as
//! two u32 words.

/// The odd 64-bit golden-ratio constant 2^64/φ: the step of the episode-seed sequence.
pub const EPISODE_SEED_STEP: u64 = 0x9e37_79b9_7f4a_7c15;

/// The seed of the episode after the one of seed `seed` in the same environment: `seed` plus
/// [`EPISODE_SEED_STEP`], wrapping (a Weyl sequence of period 2^64 over every u64).
#[inline]
pub const fn next_episode_seed(seed: u64) -> u64 {
    seed.wrapping_add(EPISODE_SEED_STEP)
}

/// The low and high 32-bit words of a u64 (how a seed is stored in state columns and on the GPU).
#[inline]
pub const fn seed_words(seed: u64) -> (u32, u32) {
    (seed as u32, (seed >> 32) as u32)
}

/// The u64 of low and high words `lo`, `hi` (inverse of [`seed_words`]).
#[inline]
pub const fn seed_from_words(lo: u32, hi: u32) -> u64 {
    lo as u64 | ((hi as u64) << 32)
}
