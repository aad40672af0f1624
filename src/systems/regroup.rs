//! Regrouping: what the social events do to the lists of 0.1.1 (lone static humans, lone walkers,
//! moving groups, standing groups, laptop users, free laptops) and how the slots follow.
//!
//! An event changes roles in place and gives every entry it appends to a list the next list
//! position (`*_seq`, from `seq_next`); [`canonicalize`] then sorts the slots back into
//! observation order (state module docs) and remaps every index that points at a slot: a
//! human's group and laptop user, a group's first member, a laptop user's human and laptop, a
//! laptop's user, the humans and laptop of a formation in progress. Events are rare, so this
//! simple sort-and-permute costs nothing on average.

use crate::fixed::Fixed;
use crate::limits::MAX_PERMUTE;
use crate::params::StepParams;
use crate::rng::RngStream;
use crate::state::{NONE, StateChunk, forming, group_kind, role};

/// The next list position of environment `e`.
pub fn next_seq(s: &mut StateChunk, e: usize) -> u32 {
    let v = s.seq_next[e];
    s.seq_next[e] = v + 1;
    v
}

/// Number list positions from the current slot order (after a reset or a loaded document).
pub fn number_lists(s: &mut StateChunk, e: usize) {
    let (hb, gb, lb, ub) = bases(s, e);
    for k in 0..s.n_humans[e] as usize {
        s.h_seq[hb + k] = k as u32;
    }
    for k in 0..s.n_groups[e] as usize {
        s.g_seq[gb + k] = k as u32;
    }
    for k in 0..s.n_laptops[e] as usize {
        s.l_seq[lb + k] = k as u32;
    }
    for k in 0..s.n_laptop_users[e] as usize {
        s.lu_seq[ub + k] = k as u32;
    }
    s.seq_next[e] = s.n_humans[e] + s.n_groups[e] + s.n_laptops[e] + s.n_laptop_users[e];
}

fn bases(s: &StateChunk, e: usize) -> (usize, usize, usize, usize) {
    let c = &s.strides;
    (
        e * c.humans,
        e * c.groups,
        e * c.laptops,
        e * c.laptop_users,
    )
}

/// Human slot `i` becomes a lone walker at the end of the walkers' list, with a new goal if one
/// is free (else it keeps its goal, as 0.1.1 does when goal sampling times out).
pub fn to_lone_walker(p: &StepParams, s: &mut StateChunk, e: usize, i: usize, rng: &mut RngStream) {
    s.h_role[i] = role::DYNAMIC;
    s.h_group[i] = NONE;
    s.h_laptop_user[i] = NONE;
    s.h_forming[i] = forming::NONE;
    s.h_seq[i] = next_seq(s, e);
    if let Some(g) = super::goals::sample_goal(p, s, e, rng, p.human_goal_radius) {
        s.h_goal_x[i] = g.x;
        s.h_goal_y[i] = g.y;
    }
}

/// Human slot `i` becomes a lone static human at the end of their list: speed 0, its goal its
/// own position.
pub fn to_lone_static(s: &mut StateChunk, e: usize, i: usize) {
    s.h_role[i] = role::STATIC;
    s.h_group[i] = NONE;
    s.h_laptop_user[i] = NONE;
    s.h_forming[i] = forming::NONE;
    s.h_seq[i] = next_seq(s, e);
    stop(s, i);
    s.h_goal_x[i] = s.h_x[i];
    s.h_goal_y[i] = s.h_y[i];
}

/// Speed 0 (and world velocity 0) for human slot `i`.
pub fn stop(s: &mut StateChunk, i: usize) {
    s.h_speed[i] = 0.0;
    s.h_vx[i] = 0.0;
    s.h_vy[i] = 0.0;
}

/// Sort the slots of environment `e` back into observation order after an event, drop dissolved
/// groups and ended laptop uses, remap every slot index, recount, and rebuild the ORCA obstacles
/// (standing groups and laptop users are obstacles).
pub fn canonicalize(p: &StepParams, s: &mut StateChunk, e: usize) {
    let group_perm = sorted_groups(s, e);
    let user_perm = sorted_users(s, e);
    let human_perm = sorted_humans(s, e);
    let laptop_perm = sorted_laptops(s, e);
    let (n_groups, n_users) = (s.n_groups[e] as usize, s.n_laptop_users[e] as usize);
    s.permute("group", e, group_perm.as_slice(), n_groups);
    s.permute("laptop_user", e, user_perm.as_slice(), n_users);
    s.permute("human", e, human_perm.as_slice(), s.n_humans[e] as usize);
    s.permute("laptop", e, laptop_perm.as_slice(), s.n_laptops[e] as usize);
    remap(s, e, &human_perm, &group_perm, &user_perm, &laptop_perm);
    // Compact list positions, as a loaded document numbers them, so that a state saved and
    // loaded after an event is the same state.
    number_lists(s, e);
    s.obstacles_dirty[e] = 1;
    // A set too large for the capacity (overlapping obstacles loaded or edited into the state)
    // leaves the flag at `OBSTACLES_FAILED` and the columns poisoned, as on the GPU.
    super::orca_obstacles::rebuild_if_dirty(p, s, e);
}

type Perm = Fixed<u32, MAX_PERMUTE>;

/// Indices `0..n` sorted by `key` (stable: insertion sort, n is small).
fn sort_by_key<K: PartialOrd + Copy + Default>(n: usize, key: impl Fn(usize) -> K) -> Perm {
    let mut keys: Fixed<K, MAX_PERMUTE> = Fixed::default();
    let mut perm = Perm::default();
    for k in 0..n {
        let kk = key(k);
        perm.push(k as u32);
        keys.push(kk);
        let mut j = k;
        while j > 0 && kk < keys[j - 1] {
            perm.swap(j, j - 1);
            keys.swap(j, j - 1);
            j -= 1;
        }
    }
    perm
}

/// Live groups, moving ones first, each kind in list order.
fn sorted_groups(s: &StateChunk, e: usize) -> Perm {
    let (_, gb, _, _) = bases(s, e);
    let mut perm = sort_by_key(s.n_groups[e] as usize, |g| {
        (s.g_kind[gb + g], s.g_seq[gb + g])
    });
    let live = perm
        .as_slice()
        .iter()
        .take_while(|&&g| s.g_kind[gb + g as usize] != group_kind::DISSOLVED)
        .count();
    perm.truncate(live);
    perm
}

/// Laptop users still seated, in list order.
fn sorted_users(s: &StateChunk, e: usize) -> Perm {
    let (_, _, _, ub) = bases(s, e);
    let mut perm = sort_by_key(s.n_laptop_users[e] as usize, |u| {
        (u32::from(s.lu_human[ub + u] == NONE), s.lu_seq[ub + u])
    });
    let live = perm
        .as_slice()
        .iter()
        .take_while(|&&u| s.lu_human[ub + u as usize] != NONE)
        .count();
    perm.truncate(live);
    perm
}

/// Humans: lone static, lone walkers, group members (groups in their new order), laptop users.
fn sorted_humans(s: &StateChunk, e: usize) -> Perm {
    let (hb, gb, _, ub) = bases(s, e);
    sort_by_key(s.n_humans[e] as usize, |k| {
        let i = hb + k;
        match s.h_role[i] {
            role::STATIC => (0, 0, 0, s.h_seq[i]),
            role::DYNAMIC => (1, 0, 0, s.h_seq[i]),
            role::MOVING_GROUP | role::STANDING_GROUP => {
                let g = gb + s.h_group[i] as usize;
                (2, s.g_kind[g], s.g_seq[g], s.h_seq[i])
            }
            _ => (3, 0, s.lu_seq[ub + s.h_laptop_user[i] as usize], s.h_seq[i]),
        }
    })
}

/// Laptops: free ones in list order, then those in use in their users' order.
fn sorted_laptops(s: &StateChunk, e: usize) -> Perm {
    let (_, _, lb, ub) = bases(s, e);
    sort_by_key(s.n_laptops[e] as usize, |l| match s.l_user[lb + l] {
        NONE => (0, s.l_seq[lb + l]),
        u => (1, s.lu_seq[ub + u as usize]),
    })
}

/// Old index → new index of a permutation (`NONE` for dropped entries).
fn inverse(perm: &Perm, n: usize) -> Fixed<u32, MAX_PERMUTE> {
    let mut inv = Fixed::default();
    for _ in 0..n {
        inv.push(NONE);
    }
    for (new, &old) in perm.as_slice().iter().enumerate() {
        inv.set(old as usize, new as u32);
    }
    inv
}

fn remap(s: &mut StateChunk, e: usize, humans: &Perm, groups: &Perm, users: &Perm, laptops: &Perm) {
    let (hb, gb, lb, ub) = bases(s, e);
    let n_groups_before = s.n_groups[e] as usize;
    let n_users_before = s.n_laptop_users[e] as usize;
    let inv_h = inverse(humans, s.n_humans[e] as usize);
    let inv_g = inverse(groups, n_groups_before);
    let inv_u = inverse(users, n_users_before);
    let inv_l = inverse(laptops, s.n_laptops[e] as usize);
    let map =
        |inv: &Fixed<u32, MAX_PERMUTE>, v: u32| if v == NONE { NONE } else { inv[v as usize] };
    let (mut n_static, mut n_dynamic) = (0, 0);
    for i in hb..hb + s.n_humans[e] as usize {
        s.h_group[i] = map(&inv_g, s.h_group[i]);
        s.h_laptop_user[i] = map(&inv_u, s.h_laptop_user[i]);
        n_static += u32::from(s.h_role[i] == role::STATIC);
        n_dynamic += u32::from(s.h_role[i] == role::DYNAMIC);
    }
    s.n_static[e] = n_static;
    s.n_dynamic[e] = n_dynamic;
    s.n_groups[e] = groups.len() as u32;
    s.n_laptop_users[e] = users.len() as u32;
    for u in ub..ub + users.len() {
        s.lu_human[u] = map(&inv_h, s.lu_human[u]);
        s.lu_laptop[u] = map(&inv_l, s.lu_laptop[u]);
    }
    for l in lb..lb + s.n_laptops[e] as usize {
        s.l_user[l] = map(&inv_u, s.l_user[l]);
    }
    // Members are consecutive now: each group's first slot and count from the humans.
    for g in gb..gb + groups.len() {
        s.g_count[g] = 0;
    }
    for k in 0..s.n_humans[e] as usize {
        let g = s.h_group[hb + k];
        if g != NONE {
            let g = gb + g as usize;
            if s.g_count[g] == 0 {
                s.g_first[g] = k as u32;
            }
            s.g_count[g] += 1;
        }
    }
    let sb = e * s.strides.group_size;
    for k in sb..sb + s.cf_count[e] as usize {
        s.cf_human[k] = map(&inv_h, s.cf_human[k]);
    }
    if s.lf_active[e] != 0 {
        s.lf_human[e] = map(&inv_h, s.lf_human[e]);
        s.lf_laptop[e] = map(&inv_l, s.lf_laptop[e]);
    }
}
