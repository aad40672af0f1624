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
    let i = at_wall(e, w);
    return geo_rect_with_trig(
        sf[batch.c_w_x + i], sf[batch.c_w_y + i], sf[batch.c_w_cos + i], sf[batch.c_w_sin + i], sf[batch.c_w_length + i],
        params.wall_thickness,
    );
}

fn world_table_rect(e: u32, t: u32) -> Rect {
    let i = at_table(e, t);
    return geo_rect_with_trig(
        sf[batch.c_t_x + i], sf[batch.c_t_y + i], sf[batch.c_t_cos + i], sf[batch.c_t_sin + i], params.table_length,
        params.table_width,
    );
}

fn world_laptop_rect(e: u32, l: u32) -> Rect {
    let i = at_laptop(e, l);
    return geo_rect_with_trig(
        sf[batch.c_l_x + i], sf[batch.c_l_y + i], sf[batch.c_l_cos + i], sf[batch.c_l_sin + i], params.laptop_length,
        params.laptop_width,
    );
}

// Which humans and objects the disc touches (touching counts), with discs shaped as
// `params.contact_shape` says.
fn world_touches(e: u32, d: Disc) -> Touches {
    let shape = params.contact_shape;
    var t = Touches(false, false, false);
    for (var i = at_human(e, 0u); i < at_human(e, su[batch.c_n_humans + e]); i += batch.k_human) {
        if (geo_disc_disc_as(shape, d, Disc(sf[batch.c_h_x + i], sf[batch.c_h_y + i], params.human_radius))) {
            t.human = true;
            break;
        }
    }
    for (var w = 0u; w < su[batch.c_n_walls + e]; w++) {
        if (geo_disc_rect_as(shape, d, world_wall_rect(e, w))) {
            t.wall = true;
            break;
        }
    }
    var plant = false;
    for (var i = at_plant(e, 0u); i < at_plant(e, su[batch.c_n_plants + e]); i += batch.k_plant) {
        if (geo_disc_disc_as(shape, d, Disc(sf[batch.c_p_x + i], sf[batch.c_p_y + i], params.plant_radius))) {
            plant = true;
            break;
        }
    }
    var table = false;
    for (var k = 0u; k < su[batch.c_n_tables + e]; k++) {
        if (geo_disc_rect_as(shape, d, world_table_rect(e, k))) {
            table = true;
            break;
        }
    }
    var laptop = false;
    for (var k = 0u; k < su[batch.c_n_laptops + e]; k++) {
        if (geo_disc_rect_as(shape, d, world_laptop_rect(e, k))) {
            laptop = true;
            break;
        }
    }
    t.object = t.wall || plant || table || laptop;
    return t;
}
