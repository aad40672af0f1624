//! `state::invariants` holds over every shipped DSRNN config stepped with adversarial actions
//! (bang-bang, spinning, random), and catches the breaks it is meant to catch.

use socnav::state::invariants::violations;
use socnav::{Actions, AutoresetMode, BatchEnv, Config, EnvOptions};

fn env(config: &str, n: usize) -> BatchEnv {
    let options = EnvOptions {
        n_envs: n,
        seed: 11,
        autoreset: AutoresetMode::NextStep,
        threads: Some(1),
        ..Default::default()
    };
    let mut env = BatchEnv::new(Config::from_name_or_path(config).unwrap(), options).unwrap();
    env.reset(Some(11)).unwrap();
    env
}

#[test]
fn shipped_configs_keep_the_invariants_under_adversarial_actions() {
    for config in [
        "exp1",
        "exp2",
        "exp3",
        "lroom_mixed",
        "corridor_mixed",
        "stress",
    ] {
        let n = 8;
        let mut env = env(config, n);
        let mut actions = vec![0.0f32; 3 * n];
        for t in 0..300u32 {
            for e in 0..n {
                // Bang-bang forward/back, spinning, and a fixed mixture.
                let a = match e % 3 {
                    0 => [
                        if (t / 7) % 2 == 0 { 1.0 } else { -1.0 },
                        0.0,
                        if t % 2 == 0 { 1.0 } else { -1.0 },
                    ],
                    1 => [0.0, 0.0, 1.0],
                    _ => [
                        1.0,
                        0.0,
                        if (t + e as u32).is_multiple_of(5) {
                            -1.0
                        } else {
                            0.3
                        },
                    ],
                };
                actions[3 * e..3 * e + 3].copy_from_slice(&a);
            }
            env.step(Actions::Continuous(&actions)).unwrap();
            for e in 0..n {
                let broken = violations(env.state().unwrap(), e);
                assert!(broken.is_empty(), "{config}, step {t}: {broken:?}");
            }
        }
    }
}

#[test]
fn broken_states_are_named() {
    let env = env("exp2", 2);
    let caps = env.state().unwrap().strides;
    let mut s = env.state().unwrap().clone();
    s.h_x[caps.humans] = f32::NAN;
    s.robot_y[0] = 1e6;
    s.h_role[1] = socnav::state::role::STATIC; // a group member that claims to be alone
    let broken = violations(&s, 0);
    assert!(
        broken
            .iter()
            .any(|m| m.contains("the robot at") && m.contains("outside the room")),
        "{broken:?}"
    );
    assert!(
        broken.iter().any(|m| m.contains("human slot 1: role 0")),
        "{broken:?}"
    );
    let other = violations(&s, 1);
    assert!(
        other
            .iter()
            .any(|m| m.contains("environment 1: human slot 0 at non-finite")),
        "{other:?}"
    );
}
