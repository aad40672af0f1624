//! One environment's state as a self-contained JSON document (docs/spec.md, fidelity): the static
//! part of a golden episode header (`room`, `walls`, `spawn_blockers`, `human_params`, `counts`)
//! plus a golden state snapshot (`state`, format in the golden README section 5), plus a
//! `socnav` object with what 0.1.1 does not have (episode counter, done flag, per-episode sums).
//! Batches with the SNGNN reward add the frame history to the snapshot (`state.sngnn_frames`,
//! module `sngnn`).
//! Tests synchronise with the reference through it; users load fixed scenarios with it.
//!
//! Numbers are rounded to f32 on the way in; non-finite numbers are the strings "inf", "-inf",
//! "nan" (as in the golden files). A loaded number must be finite (a running minimum may be
//! "inf") and at most 1e9 in magnitude, a speed within what the config allows, the walls no
//! longer than the observation's rows for the config hold, and the loaded state must keep the
//! invariants (`state::invariants`). Sizes that are config constants in socnav (radii, table and
//! laptop sizes, wall thickness) must match the batch's config. A snapshot larger than the
//! batch's capacities is an error naming the capacity.
//!
//! The module sits above the stages, not in `state`: loading a document recomputes what the stages
//! derive (list positions, episode sums, formations, the robot's world velocity, the SNGNN
//! history) with the stages' own code.

use serde_json::{Map, Value, json};

use crate::error::SimError;
use crate::math;
use crate::params::StepParams;
use crate::state::{BatchState, NONE, blocker_kind, forming, group_kind, policy, role, room_shape};

mod read;
mod sngnn;

use read::Reader;

/// Format tag of documents written by [`export`].
pub const FORMAT: &str = "socnav-state/1";

fn num(x: f32) -> Value {
    if x.is_finite() {
        json!(x as f64)
    } else if x.is_nan() {
        json!("nan")
    } else if x > 0.0 {
        json!("inf")
    } else {
        json!("-inf")
    }
}

fn opt_index(i: u32) -> Value {
    if i == NONE { Value::Null } else { json!(i) }
}

const ROLE_NAMES: [&str; 5] = ["static", "dynamic", "moving_group", "standing_group", "hl"];
const SHAPE_NAMES: [&str; 4] = ["square", "rectangle", "L", "no-walls"];

/// Environment `e` of `s` as a document.
pub fn export(p: &StepParams, s: &BatchState, e: usize) -> Value {
    let c = &s.strides;
    let wb = e * c.walls;
    let walls: Vec<Value> = (wb..wb + s.n_walls[e] as usize)
        .map(|w| {
            json!({"id": s.w_id[w], "x": num(s.w_x[w]), "y": num(s.w_y[w]), "theta": num(s.w_theta[w]),
                   "length": num(s.w_length[w]), "thickness": num(p.wall_thickness)})
        })
        .collect();
    let bb = e * c.blockers;
    let blockers: Vec<Value> = (bb..bb + s.n_blockers[e] as usize)
        .map(|b| {
            let kind = if s.b_kind[b] == blocker_kind::L_BLOCK {
                "laptop"
            } else {
                "wall"
            };
            json!({"kind": kind, "x": num(s.b_x[b]), "y": num(s.b_y[b]), "theta": num(s.b_theta[b]),
                   "length": num(s.b_length[b]), "width": num(s.b_width[b])})
        })
        .collect();
    json!({
        "format": FORMAT,
        "room": {"map_x": num(s.map_x[e]), "map_y": num(s.map_y[e]),
                 "shape": SHAPE_NAMES[s.room_shape[e] as usize]},
        "walls": walls,
        "spawn_blockers": blockers,
        "human_params": {
            "orca_neighborDist": num(s.orca_neighbor_dist[e]), "orca_timeHorizon": num(s.orca_time_horizon[e]),
            "orca_timeHorizonObst": num(s.orca_time_horizon_obst[e]), "orca_maxSpeed": num(s.orca_max_speed[e]),
            "sfm_r0": num(s.sfm_r0[e]), "sfm_gamma": num(s.sfm_gamma[e]), "sfm_n": num(s.sfm_n[e]),
            "sfm_n_prime": num(s.sfm_n_prime[e]), "sfm_lambda": num(s.sfm_lambda[e]),
        },
        "counts": {"total_humans": s.n_humans[e]},
        "state": export_snapshot(p, s, e),
        "socnav": {
            "episode": s.episode[e], "seed": s.episode_seed(e), "next_seed": s.next_seed(e),
            "done": s.done[e] != 0, "pending_reset": s.pending_reset[e] != 0,
            "episode_sums": {
                "return": num(s.ep_return[e]), "min_human_distance": num(s.ep_min_human_dist[e]),
                "min_obstacle_distance": num(s.ep_min_obstacle_dist[e]),
                "sum_average_obstacle_distance": num(s.ep_sum_avg_obstacle_dist[e]),
                "sum_time_to_collision": num(s.ep_sum_ttc[e]),
                "sum_discomfort_dsrnn": num(s.ep_sum_discomfort_dsrnn[e]), "sum_sngnn_reward": num(s.ep_sum_sngnn[e]),
            },
        },
    })
}

fn export_snapshot(p: &StepParams, s: &BatchState, e: usize) -> Value {
    let c = &s.strides;
    let hb = e * c.humans;
    let mut goals = Map::new();
    goals.insert(
        "0".into(),
        json!([num(s.goal_x[e]), num(s.goal_y[e]), num(p.goal_radius)]),
    );
    let humans: Vec<Value> = (0..s.n_humans[e] as usize)
        .map(|k| {
            let i = hb + k;
            let r = s.h_role[i];
            let group_goal = r == role::MOVING_GROUP;
            // Every human has a goal: spawned laptop users and standing-group members their own
            // position, formed ones the seat or slot they walked to (0.1.1 keeps it).
            let goal = json!([num(s.h_goal_x[i]), num(s.h_goal_y[i])]);
            // The goal registry holds a moving group's goal disc with the group goal radius;
            // a member's own arrival test uses its group's member goal radius.
            let registry_radius = if group_goal {
                p.group_goal_radius
            } else {
                p.human_goal_radius
            };
            if r != role::LAPTOP_USER && r != role::STANDING_GROUP {
                goals.insert(
                    s.h_id[i].to_string(),
                    json!([goal[0], goal[1], num(registry_radius)]),
                );
            }
            let goal_radius = match r {
                role::LAPTOP_USER => Value::Null,
                _ if s.h_group[i] != NONE => {
                    num(s.g_member_goal_radius[e * c.groups + s.h_group[i] as usize])
                }
                _ => num(p.human_goal_radius),
            };
            let mut h = json!({
                "id": s.h_id[i], "x": num(s.h_x[i]), "y": num(s.h_y[i]), "theta": num(s.h_theta[i]),
                "speed": num(s.h_speed[i]), "radius": num(p.human_radius), "goal": goal,
                "goal_radius": goal_radius,
                "policy": if s.h_policy[i] == policy::ORCA { "orca" } else { "sfm" },
                "role": ROLE_NAMES[r as usize],
            });
            if s.h_group[i] != NONE {
                h["group"] = json!(s.h_group[i]);
            }
            if s.h_laptop_user[i] != NONE {
                h["hl"] = json!(s.h_laptop_user[i]);
            }
            match s.h_forming[i] {
                forming::CROWD => h["forming_crowd"] = json!(true),
                forming::LAPTOP => h["forming_hl"] = json!(true),
                _ => {}
            }
            h
        })
        .collect();
    let gb = e * c.groups;
    let groups: Vec<Value> = (gb..gb + s.n_groups[e] as usize)
        .map(|g| {
            let moving = s.g_kind[g] == group_kind::MOVING;
            let first = hb + s.g_first[g] as usize;
            let members: Vec<u32> = (first..first + s.g_count[g] as usize).map(|i| s.h_id[i]).collect();
            json!({
                "kind": if moving { "moving" } else { "standing" }, "dispersable": s.g_dispersable[g] != 0,
                "members": members, "centre": [num(s.g_x[g]), num(s.g_y[g])],
                // A standing group's goal: its centre when spawned, the old goal when it stopped.
                "goal": [num(s.g_goal_x[g]), num(s.g_goal_y[g])],
                "goal_radius": num(p.group_goal_radius), "radius": num(p.group_radius), "noise": num(p.group_noise_std),
            })
        })
        .collect();
    let lb = e * c.laptops;
    let ub = e * c.laptop_users;
    let users: Vec<Value> = (ub..ub + s.n_laptop_users[e] as usize)
        .map(|u| {
            let h = hb + s.lu_human[u] as usize;
            let l = lb + s.lu_laptop[u] as usize;
            json!({"human": s.h_id[h], "laptop": s.l_id[l], "dispersable": s.lu_dispersable[u] != 0,
                   "centre": [num(0.5 * (s.h_x[h] + s.l_x[l])), num(0.5 * (s.h_y[h] + s.l_y[l]))],
                   "distance": num(p.laptop_width + p.human_laptop_distance)})
        })
        .collect();
    let laptops: Vec<Value> = (lb..lb + s.n_laptops[e] as usize)
        .map(|l| {
            json!({"id": s.l_id[l], "x": num(s.l_x[l]), "y": num(s.l_y[l]), "theta": num(s.l_theta[l]),
                   "length": num(p.laptop_length), "width": num(p.laptop_width), "hl": opt_index(s.l_user[l])})
        })
        .collect();
    let tb = e * c.tables;
    let tables: Vec<Value> = (tb..tb + s.n_tables[e] as usize)
        .map(|t| {
            json!({"id": s.t_id[t], "x": num(s.t_x[t]), "y": num(s.t_y[t]), "theta": num(s.t_theta[t]),
                   "length": num(p.table_length), "width": num(p.table_width)})
        })
        .collect();
    let pb = e * c.plants;
    let plants: Vec<Value> = (pb..pb + s.n_plants[e] as usize)
        .map(|i| json!({"id": s.p_id[i], "x": num(s.p_x[i]), "y": num(s.p_y[i]), "radius": num(p.plant_radius)}))
        .collect();
    let mut snapshot = json!({
        "tick": s.tick[e],
        "robot": {"x": num(s.robot_x[e]), "y": num(s.robot_y[e]), "theta": num(s.robot_theta[e]),
                  "radius": num(p.robot_radius), "goal": [num(s.goal_x[e]), num(s.goal_y[e])],
                  "goal_radius": num(p.goal_radius), "vel": [num(s.robot_vx[e]), num(s.robot_vy[e]), num(s.robot_w[e])]},
        "shadow_robot": {"x": num(s.shadow_x[e]), "y": num(s.shadow_y[e]), "theta": num(s.shadow_theta[e]),
                         "vel": [num(s.shadow_vx[e]), num(s.shadow_vy[e]), num(s.shadow_w[e])],
                         "collided": s.shadow_collided[e] != 0, "reached": s.shadow_reached[e] != 0,
                         "reach_tick": if s.shadow_reached[e] != 0 { json!(s.shadow_reach_tick[e]) } else { Value::Null },
                         "path_length": num(s.shadow_path_length[e])},
        "humans": humans,
        "groups": groups,
        "hl_interactions": users,
        "laptops": laptops,
        "tables": tables,
        "plants": plants,
        "crowd_forming": export_crowd_forming(s, e),
        "hl_forming": if s.lf_active[e] != 0 {
            json!({"human": s.h_id[hb + s.lf_human[e] as usize], "laptop": s.l_id[lb + s.lf_laptop[e] as usize],
                   "seat": [num(s.lf_seat_x[e]), num(s.lf_seat_y[e]), num(s.lf_seat_theta[e])]})
        } else { Value::Null },
        "metrics": {
            "prev_goal_distance": num(s.m_prev_goal_dist[e]), "failure_to_progress": s.m_failure_to_progress[e],
            "stalled_time": num(s.m_stalled_time[e]), "path_length": num(s.m_path_length[e]),
            "v_min": num(s.m_v_min[e]), "v_max": num(s.m_v_max[e]), "v_avg": num(s.m_v_avg[e]),
            "prev_vel": [num(s.m_prev_vx[e]), num(s.m_prev_vy[e])],
            "a_min": num(s.m_a_min[e]), "a_max": num(s.m_a_max[e]), "a_avg": num(s.m_a_avg[e]),
            "prev_a": [num(s.m_prev_ax[e]), num(s.m_prev_ay[e])],
            "jerk_min": num(s.m_j_min[e]), "jerk_max": num(s.m_j_max[e]), "jerk_avg": num(s.m_j_avg[e]),
            "compliant_count": s.m_compliant[e],
        },
        "reward_state": {
            "prev_distance": if s.r_has_prev[e] != 0 { num(s.r_prev_dist[e]) } else { Value::Null },
            "info": {"DISCOMFORT_SNGNN": num(s.r_discomfort_sngnn[e]), "DISCOMFORT_DSRNN": num(s.r_discomfort_dsrnn[e]),
                     "distance_reward": num(s.r_distance[e]), "alive_reward": num(s.r_alive[e]),
                     "sngnn_reward": num(s.r_sngnn[e])},
        },
        "goals": Value::Object(goals),
    });
    if s.strides.frames > 0 {
        snapshot["sngnn_frames"] = sngnn::export(p, s, e);
    }
    snapshot
}

fn export_crowd_forming(s: &BatchState, e: usize) -> Value {
    if s.cf_active[e] == 0 {
        return Value::Null;
    }
    let c = &s.strides;
    let hb = e * c.humans;
    let sb = e * c.group_size;
    let n = s.cf_count[e] as usize;
    let mut slot_of = Map::new();
    let humans: Vec<u32> = (0..n)
        .map(|k| {
            let id = s.h_id[hb + s.cf_human[sb + k] as usize];
            slot_of.insert(id.to_string(), json!(k));
            id
        })
        .collect();
    let slots: Vec<Value> = (sb..sb + n)
        .map(|k| {
            json!([
                num(s.cf_slot_x[k]),
                num(s.cf_slot_y[k]),
                num(s.cf_slot_theta[k])
            ])
        })
        .collect();
    json!({"humans": humans, "slot_of": slot_of, "slots": slots, "centre": [num(s.cf_x[e]), num(s.cf_y[e])],
           "almost_formed_count": s.cf_close_steps[e]})
}

/// What a document must be before its keys are read: a JSON object, and where it names its
/// format (an [`export`]ed document does; a golden episode's header and snapshot do not), this
/// one.
fn check_envelope(doc: &Value) -> Result<(), SimError> {
    let refuse = |why: String| {
        Err(SimError::shape(
            "state document",
            format!("state document: {why}"),
        ))
    };
    let Some(map) = doc.as_object() else {
        return refuse(format!("must be a JSON object, got {}", json_kind(doc)));
    };
    match map.get("format") {
        None | Some(Value::Null) => Ok(()),
        Some(Value::String(f)) if f == FORMAT => Ok(()),
        Some(other) => refuse(format!(
            "`format` is {other}, where this version reads \"{FORMAT}\" (or a golden episode's \
             snapshot, which names none)"
        )),
    }
}

/// The kind of a JSON value, for an error message.
fn json_kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "an object",
    }
}

/// Load environment `e` of `s` from `doc`.
pub fn import(p: &StepParams, s: &mut BatchState, e: usize, doc: &Value) -> Result<(), SimError> {
    check_envelope(doc)?;
    let r = Reader::root(doc);
    // Unused slots hold zeros (crate::state): nothing of the environment's previous contents
    // remains beyond what the document fills.
    s.clear_slots(e);
    read::room(p, &r, s, e)?;
    read::human_params(p, &r.at("human_params")?, s, e)?;
    let st = r.at("state")?;
    read::snapshot(p, &st, s, e)?;
    sngnn::check_entity_ids(s, e)?;
    match r.opt("socnav") {
        Some(x) => read::extras(&x, s, e)?,
        None => {
            // A 0.1.1 snapshot: a running episode whose per-episode sums start here.
            s.done[e] = 0;
            s.pending_reset[e] = 0;
            crate::systems::reset::init_episode_sums(&mut s.env_chunk(e), 0);
        }
    }
    crate::systems::regroup::number_lists(&mut s.env_chunk(e), 0);
    // What a step must keep true must hold of what it starts from: an entity at NaN or far
    // outside the room would break the step's geometry (ORCA's obstacle processing).
    let broken = crate::state::invariants::violations(s, e);
    if !broken.is_empty() {
        return Err(SimError::shape(
            "state document",
            format!("state document: {}", broken.join("; ")),
        ));
    }
    derive_goal_distances(s, e);
    (s.robot_wvx[e], s.robot_wvy[e]) = crate::systems::robot_motion::world_velocity(
        s.robot_theta[e],
        s.robot_vx[e],
        s.robot_vy[e],
    );
    // Derived: observation caches from the snapshot's poses, obstacles to rebuild.
    let hb = e * s.strides.humans;
    for i in hb..hb + s.n_humans[e] as usize {
        s.h_prev_rel_theta[i] = math::wrap_angle(s.h_theta[i] - s.robot_theta[e]);
        let (sn, c) = math::sin_cos(s.h_theta[i]);
        s.h_vx[i] = s.h_speed[i] * c;
        s.h_vy[i] = s.h_speed[i] * sn;
    }
    // The SNGNN previous poses (derived, like the caches above) and the frame history.
    crate::sngnn::frame::start_episode(&mut s.env_chunk(e), 0);
    sngnn::import(&st, s, e)?;
    s.stepping[e] = 0;
    s.obstacles_dirty[e] = 1;
    Ok(())
}

/// The room shape code of a shape name (`room_shape::*` follows [`SHAPE_NAMES`]).
fn shape_code(name: &str) -> Option<u32> {
    const _: () = assert!(room_shape::SQUARE == 0 && room_shape::NO_WALLS == 3);
    SHAPE_NAMES
        .iter()
        .position(|n| *n == name)
        .map(|i| i as u32)
}

/// The metrics' and the reward's previous goal distances are, by definition, the distance from
/// the current robot pose to the goal. Recomputing them in f32 (when the document agrees within
/// rounding) keeps "did the distance grow" decisions exact for a robot that stands still: the
/// document's value, rounded from f64, can differ from the f32 distance by an ulp.
fn derive_goal_distances(s: &mut BatchState, e: usize) {
    let dx = s.goal_x[e] - s.robot_x[e];
    let dy = s.goal_y[e] - s.robot_y[e];
    let d = (dx * dx + dy * dy).sqrt();
    let agrees = |v: f32| (v - d).abs() <= 1e-5 * d.max(1.0);
    if agrees(s.m_prev_goal_dist[e]) {
        s.m_prev_goal_dist[e] = d;
    }
    if s.r_has_prev[e] != 0 && agrees(s.r_prev_dist[e]) {
        s.r_prev_dist[e] = d;
    }
}
