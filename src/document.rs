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
//! One set of serde types (`types`) describes the document for both directions: [`export`]
//! fills them from the state and converts them to JSON; [`import`] reads them from JSON (module
//! `values`: each value as the golden format has it, a refusal naming its path, such as
//! `state.humans[3].x`), checks them against the batch's config and capacities and resolves the
//! ids they link by (`validate`), writes them into the environment (`load`), and checks the
//! state's invariants. Nothing is written before the document has been read and validated.
//!
//! The module sits above the stages, not in `state`: loading a document recomputes what the stages
//! derive (list positions, episode sums, formations, the robot's world velocity, the SNGNN
//! history) with the stages' own code.

use serde_json::Value;

use crate::error::SimError;
use crate::math;
use crate::params::StepParams;
use crate::state::{BatchState, NONE, blocker_kind, forming, group_kind, policy, role};

mod load;
mod sngnn;
mod types;
mod validate;
mod values;

use types::{
    Blocker, Counts, CrowdForming, Document, EpisodeSums, Extras, Group, Human, HumanParams,
    Laptop, LaptopForming, LaptopUser, Metrics, Plant, RewardInfo, RewardState, Robot, Room,
    Shadow, Snapshot, Table, Wall,
};
use values::{Angle, Code, F32, Flag, Id, Lazy, List, Min, Object, Slot, U32, U64, Vector};

/// Format tag of documents written by [`export`].
pub const FORMAT: &str = "socnav-state/1";

/// Environment `e` of `s` as a document.
pub fn export(p: &StepParams, s: &BatchState, e: usize) -> Value {
    // A document of f32s, strings, integers and booleans always converts.
    serde_json::to_value(document(p, s, e)).unwrap_or(Value::Null)
}

/// Environment `e` of `s` as a [`Document`].
fn document(p: &StepParams, s: &BatchState, e: usize) -> Document {
    let c = &s.strides;
    let wb = e * c.walls;
    let walls = (wb..wb + s.n_walls[e] as usize)
        .map(|w| Wall {
            id: U32(s.w_id[w]),
            x: F32(s.w_x[w]),
            y: F32(s.w_y[w]),
            theta: Angle(s.w_theta[w]),
            length: F32(s.w_length[w]),
            thickness: Some(F32(p.wall_thickness)),
        })
        .collect();
    let bb = e * c.blockers;
    let blockers = (bb..bb + s.n_blockers[e] as usize)
        .map(|b| Blocker {
            kind: Code::new(if s.b_kind[b] == blocker_kind::L_BLOCK {
                blocker_kind::L_BLOCK
            } else {
                blocker_kind::DOOR
            }),
            x: F32(s.b_x[b]),
            y: F32(s.b_y[b]),
            theta: Angle(s.b_theta[b]),
            length: F32(s.b_length[b]),
            width: F32(s.b_width[b]),
        })
        .collect();
    Document {
        format: FORMAT,
        room: Room {
            map_x: F32(s.map_x[e]),
            map_y: F32(s.map_y[e]),
            shape: Code::new(s.room_shape[e]),
        },
        walls: List(walls),
        spawn_blockers: List(blockers),
        human_params: HumanParams {
            orca_neighbor_dist: F32(s.orca_neighbor_dist[e]),
            orca_time_horizon: F32(s.orca_time_horizon[e]),
            orca_time_horizon_obst: F32(s.orca_time_horizon_obst[e]),
            orca_max_speed: F32(s.orca_max_speed[e]),
            sfm_r0: F32(s.sfm_r0[e]),
            sfm_gamma: F32(s.sfm_gamma[e]),
            sfm_n: F32(s.sfm_n[e]),
            sfm_n_prime: F32(s.sfm_n_prime[e]),
            sfm_lambda: F32(s.sfm_lambda[e]),
        },
        counts: Counts {
            total_humans: s.n_humans[e],
        },
        state: snapshot(p, s, e),
        socnav: Some(Extras {
            episode: U32(s.episode[e]),
            seed: Some(U64(s.episode_seed(e))),
            next_seed: Some(U64(s.next_seed(e))),
            done: Flag(s.done[e] != 0),
            pending_reset: Flag(s.pending_reset[e] != 0),
            episode_sums: Some(EpisodeSums {
                ret: F32(s.ep_return[e]),
                min_human_distance: Min(s.ep_min_human_dist[e]),
                min_obstacle_distance: Min(s.ep_min_obstacle_dist[e]),
                sum_average_obstacle_distance: F32(s.ep_sum_avg_obstacle_dist[e]),
                sum_time_to_collision: F32(s.ep_sum_ttc[e]),
                sum_discomfort_dsrnn: F32(s.ep_sum_discomfort_dsrnn[e]),
                sum_sngnn_reward: F32(s.ep_sum_sngnn[e]),
            }),
        }),
    }
}

fn snapshot(p: &StepParams, s: &BatchState, e: usize) -> Snapshot {
    let c = &s.strides;
    let hb = e * c.humans;
    let mut goals = std::collections::BTreeMap::new();
    goals.insert(
        "0".to_string(),
        [F32(s.goal_x[e]), F32(s.goal_y[e]), F32(p.goal_radius)],
    );
    let humans = (0..s.n_humans[e] as usize)
        .map(|k| {
            let i = hb + k;
            let r = s.h_role[i];
            // Every human has a goal: spawned laptop users and standing-group members their own
            // position, formed ones the seat or slot they walked to (0.1.1 keeps it).
            let goal = [s.h_goal_x[i], s.h_goal_y[i]];
            // The goal registry holds a moving group's goal disc with the group goal radius;
            // a member's own arrival test uses its group's member goal radius.
            let registry_radius = if r == role::MOVING_GROUP {
                p.group_goal_radius
            } else {
                p.human_goal_radius
            };
            if r != role::LAPTOP_USER && r != role::STANDING_GROUP {
                goals.insert(
                    s.h_id[i].to_string(),
                    [F32(goal[0]), F32(goal[1]), F32(registry_radius)],
                );
            }
            let goal_radius = match r {
                role::LAPTOP_USER => None,
                _ if s.h_group[i] != NONE => {
                    Some(s.g_member_goal_radius[e * c.groups + s.h_group[i] as usize])
                }
                _ => Some(p.human_goal_radius),
            };
            let index = |v: u32| (v != NONE).then_some(U32(v));
            Human {
                id: U32(s.h_id[i]),
                x: F32(s.h_x[i]),
                y: F32(s.h_y[i]),
                theta: Angle(s.h_theta[i]),
                speed: F32(s.h_speed[i]),
                radius: Some(F32(p.human_radius)),
                goal: Some(Vector(goal)),
                goal_radius: goal_radius.map(|r| Lazy::Ready(F32(r))),
                policy: Code::new(if s.h_policy[i] == policy::ORCA {
                    policy::ORCA
                } else {
                    policy::SFM
                }),
                role: Code::new(r),
                group: index(s.h_group[i]),
                hl: index(s.h_laptop_user[i]),
                forming_crowd: (s.h_forming[i] == forming::CROWD).then_some(Flag(true)),
                forming_hl: (s.h_forming[i] == forming::LAPTOP).then_some(Lazy::Ready(Flag(true))),
            }
        })
        .collect();
    let gb = e * c.groups;
    let groups = (gb..gb + s.n_groups[e] as usize)
        .map(|g| {
            let first = hb + s.g_first[g] as usize;
            Group {
                kind: Code::new(if s.g_kind[g] == group_kind::MOVING {
                    group_kind::MOVING
                } else {
                    group_kind::STANDING
                }),
                dispersable: Flag(s.g_dispersable[g] != 0),
                members: List(
                    (first..first + s.g_count[g] as usize)
                        .map(|i| Id(s.h_id[i]))
                        .collect(),
                ),
                centre: Vector([s.g_x[g], s.g_y[g]]),
                // A standing group's goal: its centre when spawned, the old goal when it stopped.
                goal: Some(Vector([s.g_goal_x[g], s.g_goal_y[g]])),
                goal_radius: F32(p.group_goal_radius),
                radius: F32(p.group_radius),
                noise: F32(p.group_noise_std),
            }
        })
        .collect();
    let lb = e * c.laptops;
    let ub = e * c.laptop_users;
    let users = (ub..ub + s.n_laptop_users[e] as usize)
        .map(|u| {
            let h = hb + s.lu_human[u] as usize;
            let l = lb + s.lu_laptop[u] as usize;
            LaptopUser {
                human: U32(s.h_id[h]),
                laptop: U32(s.l_id[l]),
                dispersable: Flag(s.lu_dispersable[u] != 0),
                centre: [
                    F32(0.5 * (s.h_x[h] + s.l_x[l])),
                    F32(0.5 * (s.h_y[h] + s.l_y[l])),
                ],
                distance: F32(p.laptop_width + p.human_laptop_distance),
            }
        })
        .collect();
    let laptops = (lb..lb + s.n_laptops[e] as usize)
        .map(|l| Laptop {
            id: U32(s.l_id[l]),
            x: F32(s.l_x[l]),
            y: F32(s.l_y[l]),
            theta: Angle(s.l_theta[l]),
            length: Some(F32(p.laptop_length)),
            width: Some(F32(p.laptop_width)),
            hl: (s.l_user[l] != NONE).then_some(U32(s.l_user[l])),
        })
        .collect();
    let tb = e * c.tables;
    let tables = (tb..tb + s.n_tables[e] as usize)
        .map(|t| Table {
            id: U32(s.t_id[t]),
            x: F32(s.t_x[t]),
            y: F32(s.t_y[t]),
            theta: Angle(s.t_theta[t]),
            length: Some(F32(p.table_length)),
            width: Some(F32(p.table_width)),
        })
        .collect();
    let pb = e * c.plants;
    let plants = (pb..pb + s.n_plants[e] as usize)
        .map(|i| Plant {
            id: U32(s.p_id[i]),
            x: F32(s.p_x[i]),
            y: F32(s.p_y[i]),
            radius: Some(F32(p.plant_radius)),
        })
        .collect();
    let robot_vel = Vector([s.robot_vx[e], s.robot_vy[e], s.robot_w[e]]);
    Snapshot {
        tick: U32(s.tick[e]),
        robot: Robot {
            x: F32(s.robot_x[e]),
            y: F32(s.robot_y[e]),
            theta: Angle(s.robot_theta[e]),
            radius: Some(F32(p.robot_radius)),
            goal: Vector([s.goal_x[e], s.goal_y[e]]),
            goal_radius: Some(F32(p.goal_radius)),
            vel: robot_vel,
        },
        shadow_robot: Shadow {
            x: F32(s.shadow_x[e]),
            y: F32(s.shadow_y[e]),
            theta: Angle(s.shadow_theta[e]),
            vel: Vector([s.shadow_vx[e], s.shadow_vy[e], s.shadow_w[e]]),
            collided: Flag(s.shadow_collided[e] != 0),
            reached: Flag(s.shadow_reached[e] != 0),
            reach_tick: (s.shadow_reached[e] != 0).then_some(U32(s.shadow_reach_tick[e])),
            path_length: F32(s.shadow_path_length[e]),
        },
        humans: List(humans),
        groups: List(groups),
        hl_interactions: List(users),
        laptops: List(laptops),
        tables: List(tables),
        plants: List(plants),
        crowd_forming: crowd_forming(s, e),
        hl_forming: (s.lf_active[e] != 0).then(|| LaptopForming {
            human: U32(s.h_id[hb + s.lf_human[e] as usize]),
            laptop: U32(s.l_id[lb + s.lf_laptop[e] as usize]),
            seat: Vector([s.lf_seat_x[e], s.lf_seat_y[e], s.lf_seat_theta[e]]),
        }),
        metrics: Metrics {
            prev_goal_distance: F32(s.m_prev_goal_dist[e]),
            failure_to_progress: U32(s.m_failure_to_progress[e]),
            stalled_time: F32(s.m_stalled_time[e]),
            path_length: F32(s.m_path_length[e]),
            v_min: Min(s.m_v_min[e]),
            v_max: F32(s.m_v_max[e]),
            v_avg: F32(s.m_v_avg[e]),
            prev_vel: Vector([s.m_prev_vx[e], s.m_prev_vy[e]]),
            a_min: Min(s.m_a_min[e]),
            a_max: F32(s.m_a_max[e]),
            a_avg: F32(s.m_a_avg[e]),
            prev_a: Vector([s.m_prev_ax[e], s.m_prev_ay[e]]),
            jerk_min: Min(s.m_j_min[e]),
            jerk_max: F32(s.m_j_max[e]),
            jerk_avg: F32(s.m_j_avg[e]),
            compliant_count: U32(s.m_compliant[e]),
        },
        reward_state: RewardState {
            prev_distance: (s.r_has_prev[e] != 0).then_some(F32(s.r_prev_dist[e])),
            info: RewardInfo {
                discomfort_sngnn: F32(s.r_discomfort_sngnn[e]),
                discomfort_dsrnn: F32(s.r_discomfort_dsrnn[e]),
                distance_reward: F32(s.r_distance[e]),
                alive_reward: F32(s.r_alive[e]),
                sngnn_reward: F32(s.r_sngnn[e]),
            },
        },
        goals,
        group_noise: List::default(),
        sngnn_frames: (s.strides.frames > 0).then(|| Lazy::Ready(sngnn::export(p, s, e))),
    }
}

fn crowd_forming(s: &BatchState, e: usize) -> Option<CrowdForming> {
    if s.cf_active[e] == 0 {
        return None;
    }
    let c = &s.strides;
    let hb = e * c.humans;
    let sb = e * c.group_size;
    let n = s.cf_count[e] as usize;
    let mut slot_of = serde_json::Map::new();
    let humans = (0..n)
        .map(|k| {
            let id = s.h_id[hb + s.cf_human[sb + k] as usize];
            slot_of.insert(id.to_string(), Value::from(k));
            id
        })
        .collect();
    let slots = (sb..sb + n)
        .map(|k| {
            Slot(
                F32(s.cf_slot_x[k]),
                F32(s.cf_slot_y[k]),
                Angle(s.cf_slot_theta[k]),
            )
        })
        .collect();
    Some(CrowdForming {
        humans,
        slot_of: Object(slot_of),
        slots: List(slots),
        centre: Vector([s.cf_x[e], s.cf_y[e]]),
        almost_formed_count: U32(s.cf_close_steps[e]),
    })
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
    let doc: Document = values::parse_at(doc, "")?;
    let plan = validate::validate(&doc, p, &s.strides)?;
    // Unused slots hold zeros (crate::state): nothing of the environment's previous contents
    // remains beyond what the document fills.
    s.clear_slots(e);
    load::write(&doc, &plan, s, e);
    sngnn::check_entity_ids(s, e)?;
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
    sngnn::import(doc.state.sngnn_frames.as_ref(), s, e)?;
    s.stepping[e] = 0;
    s.obstacles_dirty[e] = 1;
    Ok(())
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
