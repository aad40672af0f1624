//! The layers of a frame, drawn bottom to top by [`draw_scene`]: floor, tick marks, fields of
//! view, goals and group circles, formations in progress, furniture, walls, the robot's trail,
//! humans, group and laptop links, the shadow robot, the robot, and the progress bar. Each layer
//! reads only the columns it draws.

use super::canvas::{Canvas, Style};
use super::palette::{self, Rgb};
use crate::geometry::Rect;
use crate::math;
use crate::params::StepParams;
use crate::state::{BatchState, NONE, blocker_kind, forming, group_kind, role};
use crate::systems::perception;

/// Everything a frame shows (see [`super::Frame`]).
pub struct Scene<'a> {
    /// Step constants (sizes and radii).
    pub p: &'a StepParams,
    /// The batch state.
    pub s: &'a BatchState,
    /// Environment drawn.
    pub e: usize,
    /// Robot positions so far (m), oldest first.
    pub trail: &'a [(f32, f32)],
}

/// Draw every layer of `scene` on `c`.
pub fn draw_scene(c: &mut Canvas, scene: &Scene<'_>) {
    floor(c, scene);
    ticks(c);
    views(c, scene);
    goals(c, scene);
    formations(c, scene);
    furniture(c, scene);
    walls(c, scene);
    if scene.trail.len() > 1 {
        c.polyline(scene.trail, palette::ROBOT, 0.55, 1.5);
    }
    humans(c, scene);
    links(c, scene);
    robots(c, scene);
    progress(c, scene);
}

/// What a heatmap panel draws over its field: the robot's goal, furniture, walls, humans and
/// their links (no fields of view, formations, trail, robot or progress bar).
pub fn draw_overlay(c: &mut Canvas, sc: &Scene<'_>) {
    robot_goal(c, sc);
    furniture(c, sc);
    walls(c, sc);
    humans(c, sc);
    links(c, sc);
}

/// The room floor; an L room's removed block (its spawn blocker) is painted back as outside.
/// Corridor doors are gaps between wall pieces and need nothing.
pub fn floor(c: &mut Canvas, sc: &Scene<'_>) {
    let (s, e) = (sc.s, sc.e);
    let room = Rect::new(0.0, 0.0, 0.0, s.map_x[e], s.map_y[e]);
    c.rect(
        &room,
        Style {
            fill: Some((palette::FLOOR, 1.0)),
            stroke: None,
        },
    );
    let bb = e * s.strides.blockers;
    for b in bb..bb + s.n_blockers[e] as usize {
        if s.b_kind[b] == blocker_kind::L_BLOCK {
            let r = Rect::new(
                s.b_x[b],
                s.b_y[b],
                s.b_theta[b],
                s.b_length[b],
                s.b_width[b],
            );
            c.rect(
                &r,
                Style {
                    fill: Some((palette::OUTSIDE, 1.0)),
                    stroke: None,
                },
            );
        }
    }
}

/// 1 m tick marks in the margin along the room's bottom and left edges, every 5th one longer.
pub fn ticks(c: &mut Canvas) {
    let v = c.view;
    let w = v.line();
    let (left, bottom) = v.px(-0.5 * v.map_x, -0.5 * v.map_y);
    let len = |k: i32| {
        if k % 5 == 0 {
            0.5 * v.margin
        } else {
            0.3 * v.margin
        }
    };
    for k in 0..=(v.map_x.floor() as i32) {
        let x = left + v.len(k as f32);
        c.pixel_rect(x - 0.5 * w, bottom, w, len(k), palette::TICK);
    }
    for k in 0..=(v.map_y.floor() as i32) {
        let y = bottom - v.len(k as f32);
        c.pixel_rect(left - len(k), y - 0.5 * w, len(k), w, palette::TICK);
    }
}

/// Length (m) of the wedges that show a walker's field of view. 0.1.1's humans see without a
/// range limit; the wedge shows the direction and the opening, not how far they see.
const HUMAN_VIEW_LENGTH_M: f32 = 1.5;

/// The robot's sensor (its observation's field of view and range) when the observation is
/// partial, clipped to the room; and each lone walker's field of view when `human.fov_angle`
/// leaves anything out (the walkers that ORCA and SFM filter by it).
fn views(c: &mut Canvas, sc: &Scene<'_>) {
    let (p, s, e) = (sc.p, sc.s, sc.e);
    let (map_x, map_y) = (s.map_x[e], s.map_y[e]);
    c.clip_to(Some(&Rect::new(0.0, 0.0, 0.0, map_x, map_y)));
    if p.obs_partial != 0 {
        // An unlimited range reaches every point of the room.
        let reach = (map_x * map_x + map_y * map_y).sqrt();
        let sensor = Style {
            fill: Some((palette::ROBOT, 0.07)),
            stroke: Some((palette::ROBOT, 0.35, 1.0)),
        };
        c.wedge(
            (s.robot_x[e], s.robot_y[e]),
            s.robot_theta[e],
            p.obs_fov,
            p.obs_range.min(reach),
            sensor,
        );
    }
    if !perception::sees_everything(p.fov_angle) {
        let view = Style {
            fill: Some((palette::HUMAN_WALKING, 0.08)),
            stroke: Some((palette::HUMAN_WALKING, 0.3, 0.8)),
        };
        let hb = e * s.strides.humans;
        for i in hb..hb + s.n_humans[e] as usize {
            if s.h_role[i] == role::DYNAMIC {
                let apex = (s.h_x[i], s.h_y[i]);
                c.wedge(apex, s.h_theta[i], p.fov_angle, HUMAN_VIEW_LENGTH_M, view);
            }
        }
    }
    c.clip_to(None);
}

/// The robot's goal: a disc of `goal_radius`.
fn robot_goal(c: &mut Canvas, sc: &Scene<'_>) {
    let (p, s, e) = (sc.p, sc.s, sc.e);
    let goal = Style {
        fill: Some((palette::ROBOT, 0.12)),
        stroke: Some((palette::ROBOT, 0.9, 1.5)),
    };
    c.disc(s.goal_x[e], s.goal_y[e], p.goal_radius, goal);
}

/// The robot's goal (disc of `goal_radius`), lone walkers' goals (crosses), moving groups' goals
/// (crosses) and every group's stored centre (a faint circle of `group_radius`).
fn goals(c: &mut Canvas, sc: &Scene<'_>) {
    let (p, s, e) = (sc.p, sc.s, sc.e);
    robot_goal(c, sc);
    let cross = 0.6 * p.human_radius;
    let hb = e * s.strides.humans;
    for i in hb..hb + s.n_humans[e] as usize {
        if s.h_role[i] == role::DYNAMIC {
            c.cross(
                s.h_goal_x[i],
                s.h_goal_y[i],
                cross,
                palette::HUMAN_WALKING,
                0.45,
            );
        }
    }
    let gb = e * s.strides.groups;
    for g in gb..gb + s.n_groups[e] as usize {
        let colour = if s.g_kind[g] == group_kind::MOVING {
            c.cross(
                s.g_goal_x[g],
                s.g_goal_y[g],
                cross,
                palette::HUMAN_MOVING_GROUP,
                0.45,
            );
            palette::HUMAN_MOVING_GROUP
        } else {
            palette::HUMAN_STANDING_GROUP
        };
        let ring = Style {
            fill: Some((colour, 0.10)),
            stroke: Some((colour, 0.6, 1.0)),
        };
        c.disc(s.g_x[g], s.g_y[g], p.group_radius, ring);
    }
}

/// Formations in progress: a forming crowd's spot (a faint circle of
/// `group_radius`), its slots (crosses) and a line from each walker to its slot; a walker's
/// laptop seat (a cross) and the line to it.
fn formations(c: &mut Canvas, sc: &Scene<'_>) {
    let (p, s, e) = (sc.p, sc.s, sc.e);
    let hb = e * s.strides.humans;
    let cross = 0.5 * p.human_radius;
    if s.cf_active[e] != 0 {
        let colour = palette::HUMAN_STANDING_GROUP;
        c.disc(
            s.cf_x[e],
            s.cf_y[e],
            p.group_radius,
            Style::outline(colour, 0.45, 1.0),
        );
        let sb = e * s.strides.group_size;
        for k in sb..sb + s.cf_count[e] as usize {
            let slot = (s.cf_slot_x[k], s.cf_slot_y[k]);
            c.cross(slot.0, slot.1, cross, colour, 0.7);
            let i = hb + s.cf_human[k] as usize;
            if s.h_forming[i] == forming::CROWD {
                c.line((s.h_x[i], s.h_y[i]), slot, colour, 0.45, 1.0);
            }
        }
    }
    if s.lf_active[e] != 0 {
        let colour = palette::HUMAN_LAPTOP_USER;
        let seat = (s.lf_seat_x[e], s.lf_seat_y[e]);
        c.cross(seat.0, seat.1, cross, colour, 0.7);
        let i = hb + s.lf_human[e] as usize;
        c.line((s.h_x[i], s.h_y[i]), seat, colour, 0.45, 1.0);
    }
}

/// Tables, laptops (in use: highlighted) and plants.
fn furniture(c: &mut Canvas, sc: &Scene<'_>) {
    let (p, s, e) = (sc.p, sc.s, sc.e);
    let tb = e * s.strides.tables;
    for t in tb..tb + s.n_tables[e] as usize {
        let r = Rect::new(
            s.t_x[t],
            s.t_y[t],
            s.t_theta[t],
            p.table_length,
            p.table_width,
        );
        c.rect(&r, Style::solid(palette::TABLE));
    }
    let lb = e * s.strides.laptops;
    for l in lb..lb + s.n_laptops[e] as usize {
        let r = Rect::new(
            s.l_x[l],
            s.l_y[l],
            s.l_theta[l],
            p.laptop_length,
            p.laptop_width,
        );
        let style = if s.l_user[l] == NONE {
            Style::solid(palette::LAPTOP)
        } else {
            Style {
                fill: Some((palette::LAPTOP_IN_USE, 1.0)),
                stroke: Some((palette::HUMAN_LAPTOP_USER, 1.0, 2.0)),
            }
        };
        c.rect(&r, style);
    }
    let pb = e * s.strides.plants;
    for i in pb..pb + s.n_plants[e] as usize {
        c.disc(
            s.p_x[i],
            s.p_y[i],
            p.plant_radius,
            Style::solid(palette::PLANT),
        );
    }
}

/// Walls as dark rectangles of the wall thickness. A thin outline of the same colour closes the
/// anti-aliased seams where two wall pieces meet end to end (an L room's outer walls).
fn walls(c: &mut Canvas, sc: &Scene<'_>) {
    let (p, s, e) = (sc.p, sc.s, sc.e);
    let wb = e * s.strides.walls;
    for w in wb..wb + s.n_walls[e] as usize {
        let r = Rect::new(
            s.w_x[w],
            s.w_y[w],
            s.w_theta[w],
            s.w_length[w],
            p.wall_thickness,
        );
        c.rect(
            &r,
            Style {
                fill: Some((palette::WALL, 1.0)),
                stroke: Some((palette::WALL, 1.0, 0.7)),
            },
        );
    }
}

/// Lines joining the members of each group (a ring: member k to k + 1), and each laptop user
/// to their laptop. Drawn over the humans: group members stand close enough for their discs
/// to hide most of a line drawn underneath.
fn links(c: &mut Canvas, sc: &Scene<'_>) {
    let (s, e) = (sc.s, sc.e);
    let hb = e * s.strides.humans;
    let at = |i: usize| (s.h_x[i], s.h_y[i]);
    let gb = e * s.strides.groups;
    for g in gb..gb + s.n_groups[e] as usize {
        let (first, n) = (hb + s.g_first[g] as usize, s.g_count[g] as usize);
        let colour = if s.g_kind[g] == group_kind::MOVING {
            palette::HUMAN_MOVING_GROUP
        } else {
            palette::HUMAN_STANDING_GROUP
        };
        // Two members need one line, not the same line twice.
        let edges = if n > 2 { n } else { n.saturating_sub(1) };
        for k in 0..edges {
            c.line(
                at(first + k),
                at(first + (k + 1) % n),
                colour.darker(0.7),
                0.9,
                1.0,
            );
        }
    }
    let (ub, lb) = (e * s.strides.laptop_users, e * s.strides.laptops);
    for u in ub..ub + s.n_laptop_users[e] as usize {
        let h = hb + s.lu_human[u] as usize;
        let l = lb + s.lu_laptop[u] as usize;
        c.line(
            at(h),
            (s.l_x[l], s.l_y[l]),
            palette::HUMAN_LAPTOP_USER.darker(0.45),
            0.8,
            1.0,
        );
    }
}

/// A disc with a heading line from its centre to its rim.
fn agent(c: &mut Canvas, x: f32, y: f32, theta: f32, r: f32, colour: Rgb) {
    c.disc(x, y, r, Style::solid(colour));
    let (sn, cs) = math::sin_cos(theta);
    c.line(
        (x, y),
        (x + r * cs, y + r * sn),
        colour.darker(0.35),
        1.0,
        1.5,
    );
}

/// Humans, coloured by role.
fn humans(c: &mut Canvas, sc: &Scene<'_>) {
    let (p, s, e) = (sc.p, sc.s, sc.e);
    let hb = e * s.strides.humans;
    for i in hb..hb + s.n_humans[e] as usize {
        agent(
            c,
            s.h_x[i],
            s.h_y[i],
            s.h_theta[i],
            p.human_radius,
            palette::human(s.h_role[i]),
        );
    }
}

/// The ORCA shadow robot (faint outline with its heading) under the robot itself.
fn robots(c: &mut Canvas, sc: &Scene<'_>) {
    let (p, s, e) = (sc.p, sc.s, sc.e);
    let r = p.robot_radius;
    let (x, y) = (s.shadow_x[e], s.shadow_y[e]);
    c.disc(x, y, r, Style::outline(palette::SHADOW, 0.5, 1.0));
    let (sn, cs) = math::sin_cos(s.shadow_theta[e]);
    c.line((x, y), (x + r * cs, y + r * sn), palette::SHADOW, 0.5, 1.0);
    agent(
        c,
        s.robot_x[e],
        s.robot_y[e],
        s.robot_theta[e],
        r,
        palette::ROBOT,
    );
}

/// A thin bar along the bottom edge: elapsed ticks over the episode length.
fn progress(c: &mut Canvas, sc: &Scene<'_>) {
    let v = c.view;
    let h = (0.25 * v.margin).max(2.0);
    let (w, y) = (v.width as f32, v.height as f32 - h);
    let done = (sc.s.tick[sc.e] as f32 / sc.p.episode_length.max(1) as f32).clamp(0.0, 1.0);
    c.pixel_rect(0.0, y, w, h, palette::PROGRESS_TRACK);
    c.pixel_rect(0.0, y, done * w, h, palette::PROGRESS);
}
