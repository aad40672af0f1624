//! What a lone walker perceives (docs/spec.md 4.2-4.3): the entities whose shape meets its view
//! sector, used by its own ORCA simulation (`orca_world.rs`, `orca_obstacles.rs`) and its social
//! forces (`sfm.rs`). Moving groups (`group_velocities.rs`) and the shadow robot see everything, as
//! in 0.1.1, and do not come here.
//!
//! 0.1.1's sector has its apex at the human's centre, is centred on its heading, opens
//! `fov_angle` and reaches the farthest corner of the map, so everything inside the room within
//! the opening is in it: the sector is a wedge. 0.1.1 short-circuits to "everything visible" when
//! |fov − 2π| < 0.1 ([`sees_everything`]; every paper config has fov = 6.2831853), and otherwise
//! intersects shapely polygons: the sector as a 1001-point arc plus the apex, discs as 64-gons.
//! socnav tests the exact shapes against the exact wedge (`docs/fidelity.md` gives the
//! difference).
//!
//! The shapes tested are 0.1.1's: a lone human is a disc of the human radius; a plant a disc (its
//! ORCA obstacle is its bounding square, but it is seen as a disc); tables, laptops and walls
//! rectangles; a group (moving or standing) the disc of the group radius around its centre; a
//! laptop use the disc through the laptop's and the user's centres (centre halfway between them,
//! radius half the seat distance). The robot is not tested: 0.1.1 adds it whenever the human
//! avoids it this step, seen or not.

use crate::geometry::{Disc, Rect, Shape};
use crate::math;
use crate::params::StepParams;
use crate::state::{StateChunk, role};

/// How close to 2π (rad) a field of view must be for 0.1.1 to skip the test and see everything.
pub const FULL_VIEW_TOLERANCE: f32 = 0.1;

/// Whether a field of view of `fov` rad sees everything (0.1.1: |fov − 2π| < 0.1).
#[inline]
pub fn sees_everything(fov: f32) -> bool {
    (fov - math::TAU).abs() < FULL_VIEW_TOLERANCE
}

/// A view wedge: the apex and the directions of its two bounding rays (world frame).
///
/// The wedge is closed (a shape touching a bounding ray is seen, as shapely's `intersects`
/// counts touching) and unbounded (0.1.1's radius reaches the farthest map corner).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Apex x (m).
    pub x: f32,
    /// Apex y (m).
    pub y: f32,
    /// Unit direction of the clockwise bounding ray, heading − fov/2.
    pub right: [f32; 2],
    /// Unit direction of the counter-clockwise bounding ray, heading + fov/2.
    pub left: [f32; 2],
    /// Whether the opening exceeds π (the wedge is then not convex).
    pub wide: bool,
}

impl View {
    /// The wedge with apex (x, y) (m), centred on `heading` (rad), opening `fov` (rad, below 2π).
    pub fn new(x: f32, y: f32, heading: f32, fov: f32) -> Self {
        let half = 0.5 * fov;
        let (rs, rc) = math::sin_cos(heading - half);
        let (ls, lc) = math::sin_cos(heading + half);
        Self {
            x,
            y,
            right: [rc, rs],
            left: [lc, ls],
            wide: fov > math::PI,
        }
    }

    /// The view of human slot `i`, or `None` when its field of view sees everything.
    pub fn of_human(p: &StepParams, s: &StateChunk, i: usize) -> Option<Self> {
        if sees_everything(p.fov_angle) {
            return None;
        }
        Some(Self::new(s.h_x[i], s.h_y[i], s.h_theta[i], p.fov_angle))
    }

    /// Whether the point (px, py) (m) lies in the wedge.
    ///
    /// d is in the wedge when it is counter-clockwise of the right ray and clockwise of the left
    /// one. Up to π both must hold (the wedge is the intersection of the two half-planes); above
    /// π either suffices (its complement, a convex wedge narrower than π, is the intersection of
    /// the two opposite open half-planes).
    #[inline]
    pub fn contains(&self, px: f32, py: f32) -> bool {
        let (dx, dy) = (px - self.x, py - self.y);
        let after_right = self.right[0] * dy - self.right[1] * dx >= 0.0;
        let before_left = dx * self.left[1] - dy * self.left[0] >= 0.0;
        if self.wide {
            after_right || before_left
        } else {
            after_right && before_left
        }
    }

    /// Whether the disc meets the wedge.
    ///
    /// Exact, for any opening: the wedge W is closed and its boundary is its two rays, and a disc
    /// D is connected. If D meets W but is not inside it, D has points in W and outside it and so
    /// crosses the boundary: a ray hits D. Otherwise D lies in W and so does its centre. Hence D
    /// meets W iff its centre lies in W or a bounding ray hits D. Nothing here needs W convex,
    /// so it holds for openings above π too. A ray "hits" D already at its start when the apex
    /// lies inside D.
    #[inline]
    pub fn sees_disc(&self, d: &Disc) -> bool {
        self.contains(d.x, d.y)
            || self.ray_hits_disc(self.right, d)
            || self.ray_hits_disc(self.left, d)
    }

    /// Whether the rectangle meets the wedge: its centre lies in the wedge or a bounding ray hits
    /// it (exact for the same reason as [`View::sees_disc`]: a rectangle is connected, and any one
    /// of its points, its centre as well as a corner, lies in W when all of it does).
    #[inline]
    pub fn sees_rect(&self, r: &Rect) -> bool {
        self.contains(r.x, r.y)
            || self.ray_hits_rect(self.right, r)
            || self.ray_hits_rect(self.left, r)
    }

    /// Whether the shape meets the wedge.
    #[inline]
    pub fn sees(&self, shape: &Shape) -> bool {
        match shape {
            Shape::Disc(d) => self.sees_disc(d),
            Shape::Rect(r) => self.sees_rect(r),
        }
    }

    /// Does the ray from the apex along unit `u` meet the disc? The ray point nearest the centre
    /// is at t = max(0, (c − apex)·u); the apex itself when the centre is behind it.
    #[inline]
    fn ray_hits_disc(&self, u: [f32; 2], d: &Disc) -> bool {
        let (cx, cy) = (d.x - self.x, d.y - self.y);
        let t = (cx * u[0] + cy * u[1]).max(0.0);
        let (ex, ey) = (cx - t * u[0], cy - t * u[1]);
        ex * ex + ey * ey <= d.r * d.r
    }

    /// Does the ray from the apex along unit `u` meet the rectangle? Slab test in the rectangle's
    /// frame over t in [0, f32::MAX] (finite, so the WGSL twin needs no infinity); t = 0 inside
    /// both slabs is the apex inside the rectangle.
    #[inline]
    fn ray_hits_rect(&self, u: [f32; 2], r: &Rect) -> bool {
        let (ax, ay) = r.to_local(self.x, self.y);
        let dx = u[0] * r.c + u[1] * r.s;
        let dy = u[1] * r.c - u[0] * r.s;
        let (mut lo, mut hi) = (0.0f32, f32::MAX);
        for (a, d, h) in [(ax, dx, r.hl), (ay, dy, r.hw)] {
            if d == 0.0 {
                if a.abs() > h {
                    return false;
                }
                continue;
            }
            let (t1, t2) = ((-h - a) / d, (h - a) / d);
            let (near, far) = if t1 <= t2 { (t1, t2) } else { (t2, t1) };
            lo = lo.max(near);
            hi = hi.min(far);
        }
        lo <= hi
    }
}

/// Whether `view` (`None`: everything is visible) sees `shape`.
#[inline]
pub fn sees(view: Option<&View>, shape: &Shape) -> bool {
    view.is_none_or(|v| v.sees(shape))
}

/// The disc a group (moving or standing) is seen as: the group radius around its stored centre.
#[inline]
pub fn group_disc(p: &StepParams, s: &StateChunk, g: usize) -> Disc {
    Disc {
        x: s.g_x[g],
        y: s.g_y[g],
        r: p.group_radius,
    }
}

/// The disc laptop use `u` (a slot of `laptop_user` columns) of environment `e` is seen as:
/// centred halfway between the laptop and its user, of radius half the seat distance.
#[inline]
pub fn laptop_use_disc(p: &StepParams, s: &StateChunk, e: usize, u: usize) -> Disc {
    let h = e * s.strides.humans + s.lu_human[u] as usize;
    let l = e * s.strides.laptops + s.lu_laptop[u] as usize;
    Disc {
        x: 0.5 * (s.l_x[l] + s.h_x[h]),
        y: 0.5 * (s.l_y[l] + s.h_y[h]),
        r: 0.5 * (p.laptop_width + p.human_laptop_distance),
    }
}

/// Whether `view` sees human slot `j` of environment `e` as 0.1.1 decides it: a lone human by its
/// own disc, a group member by its group's disc, a laptop user by its laptop use's disc.
#[inline]
pub fn sees_human(view: Option<&View>, p: &StepParams, s: &StateChunk, e: usize, j: usize) -> bool {
    let Some(v) = view else {
        return true;
    };
    match s.h_role[j] {
        role::MOVING_GROUP | role::STANDING_GROUP => {
            let g = e * s.strides.groups + s.h_group[j] as usize;
            v.sees_disc(&group_disc(p, s, g))
        }
        role::LAPTOP_USER => {
            let u = e * s.strides.laptop_users + s.h_laptop_user[j] as usize;
            v.sees_disc(&laptop_use_disc(p, s, e, u))
        }
        _ => v.sees_disc(&Disc {
            x: s.h_x[j],
            y: s.h_y[j],
            r: p.human_radius,
        }),
    }
}
