//! Exact 2-D geometry of discs and rotated rectangles: intersection tests (touching counts, as
//! shapely's `intersects`), distances and nearest points. 0.1.1 approximates discs by inscribed
//! 64-gons (shapely's `Point.buffer(r)`, vertices at k·π/32); socnav uses the exact shapes by
//! default (a 0.12 % difference in contact distance, see `docs/fidelity.md`), and 0.1.1's 64-gons
//! where the step's contact decisions ask for them (`[model] contact_shape = "polygon64"`):
//! [`poly64_disc_disc`], [`poly64_disc_rect`], chosen by [`disc_disc_as`] and [`disc_rect_as`].

use std::f32::consts::FRAC_1_SQRT_2;

use crate::math;

/// A disc (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disc {
    /// Centre x.
    pub x: f32,
    /// Centre y.
    pub y: f32,
    /// Radius.
    pub r: f32,
}

/// A rotated rectangle (m, rad): `length` along its local x axis, `width` along local y.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rect {
    /// Centre x.
    pub x: f32,
    /// Centre y.
    pub y: f32,
    /// cos of the heading.
    pub c: f32,
    /// sin of the heading.
    pub s: f32,
    /// Half extent along local x.
    pub hl: f32,
    /// Half extent along local y.
    pub hw: f32,
}

impl Rect {
    /// Rectangle centred at (x, y) with heading `theta`, `length` along local x and `width` along local y.
    pub fn new(x: f32, y: f32, theta: f32, length: f32, width: f32) -> Self {
        let (s, c) = math::sin_cos(theta);
        Self {
            x,
            y,
            c,
            s,
            hl: 0.5 * length,
            hw: 0.5 * width,
        }
    }

    /// Rectangle from its heading's cosine and sine (cached by callers whose rectangles never turn).
    #[inline]
    pub fn with_trig(x: f32, y: f32, c: f32, s: f32, length: f32, width: f32) -> Self {
        Self {
            x,
            y,
            c,
            s,
            hl: 0.5 * length,
            hw: 0.5 * width,
        }
    }

    /// World point → rectangle frame.
    #[inline]
    pub fn to_local(&self, px: f32, py: f32) -> (f32, f32) {
        let dx = px - self.x;
        let dy = py - self.y;
        (dx * self.c + dy * self.s, dy * self.c - dx * self.s)
    }

    /// Corner `k` in 0.1.1's counter-clockwise order: local (+L/2,+W/2), (−L/2,+W/2),
    /// (−L/2,−W/2), (+L/2,−W/2), rotated and translated. These are also RVO2's obstacle vertices.
    #[inline]
    pub fn corner(&self, k: usize) -> (f32, f32) {
        let (lx, ly) = match k {
            0 => (self.hl, self.hw),
            1 => (-self.hl, self.hw),
            2 => (-self.hl, -self.hw),
            _ => (self.hl, -self.hw),
        };
        (
            self.x + (lx * self.c - ly * self.s),
            self.y + (lx * self.s + ly * self.c),
        )
    }

    /// The point of the rectangle nearest to (px, py) (the point itself when inside).
    #[inline]
    pub fn nearest_point(&self, px: f32, py: f32) -> (f32, f32) {
        let (lx, ly) = self.to_local(px, py);
        let qx = lx.clamp(-self.hl, self.hl);
        let qy = ly.clamp(-self.hw, self.hw);
        (
            self.x + (qx * self.c - qy * self.s),
            self.y + (qx * self.s + qy * self.c),
        )
    }

    /// Squared distance from (px, py) to the rectangle (0 inside).
    #[inline]
    pub fn distance_sq(&self, px: f32, py: f32) -> f32 {
        let (lx, ly) = self.to_local(px, py);
        let dx = (lx.abs() - self.hl).max(0.0);
        let dy = (ly.abs() - self.hw).max(0.0);
        dx * dx + dy * dy
    }

    /// Circumradius: half the diagonal (the observation's "radius" of tables and laptops).
    pub fn circumradius(&self) -> f32 {
        (self.hl * self.hl + self.hw * self.hw).sqrt()
    }
}

/// Do two discs intersect (touching counts)?
#[inline]
pub fn disc_disc(a: &Disc, b: &Disc) -> bool {
    let dx = a.x - b.x;
    let dy = a.y - b.y;
    let r = a.r + b.r;
    dx * dx + dy * dy <= r * r
}

/// Do a disc and a rectangle intersect (touching counts)?
#[inline]
pub fn disc_rect(d: &Disc, r: &Rect) -> bool {
    r.distance_sq(d.x, d.y) <= d.r * d.r
}

/// Do two rectangles intersect (touching counts)? Separating-axis test on the four edge normals.
pub fn rect_rect(a: &Rect, b: &Rect) -> bool {
    let dx = b.x - a.x;
    let dy = b.y - a.y;
    for (ax, ay) in [(a.c, a.s), (-a.s, a.c), (b.c, b.s), (-b.s, b.c)] {
        let centre = (dx * ax + dy * ay).abs();
        let ra = a.hl * (a.c * ax + a.s * ay).abs() + a.hw * (-a.s * ax + a.c * ay).abs();
        let rb = b.hl * (b.c * ax + b.s * ay).abs() + b.hw * (-b.s * ax + b.c * ay).abs();
        if centre > ra + rb {
            return false;
        }
    }
    true
}

/// Codes of `[model] contact_shape` as [`crate::StepParams::contact_shape`] carries them (the
/// shaders' `GEO_CONTACT_*`).
pub mod contact_shape {
    /// Exact discs.
    pub const EXACT: u32 = 0;
    /// Discs as 0.1.1's regular 64-gons.
    pub const POLYGON64: u32 = 1;
}

/// cos(m·π/64) for m = 0..63 (each the f32 nearest the exact value): the 64-gon's vertex
/// directions are the even m (angles k·π/32, as GEOS places them) and its edge normals the odd m
/// ((k + ½)·π/32); half a turn of each suffices, the polygon being centrally symmetric. sin
/// comes from the same table (`poly64_dir`), so that cos and sin share their roundings and
/// the table is exactly symmetric. The shaders get these very bits as `GEO_POLY64_COS`
/// (generated by `backend::wgsl`).
#[rustfmt::skip]
pub const POLY64_COS: [f32; 64] = [
    1.0, 0.99879545, 0.9951847, 0.9891765, 0.98078525, 0.97003126, 0.95694035, 0.94154406,
    0.9238795, 0.9039893, 0.8819213, 0.8577286, 0.8314696, 0.8032075, 0.77301043, 0.7409511,
    FRAC_1_SQRT_2, 0.671559, 0.6343933, 0.5956993, 0.55557024, 0.51410276, 0.47139674, 0.42755508,
    0.38268343, 0.33688986, 0.29028466, 0.24298018, 0.19509032, 0.14673047, 0.09801714, 0.049067676,
    0.0, -0.049067676, -0.09801714, -0.14673047, -0.19509032, -0.24298018, -0.29028466, -0.33688986,
    -0.38268343, -0.42755508, -0.47139674, -0.51410276, -0.55557024, -0.5956993, -0.6343933, -0.671559,
    -FRAC_1_SQRT_2, -0.7409511, -0.77301043, -0.8032075, -0.8314696, -0.8577286, -0.8819213, -0.9039893,
    -0.9238795, -0.94154406, -0.95694035, -0.97003126, -0.98078525, -0.9891765, -0.9951847, -0.99879545,
];

/// Radius factor of the early "no contact" answer: beyond the circumscribed disc widened by
/// 2^-10 (≈ 0.1 %). The margin keeps the early answers equal to the full test's despite f32
/// rounding: a centre that far out is separated along some tested axis by at least
/// cos(π/64)·2^-10 of the radius (the nearest-point direction lies within π/64 of a tested axis
/// that both shapes' normal cones hold), ≥ 0.1 mm for the step's radii of ≥ 0.1 m, while the
/// full test's rounding is a few ulps of the coordinates, ≤ 2e-5 m at room coordinates of ≤ 50 m.
pub const POLY64_OUTER: f32 = 1.0 + 1.0 / 1024.0;

/// Radius factor of the early "contact" answer: within the inscribed disc (radius cos(π/64))
/// narrowed by 2^-10, where the shapes overlap by at least that much along every axis (see
/// [`POLY64_OUTER`] for why the margin).
pub const POLY64_INNER: f32 = POLY64_COS[1] * (1.0 - 1.0 / 1024.0);

/// Direction m·π/64 (m < 64) as (cos, sin); sin(mπ/64) = cos(|32 − m|·π/64).
#[inline]
fn poly64_dir(m: usize) -> (f32, f32) {
    (POLY64_COS[m], POLY64_COS[m.abs_diff(32)])
}

/// Is (dx, dy) in the regular 64-gon of circumradius `r` centred at the origin, vertices at
/// k·π/32 (touching counts)? It is iff its projection on each of the 32 edge-normal directions
/// (k + ½)·π/32 is at most the apothem r·cos(π/64).
#[inline]
fn poly64_contains(dx: f32, dy: f32, r: f32) -> bool {
    let apothem = r * POLY64_COS[1];
    (0..32).all(|k| {
        let (c, s) = poly64_dir(2 * k + 1);
        (dx * c + dy * s).abs() <= apothem
    })
}

/// Do two discs, each as 0.1.1's 64-gon, intersect (touching counts)? Two 64-gons with the same
/// vertex angles intersect iff the centre difference lies in their Minkowski difference, the
/// 64-gon of circumradius r1 + r2 (the 64-gon is centrally symmetric).
#[inline]
pub fn poly64_disc_disc(a: &Disc, b: &Disc) -> bool {
    let dx = a.x - b.x;
    let dy = a.y - b.y;
    let r = a.r + b.r;
    let dist_sq = dx * dx + dy * dy;
    let outer = r * POLY64_OUTER;
    if dist_sq > outer * outer {
        return false;
    }
    let inner = r * POLY64_INNER;
    if dist_sq <= inner * inner {
        return true;
    }
    poly64_contains(dx, dy, r)
}

/// Does a disc as 0.1.1's 64-gon intersect a rectangle (touching counts)? Exact-disc early
/// answers outside the widened circumscribed disc and inside the narrowed inscribed disc, then
/// the separating-axis test.
#[inline]
pub fn poly64_disc_rect(d: &Disc, r: &Rect) -> bool {
    let dist_sq = r.distance_sq(d.x, d.y);
    let outer = d.r * POLY64_OUTER;
    if dist_sq > outer * outer {
        return false;
    }
    let inner = d.r * POLY64_INNER;
    if dist_sq <= inner * inner {
        return true;
    }
    poly64_rect_overlap(d, r)
}

/// The separating-axis test of a disc's 64-gon and a rectangle: no separation along the
/// rectangle's 2 normals nor the 64-gon's 32 edge normals.
fn poly64_rect_overlap(d: &Disc, r: &Rect) -> bool {
    let (lx, ly) = r.to_local(d.x, d.y);
    let (ha, hb) = poly64_half_widths(r.c, r.s);
    if lx.abs() > r.hl + d.r * ha || ly.abs() > r.hw + d.r * hb {
        return false;
    }
    let dx = d.x - r.x;
    let dy = d.y - r.y;
    let apothem = d.r * POLY64_COS[1];
    (0..32).all(|k| {
        let (c, s) = poly64_dir(2 * k + 1);
        // The rectangle's half-width along the normal (c, s).
        let half = r.hl * (r.c * c + r.s * s).abs() + r.hw * (r.c * s - r.s * c).abs();
        (dx * c + dy * s).abs() <= apothem + half
    })
}

/// Half-widths of the unit 64-gon along (c, s) and (−s, c): its support max_k |v_k·u| over the
/// vertices v_k (k < 32; the others are their opposites).
fn poly64_half_widths(c: f32, s: f32) -> (f32, f32) {
    let mut ha = 0.0f32;
    let mut hb = 0.0f32;
    for k in 0..32 {
        let (vc, vs) = poly64_dir(2 * k);
        ha = ha.max((vc * c + vs * s).abs());
        hb = hb.max((vs * c - vc * s).abs());
    }
    (ha, hb)
}

/// Do two discs intersect as `shape` (a [`contact_shape`] code) models them?
#[inline]
pub fn disc_disc_as(shape: u32, a: &Disc, b: &Disc) -> bool {
    if shape == contact_shape::POLYGON64 {
        poly64_disc_disc(a, b)
    } else {
        disc_disc(a, b)
    }
}

/// Do a disc and a rectangle intersect as `shape` (a [`contact_shape`] code) models the disc?
#[inline]
pub fn disc_rect_as(shape: u32, d: &Disc, r: &Rect) -> bool {
    if shape == contact_shape::POLYGON64 {
        poly64_disc_rect(d, r)
    } else {
        disc_rect(d, r)
    }
}

/// Any of the two shapes a spawn check deals with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// A disc.
    Disc(Disc),
    /// A rotated rectangle.
    Rect(Rect),
}

impl Shape {
    /// Do the two shapes intersect (touching counts)?
    #[inline]
    pub fn intersects(&self, other: &Shape) -> bool {
        match (self, other) {
            (Shape::Disc(a), Shape::Disc(b)) => disc_disc(a, b),
            (Shape::Disc(d), Shape::Rect(r)) | (Shape::Rect(r), Shape::Disc(d)) => disc_rect(d, r),
            (Shape::Rect(a), Shape::Rect(b)) => rect_rect(a, b),
        }
    }
}

/// Distance from the origin to the segment from `a` to `a + e` (m). The segment is given by its
/// displacement `e`, not its end: `(a + e) - a` would round, and Mesa's shader optimiser folds it
/// to `e` on lavapipe, which would break CPU/GPU parity.
#[inline]
pub fn origin_segment_distance(ax: f32, ay: f32, ex: f32, ey: f32) -> f32 {
    let len_sq = ex * ex + ey * ey;
    let t = if len_sq > 0.0 {
        (-(ax * ex + ay * ey) / len_sq).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let px = ax + t * ex;
    let py = ay + t * ey;
    (px * px + py * py).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn discs_touching_intersect() {
        let a = Disc {
            x: 0.0,
            y: 0.0,
            r: 1.0,
        };
        assert!(disc_disc(
            &a,
            &Disc {
                x: 2.0,
                y: 0.0,
                r: 1.0
            }
        ));
        assert!(!disc_disc(
            &a,
            &Disc {
                x: 2.001,
                y: 0.0,
                r: 1.0
            }
        ));
    }

    #[test]
    fn disc_against_rotated_rect() {
        // A 2 x 1 rectangle turned by 90°: it spans |x| <= 0.5, |y| <= 1.
        let r = Rect::new(0.0, 0.0, math::FRAC_PI_2, 2.0, 1.0);
        assert!(disc_rect(
            &Disc {
                x: 0.0,
                y: 1.4,
                r: 0.41
            },
            &r
        ));
        assert!(!disc_rect(
            &Disc {
                x: 0.0,
                y: 1.4,
                r: 0.39
            },
            &r
        ));
        assert!(!disc_rect(
            &Disc {
                x: 0.9,
                y: 0.0,
                r: 0.39
            },
            &r
        ));
        // Corner region: nearest point is the corner (0.5, 1).
        let d = (0.3f32 * 0.3 + 0.3 * 0.3).sqrt();
        assert!(disc_rect(
            &Disc {
                x: 0.8,
                y: 1.3,
                r: d + 1e-4
            },
            &r
        ));
        assert!(!disc_rect(
            &Disc {
                x: 0.8,
                y: 1.3,
                r: d - 1e-4
            },
            &r
        ));
    }

    #[test]
    fn rect_rect_separating_axes() {
        let a = Rect::new(0.0, 0.0, 0.0, 2.0, 2.0);
        // A diamond whose corner points at a's right edge.
        let b = Rect::new(2.40, 0.0, math::PI / 4.0, 2.0, 2.0);
        assert!(
            rect_rect(&a, &b),
            "the diamond's corner reaches x = 2.40 - √2 = 0.986 < 1"
        );
        let c = Rect::new(2.45, 0.0, math::PI / 4.0, 2.0, 2.0);
        assert!(!rect_rect(&a, &c));
        assert!(
            rect_rect(&a, &Rect::new(0.0, 0.0, 0.3, 0.1, 0.1)),
            "containment intersects"
        );
    }

    #[test]
    fn corners_are_counter_clockwise() {
        let r = Rect::new(1.0, 2.0, 0.0, 4.0, 2.0);
        assert_eq!(r.corner(0), (3.0, 3.0));
        assert_eq!(r.corner(1), (-1.0, 3.0));
        assert_eq!(r.corner(2), (-1.0, 1.0));
        assert_eq!(r.corner(3), (3.0, 1.0));
    }

    /// A unit vector at angle `a` (rad), in f32 (`math::sin_cos` is within 2 ulps; the cases
    /// below stay at least 0.1 mm clear of every threshold).
    fn dir(a: f64) -> (f32, f32) {
        let (s, c) = math::sin_cos(a as f32);
        (c, s)
    }

    /// Contract: between two vertices (angles π/64 + k·π/32) the 64-gons of two discs reach only
    /// the apothem, cos(π/64) ≈ 0.998795 of the radii sum: a centre distance between that and
    /// the sum touches as exact discs and not as 64-gons; along a vertex direction (k·π/32) both
    /// touch, and beyond the sum neither does.
    #[test]
    fn poly64_discs_differ_from_exact_discs_only_between_vertices() {
        let a = Disc {
            x: 0.5,
            y: -1.0,
            r: 0.25,
        };
        let at = |angle: f64, dist: f64| {
            let (c, s) = dir(angle);
            Disc {
                x: a.x + (dist as f32) * c,
                y: a.y + (dist as f32) * s,
                r: 0.4,
            }
        };
        // Radii sum 0.65 m; the 64-gons' inset there is 0.65·(1 − cos(π/64)) = 0.78 mm.
        let inside_inset = 0.65 * 0.9994;
        for k in 0..64 {
            let between = std::f64::consts::PI / 64.0 + f64::from(k) * std::f64::consts::PI / 32.0;
            let vertex = f64::from(k) * std::f64::consts::PI / 32.0;
            let b = at(between, inside_inset);
            assert!(
                disc_disc(&a, &b) && !poly64_disc_disc(&a, &b),
                "between, k = {k}"
            );
            let b = at(vertex, inside_inset);
            assert!(
                disc_disc(&a, &b) && poly64_disc_disc(&a, &b),
                "vertex, k = {k}"
            );
            let b = at(vertex, 0.65 * 1.0002);
            assert!(
                !disc_disc(&a, &b) && !poly64_disc_disc(&a, &b),
                "beyond, k = {k}"
            );
            let b = at(between, 0.65 * 0.9985);
            assert!(
                disc_disc(&a, &b) && poly64_disc_disc(&a, &b),
                "within apothem, k = {k}"
            );
        }
        // Exactly touching at a vertex counts (shapely's `intersects`): vertex (1, 0) of a unit
        // circumradius meets the other's vertex.
        let o = Disc {
            x: 0.0,
            y: 0.0,
            r: 0.5,
        };
        let touching = Disc {
            x: 1.0,
            y: 0.0,
            r: 0.5,
        };
        assert!(poly64_disc_disc(&o, &touching) && disc_disc(&o, &touching));
        assert!(disc_disc_as(
            contact_shape::EXACT,
            &a,
            &at(0.05, inside_inset)
        ));
        assert!(!disc_disc_as(
            contact_shape::POLYGON64,
            &a,
            &at(0.05, inside_inset)
        ));
    }

    /// Contract: a rectangle turned by π/64 faces the 64-gon's edge: a disc whose centre is `gap`
    /// beyond that face, r·cos(π/64) < gap < r, touches as an exact disc and not as a 64-gon;
    /// the same rectangle unturned faces a vertex and both touch. Off a corner, the same holds
    /// for the directions between vertices and at vertices.
    #[test]
    fn poly64_disc_against_a_rectangle() {
        let r = 0.36;
        let gap = r * 0.9994;
        for theta in [0.0, std::f64::consts::PI / 64.0] {
            let rect = Rect::new(1.0, 2.0, theta as f32, 2.0, 1.0);
            let (c, s) = dir(theta);
            // Beyond the +x face (half length 1), and beyond the +y face (half width 0.5).
            for (along, across) in [(1.0 + gap, 0.2), (-0.3, 0.5 + gap)] {
                let d = Disc {
                    x: 1.0 + (along as f32) * c - (across as f32) * s,
                    y: 2.0 + (along as f32) * s + (across as f32) * c,
                    r: r as f32,
                };
                let (_, ny) = rect.to_local(d.x, d.y);
                let face_is_edge = theta != 0.0;
                assert!(disc_rect(&d, &rect), "exact, θ = {theta}, local y {ny}");
                assert_eq!(
                    poly64_disc_rect(&d, &rect),
                    !face_is_edge,
                    "64-gon, θ = {theta}, along {along}, across {across}"
                );
            }
        }
        // Off corner (1, 0.5) of an unturned 2 x 1 rectangle at the origin.
        let rect = Rect::new(0.0, 0.0, 0.0, 2.0, 1.0);
        for k in 0..16 {
            for (angle, polygon_touches) in [
                (f64::from(k) * std::f64::consts::PI / 32.0, true),
                ((f64::from(k) + 0.5) * std::f64::consts::PI / 32.0, false),
            ] {
                let (c, s) = dir(angle);
                let d = Disc {
                    x: 1.0 + (gap as f32) * c,
                    y: 0.5 + (gap as f32) * s,
                    r: r as f32,
                };
                assert!(disc_rect(&d, &rect), "exact, corner, angle {angle}");
                assert_eq!(
                    poly64_disc_rect(&d, &rect),
                    polygon_touches,
                    "64-gon, corner, angle {angle}"
                );
                assert_eq!(
                    disc_rect_as(contact_shape::POLYGON64, &d, &rect),
                    polygon_touches
                );
            }
        }
        // Deep inside, and far away.
        let inside = Disc {
            x: 0.9,
            y: 0.0,
            r: 0.2,
        };
        assert!(poly64_disc_rect(&inside, &rect));
        let far = Disc {
            x: 3.0,
            y: 3.0,
            r: 0.2,
        };
        assert!(!poly64_disc_rect(&far, &rect));
    }

    /// Contract: the early answers (outside the widened circumscribed disc, inside the narrowed
    /// inscribed disc) never differ from the full tests, on pairs around both radii at room
    /// coordinates.
    #[test]
    fn poly64_early_answers_match_the_full_tests() {
        let mut state = 0x9e37_79b9_u32;
        let mut uniform = |lo: f32, hi: f32| {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            lo + (hi - lo) * (state >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut early = 0;
        for _ in 0..200_000 {
            let (x, y) = (uniform(-10.0, 10.0), uniform(-10.0, 10.0));
            let r = uniform(0.1, 0.6);
            let angle = uniform(-3.2, 3.2);
            // Around the inscribed (0.9988) and circumscribed (1) radii, both margins included.
            let t = uniform(0.996, 1.003);
            let (s, c) = math::sin_cos(angle);
            let a = Disc { x, y, r };
            let b = Disc {
                x: x + t * 2.0 * r * c,
                y: y + t * 2.0 * r * s,
                r,
            };
            let full = poly64_contains(a.x - b.x, a.y - b.y, a.r + b.r);
            assert_eq!(poly64_disc_disc(&a, &b), full, "{a:?} {b:?}");
            let rect = Rect::new(
                x,
                y,
                uniform(-3.2, 3.2),
                uniform(0.1, 3.0),
                uniform(0.05, 1.5),
            );
            // A centre at t·r beyond a random point of the rectangle's boundary region.
            let (lx, ly) = (uniform(-rect.hl, rect.hl), rect.hw + t * r);
            let (lx, ly) = if uniform(0.0, 1.0) < 0.5 {
                (lx, ly)
            } else {
                (rect.hl + t * r * c.abs(), rect.hw + t * r * s.abs())
            };
            let d = Disc {
                x: rect.x + (lx * rect.c - ly * rect.s),
                y: rect.y + (lx * rect.s + ly * rect.c),
                r,
            };
            let full = poly64_rect_overlap(&d, &rect);
            assert_eq!(poly64_disc_rect(&d, &rect), full, "{d:?} {rect:?}");
            let dist_sq = rect.distance_sq(d.x, d.y);
            early += usize::from(
                dist_sq > (r * POLY64_OUTER) * (r * POLY64_OUTER)
                    || dist_sq <= (r * POLY64_INNER) * (r * POLY64_INNER),
            );
        }
        // Most of those pairs take an early answer, so the comparison covers them.
        assert!(early > 100_000, "{early} early answers");
    }

    #[test]
    fn segment_distance() {
        assert_eq!(origin_segment_distance(1.0, -1.0, 0.0, 2.0), 1.0);
        assert_eq!(origin_segment_distance(3.0, 4.0, 3.0, 4.0), 5.0);
        assert_eq!(origin_segment_distance(3.0, 4.0, 0.0, 0.0), 5.0);
        // The nearest point inside the segment: from (-1, 1) to (1, 1), distance 1.
        assert_eq!(origin_segment_distance(-1.0, 1.0, 2.0, 0.0), 1.0);
    }
}
