//! What a read document must be beyond what each value is (module `values`): the batch's
//! config and capacities, and the links between its parts. [`validate`] refuses a document with
//! the path of the offending value (`state.humans[3].speed`) or the capacity it exceeds, and
//! resolves the links (ids to list slots) that `load` writes.

use super::types::{Document, Human, Robot, Shadow, Snapshot};
use super::values::{F32, MAX_MAGNITUDE, Vector, angle, capacity, err};
use crate::error::SimError;
use crate::params::StepParams;
use crate::state::{Caps, role};

/// The links of a valid document, as list slots.
pub(super) struct Plan {
    /// Per group: its first member's slot and its members' goal radius (m).
    pub groups: Vec<(u32, f32)>,
    /// (human slot, group) of each group member.
    pub members: Vec<(usize, u32)>,
    /// Per laptop user: its human's and laptop's slots.
    pub users: Vec<(u32, u32)>,
    /// The human slot of each slot of a forming crowd.
    pub crowd: Vec<u32>,
    /// A laptop-use formation: the walker's and the laptop's slots.
    pub laptop_forming: Option<(u32, u32)>,
    /// Replayed group noise: human slot, noise (m/s).
    pub noise: Vec<(usize, f32, f32)>,
}

/// A size that socnav takes from the config: it must equal `expected` (f32 rounding aside).
fn matches(
    path: &str,
    value: Option<F32>,
    expected: f32,
    config_key: &str,
) -> Result<(), SimError> {
    let Some(F32(v)) = value else {
        return Ok(());
    };
    if (v - expected).abs() > 1e-5 * expected.abs().max(1.0) {
        return Err(err(
            path,
            format!("is {v} but this batch's config has `{config_key}` = {expected}"),
        ));
    }
    Ok(())
}

/// A number in `lo..=hi`; `why` says where the bounds come from.
fn within(path: &str, x: F32, lo: f32, hi: f32, why: &str) -> Result<(), SimError> {
    if !(lo..=hi).contains(&x.0) {
        return Err(err(
            path,
            format!("is {}; it must be in [{lo}, {hi}] ({why})", x.0),
        ));
    }
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

/// Checks `doc` against the batch's config `p` and capacities `c`.
pub(super) fn validate(doc: &Document, p: &StepParams, c: &Caps) -> Result<Plan, SimError> {
    room(doc, p, c)?;
    human_params(doc, p)?;
    snapshot(&doc.state, p, c)
}

fn room(doc: &Document, p: &StepParams, c: &Caps) -> Result<(), SimError> {
    let walls = &doc.walls.0;
    capacity("walls", walls.len(), c.walls, "room shape and corridors")?;
    for (k, w) in walls.iter().enumerate() {
        let path = format!("walls[{k}]");
        matches(
            &format!("{path}.thickness"),
            w.thickness,
            p.wall_thickness,
            "objects.wall_thickness",
        )?;
        let length = w.length.0;
        if !(length.is_finite() && length > 0.0) {
            return Err(err(
                &format!("{path}.length"),
                format!("is {length} m; a wall's length must be a positive number"),
            ));
        }
    }
    // The observation holds the walls' segments in rows sized for the config's rooms: longer
    // walls than any of them would overrun it.
    let segments: u64 = walls
        .iter()
        .map(|w| u64::from(crate::room::segment_count(w.length.0, p.wall_segment_size)))
        .sum();
    capacity(
        "wall segments",
        segments as usize,
        c.wall_segments,
        "the walls of the config's largest room, in `objects.wall_segment_size` pieces",
    )?;
    capacity(
        "spawn blockers",
        doc.spawn_blockers.0.len(),
        c.blockers,
        "room shape and corridors",
    )
}

fn human_params(doc: &Document, p: &StepParams) -> Result<(), SimError> {
    let h = &doc.human_params;
    // RVO2 divides by the horizons: a generated one is at least 0.1 s (docs/fidelity.md).
    for (key, value) in [
        ("orca_timeHorizon", h.orca_time_horizon),
        ("orca_timeHorizonObst", h.orca_time_horizon_obst),
    ] {
        let path = format!("human_params.{key}");
        within(&path, value, 0.1, 1e9, "ORCA divides by its time horizons")?;
    }
    within(
        "human_params.orca_maxSpeed",
        h.orca_max_speed,
        0.0,
        max_walker_speed(p),
        WALKER_SPEED_BOUND,
    )?;
    // The force's range: drawn as |0.05 + 0.01 N| m, and a divisor of the surface gap in an
    // exponential, where a negative one makes the force of a nearby obstacle overflow.
    within(
        "human_params.sfm_r0",
        h.sfm_r0,
        f32::MIN_POSITIVE,
        1e9,
        "the social force's range is positive",
    )?;
    // The interaction's scale B = gamma |D| divides the pair's distance in exp(-d / B): drawn as
    // 0.25 + 0.01 N, and a negative one makes the force of a distant pedestrian overflow.
    within(
        "human_params.sfm_gamma",
        h.sfm_gamma,
        f32::MIN_POSITIVE,
        1e9,
        "the social force's interaction scale is positive",
    )
}

fn snapshot(st: &Snapshot, p: &StepParams, c: &Caps) -> Result<Plan, SimError> {
    robot(&st.robot, p)?;
    shadow(&st.shadow_robot, p)?;
    let ids = humans(&st.humans.0, p, c)?;
    let laptop_ids = objects(st, p, c)?;
    let (groups, members) = groups(st, p, c, &ids)?;
    let users = laptop_users(st, c, &ids, &laptop_ids)?;
    let (crowd, laptop_forming) = forming(st, c, &ids, &laptop_ids)?;
    let mut noise = Vec::new();
    for (k, entry) in st.group_noise.0.iter().enumerate() {
        let slot = slot_of(&ids, entry.0.0, &format!("state.group_noise[{k}]"))?;
        noise.push((slot, entry.1.0, entry.2.0));
    }
    Ok(Plan {
        groups,
        members,
        users,
        crowd,
        laptop_forming,
        noise,
    })
}

fn robot(r: &Robot, p: &StepParams) -> Result<(), SimError> {
    matches(
        "state.robot.radius",
        r.radius,
        p.robot_radius,
        "robot.radius",
    )?;
    matches(
        "state.robot.goal_radius",
        r.goal_radius,
        p.goal_radius,
        "robot.goal_radius",
    )?;
    robot_velocity("state.robot.vel", r.vel, p)
}

fn shadow(r: &Shadow, p: &StepParams) -> Result<(), SimError> {
    robot_velocity("state.shadow_robot.vel", r.vel, p)
}

/// A robot's `vel` [vx, vy, ω] (m/s, m/s, rad/s), each within the robot's limits (a
/// velocity is always a clipped command).
fn robot_velocity(path: &str, vel: Vector<3>, p: &StepParams) -> Result<(), SimError> {
    let limits = [p.robot_max_speed, p.robot_max_speed, p.robot_max_rotation];
    for (k, (v, limit)) in vel.0.iter().zip(limits).enumerate() {
        // f32 rounding of a limit that was clipped against.
        let limit = limit * (1.0 + 1e-5);
        if v.abs() > limit {
            return Err(err(
                &format!("{path}[{k}]"),
                format!(
                    "is {v}; the robot's limits (`robot.max_speed`, `robot.max_rotation`) bound it to ±{limit}"
                ),
            ));
        }
    }
    Ok(())
}

/// Humans in observation order; returns their ids by slot.
fn humans(list: &[Human], p: &StepParams, c: &Caps) -> Result<Vec<u32>, SimError> {
    capacity(
        "humans",
        list.len(),
        c.humans,
        "the configured maximum humans of every role",
    )?;
    let mut last_rank = 0;
    for (k, h) in list.iter().enumerate() {
        let path = format!("state.humans[{k}]");
        matches(
            &format!("{path}.radius"),
            h.radius,
            p.human_radius,
            "human.diameter / 2",
        )?;
        // Observation order: static, dynamic, group members (any group kind), laptop users.
        let rank = match h.role.0 {
            role::STATIC => 0,
            role::DYNAMIC => 1,
            role::MOVING_GROUP | role::STANDING_GROUP => 2,
            _ => 3,
        };
        if rank < last_rank {
            return Err(err(
                &path,
                "is out of observation order (lone static, lone walking, group members, laptop users)",
            ));
        }
        last_rank = rank;
        within(
            &format!("{path}.speed"),
            h.speed,
            0.0,
            MAX_MAGNITUDE,
            FLUNG_SPEED,
        )?;
        // Whether it walks to a laptop is read only if it does not walk to a crowd.
        if let (false, Some(f)) = (h.forming_crowd.is_some_and(|f| f.0), &h.forming_hl) {
            f.get(&format!("{path}.forming_hl"))?;
        }
    }
    Ok(list.iter().map(|h| h.id.0).collect())
}

/// Laptops, tables and plants; returns the laptops' ids by slot.
fn objects(st: &Snapshot, p: &StepParams, c: &Caps) -> Result<Vec<u32>, SimError> {
    let laptops = &st.laptops.0;
    capacity(
        "laptops",
        laptops.len(),
        c.laptops,
        "counts.laptops plus laptop users",
    )?;
    for (k, l) in laptops.iter().enumerate() {
        let path = format!("state.laptops[{k}]");
        let (length, width) = (format!("{path}.length"), format!("{path}.width"));
        matches(&length, l.length, p.laptop_length, "objects.laptop_length")?;
        matches(&width, l.width, p.laptop_width, "objects.laptop_width")?;
    }
    let tables = &st.tables.0;
    capacity("tables", tables.len(), c.tables, "counts.tables")?;
    for (k, t) in tables.iter().enumerate() {
        let path = format!("state.tables[{k}]");
        let (length, width) = (format!("{path}.length"), format!("{path}.width"));
        matches(&length, t.length, p.table_length, "objects.table_length")?;
        matches(&width, t.width, p.table_width, "objects.table_width")?;
    }
    let plants = &st.plants.0;
    capacity("plants", plants.len(), c.plants, "counts.plants")?;
    for (k, pl) in plants.iter().enumerate() {
        let path = format!("state.plants[{k}].radius");
        matches(&path, pl.radius, p.plant_radius, "objects.plant_radius")?;
    }
    Ok(laptops.iter().map(|l| l.id.0).collect())
}

/// The slot of the entity with id `id` in `ids`, refused at `path` if there is none.
fn slot_of(ids: &[u32], id: u32, path: &str) -> Result<usize, SimError> {
    ids.iter()
        .position(|&x| x == id)
        .ok_or_else(|| err(path, format!("names id {id}, which is not in the list")))
}

/// Per group its first member's slot and member goal radius; each member's slot and group.
type Groups = (Vec<(u32, f32)>, Vec<(usize, u32)>);

fn groups(st: &Snapshot, p: &StepParams, c: &Caps, ids: &[u32]) -> Result<Groups, SimError> {
    let list = &st.groups.0;
    capacity(
        "groups",
        list.len(),
        c.groups,
        "the configured maximum groups, or humans / 2 with crowd formation",
    )?;
    let (mut groups, mut members) = (Vec::new(), Vec::new());
    for (k, g) in list.iter().enumerate() {
        let path = format!("state.groups[{k}].members");
        let items = &g.members.0;
        if items.is_empty() {
            return Err(err(&path, "must list at least one member"));
        }
        // A group's members fill pair rows of the observation sized by the config's group size.
        capacity(
            "members of a group",
            items.len(),
            c.group_size,
            "counts.group_size",
        )?;
        let mut first = 0;
        for (m, id) in items.iter().enumerate() {
            let slot = slot_of(ids, id.0, &format!("{path}[{m}]"))?;
            if m == 0 {
                first = slot;
            } else if slot != first + m {
                return Err(err(
                    &path,
                    "must list consecutive humans of the `humans` list, in order",
                ));
            }
            members.push((slot, k as u32));
        }
        let radius = member_goal_radius(&st.humans.0, p, &path, first, items.len())?;
        groups.push((first as u32, radius));
    }
    Ok((groups, members))
}

/// The goal radius (m) a group's members test their arrival with: their `goal_radius` in the
/// document (0.1.1 records each human's own), which must be the same for every member (every
/// group 0.1.1 makes has one value); the group goal radius when the members do not say.
fn member_goal_radius(
    humans: &[Human],
    p: &StepParams,
    members_path: &str,
    first: usize,
    n: usize,
) -> Result<f32, SimError> {
    let mut radius = None;
    for (k, h) in humans.iter().enumerate().skip(first).take(n) {
        let Some(r) = &h.goal_radius else {
            continue;
        };
        let path = format!("state.humans[{k}].goal_radius");
        let value = r.get(&path)?.0;
        if !(value.is_finite() && value > 0.0) {
            return Err(err(
                &path,
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
    st: &Snapshot,
    c: &Caps,
    ids: &[u32],
    laptop_ids: &[u32],
) -> Result<Vec<(u32, u32)>, SimError> {
    let list = &st.hl_interactions.0;
    capacity(
        "laptop users",
        list.len(),
        c.laptop_users,
        "counts.laptop_users, or all laptops with laptop-use formation",
    )?;
    list.iter()
        .enumerate()
        .map(|(k, u)| {
            let path = format!("state.hl_interactions[{k}]");
            let human = slot_of(ids, u.human.0, &format!("{path}.human"))?;
            let laptop = slot_of(laptop_ids, u.laptop.0, &format!("{path}.laptop"))?;
            Ok((human as u32, laptop as u32))
        })
        .collect()
}

/// A formation at `path` ends in a new one of `n` `what` (a group, a laptop user): refused when
/// the environment's `cap` are all taken, where the step would have nowhere to put it.
fn slot_to_form(path: &str, n: usize, cap: usize, what: &str) -> Result<(), SimError> {
    if n >= cap {
        return Err(err(
            path,
            format!("cannot form: the {n} {what} already fill the config's capacity"),
        ));
    }
    Ok(())
}

/// The human slot of each slot of a forming crowd; a laptop-use formation's human and laptop
/// slots.
type Forming = (Vec<u32>, Option<(u32, u32)>);

fn forming(st: &Snapshot, c: &Caps, ids: &[u32], laptop_ids: &[u32]) -> Result<Forming, SimError> {
    let mut crowd = Vec::new();
    if let Some(cf) = &st.crowd_forming {
        let path = "state.crowd_forming";
        let slots = &cf.slots.0;
        capacity(
            "forming crowd slots",
            slots.len(),
            c.group_size,
            "counts.group_size",
        )?;
        if slots.is_empty() {
            return Err(err(&format!("{path}.slots"), "must hold at least one slot"));
        }
        // The crowd becomes a group when it has formed.
        slot_to_form(path, st.groups.0.len(), c.groups, "groups")?;
        let map_path = format!("{path}.slot_of");
        let entries = &cf.slot_of.0;
        // Every slot has its walker, one each.
        if entries.len() != slots.len() {
            return Err(err(
                &map_path,
                format!(
                    "names {} walkers for {} slots; each slot needs one",
                    entries.len(),
                    slots.len()
                ),
            ));
        }
        let mut taken = vec![None; slots.len()];
        for (id, k) in entries {
            let id: u32 = id
                .parse()
                .map_err(|_| err(&map_path, format!("key {id:?} is not a human id")))?;
            let k = k
                .as_u64()
                .ok_or_else(|| err(&map_path, "values must be slot indices"))?
                as usize;
            if k >= slots.len() {
                return Err(err(
                    &map_path,
                    format!("slot {k} out of range 0..{}", slots.len()),
                ));
            }
            if taken[k].is_some() {
                return Err(err(&map_path, format!("names slot {k} twice")));
            }
            taken[k] = Some(slot_of(ids, id, &map_path)? as u32);
        }
        crowd = taken.into_iter().flatten().collect();
    }
    let mut laptop_forming = None;
    if let Some(lf) = &st.hl_forming {
        let path = "state.hl_forming";
        // The walker becomes a laptop user when it reaches the seat.
        slot_to_form(
            path,
            st.hl_interactions.0.len(),
            c.laptop_users,
            "laptop users",
        )?;
        let human = slot_of(ids, lf.human.0, &format!("{path}.human"))?;
        let laptop = slot_of(laptop_ids, lf.laptop.0, &format!("{path}.laptop"))?;
        angle(lf.seat.0[2]).map_err(|why| err(&format!("{path}.seat[2]"), why))?;
        laptop_forming = Some((human as u32, laptop as u32));
    }
    Ok((crowd, laptop_forming))
}
