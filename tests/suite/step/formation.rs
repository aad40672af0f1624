//! CPU/GPU parity of stage `formation` (`src/systems/formation.rs`, `shaders/formation.wgsl`;
//! docs/spec.md, determinism), with the harness of the social-structure stages
//! (`step/social_events/gpu.rs`: states rolled out with raised event probabilities, perturbed
//! before every run, obstacle columns scrambled so that regrouping must rebuild them).

use crate::common::gpu::uniform;
use crate::step::social_events::gpu::{
    Seen, add, eventful, free_walkers, next_run, parity, selected,
};
use socnav::StepParams;
use socnav::outputs::Outputs;
use socnav::rng::RngStream;
use socnav::scenario::place;
use socnav::spec::{EVENT_KEYS, event};
use socnav::state::BatchState;
use socnav::systems::social_events;

/// For `formation`: crowd and laptop-use formations started where none is in progress, then the
/// walkers brought to their slots (the crowd forms), held together near the centre for the last
/// step before an approximate crowd, partly arrived, or left walking; laptop walkers brought to
/// their seats or not.
pub(crate) fn perturb_formation(
    s: &mut BatchState,
    _: &mut Outputs,
    p: &StepParams,
    rng: &mut RngStream,
) {
    next_run(s, rng);
    for e in 0..s.n_envs {
        let walkers = free_walkers(s, e);
        if s.cf_active[e] == 0 && s.lf_active[e] == 0 && walkers.len() >= 2 && rng.next_f32() < 0.7
        {
            let n = walkers
                .len()
                .min(s.strides.group_size)
                .min(2 + rng.below(3) as usize);
            let chosen: Vec<u32> = walkers[..n].to_vec();
            let hb = e * s.strides.humans;
            let (mut cx, mut cy) = (0.0, 0.0);
            for &h in &chosen {
                cx += s.h_x[hb + h as usize] / n as f32;
                cy += s.h_y[hb + h as usize] / n as f32;
            }
            let slots: Vec<place::Pose> = (0..n)
                .map(|k| {
                    let a = std::f32::consts::TAU * k as f32 / n as f32;
                    (
                        cx + p.group_radius * socnav::math::cos(a),
                        cy + p.group_radius * socnav::math::sin(a),
                        a - 3.0,
                    )
                })
                .collect();
            let mut ch = s.env_chunk(e);
            social_events::start_crowd_formation(&mut ch, 0, &chosen, &slots);
        }
        let free_laptop = (0..s.n_laptops[e])
            .find(|&l| s.l_user[e * s.strides.laptops + l as usize] == socnav::state::NONE);
        let walkers = free_walkers(s, e);
        if s.lf_active[e] == 0 && s.cf_active[e] == 0 && rng.next_f32() < 0.7 {
            if let (Some(l), Some(&h)) = (free_laptop, walkers.first()) {
                let ll = e * s.strides.laptops + l as usize;
                let seat = place::seat(p, s.l_x[ll], s.l_y[ll], s.l_theta[ll]);
                let mut ch = s.env_chunk(e);
                social_events::start_laptop_formation(&mut ch, 0, h, l, seat);
            }
        }
        let hb = e * s.strides.humans;
        let sb = e * s.strides.group_size;
        if s.cf_active[e] != 0 {
            let n = s.cf_count[e] as usize;
            let r = rng.next_f32();
            for k in 0..n {
                let i = hb + s.cf_human[sb + k] as usize;
                let arrive = r < 0.4 || (r < 0.6 && k % 2 == 0);
                if arrive {
                    s.h_x[i] = s.cf_slot_x[sb + k] + uniform(rng, -0.1, 0.1);
                    s.h_y[i] = s.cf_slot_y[sb + k] + uniform(rng, -0.1, 0.1);
                } else if r < 0.85 {
                    // Together near the centre, away from the slots.
                    s.h_x[i] = s.cf_x[e] + uniform(rng, -0.2, 0.2);
                    s.h_y[i] = s.cf_y[e] + uniform(rng, -0.2, 0.2);
                }
            }
            if (0.6..0.85).contains(&r) {
                s.cf_close_steps[e] = 24 - rng.below(2);
            }
        }
        if s.lf_active[e] != 0 && rng.next_f32() < 0.6 {
            let i = hb + s.lf_human[e] as usize;
            s.h_x[i] = s.lf_seat_x[e] + uniform(rng, -0.1, 0.1);
            s.h_y[i] = s.lf_seat_y[e] + uniform(rng, -0.1, 0.1);
        }
    }
}

/// Contract: `formation` (walkers taking their slot headings, crowds forming standing or moving
/// with a new group goal, approximate crowds after the walkers stayed together, laptop users
/// sitting down, the regrouping and obstacle rebuild after each) in square, L-shaped and corridor
/// rooms, one at dt = 0.3 s.
#[test]
fn formation_parity() {
    let mut total = Seen::default();
    let mut exp3 = eventful("exp3", 0.3);
    exp3.episode.time_step = 0.3;
    let configs = [
        ("exp3", exp3, 256),
        ("exp2", eventful("exp2", 0.3), 256),
        ("lroom_mixed", eventful("lroom_mixed", 0.3), 256),
        ("corridor_mixed", eventful("corridor_mixed", 0.3), 128),
    ];
    for (name, c, n) in configs {
        if !selected(name) {
            continue;
        }
        let Some(seen) = parity("formation", c, n, 10, perturb_formation) else {
            return;
        };
        add(&mut total, seen);
    }
    println!("formation overall: {total:?}");
    if std::env::var("GPU_SOCIAL_ONLY").is_ok() {
        return;
    }
    for k in [
        event::CROWD_FORMATION_COMPLETE,
        event::CROWD_FORMATION_APPROXIMATE,
        event::LAPTOP_FORMATION_COMPLETE,
    ] {
        assert!(total.events[k] > 0, "{} never happened", EVENT_KEYS[k]);
    }
    assert!(
        total.rebuilds > 0 && total.rebuilds_with_splits > 0,
        "{total:?}"
    );
}
