//! Episode seeds (docs/spec.md, determinism): every episode is named by one 64-bit seed,
//! environment i of a batch seeded with s starts with the episode of seed s + i, each later episode
//! takes the next seed of its sequence (`seeds::next_episode_seed`), the outputs report the seed of
//! every episode that ends, and the episode of seed e plays the same alone, in a batch of any size,
//! at any index.

use socnav::seeds::next_episode_seed;
use socnav::{Actions, BatchEnv, Config, EnvOptions, SimError};

/// A short-episode exp1, so that a run crosses several episode ends.
fn short_exp1() -> Config {
    let mut config = Config::from_name_or_path("exp1").expect("exp1");
    config.episode.length = 18;
    config
}

fn batch(config: &Config, n_envs: usize, seed: u64) -> BatchEnv {
    let mut env = BatchEnv::new(
        config.clone(),
        EnvOptions {
            n_envs,
            seed,
            ..Default::default()
        },
    )
    .expect("batch");
    env.reset(None).expect("reset");
    env
}

/// Varied actions that depend on the environment and the step only.
fn action(k: usize, t: usize) -> [f32; 3] {
    let forward = ((k * 5 + t * 3) % 11) as f32 / 5.0 - 1.0;
    let turn = ((k * 3 + t / 3) % 7) as f32 / 3.0 - 1.0;
    [forward, 0.0, turn]
}

fn obs_row(env: &BatchEnv, k: usize) -> Vec<u32> {
    let dim = env.layout().dim;
    env.outputs().obs[k * dim..(k + 1) * dim]
        .iter()
        .map(|x| x.to_bits())
        .collect()
}

fn ended_seed(env: &BatchEnv, k: usize) -> u64 {
    let o = env.outputs();
    socnav::seeds::seed_from_words(o.episode_seed_lo[k], o.episode_seed_hi[k])
}

/// One finished episode as an environment of the batch played it.
struct Played {
    seed: u64,
    /// The observation after the reset, then after every step.
    obs: Vec<Vec<u32>>,
    /// The reward of every step.
    rewards: Vec<u32>,
    actions: Vec<[f32; 3]>,
}

/// Every episode the environments of `env` finish in `steps` steps (NEXT_STEP autoreset: the
/// step after an episode's end resets the environment and ignores its action).
fn play(env: &mut BatchEnv, steps: usize) -> Vec<Vec<Played>> {
    let n = env.n_envs();
    let fresh = |env: &BatchEnv, k: usize| Played {
        seed: 0,
        obs: vec![obs_row(env, k)],
        rewards: Vec::new(),
        actions: Vec::new(),
    };
    let mut current: Vec<Played> = (0..n).map(|k| fresh(env, k)).collect();
    let mut finished: Vec<Vec<Played>> = (0..n).map(|_| Vec::new()).collect();
    let mut resets_next = vec![false; n];
    for t in 0..steps {
        let a: Vec<f32> = (0..n).flat_map(|k| action(k, t)).collect();
        env.step(Actions::Continuous(&a)).expect("step");
        let o = env.outputs();
        for k in 0..n {
            if resets_next[k] {
                current[k] = fresh(env, k);
                resets_next[k] = false;
                continue;
            }
            current[k].actions.push(action(k, t));
            current[k].obs.push(obs_row(env, k));
            current[k].rewards.push(o.reward[k].to_bits());
            if o.episode_done[k] != 0 {
                let mut done = fresh(env, k);
                std::mem::swap(&mut done, &mut current[k]);
                done.seed = ended_seed(env, k);
                finished[k].push(done);
                resets_next[k] = true;
            }
        }
    }
    finished
}

/// Contract: environment i's episodes have the seeds s + i, then the next ones of the sequence,
/// and the outputs report each one as it ends.
#[test]
fn batch_seeds_follow_the_sequence() {
    let (n, seed) = (6, 40);
    let mut env = batch(&short_exp1(), n, seed);
    let played = play(&mut env, 70);
    for (k, episodes) in played.iter().enumerate() {
        assert!(episodes.len() >= 3, "env {k}: {} episodes", episodes.len());
        let mut expected = seed + k as u64;
        for (j, ep) in episodes.iter().enumerate() {
            assert_eq!(ep.seed, expected, "env {k}, episode {j}");
            expected = next_episode_seed(expected);
        }
        assert_eq!(
            env.state().unwrap().next_seed(k),
            next_episode_seed(env.state().unwrap().episode_seed(k))
        );
    }
}

/// Contract: an episode of a batch (a first one and later ones, at any index) replays alone: a
/// one-environment batch reset with its seed and given the same actions produces the same
/// observations and rewards, bit for bit.
#[test]
fn an_episode_replays_alone_from_its_seed() {
    let config = short_exp1();
    let mut env = batch(&config, 5, 1234);
    let played = play(&mut env, 60);
    // Seeded with something else: only the reset's seed may matter.
    let mut single = batch(&config, 1, 77);
    let mut replayed = 0;
    for (k, episodes) in played.iter().enumerate() {
        for ep in episodes.iter().take(3) {
            single.reset(Some(ep.seed)).expect("reset");
            assert_eq!(
                obs_row(&single, 0),
                ep.obs[0],
                "env {k} seed {}: first observation",
                ep.seed
            );
            for (t, a) in ep.actions.iter().enumerate() {
                single.step(Actions::Continuous(a)).expect("step");
                assert_eq!(
                    obs_row(&single, 0),
                    ep.obs[t + 1],
                    "env {k} seed {}: step {t}",
                    ep.seed
                );
                assert_eq!(
                    single.outputs().reward[0].to_bits(),
                    ep.rewards[t],
                    "env {k}: reward at {t}"
                );
            }
            assert_eq!(
                single.outputs().episode_done[0],
                1,
                "env {k} seed {}: ends alike",
                ep.seed
            );
            assert_eq!(ended_seed(&single, 0), ep.seed);
            replayed += 1;
        }
    }
    assert_eq!(replayed, 15);
}

/// Contract: the episode of a seed does not depend on the index that plays it: seeds handed out
/// in another order give the same first observations, permuted; `None` keeps an environment's
/// sequence; a list of the wrong length is an error naming both lengths.
#[test]
fn next_seeds_name_episodes_at_any_index() {
    let config = Config::from_name_or_path("exp2").expect("exp2");
    let seeds = [9u64, u64::MAX, 1 << 40, 3];
    let mut a = batch(&config, 4, 0);
    a.set_next_seeds(&seeds.map(Some)).expect("seeds");
    a.reset(None).expect("reset");
    let mut b = batch(&config, 4, 0);
    let order = [2usize, 0, 3, 1];
    let permuted: Vec<Option<u64>> = order.iter().map(|&i| Some(seeds[i])).collect();
    b.set_next_seeds(&permuted).expect("seeds");
    b.reset(None).expect("reset");
    for (k, &i) in order.iter().enumerate() {
        assert_eq!(
            obs_row(&b, k),
            obs_row(&a, i),
            "seed {} at index {k} and {i}",
            seeds[i]
        );
        assert_eq!(b.state().unwrap().episode_seed(k), seeds[i]);
    }
    // None: the environment plays the next episode of its own sequence.
    let before = b.state().unwrap().next_seed(1);
    b.set_next_seeds(&[Some(5), None, None, None])
        .expect("seeds");
    b.reset(None).expect("reset");
    assert_eq!(b.state().unwrap().episode_seed(0), 5);
    assert_eq!(b.state().unwrap().episode_seed(1), before);
    assert_eq!(
        b.state().unwrap().episode_seed(1),
        next_episode_seed(seeds[0])
    );
    match b.set_next_seeds(&[Some(1), Some(2)]) {
        Err(SimError::Shape {
            what: "seeds",
            message: msg,
        }) => {
            assert!(
                msg.contains("2 seeds") && msg.contains("4 environments"),
                "{msg}"
            );
        }
        other => panic!("expected a shape error, got {other:?}"),
    }
}

/// Contract: `reset(Some(s))` is `s + i` for environment i, wrapping at 2^64, and the state
/// document carries the episode seed and the next one across `get_state`/`set_state`.
#[test]
fn reset_seed_wraps_and_documents_carry_seeds() {
    let config = Config::from_name_or_path("exp1").expect("exp1");
    let mut env = batch(&config, 3, 0);
    env.reset(Some(u64::MAX - 1)).expect("reset");
    let got: Vec<u64> = (0..3)
        .map(|k| env.state().unwrap().episode_seed(k))
        .collect();
    assert_eq!(got, [u64::MAX - 1, u64::MAX, 0]);
    let doc = env.get_state(1).expect("doc");
    assert_eq!(doc["socnav"]["seed"], serde_json::json!(u64::MAX));
    assert_eq!(
        doc["socnav"]["next_seed"],
        serde_json::json!(next_episode_seed(u64::MAX))
    );
    env.set_state(0, &doc).expect("load");
    assert_eq!(env.state().unwrap().episode_seed(0), u64::MAX);
    assert_eq!(
        env.state().unwrap().next_seed(0),
        next_episode_seed(u64::MAX)
    );
    let mut bad = doc.clone();
    bad["socnav"]["next_seed"] = serde_json::json!(-1);
    let err = env
        .set_state(2, &bad)
        .expect_err("negative seed")
        .to_string();
    assert!(err.contains("socnav.next_seed"), "{err}");
    assert_eq!(
        env.state().unwrap().episode_seed(2),
        0,
        "a rejected document changes nothing"
    );
}
