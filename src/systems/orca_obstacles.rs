//! The ORCA obstacles of an environment, processed as RVO2's `processObstacles` does (which may
//! split edges) and stored in the `ov_*` columns. They change only when an obstacle appears or
//! disappears (a reset, a laptop user or a standing group forming or leaving), so they are rebuilt
//! only when `obstacles_dirty` is set, not every step.
//!
//! The polygons, in 0.1.1's order: tables, free laptops, plants (bounding squares), walls, laptop
//! users (axis-aligned squares of half-side `laptop_user_half_side`, 2 x human diameter in 0.1.1)
//! and standing groups (squares of half-side the group radius around the stored centre).

use std::cell::RefCell;

use crate::fixed::Fixed;
use crate::orca::{ObstacleScratch, ObstacleSet, process_obstacles};
use crate::params::StepParams;
use crate::state::{NONE, StateChunk, group_kind};

type Polygon = [[f32; 2]; 4];

/// Most obstacle polygons of one environment.
pub const MAX_POLYGONS: usize = 256;

thread_local! {
    static BUILD: RefCell<(ObstacleScratch, ObstacleSet)> = RefCell::new(Default::default());
}

/// Rebuild the processed obstacles of environment `e` if they are stale.
pub fn rebuild_if_dirty(p: &StepParams, s: &mut StateChunk, e: usize) {
    if s.obstacles_dirty[e] == 0 {
        return;
    }
    let mut polygons: Fixed<Polygon, MAX_POLYGONS> = Fixed::default();
    collect(p, s, e, &mut polygons);
    BUILD.with(|b| {
        let (scratch, set) = &mut *b.borrow_mut();
        // Reserved from the capacities on a thread's first build, so no later build allocates.
        set.reserve(s.strides.obstacle_vertices);
        scratch.reserve(s.strides.obstacle_vertices);
        process_obstacles(polygons.as_slice(), scratch, set)
            .unwrap_or_else(|err| panic!("scenario produced a degenerate obstacle: {err}"));
        store(s, e, set);
    });
    s.obstacles_dirty[e] = 0;
}

fn collect(p: &StepParams, s: &StateChunk, e: usize, out: &mut Fixed<Polygon, MAX_POLYGONS>) {
    let rect = |r: crate::geometry::Rect| -> Polygon {
        [0, 1, 2, 3].map(|k| {
            let (x, y) = r.corner(k);
            [x, y]
        })
    };
    let square = |x: f32, y: f32, h: f32| -> Polygon {
        [
            [x + h, y + h],
            [x - h, y + h],
            [x - h, y - h],
            [x + h, y - h],
        ]
    };
    for t in 0..s.n_tables[e] as usize {
        out.push(rect(super::world::table_rect(p, s, e, t)));
    }
    let lb = e * s.strides.laptops;
    for l in 0..s.n_laptops[e] as usize {
        if s.l_user[lb + l] == NONE {
            out.push(rect(super::world::laptop_rect(p, s, e, l)));
        }
    }
    let pb = e * s.strides.plants;
    for i in pb..pb + s.n_plants[e] as usize {
        out.push(square(s.p_x[i], s.p_y[i], p.plant_radius));
    }
    for w in 0..s.n_walls[e] as usize {
        out.push(rect(super::world::wall_rect(p, s, e, w)));
    }
    let hb = e * s.strides.humans;
    let ub = e * s.strides.laptop_users;
    for u in ub..ub + s.n_laptop_users[e] as usize {
        let h = hb + s.lu_human[u] as usize;
        out.push(square(s.h_x[h], s.h_y[h], p.laptop_user_half_side));
    }
    let gb = e * s.strides.groups;
    for g in gb..gb + s.n_groups[e] as usize {
        if s.g_kind[g] == group_kind::STANDING {
            out.push(square(s.g_x[g], s.g_y[g], p.group_radius));
        }
    }
}

fn store(s: &mut StateChunk, e: usize, set: &ObstacleSet) {
    let cap = s.strides.obstacle_vertices;
    assert!(
        set.len() <= cap,
        "{} processed obstacle vertices exceed the capacity of {cap} (raise SPLIT_VERTICES_PER_VERTEX)",
        set.len()
    );
    let v = set.as_view();
    let b = e * cap;
    let n = set.len();
    s.ov_x[b..b + n].copy_from_slice(v.x);
    s.ov_y[b..b + n].copy_from_slice(v.y);
    s.ov_dir_x[b..b + n].copy_from_slice(v.dir_x);
    s.ov_dir_y[b..b + n].copy_from_slice(v.dir_y);
    s.ov_next[b..b + n].copy_from_slice(v.next);
    s.ov_prev[b..b + n].copy_from_slice(v.prev);
    s.ov_convex[b..b + n].copy_from_slice(v.convex);
    s.n_obstacle_vertices[e] = n as u32;
}
