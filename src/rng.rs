//! Interim counter-based RNG; same API as the final one.

fn mix(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// Derive a stream id from a kind and a sub-index.
pub fn stream_id(kind: u32, sub: u32) -> u32 {
    mix(kind ^ mix(sub.wrapping_add(0x9e37_79b9)))
}

/// A stream of random numbers keyed by (seed, env, episode, stream).
#[derive(Debug, Clone, Copy)]
pub struct RngStream {
    base: u32,
    draw: u32,
}

impl RngStream {
    /// New stream.
    pub fn new(seed: u64, env: u32, episode: u32, stream: u32) -> Self {
        let mut h = mix(seed as u32 ^ 0x2545_f491);
        h = mix(h ^ (seed >> 32) as u32);
        h = mix(h ^ env);
        h = mix(h ^ episode);
        h = mix(h ^ stream);
        Self { base: h, draw: 0 }
    }
    /// Next u32.
    pub fn next_u32(&mut self) -> u32 {
        let v = mix(self.base ^ mix(self.draw));
        self.draw = self.draw.wrapping_add(1);
        v
    }
    /// Uniform [0,1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }
    /// Uniform [lo, hi).
    pub fn uniform(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }
    /// Standard normal.
    pub fn normal(&mut self) -> f32 {
        let u1 = 1.0 - self.next_f32();
        let u2 = self.next_f32();
        (-2.0 * crate::math::ln(u1)).sqrt() * crate::math::cos(crate::math::TAU * u2)
    }
    /// Integer in [0, n).
    pub fn below(&mut self, n: u32) -> u32 {
        ((self.next_f32() * n as f32) as u32).min(n.saturating_sub(1))
    }
    /// Integer in [lo, hi] inclusive.
    pub fn randint(&mut self, lo: i32, hi: i32) -> i32 {
        lo + self.below((hi - lo + 1) as u32) as i32
    }
    /// True with probability p.
    pub fn chance(&mut self, p: f32) -> bool {
        self.next_f32() < p
    }
}
