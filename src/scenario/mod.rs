//! Scenario generation (docs/spec.md 3.3-3.4): a deterministic function of the episode seed that
//! writes a fresh episode into one environment's slots of the batch state.
//!
//! The spawn order is 0.1.1's (it fixes the entity ids): robot, walking humans, static humans,
//! plants, tables, laptops, moving groups, standing groups, laptop users, then the walls' ids and
//! the goals. Human slots are then laid out in observation order (see [`crate::state`]).

pub mod place;

use crate::error::SimError;
use crate::geometry::{Disc, Rect, Shape};
use crate::math;
use crate::params::{StepParams, count, shape_code};
use crate::rng::{RngStream, stream_id};
use crate::room::{self, RoomLayout};
use crate::seeds;
use crate::state::{NONE, StateChunk, blocker_kind, group_kind, policy, role, room_shape};
use place::{Kind, SamplingBox, SpawnList};

/// RNG stream kind of scenario generation (`sub` = attempt).
pub const STREAM_SCENARIO: u32 = 1;

/// Whole-scenario attempts (each from a fresh RNG stream) before reset reports an error.
pub const MAX_SCENARIO_ATTEMPTS: u32 = 16;

/// Why one attempt failed: the entity that found no free spot.
type Attempt = Result<(), &'static str>;

/// Generate the episode of seed `next_seed[e]` in environment `e` of the chunk (batch index
/// `env_index`, named in errors only): it becomes the episode seed (`seed_*`), the next seed
/// advances along [`seeds::next_episode_seed`], and the episode is counted. Errors when no
/// attempt could place everything (nothing is then changed but the slots). What the scenario
/// does not draw (counters, caches, obstacles) is then initialised by
/// `systems::reset::init_episode`.
pub fn reset_env(
    p: &StepParams,
    s: &mut StateChunk,
    e: usize,
    env_index: u32,
) -> Result<(), SimError> {
    let seed = seeds::seed_from_words(s.next_seed_lo[e], s.next_seed_hi[e]);
    let mut last = "";
    // One spawn list for every attempt, borrowed, never moved: it holds every config's capacity
    // (about 22 KB), and a move copies all of it.
    let mut spawn = SpawnList::default();
    for attempt in 0..MAX_SCENARIO_ATTEMPTS {
        let mut rng = RngStream::new(seed, stream_id(STREAM_SCENARIO, attempt));
        match generate(p, s, e, &mut rng, &mut spawn) {
            Ok(()) => {
                (s.seed_lo[e], s.seed_hi[e]) = seeds::seed_words(seed);
                (s.next_seed_lo[e], s.next_seed_hi[e]) =
                    seeds::seed_words(seeds::next_episode_seed(seed));
                s.episode[e] = s.episode[e].wrapping_add(1);
                return Ok(());
            }
            Err(what) => last = what,
        }
    }
    Err(SimError::Scenario {
        env: env_index as usize,
        entity: last.to_owned(),
        message: format!(
            "environment {env_index}, episode seed {seed}: found no free spot for {last} in \
             {MAX_SCENARIO_ATTEMPTS} attempts of {} tries each; the room is too crowded for the \
             configured counts and sizes",
            place::MAX_TRIES
        ),
    })
}

/// The entity counts of one episode.
#[derive(Debug, Clone, Copy, Default)]
struct Counts {
    static_humans: u32,
    dynamic_humans: u32,
    plants: u32,
    tables: u32,
    laptops: u32,
    /// Groups in slot order: moving dispersing, moving non-dispersing, standing dispersing, standing non-dispersing.
    group_sets: [u32; 4],
    laptop_users: [u32; 2],
}

fn draw_counts(p: &StepParams, rng: &mut RngStream) -> Counts {
    let mut draw = |i: usize| {
        let [lo, hi] = p.count_range(i);
        rng.randint(lo, hi) as u32
    };
    Counts {
        static_humans: draw(count::STATIC_HUMANS),
        dynamic_humans: draw(count::DYNAMIC_HUMANS),
        tables: draw(count::TABLES),
        plants: draw(count::PLANTS),
        laptops: draw(count::LAPTOPS),
        group_sets: [
            draw(count::MOVING_GROUPS),
            draw(count::MOVING_GROUPS_ND),
            draw(count::STANDING_GROUPS),
            draw(count::STANDING_GROUPS_ND),
        ],
        laptop_users: [draw(count::LAPTOP_USERS), draw(count::LAPTOP_USERS_ND)],
    }
}

/// Draw the room, then place everything; writes the environment's slots (`spawn`: working
/// memory, cleared first).
fn generate(
    p: &StepParams,
    s: &mut StateChunk,
    e: usize,
    rng: &mut RngStream,
    spawn: &mut SpawnList,
) -> Attempt {
    // Unused slots hold zeros (crate::state): nothing of an earlier episode or attempt remains.
    s.clear_slots(e);
    let n = draw_counts(p, rng);
    let (shape, x, y, l_location) = draw_room(p, rng);
    draw_human_params(p, s, e, rng);
    let mut layout = RoomLayout::default();
    room::build(p, rng, shape, x, y, l_location, &mut layout);
    spawn.clear();
    write_room(s, e, shape, x, y, &layout, spawn);
    let area = SamplingBox::new(p, x, y);
    let mut g = Gen {
        p,
        rng,
        spawn,
        area,
        next_id: 1,
        e,
    };
    g.place_all(s, &n)
}

/// Shape code, room size (m) and L location of a new episode.
fn draw_room(p: &StepParams, rng: &mut RngStream) -> (u32, f32, f32, u32) {
    let shape = match p.shape {
        shape_code::SQUARE => room_shape::SQUARE,
        shape_code::RECTANGLE => room_shape::RECTANGLE,
        shape_code::L => room_shape::L,
        shape_code::NO_WALLS => room_shape::NO_WALLS,
        _ => [room_shape::RECTANGLE, room_shape::SQUARE, room_shape::L][rng.below(3) as usize],
    };
    let x = rng.randint(p.size_x_min, p.size_x_max) as f32;
    // Square and L rooms have y = x (0.1.1 decides this from the previous episode's shape; socnav
    // from the current one, see docs/fidelity.md).
    let y = if matches!(shape, room_shape::SQUARE | room_shape::L) {
        x
    } else {
        rng.randint(p.size_y_min, p.size_y_max) as f32
    };
    let l_location = if shape == room_shape::L {
        rng.below(4)
    } else {
        0
    };
    (shape, x, y, l_location)
}

/// Per-episode Gaussian crowd parameters (docs/spec.md 4.3), shared by all humans of the episode.
fn draw_human_params(p: &StepParams, s: &mut StateChunk, e: usize, rng: &mut RngStream) {
    s.orca_neighbor_dist[e] = 4.0 * p.human_radius + rng.normal();
    // 5 + N(0, 1) s; a non-positive horizon would make RVO2 divide by zero (NaN velocities), which
    // happens once in ~3 million episodes: socnav keeps it at least 0.1 s (docs/fidelity.md).
    s.orca_time_horizon[e] = (5.0 + rng.normal()).max(0.1);
    s.orca_time_horizon_obst[e] = (5.0 + rng.normal()).max(0.1);
    s.orca_max_speed[e] = p.human_max_speed + 0.01 * rng.normal();
    s.sfm_r0[e] = (0.05 + 0.01 * rng.normal()).abs();
    s.sfm_gamma[e] = 0.25 + 0.01 * rng.normal();
    s.sfm_n[e] = 1.0 + 0.1 * rng.normal();
    s.sfm_n_prime[e] = 1.0 + 0.1 * rng.normal();
    s.sfm_lambda[e] = 1.0 + 0.1 * rng.normal();
}

/// Write walls and blockers into the state and the spawn list.
fn write_room(
    s: &mut StateChunk,
    e: usize,
    shape: u32,
    x: f32,
    y: f32,
    room: &RoomLayout,
    spawn: &mut SpawnList,
) {
    s.room_shape[e] = shape;
    s.map_x[e] = x;
    s.map_y[e] = y;
    let wb = e * s.strides.walls;
    for (i, w) in room.walls.as_slice().iter().enumerate() {
        s.w_x[wb + i] = w.x;
        s.w_y[wb + i] = w.y;
        s.w_theta[wb + i] = w.theta;
        (s.w_sin[wb + i], s.w_cos[wb + i]) = math::sin_cos(w.theta);
        s.w_length[wb + i] = w.length;
        spawn.add(
            Kind::Solid,
            Shape::Rect(Rect::new(w.x, w.y, w.theta, w.length, w.width)),
        );
    }
    s.n_walls[e] = room.walls.len() as u32;
    let bb = e * s.strides.blockers;
    for (i, (kind, b)) in room.blockers.as_slice().iter().enumerate() {
        s.b_kind[bb + i] = *kind;
        s.b_x[bb + i] = b.x;
        s.b_y[bb + i] = b.y;
        s.b_theta[bb + i] = b.theta;
        s.b_length[bb + i] = b.length;
        s.b_width[bb + i] = b.width;
        // 0.1.1 adds the L block as a laptop-typed object: laptops on tables are checked against it.
        let k = if *kind == blocker_kind::L_BLOCK {
            Kind::Laptop
        } else {
            Kind::Solid
        };
        spawn.add(
            k,
            Shape::Rect(Rect::new(b.x, b.y, b.theta, b.length, b.width)),
        );
    }
    s.n_blockers[e] = room.blockers.len() as u32;
}

/// Placement of the entities of one attempt.
struct Gen<'a, 'r> {
    p: &'a StepParams,
    rng: &'r mut RngStream,
    spawn: &'r mut SpawnList,
    area: SamplingBox,
    next_id: u32,
    e: usize,
}

impl Gen<'_, '_> {
    fn id(&mut self) -> u32 {
        let id = self.next_id;
        self.next_id += 1;
        id
    }

    fn policy(&mut self) -> u32 {
        match self.p.human_policy {
            0 => policy::ORCA,
            1 => policy::SFM,
            _ => {
                if self.rng.chance(0.5) {
                    policy::ORCA
                } else {
                    policy::SFM
                }
            }
        }
    }

    fn place_all(&mut self, s: &mut StateChunk, n: &Counts) -> Attempt {
        let groups: u32 = n.group_sets.iter().sum();
        let users = n.laptop_users[0] + n.laptop_users[1];
        s.n_static[self.e] = n.static_humans;
        s.n_dynamic[self.e] = n.dynamic_humans;
        s.n_plants[self.e] = n.plants;
        s.n_tables[self.e] = n.tables;
        s.n_laptops[self.e] = n.laptops + users;
        s.n_groups[self.e] = groups;
        s.n_laptop_users[self.e] = users;
        self.place_robot(s)?;
        let hb = self.e * s.strides.humans;
        for k in 0..n.dynamic_humans {
            self.place_lone_human(s, hb + (n.static_humans + k) as usize, role::DYNAMIC)?;
        }
        for k in 0..n.static_humans {
            self.place_lone_human(s, hb + k as usize, role::STATIC)?;
        }
        for k in 0..n.plants as usize {
            self.place_plant(s, k)?;
        }
        for k in 0..n.tables as usize {
            self.place_table(s, k)?;
        }
        for k in 0..n.laptops as usize {
            self.place_free_laptop(s, k, n.tables)?;
        }
        let mut slot = n.static_humans + n.dynamic_humans;
        let mut gi = 0usize;
        for (set, &count) in n.group_sets.iter().enumerate() {
            let kind = if set < 2 {
                group_kind::MOVING
            } else {
                group_kind::STANDING
            };
            let dispersable = u32::from(set % 2 == 0);
            for _ in 0..count {
                let [lo, hi] = self.p.count_range(count::GROUP_SIZE);
                let size = self.rng.randint(lo, hi) as u32;
                self.place_group(s, gi, slot, size, kind, dispersable)?;
                slot += size;
                gi += 1;
            }
        }
        let mut ui = 0usize;
        for (set, &count) in n.laptop_users.iter().enumerate() {
            for _ in 0..count {
                self.place_laptop_user(
                    s,
                    ui,
                    slot as usize,
                    n.laptops as usize + ui,
                    n.tables,
                    u32::from(set == 0),
                )?;
                slot += 1;
                ui += 1;
            }
        }
        s.n_humans[self.e] = slot;
        let wb = self.e * s.strides.walls;
        for w in 0..s.n_walls[self.e] as usize {
            s.w_id[wb + w] = self.id();
        }
        self.place_goals(s, n)
    }

    fn place_robot(&mut self, s: &mut StateChunk) -> Attempt {
        let d = place::free_disc(self.rng, &self.area, self.spawn, self.p.robot_radius)
            .ok_or("the robot")?;
        let e = self.e;
        s.robot_x[e] = d.x;
        s.robot_y[e] = d.y;
        s.robot_theta[e] = place::heading(self.rng);
        self.spawn.add(Kind::Solid, Shape::Disc(d));
        Ok(())
    }

    fn place_lone_human(&mut self, s: &mut StateChunk, i: usize, r: u32) -> Attempt {
        let d = place::free_disc(self.rng, &self.area, self.spawn, self.p.human_radius)
            .ok_or("a lone human")?;
        s.h_id[i] = self.id();
        s.h_x[i] = d.x;
        s.h_y[i] = d.y;
        s.h_theta[i] = place::heading(self.rng);
        s.h_speed[i] = if r == role::DYNAMIC {
            self.rng.uniform(0.0, self.p.human_max_speed)
        } else {
            0.0
        };
        s.h_policy[i] = self.policy();
        set_role(s, i, r, NONE, NONE);
        self.spawn.add(Kind::Solid, Shape::Disc(d));
        Ok(())
    }

    fn place_plant(&mut self, s: &mut StateChunk, k: usize) -> Attempt {
        let d = place::free_disc(self.rng, &self.area, self.spawn, self.p.plant_radius)
            .ok_or("a plant")?;
        let i = self.e * s.strides.plants + k;
        s.p_id[i] = self.id();
        s.p_x[i] = d.x;
        s.p_y[i] = d.y;
        self.spawn.add(Kind::Solid, Shape::Disc(d));
        Ok(())
    }

    fn place_table(&mut self, s: &mut StateChunk, k: usize) -> Attempt {
        let (l, w) = (self.p.table_length, self.p.table_width);
        let (x, y, theta) =
            place::free_rect(self.rng, &self.area, self.spawn, l, w).ok_or("a table")?;
        let i = self.e * s.strides.tables + k;
        s.t_id[i] = self.id();
        s.t_x[i] = x;
        s.t_y[i] = y;
        s.t_theta[i] = theta;
        (s.t_sin[i], s.t_cos[i]) = math::sin_cos(theta);
        self.spawn
            .add(Kind::Solid, Shape::Rect(Rect::new(x, y, theta, l, w)));
        Ok(())
    }

    /// A laptop on a random table edge (checked against other laptops only), or anywhere free
    /// when there is no table.
    fn place_free_laptop(&mut self, s: &mut StateChunk, k: usize, tables: u32) -> Attempt {
        let (l, w) = (self.p.laptop_length, self.p.laptop_width);
        let pose = if tables > 0 {
            self.laptop_on_some_table(s, tables, |sp, shape| sp.blocked_by_laptop(shape))
        } else {
            place::free_rect(self.rng, &self.area, self.spawn, l, w)
        };
        let (x, y, theta) = pose.ok_or("a laptop")?;
        let i = self.e * s.strides.laptops + k;
        s.l_id[i] = self.id();
        write_laptop(s, i, x, y, theta, NONE);
        self.spawn
            .add(Kind::Laptop, Shape::Rect(Rect::new(x, y, theta, l, w)));
        Ok(())
    }

    /// Rejection-sample a laptop pose on a random edge of a random table, accepted by `free`.
    fn laptop_on_some_table(
        &mut self,
        s: &StateChunk,
        tables: u32,
        free: impl Fn(&SpawnList, &Shape) -> bool,
    ) -> Option<(f32, f32, f32)> {
        let tb = self.e * s.strides.tables;
        (0..place::MAX_TRIES).find_map(|_| {
            let t = tb + self.rng.below(tables) as usize;
            let edge = self.rng.below(4);
            let (x, y, theta) =
                place::laptop_on_table(self.p, s.t_x[t], s.t_y[t], s.t_theta[t], edge);
            let shape = Shape::Rect(Rect::new(
                x,
                y,
                theta,
                self.p.laptop_length,
                self.p.laptop_width,
            ));
            (!free(self.spawn, &shape)).then_some((x, y, theta))
        })
    }

    /// A group of `size` members on a circle around a free centre (docs/spec.md 4.4); rejected if
    /// any member touches something placed.
    fn place_group(
        &mut self,
        s: &mut StateChunk,
        gi: usize,
        first: u32,
        size: u32,
        kind: u32,
        dispersable: u32,
    ) -> Attempt {
        let p = self.p;
        let hb = self.e * s.strides.humans;
        let n = size as usize;
        let mut poses = [(0.0, 0.0, 0.0); place::MAX_GROUP];
        let standing = kind == group_kind::STANDING;
        let found = (0..place::MAX_TRIES).any(|_| {
            let (cx, cy) = self.area.point(self.rng);
            place::group_layout(p, self.rng, cx, cy, n, standing, &mut poses);
            poses[..n].iter().all(|&(x, y, _)| {
                !self.spawn.blocked(&Shape::Disc(Disc {
                    x,
                    y,
                    r: p.human_radius,
                }))
            })
        });
        if !found {
            return Err("a group");
        }
        let speed = if kind == group_kind::MOVING {
            self.rng.uniform(0.0, p.human_max_speed)
        } else {
            0.0
        };
        let member_role = if kind == group_kind::MOVING {
            role::MOVING_GROUP
        } else {
            role::STANDING_GROUP
        };
        let (mut sx, mut sy) = (0.0f32, 0.0f32);
        for (k, &(x, y, theta)) in poses.iter().take(n).enumerate() {
            let i = hb + first as usize + k;
            s.h_id[i] = self.id();
            s.h_x[i] = x;
            s.h_y[i] = y;
            s.h_theta[i] = theta;
            s.h_speed[i] = speed;
            s.h_policy[i] = self.policy();
            // Standing members have no goal: their own position, as a loaded document gives
            // them (moving members get the group goal in `place_goals`).
            s.h_goal_x[i] = x;
            s.h_goal_y[i] = y;
            set_role(s, i, member_role, gi as u32, NONE);
            sx += x;
            sy += y;
            self.spawn.add(
                Kind::Solid,
                Shape::Disc(Disc {
                    x,
                    y,
                    r: p.human_radius,
                }),
            );
        }
        let g = self.e * s.strides.groups + gi;
        s.g_kind[g] = kind;
        s.g_dispersable[g] = dispersable;
        s.g_first[g] = first;
        s.g_count[g] = size;
        s.g_x[g] = sx / size as f32;
        s.g_y[g] = sy / size as f32;
        s.g_vx[g] = 0.0;
        s.g_vy[g] = 0.0;
        Ok(())
    }

    /// A laptop on a table edge free of other laptops, and its user seated in front of it; both
    /// are drawn again when the seat touches anything placed.
    fn place_laptop_user(
        &mut self,
        s: &mut StateChunk,
        ui: usize,
        slot: usize,
        laptop: usize,
        tables: u32,
        dispersable: u32,
    ) -> Attempt {
        let p = self.p;
        let tb = self.e * s.strides.tables;
        let found = (0..place::MAX_TRIES).find_map(|_| {
            let t = tb + self.rng.below(tables) as usize;
            let edge = self.rng.below(4);
            let (lx, ly, lt) = place::laptop_on_table(p, s.t_x[t], s.t_y[t], s.t_theta[t], edge);
            let laptop = Shape::Rect(Rect::new(lx, ly, lt, p.laptop_length, p.laptop_width));
            if self.spawn.blocked_by_laptop(&laptop) {
                return None;
            }
            let seat = place::seat(p, lx, ly, lt);
            let human = Disc {
                x: seat.0,
                y: seat.1,
                r: p.human_radius,
            };
            (!self.spawn.blocked(&Shape::Disc(human))).then_some((
                (lx, ly, lt),
                seat,
                laptop,
                human,
            ))
        });
        let ((lx, ly, lt), seat, laptop_shape, human) = found.ok_or("a laptop user")?;
        let li = self.e * s.strides.laptops + laptop;
        s.l_id[li] = self.id();
        write_laptop(s, li, lx, ly, lt, ui as u32);
        let i = self.e * s.strides.humans + slot;
        s.h_id[i] = self.id();
        s.h_x[i] = seat.0;
        s.h_y[i] = seat.1;
        s.h_theta[i] = seat.2;
        s.h_speed[i] = 0.0;
        // A laptop user has no goal: its own position, as a loaded document gives it.
        s.h_goal_x[i] = seat.0;
        s.h_goal_y[i] = seat.1;
        s.h_policy[i] = self.policy();
        set_role(s, i, role::LAPTOP_USER, NONE, ui as u32);
        let u = self.e * s.strides.laptop_users + ui;
        s.lu_human[u] = slot as u32;
        s.lu_laptop[u] = laptop as u32;
        s.lu_dispersable[u] = dispersable;
        self.spawn.add(Kind::Laptop, laptop_shape);
        self.spawn.add(Kind::Solid, Shape::Disc(human));
        Ok(())
    }

    /// Goals (docs/spec.md 3.4 step 9): walkers, static humans (their own position), the robot,
    /// moving groups.
    fn place_goals(&mut self, s: &mut StateChunk, n: &Counts) -> Attempt {
        let p = self.p;
        let hb = self.e * s.strides.humans;
        for k in 0..n.dynamic_humans {
            let i = hb + (n.static_humans + k) as usize;
            let g = place::free_goal(self.rng, &self.area, self.spawn, p.human_goal_radius)
                .ok_or("a human goal")?;
            s.h_goal_x[i] = g.x;
            s.h_goal_y[i] = g.y;
            self.spawn.add_goal(g);
        }
        for k in 0..n.static_humans as usize {
            let i = hb + k;
            s.h_goal_x[i] = s.h_x[i];
            s.h_goal_y[i] = s.h_y[i];
            self.spawn.add_goal(Disc {
                x: s.h_x[i],
                y: s.h_y[i],
                r: p.human_goal_radius,
            });
        }
        let g = place::free_goal(self.rng, &self.area, self.spawn, p.goal_radius)
            .ok_or("the robot goal")?;
        s.goal_x[self.e] = g.x;
        s.goal_y[self.e] = g.y;
        self.spawn.add_goal(g);
        let gb = self.e * s.strides.groups;
        let moving = (n.group_sets[0] + n.group_sets[1]) as usize;
        for gi in gb..gb + moving {
            let g = place::free_goal(self.rng, &self.area, self.spawn, p.group_goal_radius)
                .ok_or("a group goal")?;
            s.g_goal_x[gi] = g.x;
            s.g_goal_y[gi] = g.y;
            s.g_member_goal_radius[gi] = p.group_goal_radius;
            self.spawn.add_goal(g);
            for i in hb + s.g_first[gi] as usize..hb + (s.g_first[gi] + s.g_count[gi]) as usize {
                s.h_goal_x[i] = g.x;
                s.h_goal_y[i] = g.y;
            }
        }
        // Standing groups and their members stay where they are.
        for gi in gb + moving..gb + s.n_groups[self.e] as usize {
            s.g_goal_x[gi] = s.g_x[gi];
            s.g_goal_y[gi] = s.g_y[gi];
            s.g_member_goal_radius[gi] = p.group_goal_radius;
            for i in hb + s.g_first[gi] as usize..hb + (s.g_first[gi] + s.g_count[gi]) as usize {
                s.h_goal_x[i] = s.h_x[i];
                s.h_goal_y[i] = s.h_y[i];
            }
        }
        Ok(())
    }
}

fn set_role(s: &mut StateChunk, i: usize, r: u32, group: u32, user: u32) {
    s.h_role[i] = r;
    s.h_group[i] = group;
    s.h_laptop_user[i] = user;
    s.h_forming[i] = 0;
}

fn write_laptop(s: &mut StateChunk, i: usize, x: f32, y: f32, theta: f32, user: u32) {
    s.l_x[i] = x;
    s.l_y[i] = y;
    s.l_theta[i] = theta;
    (s.l_sin[i], s.l_cos[i]) = math::sin_cos(theta);
    s.l_user[i] = user;
}
