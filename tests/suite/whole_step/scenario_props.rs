//! Properties of generated scenarios (docs/spec.md 3.3-3.4), checked on the state right after
//! `reset` for every shipped config over many environments and seeds:
//!
//! - counts lie within the configured ranges; the room has the configured size and shape;
//! - entity ids are 0 (robot), then 1.. consecutive in spawn order (walking humans, static
//!   humans, plants, tables, free laptops, group members, laptop then user of each laptop use),
//!   walls last (docs/spec.md 3.1);
//! - human slots follow the observation order (static, walking, group members group by group,
//!   laptop users) and every group's members are contiguous;
//! - nothing overlaps what it was checked against at spawn, pair by pair as docs/spec.md 3.4 says
//!   (robot, humans, plants, tables, free laptops against everything placed before them; group
//!   members against everything placed before the group; a laptop on a table against laptops
//!   and laptop users only; a laptop user against everything);
//! - positions and goals lie in the sampling box (`room.margin`), and outside the L room's
//!   removed block; goals are free of every entity and of each other (docs/spec.md 3.4 step 9);
//! - laptops lie on a table edge; laptop users sit `laptop_width + human_distance` from their
//!   laptop, facing it;
//! - the processed ORCA obstacles fit the state's capacity (the largest split count is printed).
//!
//! And: a config that validation accepts but that cannot be placed makes `reset` return
//! `SimError::Scenario` naming the entity, without panicking or hanging.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use socnav::state::{BatchState, NONE, blocker_kind, group_kind, role, room_shape};
use socnav::{BatchEnv, Config, EnvOptions, SimError};

/// Environments per batch: enough to meet rare placements (tight L rooms, crowded corridors).
const N_ENVS: usize = 256;
/// Seeds per config.
const SEEDS: [u64; 3] = [0, 1, 2];
/// Penetration (m) accepted between two shapes that must not touch: the state holds f32
/// coordinates of magnitude up to ~10 m (ulp ~1e-6 m), and the simulator tests in f32 what this
/// test recomputes in f64.
const OVERLAP_EPS: f64 = 1e-5;
/// Slack (m) on "inside the sampling box": the box bounds and the sampled points are f32.
const BOX_EPS: f64 = 1e-5;

/// Every `configs/*.toml`; the spawn does not depend on the reward, so the SNGNN-v2 configs are
/// checked without the weight file.
fn shipped_configs() -> Vec<(String, Config)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs");
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("configs/ exists")
        .map(|e| e.expect("configs/ entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    paths
        .into_iter()
        .map(|p| {
            let name = p.file_stem().unwrap().to_string_lossy().into_owned();
            let config = Config::from_file(&p).unwrap_or_else(|e| panic!("{name}: {e}"));
            (name, crate::common::sngnn::without_sngnn_reward(config))
        })
        .collect()
}

/// A rotated rectangle in f64 (m): centre, cos and sin of the heading, half extents along its
/// local x and y axes.
#[derive(Debug, Clone, Copy)]
struct Rect {
    x: f64,
    y: f64,
    c: f64,
    s: f64,
    hl: f64,
    hw: f64,
}

impl Rect {
    /// Distance from (px, py) to the rectangle (0 inside).
    fn distance(&self, px: f64, py: f64) -> f64 {
        let (dx, dy) = (px - self.x, py - self.y);
        let (lx, ly) = (dx * self.c + dy * self.s, dy * self.c - dx * self.s);
        let ex = (lx.abs() - self.hl).max(0.0);
        let ey = (ly.abs() - self.hw).max(0.0);
        ex.hypot(ey)
    }

    /// Half extent of the rectangle projected on the unit axis (ax, ay).
    fn radius_along(&self, ax: f64, ay: f64) -> f64 {
        self.hl * (self.c * ax + self.s * ay).abs() + self.hw * (-self.s * ax + self.c * ay).abs()
    }
}

/// A 2-D shape in f64 (m).
#[derive(Debug, Clone, Copy)]
enum Shape {
    Disc { x: f64, y: f64, r: f64 },
    Rect(Rect),
}

fn rect(x: f32, y: f32, theta: f32, length: f32, width: f32) -> Shape {
    let t = f64::from(theta);
    Shape::Rect(Rect {
        x: x.into(),
        y: y.into(),
        c: t.cos(),
        s: t.sin(),
        hl: 0.5 * f64::from(length),
        hw: 0.5 * f64::from(width),
    })
}

fn disc(x: f32, y: f32, r: f32) -> Shape {
    Shape::Disc {
        x: x.into(),
        y: y.into(),
        r: r.into(),
    }
}

/// Signed separation of two shapes: > 0 when apart, <= 0 when they touch or overlap. For two
/// rectangles it is the largest separating-axis gap (a lower bound of the distance, exact sign).
fn gap(a: &Shape, b: &Shape) -> f64 {
    match (a, b) {
        (
            Shape::Disc { x, y, r },
            Shape::Disc {
                x: x2,
                y: y2,
                r: r2,
            },
        ) => (x - x2).hypot(y - y2) - r - r2,
        (Shape::Disc { x, y, r }, Shape::Rect(q)) | (Shape::Rect(q), Shape::Disc { x, y, r }) => {
            q.distance(*x, *y) - r
        }
        (Shape::Rect(a), Shape::Rect(b)) => {
            let (dx, dy) = (b.x - a.x, b.y - a.y);
            [(a.c, a.s), (-a.s, a.c), (b.c, b.s), (-b.s, b.c)]
                .into_iter()
                .map(|(ax, ay)| {
                    (dx * ax + dy * ay).abs() - a.radius_along(ax, ay) - b.radius_along(ax, ay)
                })
                .fold(f64::NEG_INFINITY, f64::max)
        }
    }
}

/// What a spawn-list entry is, for the checks that look at some kinds only.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// Walls, door gaps, robot, humans other than laptop users, plants, tables.
    Solid,
    /// Laptops, and the L room's removed block (0.1.1 adds it as a laptop-typed rectangle).
    Laptop,
    /// Humans seated at a laptop (part of a laptop use, docs/spec.md 3.4 step 8).
    LaptopUser,
}

/// The spawn list of one scenario, rebuilt from the state in spawn order.
#[derive(Default)]
struct SpawnList {
    shapes: Vec<(Kind, Shape, String)>,
    goals: Vec<(Shape, String)>,
    pairs_checked: usize,
}

impl SpawnList {
    /// Assert that `shape` is apart from every earlier entry `against` accepts, then add it.
    fn place(
        &mut self,
        ctx: &str,
        name: String,
        kind: Kind,
        shape: Shape,
        against: impl Fn(Kind) -> bool,
    ) {
        self.check(ctx, &name, &shape, &against);
        self.shapes.push((kind, shape, name));
    }

    fn check(&mut self, ctx: &str, name: &str, shape: &Shape, against: &impl Fn(Kind) -> bool) {
        for (k, other, other_name) in &self.shapes {
            if against(*k) {
                let g = gap(shape, other);
                assert!(
                    g > -OVERLAP_EPS,
                    "{ctx}: {name} overlaps {other_name} by {:.6} m",
                    -g
                );
                self.pairs_checked += 1;
            }
        }
    }

    /// Assert that a goal disc is free of every entity and every earlier goal, then add it.
    fn goal(&mut self, ctx: &str, name: String, shape: Shape) {
        self.check(ctx, &name, &shape, &|_| true);
        for (other, other_name) in &self.goals {
            let g = gap(&shape, other);
            assert!(
                g > -OVERLAP_EPS,
                "{ctx}: {name} overlaps {other_name} by {:.6} m",
                -g
            );
            self.pairs_checked += 1;
        }
        self.goals.push((shape, name));
    }
}

fn everything(_: Kind) -> bool {
    true
}

/// Largest number of ORCA obstacle vertices added by RVO2's edge splits in the scenes seen.
#[derive(Default)]
struct Stats {
    scenes: usize,
    pairs_checked: usize,
    max_split_vertices: usize,
    max_vertices: usize,
    laptops_on_tables: usize,
    laptop_users: usize,
    l_rooms: usize,
    groups: usize,
}

/// Contract: every invariant of the module docs, for every shipped config.
#[test]
fn scenarios_of_every_shipped_config_satisfy_the_spawn_invariants() {
    let configs = shipped_configs();
    assert!(!configs.is_empty());
    for (name, config) in &configs {
        let mut stats = Stats::default();
        for seed in SEEDS {
            let options = EnvOptions {
                n_envs: N_ENVS,
                seed,
                ..Default::default()
            };
            let mut env =
                BatchEnv::new(config.clone(), options).unwrap_or_else(|e| panic!("{name}: {e}"));
            env.reset(None)
                .unwrap_or_else(|e| panic!("{name} seed {seed}: {e}"));
            for e in 0..N_ENVS {
                let ctx = format!("{name} seed {seed} env {e}");
                check_scene(
                    &ctx,
                    config,
                    env.state().unwrap(),
                    e,
                    env.caps().obstacle_vertices,
                    &mut stats,
                );
            }
        }
        println!(
            "{name}: {} scenes, {} spawn pairs checked, {} groups, {} laptops on tables, {} laptop users, {} L rooms; \
             ORCA obstacle vertices: largest {} (capacity {}), largest split count {}",
            stats.scenes,
            stats.pairs_checked,
            stats.groups,
            stats.laptops_on_tables,
            stats.laptop_users,
            stats.l_rooms,
            stats.max_vertices,
            BatchEnv::new(config.clone(), EnvOptions::default())
                .unwrap()
                .caps()
                .obstacle_vertices,
            stats.max_split_vertices,
        );
        assert_eq!(stats.scenes, SEEDS.len() * N_ENVS);
        assert!(stats.pairs_checked > 0, "{name}: no spawn pair was checked");
    }
}

fn in_range(ctx: &str, what: &str, n: u32, range: [i32; 2]) {
    assert!(
        (range[0] as i64..=range[1] as i64).contains(&i64::from(n)),
        "{ctx}: {n} {what}, configured range {range:?}"
    );
}

/// Expected pose (x, y, θ) of a laptop on edge `edge` of a table (docs/spec.md 3.4 step 6).
fn laptop_on_edge(config: &Config, t: (f64, f64, f64), edge: usize) -> (f64, f64, f64) {
    let o = &config.objects;
    let across = 0.5 * f64::from(o.table_width - o.laptop_width);
    let along = 0.5 * f64::from(o.table_length - o.laptop_length);
    let (lx, ly, turn) = [
        (0.0, across, PI),
        (-along, 0.0, -0.5 * PI),
        (0.0, -across, 0.0),
        (along, 0.0, 0.5 * PI),
    ][edge];
    let (s, c) = t.2.sin_cos();
    (t.0 + lx * c - ly * s, t.1 + lx * s + ly * c, t.2 + turn)
}

/// Angle difference wrapped to (-π, π].
fn angle_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(2.0 * PI);
    if d > PI { d - 2.0 * PI } else { d }
}

#[expect(
    clippy::too_many_lines,
    reason = "one pass over a scene, in spawn order, reads best in one piece"
)]
fn check_scene(
    ctx: &str,
    config: &Config,
    s: &BatchState,
    e: usize,
    vertex_cap: usize,
    stats: &mut Stats,
) {
    let c = &s.strides;
    let n = &config.counts;
    let (hb, gb, lb, ub, tb, pb, wb, bb) = (
        e * c.humans,
        e * c.groups,
        e * c.laptops,
        e * c.laptop_users,
        e * c.tables,
        e * c.plants,
        e * c.walls,
        e * c.blockers,
    );
    stats.scenes += 1;
    assert_eq!(s.done[e], 0, "{ctx}: a fresh episode is not done");
    assert_eq!(s.tick[e], 0, "{ctx}");

    // ---- room ----
    let (mx, my) = (s.map_x[e], s.map_y[e]);
    assert_eq!(mx.fract(), 0.0, "{ctx}: room sizes are whole metres");
    assert_eq!(my.fract(), 0.0, "{ctx}");
    in_range(ctx, "m room x size", mx as u32, config.room.size_x);
    let shape = s.room_shape[e];
    if matches!(shape, room_shape::SQUARE | room_shape::L) {
        assert_eq!(mx, my, "{ctx}: square and L rooms have y = x");
    } else {
        in_range(ctx, "m room y size", my as u32, config.room.size_y);
    }
    let expected_walls = match (shape, config.room.corridors) {
        (room_shape::NO_WALLS, _) => 0,
        (room_shape::L, false) => 8,
        (room_shape::L, true) => 12,
        (_, false) => 4,
        (_, true) => 8,
    };
    assert_eq!(
        s.n_walls[e], expected_walls,
        "{ctx}: walls of room shape {shape}"
    );
    if shape == room_shape::L {
        stats.l_rooms += 1;
    }
    let margin = f64::from(config.room.margin);
    let (hx, hy) = (0.5 * f64::from(mx) - margin, 0.5 * f64::from(my) - margin);
    let in_box = |what: &str, x: f32, y: f32, slack: f64| {
        assert!(
            f64::from(x).abs() <= hx + slack && f64::from(y).abs() <= hy + slack,
            "{ctx}: {what} at ({x}, {y}) lies outside the sampling box ±({hx}, {hy})"
        );
    };

    // ---- counts ----
    let (n_static, n_dynamic) = (s.n_static[e], s.n_dynamic[e]);
    in_range(ctx, "static humans", n_static, n.static_humans);
    in_range(ctx, "walking humans", n_dynamic, n.dynamic_humans);
    in_range(ctx, "plants", s.n_plants[e], n.plants);
    in_range(ctx, "tables", s.n_tables[e], n.tables);
    let n_users = s.n_laptop_users[e];
    let n_free_laptops = s.n_laptops[e] - n_users;
    in_range(ctx, "free laptops", n_free_laptops, n.laptops);
    let n_groups = s.n_groups[e] as usize;
    let mut per_class = [0u32; 4]; // moving dispersing, moving non-dispersing, standing dispersing, standing non-dispersing
    for g in gb..gb + n_groups {
        let moving = s.g_kind[g] == group_kind::MOVING;
        per_class[usize::from(!moving) * 2 + usize::from(s.g_dispersable[g] == 0)] += 1;
        in_range(ctx, "members in a group", s.g_count[g], n.group_size);
    }
    in_range(
        ctx,
        "moving dispersing groups",
        per_class[0],
        n.moving_groups,
    );
    in_range(
        ctx,
        "moving non-dispersing groups",
        per_class[1],
        n.moving_groups_non_dispersing,
    );
    in_range(
        ctx,
        "standing dispersing groups",
        per_class[2],
        n.standing_groups,
    );
    in_range(
        ctx,
        "standing non-dispersing groups",
        per_class[3],
        n.standing_groups_non_dispersing,
    );
    let dispersing_users = (ub..ub + n_users as usize)
        .filter(|&u| s.lu_dispersable[u] != 0)
        .count() as u32;
    in_range(
        ctx,
        "dispersing laptop users",
        dispersing_users,
        n.laptop_users,
    );
    in_range(
        ctx,
        "non-dispersing laptop users",
        n_users - dispersing_users,
        n.laptop_users_non_dispersing,
    );
    stats.groups += n_groups;
    stats.laptop_users += n_users as usize;

    // ---- human slots in observation order, groups contiguous ----
    let members: u32 = (gb..gb + n_groups).map(|g| s.g_count[g]).sum();
    assert_eq!(
        s.n_humans[e],
        n_static + n_dynamic + members + n_users,
        "{ctx}: humans of every role"
    );
    for k in 0..n_static + n_dynamic {
        let i = hb + k as usize;
        let expected = if k < n_static {
            role::STATIC
        } else {
            role::DYNAMIC
        };
        assert_eq!(s.h_role[i], expected, "{ctx}: human slot {k}");
        assert_eq!(
            (s.h_group[i], s.h_laptop_user[i]),
            (NONE, NONE),
            "{ctx}: lone human slot {k}"
        );
    }
    let mut next = n_static + n_dynamic;
    let mut seen_standing = false;
    for (k, g) in (gb..gb + n_groups).enumerate() {
        assert_eq!(
            s.g_first[g], next,
            "{ctx}: group {k} must start right after the previous one"
        );
        let moving = s.g_kind[g] == group_kind::MOVING;
        assert!(
            !(moving && seen_standing),
            "{ctx}: moving groups come before standing groups"
        );
        seen_standing |= !moving;
        let member_role = if moving {
            role::MOVING_GROUP
        } else {
            role::STANDING_GROUP
        };
        for i in hb + next as usize..hb + (next + s.g_count[g]) as usize {
            assert_eq!(
                s.h_role[i],
                member_role,
                "{ctx}: group {k} member slot {}",
                i - hb
            );
            assert_eq!(
                s.h_group[i],
                k as u32,
                "{ctx}: group {k} member slot {}",
                i - hb
            );
        }
        next += s.g_count[g];
    }
    for (k, u) in (ub..ub + n_users as usize).enumerate() {
        assert_eq!(
            s.lu_human[u],
            next + k as u32,
            "{ctx}: laptop user {k} slot"
        );
        assert_eq!(
            s.lu_laptop[u],
            n_free_laptops + k as u32,
            "{ctx}: laptops in use follow the free ones"
        );
        let i = hb + s.lu_human[u] as usize;
        assert_eq!(s.h_role[i], role::LAPTOP_USER, "{ctx}");
        assert_eq!(s.h_laptop_user[i], k as u32, "{ctx}");
        assert_eq!(s.l_user[lb + s.lu_laptop[u] as usize], k as u32, "{ctx}");
    }
    for l in lb..lb + n_free_laptops as usize {
        assert_eq!(
            s.l_user[l],
            NONE,
            "{ctx}: free laptop {} has a user",
            l - lb
        );
    }

    // ---- ids: 0 robot, then 1.. in spawn order, walls last ----
    let mut ids: Vec<(u32, String)> = Vec::new();
    for k in n_static..n_static + n_dynamic {
        ids.push((s.h_id[hb + k as usize], format!("walking human slot {k}")));
    }
    for k in 0..n_static {
        ids.push((s.h_id[hb + k as usize], format!("static human slot {k}")));
    }
    ids.extend((0..s.n_plants[e] as usize).map(|k| (s.p_id[pb + k], format!("plant {k}"))));
    ids.extend((0..s.n_tables[e] as usize).map(|k| (s.t_id[tb + k], format!("table {k}"))));
    ids.extend((0..n_free_laptops as usize).map(|k| (s.l_id[lb + k], format!("free laptop {k}"))));
    for k in n_static + n_dynamic..n_static + n_dynamic + members {
        ids.push((s.h_id[hb + k as usize], format!("group member slot {k}")));
    }
    for u in ub..ub + n_users as usize {
        ids.push((
            s.l_id[lb + s.lu_laptop[u] as usize],
            format!("laptop of user {}", u - ub),
        ));
        ids.push((
            s.h_id[hb + s.lu_human[u] as usize],
            format!("laptop user {}", u - ub),
        ));
    }
    ids.extend((0..s.n_walls[e] as usize).map(|k| (s.w_id[wb + k], format!("wall {k}"))));
    for (k, (id, what)) in ids.iter().enumerate() {
        assert_eq!(
            *id,
            k as u32 + 1,
            "{ctx}: {what} has id {id}, expected {} (spawn order)",
            k + 1
        );
    }

    // ---- spawn list, in spawn order ----
    let p = config;
    let human_r = 0.5 * p.human.diameter;
    let mut spawn = SpawnList::default();
    for k in 0..s.n_walls[e] as usize {
        let w = wb + k;
        spawn.shapes.push((
            Kind::Solid,
            rect(
                s.w_x[w],
                s.w_y[w],
                s.w_theta[w],
                s.w_length[w],
                p.objects.wall_thickness,
            ),
            format!("wall {k}"),
        ));
    }
    let mut l_block = None;
    for k in 0..s.n_blockers[e] as usize {
        let b = bb + k;
        let shape = rect(
            s.b_x[b],
            s.b_y[b],
            s.b_theta[b],
            s.b_length[b],
            s.b_width[b],
        );
        let kind = if s.b_kind[b] == blocker_kind::L_BLOCK {
            l_block = Some(shape);
            Kind::Laptop
        } else {
            Kind::Solid
        };
        spawn
            .shapes
            .push((kind, shape, format!("spawn blocker {k}")));
    }
    assert_eq!(
        l_block.is_some(),
        shape == room_shape::L,
        "{ctx}: an L room has exactly its removed block"
    );
    let outside_l_block = |what: &str, x: f32, y: f32| {
        if let Some(Shape::Rect(block)) = l_block {
            let d = block.distance(x.into(), y.into());
            assert!(
                d > 0.0,
                "{ctx}: {what} at ({x}, {y}) lies in the L room's removed block"
            );
        }
    };
    spawn.place(
        ctx,
        "the robot".into(),
        Kind::Solid,
        disc(s.robot_x[e], s.robot_y[e], p.robot.radius),
        everything,
    );
    in_box("the robot", s.robot_x[e], s.robot_y[e], BOX_EPS);
    outside_l_block("the robot", s.robot_x[e], s.robot_y[e]);
    assert!(
        (-std::f32::consts::PI..=std::f32::consts::PI).contains(&s.robot_theta[e]),
        "{ctx}: robot heading"
    );
    for k in (n_static..n_static + n_dynamic).chain(0..n_static) {
        let i = hb + k as usize;
        let what = format!("lone human slot {k}");
        in_box(&what, s.h_x[i], s.h_y[i], BOX_EPS);
        outside_l_block(&what, s.h_x[i], s.h_y[i]);
        spawn.place(
            ctx,
            what,
            Kind::Solid,
            disc(s.h_x[i], s.h_y[i], human_r),
            everything,
        );
    }
    for k in 0..s.n_plants[e] as usize {
        let i = pb + k;
        in_box("a plant", s.p_x[i], s.p_y[i], BOX_EPS);
        outside_l_block("a plant", s.p_x[i], s.p_y[i]);
        spawn.place(
            ctx,
            format!("plant {k}"),
            Kind::Solid,
            disc(s.p_x[i], s.p_y[i], p.objects.plant_radius),
            everything,
        );
    }
    let o = &p.objects;
    let mut tables = Vec::new();
    for k in 0..s.n_tables[e] as usize {
        let i = tb + k;
        in_box("a table centre", s.t_x[i], s.t_y[i], BOX_EPS);
        outside_l_block("a table centre", s.t_x[i], s.t_y[i]);
        tables.push((
            f64::from(s.t_x[i]),
            f64::from(s.t_y[i]),
            f64::from(s.t_theta[i]),
        ));
        let shape = rect(
            s.t_x[i],
            s.t_y[i],
            s.t_theta[i],
            o.table_length,
            o.table_width,
        );
        spawn.place(ctx, format!("table {k}"), Kind::Solid, shape, everything);
    }
    let on_a_table = |what: &str, l: usize| {
        let (x, y, t) = (
            f64::from(s.l_x[l]),
            f64::from(s.l_y[l]),
            f64::from(s.l_theta[l]),
        );
        // 1e-4 m / rad: the pose is computed in f32 from f32 table poses of magnitude ~10 m.
        let found = tables.iter().any(|&table| {
            (0..4).any(|edge| {
                let (ex, ey, et) = laptop_on_edge(p, table, edge);
                (ex - x).abs() < 1e-4 && (ey - y).abs() < 1e-4 && angle_diff(et, t).abs() < 1e-4
            })
        });
        assert!(
            found,
            "{ctx}: {what} at ({x}, {y}, θ {t}) is on no table edge"
        );
    };
    for k in 0..n_free_laptops as usize {
        let l = lb + k;
        let shape = rect(
            s.l_x[l],
            s.l_y[l],
            s.l_theta[l],
            o.laptop_length,
            o.laptop_width,
        );
        if tables.is_empty() {
            in_box("a free-standing laptop", s.l_x[l], s.l_y[l], BOX_EPS);
            spawn.place(
                ctx,
                format!("free laptop {k}"),
                Kind::Laptop,
                shape,
                everything,
            );
        } else {
            // docs/spec.md 3.4 step 6: a laptop on a table is checked against other laptops only.
            on_a_table(&format!("free laptop {k}"), l);
            stats.laptops_on_tables += 1;
            spawn.place(ctx, format!("free laptop {k}"), Kind::Laptop, shape, |k| {
                k == Kind::Laptop
            });
        }
    }
    let group_r = f64::from(p.group.radius);
    for (k, g) in (gb..gb + n_groups).enumerate() {
        // Members are checked against everything placed before their group, not each other.
        let first = hb + s.g_first[g] as usize;
        let shapes: Vec<Shape> = (first..first + s.g_count[g] as usize)
            .map(|i| disc(s.h_x[i], s.h_y[i], human_r))
            .collect();
        for (m, shape) in shapes.iter().enumerate() {
            spawn.check(ctx, &format!("group {k} member {m}"), shape, &everything);
            let i = first + m;
            // Members stand within the group radius of a centre sampled in the box (per axis).
            in_box(
                &format!("group {k} member {m}"),
                s.h_x[i],
                s.h_y[i],
                group_r + BOX_EPS,
            );
        }
        for (m, shape) in shapes.into_iter().enumerate() {
            spawn
                .shapes
                .push((Kind::Solid, shape, format!("group {k} member {m}")));
        }
    }
    let seat = f64::from(o.laptop_width + p.laptop_use.human_distance);
    for (k, u) in (ub..ub + n_users as usize).enumerate() {
        let l = lb + s.lu_laptop[u] as usize;
        let i = hb + s.lu_human[u] as usize;
        on_a_table(&format!("laptop of user {k}"), l);
        // docs/spec.md 3.4 step 8: the laptop must not touch existing laptops or laptop uses.
        let laptop = rect(
            s.l_x[l],
            s.l_y[l],
            s.l_theta[l],
            o.laptop_length,
            o.laptop_width,
        );
        spawn.check(ctx, &format!("laptop of user {k}"), &laptop, &|k| {
            matches!(k, Kind::Laptop | Kind::LaptopUser)
        });
        // The user touches nothing placed before this laptop use.
        let human = disc(s.h_x[i], s.h_y[i], human_r);
        spawn.check(ctx, &format!("laptop user {k}"), &human, &everything);
        spawn
            .shapes
            .push((Kind::Laptop, laptop, format!("laptop of user {k}")));
        spawn
            .shapes
            .push((Kind::LaptopUser, human, format!("laptop user {k}")));
        // Seated laptop_width + human_distance from the laptop centre, facing it.
        let (dx, dy) = (
            f64::from(s.l_x[l] - s.h_x[i]),
            f64::from(s.l_y[l] - s.h_y[i]),
        );
        let d = dx.hypot(dy);
        // 1e-5 m: f32 pose arithmetic on coordinates of magnitude ~10 m.
        assert!(
            (d - seat).abs() < 1e-5,
            "{ctx}: laptop user {k} sits {d} m from the laptop, expected {seat}"
        );
        let facing = angle_diff(dy.atan2(dx), f64::from(s.h_theta[i]));
        assert!(
            facing.abs() < 1e-5,
            "{ctx}: laptop user {k} faces {facing} rad away from the laptop"
        );
    }

    // ---- goals (docs/spec.md 3.4 step 9) ----
    for k in n_static..n_static + n_dynamic {
        let i = hb + k as usize;
        let what = format!("goal of walking human slot {k}");
        in_box(&what, s.h_goal_x[i], s.h_goal_y[i], BOX_EPS);
        outside_l_block(&what, s.h_goal_x[i], s.h_goal_y[i]);
        spawn.goal(
            ctx,
            what,
            disc(s.h_goal_x[i], s.h_goal_y[i], p.human.goal_radius),
        );
    }
    for k in 0..n_static as usize {
        let i = hb + k;
        assert_eq!(
            (s.h_goal_x[i], s.h_goal_y[i]),
            (s.h_x[i], s.h_y[i]),
            "{ctx}: a static human's goal is its position"
        );
        spawn.goals.push((
            disc(s.h_x[i], s.h_y[i], p.human.goal_radius),
            format!("goal of static human slot {k}"),
        ));
    }
    in_box("the robot goal", s.goal_x[e], s.goal_y[e], BOX_EPS);
    outside_l_block("the robot goal", s.goal_x[e], s.goal_y[e]);
    spawn.goal(
        ctx,
        "the robot goal".into(),
        disc(s.goal_x[e], s.goal_y[e], p.robot.goal_radius),
    );
    for (k, g) in (gb..gb + n_groups).enumerate() {
        if s.g_kind[g] != group_kind::MOVING {
            continue;
        }
        let what = format!("goal of group {k}");
        in_box(&what, s.g_goal_x[g], s.g_goal_y[g], BOX_EPS);
        outside_l_block(&what, s.g_goal_x[g], s.g_goal_y[g]);
        spawn.goal(
            ctx,
            what,
            disc(s.g_goal_x[g], s.g_goal_y[g], p.group.goal_radius),
        );
        let first = hb + s.g_first[g] as usize;
        for i in first..first + s.g_count[g] as usize {
            assert_eq!(
                (s.h_goal_x[i], s.h_goal_y[i]),
                (s.g_goal_x[g], s.g_goal_y[g]),
                "{ctx}: group {k} member goal"
            );
        }
    }
    stats.pairs_checked += spawn.pairs_checked;

    // ---- ORCA obstacles ----
    let standing = (gb..gb + n_groups)
        .filter(|&g| s.g_kind[g] == group_kind::STANDING)
        .count();
    let polygons = s.n_tables[e] as usize
        + n_free_laptops as usize
        + s.n_plants[e] as usize
        + s.n_walls[e] as usize
        + n_users as usize
        + standing;
    let vertices = s.n_obstacle_vertices[e] as usize;
    assert!(
        vertices >= 4 * polygons,
        "{ctx}: {vertices} obstacle vertices for {polygons} rectangles"
    );
    assert!(
        vertices <= vertex_cap,
        "{ctx}: {vertices} obstacle vertices exceed the capacity {vertex_cap}"
    );
    stats.max_split_vertices = stats.max_split_vertices.max(vertices - 4 * polygons);
    stats.max_vertices = stats.max_vertices.max(vertices);
}

/// A room split into strips by two corridor walls: every strip is narrower than `what` needs.
fn corridor_config(size_y: i32, plant_radius: f32, plants: i32, tables: i32) -> Config {
    let mut c = Config::default();
    c.room.shape = socnav::config::Shape::Rectangle;
    c.room.corridors = true;
    c.room.size_x = [8, 8];
    c.room.size_y = [size_y, size_y];
    c.counts.dynamic_humans = [0, 0];
    c.objects.plant_radius = plant_radius;
    c.counts.plants = [plants, plants];
    c.counts.tables = [tables, tables];
    c
}

/// Contract: a config that validation accepts but whose entities cannot be placed is reported
/// by `reset` as `SimError::Scenario` naming the entity (never a panic, never a hang).
///
/// The scenes: an 8 m room split by the two corridor walls into strips. At 3 m the strips are
/// 0.7, 0.8 and 0.7 m wide (inside the walls), so a 0.9 m plant fits nowhere; at 5 m they are
/// at most 1.47 m wide, so a 1.5 m wide table fits nowhere. The door gaps are blocked for
/// spawning (docs/spec.md 3.3), so nothing can straddle a corridor wall. Validation does not model
/// the corridor walls, so it lets both through.
#[test]
fn unsatisfiable_scenario_is_an_error_naming_the_entity() {
    let cases = [
        ("plant", corridor_config(3, 0.45, 1, 0)),
        ("table", corridor_config(5, 0.4, 0, 1)),
    ];
    for (entity, config) in cases {
        assert!(
            socnav::config::validate(&config).is_empty(),
            "the {entity} case must pass validation"
        );
        let mut env = BatchEnv::new(
            config,
            EnvOptions {
                n_envs: 4,
                seed: 3,
                ..Default::default()
            },
        )
        .unwrap();
        let start = std::time::Instant::now();
        let err = env.reset(None).expect_err("the scenario cannot be placed");
        println!(
            "{entity}: reset failed after {:.2?}: {err}",
            start.elapsed()
        );
        match err {
            SimError::Scenario {
                entity: what,
                message,
                ..
            } => assert!(
                message.contains(entity) && what.contains(entity),
                "the error must name the {entity}: {what}, {message}"
            ),
            other => panic!("expected SimError::Scenario, got {other:?}"),
        }
    }
}
