//! Counter-based random numbers: every draw is a pure function of
//! (episode seed, stream, draw).
//!
//! Why counter-based: the simulation must give the same trajectory for the same seed and actions
//! on any machine, any thread count and on both backends, bit for bit (docs/spec.md, determinism).
//! A draw therefore depends only on its key, never on a global generator, on evaluation order or on
//! the wall clock, and it is computed with 32-bit integer operations only (wrapping multiply and
//! add, xor, shifts), because WGSL has no u64 and no 32×32→64 multiply.
//! `shaders/common/rng.wgsl` is the line-by-line twin of this file (`RngStream::next_u32` there
//! is `rng_next_u32`, and so on); both use the same hexadecimal constants, which
//! `tests/suite/foundations/shaders_validate.rs` checks.
//!
//! # Construction
//!
//! - The mixer is Chris Wellons' `lowbias32` ([`mix32`]), a bijection on u32 with very low
//!   avalanche bias: `x ^= x >> 16; x *= 0x7feb352d; x ^= x >> 15; x *= 0x846ca68b; x ^= x >> 16`.
//! - The stream base chains the mixer over the key words, starting from a fixed non-zero value:
//!   `h = mix32(h ^ w)` for w = seed_lo, seed_hi, stream, in that order (the u64 episode seed is
//!   split into its low and high 32-bit words, the two columns the GPU holds it in).
//! - Draw number d of a stream is `mix32(base ^ mix32(d ^ DRAW_TWEAK))`. Consecutive draws feed
//!   unrelated words into the outer mixer, and a stream's draws never depend on each other, so
//!   any draw can be computed directly, in any order, in parallel.
//!
//! The only state is [`RngStream`] `{ base, draw }`: eight bytes, copied to and from the GPU as
//! two u32. Each consumer owns its stream (per env, per purpose) and keeps the draw counter; the
//! conversions below consume a fixed number of draws each, which is part of the contract.
//!
//! # Episode seeds
//!
//! Every episode is named by one u64 episode seed, and every draw of the episode (its scenario,
//! every step's noise and events) is keyed by that seed alone, never by the environment's place
//! in the batch: an episode replays alone, in a batch of any size, from its seed. An environment's
//! episodes follow a fixed sequence, host-side ([`crate::seeds`]).
//!
//! Conversions: [`RngStream::next_f32`] is `(u >> 8) as f32 * 2^-24` (24 random bits, uniform on
//! the grid k·2^-24 of [0, 1)); everything else is built from it with the exact expressions
//! documented on each method, mirrored in WGSL.

use crate::math;

/// Fixed non-zero start of the key chain (the golden-ratio constant), so that an all-zero key
/// does not start the chain at the mixer's fixed point 0.
const KEY_IV: u32 = 0x9e3779b9;
/// Xor-ed onto the draw counter before mixing, so that draw 0 is not `mix32(base)` (which is
/// how the chain would continue with a zero key word).
const DRAW_TWEAK: u32 = 0x85ebca6b;
/// Start of the chain of [`stream_id`], distinct from [`KEY_IV`].
const STREAM_ID_IV: u32 = 0xc2b2ae35;
/// lowbias32 multipliers.
const MIX_M1: u32 = 0x7feb352d;
const MIX_M2: u32 = 0x846ca68b;
/// 2^-24: maps the top 24 bits of a draw to [0, 1) exactly.
const U24_SCALE: f32 = f32::from_bits(0x33800000);

/// Chris Wellons' `lowbias32` integer hash: a bijection on u32 whose output bits each flip with
/// probability close to 1/2 when any input bit flips. `mix32(0) == 0`.
#[inline]
pub fn mix32(x: u32) -> u32 {
    let mut x = x;
    x ^= x >> 16;
    x = x.wrapping_mul(MIX_M1);
    x ^= x >> 15;
    x = x.wrapping_mul(MIX_M2);
    x ^= x >> 16;
    x
}

/// A stream id for a purpose `kind` (e.g. "human placement", "per-tick social events") and a
/// sub-index `sub` (e.g. the tick number or the entity slot).
///
/// Computed as `mix32(mix32(STREAM_ID_IV ^ kind) ^ sub)`. For a fixed `kind`, distinct `sub`
/// give distinct ids (the mixer is a bijection); ids of different kinds look unrelated and
/// collide only by chance (probability 2^-32 per pair). Streams built from distinct ids are
/// statistically independent for all practical purposes.
#[inline]
pub fn stream_id(kind: u32, sub: u32) -> u32 {
    mix32(mix32(STREAM_ID_IV ^ kind) ^ sub)
}

/// One random stream: the base hash of its key and the number of draws taken so far.
///
/// `Copy` on purpose: a stream is a value (its key hash and a counter), cheap to store per env
/// in a column and to hand to the GPU. Copying a stream and drawing from both copies repeats
/// the same numbers, which is what determinism means here.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct RngStream {
    /// Hash of (episode seed, stream); see the module docs.
    pub base: u32,
    /// Index of the next draw.
    pub draw: u32,
}

impl RngStream {
    /// The stream for key (episode seed, stream), positioned at draw 0.
    #[inline]
    pub fn new(seed: u64, stream: u32) -> Self {
        let (seed_lo, seed_hi) = crate::seeds::seed_words(seed);
        Self::from_seed_words(seed_lo, seed_hi, stream)
    }

    /// Same as [`RngStream::new`], with the seed given as its low and high 32-bit words, the way
    /// the state columns and the GPU hold it (`rng_new` in WGSL).
    #[inline]
    pub fn from_seed_words(seed_lo: u32, seed_hi: u32, stream: u32) -> Self {
        let mut h = KEY_IV;
        h = mix32(h ^ seed_lo);
        h = mix32(h ^ seed_hi);
        h = mix32(h ^ stream);
        Self { base: h, draw: 0 }
    }

    /// Draw number `draw` of the stream with base `base`, without touching any state.
    #[inline]
    pub fn u32_at(base: u32, draw: u32) -> u32 {
        mix32(base ^ mix32(draw ^ DRAW_TWEAK))
    }

    /// Next 32 uniformly distributed bits (one draw). The counter wraps after 2^32 draws.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let u = Self::u32_at(self.base, self.draw);
        self.draw = self.draw.wrapping_add(1);
        u
    }

    /// Uniform on [0, 1), exactly `(next_u32() >> 8) as f32 * 2^-24` (one draw): one of the 2^24
    /// values k·2^-24, so never 1.0, and 0.0 with probability 2^-24.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * U24_SCALE
    }

    /// Uniform on [lo, hi], exactly `lo + (hi - lo) * next_f32()` (one draw), as Python's
    /// `random.uniform`. The result can equal `hi` through rounding; swapped bounds work too.
    #[inline]
    pub fn uniform(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }

    /// Standard normal N(0, 1) by Box–Muller (two draws, one value returned).
    ///
    /// Exactly: `u1 = 1.0 - next_f32()` (in (0, 1], so the logarithm is finite), then
    /// `u2 = next_f32()`, then `sqrt(-2.0 * ln(u1)) * cos(TAU * u2)` with [`math::ln`],
    /// [`math::cos`] and [`math::TAU`]. |result| ≤ about 5.8 since u1 ≥ 2^-24. When u1 = 1
    /// (probability 2^-24) the result is ±0, with the sign of `-0.0 * cos`, the same on both
    /// backends (a `0.0 - x` form would not be: the GPU compiler drops the `0.0 -`).
    #[inline]
    pub fn normal(&mut self) -> f32 {
        let u1 = 1.0 - self.next_f32();
        let u2 = self.next_f32();
        (-2.0 * math::ln(u1)).sqrt() * math::cos(math::TAU * u2)
    }

    /// Normal with the given mean and standard deviation, exactly `mean + std_dev * normal()`
    /// (two draws), as numpy's `random.normal(mean, std_dev)`.
    #[inline]
    pub fn gauss(&mut self, mean: f32, std_dev: f32) -> f32 {
        mean + std_dev * self.normal()
    }

    /// Uniform integer in [0, n) for 1 ≤ n ≤ 2^24 (one draw).
    ///
    /// Exactly `min(floor(next_f32() * n as f32) as u32, n - 1)`: each value has probability
    /// ⌊2^24/n⌋·2^-24 or ⌈2^24/n⌉·2^-24 (bias below n·2^-24). `below(0)` returns 0 (the `n - 1`
    /// wraps, as in WGSL) and still consumes its draw.
    #[inline]
    pub fn below(&mut self, n: u32) -> u32 {
        let x = (self.next_f32() * n as f32).floor() as u32;
        x.min(n.wrapping_sub(1))
    }

    /// Uniform integer in [lo, hi], both inclusive, like Python's `random.randint` (one draw).
    ///
    /// Exactly `lo + below(hi - lo + 1)` in wrapping 32-bit arithmetic. Needs lo ≤ hi and
    /// hi - lo < 2^24; `randint(x, x)` is x.
    #[inline]
    pub fn randint(&mut self, lo: i32, hi: i32) -> i32 {
        let span = (hi.wrapping_sub(lo) as u32).wrapping_add(1);
        lo.wrapping_add(self.below(span) as i32)
    }

    /// True with probability p, exactly `next_f32() < p` (one draw): never for p ≤ 0, always for
    /// p ≥ 1.
    #[inline]
    pub fn chance(&mut self, p: f32) -> bool {
        self.next_f32() < p
    }
}
