//! Queries of one environment's world during a step: which entities a disc touches, and the
//! shapes of the static objects. Shared by termination, the shadow robot, goal re-sampling and
//! contact handling, so every stage sees the same geometry.

use crate::geometry::{Disc, Rect, Shape, disc_disc_as, disc_rect_as};
use crate::params::StepParams;
use crate::state::StateChunk;

/// What a disc touches.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Touches {
    /// Any human (lone, group member, laptop user).
    pub human: bool,
    /// Any plant, wall, table or laptop.
    pub object: bool,
    /// Any wall.
    pub wall: bool,
}

/// Wall `w` of environment `e` as a rectangle.
#[inline]
pub fn wall_rect(p: &StepParams, s: &StateChunk, e: usize, w: usize) -> Rect {
    let i = e * s.strides.walls + w;
    Rect::with_trig(
        s.w_x[i],
        s.w_y[i],
        s.w_cos[i],
        s.w_sin[i],
        s.w_length[i],
        p.wall_thickness,
    )
}

/// Table `t` of environment `e` as a rectangle.
#[inline]
pub fn table_rect(p: &StepParams, s: &StateChunk, e: usize, t: usize) -> Rect {
    let i = e * s.strides.tables + t;
    Rect::with_trig(
        s.t_x[i],
        s.t_y[i],
        s.t_cos[i],
        s.t_sin[i],
        p.table_length,
        p.table_width,
    )
}

/// Laptop `l` of environment `e` as a rectangle.
#[inline]
pub fn laptop_rect(p: &StepParams, s: &StateChunk, e: usize, l: usize) -> Rect {
    let i = e * s.strides.laptops + l;
    Rect::with_trig(
        s.l_x[i],
        s.l_y[i],
        s.l_cos[i],
        s.l_sin[i],
        p.laptop_length,
        p.laptop_width,
    )
}

/// Blocker `b` of environment `e` as a rectangle.
#[inline]
pub fn blocker_rect(s: &StateChunk, e: usize, b: usize) -> Rect {
    let i = e * s.strides.blockers + b;
    Rect::new(
        s.b_x[i],
        s.b_y[i],
        s.b_theta[i],
        s.b_length[i],
        s.b_width[i],
    )
}

/// Which humans and objects the disc touches (touching counts), with discs shaped as
/// `[model] contact_shape` says ([`StepParams::contact_shape`]): the collision test of the
/// robot and of the shadow robot.
pub fn touches(p: &StepParams, s: &StateChunk, e: usize, d: &Disc) -> Touches {
    let shape = p.contact_shape;
    let mut t = Touches::default();
    let hb = e * s.strides.humans;
    t.human = (hb..hb + s.n_humans[e] as usize).any(|i| {
        disc_disc_as(
            shape,
            d,
            &Disc {
                x: s.h_x[i],
                y: s.h_y[i],
                r: p.human_radius,
            },
        )
    });
    t.wall = (0..s.n_walls[e] as usize).any(|w| disc_rect_as(shape, d, &wall_rect(p, s, e, w)));
    let pb = e * s.strides.plants;
    let plant = (pb..pb + s.n_plants[e] as usize).any(|i| {
        disc_disc_as(
            shape,
            d,
            &Disc {
                x: s.p_x[i],
                y: s.p_y[i],
                r: p.plant_radius,
            },
        )
    });
    let table =
        (0..s.n_tables[e] as usize).any(|k| disc_rect_as(shape, d, &table_rect(p, s, e, k)));
    let laptop =
        (0..s.n_laptops[e] as usize).any(|k| disc_rect_as(shape, d, &laptop_rect(p, s, e, k)));
    t.object = t.wall || plant || table || laptop;
    t
}

/// Does `shape` intersect anything that goal sampling avoids: every entity where it is now,
/// walls and spawn blockers (docs/spec.md 14: 0.1.1's spawn list holds live references)?
pub fn blocks_goal(p: &StepParams, s: &StateChunk, e: usize, shape: &Shape) -> bool {
    let robot = Shape::Disc(Disc {
        x: s.robot_x[e],
        y: s.robot_y[e],
        r: p.robot_radius,
    });
    if robot.intersects(shape) {
        return true;
    }
    let hb = e * s.strides.humans;
    let humans = (hb..hb + s.n_humans[e] as usize).any(|i| {
        Shape::Disc(Disc {
            x: s.h_x[i],
            y: s.h_y[i],
            r: p.human_radius,
        })
        .intersects(shape)
    });
    let pb = e * s.strides.plants;
    let plants = (pb..pb + s.n_plants[e] as usize).any(|i| {
        Shape::Disc(Disc {
            x: s.p_x[i],
            y: s.p_y[i],
            r: p.plant_radius,
        })
        .intersects(shape)
    });
    humans
        || plants
        || (0..s.n_walls[e] as usize).any(|w| Shape::Rect(wall_rect(p, s, e, w)).intersects(shape))
        || (0..s.n_tables[e] as usize)
            .any(|k| Shape::Rect(table_rect(p, s, e, k)).intersects(shape))
        || (0..s.n_laptops[e] as usize)
            .any(|k| Shape::Rect(laptop_rect(p, s, e, k)).intersects(shape))
        || (0..s.n_blockers[e] as usize)
            .any(|b| Shape::Rect(blocker_rect(s, e, b)).intersects(shape))
}
