//! Stage `social_events` (docs/spec.md 4.1 step 12, 4.5): the random social events, drawn after the
//! observation so that they show up in the next step's, in 0.1.1's order: crowd dispersal,
//! laptop-use dispersal, crowd formation, laptop-use formation.
//!
//! Each event is split into a draw (which group, which members, ...) and an application that
//! takes those decisions, so tests can apply the decisions the golden episodes recorded and
//! compare the resulting lists with 0.1.1's. In replay mode nothing is drawn: the golden replay
//! re-synchronises with the recorded state instead.

use crate::fixed::Fixed;
use crate::geometry::{Disc, Shape};
use crate::limits::{MAX_GROUP, MAX_PERMUTE};
use crate::params::StepParams;
use crate::rng::RngStream;
use crate::scenario::place::{self, MAX_TRIES, Pose, SamplingBox};
use crate::spec::event;
use crate::state::{NONE, StateChunk, forming, group_kind, policy, role};

use super::Batch;
use super::regroup;

/// RNG stream kind of the social events (`sub` = tick).
pub const STREAM_SOCIAL: u32 = 6;

/// Draw and apply the social events of environment `e`.
pub fn social_events(p: &StepParams, b: &mut Batch<'_>, e: usize) {
    if b.s.stepping[e] == 0 || b.s.done[e] != 0 || p.replay != 0 {
        return;
    }
    let events = b.o.strides.events();
    let counts = &mut b.o.events[e * events..(e + 1) * events];
    let s = &mut b.s;
    let mut rng = super::LazyStream::new(s, e, STREAM_SOCIAL);
    if p.p_crowd_dispersal > 0.0
        && rng.get().chance(p.p_crowd_dispersal)
        && crowd_dispersal(p, s, e, rng.get())
    {
        counts[event::CROWD_DISPERSAL] += 1;
    }
    if p.p_laptop_dispersal > 0.0
        && rng.get().chance(p.p_laptop_dispersal)
        && laptop_dispersal(p, s, e, rng.get())
    {
        counts[event::LAPTOP_DISPERSAL] += 1;
    }
    let idle = s.cf_active[e] == 0 && s.lf_active[e] == 0;
    if idle && p.p_crowd_formation > 0.0 && rng.get().chance(p.p_crowd_formation) {
        match crowd_formation(p, s, e, rng.get()) {
            Start::Started => counts[event::CROWD_FORMATION_START] += 1,
            Start::Blocked => counts[event::CROWD_FORMATION_GAVE_UP] += 1,
            Start::Impossible => {}
        }
    }
    let idle = s.cf_active[e] == 0 && s.lf_active[e] == 0;
    if idle && p.p_laptop_formation > 0.0 && rng.get().chance(p.p_laptop_formation) {
        match laptop_formation(p, s, e, rng.get()) {
            Start::Started => counts[event::LAPTOP_FORMATION_START] += 1,
            Start::Blocked => counts[event::LAPTOP_FORMATION_BLOCKED] += 1,
            Start::Impossible => {}
        }
    }
}

/// Outcome of an attempt to start a formation.
enum Start {
    Started,
    Blocked,
    Impossible,
}

/// Local indices of the dispersable groups of `kind`, in group order.
fn dispersable_groups(s: &StateChunk, e: usize, kind: u32) -> Fixed<u32, MAX_PERMUTE> {
    let gb = e * s.strides.groups;
    let mut out = Fixed::default();
    for g in 0..s.n_groups[e] as usize {
        if s.g_kind[gb + g] == kind && s.g_dispersable[gb + g] != 0 {
            out.push(g as u32);
        }
    }
    out
}

/// Pick the kind (standing or moving with equal chance), then a dispersable group of it, then a
/// coin per member; false when there is no such group.
fn crowd_dispersal(p: &StepParams, s: &mut StateChunk, e: usize, rng: &mut RngStream) -> bool {
    let kind = if rng.below(2) == 0 {
        group_kind::STANDING
    } else {
        group_kind::MOVING
    };
    let groups = dispersable_groups(s, e, kind);
    if groups.is_empty() {
        return false;
    }
    let g = groups[rng.below(groups.len() as u32) as usize] as usize;
    let n = s.g_count[e * s.strides.groups + g] as usize;
    let mut stays = [false; MAX_GROUP];
    for stay in stays.iter_mut().take(n) {
        *stay = rng.chance(0.5);
    }
    let became_standing = rng.chance(0.5);
    disperse_group(p, s, e, g, &stays[..n], became_standing, rng);
    true
}

/// Apply a crowd dispersal of local group `g`. `stays[k]`: member k keeps its place (for a
/// standing group, "becomes static"). Standing: with at most one stayer the group dissolves
/// (stayers become lone static humans, the others lone walkers); otherwise the leavers walk away.
/// Moving: leavers walk away; with at most one stayer it becomes a lone static human and the
/// group dissolves; otherwise the stayers stop and, if `became_standing`, the group stands.
pub fn disperse_group(
    p: &StepParams,
    s: &mut StateChunk,
    e: usize,
    g: usize,
    stays: &[bool],
    became_standing: bool,
    rng: &mut RngStream,
) {
    let gg = e * s.strides.groups + g;
    let first = e * s.strides.humans + s.g_first[gg] as usize;
    let stayers = stays.iter().filter(|&&x| x).count();
    let dissolve = stayers <= 1;
    for (k, &stay) in stays.iter().enumerate() {
        let i = first + k;
        if !stay {
            regroup::to_lone_walker(p, s, e, i, rng);
        } else if dissolve {
            regroup::to_lone_static(s, e, i);
        } else if s.g_kind[gg] == group_kind::MOVING {
            regroup::stop(s, i);
        }
    }
    if dissolve {
        s.g_kind[gg] = group_kind::DISSOLVED;
    } else if s.g_kind[gg] == group_kind::MOVING && became_standing {
        s.g_kind[gg] = group_kind::STANDING;
        s.g_seq[gg] = regroup::next_seq(s, e);
        for (k, &stay) in stays.iter().enumerate() {
            if stay {
                s.h_role[first + k] = role::STANDING_GROUP;
            }
        }
    }
    regroup::canonicalize(p, s, e);
}

/// A random dispersable laptop user leaves; false when there is none.
fn laptop_dispersal(p: &StepParams, s: &mut StateChunk, e: usize, rng: &mut RngStream) -> bool {
    let ub = e * s.strides.laptop_users;
    let mut users: Fixed<u32, MAX_PERMUTE> = Fixed::default();
    for u in 0..s.n_laptop_users[e] as usize {
        if s.lu_dispersable[ub + u] != 0 {
            users.push(u as u32);
        }
    }
    if users.is_empty() {
        return false;
    }
    let u = users[rng.below(users.len() as u32) as usize] as usize;
    end_laptop_use(p, s, e, u, rng);
    true
}

/// Apply a laptop-use dispersal of local user `u`: the human walks away with a new goal (keeping
/// its speed), the laptop becomes free at the end of the free list.
pub fn end_laptop_use(p: &StepParams, s: &mut StateChunk, e: usize, u: usize, rng: &mut RngStream) {
    let uu = e * s.strides.laptop_users + u;
    let i = e * s.strides.humans + s.lu_human[uu] as usize;
    let l = e * s.strides.laptops + s.lu_laptop[uu] as usize;
    regroup::to_lone_walker(p, s, e, i, rng);
    s.l_user[l] = NONE;
    s.l_seq[l] = regroup::next_seq(s, e);
    s.lu_human[uu] = NONE;
    regroup::canonicalize(p, s, e);
}

/// Lone walkers that are not heading anywhere special, in slot order.
fn free_walkers(s: &StateChunk, e: usize) -> Fixed<u32, MAX_PERMUTE> {
    let hb = e * s.strides.humans;
    let mut out = Fixed::default();
    for k in 0..s.n_humans[e] as usize {
        if s.h_role[hb + k] == role::DYNAMIC && s.h_forming[hb + k] == forming::NONE {
            out.push(k as u32);
        }
    }
    out
}

/// Draw a crowd size, pick that many walkers, and look for a free spot for the crowd (standing
/// layout, checked against every entity and goal).
fn crowd_formation(p: &StepParams, s: &mut StateChunk, e: usize, rng: &mut RngStream) -> Start {
    let [lo, hi] = p.count_range(crate::params::count::GROUP_SIZE);
    let n = rng.randint(lo, hi) as usize;
    let mut walkers = free_walkers(s, e);
    if n < 2 || walkers.len() < n {
        return Start::Impossible;
    }
    let mut chosen: Fixed<u32, MAX_GROUP> = Fixed::default();
    for _ in 0..n {
        let k = rng.below(walkers.len() as u32) as usize;
        chosen.push(walkers[k]);
        walkers.remove(k);
    }
    let area = SamplingBox::new(p, s.map_x[e], s.map_y[e]);
    let mut poses: [Pose; MAX_GROUP] = [(0.0, 0.0, 0.0); MAX_GROUP];
    let found = (0..MAX_TRIES).any(|_| {
        let (cx, cy) = area.point(rng);
        place::group_layout(p, rng, cx, cy, n, true, &mut poses);
        poses[..n].iter().all(|&(x, y, _)| spot_free(p, s, e, x, y))
    });
    if !found {
        return Start::Blocked;
    }
    start_crowd_formation(s, e, chosen.as_slice(), &poses[..n]);
    Start::Started
}

/// Is a human-sized disc at (x, y) free of every entity and every goal?
fn spot_free(p: &StepParams, s: &StateChunk, e: usize, x: f32, y: f32) -> bool {
    let d = Disc {
        x,
        y,
        r: p.human_radius,
    };
    !super::world::blocks_goal(p, s, e, &Shape::Disc(d)) && !super::goals::touches_goal(p, s, e, &d)
}

/// Apply a crowd-formation start: the walkers `chosen` (local slots, in formation order) head for
/// `slots`; their goals become the slots and their policy ORCA.
pub fn start_crowd_formation(s: &mut StateChunk, e: usize, chosen: &[u32], slots: &[Pose]) {
    let hb = e * s.strides.humans;
    let sb = e * s.strides.group_size;
    let (mut cx, mut cy) = (0.0f32, 0.0f32);
    for (k, (&h, &(x, y, theta))) in chosen.iter().zip(slots).enumerate() {
        let i = hb + h as usize;
        s.cf_human[sb + k] = h;
        s.cf_slot_x[sb + k] = x;
        s.cf_slot_y[sb + k] = y;
        s.cf_slot_theta[sb + k] = theta;
        s.h_goal_x[i] = x;
        s.h_goal_y[i] = y;
        s.h_forming[i] = forming::CROWD;
        s.h_policy[i] = policy::ORCA;
        cx += x;
        cy += y;
    }
    let n = chosen.len();
    s.cf_x[e] = cx / n as f32;
    s.cf_y[e] = cy / n as f32;
    s.cf_count[e] = n as u32;
    s.cf_close_steps[e] = 0;
    s.cf_active[e] = 1;
}

/// Pick a free laptop and a walker; if the seat is free the walker heads for it, otherwise the
/// formation is blocked (and the walker's policy still becomes ORCA, as in 0.1.1).
fn laptop_formation(p: &StepParams, s: &mut StateChunk, e: usize, rng: &mut RngStream) -> Start {
    let lb = e * s.strides.laptops;
    let mut laptops: Fixed<u32, MAX_PERMUTE> = Fixed::default();
    for l in 0..s.n_laptops[e] as usize {
        if s.l_user[lb + l] == NONE {
            laptops.push(l as u32);
        }
    }
    let walkers = free_walkers(s, e);
    if laptops.is_empty() || walkers.is_empty() {
        return Start::Impossible;
    }
    let l = laptops[rng.below(laptops.len() as u32) as usize];
    let h = walkers[rng.below(walkers.len() as u32) as usize];
    if send_to_laptop(p, s, e, h, l) {
        Start::Started
    } else {
        Start::Blocked
    }
}

/// Send walker `h` (local slot) to the seat of free laptop `l`: its policy becomes ORCA either
/// way (as in 0.1.1); if the seat is free it heads there (true), else nothing starts (false).
pub fn send_to_laptop(p: &StepParams, s: &mut StateChunk, e: usize, h: u32, l: u32) -> bool {
    let i = e * s.strides.humans + h as usize;
    s.h_policy[i] = policy::ORCA;
    let ll = e * s.strides.laptops + l as usize;
    let seat = place::seat(p, s.l_x[ll], s.l_y[ll], s.l_theta[ll]);
    if !spot_free(p, s, e, seat.0, seat.1) {
        return false;
    }
    start_laptop_formation(s, e, h, l, seat);
    true
}

/// Apply a laptop-use formation start: walker `h` (local slot) heads for the seat of laptop `l`.
pub fn start_laptop_formation(s: &mut StateChunk, e: usize, h: u32, l: u32, seat: Pose) {
    let i = e * s.strides.humans + h as usize;
    s.h_goal_x[i] = seat.0;
    s.h_goal_y[i] = seat.1;
    s.h_forming[i] = forming::LAPTOP;
    s.h_policy[i] = policy::ORCA;
    s.lf_human[e] = h;
    s.lf_laptop[e] = l;
    s.lf_seat_x[e] = seat.0;
    s.lf_seat_y[e] = seat.1;
    s.lf_seat_theta[e] = seat.2;
    s.lf_active[e] = 1;
}
