// requires: common/regroup.wgsl
//
// Twin of src/systems/social_events.rs (stage `social_events`, docs/spec.md 4.1 step 12, 4.5): the
// random social events, in 0.1.1's order: crowd dispersal, laptop-use dispersal, crowd formation,
// laptop-use formation, each counted in the `events` output when it happens. Nothing is drawn in
// replay mode. Same operations and draws in the same order as the Rust file; change both in the
// same commit. Local slot lists (`free_walkers`, the dispersable groups and users, the free
// laptops) are PERMUTE_CAP long (the largest of those capacities); a group's members and poses
// place_group_cap() (common/place.wgsl). A dispersal regroups the environment
// (`regroup_canonicalize`) at the end of the Rust `disperse_group` and `end_laptop_use`; here
// `main` calls it right after them, from one place for each way of taking an environment (Mesa
// inlines every call, and each copy of the regrouping costs llvmpipe compile time): a lane, or a
// workgroup whose lanes share the regrouping (REGROUP_LANES, `regroup_canonicalize_on_lanes`).
//
// Rare work out of the hot pass (the stage's GpuPlan: backend::schedule::has_rare_work):
// `queue_work`, over every environment, draws the events' chances in `main`'s order up to the first
// that hits and queues the environments where one does; `main` runs one lane per queued environment
// (or one workgroup: REGROUP_LANES) and redraws from the start (the step's stream is keyed by the
// tick, so it draws the same numbers). Where no chance hits, `main` would have changed nothing, and
// the environment is not queued. The ORCA obstacle rebuild that ends a regrouping is queued
// (RARE_REBUILD) for one dispatch after the submit's last stage, `formation`'s regroupings with
// these (`rebuild` or `rebuild_in_workgroups`, generated: backend::schedule::regroups).

// Outcome of an attempt to start a formation (Rust `Start`).
const START_STARTED: u32 = 0u;
const START_BLOCKED: u32 = 1u;
const START_IMPOSSIBLE: u32 = 2u;

struct SlotList {
    len: u32,
    v: array<u32, PERMUTE_CAP>,
}

fn count_event(e: u32, ev: u32) {
    outu[batch.co_events + e * batch.so_events + ev] += 1u;
}

// Rust `dispersable_groups`: local indices of the dispersable groups of `kind`, in group order.
fn dispersable_groups(e: u32, kind: u32, out: ptr<function, SlotList>) {
    (*out).len = 0u;
    for (var g = 0u; g < su[batch.c_n_groups + e]; g++) {
        let gg = at_group(e, g);
        if (su[batch.c_g_kind + gg] == kind && su[batch.c_g_dispersable + gg] != 0u) {
            (*out).v[(*out).len] = g;
            (*out).len += 1u;
        }
    }
}

// Rust `disperse_group` for local group g; stays[k] for its n members.
fn disperse_group(
    e: u32,
    g: u32,
    stays: ptr<function, array<bool, PLACE_GROUP_ARRAY>>,
    n: u32,
    became_standing: bool,
    rng: ptr<function, RngStream>,
) {
    let gg = at_group(e, g);
    let first = su[batch.c_g_first + gg];
    var stayers = 0u;
    for (var k = 0u; k < n; k++) {
        stayers += u32((*stays)[k]);
    }
    let dissolve = stayers <= 1u;
    for (var k = 0u; k < n; k++) {
        let i = at_human(e, first + k);
        if (!(*stays)[k]) {
            regroup_to_lone_walker(e, i, rng);
        } else if (dissolve) {
            regroup_to_lone_static(e, i);
        } else if (su[batch.c_g_kind + gg] == GROUP_MOVING) {
            regroup_stop(i);
        }
    }
    if (dissolve) {
        su[batch.c_g_kind + gg] = GROUP_DISSOLVED;
    } else if (su[batch.c_g_kind + gg] == GROUP_MOVING && became_standing) {
        su[batch.c_g_kind + gg] = GROUP_STANDING;
        su[batch.c_g_seq + gg] = regroup_next_seq(e);
        for (var k = 0u; k < n; k++) {
            if ((*stays)[k]) {
                su[batch.c_h_role + at_human(e, first + k)] = ROLE_STANDING_GROUP;
            }
        }
    }
    // Rust: `regroup::canonicalize`, called by `main` (see the header).
}

// Rust `crowd_dispersal`.
fn crowd_dispersal(e: u32, rng: ptr<function, RngStream>) -> bool {
    var kind = GROUP_MOVING;
    if (rng_below(rng, 2u) == 0u) {
        kind = GROUP_STANDING;
    }
    var groups: SlotList;
    dispersable_groups(e, kind, &groups);
    if (groups.len == 0u) {
        return false;
    }
    let g = groups.v[rng_below(rng, groups.len)];
    let n = min(su[batch.c_g_count + at_group(e, g)], place_group_cap());
    var stays: array<bool, PLACE_GROUP_ARRAY>;
    for (var k = 0u; k < n; k++) {
        stays[k] = rng_chance(rng, 0.5);
    }
    let became_standing = rng_chance(rng, 0.5);
    disperse_group(e, g, &stays, n, became_standing, rng);
    return true;
}

// Rust `end_laptop_use` for local user u.
fn end_laptop_use(e: u32, u: u32, rng: ptr<function, RngStream>) {
    let uu = at_laptop_user(e, u);
    let i = at_human(e, su[batch.c_lu_human + uu]);
    let l = at_laptop(e, su[batch.c_lu_laptop + uu]);
    regroup_to_lone_walker(e, i, rng);
    su[batch.c_l_user + l] = NONE;
    su[batch.c_l_seq + l] = regroup_next_seq(e);
    su[batch.c_lu_human + uu] = NONE;
    // Rust: `regroup::canonicalize`, called by `main` (see the header).
}

// Rust `laptop_dispersal`.
fn laptop_dispersal(e: u32, rng: ptr<function, RngStream>) -> bool {
    var users: SlotList;
    for (var u = 0u; u < su[batch.c_n_laptop_users + e]; u++) {
        if (su[batch.c_lu_dispersable + at_laptop_user(e, u)] != 0u) {
            users.v[users.len] = u;
            users.len += 1u;
        }
    }
    if (users.len == 0u) {
        return false;
    }
    let u = users.v[rng_below(rng, users.len)];
    end_laptop_use(e, u, rng);
    return true;
}

// Rust `free_walkers`: lone walkers not heading anywhere special, in slot order (local slots).
fn free_walkers(e: u32, out: ptr<function, SlotList>) {
    (*out).len = 0u;
    for (var k = 0u; k < su[batch.c_n_humans + e]; k++) {
        let i = at_human(e, k);
        if (su[batch.c_h_role + i] == ROLE_DYNAMIC && su[batch.c_h_forming + i] == FORMING_NONE) {
            (*out).v[(*out).len] = k;
            (*out).len += 1u;
        }
    }
}

// Rust `spot_free`: is a human-sized disc at (x, y) free of every entity and every goal?
fn spot_free(e: u32, x: f32, y: f32) -> bool {
    let d = Disc(x, y, params.human_radius);
    return !world_blocks_goal(e, d) && !goals_touches_goal(e, d);
}

// Rust `start_crowd_formation`: the walkers chosen[0..n] (local slots) head for poses[0..n].
fn start_crowd_formation(
    e: u32,
    chosen: ptr<function, array<u32, PLACE_GROUP_ARRAY>>,
    poses: ptr<function, array<vec3<f32>, PLACE_GROUP_ARRAY>>,
    n: u32,
) {
    var cx = 0.0;
    var cy = 0.0;
    for (var k = 0u; k < n; k++) {
        let h = (*chosen)[k];
        let pose = (*poses)[k];
        let i = at_human(e, h);
        let s = at_crowd_slot(e, k);
        su[batch.c_cf_human + s] = h;
        sf[batch.c_cf_slot_x + s] = pose.x;
        sf[batch.c_cf_slot_y + s] = pose.y;
        sf[batch.c_cf_slot_theta + s] = pose.z;
        sf[batch.c_h_goal_x + i] = pose.x;
        sf[batch.c_h_goal_y + i] = pose.y;
        su[batch.c_h_forming + i] = FORMING_CROWD;
        su[batch.c_h_policy + i] = POLICY_ORCA;
        cx += pose.x;
        cy += pose.y;
    }
    sf[batch.c_cf_x + e] = cx / f32(n);
    sf[batch.c_cf_y + e] = cy / f32(n);
    su[batch.c_cf_count + e] = n;
    su[batch.c_cf_close_steps + e] = 0u;
    su[batch.c_cf_active + e] = 1u;
}

// Rust `crowd_formation`.
fn crowd_formation(e: u32, rng: ptr<function, RngStream>) -> u32 {
    let lo = params.counts[2u * COUNT_GROUP_SIZE];
    let hi = params.counts[2u * COUNT_GROUP_SIZE + 1u];
    let n_signed = rng_randint(rng, lo, hi);
    var walkers: SlotList;
    free_walkers(e, &walkers);
    // Rust casts a negative size to a huge usize, which no walker list reaches.
    if (n_signed < 2 || u32(n_signed) > walkers.len || u32(n_signed) > place_group_cap()) {
        return START_IMPOSSIBLE;
    }
    let n = u32(n_signed);
    var chosen: array<u32, PLACE_GROUP_ARRAY>;
    for (var c = 0u; c < n; c++) {
        let k = rng_below(rng, walkers.len);
        chosen[c] = walkers.v[k];
        // `walkers.remove(k)`.
        for (var j = k; j + 1u < walkers.len; j++) {
            walkers.v[j] = walkers.v[j + 1u];
        }
        walkers.len -= 1u;
    }
    let area = place_sampling_box(sf[batch.c_map_x + e], sf[batch.c_map_y + e]);
    var poses: array<vec3<f32>, PLACE_GROUP_ARRAY>;
    var found = false;
    for (var t = 0u; t < PLACE_MAX_TRIES; t++) {
        let c = place_box_point(area, rng);
        place_group_layout(rng, c.x, c.y, n, true, &poses);
        var all_free = true;
        for (var k = 0u; k < n; k++) {
            if (!spot_free(e, poses[k].x, poses[k].y)) {
                all_free = false;
                break;
            }
        }
        if (all_free) {
            found = true;
            break;
        }
    }
    if (!found) {
        return START_BLOCKED;
    }
    start_crowd_formation(e, &chosen, &poses, n);
    return START_STARTED;
}

// Rust `start_laptop_formation`: walker h (local slot) heads for the seat of laptop l.
fn start_laptop_formation(e: u32, h: u32, l: u32, seat: vec3<f32>) {
    let i = at_human(e, h);
    sf[batch.c_h_goal_x + i] = seat.x;
    sf[batch.c_h_goal_y + i] = seat.y;
    su[batch.c_h_forming + i] = FORMING_LAPTOP;
    su[batch.c_h_policy + i] = POLICY_ORCA;
    su[batch.c_lf_human + e] = h;
    su[batch.c_lf_laptop + e] = l;
    sf[batch.c_lf_seat_x + e] = seat.x;
    sf[batch.c_lf_seat_y + e] = seat.y;
    sf[batch.c_lf_seat_theta + e] = seat.z;
    su[batch.c_lf_active + e] = 1u;
}

// Rust `send_to_laptop`.
fn send_to_laptop(e: u32, h: u32, l: u32) -> bool {
    let i = at_human(e, h);
    su[batch.c_h_policy + i] = POLICY_ORCA;
    let ll = at_laptop(e, l);
    let seat = place_seat(sf[batch.c_l_x + ll], sf[batch.c_l_y + ll], sf[batch.c_l_theta + ll]);
    if (!spot_free(e, seat.x, seat.y)) {
        return false;
    }
    start_laptop_formation(e, h, l, seat);
    return true;
}

// Rust `laptop_formation`.
fn laptop_formation(e: u32, rng: ptr<function, RngStream>) -> u32 {
    var laptops: SlotList;
    for (var l = 0u; l < su[batch.c_n_laptops + e]; l++) {
        if (su[batch.c_l_user + at_laptop(e, l)] == NONE) {
            laptops.v[laptops.len] = l;
            laptops.len += 1u;
        }
    }
    var walkers: SlotList;
    free_walkers(e, &walkers);
    if (laptops.len == 0u || walkers.len == 0u) {
        return START_IMPOSSIBLE;
    }
    let l = laptops.v[rng_below(rng, laptops.len)];
    let h = walkers.v[rng_below(rng, walkers.len)];
    if (send_to_laptop(e, h, l)) {
        return START_STARTED;
    }
    return START_BLOCKED;
}

// Environment e's stream of the step's social events, keyed like the Rust LazyStream (which
// only defers the key hash to the first draw).
fn social_rng(e: u32) -> RngStream {
    return rng_new(
        su[batch.c_seed_lo + e],
        su[batch.c_seed_hi + e],
        rng_stream_id(STREAM_SOCIAL, su[batch.c_tick + e]),
    );
}

// Queue the environments where a chance of `main` hits (see the header): the same draws in the
// same order up to the first hit (`||` stops there). Nothing happens before a hit, so the
// forming flags `main` reads for its formation chances are those read here.
@compute @workgroup_size(WORKGROUP_SIZE)
fn queue_work(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= batch.n_envs || su[batch.c_stepping + e] == 0u || su[batch.c_done + e] != 0u || params.replay != 0u) {
        return;
    }
    var rng = social_rng(e);
    let idle = su[batch.c_cf_active + e] == 0u && su[batch.c_lf_active + e] == 0u;
    if ((params.p_crowd_dispersal > 0.0 && rng_chance(&rng, params.p_crowd_dispersal))
        || (params.p_laptop_dispersal > 0.0 && rng_chance(&rng, params.p_laptop_dispersal))
        || (idle && params.p_crowd_formation > 0.0 && rng_chance(&rng, params.p_crowd_formation))
        || (idle && params.p_laptop_formation > 0.0 && rng_chance(&rng, params.p_laptop_formation))) {
        rare_push(RARE_SOCIAL_EVENTS, e);
    }
}

// The events of the queued environments (`queue_work` checked that they step): one a lane, or
// one a workgroup whose lanes share each regrouping (REGROUP_LANES; common/regroup.wgsl).
@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    if (REGROUP_LANES == 1u) {
        let e = rare_env(RARE_SOCIAL_EVENTS, gid.x);
        if (e == NONE) {
            return;
        }
        var rng = social_rng(e);
        // The two dispersals, each followed by the regrouping when it happened (see the header).
        for (var phase = 0u; phase < 2u; phase++) {
            if (dispersal(e, phase, &rng)) {
                regroup_canonicalize(e);
            }
        }
        formations(e, &rng);
        return;
    }
    for (var k = wid.x; ; k += groups.x) {
        let e = regroup_team_env(RARE_SOCIAL_EVENTS, k, lane);
        if (e == NONE) {
            break;
        }
        // Lane 0's stream is the one drawn from.
        var rng = social_rng(e);
        for (var phase = 0u; phase < 2u; phase++) {
            var dispersed = false;
            if (lane == 0u) {
                dispersed = dispersal(e, phase, &rng);
            }
            if (regroup_lane0_says(dispersed, lane)) {
                regroup_canonicalize_on_lanes(e, lane);
            }
        }
        if (lane == 0u) {
            formations(e, &rng);
        }
    }
}

// Dispersal `phase` of environment e (0 a crowd's, 1 a laptop use's), counted: whether it
// happened, and so regroups.
fn dispersal(e: u32, phase: u32, rng: ptr<function, RngStream>) -> bool {
    if (phase == 0u) {
        if (params.p_crowd_dispersal > 0.0 && rng_chance(rng, params.p_crowd_dispersal)
            && crowd_dispersal(e, rng)) {
            count_event(e, EV_CROWD_DISPERSAL);
            return true;
        }
        return false;
    }
    if (params.p_laptop_dispersal > 0.0 && rng_chance(rng, params.p_laptop_dispersal)
        && laptop_dispersal(e, rng)) {
        count_event(e, EV_LAPTOP_DISPERSAL);
        return true;
    }
    return false;
}

// The two formation starts of environment e, after its dispersals, counted.
fn formations(e: u32, rng: ptr<function, RngStream>) {
    var idle = su[batch.c_cf_active + e] == 0u && su[batch.c_lf_active + e] == 0u;
    if (idle && params.p_crowd_formation > 0.0 && rng_chance(rng, params.p_crowd_formation)) {
        let start = crowd_formation(e, rng);
        if (start == START_STARTED) {
            count_event(e, EV_CROWD_FORMATION_START);
        } else if (start == START_BLOCKED) {
            count_event(e, EV_CROWD_FORMATION_GAVE_UP);
        }
    }
    idle = su[batch.c_cf_active + e] == 0u && su[batch.c_lf_active + e] == 0u;
    if (idle && params.p_laptop_formation > 0.0 && rng_chance(rng, params.p_laptop_formation)) {
        let start = laptop_formation(e, rng);
        if (start == START_STARTED) {
            count_event(e, EV_LAPTOP_FORMATION_START);
        } else if (start == START_BLOCKED) {
            count_event(e, EV_LAPTOP_FORMATION_BLOCKED);
        }
    }
}
