//! Determinism, golden values and statistical sanity of the counter-based RNG (`socnav::rng`).
//!
//! Every statistical bound below sits many standard errors away from its expected value, and the
//! generator is deterministic, so these tests never flake: a failure means the generator changed.

use socnav::rng::{RngStream, mix32, stream_id};
use socnav::seeds::{EPISODE_SEED_STEP, next_episode_seed, seed_from_words, seed_words};

const N: usize = 1_000_000;

/// Pearson correlation coefficient of two equally long samples.
fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    sab / (saa * sbb).sqrt()
}

fn floats(s: &mut RngStream, n: usize) -> Vec<f64> {
    (0..n).map(|_| f64::from(s.next_f32())).collect()
}

/// The RNG's contract: the first outputs of a fixed key.
///
/// These values define every scenario that socnav generates (room sizes, entity placement,
/// per-episode human parameters, social events). They must only be re-minted deliberately, when
/// the generator is changed on purpose (together with `shaders/common/rng.wgsl`), with a
/// CHANGELOG note saying that seeds give different episodes from that version on. The `normal`
/// value also pins `math::ln` and `math::cos`, which Box–Muller uses.
#[test]
fn golden_first_draws() {
    let mut s = RngStream::new(42, 0);
    let u: Vec<u32> = (0..4).map(|_| s.next_u32()).collect();
    assert_eq!(
        u,
        [0xf6e4ff10, 0xf317e035, 0xf05bd435, 0x4a0a5d48],
        "next_u32"
    );
    let mut s = RngStream::new(0x0123_4567_89ab_cdef, stream_id(1, 2));
    assert_eq!(s.next_f32().to_bits(), 0x3d1dc970, "next_f32"); // 0.038522184
    assert_eq!(s.uniform(-2.0, 5.0).to_bits(), 0x403b2dd8, "uniform"); // 2.924673
    assert_eq!(s.normal().to_bits(), 0x3d9bca26, "normal"); // 0.07606916
    assert_eq!(s.below(10), 7, "below");
    assert_eq!(s.randint(-3, 3), 1, "randint");
    assert!(!s.chance(0.5), "chance");
    assert_eq!(s.draw, 7, "draws consumed");
    assert_eq!(stream_id(1, 2), 0xa66197ad, "stream_id");
}

#[test]
fn same_key_same_sequence() {
    let mut a = RngStream::new(12345, 9);
    let mut b = RngStream::new(12345, 9);
    for _ in 0..1000 {
        assert_eq!(a.next_u32(), b.next_u32());
    }
    // The seed as two words, as the GPU gets it, is the same stream.
    let seed: u64 = 0xdead_beef_0bad_f00d;
    let a = RngStream::new(seed, 3);
    let b = RngStream::from_seed_words(seed as u32, (seed >> 32) as u32, 3);
    assert_eq!(a, b);
    // Any draw can be computed directly from (base, draw).
    let mut s = RngStream::new(7, 0);
    let base = s.base;
    for d in 0..100 {
        assert_eq!(s.next_u32(), RngStream::u32_at(base, d));
    }
    // A copy repeats its draws: the stream is a value.
    let mut s = RngStream::new(7, 1);
    s.next_u32();
    let mut t = s;
    assert_eq!(s.next_f32(), t.next_f32());
}

#[test]
fn every_key_word_changes_the_stream() {
    let key = (5u64, 8u32);
    let base = RngStream::new(key.0, key.1).base;
    let variants = [
        RngStream::new(key.0 + 1, key.1),
        RngStream::new(key.0 | (1 << 32), key.1),
        RngStream::new(key.0, key.1 + 1),
        RngStream::new(next_episode_seed(key.0), key.1),
        // Seed words swapped.
        RngStream::new(key.0.rotate_right(32), key.1),
    ];
    for v in variants {
        assert_ne!(v.base, base);
    }
    // The all-zero key is not degenerate.
    let mut z = RngStream::new(0, 0);
    assert_ne!(z.base, 0);
    assert_ne!(z.next_u32(), 0);
}

/// The episode-seed sequence (docs/spec.md, determinism): environment i of a batch seeded with s
/// plays seeds s + i + k·G in its k-th episode. Hand-computed steps, the wrap at 2^64, the words,
/// and no seed repeated over a grid of 4096 environments × 4096 episodes of neighbouring batch
/// seeds.
#[test]
fn episode_seed_sequence() {
    assert_eq!(EPISODE_SEED_STEP, 0x9e37_79b9_7f4a_7c15);
    assert_eq!(EPISODE_SEED_STEP % 2, 1, "odd: period 2^64");
    assert_eq!(next_episode_seed(0), 0x9e37_79b9_7f4a_7c15);
    assert_eq!(next_episode_seed(1), 0x9e37_79b9_7f4a_7c16);
    // Wraps: u64::MAX + G = G - 1.
    assert_eq!(next_episode_seed(u64::MAX), 0x9e37_79b9_7f4a_7c14);
    // A carry from the low word into the high one.
    assert_eq!(
        seed_words(next_episode_seed(0xffff_ffff)),
        (0x7f4a_7c14, 0x9e37_79ba)
    );
    assert_eq!(
        seed_from_words(0x89ab_cdef, 0x0123_4567),
        0x0123_4567_89ab_cdef
    );
    assert_eq!(
        seed_words(0x0123_4567_89ab_cdef),
        (0x89ab_cdef, 0x0123_4567)
    );
    let mut seen = std::collections::HashSet::new();
    for batch_seed in [0u64, 1, 4096] {
        for env in 0..4096u64 {
            let mut seed = batch_seed + env;
            for _ in 0..64 {
                // Batches seeded 0, 1 and 4096 share environments' first seeds by design
                // (s + i); count each seed once.
                seen.insert(seed);
                seed = next_episode_seed(seed);
            }
        }
    }
    // 4096 + 1 + 4096 distinct start seeds (0..8192 as i ranges over the three batches), each
    // followed by 63 distinct later seeds.
    assert_eq!(seen.len(), 8192 * 64, "a seed repeated within the grid");
}

#[test]
fn uniform_mean_variance_and_chi_square() {
    let mut s = RngStream::new(1, 4);
    let mut bins = [0u64; 64];
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..N {
        let u = s.next_f32();
        assert!((0.0..1.0).contains(&u));
        bins[(u * 64.0) as usize] += 1;
        let u = f64::from(u);
        sum += u;
        sum2 += u * u;
    }
    let n = N as f64;
    let mean = sum / n;
    let var = sum2 / n - mean * mean;
    // Standard errors: 0.29e-3 for the mean, 0.075e-3 for the variance.
    assert!((mean - 0.5).abs() < 2e-3, "mean {mean}");
    assert!((var - 1.0 / 12.0).abs() < 1e-3, "variance {var}");
    let expected = n / 64.0;
    let chi2: f64 = bins
        .iter()
        .map(|&c| (c as f64 - expected).powi(2) / expected)
        .sum();
    // 63 degrees of freedom: mean 63, standard deviation 11.2; 130 is p ≈ 1e-6.
    println!("chi-square over 64 bins: {chi2:.1}");
    assert!(chi2 < 130.0, "chi-square {chi2}");
}

#[test]
fn every_output_bit_is_balanced() {
    let mut s = RngStream::new(99, 0);
    let mut ones = [0u32; 32];
    for _ in 0..N {
        let u = s.next_u32();
        for (b, c) in ones.iter_mut().enumerate() {
            *c += (u >> b) & 1;
        }
    }
    for (b, &c) in ones.iter().enumerate() {
        let p = f64::from(c) / N as f64;
        // Standard error 0.0005.
        assert!((p - 0.5).abs() < 0.003, "bit {b}: {p}");
    }
}

#[test]
fn no_correlation_between_neighbours() {
    const LIMIT: f64 = 0.01; // 10 standard errors at N = 1e6
    // Consecutive draws of one stream.
    let mut s = RngStream::new(3, 0);
    let v = floats(&mut s, N + 1);
    let r = correlation(&v[..N], &v[1..]);
    println!("consecutive draws: r = {r:.5}");
    assert!(r.abs() < LIMIT, "consecutive draws: r = {r}");

    // The same draw of neighbouring keys: stream, seed (low and high word), the next episode's
    // seed.
    type KeyFn = fn(u32) -> RngStream;
    let neighbours: [(&str, KeyFn, KeyFn); 4] = [
        (
            "stream",
            |i| RngStream::new(3, i),
            |i| RngStream::new(3, i + 1),
        ),
        (
            "seed",
            |i| RngStream::new(u64::from(i), 0),
            |i| RngStream::new(u64::from(i) + 1, 0),
        ),
        (
            "seed high word",
            |i| RngStream::new(u64::from(i) << 32, 0),
            |i| RngStream::new((u64::from(i) + 1) << 32, 0),
        ),
        (
            "next episode",
            |i| RngStream::new(u64::from(i), 0),
            |i| RngStream::new(next_episode_seed(u64::from(i)), 0),
        ),
    ];
    for (name, fa, fb) in neighbours {
        // 1e6 pairs: 1e5 keys, 10 draws each.
        let (mut a, mut b) = (Vec::with_capacity(N), Vec::with_capacity(N));
        for i in 0..(N / 10) as u32 {
            a.extend(floats(&mut fa(i), 10));
            b.extend(floats(&mut fb(i), 10));
        }
        let r = correlation(&a, &b);
        println!("neighbouring {name}: r = {r:.5}");
        assert!(r.abs() < LIMIT, "neighbouring {name}: r = {r}");
    }

    // Neighbouring purpose streams from stream_id.
    let (mut a, mut b) = (Vec::with_capacity(N), Vec::with_capacity(N));
    for i in 0..(N / 10) as u32 {
        a.extend(floats(&mut RngStream::new(3, stream_id(1, i)), 10));
        b.extend(floats(&mut RngStream::new(3, stream_id(1, i + 1)), 10));
    }
    let r = correlation(&a, &b);
    println!("neighbouring stream_id sub: r = {r:.5}");
    assert!(r.abs() < LIMIT, "stream_id: r = {r}");
}

#[test]
fn normal_moments() {
    let mut s = RngStream::new(11, 0);
    let (mut sum, mut sum2, mut sum4, mut within1) = (0.0f64, 0.0f64, 0.0f64, 0usize);
    for _ in 0..N {
        let z = s.normal();
        assert!(z.is_finite() && z.abs() < 6.0, "{z}");
        let z = f64::from(z);
        sum += z;
        sum2 += z * z;
        sum4 += z * z * z * z;
        within1 += usize::from(z.abs() < 1.0);
    }
    let n = N as f64;
    let mean = sum / n;
    let var = sum2 / n - mean * mean;
    let kurt = sum4 / n;
    let p1 = within1 as f64 / n;
    println!("normal: mean {mean:.4} var {var:.4} E[z^4] {kurt:.3} P(|z|<1) {p1:.4}");
    // Standard errors: 0.001 (mean), 0.0014 (variance), 0.01 (fourth moment), 0.0005 (P).
    assert!(mean.abs() < 0.006, "mean {mean}");
    assert!((var - 1.0).abs() < 0.008, "variance {var}");
    assert!((kurt - 3.0).abs() < 0.06, "fourth moment {kurt}");
    assert!((p1 - 0.682_689).abs() < 0.003, "P(|z|<1) {p1}");
    assert_eq!(s.draw, 2 * N as u32, "two draws per normal");
    let mut g = RngStream::new(11, 0);
    let mut h = RngStream::new(11, 0);
    assert_eq!(g.gauss(2.0, 0.5), 2.0 + 0.5 * h.normal());
}

#[test]
fn below_randint_chance_uniform() {
    let mut s = RngStream::new(21, 0);
    // below: uniform over [0, n).
    let mut counts = [0u64; 10];
    for _ in 0..N {
        counts[s.below(10) as usize] += 1;
    }
    let expected = N as f64 / 10.0;
    let chi2: f64 = counts
        .iter()
        .map(|&c| (c as f64 - expected).powi(2) / expected)
        .sum();
    // 9 degrees of freedom; 40 is p ≈ 5e-6.
    assert!(chi2 < 40.0, "below(10) chi-square {chi2}: {counts:?}");
    for _ in 0..1000 {
        assert_eq!(s.below(1), 0);
        assert_eq!(s.below(0), 0);
        assert!(s.below(1 << 24) < 1 << 24);
        assert!(s.below(3) < 3);
    }
    // randint is inclusive at both ends, like Python's random.randint.
    let (mut lo_seen, mut hi_seen) = (false, false);
    for _ in 0..10_000 {
        let v = s.randint(-2, 3);
        assert!((-2..=3).contains(&v));
        lo_seen |= v == -2;
        hi_seen |= v == 3;
        assert_eq!(s.randint(5, 5), 5);
    }
    assert!(lo_seen && hi_seen);
    // chance
    for _ in 0..1000 {
        assert!(!s.chance(0.0));
        assert!(s.chance(1.0));
    }
    let hits = (0..N).filter(|_| s.chance(0.3)).count();
    let p = hits as f64 / N as f64;
    assert!((p - 0.3).abs() < 0.003, "chance(0.3): {p}");
    // uniform stays in [lo, hi].
    for _ in 0..10_000 {
        let v = s.uniform(-1.5, 2.5);
        assert!((-1.5..=2.5).contains(&v), "{v}");
    }
    // Each of these consumes exactly one draw.
    let d = s.draw;
    s.next_u32();
    s.next_f32();
    s.uniform(0.0, 1.0);
    s.below(7);
    s.randint(0, 9);
    s.chance(0.5);
    assert_eq!(s.draw, d + 6);
}

#[test]
fn stream_ids_are_distinct() {
    let mut ids: Vec<u32> = (0..64)
        .flat_map(|kind| (0..4096).map(move |sub| stream_id(kind, sub)))
        .collect();
    ids.sort_unstable();
    ids.dedup();
    assert_eq!(ids.len(), 64 * 4096);
}

#[test]
fn mixer_avalanche() {
    // Flipping any one input bit flips each output bit with probability close to 1/2.
    let mut s = RngStream::new(77, 0);
    let mut flips = [[0u32; 32]; 32];
    const M: u32 = 20_000;
    for _ in 0..M {
        let x = s.next_u32();
        let h = mix32(x);
        for (i, row) in flips.iter_mut().enumerate() {
            let d = h ^ mix32(x ^ (1 << i));
            for (o, c) in row.iter_mut().enumerate() {
                *c += (d >> o) & 1;
            }
        }
    }
    for (i, row) in flips.iter().enumerate() {
        for (o, &c) in row.iter().enumerate() {
            let p = f64::from(c) / f64::from(M);
            // Standard error 0.0035; lowbias32's own bias is far smaller than this bound.
            assert!((p - 0.5).abs() < 0.03, "in bit {i} -> out bit {o}: {p}");
        }
    }
    assert_eq!(mix32(0), 0);
}

/// Contract (docs/ARCHITECTURE.md, determinism): every purpose has its own stream kind. Two
/// `pub const STREAM_*: u32 = N;` kinds with the same number would draw identical numbers for
/// different purposes; this scans the sources, so that kinds added on different branches cannot
/// collide unnoticed after a merge.
#[test]
fn stream_kinds_are_distinct() {
    fn scan(dir: &std::path::Path, kinds: &mut Vec<(u32, String)>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                scan(&path, kinds);
            } else if path.extension().is_some_and(|x| x == "rs") {
                for line in std::fs::read_to_string(&path).unwrap().lines() {
                    let line = line.trim();
                    let Some(rest) = line.strip_prefix("pub const STREAM_") else {
                        continue;
                    };
                    let (name, value) = rest.split_once(": u32 = ").unwrap_or_else(|| {
                        panic!("{}: unexpected stream kind line `{line}`", path.display())
                    });
                    let value = value.trim_end_matches(';').parse().unwrap_or_else(|_| {
                        panic!("{}: stream kind `{line}` is not a literal", path.display())
                    });
                    kinds.push((value, format!("STREAM_{name} ({})", path.display())));
                }
            }
        }
    }
    let mut kinds = Vec::new();
    scan(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src"),
        &mut kinds,
    );
    kinds.sort();
    assert!(kinds.len() >= 5, "stream kinds found: {kinds:?}");
    for pair in kinds.windows(2) {
        assert_ne!(
            pair[0].0, pair[1].0,
            "two streams share kind {}: {} and {}",
            pair[0].0, pair[0].1, pair[1].1
        );
    }
}
