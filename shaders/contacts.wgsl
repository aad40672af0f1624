// requires: common/world.wgsl
//
// Twin of src/systems/contacts.rs (stage `contacts`, docs/spec.md 4.6): after all motion, a human
// that touches a plant, wall, table or free laptop is pushed out by an MPE-style soft contact
// force: it turns to the force direction, takes speed min(|F|·dt, max speed) and moves once more. A
// lone static human only takes the speed (0.1.1 neither moves nor turns it). Whether a human
// touches an object is decided with discs shaped as `params.contact_shape` says, an overlap of at
// most CONTACT_SLOP not counting. Change both files in the same commit.
//
// The prelude defines, from the Rust constants: CONTACT_MARGIN (softness of the contact, m, MPE's
// `contact_margin`), CONTACT_STIFFNESS (MPE's `contact_force`) and CONTACT_SLOP (the overlap, m,
// that does not count as a contact: the f32 rounding of a position update, which leaves walkers
// that ORCA holds at an obstacle's surface slightly inside it).

// The human's disc for the contact decision: its radius less CONTACT_SLOP.
fn human_disc(i: u32) -> Disc {
    return Disc(sf[batch.c_h_x + i], sf[batch.c_h_y + i], params.human_radius - CONTACT_SLOP);
}

// Apply the contact force for separation vector (dx, dy) and contact distance `reach` (m): the
// human turns to the force, takes its speed and moves, except a lone static human, which only
// takes the speed (its cached velocity follows along its unchanged heading).
fn push(i: u32, dx: f32, dy: f32, reach: f32) {
    let dist = sqrt(dx * dx + dy * dy);
    if (dist <= 0.0) {
        return;
    }
    let penetration = CONTACT_MARGIN * math_softplus(-(dist - reach) / CONTACT_MARGIN);
    let fx = CONTACT_STIFFNESS * dx / dist * penetration;
    let fy = CONTACT_STIFFNESS * dy / dist * penetration;
    let movable = su[batch.c_h_role + i] != ROLE_STATIC;
    var theta = sf[batch.c_h_theta + i];
    if (movable) {
        theta = math_atan2(fy, fx);
    }
    let speed = min(sqrt(fx * fx + fy * fy) * params.dt, params.human_max_speed);
    let sc = math_sin_cos(theta);
    sf[batch.c_h_theta + i] = theta;
    sf[batch.c_h_speed + i] = speed;
    sf[batch.c_h_vx + i] = speed * sc.y;
    sf[batch.c_h_vy + i] = speed * sc.x;
    if (movable) {
        sf[batch.c_h_x + i] += speed * params.dt * sc.y;
        sf[batch.c_h_y + i] += speed * params.dt * sc.x;
    }
}

fn push_from_rect(i: u32, rect: Rect) {
    if (geo_disc_rect_as(params.contact_shape, human_disc(i), rect)) {
        let dx = sf[batch.c_h_x + i] - rect.x;
        let dy = sf[batch.c_h_y + i] - rect.y;
        push(i, dx, dy, params.human_radius + geo_rect_circumradius(rect));
    }
}

// Human centre minus its mirror image across the wall face on the human's side.
fn mirror_delta(wall: Rect, x: f32, y: f32) -> vec2<f32> {
    let ly = geo_rect_to_local(wall, x, y).y;
    var face = -wall.hw;
    if (ly >= 0.0) {
        face = wall.hw;
    }
    let across = 2.0 * (ly - face);
    return vec2<f32>(-wall.s * across, wall.c * across);
}

fn push_out(e: u32, i: u32) {
    let r = params.human_radius;
    for (var k = at_plant(e, 0u); k < at_plant(e, su[batch.c_n_plants + e]); k += batch.k_plant) {
        let plant = Disc(sf[batch.c_p_x + k], sf[batch.c_p_y + k], params.plant_radius);
        if (geo_disc_disc_as(params.contact_shape, human_disc(i), plant)) {
            push(i, sf[batch.c_h_x + i] - plant.x, sf[batch.c_h_y + i] - plant.y, r + plant.r);
        }
    }
    for (var w = 0u; w < su[batch.c_n_walls + e]; w++) {
        let wall = world_wall_rect(e, w);
        if (geo_disc_rect_as(params.contact_shape, human_disc(i), wall)) {
            let d = mirror_delta(wall, sf[batch.c_h_x + i], sf[batch.c_h_y + i]);
            push(i, d.x, d.y, 2.0 * r);
        }
    }
    for (var t = 0u; t < su[batch.c_n_tables + e]; t++) {
        push_from_rect(i, world_table_rect(e, t));
    }
    for (var l = 0u; l < su[batch.c_n_laptops + e]; l++) {
        if (su[batch.c_l_user + at_laptop(e, l)] == NONE) {
            push_from_rect(i, world_laptop_rect(e, l));
        }
    }
}

// The stage over environment `e`, which steps this tick: its fused pass's entry point
// (`pipeline::FusedPass`, generated) calls it.
fn stage_contacts(e: u32) {
    for (var i = at_human(e, 0u); i < at_human(e, su[batch.c_n_humans + e]); i += batch.k_human) {
        push_out(e, i);
    }
}
