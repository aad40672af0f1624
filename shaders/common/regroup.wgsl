// requires: common/goal_sampling.wgsl
// requires: common/orca_obstacles.wgsl
//
// Twin of src/systems/regroup.rs: what the social events do to the lists of 0.1.1 (lone static
// humans, lone walkers, moving groups, standing groups, laptop users, free laptops) and how the
// slots follow: `regroup_next_seq`, `regroup_number_lists`, `regroup_to_lone_walker`,
// `regroup_to_lone_static`, `regroup_stop` and `regroup_canonicalize` (stable insertion sorts of
// the slots back into observation order, the permutation of every column of each slot kind by the
// prelude's generated `state_permute_*`, the remapping of every slot index, the recount, the
// renumbering of the lists; the rebuild of the ORCA obstacles that Rust runs there follows in the
// pass's `rebuild` dispatch, `regroup_rebuild_queued`). Library file (no entry point,
// reads and writes the prelude's `sf`/`su`). Same operations in the same order as the Rust file;
// change both in the same commit. `i` arguments are global human slots (as the Rust `usize`
// slots), `e` the environment.
//
// The permutations, their keys and inverses are PERMUTE_CAP long (a size class of the largest capacity
// of humans, groups, laptop users and laptops), so they cannot overflow. Every large local lives
// in one place (one canonicalize per call site): Mesa inlines
// every call, and llvmpipe's compile time grows quickly with the private memory of a shader.

// A permutation of slot indices (Rust `Perm`).
struct RegroupPerm {
    len: u32,
    v: array<u32, PERMUTE_CAP>,
}

// Rust `next_seq`: the next list position of environment e.
fn regroup_next_seq(e: u32) -> u32 {
    let v = su[batch.c_seq_next + e];
    su[batch.c_seq_next + e] = v + 1u;
    return v;
}

// Rust `number_lists`: list positions from the current slot order.
fn regroup_number_lists(e: u32) {
    for (var k = 0u; k < su[batch.c_n_humans + e]; k++) {
        su[batch.c_h_seq + at_human(e, k)] = k;
    }
    for (var k = 0u; k < su[batch.c_n_groups + e]; k++) {
        su[batch.c_g_seq + at_group(e, k)] = k;
    }
    for (var k = 0u; k < su[batch.c_n_laptops + e]; k++) {
        su[batch.c_l_seq + at_laptop(e, k)] = k;
    }
    for (var k = 0u; k < su[batch.c_n_laptop_users + e]; k++) {
        su[batch.c_lu_seq + at_laptop_user(e, k)] = k;
    }
    su[batch.c_seq_next + e] = su[batch.c_n_humans + e] + su[batch.c_n_groups + e] + su[batch.c_n_laptops + e]
        + su[batch.c_n_laptop_users + e];
}

// Rust `to_lone_walker`: human slot i becomes a lone walker at the end of the walkers' list, with
// a new goal if one is free.
fn regroup_to_lone_walker(e: u32, i: u32, rng: ptr<function, RngStream>) {
    su[batch.c_h_role + i] = ROLE_DYNAMIC;
    su[batch.c_h_group + i] = NONE;
    su[batch.c_h_laptop_user + i] = NONE;
    su[batch.c_h_forming + i] = FORMING_NONE;
    su[batch.c_h_seq + i] = regroup_next_seq(e);
    let g = goals_sample_goal(e, rng, params.human_goal_radius);
    if (g.found) {
        sf[batch.c_h_goal_x + i] = g.disc.x;
        sf[batch.c_h_goal_y + i] = g.disc.y;
    }
}

// Rust `stop`: speed 0 (and world velocity 0) for human slot i.
fn regroup_stop(i: u32) {
    sf[batch.c_h_speed + i] = 0.0;
    sf[batch.c_h_vx + i] = 0.0;
    sf[batch.c_h_vy + i] = 0.0;
}

// Rust `to_lone_static`: human slot i becomes a lone static human at the end of their list.
fn regroup_to_lone_static(e: u32, i: u32) {
    su[batch.c_h_role + i] = ROLE_STATIC;
    su[batch.c_h_group + i] = NONE;
    su[batch.c_h_laptop_user + i] = NONE;
    su[batch.c_h_forming + i] = FORMING_NONE;
    su[batch.c_h_seq + i] = regroup_next_seq(e);
    regroup_stop(i);
    sf[batch.c_h_goal_x + i] = sf[batch.c_h_x + i];
    sf[batch.c_h_goal_y + i] = sf[batch.c_h_y + i];
}

// Lexicographic `a < b` of the Rust tuple keys (shorter tuples padded with zeros).
fn regroup_key_less(a: vec4<u32>, b: vec4<u32>) -> bool {
    if (a.x != b.x) {
        return a.x < b.x;
    }
    if (a.y != b.y) {
        return a.y < b.y;
    }
    if (a.z != b.z) {
        return a.z < b.z;
    }
    return a.w < b.w;
}

// The sort key of slot k of kind `kind` (0 groups, 1 laptop users, 2 humans, 3 laptops) of
// environment e: Rust `sorted_groups`' (group kind, list position), `sorted_users`' (ended,
// list position), `sorted_humans`' (lone static, lone walkers, group members in their groups'
// order, laptop users; then list position) and `sorted_laptops`' (free laptops in list order,
// then those in use in their users' order).
fn regroup_key(e: u32, kind: u32, k: u32) -> vec4<u32> {
    if (kind == 0u) {
        let g = at_group(e, k);
        return vec4<u32>(su[batch.c_g_kind + g], su[batch.c_g_seq + g], 0u, 0u);
    }
    if (kind == 1u) {
        let u = at_laptop_user(e, k);
        return vec4<u32>(u32(su[batch.c_lu_human + u] == NONE), su[batch.c_lu_seq + u], 0u, 0u);
    }
    if (kind == 2u) {
        let i = at_human(e, k);
        let r = su[batch.c_h_role + i];
        let seq = su[batch.c_h_seq + i];
        if (r == ROLE_STATIC) {
            return vec4<u32>(0u, 0u, 0u, seq);
        } else if (r == ROLE_DYNAMIC) {
            return vec4<u32>(1u, 0u, 0u, seq);
        } else if (r == ROLE_MOVING_GROUP || r == ROLE_STANDING_GROUP) {
            let g = at_group(e, su[batch.c_h_group + i]);
            return vec4<u32>(2u, su[batch.c_g_kind + g], su[batch.c_g_seq + g], seq);
        }
        return vec4<u32>(3u, 0u, su[batch.c_lu_seq + at_laptop_user(e, su[batch.c_h_laptop_user + i])], seq);
    }
    let l = at_laptop(e, k);
    let u = su[batch.c_l_user + l];
    if (u == NONE) {
        return vec4<u32>(0u, su[batch.c_l_seq + l], 0u, 0u);
    }
    return vec4<u32>(1u, su[batch.c_lu_seq + at_laptop_user(e, u)], 0u, 0u);
}

// Whether sorted entry `old` of kind `kind` is kept: Rust `sorted_groups` and `sorted_users`
// keep the leading live entries (dissolved groups and ended uses sort last).
fn regroup_live(e: u32, kind: u32, old: u32) -> bool {
    if (kind == 0u) {
        return su[batch.c_g_kind + at_group(e, old)] != GROUP_DISSOLVED;
    }
    if (kind == 1u) {
        return su[batch.c_lu_human + at_laptop_user(e, old)] != NONE;
    }
    return true;
}

// The slot count of kind `kind` (as `regroup_key`) of environment e.
fn regroup_count(e: u32, kind: u32) -> u32 {
    if (kind == 0u) {
        return su[batch.c_n_groups + e];
    }
    if (kind == 1u) {
        return su[batch.c_n_laptop_users + e];
    }
    if (kind == 2u) {
        return su[batch.c_n_humans + e];
    }
    return su[batch.c_n_laptops + e];
}

// Rust `sorted_groups`, `sorted_users`, `sorted_humans` or `sorted_laptops` (index `kind` of
// `regroup_key`): Rust `sort_by_key` (indices sorted by key, stable insertion sort with the same
// swaps; the keys are sorted in place, which is Rust's `keys` list), then the truncation to the
// live entries.
fn regroup_sorted(e: u32, kind: u32) -> RegroupPerm {
    let n = regroup_count(e, kind);
    var keys: array<vec4<u32>, PERMUTE_CAP>;
    var perm: RegroupPerm;
    perm.len = 0u;
    for (var k = 0u; k < n; k++) {
        let kk = regroup_key(e, kind, k);
        perm.v[k] = k;
        keys[k] = kk;
        perm.len = k + 1u;
        var j = k;
        while (j > 0u) {
            if (!regroup_key_less(kk, keys[j - 1u])) {
                break;
            }
            let p = perm.v[j];
            perm.v[j] = perm.v[j - 1u];
            perm.v[j - 1u] = p;
            let s = keys[j];
            keys[j] = keys[j - 1u];
            keys[j - 1u] = s;
            j -= 1u;
        }
    }
    var live = 0u;
    while (live < perm.len) {
        if (!regroup_live(e, kind, perm.v[live])) {
            break;
        }
        live += 1u;
    }
    perm.len = live;
    return perm;
}

// Rust `inverse`: old index -> new index of `perm` over n entries (NONE for dropped ones).
fn regroup_inverse(perm: RegroupPerm, n: u32) -> array<u32, PERMUTE_CAP> {
    var inv: array<u32, PERMUTE_CAP>;
    for (var k = 0u; k < n; k++) {
        inv[k] = NONE;
    }
    for (var k = 0u; k < perm.len; k++) {
        inv[perm.v[k]] = k;
    }
    return inv;
}

// Rust `remap`'s `map`.
fn regroup_map(inv: ptr<function, array<u32, PERMUTE_CAP>>, v: u32) -> u32 {
    if (v == NONE) {
        return NONE;
    }
    return (*inv)[v];
}

// Rust `remap`.
fn regroup_remap(e: u32, perms: ptr<function, array<RegroupPerm, 4>>) {
    let n_humans = su[batch.c_n_humans + e];
    var inv_g = regroup_inverse((*perms)[0], su[batch.c_n_groups + e]);
    var inv_u = regroup_inverse((*perms)[1], su[batch.c_n_laptop_users + e]);
    var inv_h = regroup_inverse((*perms)[2], n_humans);
    var inv_l = regroup_inverse((*perms)[3], su[batch.c_n_laptops + e]);
    var n_static = 0u;
    var n_dynamic = 0u;
    for (var i = at_human(e, 0u); i < at_human(e, n_humans); i += batch.k_human) {
        su[batch.c_h_group + i] = regroup_map(&inv_g, su[batch.c_h_group + i]);
        su[batch.c_h_laptop_user + i] = regroup_map(&inv_u, su[batch.c_h_laptop_user + i]);
        n_static += u32(su[batch.c_h_role + i] == ROLE_STATIC);
        n_dynamic += u32(su[batch.c_h_role + i] == ROLE_DYNAMIC);
    }
    su[batch.c_n_static + e] = n_static;
    su[batch.c_n_dynamic + e] = n_dynamic;
    su[batch.c_n_groups + e] = (*perms)[0].len;
    su[batch.c_n_laptop_users + e] = (*perms)[1].len;
    for (var u = at_laptop_user(e, 0u); u < at_laptop_user(e, (*perms)[1].len); u += batch.k_laptop_user) {
        su[batch.c_lu_human + u] = regroup_map(&inv_h, su[batch.c_lu_human + u]);
        su[batch.c_lu_laptop + u] = regroup_map(&inv_l, su[batch.c_lu_laptop + u]);
    }
    for (var l = at_laptop(e, 0u); l < at_laptop(e, su[batch.c_n_laptops + e]); l += batch.k_laptop) {
        su[batch.c_l_user + l] = regroup_map(&inv_u, su[batch.c_l_user + l]);
    }
    // Members are consecutive now: each group's first slot and count from the humans.
    for (var g = at_group(e, 0u); g < at_group(e, (*perms)[0].len); g += batch.k_group) {
        su[batch.c_g_count + g] = 0u;
    }
    for (var k = 0u; k < n_humans; k++) {
        let g = su[batch.c_h_group + at_human(e, k)];
        if (g != NONE) {
            let gg = at_group(e, g);
            if (su[batch.c_g_count + gg] == 0u) {
                su[batch.c_g_first + gg] = k;
            }
            su[batch.c_g_count + gg] += 1u;
        }
    }
    for (var k = at_crowd_slot(e, 0u); k < at_crowd_slot(e, su[batch.c_cf_count + e]); k += batch.k_crowd_slot) {
        su[batch.c_cf_human + k] = regroup_map(&inv_h, su[batch.c_cf_human + k]);
    }
    if (su[batch.c_lf_active + e] != 0u) {
        su[batch.c_lf_human + e] = regroup_map(&inv_h, su[batch.c_lf_human + e]);
        su[batch.c_lf_laptop + e] = regroup_map(&inv_l, su[batch.c_lf_laptop + e]);
    }
}

// Rust `canonicalize`: slots back into observation order, dissolved groups and ended laptop uses
// dropped, every slot index remapped, counts and list positions renewed, obstacles rebuilt.
fn regroup_canonicalize(e: u32) {
    var perms: array<RegroupPerm, 4>;
    perms[0] = regroup_sorted(e, 0u);
    perms[1] = regroup_sorted(e, 1u);
    perms[2] = regroup_sorted(e, 2u);
    perms[3] = regroup_sorted(e, 3u);
    let n_groups = su[batch.c_n_groups + e];
    let n_users = su[batch.c_n_laptop_users + e];
    state_permute_groups(e, perms[0].v, perms[0].len, n_groups);
    state_permute_laptop_users(e, perms[1].v, perms[1].len, n_users);
    state_permute_humans(e, perms[2].v, perms[2].len, su[batch.c_n_humans + e]);
    state_permute_laptops(e, perms[3].v, perms[3].len, su[batch.c_n_laptops + e]);
    regroup_remap(e, &perms);
    // Compact list positions, as a loaded document numbers them.
    regroup_number_lists(e);
    // Rust rebuilds the obstacles here; on the GPU the pass's `rebuild` dispatch does, after
    // `main` (`regroup_rebuild_queued`): nothing before it reads the `ov_*` columns.
    su[batch.c_obstacles_dirty + e] = 1u;
}

// The ORCA obstacle rebuild of entry `k` of queue `queue` (a pass's environments, which its
// `main` may have regrouped), if it has one and its obstacles are dirty; whether it has one. The
// rebuild entry points of the passes that regroup are generated over it (src/backend/wgsl.rs,
// `rebuild_entries`).
fn regroup_rebuild_queued(queue: u32, k: u32) -> bool {
    let e = rare_env(queue, k);
    if (e == NONE) {
        return false;
    }
    orca_obstacles_rebuild_if_dirty(e);
    return true;
}
