//! Reading a state document into one environment's slots, with errors that name the path of the
//! offending value (`state.humans[3].x`) or the capacity that a snapshot exceeds.

use serde_json::Value;

use super::{ROLE_NAMES, shape_code};
use crate::error::SimError;
use crate::params::StepParams;
use crate::state::{BatchState, NONE, blocker_kind, forming, group_kind, policy, role};

/// A JSON value with the path it was reached by.
#[derive(Clone)]
pub(super) struct Reader<'a> {
    value: &'a Value,
    path: String,
}

/// The largest magnitude of a number in a document: positions, sums over an episode and
/// parameters stay orders of magnitude below, while squares and products of larger numbers in a
/// step would overflow f32.
const MAX_MAGNITUDE: f32 = 1e9;

pub(super) fn err(path: &str, what: impl std::fmt::Display) -> SimError {
    SimError::shape("state document", format!("state document: `{path}` {what}"))
}

impl<'a> Reader<'a> {
    pub(super) fn root(value: &'a Value) -> Self {
        Self {
            value,
            path: String::new(),
        }
    }

    fn child_path(&self, key: &str) -> String {
        if self.path.is_empty() {
            key.to_string()
        } else {
            format!("{}.{key}", self.path)
        }
    }

    /// The path this value was reached by (`state.humans[3]`), for error messages.
    pub(super) fn path(&self) -> &str {
        &self.path
    }

    pub(super) fn at(&self, key: &str) -> Result<Reader<'a>, SimError> {
        self.opt(key)
            .ok_or_else(|| err(&self.child_path(key), "is missing"))
    }

    pub(super) fn opt(&self, key: &str) -> Option<Reader<'a>> {
        self.value
            .get(key)
            .filter(|v| !v.is_null())
            .map(|value| Reader {
                value,
                path: self.child_path(key),
            })
    }

    pub(super) fn items(&self) -> Result<Vec<Reader<'a>>, SimError> {
        let list = self
            .value
            .as_array()
            .ok_or_else(|| err(&self.path, "must be a list"))?;
        Ok(list
            .iter()
            .enumerate()
            .map(|(i, value)| Reader {
                value,
                path: format!("{}[{i}]", self.path),
            })
            .collect())
    }

    pub(super) fn list(&self, key: &str) -> Result<Vec<Reader<'a>>, SimError> {
        match self.opt(key) {
            Some(r) => r.items(),
            None => Ok(Vec::new()),
        }
    }

    /// A number; "inf", "-inf" and "nan" strings stand for the non-finite values.
    /// A finite number of magnitude at most [`MAX_MAGNITUDE`].
    fn as_f32(&self) -> Result<f32, SimError> {
        let x = self.as_number()?;
        if !x.is_finite() {
            return Err(err(&self.path, format!("is {x}; it must be finite")));
        }
        if x.abs() > MAX_MAGNITUDE {
            return Err(err(
                &self.path,
                format!("is {x}; no quantity of a state exceeds {MAX_MAGNITUDE:e} in magnitude"),
            ));
        }
        Ok(x)
    }

    /// An angle (rad) that `math::sin_cos` takes: |θ| ≤ 2^20 rad.
    pub(super) fn angle(&self, key: &str) -> Result<f32, SimError> {
        self.at(key)?.as_angle()
    }

    /// This node as an angle (see [`Reader::angle`]).
    fn as_angle(&self) -> Result<f32, SimError> {
        let x = self.as_f32()?;
        let max = crate::math::SIN_COS_MAX_ARG;
        if x.abs() > max {
            return Err(err(
                &self.path,
                format!("is {x} rad; socnav's sine and cosine take angles up to {max} rad"),
            ));
        }
        Ok(x)
    }

    /// A finite number in `lo..=hi`; `why` says where the bounds come from.
    pub(super) fn f_in(&self, key: &str, lo: f32, hi: f32, why: &str) -> Result<f32, SimError> {
        let x = self.f(key)?;
        if !(lo..=hi).contains(&x) {
            return Err(err(
                &self.child_path(key),
                format!("is {x}; it must be in [{lo}, {hi}] ({why})"),
            ));
        }
        Ok(x)
    }

    /// A number, the strings "inf", "-inf" and "nan" included.
    fn as_number(&self) -> Result<f32, SimError> {
        match self.value {
            Value::Number(n) => n
                .as_f64()
                .map(|x| x as f32)
                .ok_or_else(|| err(&self.path, "is not a number")),
            Value::String(s) if s == "inf" => Ok(f32::INFINITY),
            Value::String(s) if s == "-inf" => Ok(f32::NEG_INFINITY),
            Value::String(s) if s == "nan" => Ok(f32::NAN),
            Value::Bool(b) => Ok(if *b { 1.0 } else { 0.0 }),
            other => Err(err(&self.path, format!("must be a number, got {other}"))),
        }
    }

    /// A finite number (m, rad, s, ... as the key says).
    pub(super) fn f(&self, key: &str) -> Result<f32, SimError> {
        self.at(key)?.as_f32()
    }

    /// A finite number or +inf: a running minimum before its first sample (`metrics.v_min`,
    /// `episode_sums.min_human_distance`, ...). Never NaN or -inf.
    pub(super) fn f_or_inf(&self, key: &str) -> Result<f32, SimError> {
        let r = self.at(key)?;
        match r.as_number()? {
            f32::INFINITY => Ok(f32::INFINITY),
            _ => r.as_f32(),
        }
    }

    pub(super) fn u(&self, key: &str) -> Result<u32, SimError> {
        self.at(key)?.as_u32()
    }

    fn as_u64(&self) -> Result<u64, SimError> {
        self.value.as_u64().ok_or_else(|| {
            err(
                &self.path,
                format!("must be an integer in 0..2^64, got {}", self.value),
            )
        })
    }

    fn as_u32(&self) -> Result<u32, SimError> {
        match self.value {
            Value::Bool(b) => Ok(u32::from(*b)),
            v => v
                .as_u64()
                .and_then(|x| u32::try_from(x).ok())
                .ok_or_else(|| {
                    err(
                        &self.path,
                        format!("must be an integer in 0..=4294967295, got {v}"),
                    )
                }),
        }
    }

    fn flag(&self, key: &str) -> Result<u32, SimError> {
        match self.opt(key) {
            Some(r) => r
                .value
                .as_bool()
                .map(u32::from)
                .ok_or_else(|| err(&r.path, "must be true or false")),
            None => Ok(0),
        }
    }

    fn text(&self, key: &str) -> Result<&'a str, SimError> {
        let r = self.at(key)?;
        r.value
            .as_str()
            .ok_or_else(|| err(&r.path, "must be a string"))
    }

    /// A list of exactly `N` numbers.
    pub(super) fn vec<const N: usize>(&self, key: &str) -> Result<[f32; N], SimError> {
        let r = self.at(key)?;
        let items = r.items()?;
        if items.len() != N {
            return Err(err(
                &r.path,
                format!("must hold {N} numbers, got {}", items.len()),
            ));
        }
        let mut out = [0.0; N];
        for (o, item) in out.iter_mut().zip(&items) {
            *o = item.as_f32()?;
        }
        Ok(out)
    }

    /// A size that socnav takes from the config: it must equal `expected` (f32 rounding aside).
    fn matches(&self, key: &str, expected: f32, config_key: &str) -> Result<(), SimError> {
        if let Some(r) = self.opt(key) {
            let v = r.as_f32()?;
            if (v - expected).abs() > 1e-5 * expected.abs().max(1.0) {
                return Err(err(
                    &r.path,
                    format!("is {v} but this batch's config has `{config_key}` = {expected}"),
                ));
            }
        }
        Ok(())
    }
}

pub(super) fn capacity(what: &str, n: usize, cap: usize, why: &str) -> Result<(), SimError> {
    if n > cap {
        return Err(SimError::shape(
            "state document",
            format!(
                "state document has {n} {what} but the batch's capacity is {cap} ({why}); make the batch from a config whose maximum counts cover it"
            ),
        ));
    }
    Ok(())
}

pub(super) fn room(
    p: &StepParams,
    r: &Reader<'_>,
    s: &mut BatchState,
    e: usize,
) -> Result<(), SimError> {
    let room = r.at("room")?;
    s.map_x[e] = room.f("map_x")?;
    s.map_y[e] = room.f("map_y")?;
    let shape = room.text("shape")?;
    s.room_shape[e] = shape_code(shape).ok_or_else(|| {
        err(
            &room.child_path("shape"),
            format!("{shape:?} is not a room shape"),
        )
    })?;
    let walls = r.list("walls")?;
    capacity(
        "walls",
        walls.len(),
        s.strides.walls,
        "room shape and corridors",
    )?;
    let wb = e * s.strides.walls;
    for (k, w) in walls.iter().enumerate() {
        w.matches("thickness", p.wall_thickness, "objects.wall_thickness")?;
        s.w_id[wb + k] = w.u("id")?;
        s.w_x[wb + k] = w.f("x")?;
        s.w_y[wb + k] = w.f("y")?;
        s.w_theta[wb + k] = w.angle("theta")?;
        (s.w_sin[wb + k], s.w_cos[wb + k]) = crate::math::sin_cos(s.w_theta[wb + k]);
        let length = w.f("length")?;
        if !(length.is_finite() && length > 0.0) {
            return Err(err(
                &w.child_path("length"),
                format!("is {length} m; a wall's length must be a positive number"),
            ));
        }
        s.w_length[wb + k] = length;
    }
    // The observation holds the walls' segments in rows sized for the config's rooms: longer
    // walls than any of them would overrun it.
    let segments: u64 = (wb..wb + walls.len())
        .map(|w| {
            u64::from(crate::room::segment_count(
                s.w_length[w],
                p.wall_segment_size,
            ))
        })
        .sum();
    capacity(
        "wall segments",
        segments as usize,
        s.strides.wall_segments,
        "the walls of the config's largest room, in `objects.wall_segment_size` pieces",
    )?;
    s.n_walls[e] = walls.len() as u32;
    let blockers = r.list("spawn_blockers")?;
    capacity(
        "spawn blockers",
        blockers.len(),
        s.strides.blockers,
        "room shape and corridors",
    )?;
    let bb = e * s.strides.blockers;
    for (k, b) in blockers.iter().enumerate() {
        s.b_kind[bb + k] = match b.text("kind")? {
            "laptop" => blocker_kind::L_BLOCK,
            "wall" => blocker_kind::DOOR,
            other => {
                return Err(err(
                    &b.child_path("kind"),
                    format!("{other:?} is not \"laptop\" or \"wall\""),
                ));
            }
        };
        s.b_x[bb + k] = b.f("x")?;
        s.b_y[bb + k] = b.f("y")?;
        s.b_theta[bb + k] = b.angle("theta")?;
        s.b_length[bb + k] = b.f("length")?;
        s.b_width[bb + k] = b.f("width")?;
    }
    s.n_blockers[e] = blockers.len() as u32;
    Ok(())
}

pub(super) fn human_params(
    p: &StepParams,
    r: &Reader<'_>,
    s: &mut BatchState,
    e: usize,
) -> Result<(), SimError> {
    s.orca_neighbor_dist[e] = r.f("orca_neighborDist")?;
    // RVO2 divides by the horizons: a generated one is at least 0.1 s (docs/fidelity.md).
    for (key, column) in [
        ("orca_timeHorizon", &mut s.orca_time_horizon),
        ("orca_timeHorizonObst", &mut s.orca_time_horizon_obst),
    ] {
        column[e] = r.f_in(key, 0.1, 1e9, "ORCA divides by its time horizons")?;
    }
    s.orca_max_speed[e] = r.f_in(
        "orca_maxSpeed",
        0.0,
        max_walker_speed(p),
        WALKER_SPEED_BOUND,
    )?;
    // The force's range: drawn as |0.05 + 0.01 N| m, and a divisor of the surface gap in an
    // exponential, where a negative one makes the force of a nearby obstacle overflow.
    s.sfm_r0[e] = r.f_in(
        "sfm_r0",
        f32::MIN_POSITIVE,
        1e9,
        "the social force's range is positive",
    )?;
    // The interaction's scale B = gamma |D| divides the pair's distance in exp(-d / B): drawn as
    // 0.25 + 0.01 N, and a negative one makes the force of a distant pedestrian overflow.
    s.sfm_gamma[e] = r.f_in(
        "sfm_gamma",
        f32::MIN_POSITIVE,
        1e9,
        "the social force's interaction scale is positive",
    )?;
    s.sfm_n[e] = r.f("sfm_n")?;
    s.sfm_n_prime[e] = r.f("sfm_n_prime")?;
    s.sfm_lambda[e] = r.f("sfm_lambda")?;
    Ok(())
}

pub(super) fn snapshot(
    p: &StepParams,
    st: &Reader<'_>,
    s: &mut BatchState,
    e: usize,
) -> Result<(), SimError> {
    s.tick[e] = st.u("tick")?;
    robot(p, &st.at("robot")?, s, e)?;
    shadow(p, &st.at("shadow_robot")?, s, e)?;
    let ids = humans(p, st, s, e)?;
    let laptop_ids = objects(p, st, s, e)?;
    groups(st, p, s, e, &ids)?;
    laptop_users(st, s, e, &ids, &laptop_ids)?;
    forming(st, s, e, &ids, &laptop_ids)?;
    group_noise(st, s, e, &ids)?;
    metrics(&st.at("metrics")?, s, e)?;
    reward_state(&st.at("reward_state")?, s, e)
}

fn robot(p: &StepParams, r: &Reader<'_>, s: &mut BatchState, e: usize) -> Result<(), SimError> {
    r.matches("radius", p.robot_radius, "robot.radius")?;
    r.matches("goal_radius", p.goal_radius, "robot.goal_radius")?;
    s.robot_x[e] = r.f("x")?;
    s.robot_y[e] = r.f("y")?;
    s.robot_theta[e] = r.angle("theta")?;
    [s.goal_x[e], s.goal_y[e]] = r.vec::<2>("goal")?;
    [s.robot_vx[e], s.robot_vy[e], s.robot_w[e]] = robot_velocity(p, r)?;
    Ok(())
}

/// Why a walker's speed limit is bounded (as `config::validate` bounds `human.max_speed`).
const WALKER_SPEED_BOUND: &str = "a step moves a walker at most its diameter";

/// Why a human's current speed is bounded by the document's magnitude only, not by its limit:
/// the step itself makes faster ones. RVO2's f32 linear programs can fling a walker or a moving
/// group far beyond its limit (`state::invariants::human_in_room`, docs/fidelity.md), and a
/// moving group's members add the group's noise to its velocity. The next step recomputes every
/// walker's velocity (ORCA from its preferred velocity, the social force capped at the limit),
/// so a loaded speed moves nothing by itself.
const FLUNG_SPEED: &str = "a speed is not negative; the step may make one far beyond the limit";

/// The fastest a walker may go (m/s): one diameter per step.
fn max_walker_speed(p: &StepParams) -> f32 {
    2.0 * p.human_radius / p.dt
}

/// A robot's `vel` [vx, vy, ω] (m/s, m/s, rad/s), each within the robot's limits (a
/// velocity is always a clipped command).
fn robot_velocity(p: &StepParams, r: &Reader<'_>) -> Result<[f32; 3], SimError> {
    let vel = r.vec::<3>("vel")?;
    let limits = [p.robot_max_speed, p.robot_max_speed, p.robot_max_rotation];
    for (k, (v, limit)) in vel.iter().zip(limits).enumerate() {
        // f32 rounding of a limit that was clipped against.
        let limit = limit * (1.0 + 1e-5);
        if v.abs() > limit {
            return Err(err(
                &format!("{}[{k}]", r.child_path("vel")),
                format!(
                    "is {v}; the robot's limits (`robot.max_speed`, `robot.max_rotation`) bound it to ±{limit}"
                ),
            ));
        }
    }
    Ok(vel)
}

fn shadow(p: &StepParams, r: &Reader<'_>, s: &mut BatchState, e: usize) -> Result<(), SimError> {
    s.shadow_x[e] = r.f("x")?;
    s.shadow_y[e] = r.f("y")?;
    s.shadow_theta[e] = r.angle("theta")?;
    [s.shadow_vx[e], s.shadow_vy[e], s.shadow_w[e]] = robot_velocity(p, r)?;
    s.shadow_collided[e] = r.flag("collided")?;
    s.shadow_reached[e] = r.flag("reached")?;
    s.shadow_reach_tick[e] = if r.opt("reach_tick").is_some() {
        r.u("reach_tick")?
    } else {
        0
    };
    s.shadow_path_length[e] = r.f("path_length")?;
    Ok(())
}

/// Humans in observation order; returns their ids by slot.
fn humans(
    p: &StepParams,
    st: &Reader<'_>,
    s: &mut BatchState,
    e: usize,
) -> Result<Vec<u32>, SimError> {
    let list = st.list("humans")?;
    capacity(
        "humans",
        list.len(),
        s.strides.humans,
        "the configured maximum humans of every role",
    )?;
    let hb = e * s.strides.humans;
    let mut ids = Vec::with_capacity(list.len());
    let (mut n_static, mut n_dynamic, mut last_rank) = (0u32, 0u32, 0u32);
    for (k, h) in list.iter().enumerate() {
        let i = hb + k;
        h.matches("radius", p.human_radius, "human.diameter / 2")?;
        let role_name = h.text("role")?;
        let r = ROLE_NAMES
            .iter()
            .position(|n| *n == role_name)
            .ok_or_else(|| {
                err(
                    &h.child_path("role"),
                    format!("{role_name:?} is not a human role"),
                )
            })? as u32;
        // Observation order: static, dynamic, group members (any group kind), laptop users.
        let rank = match r {
            role::STATIC => 0,
            role::DYNAMIC => 1,
            role::MOVING_GROUP | role::STANDING_GROUP => 2,
            _ => 3,
        };
        if rank < last_rank {
            return Err(err(
                &h.path,
                "is out of observation order (lone static, lone walking, group members, laptop users)",
            ));
        }
        last_rank = rank;
        n_static += u32::from(r == role::STATIC);
        n_dynamic += u32::from(r == role::DYNAMIC);
        ids.push(h.u("id")?);
        s.h_id[i] = ids[k];
        s.h_x[i] = h.f("x")?;
        s.h_y[i] = h.f("y")?;
        s.h_theta[i] = h.angle("theta")?;
        s.h_speed[i] = h.f_in("speed", 0.0, MAX_MAGNITUDE, FLUNG_SPEED)?;
        [s.h_goal_x[i], s.h_goal_y[i]] = if h.opt("goal").is_some() {
            h.vec::<2>("goal")?
        } else {
            [s.h_x[i], s.h_y[i]]
        };
        s.h_policy[i] = match h.text("policy")? {
            "orca" => policy::ORCA,
            "sfm" => policy::SFM,
            other => {
                return Err(err(
                    &h.child_path("policy"),
                    format!("{other:?} is not \"orca\" or \"sfm\""),
                ));
            }
        };
        s.h_role[i] = r;
        s.h_group[i] = if h.opt("group").is_some() {
            h.u("group")?
        } else {
            NONE
        };
        s.h_laptop_user[i] = if h.opt("hl").is_some() {
            h.u("hl")?
        } else {
            NONE
        };
        s.h_forming[i] = if h.flag("forming_crowd")? != 0 {
            forming::CROWD
        } else if h.flag("forming_hl")? != 0 {
            forming::LAPTOP
        } else {
            forming::NONE
        };
    }
    s.n_humans[e] = list.len() as u32;
    s.n_static[e] = n_static;
    s.n_dynamic[e] = n_dynamic;
    Ok(ids)
}

/// Laptops, tables and plants; returns the laptops' ids by slot.
fn objects(
    p: &StepParams,
    st: &Reader<'_>,
    s: &mut BatchState,
    e: usize,
) -> Result<Vec<u32>, SimError> {
    let laptops = st.list("laptops")?;
    capacity(
        "laptops",
        laptops.len(),
        s.strides.laptops,
        "counts.laptops plus laptop users",
    )?;
    let lb = e * s.strides.laptops;
    let mut ids = Vec::with_capacity(laptops.len());
    for (k, l) in laptops.iter().enumerate() {
        l.matches("length", p.laptop_length, "objects.laptop_length")?;
        l.matches("width", p.laptop_width, "objects.laptop_width")?;
        ids.push(l.u("id")?);
        s.l_id[lb + k] = ids[k];
        s.l_x[lb + k] = l.f("x")?;
        s.l_y[lb + k] = l.f("y")?;
        s.l_theta[lb + k] = l.angle("theta")?;
        (s.l_sin[lb + k], s.l_cos[lb + k]) = crate::math::sin_cos(s.l_theta[lb + k]);
        s.l_user[lb + k] = if l.opt("hl").is_some() {
            l.u("hl")?
        } else {
            NONE
        };
    }
    s.n_laptops[e] = laptops.len() as u32;
    let tables = st.list("tables")?;
    capacity("tables", tables.len(), s.strides.tables, "counts.tables")?;
    let tb = e * s.strides.tables;
    for (k, t) in tables.iter().enumerate() {
        t.matches("length", p.table_length, "objects.table_length")?;
        t.matches("width", p.table_width, "objects.table_width")?;
        s.t_id[tb + k] = t.u("id")?;
        s.t_x[tb + k] = t.f("x")?;
        s.t_y[tb + k] = t.f("y")?;
        s.t_theta[tb + k] = t.angle("theta")?;
        (s.t_sin[tb + k], s.t_cos[tb + k]) = crate::math::sin_cos(s.t_theta[tb + k]);
    }
    s.n_tables[e] = tables.len() as u32;
    let plants = st.list("plants")?;
    capacity("plants", plants.len(), s.strides.plants, "counts.plants")?;
    let pb = e * s.strides.plants;
    for (k, pl) in plants.iter().enumerate() {
        pl.matches("radius", p.plant_radius, "objects.plant_radius")?;
        s.p_id[pb + k] = pl.u("id")?;
        s.p_x[pb + k] = pl.f("x")?;
        s.p_y[pb + k] = pl.f("y")?;
    }
    s.n_plants[e] = plants.len() as u32;
    Ok(ids)
}

fn slot_of(ids: &[u32], id: u32, path: &str) -> Result<usize, SimError> {
    ids.iter()
        .position(|&x| x == id)
        .ok_or_else(|| err(path, format!("names id {id}, which is not in the list")))
}

fn groups(
    st: &Reader<'_>,
    p: &StepParams,
    s: &mut BatchState,
    e: usize,
    ids: &[u32],
) -> Result<(), SimError> {
    let list = st.list("groups")?;
    capacity(
        "groups",
        list.len(),
        s.strides.groups,
        "the configured maximum groups, or humans / 2 with crowd formation",
    )?;
    let gb = e * s.strides.groups;
    let hb = e * s.strides.humans;
    for (k, g) in list.iter().enumerate() {
        let members = g.at("members")?;
        let items = members.items()?;
        if items.is_empty() {
            return Err(err(&members.path, "must list at least one member"));
        }
        // A group's members fill pair rows of the observation sized by the config's group size.
        capacity(
            "members of a group",
            items.len(),
            s.strides.group_size,
            "counts.group_size",
        )?;
        let mut first = 0;
        for (m, item) in items.iter().enumerate() {
            let id = item
                .value
                .as_u64()
                .and_then(|id| u32::try_from(id).ok())
                .ok_or_else(|| err(&item.path, "must be a human id"))?;
            let slot = slot_of(ids, id, &item.path)?;
            if m == 0 {
                first = slot;
            } else if slot != first + m {
                return Err(err(
                    &members.path,
                    "must list consecutive humans of the `humans` list, in order",
                ));
            }
            s.h_group[hb + slot] = k as u32;
        }
        let moving = match g.text("kind")? {
            "moving" => true,
            "standing" => false,
            other => {
                return Err(err(
                    &g.child_path("kind"),
                    format!("{other:?} is not \"moving\" or \"standing\""),
                ));
            }
        };
        s.g_kind[gb + k] = if moving {
            group_kind::MOVING
        } else {
            group_kind::STANDING
        };
        s.g_dispersable[gb + k] = g.flag("dispersable")?;
        s.g_first[gb + k] = first as u32;
        s.g_count[gb + k] = items.len() as u32;
        [s.g_x[gb + k], s.g_y[gb + k]] = g.vec::<2>("centre")?;
        [s.g_goal_x[gb + k], s.g_goal_y[gb + k]] = if g.opt("goal").is_some() {
            g.vec::<2>("goal")?
        } else {
            [s.g_x[gb + k], s.g_y[gb + k]]
        };
        s.g_vx[gb + k] = 0.0;
        s.g_vy[gb + k] = 0.0;
        s.g_member_goal_radius[gb + k] =
            member_goal_radius(st, p, &g.child_path("members"), first, items.len())?;
    }
    s.n_groups[e] = list.len() as u32;
    Ok(())
}

/// The goal radius (m) a group's members test their arrival with: their `goal_radius` in the
/// document (0.1.1 records each human's own), which must be the same for every member (every
/// group 0.1.1 makes has one value); the group goal radius when the members do not say.
fn member_goal_radius(
    st: &Reader<'_>,
    p: &StepParams,
    members_path: &str,
    first: usize,
    n: usize,
) -> Result<f32, SimError> {
    let humans = st.list("humans")?;
    let mut radius = None;
    for h in humans.iter().skip(first).take(n) {
        let Some(r) = h.opt("goal_radius") else {
            continue;
        };
        let value = r.as_f32()?;
        if !(value.is_finite() && value > 0.0) {
            return Err(err(
                &r.path,
                format!("must be a positive distance (m), got {value}"),
            ));
        }
        match radius {
            Some(first_value) if first_value != value => {
                return Err(err(
                    members_path,
                    format!(
                        "name humans with different goal radii ({first_value} and {value}); a group's members share one"
                    ),
                ));
            }
            _ => radius = Some(value),
        }
    }
    Ok(radius.unwrap_or(p.group_goal_radius))
}

fn laptop_users(
    st: &Reader<'_>,
    s: &mut BatchState,
    e: usize,
    ids: &[u32],
    laptop_ids: &[u32],
) -> Result<(), SimError> {
    let list = st.list("hl_interactions")?;
    capacity(
        "laptop users",
        list.len(),
        s.strides.laptop_users,
        "counts.laptop_users, or all laptops with laptop-use formation",
    )?;
    let ub = e * s.strides.laptop_users;
    for (k, u) in list.iter().enumerate() {
        s.lu_human[ub + k] = slot_of(ids, u.u("human")?, &u.child_path("human"))? as u32;
        s.lu_laptop[ub + k] = slot_of(laptop_ids, u.u("laptop")?, &u.child_path("laptop"))? as u32;
        s.lu_dispersable[ub + k] = u.flag("dispersable")?;
    }
    s.n_laptop_users[e] = list.len() as u32;
    Ok(())
}

/// A formation at `r` ends in a new one of `n` `what` (a group, a laptop user): refused when
/// the environment's `cap` are all taken, where the step would have nowhere to put it.
fn slot_to_form(r: &Reader<'_>, n: u32, cap: usize, what: &str) -> Result<(), SimError> {
    if n as usize >= cap {
        return Err(err(
            r.path(),
            format!("cannot form: the {n} {what} already fill the config's capacity"),
        ));
    }
    Ok(())
}

fn forming(
    st: &Reader<'_>,
    s: &mut BatchState,
    e: usize,
    ids: &[u32],
    laptop_ids: &[u32],
) -> Result<(), SimError> {
    let mut env = s.env_chunk(e);
    crate::systems::formation::clear_crowd_formation(&mut env, 0);
    crate::systems::formation::clear_laptop_formation(&mut env, 0);
    if let Some(cf) = st.opt("crowd_forming") {
        let slots = cf.at("slots")?.items()?;
        capacity(
            "forming crowd slots",
            slots.len(),
            s.strides.group_size,
            "counts.group_size",
        )?;
        if slots.is_empty() {
            return Err(err(&cf.child_path("slots"), "must hold at least one slot"));
        }
        // The crowd becomes a group when it has formed.
        slot_to_form(&cf, s.n_groups[e], s.strides.groups, "groups")?;
        let sb = e * s.strides.group_size;
        for (k, slot) in slots.iter().enumerate() {
            let items = slot.items()?;
            if items.len() != 3 {
                return Err(err(&slot.path, "must be [x, y, theta]"));
            }
            s.cf_slot_x[sb + k] = items[0].as_f32()?;
            s.cf_slot_y[sb + k] = items[1].as_f32()?;
            s.cf_slot_theta[sb + k] = items[2].as_angle()?;
        }
        let slot_map = cf.at("slot_of")?;
        let entries = slot_map
            .value
            .as_object()
            .ok_or_else(|| err(&slot_map.path, "must be an object"))?;
        // Every slot has its walker, one each.
        if entries.len() != slots.len() {
            return Err(err(
                &slot_map.path,
                format!(
                    "names {} walkers for {} slots; each slot needs one",
                    entries.len(),
                    slots.len()
                ),
            ));
        }
        let mut taken = vec![false; slots.len()];
        for (id, k) in entries {
            let id: u32 = id
                .parse()
                .map_err(|_| err(&slot_map.path, format!("key {id:?} is not a human id")))?;
            let k = k
                .as_u64()
                .ok_or_else(|| err(&slot_map.path, "values must be slot indices"))?
                as usize;
            if k >= slots.len() {
                return Err(err(
                    &slot_map.path,
                    format!("slot {k} out of range 0..{}", slots.len()),
                ));
            }
            if std::mem::replace(&mut taken[k], true) {
                return Err(err(&slot_map.path, format!("names slot {k} twice")));
            }
            s.cf_human[sb + k] = slot_of(ids, id, &slot_map.path)? as u32;
        }
        [s.cf_x[e], s.cf_y[e]] = cf.vec::<2>("centre")?;
        s.cf_close_steps[e] = cf.u("almost_formed_count")?;
        s.cf_count[e] = slots.len() as u32;
        s.cf_active[e] = 1;
    }
    if let Some(lf) = st.opt("hl_forming") {
        // The walker becomes a laptop user when it reaches the seat.
        slot_to_form(
            &lf,
            s.n_laptop_users[e],
            s.strides.laptop_users,
            "laptop users",
        )?;
        s.lf_human[e] = slot_of(ids, lf.u("human")?, &lf.child_path("human"))? as u32;
        s.lf_laptop[e] = slot_of(laptop_ids, lf.u("laptop")?, &lf.child_path("laptop"))? as u32;
        [s.lf_seat_x[e], s.lf_seat_y[e], _] = lf.vec::<3>("seat")?;
        s.lf_seat_theta[e] = lf.at("seat")?.items()?[2].as_angle()?;
        s.lf_active[e] = 1;
    }
    Ok(())
}

/// Replay: the group velocity noise (m/s) the next step adds to each listed member
/// (`group_noise`: `[[member_id, noise_x, noise_y], ...]`, as the golden episodes recorded it);
/// members not listed get none.
fn group_noise(st: &Reader<'_>, s: &mut BatchState, e: usize, ids: &[u32]) -> Result<(), SimError> {
    let hb = e * s.strides.humans;
    s.h_noise_x[hb..hb + s.strides.humans].fill(0.0);
    s.h_noise_y[hb..hb + s.strides.humans].fill(0.0);
    for entry in st.list("group_noise")? {
        let items = entry.items()?;
        if items.len() != 3 {
            return Err(err(&entry.path, "must be [member_id, noise_x, noise_y]"));
        }
        let id = items[0].as_u32()?;
        let i = hb + slot_of(ids, id, &entry.path)?;
        s.h_noise_x[i] = items[1].as_f32()?;
        s.h_noise_y[i] = items[2].as_f32()?;
    }
    Ok(())
}

fn metrics(m: &Reader<'_>, s: &mut BatchState, e: usize) -> Result<(), SimError> {
    s.m_prev_goal_dist[e] = m.f("prev_goal_distance")?;
    s.m_failure_to_progress[e] = m.u("failure_to_progress")?;
    s.m_stalled_time[e] = m.f("stalled_time")?;
    s.m_path_length[e] = m.f("path_length")?;
    s.m_v_min[e] = m.f_or_inf("v_min")?;
    s.m_v_max[e] = m.f("v_max")?;
    s.m_v_avg[e] = m.f("v_avg")?;
    [s.m_prev_vx[e], s.m_prev_vy[e]] = m.vec::<2>("prev_vel")?;
    s.m_a_min[e] = m.f_or_inf("a_min")?;
    s.m_a_max[e] = m.f("a_max")?;
    s.m_a_avg[e] = m.f("a_avg")?;
    [s.m_prev_ax[e], s.m_prev_ay[e]] = m.vec::<2>("prev_a")?;
    s.m_j_min[e] = m.f_or_inf("jerk_min")?;
    s.m_j_max[e] = m.f("jerk_max")?;
    s.m_j_avg[e] = m.f("jerk_avg")?;
    s.m_compliant[e] = m.u("compliant_count")?;
    Ok(())
}

fn reward_state(r: &Reader<'_>, s: &mut BatchState, e: usize) -> Result<(), SimError> {
    match r.opt("prev_distance") {
        Some(d) => {
            s.r_prev_dist[e] = d.as_f32()?;
            s.r_has_prev[e] = 1;
        }
        None => {
            s.r_prev_dist[e] = 0.0;
            s.r_has_prev[e] = 0;
        }
    }
    let info = r.at("info")?;
    s.r_discomfort_sngnn[e] = info.f("DISCOMFORT_SNGNN")?;
    s.r_discomfort_dsrnn[e] = info.f("DISCOMFORT_DSRNN")?;
    s.r_distance[e] = info.f("distance_reward")?;
    s.r_alive[e] = info.f("alive_reward")?;
    s.r_sngnn[e] = info.f("sngnn_reward")?;
    Ok(())
}

pub(super) fn extras(x: &Reader<'_>, s: &mut BatchState, e: usize) -> Result<(), SimError> {
    // Documents written before episode seeds existed lack them: the environment keeps its own.
    if let Some(seed) = x.opt("next_seed") {
        s.set_next_seed(e, seed.as_u64()?);
    }
    if let Some(seed) = x.opt("seed") {
        (s.seed_lo[e], s.seed_hi[e]) = crate::seeds::seed_words(seed.as_u64()?);
    }
    s.episode[e] = x.u("episode")?;
    s.done[e] = x.flag("done")?;
    s.pending_reset[e] = x.flag("pending_reset")?;
    if let Some(sums) = x.opt("episode_sums") {
        s.ep_return[e] = sums.f("return")?;
        s.ep_min_human_dist[e] = sums.f_or_inf("min_human_distance")?;
        s.ep_min_obstacle_dist[e] = sums.f_or_inf("min_obstacle_distance")?;
        s.ep_sum_avg_obstacle_dist[e] = sums.f("sum_average_obstacle_distance")?;
        s.ep_sum_ttc[e] = sums.f("sum_time_to_collision")?;
        s.ep_sum_discomfort_dsrnn[e] = sums.f("sum_discomfort_dsrnn")?;
        s.ep_sum_sngnn[e] = sums.f("sum_sngnn_reward")?;
    }
    Ok(())
}
