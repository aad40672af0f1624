//! Writing a validated document into one environment's (emptied) slots: the values as they are,
//! the links as `validate` resolved them.

use super::types::{Document, Extras, Snapshot};
use super::validate::Plan;
use crate::state::{BatchState, NONE, forming};

/// Writes `doc` (with its links `plan`) into environment `e` of `s`, whose slots are empty.
pub(super) fn write(doc: &Document, plan: &Plan, s: &mut BatchState, e: usize) {
    s.map_x[e] = doc.room.map_x.0;
    s.map_y[e] = doc.room.map_y.0;
    s.room_shape[e] = doc.room.shape.0;
    let wb = e * s.strides.walls;
    for (k, w) in doc.walls.0.iter().enumerate() {
        let i = wb + k;
        s.w_id[i] = w.id.0;
        (s.w_x[i], s.w_y[i], s.w_theta[i]) = (w.x.0, w.y.0, w.theta.0);
        (s.w_sin[i], s.w_cos[i]) = crate::math::sin_cos(s.w_theta[i]);
        s.w_length[i] = w.length.0;
    }
    s.n_walls[e] = doc.walls.0.len() as u32;
    let bb = e * s.strides.blockers;
    for (k, b) in doc.spawn_blockers.0.iter().enumerate() {
        let i = bb + k;
        s.b_kind[i] = b.kind.0;
        (s.b_x[i], s.b_y[i], s.b_theta[i]) = (b.x.0, b.y.0, b.theta.0);
        (s.b_length[i], s.b_width[i]) = (b.length.0, b.width.0);
    }
    s.n_blockers[e] = doc.spawn_blockers.0.len() as u32;
    let h = &doc.human_params;
    s.orca_neighbor_dist[e] = h.orca_neighbor_dist.0;
    s.orca_time_horizon[e] = h.orca_time_horizon.0;
    s.orca_time_horizon_obst[e] = h.orca_time_horizon_obst.0;
    s.orca_max_speed[e] = h.orca_max_speed.0;
    s.sfm_r0[e] = h.sfm_r0.0;
    s.sfm_gamma[e] = h.sfm_gamma.0;
    s.sfm_n[e] = h.sfm_n.0;
    s.sfm_n_prime[e] = h.sfm_n_prime.0;
    s.sfm_lambda[e] = h.sfm_lambda.0;
    snapshot(&doc.state, plan, s, e);
    match &doc.socnav {
        Some(x) => extras(x, s, e),
        None => {
            // A 0.1.1 snapshot: a running episode whose per-episode sums start here.
            s.done[e] = 0;
            s.pending_reset[e] = 0;
            crate::systems::reset::init_episode_sums(&mut s.env_chunk(e), 0);
        }
    }
}

fn snapshot(st: &Snapshot, plan: &Plan, s: &mut BatchState, e: usize) {
    s.tick[e] = st.tick.0;
    let r = &st.robot;
    (s.robot_x[e], s.robot_y[e], s.robot_theta[e]) = (r.x.0, r.y.0, r.theta.0);
    [s.goal_x[e], s.goal_y[e]] = r.goal.0;
    [s.robot_vx[e], s.robot_vy[e], s.robot_w[e]] = r.vel.0;
    let r = &st.shadow_robot;
    (s.shadow_x[e], s.shadow_y[e], s.shadow_theta[e]) = (r.x.0, r.y.0, r.theta.0);
    [s.shadow_vx[e], s.shadow_vy[e], s.shadow_w[e]] = r.vel.0;
    s.shadow_collided[e] = u32::from(r.collided.0);
    s.shadow_reached[e] = u32::from(r.reached.0);
    s.shadow_reach_tick[e] = r.reach_tick.map_or(0, |t| t.0);
    s.shadow_path_length[e] = r.path_length.0;
    humans(st, s, e);
    objects(st, s, e);
    groups(st, plan, s, e);
    let ub = e * s.strides.laptop_users;
    for (k, (u, &(human, laptop))) in st.hl_interactions.0.iter().zip(&plan.users).enumerate() {
        s.lu_human[ub + k] = human;
        s.lu_laptop[ub + k] = laptop;
        s.lu_dispersable[ub + k] = u32::from(u.dispersable.0);
    }
    s.n_laptop_users[e] = st.hl_interactions.0.len() as u32;
    formations(st, plan, s, e);
    // Replay: the group velocity noise (m/s) the next step adds to each listed member
    // (`group_noise`: `[[member_id, noise_x, noise_y], ...]`, as the golden episodes recorded
    // it); members not listed get none.
    let hb = e * s.strides.humans;
    s.h_noise_x[hb..hb + s.strides.humans].fill(0.0);
    s.h_noise_y[hb..hb + s.strides.humans].fill(0.0);
    for &(slot, x, y) in &plan.noise {
        s.h_noise_x[hb + slot] = x;
        s.h_noise_y[hb + slot] = y;
    }
    let m = &st.metrics;
    s.m_prev_goal_dist[e] = m.prev_goal_distance.0;
    s.m_failure_to_progress[e] = m.failure_to_progress.0;
    s.m_stalled_time[e] = m.stalled_time.0;
    s.m_path_length[e] = m.path_length.0;
    (s.m_v_min[e], s.m_v_max[e], s.m_v_avg[e]) = (m.v_min.0, m.v_max.0, m.v_avg.0);
    [s.m_prev_vx[e], s.m_prev_vy[e]] = m.prev_vel.0;
    (s.m_a_min[e], s.m_a_max[e], s.m_a_avg[e]) = (m.a_min.0, m.a_max.0, m.a_avg.0);
    [s.m_prev_ax[e], s.m_prev_ay[e]] = m.prev_a.0;
    (s.m_j_min[e], s.m_j_max[e], s.m_j_avg[e]) = (m.jerk_min.0, m.jerk_max.0, m.jerk_avg.0);
    s.m_compliant[e] = m.compliant_count.0;
    let r = &st.reward_state;
    (s.r_prev_dist[e], s.r_has_prev[e]) = match r.prev_distance {
        Some(d) => (d.0, 1),
        None => (0.0, 0),
    };
    s.r_discomfort_sngnn[e] = r.info.discomfort_sngnn.0;
    s.r_discomfort_dsrnn[e] = r.info.discomfort_dsrnn.0;
    s.r_distance[e] = r.info.distance_reward.0;
    s.r_alive[e] = r.info.alive_reward.0;
    s.r_sngnn[e] = r.info.sngnn_reward.0;
}

/// Humans in observation order.
fn humans(st: &Snapshot, s: &mut BatchState, e: usize) {
    let hb = e * s.strides.humans;
    let list = &st.humans.0;
    for (k, h) in list.iter().enumerate() {
        let i = hb + k;
        s.h_id[i] = h.id.0;
        (s.h_x[i], s.h_y[i], s.h_theta[i]) = (h.x.0, h.y.0, h.theta.0);
        s.h_speed[i] = h.speed.0;
        [s.h_goal_x[i], s.h_goal_y[i]] = h.goal.map_or([h.x.0, h.y.0], |g| g.0);
        s.h_policy[i] = h.policy.0;
        s.h_role[i] = h.role.0;
        // A group's members get their group's index below.
        s.h_group[i] = h.group.map_or(NONE, |g| g.0);
        s.h_laptop_user[i] = h.hl.map_or(NONE, |u| u.0);
        // `validate` read `forming_hl` where it counts.
        let laptop = |h: &super::types::Human| {
            h.forming_hl
                .as_ref()
                .is_some_and(|f| f.get("").is_ok_and(|f| f.0))
        };
        s.h_forming[i] = if h.forming_crowd.is_some_and(|f| f.0) {
            forming::CROWD
        } else if laptop(h) {
            forming::LAPTOP
        } else {
            forming::NONE
        };
    }
    s.n_humans[e] = list.len() as u32;
    s.n_static[e] = list
        .iter()
        .filter(|h| h.role.0 == crate::state::role::STATIC)
        .count() as u32;
    s.n_dynamic[e] = list
        .iter()
        .filter(|h| h.role.0 == crate::state::role::DYNAMIC)
        .count() as u32;
}

/// Laptops, tables and plants.
fn objects(st: &Snapshot, s: &mut BatchState, e: usize) {
    let lb = e * s.strides.laptops;
    for (k, l) in st.laptops.0.iter().enumerate() {
        let i = lb + k;
        s.l_id[i] = l.id.0;
        (s.l_x[i], s.l_y[i], s.l_theta[i]) = (l.x.0, l.y.0, l.theta.0);
        (s.l_sin[i], s.l_cos[i]) = crate::math::sin_cos(s.l_theta[i]);
        s.l_user[i] = l.hl.map_or(NONE, |u| u.0);
    }
    s.n_laptops[e] = st.laptops.0.len() as u32;
    let tb = e * s.strides.tables;
    for (k, t) in st.tables.0.iter().enumerate() {
        let i = tb + k;
        s.t_id[i] = t.id.0;
        (s.t_x[i], s.t_y[i], s.t_theta[i]) = (t.x.0, t.y.0, t.theta.0);
        (s.t_sin[i], s.t_cos[i]) = crate::math::sin_cos(s.t_theta[i]);
    }
    s.n_tables[e] = st.tables.0.len() as u32;
    let pb = e * s.strides.plants;
    for (k, p) in st.plants.0.iter().enumerate() {
        s.p_id[pb + k] = p.id.0;
        (s.p_x[pb + k], s.p_y[pb + k]) = (p.x.0, p.y.0);
    }
    s.n_plants[e] = st.plants.0.len() as u32;
}

fn groups(st: &Snapshot, plan: &Plan, s: &mut BatchState, e: usize) {
    let gb = e * s.strides.groups;
    let hb = e * s.strides.humans;
    for &(slot, k) in &plan.members {
        s.h_group[hb + slot] = k;
    }
    for (k, (g, &(first, radius))) in st.groups.0.iter().zip(&plan.groups).enumerate() {
        let i = gb + k;
        s.g_kind[i] = g.kind.0;
        s.g_dispersable[i] = u32::from(g.dispersable.0);
        s.g_first[i] = first;
        s.g_count[i] = g.members.0.len() as u32;
        [s.g_x[i], s.g_y[i]] = g.centre.0;
        [s.g_goal_x[i], s.g_goal_y[i]] = g.goal.map_or(g.centre.0, |v| v.0);
        s.g_vx[i] = 0.0;
        s.g_vy[i] = 0.0;
        s.g_member_goal_radius[i] = radius;
    }
    s.n_groups[e] = st.groups.0.len() as u32;
}

fn formations(st: &Snapshot, plan: &Plan, s: &mut BatchState, e: usize) {
    let mut env = s.env_chunk(e);
    crate::systems::formation::clear_crowd_formation(&mut env, 0);
    crate::systems::formation::clear_laptop_formation(&mut env, 0);
    if let Some(cf) = &st.crowd_forming {
        let sb = e * s.strides.group_size;
        for (k, (slot, &human)) in cf.slots.0.iter().zip(&plan.crowd).enumerate() {
            s.cf_slot_x[sb + k] = slot.0.0;
            s.cf_slot_y[sb + k] = slot.1.0;
            s.cf_slot_theta[sb + k] = slot.2.0;
            s.cf_human[sb + k] = human;
        }
        [s.cf_x[e], s.cf_y[e]] = cf.centre.0;
        s.cf_close_steps[e] = cf.almost_formed_count.0;
        s.cf_count[e] = cf.slots.0.len() as u32;
        s.cf_active[e] = 1;
    }
    if let (Some(lf), Some((human, laptop))) = (&st.hl_forming, plan.laptop_forming) {
        s.lf_human[e] = human;
        s.lf_laptop[e] = laptop;
        [s.lf_seat_x[e], s.lf_seat_y[e], s.lf_seat_theta[e]] = lf.seat.0;
        s.lf_active[e] = 1;
    }
}

fn extras(x: &Extras, s: &mut BatchState, e: usize) {
    // Documents written before episode seeds existed lack them: the environment keeps its own.
    if let Some(seed) = x.next_seed {
        s.set_next_seed(e, seed.0);
    }
    if let Some(seed) = x.seed {
        (s.seed_lo[e], s.seed_hi[e]) = crate::seeds::seed_words(seed.0);
    }
    s.episode[e] = x.episode.0;
    s.done[e] = u32::from(x.done.0);
    s.pending_reset[e] = u32::from(x.pending_reset.0);
    if let Some(sums) = &x.episode_sums {
        s.ep_return[e] = sums.ret.0;
        s.ep_min_human_dist[e] = sums.min_human_distance.0;
        s.ep_min_obstacle_dist[e] = sums.min_obstacle_distance.0;
        s.ep_sum_avg_obstacle_dist[e] = sums.sum_average_obstacle_distance.0;
        s.ep_sum_ttc[e] = sums.sum_time_to_collision.0;
        s.ep_sum_discomfort_dsrnn[e] = sums.sum_discomfort_dsrnn.0;
        s.ep_sum_sngnn[e] = sums.sum_sngnn_reward.0;
    }
}
