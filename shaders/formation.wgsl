// requires: common/regroup.wgsl
//
// Twin of src/systems/formation.rs (stage `formation`, docs/spec.md 4.1 step 9, 4.5): the
// bookkeeping of formations in progress after the motion and goal re-sampling of the step. A
// forming crowd: walkers at their slots take the slot's heading; when all are there the crowd forms
// (standing, or moving to a new goal); if they stayed together for FORMATION_APPROXIMATE_AFTER
// steps an approximate standing group forms where they are. A walker at its laptop seat sits down.
// Same operations and draws in the same order as the Rust file; change both in the same commit. The
// regrouping that ends a completed formation (`regroup_canonicalize`, at the end of the Rust
// `end_crowd_formation` and `sit_down`) is called by `main` right after them, from one place
// (Mesa inlines every call, and each copy of the regrouping costs llvmpipe
// compile time).
//
// Rare work out of the hot pass (the stage's GpuPlan: backend::schedule::has_rare_work):
// `queue_work`, over every environment, queues those with a crowd forming or a walker at its laptop
// seat; `main` runs one lane per queued environment, or one workgroup (REGROUP_LANES: its lane 0
// the logic, every lane a share of the regrouping). Any other environment `main` would leave as it
// is. The ORCA obstacle rebuild that ends a regrouping is queued (RARE_REBUILD) for one dispatch
// after the submit's last stage, `social_events`' regroupings with these (`rebuild` or
// `rebuild_in_workgroups`, generated: backend::schedule::regroups).
//
// Capacities: Rust asserts that a new group and a new laptop user fit their capacities
// (guaranteed by `Caps`: crowd formation raises the group capacity to humans / 2, laptop-use
// formation the laptop-user capacity to the laptops). Should one not fit, the GPU poisons the
// environment instead of panicking: the positions of the humans involved become NaN and the
// formation is left as it is.

// Rust `distance`.
fn distance(ax: f32, ay: f32, bx: f32, by: f32) -> f32 {
    let dx = ax - bx;
    let dy = ay - by;
    return sqrt(dx * dx + dy * dy);
}

// Rust `set_heading`: heading of human slot i, keeping its speed; the world velocity follows.
fn set_heading(i: u32, theta: f32) {
    let sc = math_sin_cos(theta);
    sf[batch.c_h_theta + i] = theta;
    sf[batch.c_h_vx + i] = sf[batch.c_h_speed + i] * sc.y;
    sf[batch.c_h_vy + i] = sf[batch.c_h_speed + i] * sc.x;
}

// Rust `walkers_centroid`.
fn walkers_centroid(e: u32) -> vec2<f32> {
    let n = su[batch.c_cf_count + e];
    var x = 0.0;
    var y = 0.0;
    for (var k = at_crowd_slot(e, 0u); k < at_crowd_slot(e, n); k += batch.k_crowd_slot) {
        let i = at_human(e, su[batch.c_cf_human + k]);
        x += sf[batch.c_h_x + i];
        y += sf[batch.c_h_y + i];
    }
    return vec2<f32>(x / f32(n), y / f32(n));
}

// Poison (see the header): the forming walkers' positions become NaN.
fn poison_crowd(e: u32) {
    for (var k = at_crowd_slot(e, 0u); k < at_crowd_slot(e, su[batch.c_cf_count + e]); k += batch.k_crowd_slot) {
        let i = at_human(e, su[batch.c_cf_human + k]);
        sf[batch.c_h_x + i] = math_nan();
        sf[batch.c_h_y + i] = math_nan();
    }
}

// Rust `new_group`: a new group slot (global) with the forming walkers as members, in formation
// order; NONE (and the walkers poisoned) when the group capacity is exhausted.
fn new_group(e: u32, kind: u32) -> u32 {
    if (su[batch.c_n_groups + e] >= batch.s_g_kind) {
        poison_crowd(e);
        return NONE;
    }
    let g = at_group(e, su[batch.c_n_groups + e]);
    su[batch.c_n_groups + e] += 1u;
    su[batch.c_g_kind + g] = kind;
    su[batch.c_g_dispersable + g] = 1u;
    su[batch.c_g_seq + g] = regroup_next_seq(e);
    sf[batch.c_g_vx + g] = 0.0;
    sf[batch.c_g_vy + g] = 0.0;
    // The members are the walkers that formed the crowd, with their human goal radius.
    sf[batch.c_g_member_goal_radius + g] = params.human_goal_radius;
    var member_role = ROLE_STANDING_GROUP;
    if (kind == GROUP_MOVING) {
        member_role = ROLE_MOVING_GROUP;
    }
    for (var k = at_crowd_slot(e, 0u); k < at_crowd_slot(e, su[batch.c_cf_count + e]); k += batch.k_crowd_slot) {
        let i = at_human(e, su[batch.c_cf_human + k]);
        su[batch.c_h_role + i] = member_role;
        su[batch.c_h_group + i] = slot_group(e, g);
        su[batch.c_h_forming + i] = FORMING_NONE;
        su[batch.c_h_seq + i] = regroup_next_seq(e);
    }
    return g;
}

// Rust `clear_crowd_formation`.
fn clear_crowd_formation(e: u32) {
    su[batch.c_cf_active + e] = 0u;
    su[batch.c_cf_count + e] = 0u;
    su[batch.c_cf_close_steps + e] = 0u;
    sf[batch.c_cf_x + e] = 0.0;
    sf[batch.c_cf_y + e] = 0.0;
    for (var k = at_crowd_slot(e, 0u); k < at_crowd_slot(e, batch.s_cf_human); k += batch.k_crowd_slot) {
        sf[batch.c_cf_slot_x + k] = 0.0;
        sf[batch.c_cf_slot_y + k] = 0.0;
        sf[batch.c_cf_slot_theta + k] = 0.0;
        su[batch.c_cf_human + k] = 0u;
    }
}

// Rust `clear_laptop_formation`.
fn clear_laptop_formation(e: u32) {
    su[batch.c_lf_active + e] = 0u;
    su[batch.c_lf_human + e] = 0u;
    su[batch.c_lf_laptop + e] = 0u;
    sf[batch.c_lf_seat_x + e] = 0.0;
    sf[batch.c_lf_seat_y + e] = 0.0;
    sf[batch.c_lf_seat_theta + e] = 0.0;
}

// Rust `end_crowd_formation`.
fn end_crowd_formation(e: u32) {
    clear_crowd_formation(e);
    // Rust: `regroup::canonicalize`, called by `main` (see the header).
}

// Rust `form_crowd`: every walker is at its slot.
fn form_crowd(e: u32, rng: ptr<function, RngStream>) {
    let n = su[batch.c_cf_count + e];
    var poses: array<vec3<f32>, PLACE_GROUP_ARRAY>;
    place_group_layout(rng, sf[batch.c_cf_x + e], sf[batch.c_cf_y + e], n, true, &poses);
    let moving = rng_chance(rng, 0.5);
    var kind = GROUP_STANDING;
    if (moving) {
        kind = GROUP_MOVING;
    }
    let g = new_group(e, kind);
    if (g == NONE) {
        return;
    }
    var cx = 0.0;
    var cy = 0.0;
    for (var k = 0u; k < min(n, place_group_cap()); k++) {
        let pose = poses[k];
        let i = at_human(e, su[batch.c_cf_human + at_crowd_slot(e, k)]);
        sf[batch.c_h_x + i] = pose.x;
        sf[batch.c_h_y + i] = pose.y;
        set_heading(i, pose.z);
        cx += pose.x;
        cy += pose.y;
    }
    sf[batch.c_g_x + g] = cx / f32(n);
    sf[batch.c_g_y + g] = cy / f32(n);
    if (moving) {
        let goal = goals_sample_goal(e, rng, params.group_goal_radius);
        var gx = sf[batch.c_g_x + g];
        var gy = sf[batch.c_g_y + g];
        if (goal.found) {
            gx = goal.disc.x;
            gy = goal.disc.y;
        }
        sf[batch.c_g_goal_x + g] = gx;
        sf[batch.c_g_goal_y + g] = gy;
        for (var k = at_crowd_slot(e, 0u); k < at_crowd_slot(e, n); k += batch.k_crowd_slot) {
            let i = at_human(e, su[batch.c_cf_human + k]);
            sf[batch.c_h_goal_x + i] = gx;
            sf[batch.c_h_goal_y + i] = gy;
        }
    }
    end_crowd_formation(e);
}

// Rust `form_approximate_crowd`: a standing group where the walkers are, facing (cx, cy).
fn form_approximate_crowd(e: u32, rng: ptr<function, RngStream>, cx: f32, cy: f32) {
    let n = su[batch.c_cf_count + e];
    var poses: array<vec3<f32>, PLACE_GROUP_ARRAY>;
    place_group_layout(rng, cx, cy, n, true, &poses);
    let g = new_group(e, GROUP_STANDING);
    if (g == NONE) {
        return;
    }
    var px = 0.0;
    var py = 0.0;
    for (var k = 0u; k < min(n, place_group_cap()); k++) {
        px += poses[k].x;
        py += poses[k].y;
    }
    sf[batch.c_g_x + g] = px / f32(n);
    sf[batch.c_g_y + g] = py / f32(n);
    for (var k = at_crowd_slot(e, 0u); k < at_crowd_slot(e, n); k += batch.k_crowd_slot) {
        let i = at_human(e, su[batch.c_cf_human + k]);
        set_heading(i, math_atan2(cy - sf[batch.c_h_y + i], cx - sf[batch.c_h_x + i]));
    }
    end_crowd_formation(e);
}

// Rust `crowd_progress`: 0 walking, 1 formed, 2 approximate.
fn crowd_progress(e: u32, rng: ptr<function, RngStream>) -> u32 {
    let n = su[batch.c_cf_count + e];
    var all_arrived = true;
    for (var k = at_crowd_slot(e, 0u); k < at_crowd_slot(e, n); k += batch.k_crowd_slot) {
        let i = at_human(e, su[batch.c_cf_human + k]);
        if (distance(sf[batch.c_h_x + i], sf[batch.c_h_y + i], sf[batch.c_cf_slot_x + k], sf[batch.c_cf_slot_y + k]) < params.human_goal_radius) {
            set_heading(i, sf[batch.c_cf_slot_theta + k]);
        } else {
            all_arrived = false;
        }
    }
    if (all_arrived) {
        form_crowd(e, rng);
        return 1u;
    }
    let c = walkers_centroid(e);
    let reach = params.group_radius + params.human_radius;
    var together = true;
    for (var k = at_crowd_slot(e, 0u); k < at_crowd_slot(e, n); k += batch.k_crowd_slot) {
        let i = at_human(e, su[batch.c_cf_human + k]);
        if (!(distance(sf[batch.c_h_x + i], sf[batch.c_h_y + i], c.x, c.y) < reach)) {
            together = false;
            break;
        }
    }
    if (together) {
        su[batch.c_cf_close_steps + e] += 1u;
    } else {
        su[batch.c_cf_close_steps + e] = 0u;
    }
    if (su[batch.c_cf_close_steps + e] >= FORMATION_APPROXIMATE_AFTER) {
        form_approximate_crowd(e, rng, c.x, c.y);
        return 2u;
    }
    return 0u;
}

// Rust `seat_reached`.
fn seat_reached(e: u32) -> bool {
    let i = at_human(e, su[batch.c_lf_human + e]);
    return distance(sf[batch.c_h_x + i], sf[batch.c_h_y + i], sf[batch.c_lf_seat_x + e], sf[batch.c_lf_seat_y + e]) < params.human_goal_radius;
}

// Rust `sit_down`: the walker becomes a new (dispersable) laptop user at the seat.
fn sit_down(e: u32) {
    let i = at_human(e, su[batch.c_lf_human + e]);
    let l = at_laptop(e, su[batch.c_lf_laptop + e]);
    let u_local = su[batch.c_n_laptop_users + e];
    if (u_local >= batch.s_lu_human) {
        sf[batch.c_h_x + i] = math_nan();
        sf[batch.c_h_y + i] = math_nan();
        return;
    }
    let u = at_laptop_user(e, u_local);
    su[batch.c_n_laptop_users + e] += 1u;
    su[batch.c_lu_human + u] = su[batch.c_lf_human + e];
    su[batch.c_lu_laptop + u] = su[batch.c_lf_laptop + e];
    su[batch.c_lu_dispersable + u] = 1u;
    su[batch.c_lu_seq + u] = regroup_next_seq(e);
    su[batch.c_l_user + l] = u_local;
    sf[batch.c_h_x + i] = sf[batch.c_lf_seat_x + e];
    sf[batch.c_h_y + i] = sf[batch.c_lf_seat_y + e];
    set_heading(i, sf[batch.c_lf_seat_theta + e]);
    su[batch.c_h_role + i] = ROLE_LAPTOP_USER;
    su[batch.c_h_laptop_user + i] = u_local;
    su[batch.c_h_group + i] = NONE;
    su[batch.c_h_forming + i] = FORMING_NONE;
    su[batch.c_h_policy + i] = POLICY_ORCA;
    su[batch.c_h_seq + i] = regroup_next_seq(e);
    clear_laptop_formation(e);
    // Rust: `regroup::canonicalize`, called by `main` (see the header).
}

// Queue the environments `main` has work in (see the header).
@compute @workgroup_size(WORKGROUP_SIZE)
fn queue_work(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= batch.n_envs || su[batch.c_stepping + e] == 0u) {
        return;
    }
    if (su[batch.c_cf_active + e] != 0u || (su[batch.c_lf_active + e] != 0u && seat_reached(e))) {
        rare_push(RARE_FORMATION, e);
    }
}

// The formations of the queued environments (`queue_work` checked that they step): one a lane,
// or one a workgroup whose lanes share each regrouping (REGROUP_LANES; common/regroup.wgsl).
@compute @workgroup_size(WORKGROUP_SIZE)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    if (REGROUP_LANES == 1u) {
        let e = rare_env(RARE_FORMATION, gid.x);
        if (e == NONE) {
            return;
        }
        var rng = formation_rng(e);
        // The crowd, then the laptop seat, each followed by the regrouping when it completed
        // (see the header).
        for (var phase = 0u; phase < 2u; phase++) {
            if (formation_phase(e, phase, &rng)) {
                regroup_canonicalize(e);
            }
        }
        return;
    }
    for (var k = wid.x; ; k += groups.x) {
        let e = regroup_team_env(RARE_FORMATION, k, lane);
        if (e == NONE) {
            break;
        }
        // Lane 0's stream is the one drawn from.
        var rng = formation_rng(e);
        for (var phase = 0u; phase < 2u; phase++) {
            var completed = false;
            if (lane == 0u) {
                completed = formation_phase(e, phase, &rng);
            }
            if (regroup_lane0_says(completed, lane)) {
                regroup_canonicalize_on_lanes(e, lane);
            }
        }
    }
}

fn formation_rng(e: u32) -> RngStream {
    return rng_new(
        su[batch.c_seed_lo + e],
        su[batch.c_seed_hi + e],
        rng_stream_id(STREAM_FORMATION, su[batch.c_tick + e]),
    );
}

// Phase `phase` of environment e's formations (0 the crowd, 1 the laptop seat), its events
// counted: whether it completed, and so regroups.
fn formation_phase(e: u32, phase: u32, rng: ptr<function, RngStream>) -> bool {
    if (phase == 0u) {
        if (su[batch.c_cf_active + e] == 0u) {
            return false;
        }
        let progress = crowd_progress(e, rng);
        if (progress == 1u) {
            count_formation_event(e, EV_CROWD_FORMATION_COMPLETE);
            return true;
        } else if (progress == 2u) {
            count_formation_event(e, EV_CROWD_FORMATION_APPROXIMATE);
            return true;
        }
        return false;
    }
    if (su[batch.c_lf_active + e] != 0u && seat_reached(e)) {
        sit_down(e);
        count_formation_event(e, EV_LAPTOP_FORMATION_COMPLETE);
        return true;
    }
    return false;
}

fn count_formation_event(e: u32, ev: u32) {
    outu[batch.co_events + e * batch.so_events + ev] += 1u;
}
