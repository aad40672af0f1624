//! Accuracy of `socnav::math` against f64 std functions rounded to f32 (the correctly rounded
//! result, up to rare double roundings), measured as the distance in representable f32 values.
//!
//! The bounds asserted here are the ones documented on each function. They were also checked
//! exhaustively over every f32 of each domain (sin/cos up to 25,735 rad, atan over all f32,
//! acos over [-1, 1], exp over [-104, 89], ln over all positive f32, ln_1p, softplus); these
//! tests sweep dense strided grids and fixed pseudo-random points so that they run in seconds.

use socnav::math;

/// Position of an f32 on the number line of representable values (±0 both map to 0).
fn ord(x: f32) -> i64 {
    let b = x.to_bits();
    if b & 0x8000_0000 != 0 {
        -i64::from(b & 0x7fff_ffff)
    } else {
        i64::from(b)
    }
}

/// Distance in ULP between `got` and `want`; NaN only matches NaN.
fn ulp_dist(got: f32, want: f32) -> i64 {
    match (got.is_nan(), want.is_nan()) {
        (true, true) => 0,
        (false, false) => (ord(got) - ord(want)).abs(),
        _ => i64::MAX,
    }
}

/// The ULP scale only means something for normal results (and zero).
fn is_normal_or_zero(v: f32) -> bool {
    v == 0.0 || v.is_normal()
}

/// Fixed, dependency-free generator for test points (SplitMix64); no global RNG.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    fn uniform(&mut self, lo: f64, hi: f64) -> f32 {
        let u = (self.next() >> 11) as f64 / (1u64 << 53) as f64;
        (lo + (hi - lo) * u) as f32
    }
    /// Random sign and a magnitude with a uniformly random binade in [2^lo_exp, 2^hi_exp).
    fn log_uniform(&mut self, lo_exp: i32, hi_exp: i32) -> f32 {
        let e = lo_exp + (self.next() % (hi_exp - lo_exp) as u64) as i32;
        let m = 1.0 + (self.next() >> 11) as f64 / (1u64 << 53) as f64;
        let s = if self.next() & 1 == 0 { 1.0 } else { -1.0 };
        (s * m * 2f64.powi(e)) as f32
    }
}

/// Every `stride`-th f32 between `a` and `b` (same sign, |a| ≤ |b|), both ends included.
fn strided(a: f32, b: f32, stride: u32) -> impl Iterator<Item = f32> {
    let (lo, hi) = (a.to_bits(), b.to_bits());
    (lo..=hi)
        .step_by(stride as usize)
        .chain(std::iter::once(hi))
        .map(f32::from_bits)
}

/// Tracks the worst ULP distance seen and where.
#[derive(Default)]
struct Worst {
    ulp: i64,
    at: (f32, f32),
    n: usize,
}

impl Worst {
    fn check(&mut self, got: f32, want: f32, at: (f32, f32)) {
        if !is_normal_or_zero(want) {
            return;
        }
        self.n += 1;
        let d = ulp_dist(got, want);
        if d > self.ulp {
            self.ulp = d;
            self.at = at;
        }
    }
    fn assert_at_most(&self, name: &str, bound: i64) {
        println!(
            "{name}: max {} ULP over {} points (worst at {:?})",
            self.ulp, self.n, self.at
        );
        assert!(self.n > 1000, "{name}: too few points checked");
        assert!(
            self.ulp <= bound,
            "{name}: {} ULP > {bound} at {:?}",
            self.ulp,
            self.at
        );
    }
}

/// |x| up to which sin/cos reduce exactly (k < 2^14 multiples of π/2).
const TRIG_EXACT: f32 = 25_735.0;

fn trig_points() -> Vec<f32> {
    let mut rng = SplitMix(1);
    let mut xs: Vec<f32> = strided(0.0, 7.0, 4099).collect();
    xs.extend(strided(7.0, TRIG_EXACT, 2053));
    xs.extend((0..200_000).map(|_| rng.uniform(-TRIG_EXACT as f64, TRIG_EXACT as f64)));
    xs.extend((0..100_000).map(|_| rng.log_uniform(-30, 14)));
    // The hard cases: the f32 values nearest to multiples of π/2, where sin or cos is tiny and
    // the reduction must carry many bits of π/2.
    for k in 0..16_384u32 {
        let c = (f64::from(k) * std::f64::consts::FRAC_PI_2) as f32;
        for d in -3i32..=3 {
            let x = f32::from_bits(c.to_bits().wrapping_add_signed(d));
            if x.abs() <= TRIG_EXACT {
                xs.push(x);
                xs.push(-x);
            }
        }
    }
    xs
}

#[test]
fn sin_cos_within_2_ulp_up_to_25735() {
    let (mut ws, mut wc) = (Worst::default(), Worst::default());
    for x in trig_points() {
        let (s, c) = math::sin_cos(x);
        assert_eq!(s.to_bits(), math::sin(x).to_bits(), "sin_cos vs sin at {x}");
        assert_eq!(c.to_bits(), math::cos(x).to_bits(), "sin_cos vs cos at {x}");
        ws.check(s, f64::from(x).sin() as f32, (x, 0.0));
        wc.check(c, f64::from(x).cos() as f32, (x, 0.0));
    }
    ws.assert_at_most("sin", 2);
    wc.assert_at_most("cos", 2);
}

#[test]
fn sin_cos_beyond_exact_range_bounded_absolute_error() {
    // Past 2^14 multiples of π/2 the products k·C_i round; the absolute error stays below
    // |x|·2^-23, the spacing of f32 values at x (measured: about |x|·2^-24).
    let mut rng = SplitMix(2);
    let mut worst: f64 = 0.0;
    for _ in 0..200_000 {
        let x = rng.uniform(f64::from(TRIG_EXACT), f64::from(math::SIN_COS_MAX_ARG));
        let (s, c) = math::sin_cos(x);
        let xs = f64::from(x);
        let err = (f64::from(s) - xs.sin())
            .abs()
            .max((f64::from(c) - xs.cos()).abs());
        worst = worst.max(err / xs);
    }
    println!("sin/cos beyond 25735: max abs error / |x| = {worst:e}");
    assert!(worst <= 2f64.powi(-23), "{worst:e}");
}

#[test]
fn sin_cos_special_values() {
    assert_eq!(math::sin(0.0).to_bits(), 0.0f32.to_bits());
    assert_eq!(math::sin(-0.0).to_bits(), (-0.0f32).to_bits());
    assert_eq!(math::cos(0.0), 1.0);
    assert_eq!(math::cos(-0.0), 1.0);
    for x in [
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        1.1e6,
        -2.0e6,
        f32::MAX,
    ] {
        assert!(math::sin(x).is_nan(), "sin({x})");
        assert!(math::cos(x).is_nan(), "cos({x})");
        let (s, c) = math::sin_cos(x);
        assert!(s.is_nan() && c.is_nan(), "sin_cos({x})");
    }
    // Odd and even symmetry, bit for bit.
    for x in [0.3f32, 1.0, 2.5, 100.0, 12345.678, 1e-20] {
        assert_eq!(math::sin(-x).to_bits(), (-math::sin(x)).to_bits());
        assert_eq!(math::cos(-x).to_bits(), math::cos(x).to_bits());
    }
    // |sin|, |cos| never exceed 1.
    for x in strided(0.0, 10.0, 65_537) {
        let (s, c) = math::sin_cos(x);
        assert!(s.abs() <= 1.0 && c.abs() <= 1.0, "{x}");
    }
}

#[test]
fn atan2_within_2_ulp() {
    let mut w = Worst::default();
    let mut rng = SplitMix(3);
    let mut check = |y: f32, x: f32| {
        w.check(
            math::atan2(y, x),
            f64::from(y).atan2(f64::from(x)) as f32,
            (y, x),
        );
    };
    for _ in 0..300_000 {
        check(rng.log_uniform(-40, 40), rng.log_uniform(-40, 40));
    }
    for _ in 0..300_000 {
        // Comparable magnitudes: every octant and the fold at tan(π/8) are exercised.
        let (y, x) = (rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0));
        check(y, x);
    }
    for i in 0..100_000 {
        let a = -std::f64::consts::PI + f64::from(i) * (std::f64::consts::TAU / 100_000.0);
        check(a.sin() as f32, a.cos() as f32);
    }
    w.assert_at_most("atan2", 2);
}

#[test]
fn atan_within_2_ulp() {
    let mut w = Worst::default();
    for x in strided(0.0, f32::MAX, 1021).chain(strided(0.4, 0.43, 7)) {
        for x in [x, -x] {
            w.check(math::atan(x), f64::from(x).atan() as f32, (x, 0.0));
        }
    }
    w.assert_at_most("atan", 2);
}

#[test]
fn atan2_special_values_follow_ieee() {
    use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    let inf = f32::INFINITY;
    let cases: [(f32, f32); 20] = [
        (0.0, 0.0),
        (-0.0, 0.0),
        (0.0, -0.0),
        (-0.0, -0.0),
        (0.0, -1.0),
        (-0.0, -1.0),
        (0.0, 1.0),
        (-0.0, 1.0),
        (1.0, 0.0),
        (1.0, -0.0),
        (-1.0, 0.0),
        (inf, inf),
        (-inf, inf),
        (inf, -inf),
        (-inf, -inf),
        (inf, 3.0),
        (-inf, -3.0),
        (3.0, inf),
        (-3.0, -inf),
        (3.0, -inf),
    ];
    for (y, x) in cases {
        let want = f64::from(y).atan2(f64::from(x)) as f32;
        let got = math::atan2(y, x);
        assert!(
            ulp_dist(got, want) <= 1 && got.is_sign_negative() == want.is_sign_negative(),
            "atan2({y}, {x}) = {got}, std {want}"
        );
    }
    assert_eq!(math::atan2(0.0, 0.0).to_bits(), 0);
    assert_eq!(math::atan2(1.0, 1.0), FRAC_PI_4);
    assert_eq!(math::atan2(1.0, 0.0), FRAC_PI_2);
    assert_eq!(math::atan2(0.0, -1.0), PI);
    assert!(math::atan2(f32::NAN, 1.0).is_nan());
    assert!(math::atan2(1.0, f32::NAN).is_nan());
    assert!(math::atan2(f32::NAN, f32::INFINITY).is_nan());
    assert_eq!(math::atan(inf), FRAC_PI_2);
    assert_eq!(math::atan(-inf), -FRAC_PI_2);
    assert_eq!(math::atan(-0.0).to_bits(), (-0.0f32).to_bits());
    assert!(math::atan(f32::NAN).is_nan());
}

#[test]
fn acos_within_1_ulp() {
    let mut w = Worst::default();
    for x in strided(0.0, 1.0, 97).chain(strided(-0.0, -1.0, 97)) {
        w.check(math::acos(x), f64::from(x).acos() as f32, (x, 0.0));
    }
    w.assert_at_most("acos", 1);
}

#[test]
fn acos_special_values() {
    assert_eq!(math::acos(1.0).to_bits(), 0);
    assert_eq!(math::acos(-1.0), math::PI);
    assert_eq!(math::acos(0.0), math::FRAC_PI_2);
    // Slightly outside [-1, 1]: clamped.
    assert_eq!(math::acos(1.000_000_1).to_bits(), 0);
    assert_eq!(math::acos(-1.000_000_1), math::PI);
    assert_eq!(math::acos(math::ACOS_DOMAIN_MAX).to_bits(), 0);
    // Clearly outside: NaN, like std.
    for x in [
        1.001,
        -1.001,
        2.0,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
    ] {
        assert!(math::acos(x).is_nan(), "acos({x})");
    }
}

#[test]
fn exp_within_1_ulp() {
    let mut w = Worst::default();
    for x in strided(0.0, 89.0, 331).chain(strided(-0.0, -104.0, 331)) {
        w.check(math::exp(x), f64::from(x).exp() as f32, (x, 0.0));
    }
    w.assert_at_most("exp", 1);
}

#[test]
fn exp_special_values() {
    assert_eq!(math::exp(0.0), 1.0);
    assert_eq!(math::exp(-0.0), 1.0);
    for x in [88.8f32, 89.0, 100.0, 1e3, 1e30, f32::MAX, f32::INFINITY] {
        assert_eq!(math::exp(x), f32::INFINITY, "exp({x})");
    }
    for x in [-104.0f32, -1e3, -1e30, f32::MIN, f32::NEG_INFINITY] {
        assert_eq!(math::exp(x).to_bits(), 0, "exp({x})");
    }
    assert!(math::exp(f32::NAN).is_nan());
    // Largest finite and smallest normal results.
    assert!(math::exp(88.72).is_finite());
    assert!(math::exp(-87.3) > 0.0);
    // Subnormal results stay within a couple of subnormal steps.
    for x in strided(-87.4, -103.0, 9_973) {
        let d = ulp_dist(math::exp(x), f64::from(x).exp() as f32);
        assert!(d <= 1, "exp({x}): {d} ULP");
    }
}

#[test]
fn ln_within_1_ulp() {
    let mut w = Worst::default();
    let tiny = f32::from_bits(1);
    for x in strided(tiny, f32::MAX, 2_039).chain(strided(0.5, 2.0, 257)) {
        w.check(math::ln(x), f64::from(x).ln() as f32, (x, 0.0));
    }
    w.assert_at_most("ln", 1);
}

#[test]
fn ln_special_values() {
    assert_eq!(math::ln(1.0).to_bits(), 0);
    assert_eq!(math::ln(0.0), f32::NEG_INFINITY);
    assert_eq!(math::ln(-0.0), f32::NEG_INFINITY);
    assert_eq!(math::ln(f32::INFINITY), f32::INFINITY);
    for x in [-1.0f32, -1e-30, f32::NEG_INFINITY, f32::NAN] {
        assert!(math::ln(x).is_nan(), "ln({x})");
    }
    assert_eq!(math::ln(std::f32::consts::E), 1.0);
}

#[test]
fn ln_1p_within_2_ulp() {
    let mut w = Worst::default();
    for x in strided(0.0, f32::MAX, 2_039).chain(strided(-0.0, -1.0, 257)) {
        w.check(math::ln_1p(x), f64::from(x).ln_1p() as f32, (x, 0.0));
    }
    w.assert_at_most("ln_1p", 2);
    assert_eq!(math::ln_1p(-0.0).to_bits(), (-0.0f32).to_bits());
    assert_eq!(math::ln_1p(-1.0), f32::NEG_INFINITY);
    assert_eq!(math::ln_1p(f32::INFINITY), f32::INFINITY);
    assert!(math::ln_1p(-1.5).is_nan());
    assert!(math::ln_1p(f32::NAN).is_nan());
}

#[test]
fn softplus_within_2_ulp() {
    let reference = |x: f32| {
        let x = f64::from(x);
        (x.max(0.0) + (-x.abs()).exp().ln_1p()) as f32
    };
    let mut w = Worst::default();
    for x in strided(0.0, 2000.0, 331).chain(strided(-0.0, -104.0, 331)) {
        w.check(math::softplus(x), reference(x), (x, 0.0));
    }
    w.assert_at_most("softplus", 2);
    assert_eq!(math::softplus(1e3), 1e3);
    assert_eq!(math::softplus(-1e3).to_bits(), 0);
    assert_eq!(math::softplus(f32::INFINITY), f32::INFINITY);
    assert_eq!(math::softplus(f32::NEG_INFINITY).to_bits(), 0);
    assert_eq!(math::softplus(0.0), std::f32::consts::LN_2);
    assert_eq!(math::softplus(-0.0), std::f32::consts::LN_2);
    assert!(math::softplus(f32::NAN).is_nan());
}

/// The exactly wrapped angle in f64 (2π in f64 is exact to 2.4e-16, far below f32 resolution).
fn wrap_reference(a: f32) -> f64 {
    let a = f64::from(a);
    let k = (a / std::f64::consts::TAU).round();
    let mut r = a - k * std::f64::consts::TAU;
    if r <= -std::f64::consts::PI {
        r += std::f64::consts::TAU;
    } else if r > std::f64::consts::PI {
        r -= std::f64::consts::TAU;
    }
    r
}

#[test]
fn wrap_angle_in_range_and_exact() {
    let mut rng = SplitMix(4);
    let mut xs: Vec<f32> = strided(0.0, 40.0, 1_009).collect();
    xs.extend((0..300_000).map(|_| rng.uniform(-6400.0, 6400.0)));
    // Around every odd multiple of π (the wrap boundaries) and every multiple of 2π (results
    // near zero) up to 6,400 rad.
    for k in -1018i32..=1018 {
        for c in [
            (f64::from(2 * k + 1) * std::f64::consts::PI) as f32,
            (f64::from(2 * k) * std::f64::consts::PI) as f32,
        ] {
            for d in -8i32..=8 {
                let a = f32::from_bits(c.to_bits().wrapping_add_signed(d));
                if a.is_finite() {
                    xs.push(a);
                }
            }
        }
    }
    let mut w = Worst::default();
    let mut worst_abs: f64 = 0.0;
    for a in xs.iter().flat_map(|&a| [a, -a]) {
        let r = math::wrap_angle(a);
        assert!(-math::PI < r && r <= math::PI, "wrap_angle({a}) = {r}");
        let want = wrap_reference(a);
        // At the boundary, the exact wrapped value may round to -PI, which wrap_angle maps to +PI.
        if (want as f32) == -math::PI {
            assert_eq!(r, math::PI);
            continue;
        }
        worst_abs =
            worst_abs.max((f64::from(r) - want).abs() - f64::from(ulp_at(want as f32)) / 2.0);
        // Near zero the ULP shrinks below that absolute error; elsewhere the result is the
        // correctly rounded one or its neighbour.
        if want.abs() >= 2f64.powi(-10) {
            w.check(r, want as f32, (a, 0.0));
        }
    }
    println!("wrap_angle: absolute error beyond half an ULP: {worst_abs:e}");
    // 2πk is carried to about 2^-46 relative, so before its final rounding the result is off by
    // about 2^-37 at most (for |k| < 2^10), which is far below an ULP unless the result is tiny.
    assert!(worst_abs < 2f64.powi(-36), "{worst_abs:e}");
    w.assert_at_most("wrap_angle", 1);
}

fn ulp_at(v: f32) -> f32 {
    let b = v.abs().to_bits();
    f32::from_bits(b + 1) - f32::from_bits(b)
}

#[test]
fn wrap_angle_boundaries_and_small_multiples() {
    let pi = math::PI;
    // The f32 PI lies above π, so it wraps to just above -π; and the other way round.
    assert_eq!(math::wrap_angle(pi), -3.141_592_5);
    assert_eq!(math::wrap_angle(-pi), 3.141_592_5);
    assert_eq!(math::wrap_angle(3.141_592_5), 3.141_592_5);
    // 3π + 2.4e-8 wraps to -π + 2.4e-8, which rounds to -PI and is returned as PI.
    assert_eq!(math::wrap_angle(f32::from_bits(0x4116_cbe4)), pi);
    assert_eq!(math::wrap_angle(0.0).to_bits(), 0);
    assert_eq!(math::wrap_angle(-0.0).to_bits(), (-0.0f32).to_bits());
    assert_eq!(math::wrap_angle(1.0), 1.0);
    assert_eq!(math::wrap_angle(-3.0), -3.0);
    // Exactly what a single rounding of a - 2π gives.
    assert_eq!(math::wrap_angle(4.0), (4.0 - std::f64::consts::TAU) as f32);
    assert_eq!(
        math::wrap_angle(-10.0),
        (-10.0 + 2.0 * std::f64::consts::TAU) as f32
    );
    for a in [f32::INFINITY, f32::NEG_INFINITY, f32::NAN] {
        assert!(math::wrap_angle(a).is_nan(), "wrap_angle({a})");
    }
    // Agrees with SocNavGym's atan2(sin a, cos a) up to the rounding of those functions.
    let mut rng = SplitMix(5);
    for _ in 0..10_000 {
        let a = rng.uniform(-30.0, 30.0);
        let (s, c) = math::sin_cos(a);
        let b = math::atan2(s, c);
        let r = math::wrap_angle(a);
        assert!(
            (b - r).abs() <= 4e-7 || ((b - r).abs() - math::TAU).abs() <= 4e-7,
            "{a}: {b} vs {r}"
        );
    }
}

#[test]
fn constants_are_the_std_values() {
    assert_eq!(math::PI, std::f32::consts::PI);
    assert_eq!(math::TAU, std::f32::consts::TAU);
    assert_eq!(math::FRAC_PI_2, std::f32::consts::FRAC_PI_2);
}
