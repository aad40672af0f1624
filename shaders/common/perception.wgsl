// requires: common/geometry.wgsl
//
// Twin of src/systems/perception.rs: what a lone walker perceives (docs/spec.md 4.2-4.3), the
// entities whose shape meets its view wedge (apex at the human's centre, centred on its heading,
// opening `fov_angle`, unbounded, closed). Used by the walker's ORCA simulation
// (common/orca_world.wgsl) and its social forces (common/sfm.wgsl). Library file (no entry point)
// over the prelude's `sf`/`su`/`params`. Same operations in the same order as the Rust file (read
// it for why the tests are exact); change both files in the same commit.
//
// Rust `Option<View>` is `MaybeView` (`some == false`: everything is visible); Rust
// `sees(view, shape)` is `perception_maybe_sees_disc` / `perception_maybe_sees_rect`.
//
// The prelude defines PERCEPTION_FULL_VIEW_TOLERANCE (Rust `FULL_VIEW_TOLERANCE`) and
// PERCEPTION_F32_MAX (Rust `f32::MAX`, the far end of a ray's slab test) from the Rust values.

// Rust `View`: the apex (m) and the unit directions of the clockwise (heading − fov/2) and
// counter-clockwise (heading + fov/2) bounding rays; `wide` when the opening exceeds π.
struct View {
    x: f32,
    y: f32,
    right: vec2<f32>,
    left: vec2<f32>,
    wide: bool,
}

// Rust `Option<View>`.
struct MaybeView {
    some: bool,
    view: View,
}

// Rust `None::<View>`: everything is visible.
fn perception_everything() -> MaybeView {
    return MaybeView(false, View(0.0, 0.0, vec2<f32>(0.0, 0.0), vec2<f32>(0.0, 0.0), false));
}

// Rust `sees_everything`: |fov − 2π| < 0.1.
fn perception_sees_everything(fov: f32) -> bool {
    return abs(fov - MATH_TAU) < PERCEPTION_FULL_VIEW_TOLERANCE;
}

// Rust `View::new`: apex (x, y) (m), centred on `heading` (rad), opening `fov` (rad).
fn perception_view_new(x: f32, y: f32, heading: f32, fov: f32) -> View {
    let half = 0.5 * fov;
    let r = math_sin_cos(heading - half);
    let l = math_sin_cos(heading + half);
    return View(x, y, vec2<f32>(r.y, r.x), vec2<f32>(l.y, l.x), fov > MATH_PI);
}

// Rust `View::of_human`: the view of human slot `i` (global), none when it sees everything.
fn perception_view_of_human(i: u32) -> MaybeView {
    if (perception_sees_everything(params.fov_angle)) {
        return perception_everything();
    }
    return MaybeView(true, perception_view_new(sf[batch.c_h_x + i], sf[batch.c_h_y + i], sf[batch.c_h_theta + i], params.fov_angle));
}

// Rust `View::contains`: is the point (px, py) (m) in the wedge?
fn perception_contains(v: View, px: f32, py: f32) -> bool {
    let dx = px - v.x;
    let dy = py - v.y;
    let after_right = v.right.x * dy - v.right.y * dx >= 0.0;
    let before_left = dx * v.left.y - dy * v.left.x >= 0.0;
    if (v.wide) {
        return after_right || before_left;
    }
    return after_right && before_left;
}

// Rust `View::ray_hits_disc`: does the ray from the apex along unit `u` meet the disc?
fn perception_ray_hits_disc(v: View, u: vec2<f32>, d: Disc) -> bool {
    let cx = d.x - v.x;
    let cy = d.y - v.y;
    let t = max(cx * u.x + cy * u.y, 0.0);
    let ex = cx - t * u.x;
    let ey = cy - t * u.y;
    return ex * ex + ey * ey <= d.r * d.r;
}

// One slab of Rust `View::ray_hits_rect`: the ray's local coordinate `a` and direction `d` against
// the half extent `h`, narrowing [lo, hi]; false when the ray misses the slab altogether.
fn perception_slab(a: f32, d: f32, h: f32, lo: ptr<function, f32>, hi: ptr<function, f32>) -> bool {
    if (d == 0.0) {
        if (abs(a) > h) {
            return false;
        }
        return true;
    }
    let t1 = (-h - a) / d;
    let t2 = (h - a) / d;
    var near = t2;
    var far = t1;
    if (t1 <= t2) {
        near = t1;
        far = t2;
    }
    *lo = max(*lo, near);
    *hi = min(*hi, far);
    return true;
}

// Rust `View::ray_hits_rect`: slab test in the rectangle's frame over t in [0, f32::MAX].
fn perception_ray_hits_rect(v: View, u: vec2<f32>, r: Rect) -> bool {
    let a = geo_rect_to_local(r, v.x, v.y);
    let dx = u.x * r.c + u.y * r.s;
    let dy = u.y * r.c - u.x * r.s;
    var lo = 0.0;
    var hi = PERCEPTION_F32_MAX;
    if (!perception_slab(a.x, dx, r.hl, &lo, &hi)) {
        return false;
    }
    if (!perception_slab(a.y, dy, r.hw, &lo, &hi)) {
        return false;
    }
    return lo <= hi;
}

// Rust `View::sees_disc`: the centre is in the wedge or a bounding ray hits the disc.
fn perception_sees_disc(v: View, d: Disc) -> bool {
    return perception_contains(v, d.x, d.y) || perception_ray_hits_disc(v, v.right, d)
        || perception_ray_hits_disc(v, v.left, d);
}

// Rust `View::sees_rect`: the centre is in the wedge or a bounding ray hits the rectangle.
fn perception_sees_rect(v: View, r: Rect) -> bool {
    return perception_contains(v, r.x, r.y) || perception_ray_hits_rect(v, v.right, r)
        || perception_ray_hits_rect(v, v.left, r);
}

// Rust `sees(view, &Shape::Disc(d))`.
fn perception_maybe_sees_disc(mv: MaybeView, d: Disc) -> bool {
    return !mv.some || perception_sees_disc(mv.view, d);
}

// Rust `sees(view, &Shape::Rect(r))`.
fn perception_maybe_sees_rect(mv: MaybeView, r: Rect) -> bool {
    return !mv.some || perception_sees_rect(mv.view, r);
}

// Rust `group_disc`: group slot `g` (global) as the disc of the group radius around its centre.
fn perception_group_disc(g: u32) -> Disc {
    return Disc(sf[batch.c_g_x + g], sf[batch.c_g_y + g], params.group_radius);
}

// Rust `laptop_use_disc`: laptop use `u` (global slot) of environment e, centred halfway between
// the laptop and its user, of radius half the seat distance.
fn perception_laptop_use_disc(e: u32, u: u32) -> Disc {
    let h = at_human(e, su[batch.c_lu_human + u]);
    let l = at_laptop(e, su[batch.c_lu_laptop + u]);
    return Disc(
        0.5 * (sf[batch.c_l_x + l] + sf[batch.c_h_x + h]),
        0.5 * (sf[batch.c_l_y + l] + sf[batch.c_h_y + h]),
        0.5 * (params.laptop_width + params.human_laptop_distance),
    );
}

// Rust `sees_human`: does the view see human slot `j` (global) of environment e as 0.1.1 decides
// it (a lone human by its disc, a group member by its group's, a laptop user by its laptop use's)?
fn perception_sees_human(mv: MaybeView, e: u32, j: u32) -> bool {
    if (!mv.some) {
        return true;
    }
    let r = su[batch.c_h_role + j];
    if (r == ROLE_MOVING_GROUP || r == ROLE_STANDING_GROUP) {
        let g = at_group(e, su[batch.c_h_group + j]);
        return perception_sees_disc(mv.view, perception_group_disc(g));
    }
    if (r == ROLE_LAPTOP_USER) {
        let u = at_laptop_user(e, su[batch.c_h_laptop_user + j]);
        return perception_sees_disc(mv.view, perception_laptop_use_disc(e, u));
    }
    return perception_sees_disc(mv.view, Disc(sf[batch.c_h_x + j], sf[batch.c_h_y + j], params.human_radius));
}
