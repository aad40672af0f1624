//! Human motion (docs/spec.md 4.1 step 6): the speed threshold, hand-computed on an exact scene
//! (the scene helpers and the tolerances: `step/mod.rs`).

use crate::common::scene::{load, push, scene, walker};
use crate::step::{close, scene_config, step};

/// Contract: a walker whose velocity is below `speed_threshold` stands still (speed 0) but turns
/// to its velocity's direction; above the threshold it walks.
#[test]
fn speed_threshold_zeroes_a_slow_walker() {
    let mut doc = scene(false, [0.0, 0.0, 0.0], [-3.0, -3.0]);
    push(
        &mut doc,
        "humans",
        walker(1, 0.0, 2.0, 2.0, 0.05, [4.0, 2.0]),
    );
    // The walker's ORCA velocity in free space is its preferred velocity, 0.004 m/s towards +x.
    for (threshold, expected_speed) in [(0.005f32, 0.0f64), (0.003, 0.004)] {
        let mut c = scene_config();
        c.human.max_speed = 0.004;
        c.human.speed_threshold = threshold;
        let mut env = load(c, std::slice::from_ref(&doc));
        step(&mut env, &[[0.0; 3]]);
        let s = env.state().unwrap();
        close(
            &format!("threshold {threshold}: speed"),
            s.h_speed[0],
            expected_speed,
            1e-9,
        );
        close(
            &format!("threshold {threshold}: x"),
            s.h_x[0],
            expected_speed,
            1e-9,
        );
        assert_eq!(s.h_y[0], 2.0, "threshold {threshold}");
        // Heading 2.0 before; the velocity points along +x.
        close(
            &format!("threshold {threshold}: θ"),
            s.h_theta[0],
            0.0,
            1e-7,
        );
    }
}
