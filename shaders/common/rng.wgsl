// requires: common/math.wgsl
//
// Twin of src/rng.rs: the counter-based random streams keyed by (episode seed, stream, draw).
//
// Library file (no entry points), prepended, after common/math.wgsl (which `rng_normal` uses), to
// the stage shaders that draw random numbers. Every function mirrors its Rust twin operation for
// operation (`RngStream::next_f32` is `rng_next_f32`, `rng::stream_id` is `rng_stream_id`, and
// so on), with 32-bit integer operations only; read the Rust file for the construction and the
// exact contract of each conversion, and change both files in the same commit.
//
// WGSL has no u64: an episode seed is held as its low and high 32-bit words (state columns
// `seed_lo`/`seed_hi`, `rng_new`). A stream lives
// in a function-scope `var` while drawing; a stage copies it in from its column and writes it
// back so that the draw counter advances exactly as on the CPU.

const RNG_KEY_IV: u32 = 0x9e3779b9u;
const RNG_DRAW_TWEAK: u32 = 0x85ebca6bu;
const RNG_STREAM_ID_IV: u32 = 0xc2b2ae35u;
const RNG_MIX_M1: u32 = 0x7feb352du;
const RNG_MIX_M2: u32 = 0x846ca68bu;
// Exactly 2^-24.
const RNG_U24_SCALE: f32 = 0x1p-24f;

struct RngStream {
    base: u32,
    draw: u32,
}

// Chris Wellons' lowbias32.
fn rng_mix32(x_in: u32) -> u32 {
    var x = x_in;
    x = x ^ (x >> 16u);
    x = x * RNG_MIX_M1;
    x = x ^ (x >> 15u);
    x = x * RNG_MIX_M2;
    x = x ^ (x >> 16u);
    return x;
}

fn rng_stream_id(kind: u32, sub: u32) -> u32 {
    return rng_mix32(rng_mix32(RNG_STREAM_ID_IV ^ kind) ^ sub);
}

// RngStream::from_seed_words (RngStream::new splits the u64 seed into these two words).
fn rng_new(seed_lo: u32, seed_hi: u32, stream: u32) -> RngStream {
    var h = RNG_KEY_IV;
    h = rng_mix32(h ^ seed_lo);
    h = rng_mix32(h ^ seed_hi);
    h = rng_mix32(h ^ stream);
    return RngStream(h, 0u);
}

fn rng_u32_at(base: u32, draw: u32) -> u32 {
    return rng_mix32(base ^ rng_mix32(draw ^ RNG_DRAW_TWEAK));
}

fn rng_next_u32(s: ptr<function, RngStream>) -> u32 {
    let u = rng_u32_at((*s).base, (*s).draw);
    (*s).draw = (*s).draw + 1u;
    return u;
}

fn rng_next_f32(s: ptr<function, RngStream>) -> f32 {
    return f32(rng_next_u32(s) >> 8u) * RNG_U24_SCALE;
}

fn rng_uniform(s: ptr<function, RngStream>, lo: f32, hi: f32) -> f32 {
    return lo + (hi - lo) * rng_next_f32(s);
}

fn rng_normal(s: ptr<function, RngStream>) -> f32 {
    let u1 = 1.0 - rng_next_f32(s);
    let u2 = rng_next_f32(s);
    return sqrt(-2.0 * math_ln(u1)) * math_cos(MATH_TAU * u2);
}

fn rng_gauss(s: ptr<function, RngStream>, mean: f32, std_dev: f32) -> f32 {
    return mean + std_dev * rng_normal(s);
}

fn rng_below(s: ptr<function, RngStream>, n: u32) -> u32 {
    let x = u32(floor(rng_next_f32(s) * f32(n)));
    return min(x, n - 1u);
}

fn rng_randint(s: ptr<function, RngStream>, lo: i32, hi: i32) -> i32 {
    let span = u32(hi - lo) + 1u;
    return lo + i32(rng_below(s, span));
}

fn rng_chance(s: ptr<function, RngStream>, p: f32) -> bool {
    return rng_next_f32(s) < p;
}
