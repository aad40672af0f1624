//! A headless batched rollout with random actions: prints outcome counts and env-steps/s.
//!
//! `cargo run --release --example headless -- configs/exp1.toml 1024 1000`

use std::time::Instant;

use socnav::{Actions, BatchEnv, Config, EnvOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let config = Config::from_name_or_path(&args.next().unwrap_or_else(|| "exp1".into()))?;
    let n_envs: usize = args.next().map_or(Ok(1024), |a| a.parse())?;
    let steps: usize = args.next().map_or(Ok(1000), |a| a.parse())?;
    let mut env = BatchEnv::new(
        config,
        EnvOptions {
            n_envs,
            seed: 0,
            ..Default::default()
        },
    )?;
    env.reset(None)?;
    // A fixed pseudo-random action sequence (a tiny LCG keeps the example dependency-free).
    let mut lcg = 12345u32;
    let mut actions = vec![0.0f32; 3 * n_envs];
    let (mut episodes, mut successes) = (0usize, 0usize);
    let start = Instant::now();
    for _ in 0..steps {
        for (i, a) in actions.iter_mut().enumerate() {
            lcg = lcg.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            *a = if i % 3 == 1 {
                0.0
            } else {
                (lcg >> 8) as f32 / 8_388_608.0 - 1.0
            };
        }
        env.step(Actions::Continuous(&actions))?;
        let out = env.outputs();
        for e in 0..n_envs {
            if out.episode_done[e] != 0 {
                episodes += 1;
                successes += usize::from(out.episode[e * socnav::spec::N_EPISODE + 2] != 0.0);
            }
        }
    }
    let secs = start.elapsed().as_secs_f64();
    println!(
        "{n_envs} envs x {steps} steps in {secs:.2} s: {:.0} env-steps/s; {episodes} episodes, {successes} successes",
        (n_envs * steps) as f64 / secs
    );
    Ok(())
}
