// Twin of src/math.rs: the only home of transcendental maths in the shaders (f32).
//
// Library file (no entry points), prepended to the stage shaders that use it. Every function
// mirrors its Rust twin operation for operation (`math::sin` is `math_sin`, `math::PI` is
// `MATH_PI`, and so on), so that lavapipe computes the same bits as the CPU backend
// (docs/spec.md, determinism and bit parity). Read the Rust file for the method,
// domain and accuracy of each function; change both files in the same commit.
//
// Rules kept here: no `fma` and no builtin transcendentals (`sin`, `exp`, ...); `a * b + c` is
// written out; constants are exact hexadecimal floats of the bits the Rust file gives to
// `f32::from_bits` (a decimal literal is parsed as an abstract float and could round differently,
// and naga cannot evaluate `bitcast` in a constant expression);
// tests/suite/foundations/shaders_validate.rs checks that both files denote the same bit patterns.
// NaN and infinity are made at run time (`math_nan`, `math_inf`), because a non-finite constant
// expression is a shader-creation error. Float-to-integer conversions only see finite, in-range
// values. Mesa's NIR optimiser rewrites some float expressions on lavapipe (cancellations,
// factoring, moving constants through sums): the forms here were chosen to be immune, and checked
// bit for bit against the Rust twin; keep the exact shape of every expression when editing
// (src/math.rs, module docs, lists the rules).

const MATH_PI: f32 = 0x1.921fb6p1f;
const MATH_TAU: f32 = 0x1.921fb6p2f;
const MATH_FRAC_PI_2: f32 = 0x1.921fb6p0f;
const MATH_SIN_COS_MAX_ARG: f32 = 1048576.0;
const MATH_ACOS_DOMAIN_MAX: f32 = 0x1.001p0f;

const MATH_NAN_BITS: u32 = 0x7fc00000u;
const MATH_INF_BITS: u32 = 0x7f800000u;
const MATH_SIGN_MASK: u32 = 0x80000000u;
const MATH_ABS_MASK: u32 = 0x7fffffffu;

// A `var` keeps the value out of constant evaluation, where NaN and infinity are not allowed.
fn math_nan() -> f32 {
    var b = MATH_NAN_BITS;
    return bitcast<f32>(b);
}

fn math_inf() -> f32 {
    var b = MATH_INF_BITS;
    return bitcast<f32>(b);
}

fn math_is_nan_bits(x: f32) -> bool {
    return (bitcast<u32>(x) & MATH_ABS_MASK) > MATH_INF_BITS;
}

// Rust `f32::is_finite`, on the bits (no comparison a compiler may assume finite).
fn math_is_finite_bits(x: f32) -> bool {
    return (bitcast<u32>(x) & MATH_ABS_MASK) < MATH_INF_BITS;
}

// ---- sin / cos ----------------------------------------------------------------------------------

const MATH_FRAC_2_PI: f32 = 0x1.45f306p-1f;
const MATH_PIO2_C1: f32 = 0x1.92p0f;
const MATH_PIO2_C2: f32 = 0x1.fap-12f;
const MATH_PIO2_C3: f32 = 0x1.54p-20f;
const MATH_PIO2_C4: f32 = 0x1.108p-30f;
const MATH_PIO2_C5: f32 = 0x1.a308d4p-41f;
const MATH_PIO2_C3B: f32 = 0x1.5p-20f;
const MATH_PIO2_C4B: f32 = 0x1.110b46p-26f;
const MATH_REDUCE_SPLIT: f32 = 0.015625;
const MATH_SIN_P0: f32 = -0x1.555546p-3f;
const MATH_SIN_P1: f32 = 0x1.11073cp-7f;
const MATH_SIN_P2: f32 = -0x1.9943f2p-13f;
const MATH_COS_P0: f32 = 0x1.55554ap-5f;
const MATH_COS_P1: f32 = -0x1.6c0c34p-10f;
const MATH_COS_P2: f32 = 0x1.99eb9cp-16f;

// Cody-Waite in two variants, no TwoSum compensation, which NIR would fold away (see src/math.rs).
struct MathReduced {
    r: f32,
    k: i32,
}

fn math_reduce_pio2(ax: f32) -> MathReduced {
    let k = floor(ax * MATH_FRAC_2_PI + 0.5);
    var t = ax - k * MATH_PIO2_C1;
    t = t - k * MATH_PIO2_C2;
    let r_big = (t - k * MATH_PIO2_C3B) - k * MATH_PIO2_C4B;
    let r_small = ((t - k * MATH_PIO2_C3) - k * MATH_PIO2_C4) - k * MATH_PIO2_C5;
    var r = r_small;
    if (abs(r_big) >= MATH_REDUCE_SPLIT) {
        r = r_big;
    }
    return MathReduced(r, i32(k));
}

fn math_sin_kernel(r: f32) -> f32 {
    let z = r * r;
    let p = (MATH_SIN_P2 * z + MATH_SIN_P1) * z + MATH_SIN_P0;
    return r + r * z * p;
}

fn math_cos_kernel(r: f32) -> f32 {
    let z = r * r;
    let q = (MATH_COS_P2 * z + MATH_COS_P1) * z + MATH_COS_P0;
    let hz = 0.5 * z;
    return 1.0 - (hz - z * z * q);
}

fn math_xor_sign(v: f32, s: f32) -> f32 {
    return bitcast<f32>(bitcast<u32>(v) ^ (bitcast<u32>(s) & MATH_SIGN_MASK));
}

fn math_sin(x: f32) -> f32 {
    var ax = abs(x);
    let ok = ax <= MATH_SIN_COS_MAX_ARG;
    if (!ok) {
        ax = 0.0;
    }
    let red = math_reduce_pio2(ax);
    var v: f32;
    if ((red.k & 1) == 0) {
        v = math_sin_kernel(red.r);
    } else {
        v = math_cos_kernel(red.r);
    }
    if ((red.k & 2) != 0) {
        v = -v;
    }
    if (ok) {
        return math_xor_sign(v, x);
    }
    return math_nan();
}

fn math_cos(x: f32) -> f32 {
    var ax = abs(x);
    let ok = ax <= MATH_SIN_COS_MAX_ARG;
    if (!ok) {
        ax = 0.0;
    }
    let red = math_reduce_pio2(ax);
    var v: f32;
    if ((red.k & 1) == 0) {
        v = math_cos_kernel(red.r);
    } else {
        v = math_sin_kernel(red.r);
    }
    if (((red.k + 1) & 2) != 0) {
        v = -v;
    }
    if (ok) {
        return v;
    }
    return math_nan();
}

// Returns vec2(sin(x), cos(x)).
fn math_sin_cos(x: f32) -> vec2<f32> {
    var ax = abs(x);
    let ok = ax <= MATH_SIN_COS_MAX_ARG;
    if (!ok) {
        ax = 0.0;
    }
    let red = math_reduce_pio2(ax);
    let s = math_sin_kernel(red.r);
    let c = math_cos_kernel(red.r);
    var vs = s;
    var vc = c;
    if ((red.k & 1) != 0) {
        vs = c;
        vc = s;
    }
    if ((red.k & 2) != 0) {
        vs = -vs;
    }
    if (((red.k + 1) & 2) != 0) {
        vc = -vc;
    }
    if (ok) {
        return vec2<f32>(math_xor_sign(vs, x), vc);
    }
    return vec2<f32>(math_nan(), math_nan());
}

// ---- atan2 / atan / acos ------------------------------------------------------------------------

const MATH_TAN_PI_8: f32 = 0x1.a8279ap-2f;
const MATH_PIO4_HI: f32 = 0x1.921fb6p-1f;
const MATH_PIO4_LO: f32 = -0x1.777a5cp-26f;
const MATH_PIO2_HI: f32 = 0x1.921fb6p0f;
const MATH_PIO2_LO: f32 = -0x1.777a5cp-25f;
const MATH_PI3O4_HI: f32 = 0x1.2d97c8p1f;
const MATH_PI3O4_LO: f32 = -0x1.99bc5cp-28f;
const MATH_PI_HI: f32 = 0x1.921fb6p1f;
const MATH_PI_LO: f32 = -0x1.777a5cp-24f;
const MATH_ATAN_P0: f32 = -0x1.555454p-2f;
const MATH_ATAN_P1: f32 = 0x1.9924bep-3f;
const MATH_ATAN_P2: f32 = -0x1.1c370ap-3f;
const MATH_ATAN_P3: f32 = 0x1.49e1a2p-4f;

fn math_atan2(y: f32, x: f32) -> f32 {
    let ax = abs(x);
    let ay = abs(y);
    let swap = ay > ax;
    var mx = ax;
    var mn = ay;
    if (swap) {
        mx = ay;
        mn = ax;
    }
    if (mx == math_inf()) {
        if (mn == math_inf()) {
            mn = 1.0;
        } else {
            mn = 0.0;
        }
        mx = 1.0;
    }
    if (mx == 0.0) {
        mx = 1.0;
    }
    let big = mn > mx * MATH_TAN_PI_8;
    var t: f32;
    if (big) {
        t = (mn - mx) / (mn + mx);
    } else {
        t = mn / mx;
    }
    let z = t * t;
    let p = t + t * z * (((MATH_ATAN_P3 * z + MATH_ATAN_P2) * z + MATH_ATAN_P1) * z + MATH_ATAN_P0);
    var j = 0u;
    if (big) {
        j = 1u;
    }
    var neg = false;
    if (swap) {
        j = 2u - j;
        neg = true;
    }
    if ((bitcast<u32>(x) & MATH_SIGN_MASK) != 0u) {
        j = 4u - j;
        neg = !neg;
    }
    var c_hi: f32 = 0.0;
    var c_lo: f32 = 0.0;
    if (j == 1u) {
        c_hi = MATH_PIO4_HI;
        c_lo = MATH_PIO4_LO;
    } else if (j == 2u) {
        c_hi = MATH_PIO2_HI;
        c_lo = MATH_PIO2_LO;
    } else if (j == 3u) {
        c_hi = MATH_PI3O4_HI;
        c_lo = MATH_PI3O4_LO;
    } else if (j != 0u) {
        c_hi = MATH_PI_HI;
        c_lo = MATH_PI_LO;
    }
    var sp = p;
    if (neg) {
        sp = -p;
    }
    let theta = math_xor_sign(c_hi + (c_lo + sp), y);
    if (math_is_nan_bits(x) || math_is_nan_bits(y)) {
        return math_nan();
    }
    return theta;
}

fn math_atan(x: f32) -> f32 {
    return math_atan2(x, 1.0);
}

const MATH_ASIN_P0: f32 = 0x1.5555c8p-3f;
const MATH_ASIN_P1: f32 = 0x1.3301ecp-4f;
const MATH_ASIN_P2: f32 = 0x1.747d8ep-5f;
const MATH_ASIN_P3: f32 = 0x1.8c2fc6p-6f;
const MATH_ASIN_P4: f32 = 0x1.5966a4p-5f;
const MATH_ACOS_DF_MASK: u32 = 0xfffff000u;

fn math_asin_r(z: f32) -> f32 {
    return z * ((((MATH_ASIN_P4 * z + MATH_ASIN_P3) * z + MATH_ASIN_P2) * z + MATH_ASIN_P1) * z + MATH_ASIN_P0);
}

fn math_acos(x_in: f32) -> f32 {
    let ok = abs(x_in) <= MATH_ACOS_DOMAIN_MAX;
    let x = clamp(x_in, -1.0, 1.0);
    var v: f32;
    if (x > 0.5) {
        let z = (1.0 - x) * 0.5;
        let s = sqrt(z);
        let df = bitcast<f32>(bitcast<u32>(s) & MATH_ACOS_DF_MASK);
        let c = (z - df * df) / (s + df);
        let w = s * math_asin_r(z) + c;
        if (x == 1.0) {
            v = 0.0;
        } else {
            v = 2.0 * (df + w);
        }
    } else if (x < -0.5) {
        let z = (1.0 + x) * 0.5;
        let s = sqrt(z);
        let w = s * math_asin_r(z) - MATH_PIO2_LO;
        v = MATH_PI_HI - 2.0 * (s + w);
    } else {
        let z = x * x;
        v = MATH_PIO2_HI - (x - (MATH_PIO2_LO - x * math_asin_r(z)));
    }
    if (ok) {
        return v;
    }
    return math_nan();
}

// ---- exp / ln / softplus ------------------------------------------------------------------------

const MATH_LOG2E: f32 = 0x1.715476p0f;
const MATH_LN2_HI: f32 = 0x1.63p-1f;
const MATH_LN2_LO: f32 = -0x1.bd0106p-13f;
const MATH_EXP_P0: f32 = 0.5;
const MATH_EXP_P1: f32 = 0x1.555554p-3f;
const MATH_EXP_P2: f32 = 0x1.555382p-5f;
const MATH_EXP_P3: f32 = 0x1.11121p-7f;
const MATH_EXP_P4: f32 = 0x1.6e879cp-10f;
const MATH_EXP_P5: f32 = 0x1.a0d2cep-13f;
const MATH_EXP_ARG_MIN: f32 = -104.0;
const MATH_EXP_ARG_MAX: f32 = 89.0;

// 2^n for -126 <= n <= 127.
fn math_pow2i(n: i32) -> f32 {
    return bitcast<f32>(u32(n + 127) << 23u);
}

fn math_exp(x: f32) -> f32 {
    let nan = math_is_nan_bits(x);
    var xc = x;
    if (nan) {
        xc = 0.0;
    }
    xc = clamp(xc, MATH_EXP_ARG_MIN, MATH_EXP_ARG_MAX);
    let n = floor(xc * MATH_LOG2E + 0.5);
    var r = xc - n * MATH_LN2_HI;
    r = r - n * MATH_LN2_LO;
    let p = ((((MATH_EXP_P5 * r + MATH_EXP_P4) * r + MATH_EXP_P3) * r + MATH_EXP_P2) * r + MATH_EXP_P1) * r + MATH_EXP_P0;
    var y = (p * r + 1.0) * r + 1.0;
    let ni = i32(n);
    let n1 = ni >> 1u;
    let n2 = ni - n1;
    y = y * math_pow2i(n1) * math_pow2i(n2);
    if (nan) {
        return math_nan();
    }
    return y;
}

const MATH_SQRT_HALF: f32 = 0x1.6a09e6p-1f;
const MATH_TWO_POW_24: f32 = 0x1p24f;
const MATH_MIN_POSITIVE: f32 = 0x1p-126f;
const MATH_MANTISSA_MASK: u32 = 0x007fffffu;
const MATH_HALF_EXPONENT: u32 = 0x3f000000u;
const MATH_LN_P0: f32 = 0x1.555554p-2f;
const MATH_LN_P1: f32 = -0x1.fffff8p-3f;
const MATH_LN_P2: f32 = 0x1.999d58p-3f;
const MATH_LN_P3: f32 = -0x1.555cap-3f;
const MATH_LN_P4: f32 = 0x1.23d37ep-3f;
const MATH_LN_P5: f32 = -0x1.fcba9ep-4f;
const MATH_LN_P6: f32 = 0x1.de4a34p-4f;
const MATH_LN_P7: f32 = -0x1.d7a37p-4f;
const MATH_LN_P8: f32 = 0x1.204376p-4f;

fn math_ln(x: f32) -> f32 {
    let sub = x < MATH_MIN_POSITIVE;
    var xs = x;
    if (sub) {
        xs = x * MATH_TWO_POW_24;
    }
    let bits = bitcast<u32>(xs);
    var e = i32((bits >> 23u) & 0xffu) - 126;
    if (sub) {
        e = e - 24;
    }
    let m = bitcast<f32>((bits & MATH_MANTISSA_MASK) | MATH_HALF_EXPONENT);
    var f: f32;
    if (m < MATH_SQRT_HALF) {
        f = m + m - 1.0;
        e = e - 1;
    } else {
        f = m - 1.0;
    }
    let z = f * f;
    let p = ((((((((MATH_LN_P8 * f + MATH_LN_P7) * f + MATH_LN_P6) * f + MATH_LN_P5) * f + MATH_LN_P4) * f + MATH_LN_P3) * f + MATH_LN_P2) * f + MATH_LN_P1) * f + MATH_LN_P0) * f * z;
    let ef = f32(e);
    var y = p + ef * MATH_LN2_LO;
    y = y - 0.5 * z;
    var v = f + y;
    v = v + ef * MATH_LN2_HI;
    if (x == math_inf()) {
        return math_inf();
    } else if (x == 0.0) {
        return -math_inf();
    } else if (x > 0.0) {
        return v;
    }
    return math_nan();
}

const MATH_LN1P_KERNEL_MIN: f32 = -0x1.2bec34p-2f;
const MATH_LN1P_KERNEL_MAX: f32 = 0x1.a8279ap-2f;

fn math_ln_1p(u: f32) -> f32 {
    if (u >= MATH_LN1P_KERNEL_MIN && u <= MATH_LN1P_KERNEL_MAX) {
        let z = u * u;
        let q = (((((((MATH_LN_P8 * u + MATH_LN_P7) * u + MATH_LN_P6) * u + MATH_LN_P5) * u + MATH_LN_P4) * u + MATH_LN_P3) * u + MATH_LN_P2) * u + MATH_LN_P1) * u + MATH_LN_P0;
        let p = q * (u * z);
        let y = u - 0.5 * z;
        return y + p;
    }
    return math_ln(1.0 + u);
}

const MATH_LN2: f32 = 0x1.62e43p-1f;
const MATH_LNCOSH_G0: f32 = 0.5;
const MATH_LNCOSH_G1: f32 = -0x1.555556p-4f;
const MATH_LNCOSH_G2: f32 = 0x1.6c16c2p-6f;
const MATH_LNCOSH_G3: f32 = -0x1.ba1ba2p-8f;
const MATH_LNCOSH_G4: f32 = 0x1.1ea5d4p-9f;
const MATH_LNCOSH_G5: f32 = -0x1.833d9cp-11f;
const MATH_LNCOSH_G6: f32 = 0x1.0d0b52p-12f;
const MATH_LNCOSH_G7: f32 = -0x1.7da364p-14f;

fn math_softplus(x: f32) -> f32 {
    if (abs(x) <= 1.0) {
        let y = 0.5 * x;
        let w = y * y;
        let g = ((((((MATH_LNCOSH_G7 * w + MATH_LNCOSH_G6) * w + MATH_LNCOSH_G5) * w + MATH_LNCOSH_G4) * w + MATH_LNCOSH_G3) * w + MATH_LNCOSH_G2) * w + MATH_LNCOSH_G1) * w + MATH_LNCOSH_G0;
        return (MATH_LN2 + y) + w * g;
    }
    var pos = 0.0;
    if (x > 0.0) {
        pos = x;
    }
    return pos + math_ln_1p(math_exp(-abs(x)));
}

// ---- angles -------------------------------------------------------------------------------------

const MATH_FRAC_1_TAU: f32 = 0x1.45f306p-3f;
const MATH_TAU_HI: f32 = 0x1.9218p2f;
const MATH_TAU_MID: f32 = 0x1.ed4p-12f;
const MATH_TAU_LO: f32 = 0x1.110b46p-24f;

fn math_wrap_angle(a: f32) -> f32 {
    var k = floor(a * MATH_FRAC_1_TAU + 0.5);
    let t = (a - k * MATH_TAU_HI) - k * MATH_TAU_MID;
    let kl = k * MATH_TAU_LO;
    let above = (t - MATH_PI_HI) - (kl + MATH_PI_LO) > 0.0;
    let below = (t + MATH_PI_HI) - (kl - MATH_PI_LO) <= 0.0;
    if (above) {
        k = k + 1.0;
    } else if (below) {
        k = k - 1.0;
    }
    let r = ((a - k * MATH_TAU_HI) - k * MATH_TAU_MID) - k * MATH_TAU_LO;
    if (r <= -MATH_PI) {
        return MATH_PI;
    }
    return r;
}
