// requires: common/math.wgsl
//
// Twin of src/geometry.rs: exact 2-D geometry of discs and rotated rectangles (touching counts).
// Every function mirrors its Rust twin operation for operation (`Rect::distance_sq` is
// `geo_rect_distance_sq`, `disc_rect` is `geo_disc_rect`, ...); change both files in the same
// commit. Lengths in metres.

struct Disc {
    x: f32,
    y: f32,
    r: f32,
}

// A rotated rectangle: centre, cos and sin of its heading, half extents along local x and y.
struct Rect {
    x: f32,
    y: f32,
    c: f32,
    s: f32,
    hl: f32,
    hw: f32,
}

fn geo_rect_new(x: f32, y: f32, theta: f32, length: f32, width: f32) -> Rect {
    let sc = math_sin_cos(theta);
    return Rect(x, y, sc.y, sc.x, 0.5 * length, 0.5 * width);
}

fn geo_rect_with_trig(x: f32, y: f32, c: f32, s: f32, length: f32, width: f32) -> Rect {
    return Rect(x, y, c, s, 0.5 * length, 0.5 * width);
}

// World point -> rectangle frame.
fn geo_rect_to_local(r: Rect, px: f32, py: f32) -> vec2<f32> {
    let dx = px - r.x;
    let dy = py - r.y;
    return vec2<f32>(dx * r.c + dy * r.s, dy * r.c - dx * r.s);
}

// `a + s` for `s` a sum of two products, rounded as Rust's `a + (p + q)`. Mesa's NIR optimiser
// rewrites `(p + q) + a` into `(p + a) + q` when the inner sum has a single use ("FMA-friendly",
// see common/orca.wgsl's `orca_lp1`), which rounds differently; a second use of `s`, a NaN test
// of its bits that changes nothing (a NaN `s` makes `a + s` NaN too), keeps the Rust order.
fn geo_add_sum(a: f32, s: f32) -> f32 {
    return select(a + s, s, math_is_nan_bits(s));
}

// The point of the rectangle nearest to (px, py) (the point itself when inside).
fn geo_rect_nearest_point(r: Rect, px: f32, py: f32) -> vec2<f32> {
    let l = geo_rect_to_local(r, px, py);
    let qx = clamp(l.x, -r.hl, r.hl);
    let qy = clamp(l.y, -r.hw, r.hw);
    return vec2<f32>(geo_add_sum(r.x, qx * r.c - qy * r.s), geo_add_sum(r.y, qx * r.s + qy * r.c));
}

// Squared distance from (px, py) to the rectangle (0 inside).
fn geo_rect_distance_sq(r: Rect, px: f32, py: f32) -> f32 {
    let l = geo_rect_to_local(r, px, py);
    let dx = max(abs(l.x) - r.hl, 0.0);
    let dy = max(abs(l.y) - r.hw, 0.0);
    return dx * dx + dy * dy;
}

fn geo_disc_disc(a: Disc, b: Disc) -> bool {
    let dx = a.x - b.x;
    let dy = a.y - b.y;
    let r = a.r + b.r;
    return dx * dx + dy * dy <= r * r;
}

fn geo_disc_rect(d: Disc, r: Rect) -> bool {
    return geo_rect_distance_sq(r, d.x, d.y) <= d.r * d.r;
}

// Distance from the origin to the segment from a to a + e (m), the segment given by its
// displacement (see the Rust twin).
fn geo_origin_segment_distance(ax: f32, ay: f32, ex: f32, ey: f32) -> f32 {
    let len_sq = ex * ex + ey * ey;
    var t = 0.0;
    if (len_sq > 0.0) {
        t = clamp(-(ax * ex + ay * ey) / len_sq, 0.0, 1.0);
    }
    let px = ax + t * ex;
    let py = ay + t * ey;
    return sqrt(px * px + py * py);
}

// Circumradius: half the diagonal.
fn geo_rect_circumradius(r: Rect) -> f32 {
    return sqrt(r.hl * r.hl + r.hw * r.hw);
}
