// requires: common/math.wgsl
//
// Twin of src/geometry.rs: 2-D geometry of discs and rotated rectangles (touching counts), exact
// or with discs as 0.1.1's 64-gons. Every function mirrors its Rust twin operation for operation
// (`Rect::distance_sq` is `geo_rect_distance_sq`, `disc_rect` is `geo_disc_rect`, ...); change
// both files in the same commit. Lengths in metres.
//
// The 64-gon's constants come from the Rust definitions through the generated head of every
// shader (src/backend/wgsl/prelude.rs, `geometry_constants`): GEO_POLY64_COS (`POLY64_COS`),
// GEO_POLY64_OUTER, GEO_POLY64_INNER, and the contact-shape codes GEO_CONTACT_EXACT and
// GEO_CONTACT_POLYGON64.

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

// Direction m·π/64 (m < 64) as (cos, sin); sin(mπ/64) = cos(|32 − m|·π/64).
fn geo_poly64_dir(m: u32) -> vec2<f32> {
    let j = select(32u - m, m - 32u, m >= 32u);
    return vec2<f32>(GEO_POLY64_COS[m], GEO_POLY64_COS[j]);
}

// Is (dx, dy) in the regular 64-gon of circumradius r centred at the origin (touching counts)?
fn geo_poly64_contains(dx: f32, dy: f32, r: f32) -> bool {
    let apothem = r * GEO_POLY64_COS[1];
    for (var k = 0u; k < 32u; k++) {
        let n = geo_poly64_dir(2u * k + 1u);
        if (!(abs(dx * n.x + dy * n.y) <= apothem)) {
            return false;
        }
    }
    return true;
}

// Do two discs, each as 0.1.1's 64-gon, intersect (touching counts)?
fn geo_poly64_disc_disc(a: Disc, b: Disc) -> bool {
    let dx = a.x - b.x;
    let dy = a.y - b.y;
    let r = a.r + b.r;
    let dist_sq = dx * dx + dy * dy;
    let outer = r * GEO_POLY64_OUTER;
    if (dist_sq > outer * outer) {
        return false;
    }
    let inner = r * GEO_POLY64_INNER;
    if (dist_sq <= inner * inner) {
        return true;
    }
    return geo_poly64_contains(dx, dy, r);
}

// Half-widths of the unit 64-gon along (c, s) and (−s, c): max over its vertices of |v·u|.
fn geo_poly64_half_widths(c: f32, s: f32) -> vec2<f32> {
    var ha = 0.0;
    var hb = 0.0;
    for (var k = 0u; k < 32u; k++) {
        let v = geo_poly64_dir(2u * k);
        ha = max(ha, abs(v.x * c + v.y * s));
        hb = max(hb, abs(v.y * c - v.x * s));
    }
    return vec2<f32>(ha, hb);
}

// The separating-axis test of a disc's 64-gon and a rectangle: the rectangle's 2 normals, then
// the 64-gon's 32 edge normals.
fn geo_poly64_rect_overlap(d: Disc, r: Rect) -> bool {
    let l = geo_rect_to_local(r, d.x, d.y);
    let h = geo_poly64_half_widths(r.c, r.s);
    if (abs(l.x) > r.hl + d.r * h.x || abs(l.y) > r.hw + d.r * h.y) {
        return false;
    }
    let dx = d.x - r.x;
    let dy = d.y - r.y;
    let apothem = d.r * GEO_POLY64_COS[1];
    for (var k = 0u; k < 32u; k++) {
        let n = geo_poly64_dir(2u * k + 1u);
        // The rectangle's half-width along the normal n.
        let half = r.hl * abs(r.c * n.x + r.s * n.y) + r.hw * abs(r.c * n.y - r.s * n.x);
        if (!(abs(dx * n.x + dy * n.y) <= geo_add_sum(apothem, half))) {
            return false;
        }
    }
    return true;
}

// Does a disc as 0.1.1's 64-gon intersect a rectangle (touching counts)?
fn geo_poly64_disc_rect(d: Disc, r: Rect) -> bool {
    let dist_sq = geo_rect_distance_sq(r, d.x, d.y);
    let outer = d.r * GEO_POLY64_OUTER;
    if (dist_sq > outer * outer) {
        return false;
    }
    let inner = d.r * GEO_POLY64_INNER;
    if (dist_sq <= inner * inner) {
        return true;
    }
    return geo_poly64_rect_overlap(d, r);
}

// Do two discs intersect as contact shape `shape` (GEO_CONTACT_*) models them?
fn geo_disc_disc_as(shape: u32, a: Disc, b: Disc) -> bool {
    if (shape == GEO_CONTACT_POLYGON64) {
        return geo_poly64_disc_disc(a, b);
    }
    return geo_disc_disc(a, b);
}

// Do a disc and a rectangle intersect as contact shape `shape` (GEO_CONTACT_*) models the disc?
fn geo_disc_rect_as(shape: u32, d: Disc, r: Rect) -> bool {
    if (shape == GEO_CONTACT_POLYGON64) {
        return geo_poly64_disc_rect(d, r);
    }
    return geo_disc_rect(d, r);
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
