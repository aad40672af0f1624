//! CPU/GPU parity of stage `contacts` (docs/spec.md, determinism): from the same state, parameters
//! and actions, `shaders/contacts.wgsl` must leave the state and the outputs bit-identical to the
//! Rust stage on lavapipe, on rolled-out states perturbed before each run (the harness:
//! `tests/common/gpu.rs`); with `contact_shape = "polygon64"` also the collisions `termination`
//! decides with that shape.

use crate::common::gpu::*;
use socnav::StepParams;
use socnav::config::ContactShape;
use socnav::geometry::{Disc, Rect, disc_disc, disc_rect, poly64_disc_disc, poly64_disc_rect};
use socnav::outputs::Outputs;
use socnav::rng::RngStream;
use socnav::spec::{INFO_KEYS, info};
use socnav::state::BatchState;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Humans scattered over the room (and into its objects), half of them walking: every kind of
/// contact `contacts` resolves.
fn scatter_humans(s: &mut BatchState, _: &mut Outputs, _: &StepParams, rng: &mut RngStream) {
    for e in 0..s.n_envs {
        let (hx, hy) = (0.5 * s.map_x[e], 0.5 * s.map_y[e]);
        let hb = e * s.strides.humans;
        for i in hb..hb + s.n_humans[e] as usize {
            s.h_x[i] = uniform(rng, -hx, hx);
            s.h_y[i] = uniform(rng, -hy, hy);
        }
    }
}

/// Contract: `contacts`: humans pushed out of plants, walls (mirror images), tables and free
/// laptops; static humans only take the push's speed.
#[test]
fn contacts() {
    for name in ["exp1", "exp2", "exp3", "lroom_mixed", "corridor_mixed"] {
        check_parity("contacts", config(name), 256, 10, Some(scatter_humans));
    }
    let mut c = config("exp2");
    c.episode.time_step = 0.3;
    check_parity("contacts", c, 256, 10, Some(scatter_humans));
}

/// Placements inside the 64-gon's inset by [`near_contact`]: decisions that exact discs and
/// 64-gons make differently.
static INSET_PLACEMENTS: AtomicUsize = AtomicUsize::new(0);

/// A point at t x the contact distance of a disc of radius `r` from a random entity of
/// environment `e` (a human when `humans`, a plant, a table, a laptop or a wall), t in
/// [0.997, 1.002] around the 64-gon's inset (cos(π/64) = 0.9988), in a random direction: off a
/// disc's centre, or off a random point of a rectangle's edge or corner region. Counts the
/// placements whose exact and 64-gon verdicts differ in [`INSET_PLACEMENTS`].
fn near_contact(
    s: &BatchState,
    p: &StepParams,
    e: usize,
    r: f32,
    humans: bool,
    rng: &mut RngStream,
) -> Option<(f32, f32)> {
    let mut discs: Vec<Disc> = Vec::new();
    if humans {
        let hb = e * s.strides.humans;
        discs.extend((hb..hb + s.n_humans[e] as usize).map(|i| Disc {
            x: s.h_x[i],
            y: s.h_y[i],
            r: p.human_radius,
        }));
    }
    let pb = e * s.strides.plants;
    discs.extend((pb..pb + s.n_plants[e] as usize).map(|i| Disc {
        x: s.p_x[i],
        y: s.p_y[i],
        r: p.plant_radius,
    }));
    let mut rects: Vec<Rect> = Vec::new();
    let tb = e * s.strides.tables;
    rects.extend((tb..tb + s.n_tables[e] as usize).map(|i| {
        Rect::with_trig(
            s.t_x[i],
            s.t_y[i],
            s.t_cos[i],
            s.t_sin[i],
            p.table_length,
            p.table_width,
        )
    }));
    let lb = e * s.strides.laptops;
    rects.extend((lb..lb + s.n_laptops[e] as usize).map(|i| {
        Rect::with_trig(
            s.l_x[i],
            s.l_y[i],
            s.l_cos[i],
            s.l_sin[i],
            p.laptop_length,
            p.laptop_width,
        )
    }));
    let wb = e * s.strides.walls;
    rects.extend((wb..wb + s.n_walls[e] as usize).map(|i| {
        Rect::with_trig(
            s.w_x[i],
            s.w_y[i],
            s.w_cos[i],
            s.w_sin[i],
            s.w_length[i],
            p.wall_thickness,
        )
    }));
    let n = discs.len() + rects.len();
    if n == 0 {
        return None;
    }
    let k = rng.next_u32() as usize % n;
    let t = uniform(rng, 0.997, 1.002);
    let angle = uniform(rng, -std::f32::consts::PI, std::f32::consts::PI);
    let (sn, c) = socnav::math::sin_cos(angle);
    let (x, y, differs) = if k < discs.len() {
        let o = discs[k];
        let dist = t * (r + o.r);
        let (x, y) = (o.x + dist * c, o.y + dist * sn);
        let d = Disc { x, y, r };
        (x, y, disc_disc(&d, &o) != poly64_disc_disc(&d, &o))
    } else {
        let o = rects[k - discs.len()];
        // A boundary point in the local frame (on an edge, or a corner), then outwards by t·r
        // along the edge normal, or along `angle` folded into the corner's quarter.
        let (sx, sy) = (c.signum(), sn.signum());
        let (lx, ly) = match rng.next_u32() % 3 {
            0 => (sx * (o.hl + t * r), uniform(rng, -o.hw, o.hw)),
            1 => (uniform(rng, -o.hl, o.hl), sy * (o.hw + t * r)),
            _ => (
                sx * (o.hl + t * r * c.abs()),
                sy * (o.hw + t * r * sn.abs()),
            ),
        };
        let (x, y) = (o.x + (lx * o.c - ly * o.s), o.y + (lx * o.s + ly * o.c));
        let d = Disc { x, y, r };
        (x, y, disc_rect(&d, &o) != poly64_disc_rect(&d, &o))
    };
    INSET_PLACEMENTS.fetch_add(usize::from(differs), Ordering::Relaxed);
    Some((x, y))
}

/// Every walking human placed at a contact distance around the 64-gon's inset from an object.
fn humans_near_objects(s: &mut BatchState, _: &mut Outputs, p: &StepParams, rng: &mut RngStream) {
    for e in 0..s.n_envs {
        let hb = e * s.strides.humans;
        for i in hb..hb + s.n_humans[e] as usize {
            if let Some((x, y)) = near_contact(s, p, e, p.human_radius, false, rng) {
                (s.h_x[i], s.h_y[i]) = (x, y);
            }
        }
    }
}

/// The robot and the shadow robot each placed at a contact distance around the 64-gon's inset
/// from a human or an object, outcomes cleared, ticks before the episode's end.
fn robots_near_contacts(s: &mut BatchState, _: &mut Outputs, p: &StepParams, rng: &mut RngStream) {
    for e in 0..s.n_envs {
        if let Some((x, y)) = near_contact(s, p, e, p.robot_radius, true, rng) {
            (s.robot_x[e], s.robot_y[e]) = (x, y);
        }
        if let Some((x, y)) = near_contact(s, p, e, p.robot_radius, true, rng) {
            (s.shadow_x[e], s.shadow_y[e]) = (x, y);
        }
        s.tick[e] = 1;
        s.done[e] = 0;
        s.shadow_collided[e] = 0;
        s.shadow_reached[e] = 0;
    }
}

/// Contract: with `contact_shape = "polygon64"` (the 64-gon tests of common/geometry.wgsl), the
/// human push-out of `contacts` and the robot's and shadow robot's collisions of `termination`
/// are bit-identical, on states whose contacts lie around the 64-gon's inset: walls, plants,
/// tables and laptops (L rooms with corridors' mixed counts), a few hundred placements decided
/// differently by exact discs among them.
#[test]
fn polygon64_contacts_and_termination() {
    let mut c = config("lroom_mixed");
    c.model.contact_shape = ContactShape::Polygon64;
    INSET_PLACEMENTS.store(0, Ordering::Relaxed);
    if check_parity("contacts", c.clone(), 256, 8, Some(humans_near_objects)).is_none() {
        return;
    }
    let raised = check_parity("termination", c, 256, 8, Some(robots_near_contacts))
        .expect("the device opened once");
    for k in [
        info::COLLISION_HUMAN,
        info::COLLISION_OBJECT,
        info::COLLISION_WALL,
    ] {
        assert!(raised[k] > 0, "info flag {} never raised", INFO_KEYS[k]);
    }
    let inset = INSET_PLACEMENTS.load(Ordering::Relaxed);
    println!("{inset} placements inside the 64-gon's inset");
    assert!(inset >= 200, "only {inset} placements inside the inset");
}
