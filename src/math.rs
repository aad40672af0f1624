//! The only home of transcendental maths in the simulation (f32).
//!
//! Why our own maths: the CPU backend and the WGSL shaders must produce bit-identical state on
//! lavapipe (docs/spec.md, determinism). Builtin transcendentals differ between Rust's libm and the
//! shader compiler by up to hundreds of ULP, while `+ - * /`, `sqrt`, `abs`, `floor`, `min`/`max`,
//! comparisons, integer operations and bit casts are exact on both sides (docs/spec.md,
//! bit parity). So every function here is built from those operations only, and
//! `shaders/common/math.wgsl` is its line-by-line twin (`math::sin` there is `math_sin`, and so on).
//!
//! Invariants, which the twin must keep too:
//! - No `mul_add`/`fma`: `a * b + c` is written out and evaluated unfused on both sides.
//! - Every expression tree is written in the order the twin uses; polynomials are explicit,
//!   unfused Horner schemes `((c3 * x + c2) * x + c1) * x + c0`. Do not "simplify" an expression
//!   here without changing the WGSL in the same commit.
//! - Constants that are not small exact decimals are given by their bits (`f32::from_bits`), and
//!   the twin writes the same values as exact hexadecimal floats (`0x1.921fb6p1f`);
//!   `tests/suite/foundations/shaders_validate.rs` checks that both files denote the same set of
//!   bit patterns.
//! - The shader compiler is not neutral. lavapipe runs Mesa's NIR optimiser, which applies
//!   algebraic rewrites that are not bit-exact to every float operation that SPIR-V does not mark
//!   exact (naga never does). Among them: cancellations such as `(a + b) - a → b` (so TwoSum /
//!   Fast2Sum error terms become 0 on the GPU), factoring `a·c + b·c → (a + b)·c`, moving a
//!   constant into a sum whose result is used once, `(a + b) + C → (a + C) + b`, and
//!   `x + 0 → x`, `x·1 → x`, `x·0 → 0`. So this file uses no error-free transformations and avoids
//!   those shapes; where a natural form had one, the comment there says so. Every function was
//!   checked bit for bit against its twin on lavapipe (Mesa 22.3.6, over 7 million inputs
//!   including special values and the hard cases of each reduction); the parity test itself lands
//!   with the wgpu backend.
//! - Float-to-integer conversions only ever see finite, in-range values (out-of-range and NaN
//!   conversions are not portable to WGSL); special inputs are routed around them and selected at
//!   the end. `min`/`max`/`clamp` (whose NaN and ±0 handling is not portable) only see operands
//!   that are neither NaN nor a signed-zero tie, or their result is discarded for NaN inputs.
//!
//! Accuracy is given per function as the maximum distance, in units in the last place, from the
//! correctly rounded result, measured by `tests/suite/foundations/math_accuracy.rs` over the domain
//! stated.

/// π rounded to f32 (the same value as `std::f32::consts::PI`).
pub const PI: f32 = f32::from_bits(0x40490fdb);
/// 2π rounded to f32 (exactly `2.0 * PI`; the same value as `std::f32::consts::TAU`).
pub const TAU: f32 = f32::from_bits(0x40c90fdb);
/// π/2 rounded to f32 (exactly `0.5 * PI`; the same value as `std::f32::consts::FRAC_PI_2`).
pub const FRAC_PI_2: f32 = f32::from_bits(0x3fc90fdb);

/// Largest |x| accepted by [`sin`], [`cos`] and [`sin_cos`] (2^20 rad); beyond it they return NaN.
///
/// Past about 2^24 the reduction modulo π/2 would be meaningless, and anything above 2^20 rad in
/// the simulation is a bug that a NaN makes loud.
pub const SIN_COS_MAX_ARG: f32 = 1048576.0;

/// Largest |x| that [`acos`] accepts (1 + 2^-12): inputs in `(1, 1 + 2^-12]` are clamped to 1 (and
/// likewise for -1), because a dot product of unit vectors can round slightly past 1. Beyond it,
/// `acos` returns NaN like `f32::acos`.
pub const ACOS_DOMAIN_MAX: f32 = f32::from_bits(0x3f800800);

const NAN_BITS: u32 = 0x7fc00000;
const INF_BITS: u32 = 0x7f800000;
const NAN: f32 = f32::from_bits(NAN_BITS);
const INF: f32 = f32::from_bits(INF_BITS);
const SIGN_MASK: u32 = 0x80000000;
const ABS_MASK: u32 = 0x7fffffff;

/// NaN test on the bits, as the WGSL twin does it (a float self-comparison could be folded away
/// by a shader compiler that assumes no NaNs).
#[inline]
fn is_nan_bits(x: f32) -> bool {
    (x.to_bits() & ABS_MASK) > INF_BITS
}

// ---- sin / cos -------------------------------------------------------------------------------

/// floor(v), exactly as `f32::floor` and WGSL's `floor` for every input (±0, ±∞ and NaN
/// included), without a call: on the x86-64 baseline (no SSE4.1) `f32::floor` is a libm call,
/// which took 5 % of a step.
#[inline]
fn floor(v: f32) -> f32 {
    // |v| ≥ 2^23 is already an integer (or ±∞); NaN passes through.
    if v.is_nan() || v.abs() >= 8_388_608.0 {
        return v;
    }
    let t = (v as i32) as f32;
    if t > v {
        t - 1.0
    } else if t < v {
        t
    } else {
        v // v is an integer: keeps the sign of -0.0
    }
}

/// 2/π rounded to f32: picks the multiple k of π/2 nearest to x.
const FRAC_2_PI: f32 = f32::from_bits(0x3f22f983);
// π/2 = C1 + C2 + C3 + C4 + C5 (to about 2^-64). C1..C4 have 10 significant bits each, so
// `k * Ci` is exact for k < 2^14 (|x| up to about 25,700 rad); C5 is the f32-rounded rest, whose
// product with k is below 2^-26 and rounds far below an ULP of any reduced argument.
const PIO2_C1: f32 = f32::from_bits(0x3fc90000);
const PIO2_C2: f32 = f32::from_bits(0x39fd0000);
const PIO2_C3: f32 = f32::from_bits(0x35aa0000);
const PIO2_C4: f32 = f32::from_bits(0x30884000);
const PIO2_C5: f32 = f32::from_bits(0x2b51846a);
// The other split for large reduced arguments: C3B holds the bits of π/2 from 2^-20 to 2^-24
// (5 significant bits), C4B is the f32-rounded rest.
const PIO2_C3B: f32 = f32::from_bits(0x35a80000);
const PIO2_C4B: f32 = f32::from_bits(0x328885a3);
/// 2^-6: reduced arguments at least this large take the one-rounding variant.
const REDUCE_SPLIT: f32 = 0.015625;
// Cephes sinf/cosf minimax coefficients on [-π/4, π/4].
const SIN_P0: f32 = f32::from_bits(0xbe2aaaa3);
const SIN_P1: f32 = f32::from_bits(0x3c08839e);
const SIN_P2: f32 = f32::from_bits(0xb94ca1f9);
const COS_P0: f32 = f32::from_bits(0x3d2aaaa5);
const COS_P1: f32 = f32::from_bits(0xbab6061a);
const COS_P2: f32 = f32::from_bits(0x37ccf5ce);

/// Cody–Waite reduction of `ax` (0 ≤ ax ≤ [`SIN_COS_MAX_ARG`]) modulo π/2.
///
/// Returns `(r, k)` with `ax ≈ k·π/2 + r` and |r| ≤ π/4 (plus a few ULP). For k < 2^14 all the
/// products `k * Ci` are exact and the first two subtractions are exact (Sterbenz, then a result
/// on the 2^-24 grid below 1). Then two variants, chosen by the size of r:
/// - |r| ≥ 2^-6: subtract the chunk that ends at 2^-24 (exact again) and the f32-rounded rest of
///   π/2 in one product: one rounding at the scale of r, plus an error below 2^-33 from the rest.
/// - |r| < 2^-6: subtract 10-bit chunks down to 2^-39 and the rounded rest; every step is exact
///   while its result is small, so tiny r (down to 2^-28 in this domain) keep their accuracy.
///
/// No error-free transformation (TwoSum) carries the rounding errors along: Mesa's NIR optimiser,
/// which lavapipe runs on every shader, rewrites `(a + b) - a` into `b` for floating-point
/// operations that SPIR-V does not mark exact (naga never does), so compensation terms would be
/// computed on the CPU and folded to zero on the GPU.
#[inline]
fn reduce_pio2(ax: f32) -> (f32, i32) {
    let k = floor(ax * FRAC_2_PI + 0.5);
    let t = ax - k * PIO2_C1;
    let t = t - k * PIO2_C2;
    let r_big = (t - k * PIO2_C3B) - k * PIO2_C4B;
    let r_small = ((t - k * PIO2_C3) - k * PIO2_C4) - k * PIO2_C5;
    let r = if r_big.abs() >= REDUCE_SPLIT {
        r_big
    } else {
        r_small
    };
    (r, k as i32)
}

/// sin(r) for |r| ≤ π/4.
#[inline]
fn sin_kernel(r: f32) -> f32 {
    let z = r * r;
    let p = (SIN_P2 * z + SIN_P1) * z + SIN_P0;
    r + r * z * p
}

/// cos(r) for |r| ≤ π/4, as 1 - (z/2 - z²·Q(z)): the small terms are combined first so that the
/// only rounding at the scale of the result is the last one.
#[inline]
fn cos_kernel(r: f32) -> f32 {
    let z = r * r;
    let q = (COS_P2 * z + COS_P1) * z + COS_P0;
    let hz = 0.5 * z;
    1.0 - (hz - z * z * q)
}

/// Gives `v` the sign bit of `v` xor the sign bit of `s` (an exact, branch-free sign transfer).
#[inline]
fn xor_sign(v: f32, s: f32) -> f32 {
    f32::from_bits(v.to_bits() ^ (s.to_bits() & SIGN_MASK))
}

/// Sine of `x` (rad).
///
/// Accuracy: ≤ 2 ULP for |x| ≤ 25,735 (2^14·π/2, where the reduction's products are exact;
/// checked over every f32 there). For larger |x| up to [`SIN_COS_MAX_ARG`] the absolute error
/// grows to about |x|·2^-24 (at most the spacing of f32 values around x, so the input's own
/// rounding dominates). NaN for |x| > 2^20, ±∞ and NaN. Odd: `sin(-x) == -sin(x)`,
/// `sin(-0) = -0`.
#[inline]
pub fn sin(x: f32) -> f32 {
    let ax = x.abs();
    let ok = ax <= SIN_COS_MAX_ARG;
    let ax = if ok { ax } else { 0.0 };
    let (r, k) = reduce_pio2(ax);
    let v = if (k & 1) == 0 {
        sin_kernel(r)
    } else {
        cos_kernel(r)
    };
    let v = if (k & 2) == 0 { v } else { -v };
    if ok { xor_sign(v, x) } else { NAN }
}

/// Cosine of `x` (rad). Same domain and accuracy as [`sin`]; even, `cos(-x) == cos(x)`.
#[inline]
pub fn cos(x: f32) -> f32 {
    let ax = x.abs();
    let ok = ax <= SIN_COS_MAX_ARG;
    let ax = if ok { ax } else { 0.0 };
    let (r, k) = reduce_pio2(ax);
    let v = if (k & 1) == 0 {
        cos_kernel(r)
    } else {
        sin_kernel(r)
    };
    let v = if ((k + 1) & 2) == 0 { v } else { -v };
    if ok { v } else { NAN }
}

/// `(sin(x), cos(x))` with one shared range reduction; bit-identical to calling [`sin`] and
/// [`cos`] separately.
#[inline]
pub fn sin_cos(x: f32) -> (f32, f32) {
    let ax = x.abs();
    let ok = ax <= SIN_COS_MAX_ARG;
    let ax = if ok { ax } else { 0.0 };
    let (r, k) = reduce_pio2(ax);
    let s = sin_kernel(r);
    let c = cos_kernel(r);
    let (vs, vc) = if (k & 1) == 0 { (s, c) } else { (c, s) };
    let vs = if (k & 2) == 0 { vs } else { -vs };
    let vc = if ((k + 1) & 2) == 0 { vc } else { -vc };
    if ok {
        (xor_sign(vs, x), vc)
    } else {
        (NAN, NAN)
    }
}

// ---- atan2 / atan / acos ----------------------------------------------------------------------

/// tan(π/8): above it the octant argument t is folded as (t - 1)/(t + 1) around π/4.
const TAN_PI_8: f32 = f32::from_bits(0x3ed413cd);
// Multiples j·π/4 as hi + lo pairs (hi = f32 nearest, lo = f32 nearest of the rest).
const PIO4_HI: f32 = f32::from_bits(0x3f490fdb);
const PIO4_LO: f32 = f32::from_bits(0xb2bbbd2e);
const PIO2_HI: f32 = f32::from_bits(0x3fc90fdb);
const PIO2_LO: f32 = f32::from_bits(0xb33bbd2e);
const PI3O4_HI: f32 = f32::from_bits(0x4016cbe4);
const PI3O4_LO: f32 = f32::from_bits(0xb1ccde2e);
const PI_HI: f32 = f32::from_bits(0x40490fdb);
const PI_LO: f32 = f32::from_bits(0xb3bbbd2e);
// Cephes atanf coefficients on [-tan(π/8), tan(π/8)]: atan(t) ≈ t + t·z·P(z), z = t².
const ATAN_P0: f32 = f32::from_bits(0xbeaaaa2a);
const ATAN_P1: f32 = f32::from_bits(0x3e4c925f);
const ATAN_P2: f32 = f32::from_bits(0xbe0e1b85);
const ATAN_P3: f32 = f32::from_bits(0x3da4f0d1);

/// Four-quadrant arctangent of `y/x` (rad), in [-π, π].
///
/// Follows IEEE 754 / `f32::atan2` for every special case: `atan2(±0, +0) = ±0`,
/// `atan2(±0, -0) = ±π`, `atan2(±0, x<0) = ±π`, `atan2(y≠0, ±0) = ±π/2`, `atan2(±∞, +∞) = ±π/4`,
/// `atan2(±∞, -∞) = ±3π/4`, `atan2(±y, +∞) = ±0`, `atan2(±y, -∞) = ±π`, NaN in → NaN out.
/// The sign of the result is the sign bit of `y` (so `-0.0` matters, as in std).
///
/// Accuracy: ≤ 2 ULP over all finite inputs whose result is a normal number.
///
/// Method: reduce to the first octant with t = min(|x|,|y|)/max(|x|,|y|) (no overflow), fold t
/// above tan(π/8) as (mn - mx)/(mn + mx) around π/4, evaluate the odd polynomial, then add the
/// octant's multiple of π/4 as an exact hi/lo pair.
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    let ax = x.abs();
    let ay = y.abs();
    let swap = ay > ax;
    let mut mx = if swap { ay } else { ax };
    let mut mn = if swap { ax } else { ay };
    // Infinities become the ratios 1/1 or 0/1, and 0/0 becomes 0/1, so that the general path
    // below yields the IEEE special values without a NaN.
    if mx == INF {
        mn = if mn == INF { 1.0 } else { 0.0 };
        mx = 1.0;
    }
    if mx == 0.0 {
        mx = 1.0;
    }
    let big = mn > mx * TAN_PI_8;
    let t = if big { (mn - mx) / (mn + mx) } else { mn / mx };
    let z = t * t;
    let p = t + t * z * (((ATAN_P3 * z + ATAN_P2) * z + ATAN_P1) * z + ATAN_P0);
    // Angle = j·π/4 + (±p): j counts quarter-π steps of the octant fold, swap and x < 0.
    let mut j: u32 = if big { 1 } else { 0 };
    let mut neg = false;
    if swap {
        j = 2 - j;
        neg = true;
    }
    if (x.to_bits() & SIGN_MASK) != 0 {
        j = 4 - j;
        neg = !neg;
    }
    let (c_hi, c_lo) = match j {
        0 => (0.0, 0.0),
        1 => (PIO4_HI, PIO4_LO),
        2 => (PIO2_HI, PIO2_LO),
        3 => (PI3O4_HI, PI3O4_LO),
        _ => (PI_HI, PI_LO),
    };
    let sp = if neg { -p } else { p };
    let theta = c_hi + (c_lo + sp);
    let theta = xor_sign(theta, y);
    if is_nan_bits(x) || is_nan_bits(y) {
        NAN
    } else {
        theta
    }
}

/// Arctangent of `x` (rad), in [-π/2, π/2]; exactly `atan2(x, 1.0)`.
///
/// Accuracy: ≤ 2 ULP for all finite x with a normal result; `atan(±∞) = ±π/2`, `atan(-0) = -0`.
#[inline]
pub fn atan(x: f32) -> f32 {
    atan2(x, 1.0)
}

// Cephes asinf coefficients for |a| ≤ 1/2: asin(a) ≈ a + a·z·P(z), z = a².
const ASIN_P0: f32 = f32::from_bits(0x3e2aaae4);
const ASIN_P1: f32 = f32::from_bits(0x3d9980f6);
const ASIN_P2: f32 = f32::from_bits(0x3d3a3ec7);
const ASIN_P3: f32 = f32::from_bits(0x3cc617e3);
const ASIN_P4: f32 = f32::from_bits(0x3d2cb352);
/// Clears the low 12 mantissa bits so that `df * df` is exact (fdlibm's acosf trick).
const ACOS_DF_MASK: u32 = 0xfffff000;

/// z·P(z) with asin(a) = a + a·z·P(z) for z = a² ≤ 1/4.
#[inline]
fn asin_r(z: f32) -> f32 {
    z * ((((ASIN_P4 * z + ASIN_P3) * z + ASIN_P2) * z + ASIN_P1) * z + ASIN_P0)
}

/// Arccosine of `x` (rad), in [0, π].
///
/// Domain [-1, 1]; inputs within [`ACOS_DOMAIN_MAX`] of ±1 are clamped to ±1, larger |x| and NaN
/// give NaN. Accuracy: ≤ 1 ULP over [-1, 1]. `acos(1) = 0`, `acos(-1) = PI`.
///
/// Method (fdlibm acosf with a polynomial in place of its rational function): for |x| ≤ 1/2,
/// π/2 - asin(x); for x > 1/2, 2·asin(√((1-x)/2)) with the square root split into an exact high
/// part and a correction; for x < -1/2, π - 2·asin(√((1+x)/2)).
#[inline]
pub fn acos(x: f32) -> f32 {
    let ok = x.abs() <= ACOS_DOMAIN_MAX;
    let x = x.clamp(-1.0, 1.0);
    let v = if x > 0.5 {
        let z = (1.0 - x) * 0.5;
        let s = z.sqrt();
        let df = f32::from_bits(s.to_bits() & ACOS_DF_MASK);
        let c = (z - df * df) / (s + df);
        let w = s * asin_r(z) + c;
        // x == 1 makes c = 0/0; its exact result is +0.
        if x == 1.0 { 0.0 } else { 2.0 * (df + w) }
    } else if x < -0.5 {
        let z = (1.0 + x) * 0.5;
        let s = z.sqrt();
        let w = s * asin_r(z) - PIO2_LO;
        PI_HI - 2.0 * (s + w)
    } else {
        let z = x * x;
        PIO2_HI - (x - (PIO2_LO - x * asin_r(z)))
    };
    if ok { v } else { NAN }
}

// ---- exp / ln / softplus ----------------------------------------------------------------------

const LOG2E: f32 = f32::from_bits(0x3fb8aa3b);
// ln 2 = LN2_HI + LN2_LO; LN2_HI has 9 significant bits so `n * LN2_HI` is exact for |n| < 2^15.
const LN2_HI: f32 = f32::from_bits(0x3f318000);
const LN2_LO: f32 = f32::from_bits(0xb95e8083);
// Cephes expf coefficients: e^r ≈ 1 + r + r²·P(r) on [-ln2/2, ln2/2], evaluated as the Horner
// scheme (P(r)·r + 1)·r + 1. (Cephes writes P(r)·r² + r + 1, but Mesa's NIR optimiser
// reassociates `(a + b) + 1.0` on the GPU, which would round differently.)
const EXP_P0: f32 = 0.5;
const EXP_P1: f32 = f32::from_bits(0x3e2aaaaa);
const EXP_P2: f32 = f32::from_bits(0x3d2aa9c1);
const EXP_P3: f32 = f32::from_bits(0x3c088908);
const EXP_P4: f32 = f32::from_bits(0x3ab743ce);
const EXP_P5: f32 = f32::from_bits(0x39506967);
/// e^89 > f32::MAX and e^-104 < 2^-150 (half the smallest subnormal), so clamping the argument to
/// [-104, 89] changes no result while keeping the exponent arithmetic in range.
const EXP_ARG_MIN: f32 = -104.0;
const EXP_ARG_MAX: f32 = 89.0;

/// 2^n as f32 for -126 ≤ n ≤ 127, built from its bits.
#[inline]
fn pow2i(n: i32) -> f32 {
    f32::from_bits(((n + 127) as u32) << 23)
}

/// e^x.
///
/// Accuracy: ≤ 1 ULP wherever the result is normal; subnormal results are rounded once from a
/// slightly inexact value. Overflow gives +∞ (x > about 88.72), underflow gives +0
/// (x < about -103.97), `exp(-∞) = 0`, `exp(+∞) = +∞`, NaN → NaN.
#[inline]
pub fn exp(x: f32) -> f32 {
    let nan = is_nan_bits(x);
    let xc = if nan { 0.0 } else { x };
    let xc = xc.clamp(EXP_ARG_MIN, EXP_ARG_MAX);
    let n = floor(xc * LOG2E + 0.5);
    let r = xc - n * LN2_HI;
    let r = r - n * LN2_LO;
    let p = ((((EXP_P5 * r + EXP_P4) * r + EXP_P3) * r + EXP_P2) * r + EXP_P1) * r + EXP_P0;
    let y = (p * r + 1.0) * r + 1.0;
    // Scale by 2^n in two exact-exponent steps, since n ranges over [-150, 128] and a single
    // power of two would leave the normal range; only the second product rounds.
    let ni = n as i32;
    let n1 = ni >> 1;
    let n2 = ni - n1;
    let y = y * pow2i(n1) * pow2i(n2);
    if nan { NAN } else { y }
}

const SQRT_HALF: f32 = f32::from_bits(0x3f3504f3);
/// 2^24, to lift subnormal inputs of `ln` into the normal range.
const TWO_POW_24: f32 = f32::from_bits(0x4b800000);
const MIN_POSITIVE: f32 = f32::from_bits(0x00800000);
const MANTISSA_MASK: u32 = 0x007fffff;
/// Exponent field of 0.5: OR-ed onto a mantissa it gives the significand in [0.5, 1).
const HALF_EXPONENT: u32 = 0x3f000000;
// Cephes logf coefficients: ln(1+f) ≈ f - f²/2 + f³·P(f) for f in [√½ - 1, √2 - 1].
const LN_P0: f32 = f32::from_bits(0x3eaaaaaa);
const LN_P1: f32 = f32::from_bits(0xbe7ffffc);
const LN_P2: f32 = f32::from_bits(0x3e4cceac);
const LN_P3: f32 = f32::from_bits(0xbe2aae50);
const LN_P4: f32 = f32::from_bits(0x3e11e9bf);
const LN_P5: f32 = f32::from_bits(0xbdfe5d4f);
const LN_P6: f32 = f32::from_bits(0x3def251a);
const LN_P7: f32 = f32::from_bits(0xbdebd1b8);
const LN_P8: f32 = f32::from_bits(0x3d9021bb);

/// Natural logarithm of `x`.
///
/// Accuracy: ≤ 1 ULP for all positive finite x, subnormals included. `ln(±0) = -∞`,
/// `ln(x < 0) = NaN`, `ln(+∞) = +∞`, NaN → NaN (as `f32::ln`).
///
/// Method (Cephes logf): x = m·2^e with m in [√½, √2), ln x = e·ln2 + ln(1 + f), f = m - 1
/// exact, the polynomial for the tail and ln2 as a hi/lo pair.
#[inline]
pub fn ln(x: f32) -> f32 {
    let sub = x < MIN_POSITIVE;
    let xs = if sub { x * TWO_POW_24 } else { x };
    let bits = xs.to_bits();
    let mut e = ((bits >> 23) & 0xff) as i32 - 126;
    if sub {
        e -= 24;
    }
    let m = f32::from_bits((bits & MANTISSA_MASK) | HALF_EXPONENT);
    let (f, e) = if m < SQRT_HALF {
        (m + m - 1.0, e - 1)
    } else {
        (m - 1.0, e)
    };
    let z = f * f;
    let p = ((((((((LN_P8 * f + LN_P7) * f + LN_P6) * f + LN_P5) * f + LN_P4) * f + LN_P3) * f
        + LN_P2)
        * f
        + LN_P1)
        * f
        + LN_P0)
        * f
        * z;
    let ef = e as f32;
    let y = p + ef * LN2_LO;
    let y = y - 0.5 * z;
    let v = f + y;
    let v = v + ef * LN2_HI;
    if x == INF {
        INF
    } else if x == 0.0 {
        -INF
    } else if x > 0.0 {
        v
    } else {
        // x < 0 or NaN.
        NAN
    }
}

/// √½ - 1 and √2 - 1: for u between them, ln(1 + u) is Cephes' kernel at f = u, exactly.
const LN1P_KERNEL_MIN: f32 = f32::from_bits(0xbe95f61a);
const LN1P_KERNEL_MAX: f32 = f32::from_bits(0x3ed413cd);

/// ln(1 + u), accurate also for tiny |u| where `ln(1.0 + u)` would lose every digit.
///
/// Method: for √½ - 1 ≤ u ≤ √2 - 1, the kernel of [`ln`] applied to f = u directly (so no
/// rounding of 1 + u happens); otherwise `ln(1.0 + u)`, where 1 + u is exact (u < √½ - 1) or its
/// rounding costs at most about one ULP (u > √2 - 1). The textbook log1p tricks recover the
/// rounding error of 1 + u by computing `(1 + u) - 1`, which Mesa's NIR optimiser folds to `u` on
/// the GPU, so they would not be bit-identical.
///
/// Accuracy: ≤ 1 ULP for √½ - 1 ≤ u ≤ √2 - 1 (the range [`softplus`] uses), ≤ 2 ULP elsewhere
/// (normal results). `ln_1p(-1) = -∞`, NaN for
/// u < -1 and NaN, `ln_1p(+∞) = +∞`, `ln_1p(-0) = -0`.
#[inline]
pub fn ln_1p(u: f32) -> f32 {
    if (LN1P_KERNEL_MIN..=LN1P_KERNEL_MAX).contains(&u) {
        let z = u * u;
        // Summed as (u - z/2) + u³·P(u): NIR reassociates the form u + (u³·P(u) - z/2) that ln
        // uses, and factors `a·z + b·z` into `(a + b)·z`, both of which round differently.
        let q = (((((((LN_P8 * u + LN_P7) * u + LN_P6) * u + LN_P5) * u + LN_P4) * u + LN_P3) * u
            + LN_P2)
            * u
            + LN_P1)
            * u
            + LN_P0;
        let p = q * (u * z);
        let y = u - 0.5 * z;
        y + p
    } else {
        ln(1.0 + u)
    }
}

/// ln 2 rounded to f32 (its rounding error, 1.9e-9, is far below an ULP of softplus near 0).
const LN2: f32 = f32::from_bits(0x3f317218);
// ln(cosh y) = y²·G(y²): Taylor coefficients 2^2n (2^2n - 1) B_2n / (2n (2n)!), eight terms,
// relative error below 1e-9 for y² ≤ 1/4.
const LNCOSH_G0: f32 = 0.5;
const LNCOSH_G1: f32 = f32::from_bits(0xbdaaaaab);
const LNCOSH_G2: f32 = f32::from_bits(0x3cb60b61);
const LNCOSH_G3: f32 = f32::from_bits(0xbbdd0dd1);
const LNCOSH_G4: f32 = f32::from_bits(0x3b0f52ea);
const LNCOSH_G5: f32 = f32::from_bits(0xba419ece);
const LNCOSH_G6: f32 = f32::from_bits(0x398685a9);
const LNCOSH_G7: f32 = f32::from_bits(0xb8bed1b2);

/// softplus(x) = ln(1 + e^x), computed stably.
///
/// For |x| > 1 as `max(x, 0) + ln_1p(e^-|x|)`: never overflows (softplus(1e3) = 1e3,
/// softplus(-1e3) = 0) and keeps its relative accuracy for very negative x, where the result is
/// about e^x. For |x| ≤ 1 as `ln 2 + x/2 + ln(cosh(x/2))` with a polynomial for the last term,
/// which avoids the rounding of 1 + e^-|x| that would cost an extra ULP there.
/// Accuracy: ≤ 2 ULP for normal results. Used for the smooth MPE-style contact penetration term.
/// `max(x, 0)` is written as a comparison so that `-0.0` and NaN behave the same on CPU and GPU.
#[inline]
pub fn softplus(x: f32) -> f32 {
    if x.abs() <= 1.0 {
        let y = 0.5 * x;
        let w = y * y;
        let g = ((((((LNCOSH_G7 * w + LNCOSH_G6) * w + LNCOSH_G5) * w + LNCOSH_G4) * w
            + LNCOSH_G3)
            * w
            + LNCOSH_G2)
            * w
            + LNCOSH_G1)
            * w
            + LNCOSH_G0;
        (LN2 + y) + w * g
    } else {
        let pos = if x > 0.0 { x } else { 0.0 };
        pos + ln_1p(exp(-x.abs()))
    }
}

// ---- angles -----------------------------------------------------------------------------------

/// 1/(2π) rounded to f32.
const FRAC_1_TAU: f32 = f32::from_bits(0x3e22f983);
// 2π = TAU_HI + TAU_MID + TAU_LO. TAU_HI has 14 significant bits (lowest 2^-11) and TAU_MID 11
// (lowest 2^-22), so for |k| < 2^10 both products with k are exact, `a - k·TAU_HI` is exact by
// Sterbenz and subtracting `k·TAU_MID` is exact too (the result is below 4 on the 2^-22 grid).
// TAU_LO is the f32-rounded rest (2π is carried to about 2^-46).
const TAU_HI: f32 = f32::from_bits(0x40c90c00);
const TAU_MID: f32 = f32::from_bits(0x39f6a000);
const TAU_LO: f32 = f32::from_bits(0x338885a3);

/// Wraps an angle `a` (rad) to (-π, π], i.e. `-PI < wrap_angle(a) <= PI` always holds.
///
/// Computes `a - 2πk` for the integer k that puts it in (-π, π], with 2π split into three parts
/// so that all but the last, tiny product is exact: for |a| < 6,400 rad (|k| < 2^10) the result is
/// the exactly wrapped angle rounded once (correctly rounded up to an error of about 2^-37 rad
/// before that rounding). For larger |a| the error grows slowly (about |a|·2^-34 absolute).
/// SocNavGym wraps with `atan2(sin a, cos a)`: that gives the same angle up to the rounding of
/// sin, cos and atan2 (a few ULP, with the result at ±π decided by those roundings); this
/// function is cheaper (about 20 flops, no polynomial) and exact.
///
/// Boundaries: the side of ±π is decided on the exact value, so `wrap_angle(PI)` is
/// `-3.1415925` (the f32 `PI` lies 8.7e-8 above π) and `wrap_angle(-PI)` is `3.1415925`. An input
/// whose exactly wrapped value lies within half an ULP above -π, so that it would round to -PI, is
/// returned as `PI` (e.g. `wrap_angle(9.424778)`, as 3π + 2.4e-8 wraps to -π + 2.4e-8).
/// `wrap_angle(-0.0)` is `-0.0`; ±∞ and NaN give NaN.
#[inline]
pub fn wrap_angle(a: f32) -> f32 {
    let k = floor(a * FRAC_1_TAU + 0.5);
    let t = (a - k * TAU_HI) - k * TAU_MID;
    let kl = k * TAU_LO;
    // The rounded a/2π can pick a neighbouring k right at the boundary, and r = t - kl can round
    // onto ±PI from outside (-π, π], so decide on v - π and v + π for v = t - kl instead: t ∓ PI_HI
    // is exact there (Sterbenz), leaving only the tiny rounding of kl ± PI_LO. Then redo the
    // reduction with the corrected k rather than adding ±2π to r, which would round twice.
    let above = (t - PI_HI) - (kl + PI_LO) > 0.0;
    let below = (t + PI_HI) - (kl - PI_LO) <= 0.0;
    let k = if above {
        k + 1.0
    } else if below {
        k - 1.0
    } else {
        k
    };
    let r = ((a - k * TAU_HI) - k * TAU_MID) - k * TAU_LO;
    if r <= -PI { PI } else { r }
}

#[cfg(test)]
mod tests {
    use super::floor;

    /// The inlined floor equals `f32::floor` bit for bit: specials, integers, halves, values
    /// next to integers, and a sweep of bit patterns over the whole f32 range.
    #[test]
    fn floor_equals_std_floor_bit_for_bit() {
        let mut checked = 0u32;
        let mut check = |v: f32| {
            let (ours, std) = (floor(v), v.floor());
            assert!(
                ours.to_bits() == std.to_bits() || (ours.is_nan() && std.is_nan()),
                "floor({v:e}) = {ours:e}, std {std:e}"
            );
            checked += 1;
        };
        for v in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.5,
            -2.5,
            8_388_607.5,
            -8_388_607.5,
            8_388_608.0,
            1e30,
            -1e30,
        ] {
            check(v);
        }
        for v in [
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            f32::MAX,
            f32::MIN,
        ] {
            check(v);
        }
        for k in -2000..2000 {
            let v = k as f32 * 0.25;
            check(v);
            check(f32::from_bits(v.to_bits().wrapping_add(1)));
            check(f32::from_bits(v.to_bits().wrapping_sub(1)));
        }
        for bits in (0..u32::MAX).step_by(65_537) {
            check(f32::from_bits(bits));
        }
        assert!(checked > 70_000);
    }
}
