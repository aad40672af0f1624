//! Exact 2-D geometry of discs and rotated rectangles: intersection tests (touching counts, as
//! shapely's `intersects`), distances and nearest points. 0.1.1 approximates discs by inscribed
//! 64-gons; socnav uses the exact shapes (a 0.12 % difference in contact distance, see
//! `docs/fidelity.md`).

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

    #[test]
    fn segment_distance() {
        assert_eq!(origin_segment_distance(1.0, -1.0, 0.0, 2.0), 1.0);
        assert_eq!(origin_segment_distance(3.0, 4.0, 3.0, 4.0), 5.0);
        assert_eq!(origin_segment_distance(3.0, 4.0, 0.0, 0.0), 5.0);
        // The nearest point inside the segment: from (-1, 1) to (1, 1), distance 1.
        assert_eq!(origin_segment_distance(-1.0, 1.0, 2.0, 0.0), 1.0);
    }
}
