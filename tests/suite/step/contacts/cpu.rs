//! Contacts (docs/spec.md 4.6): the push-out of humans from objects, hand-computed on exact scenes
//! (the scene helpers and the tolerances: `step/mod.rs`).

use crate::common::scene::{load, push, scene, static_human};
use crate::step::{close, scene_config, step};
use serde_json::json;
use socnav::spec::entity;

/// Contract: a human overlapping a plant is pushed out (docs/spec.md 4.6): penetration
/// k·ln(1 + exp(-(d - r_sum)/k)) with k = 1e-3, force 100·penetration away from the plant; the
/// human turns to the force, takes speed min(|F|·dt, max speed) and moves once more. Lone static
/// humans are never moved; a member of a standing group is.
#[test]
fn contact_pushes_a_human_out_of_a_plant() {
    let mut doc = scene(false, [-3.0, -3.0, 0.0], [3.0, -3.0]);
    push(&mut doc, "plants", json!({"id": 4, "x": 0.0, "y": 0.0}));
    // Slot 0: a static human overlapping the plant on the left. Slots 1, 2: a standing group,
    // member 1 overlapping the plant on the right (0.7 m < 0.36 + 0.4), member 2 clear of it.
    push(&mut doc, "humans", static_human(3, -0.7, 0.0, 0.5));
    for (id, x) in [(1, 0.7), (2, 2.14)] {
        push(
            &mut doc,
            "humans",
            json!({"id": id, "x": x, "y": 0.0, "theta": 1.0, "speed": 0.0, "policy": "orca",
                                        "role": "standing_group", "group": 0}),
        );
    }
    push(
        &mut doc,
        "groups",
        json!({"kind": "standing", "dispersable": false, "members": [1, 2], "centre": [1.42, 0.0]}),
    );
    let mut env = load(scene_config(), &[doc]);
    step(&mut env, &[[0.0; 3]]);
    let s = env.state().unwrap();
    // Penetration 1e-3·softplus(60) = 0.06 m, force 6 → speed min(6, 0.1) = 0.1 m/s along +x.
    // 1e-6: f32 positions near 1 m.
    close("pushed x", s.h_x[1], 0.8, 1e-6);
    close("pushed y", s.h_y[1], 0.0, 1e-6);
    close("pushed θ", s.h_theta[1], 0.0, 1e-6);
    close("pushed speed", s.h_speed[1], 0.1, 1e-7);
    assert_eq!(
        (s.h_x[2], s.h_y[2], s.h_theta[2], s.h_speed[2]),
        (2.14, 0.0, 1.0, 0.0),
        "member clear of the plant"
    );
    assert_eq!(
        (s.h_x[0], s.h_y[0], s.h_theta[0]),
        (-0.7, 0.0, 0.5),
        "a static human is never moved"
    );
}

/// Regression (found by `tests/suite/whole_step/golden_perturbed.rs`): a lone static human that
/// touches an object keeps its position and heading but takes the push's speed, as in 0.1.1, whose
/// `handle_collision` assigns `human.speed` while `Human.update_orientation` and `Human.update`
/// return early for a static human. socnav used to leave it untouched. The speed shows wherever a
/// human's velocity does: here the observation's relative speed.
#[test]
fn contact_gives_a_static_human_the_push_speed() {
    let mut doc = scene(false, [-3.0, -3.0, 0.0], [3.0, -3.0]);
    push(&mut doc, "plants", json!({"id": 2, "x": 0.0, "y": 0.0}));
    push(&mut doc, "humans", static_human(1, -0.7, 0.0, 0.5));
    let mut env = load(scene_config(), &[doc]);
    step(&mut env, &[[0.0; 3]]);
    let s = env.state().unwrap();
    assert_eq!(
        (s.h_x[0], s.h_y[0], s.h_theta[0]),
        (-0.7, 0.0, 0.5),
        "a static human is never moved nor turned"
    );
    // Penetration 1e-3·softplus(60) = 0.06 m, force 6 → speed min(6·1, 0.1) = 0.1 m/s, along the
    // unchanged heading 0.5 rad. 1e-7: f32 products of values below 1.
    close("speed", s.h_speed[0], 0.1, 1e-7);
    close("v_x", s.h_vx[0], 0.1 * 0.5f64.cos(), 1e-7);
    close("v_y", s.h_vy[0], 0.1 * 0.5f64.sin(), 1e-7);
    // The robot stands still: the relative speed is the human's.
    let at = env.layout().offset[entity::HUMANS];
    close(
        "observed relative speed",
        env.outputs().obs[at + 11],
        0.1,
        1e-7,
    );
}
