//! The built-in policies (`socnav::policies`) on hand-made scenes: the go-to-goal controller and
//! the ORCA-driven robot drive straight at a free goal, turn toward one to the side, and ORCA
//! steers around a human standing in the way.

use crate::common::scene::{load, push, scene, static_human};

use socnav::policies::{OrcaRobot, goal_actions};
use socnav::{BatchEnv, Config};

/// exp1: a diff-drive robot.
fn exp1() -> Config {
    Config::from_name_or_path("exp1").expect("exp1")
}

fn actions(env: &BatchEnv) -> (Vec<f32>, Vec<f32>) {
    let mut goal = vec![0.0; 3 * env.n_envs()];
    goal_actions(env, &mut goal);
    let mut orca = vec![0.0; 3 * env.n_envs()];
    OrcaRobot::new().actions(env, &mut orca).unwrap();
    (goal, orca)
}

/// Contract: scene 0 (goal 3 m straight ahead, nothing between): both drive forward at full
/// speed without turning. Scene 1 (goal 3 m to the left): the goal controller turns in place at
/// full rate (π/2 is more than one step's turn); ORCA's velocity points left, which the diff-drive
/// mapping turns toward at full rate while driving at |v|. Scene 2: a human 0.8 m ahead on the
/// line to the goal: ORCA slows down or turns away, the goal controller does not see it.
#[test]
fn goal_and_orca_policies_on_hand_made_scenes() {
    let free = scene(true, [0.0, 0.0, 0.0], [3.0, 0.0]);
    let left = scene(true, [0.0, 0.0, 0.0], [0.0, 3.0]);
    let mut blocked = scene(true, [0.0, 0.0, 0.0], [3.0, 0.0]);
    push(
        &mut blocked,
        "humans",
        static_human(1, 0.8, 0.0, std::f64::consts::PI),
    );
    let env = load(exp1(), &[free, left, blocked]);
    let (goal, orca) = actions(&env);
    assert_eq!(&goal[0..3], &[1.0, 0.0, 0.0], "goal controller, free");
    assert_eq!(&orca[0..3], &[1.0, 0.0, 0.0], "ORCA, free");
    assert_eq!(
        &goal[3..6],
        &[0.0, 0.0, 1.0],
        "goal controller, goal to the left"
    );
    assert_eq!(orca[5], 1.0, "ORCA turns left at full rate");
    assert!(
        (orca[3] - 1.0).abs() < 1e-6,
        "ORCA drives at |v| = max speed: {}",
        orca[3]
    );
    assert_eq!(
        &goal[6..9],
        &[1.0, 0.0, 0.0],
        "the goal controller ignores the human"
    );
    // ORCA's velocity avoids the collision within its time horizon: it slows down (here to
    // under half speed) or turns.
    assert!(
        orca[6] < 0.5 || orca[8].abs() > 0.05,
        "ORCA drives into the human: {:?}",
        &orca[6..9]
    );
    for a in orca.iter().chain(&goal) {
        assert!((-1.0..=1.0).contains(a), "actions in [-1, 1]: {a}");
    }
}

/// Contract: a robot whose limits are 0 (a valid config: it stands still) gets 0 from the ORCA
/// policy, not 0 / 0, which the step would refuse as a NaN action.
#[test]
fn the_orca_policy_of_a_robot_that_cannot_move_is_zero() {
    let mut config = exp1();
    config.robot.max_speed = 0.0;
    config.robot.max_rotation = 0.0;
    let env = load(config, &[scene(true, [0.0, 0.0, 0.0], [3.0, 0.0])]);
    let (_, orca) = actions(&env);
    assert_eq!(orca, [0.0; 3]);
}
