// requires: common/geometry.wgsl
//
// Twin of src/systems/world.rs: queries of one environment's world during a step (which entities
// a disc touches, the shapes of the static objects), over the state columns of the prelude.
// Change both files in the same commit.

struct Touches {
    human: bool,
    object: bool,
    wall: bool,
}

fn world_wall_rect(e: u32, w: u32) -> Rect {
    let i = e * S_W_X + w;
    return geo_rect_with_trig(
        sf[C_W_X + i], sf[C_W_Y + i], sf[C_W_COS + i], sf[C_W_SIN + i], sf[C_W_LENGTH + i],
        params.wall_thickness,
    );
}

fn world_table_rect(e: u32, t: u32) -> Rect {
    let i = e * S_T_X + t;
    return geo_rect_with_trig(
        sf[C_T_X + i], sf[C_T_Y + i], sf[C_T_COS + i], sf[C_T_SIN + i], params.table_length,
        params.table_width,
    );
}

fn world_laptop_rect(e: u32, l: u32) -> Rect {
    let i = e * S_L_X + l;
    return geo_rect_with_trig(
        sf[C_L_X + i], sf[C_L_Y + i], sf[C_L_COS + i], sf[C_L_SIN + i], params.laptop_length,
        params.laptop_width,
    );
}

// Which humans and objects the disc touches (touching counts), with discs shaped as
// `params.contact_shape` says.
fn world_touches(e: u32, d: Disc) -> Touches {
    let shape = params.contact_shape;
    var t = Touches(false, false, false);
    let hb = e * S_H_X;
    for (var i = hb; i < hb + su[C_N_HUMANS + e]; i++) {
        if (geo_disc_disc_as(shape, d, Disc(sf[C_H_X + i], sf[C_H_Y + i], params.human_radius))) {
            t.human = true;
            break;
        }
    }
    for (var w = 0u; w < su[C_N_WALLS + e]; w++) {
        if (geo_disc_rect_as(shape, d, world_wall_rect(e, w))) {
            t.wall = true;
            break;
        }
    }
    var plant = false;
    let pb = e * S_P_X;
    for (var i = pb; i < pb + su[C_N_PLANTS + e]; i++) {
        if (geo_disc_disc_as(shape, d, Disc(sf[C_P_X + i], sf[C_P_Y + i], params.plant_radius))) {
            plant = true;
            break;
        }
    }
    var table = false;
    for (var k = 0u; k < su[C_N_TABLES + e]; k++) {
        if (geo_disc_rect_as(shape, d, world_table_rect(e, k))) {
            table = true;
            break;
        }
    }
    var laptop = false;
    for (var k = 0u; k < su[C_N_LAPTOPS + e]; k++) {
        if (geo_disc_rect_as(shape, d, world_laptop_rect(e, k))) {
            laptop = true;
            break;
        }
    }
    t.object = t.wall || plant || table || laptop;
    return t;
}
