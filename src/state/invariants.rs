//! What every step must leave true of an environment's state, checked by `socnav soak` over
//! billions of steps with adversarial actions, by `set_state` on every loaded document, and
//! usable by any test: positions finite and in the room (robot, laptop users, objects, walls;
//! other humans finite only, see [`human_in_room`]), counts within the capacities, and every
//! human in exactly the place its role says: each human's role agreeing with its group or laptop,
//! the groups' and laptop users' lists agreeing with the humans (and each laptop's user with the
//! users), groups holding runs of slots in group order. `tests/suite/whole_step/invariants.rs`
//! checks them under adversarial actions.
//!
//! `set_state` (`document::import`) refuses a document that breaks them, and besides numbers that
//! are not finite or beyond 1e9, the robot's speeds beyond its limits, negative human speeds (a
//! human's may exceed the walkers' limit: the step flings some), a social force range `sfm_r0` or
//! interaction scale `sfm_gamma` that is not positive (each divides a distance in an exponential),
//! and walls longer than the observation's rows for the config. Which info values of a step may
//! be non-finite is `spec::info_outside_spec` (NaN for 0.1.1's `None`, +inf for its "inf if none",
//! each only where docs/spec.md 8.2 gives it; in `spec`, beside the info keys, so that `state` does
//! not depend on `spec`): `socnav soak` and the fuzz targets count the others.

use super::{BatchState, NONE, group_kind, role};

/// How far outside the room's bounding rectangle (m) an entity may be: a robot that leaves the
/// map ends its episode on that step (0.1.1's OUT_OF_MAP), a step moves at most a few tenths of
/// a metre, a laptop's user sits at most `config::validate::MAX_SEAT_DISTANCE_M` (1.5 m) from a
/// laptop on a table inside the walls, and an L room's removed block is inside the rectangle.
pub const ROOM_SLACK_M: f32 = 2.0;

/// Whether a human of role `r` must be in the room (within [`ROOM_SLACK_M`]); every human must be
/// finite.
///
/// Only laptop users must: they sit at a seat pose beside a laptop inside the walls (sitting down
/// snaps them there). Any other human may be anywhere, as in 0.1.1: RVO2 2.0.3's linear programs
/// in f32 can return a velocity far outside the agent's speed disc (LP3 intersects two nearly
/// opposite ORCA lines ~1e5 m/s out, and LP1's discriminant on that line cancels), which 0.1.1
/// applies as it is, so a lone ORCA walker or a moving group can be flung metres through the
/// walls in one step (docs/fidelity.md); outside, the walls keep it out, and the social events
/// can then make it a lone static human or a standing group's member. socnav's ORCA is RVO2's bit
/// for bit: in `lroom_mixed`'s episode 15640823229041020432 a moving group gets 22.6 m/s at tick 71
/// (its limit: 0.139 m/s).
#[inline]
pub fn human_in_room(r: u32) -> bool {
    r == role::LAPTOP_USER
}

/// Every broken invariant of environment `e` (empty when none), each naming the environment,
/// the entity and the values.
pub fn violations(s: &BatchState, e: usize) -> Vec<String> {
    let caps = s.strides;
    let counts = [
        ("humans", s.n_humans[e], caps.humans),
        ("groups", s.n_groups[e], caps.groups),
        ("laptop users", s.n_laptop_users[e], caps.laptop_users),
        ("laptops", s.n_laptops[e], caps.laptops),
        ("tables", s.n_tables[e], caps.tables),
        ("plants", s.n_plants[e], caps.plants),
        ("walls", s.n_walls[e], caps.walls),
    ];
    let over: Vec<String> = counts
        .iter()
        .filter(|&&(_, n, cap)| n as usize > cap)
        .map(|(what, n, cap)| format!("environment {e}: {n} {what}, more than the capacity {cap}"))
        .collect();
    if !over.is_empty() {
        return over;
    }
    let mut out = Vec::new();
    let mut fail = |msg: String| out.push(format!("environment {e}: {msg}"));
    let (hx, hy) = (
        s.map_x[e] / 2.0 + ROOM_SLACK_M,
        s.map_y[e] / 2.0 + ROOM_SLACK_M,
    );
    // `who`: the entity's kind and slot, or None for the robot; named only on failure (this runs
    // every step of a soak, for every environment). `in_room`: whether it must be in the room,
    // or only finite.
    let mut place = |who: Option<(&str, usize)>, x: f32, y: f32, in_room: bool| {
        let finite = x.is_finite() && y.is_finite();
        if finite && (!in_room || (x.abs() <= hx && y.abs() <= hy)) {
            return;
        }
        let what = who.map_or_else(|| "the robot".to_owned(), |(k, i)| format!("{k} slot {i}"));
        if !(x.is_finite() && y.is_finite()) {
            fail(format!("{what} at non-finite ({x}, {y})"));
        } else {
            fail(format!(
                "{what} at ({x}, {y}), outside the room of {} x {} m",
                s.map_x[e], s.map_y[e]
            ));
        }
    };
    place(None, s.robot_x[e], s.robot_y[e], true);
    let hb = e * caps.humans;
    for k in 0..s.n_humans[e] as usize {
        let h = hb + k;
        place(
            Some(("human", k)),
            s.h_x[h],
            s.h_y[h],
            human_in_room(s.h_role[h]),
        );
    }
    for (kind, n, cap, xs, ys) in [
        ("table", s.n_tables[e], caps.tables, &s.t_x, &s.t_y),
        ("laptop", s.n_laptops[e], caps.laptops, &s.l_x, &s.l_y),
        ("plant", s.n_plants[e], caps.plants, &s.p_x, &s.p_y),
        ("wall", s.n_walls[e], caps.walls, &s.w_x, &s.w_y),
    ] {
        for k in 0..n as usize {
            place(Some((kind, k)), xs[e * cap + k], ys[e * cap + k], true);
        }
    }
    humans_in_their_places(s, e, &mut fail);
    out
}

/// Each human's role agrees with its group or laptop, and the groups and laptop users list
/// exactly those humans.
fn humans_in_their_places(s: &BatchState, e: usize, fail: &mut impl FnMut(String)) {
    let caps = s.strides;
    let n_humans = s.n_humans[e] as usize;
    let (n_groups, n_users) = (s.n_groups[e] as usize, s.n_laptop_users[e] as usize);
    let mut grouped = 0;
    for k in 0..n_humans {
        let h = e * caps.humans + k;
        let (r, g, u) = (s.h_role[h], s.h_group[h], s.h_laptop_user[h]);
        match r {
            role::STATIC | role::DYNAMIC if g == NONE && u == NONE => {}
            role::MOVING_GROUP | role::STANDING_GROUP if (g as usize) < n_groups && u == NONE => {
                let gi = e * caps.groups + g as usize;
                let (first, count) = (s.g_first[gi] as usize, s.g_count[gi] as usize);
                if !(first..first + count).contains(&k) {
                    fail(format!(
                        "human slot {k} in group {g}, whose members are slots {first}..{}",
                        first + count
                    ));
                }
                grouped += 1;
            }
            role::LAPTOP_USER if (u as usize) < n_users && g == NONE => {
                let ui = e * caps.laptop_users + u as usize;
                if s.lu_human[ui] as usize != k {
                    fail(format!(
                        "human slot {k} says laptop user {u}, who is slot {}",
                        s.lu_human[ui]
                    ));
                }
            }
            _ => fail(format!(
                "human slot {k}: role {r}, group {g}, laptop user {u} disagree"
            )),
        }
    }
    // Groups hold runs of slots in group order, each starting at or after the end of the one
    // before (the observation's interaction pairs walk them so, `systems::observation`).
    let mut end = 0;
    for g in 0..n_groups {
        let gi = e * caps.groups + g;
        let (first, count) = (s.g_first[gi] as usize, s.g_count[gi] as usize);
        if first < end || first + count > n_humans {
            fail(format!(
                "group {g}: slots {first}..{}, starting before the end {end} of the group before \
                 it or past the {n_humans} humans",
                first + count
            ));
        }
        end = first + count;
    }
    let members: usize = (0..n_groups)
        .map(|g| e * caps.groups + g)
        .filter(|&gi| s.g_kind[gi] != group_kind::DISSOLVED)
        .map(|gi| s.g_count[gi] as usize)
        .sum();
    if members != grouped {
        fail(format!(
            "the groups list {members} members, {grouped} humans have a group role"
        ));
    }
    // The laptops' side of the links: a laptop names no user, or the user who sits at it.
    for l in 0..s.n_laptops[e] as usize {
        let user = s.l_user[e * caps.laptops + l];
        let sits_here = (user as usize) < n_users
            && s.lu_laptop[e * caps.laptop_users + user as usize] as usize == l;
        if user != NONE && !sits_here {
            fail(format!(
                "laptop {l} names laptop user {user}, who is not at it ({n_users} users)"
            ));
        }
    }
    for u in 0..n_users {
        let ui = e * caps.laptop_users + u;
        let laptop = s.lu_laptop[ui];
        if laptop as usize >= s.n_laptops[e] as usize {
            fail(format!(
                "laptop user {u} at laptop {laptop} of {}",
                s.n_laptops[e]
            ));
        } else if s.l_user[e * caps.laptops + laptop as usize] as usize != u {
            fail(format!(
                "laptop user {u} at laptop {laptop}, whose user is {}",
                s.l_user[e * caps.laptops + laptop as usize]
            ));
        }
    }
}
