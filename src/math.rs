//! Interim transcendental maths (f64 std rounded to f32) until the bit-reproducible polynomial
//! versions land; same API.
#![expect(clippy::disallowed_methods, reason = "interim implementation")]

/// π.
pub const PI: f32 = std::f32::consts::PI;
/// 2π.
pub const TAU: f32 = std::f32::consts::TAU;
/// π/2.
pub const FRAC_PI_2: f32 = std::f32::consts::FRAC_PI_2;

/// Sine.
pub fn sin(x: f32) -> f32 {
    (x as f64).sin() as f32
}
/// Cosine.
pub fn cos(x: f32) -> f32 {
    (x as f64).cos() as f32
}
/// Sine and cosine.
pub fn sin_cos(x: f32) -> (f32, f32) {
    (sin(x), cos(x))
}
/// atan2.
pub fn atan2(y: f32, x: f32) -> f32 {
    (y as f64).atan2(x as f64) as f32
}
/// atan.
pub fn atan(x: f32) -> f32 {
    (x as f64).atan() as f32
}
/// acos.
pub fn acos(x: f32) -> f32 {
    (x.clamp(-1.0, 1.0) as f64).acos() as f32
}
/// exp.
pub fn exp(x: f32) -> f32 {
    (x as f64).exp() as f32
}
/// ln.
pub fn ln(x: f32) -> f32 {
    (x as f64).ln() as f32
}
/// ln(1 + exp(x)).
pub fn softplus(x: f32) -> f32 {
    x.max(0.0) + ln(1.0 + exp(-x.abs()))
}
/// Wrap to (-π, π].
pub fn wrap_angle(a: f32) -> f32 {
    atan2(sin(a), cos(a))
}
