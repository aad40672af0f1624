//! Criterion benches of the CPU step: exp1, exp2, exp3 at 1, 64, 1,024 and 4,096 environments,
//! observations written, DSRNN reward. Throughput is reported in env-steps per second.
//!
//! `cargo bench --bench step`; record figures in `benches/RESULTS.md` with the machine, batch size,
//! backend and commit.

use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use socnav::{Actions, BatchEnv, Config, EnvOptions};

fn step(c: &mut Criterion) {
    for name in ["exp1", "exp2", "exp3"] {
        let config = Config::from_name_or_path(name).expect("shipped config");
        let mut group = c.benchmark_group(format!("step/{name}"));
        group
            .measurement_time(Duration::from_secs(3))
            .warm_up_time(Duration::from_secs(1))
            .sample_size(20);
        for n in [1usize, 64, 1024, 4096] {
            let mut env = BatchEnv::new(
                config.clone(),
                EnvOptions {
                    n_envs: n,
                    seed: 0,
                    ..Default::default()
                },
            )
            .expect("valid batch");
            env.reset(None).expect("reset");
            // Forward while turning: episodes end by collisions and timeouts, so resets are included.
            let actions = [0.8f32, 0.0, 0.3].repeat(n);
            group.throughput(Throughput::Elements(n as u64));
            group.bench_function(BenchmarkId::from_parameter(n), |b| {
                b.iter(|| env.step(Actions::Continuous(&actions)).expect("step"));
            });
        }
        group.finish();
    }
}

criterion_group!(benches, step);
criterion_main!(benches);
