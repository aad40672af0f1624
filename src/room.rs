//! Room layouts (docs/spec.md 3.3): the walls of square, rectangular and L-shaped rooms, corridor
//! walls with doors, and the invisible spawn blockers (the L room's removed block, the door gaps).
//!
//! Walls are rectangles of the configured thickness whose outer face lies on the map border; the
//! L room's two inner walls are centred on the removed block's edges. Wall order and headings
//! follow 0.1.1 (checked against the golden episodes' headers), because they fix the order and
//! direction of the observed wall segments.
//!
//! Below the state: scenario generation builds an episode's room with it and `state::Caps` builds
//! every room a config allows to size the wall columns. The codes of the state's `room_shape` and
//! `b_kind` columns live here with the layouts that use them (`state` re-exports them).

use crate::fixed::Fixed;
use crate::math::{FRAC_PI_2, PI};
use crate::params::StepParams;
use crate::rng::RngStream;

/// Kind of an invisible spawn blocker (column `b_kind`): which entity type 0.1.1 used for it.
pub mod blocker_kind {
    /// The removed block of an L-shaped room (0.1.1 uses a laptop-typed rectangle).
    pub const L_BLOCK: u32 = 0;
    /// A corridor door gap (0.1.1 uses a wall-typed rectangle).
    pub const DOOR: u32 = 1;
}

/// Room shape of the current episode (column `room_shape`).
pub mod room_shape {
    /// Square.
    pub const SQUARE: u32 = 0;
    /// Rectangle.
    pub const RECTANGLE: u32 = 1;
    /// L-shaped.
    pub const L: u32 = 2;
    /// No walls.
    pub const NO_WALLS: u32 = 3;
}

/// A wall or blocker rectangle (m, rad).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Piece {
    /// Centre x.
    pub x: f32,
    /// Centre y.
    pub y: f32,
    /// Heading of the long axis.
    pub theta: f32,
    /// Extent along the heading.
    pub length: f32,
    /// Extent across (the wall thickness for walls).
    pub width: f32,
}

/// Most walls a room has: an L room's eight plus four corridor pieces.
pub const MAX_WALLS: usize = 12;

/// Most spawn blockers a room has: the L block and two doors.
pub const MAX_BLOCKERS: usize = 3;

/// The walls and blockers of one room, in 0.1.1's order.
#[derive(Debug, Clone, Default)]
pub struct RoomLayout {
    /// Walls.
    pub walls: Fixed<Piece, MAX_WALLS>,
    /// L-block and door blockers, with their `blocker_kind` code.
    pub blockers: Fixed<(u32, Piece), MAX_BLOCKERS>,
}

/// How the observation splits a wall of `length` (m) into segments of `step` (m): `full` segments
/// of length `step` from the wall's left end, then one of length `rest` if `rest > 0`.
#[inline]
pub fn segments(length: f32, step: f32) -> (u32, f32) {
    let full = (length / step).floor();
    (full as u32, length - full * step)
}

/// Number of observed segments of a wall of `length` (m); `u32::MAX` for a wall of that many
/// or more (a loaded document's, which the capacity check then refuses), never a count wrapped
/// past it.
#[inline]
pub fn segment_count(length: f32, step: f32) -> u32 {
    let (full, rest) = segments(length, step);
    full.saturating_add(u32::from(rest > 0.0))
}

/// Build the walls of an `x` by `y` room (m) of shape `shape` ([`room_shape`]); `l_location`
/// (0 top-right, 1 top-left, 2 bottom-right, 3 bottom-left) picks the L room's removed corner.
pub fn build(
    p: &StepParams,
    rng: &mut RngStream,
    shape: u32,
    x: f32,
    y: f32,
    l_location: u32,
    out: &mut RoomLayout,
) {
    out.walls.clear();
    out.blockers.clear();
    let t = p.wall_thickness;
    match shape {
        room_shape::NO_WALLS => {}
        room_shape::L => {
            let (lx, ly) = l_room(t, x, y, l_location, out);
            if p.corridors != 0 {
                l_corridors(p, rng, x, y, lx, ly, l_location, out);
            }
        }
        _ => {
            box_walls(t, x, y, out);
            if p.corridors != 0 {
                for k in 1..3 {
                    let line_y = -0.5 * y + k as f32 * y / 3.0;
                    corridor_wall(p, rng, 0.0, line_y, 0.0, x, out);
                }
            }
        }
    }
}

fn wall(out: &mut RoomLayout, t: f32, x: f32, y: f32, theta: f32, length: f32) {
    out.walls.push(Piece {
        x,
        y,
        theta,
        length,
        width: t,
    });
}

/// The four walls of a rectangular room: right, bottom, left, top.
fn box_walls(t: f32, x: f32, y: f32, out: &mut RoomLayout) {
    let (hx, hy) = (0.5 * x, 0.5 * y);
    wall(out, t, hx - 0.5 * t, 0.0, -FRAC_PI_2, y);
    wall(out, t, 0.0, -hy + 0.5 * t, -PI, x);
    wall(out, t, -hx + 0.5 * t, 0.0, FRAC_PI_2, y);
    wall(out, t, 0.0, hy - 0.5 * t, 0.0, x);
}

/// The eight walls of an L room, walking its outline; returns the removed block's size.
fn l_room(t: f32, x: f32, y: f32, loc: u32, out: &mut RoomLayout) -> (f32, f32) {
    let (hx, hy, ht) = (0.5 * x, 0.5 * y, 0.5 * t);
    let (lx, ly) = if loc == 0 || loc == 3 {
        (2.0 * x / 3.0, y / 3.0)
    } else {
        (x / 3.0, 2.0 * y / 3.0)
    };
    let (block_x, block_y) = match loc {
        0 => {
            wall(out, t, hx - lx, hy - 0.5 * ly, FRAC_PI_2, ly);
            wall(out, t, -0.5 * lx, hy - ht, PI, x - lx);
            wall(out, t, -hx + ht, hy - 0.5 * ly, -FRAC_PI_2, ly);
            wall(out, t, -hx + ht, -0.5 * ly, -FRAC_PI_2, y - ly);
            wall(out, t, -0.5 * lx, -hy + ht, 0.0, x - lx);
            wall(out, t, hx - 0.5 * lx, -hy + ht, 0.0, lx);
            wall(out, t, hx - ht, -0.5 * ly, FRAC_PI_2, y - ly);
            wall(out, t, hx - 0.5 * lx, hy - ly, PI, lx);
            (hx - 0.5 * lx, hy - 0.5 * ly)
        }
        1 => {
            wall(out, t, -hx + 0.5 * lx, hy - ly, PI, lx);
            wall(out, t, -hx + ht, -0.5 * ly, -FRAC_PI_2, y - ly);
            wall(out, t, -hx + 0.5 * lx, -hy + ht, 0.0, lx);
            wall(out, t, 0.5 * lx, -hy + ht, 0.0, x - lx);
            wall(out, t, hx - ht, -0.5 * ly, FRAC_PI_2, y - ly);
            wall(out, t, hx - ht, hy - 0.5 * ly, FRAC_PI_2, ly);
            wall(out, t, 0.5 * lx, hy - ht, PI, x - lx);
            wall(out, t, -hx + lx, hy - 0.5 * ly, FRAC_PI_2, ly);
            (-hx + 0.5 * lx, hy - 0.5 * ly)
        }
        2 => {
            wall(out, t, hx - 0.5 * lx, -hy + ly, 0.0, lx);
            wall(out, t, hx - ht, 0.5 * ly, FRAC_PI_2, y - ly);
            wall(out, t, hx - 0.5 * lx, hy - ht, PI, lx);
            wall(out, t, -0.5 * lx, hy - ht, PI, x - lx);
            wall(out, t, -hx + ht, 0.5 * ly, -FRAC_PI_2, y - ly);
            wall(out, t, -hx + ht, 0.5 * ly - hy, -FRAC_PI_2, ly);
            wall(out, t, -0.5 * lx, -hy + ht, 0.0, x - lx);
            wall(out, t, hx - lx, -hy + 0.5 * ly, FRAC_PI_2, ly);
            (hx - 0.5 * lx, -hy + 0.5 * ly)
        }
        _ => {
            // Not seen in the golden set: mirrors location 0 through the x axis.
            wall(out, t, -hx + lx, -hy + 0.5 * ly, FRAC_PI_2, ly);
            wall(out, t, 0.5 * lx, -hy + ht, 0.0, x - lx);
            wall(out, t, hx - ht, -hy + 0.5 * ly, FRAC_PI_2, ly);
            wall(out, t, hx - ht, 0.5 * ly, FRAC_PI_2, y - ly);
            wall(out, t, 0.5 * lx, hy - ht, PI, x - lx);
            wall(out, t, 0.5 * lx - hx, hy - ht, PI, lx);
            wall(out, t, -hx + ht, 0.5 * ly, -FRAC_PI_2, y - ly);
            wall(out, t, -hx + 0.5 * lx, -hy + ly, 0.0, lx);
            (-hx + 0.5 * lx, -hy + 0.5 * ly)
        }
    };
    let block = Piece {
        x: block_x,
        y: block_y,
        theta: 0.0,
        length: lx,
        width: ly,
    };
    out.blockers.push((blocker_kind::L_BLOCK, block));
    (lx, ly)
}

/// Corridors of an L room: the removed block's two inner edges extended across the room.
#[expect(
    clippy::too_many_arguments,
    reason = "room geometry is passed as plain numbers"
)]
fn l_corridors(
    p: &StepParams,
    rng: &mut RngStream,
    x: f32,
    y: f32,
    lx: f32,
    ly: f32,
    loc: u32,
    out: &mut RoomLayout,
) {
    let (hx, hy) = (0.5 * x, 0.5 * y);
    // Signs of the removed corner: +x for locations 0 and 2, +y for 0 and 1.
    let sx = if loc == 0 || loc == 2 { 1.0 } else { -1.0 };
    let sy = if loc == 0 || loc == 1 { 1.0 } else { -1.0 };
    let edge_y = sy * (hy - ly);
    let edge_x = sx * (hx - lx);
    // Horizontal line from the block's inner edge to the opposite outer wall.
    let h_len = x - lx;
    corridor_wall(p, rng, -sx * 0.5 * lx, edge_y, 0.0, h_len, out);
    let v_len = y - ly;
    corridor_wall(p, rng, edge_x, -sy * 0.5 * ly, FRAC_PI_2, v_len, out);
}

/// A straight internal wall of `length` centred at (cx, cy) along `theta`, with one door: width
/// g = u·m + m (m = max(robot diameter, human diameter) + 0.5) centred at offset U[0,1)·(L/2 − g/2)
/// from the middle (0.1.1 only samples the positive half). Pushes the two pieces and the door blocker.
fn corridor_wall(
    p: &StepParams,
    rng: &mut RngStream,
    cx: f32,
    cy: f32,
    theta: f32,
    length: f32,
    out: &mut RoomLayout,
) {
    let m = (2.0 * p.robot_radius).max(2.0 * p.human_radius) + 0.5;
    // A door wider than its wall (a large robot in a short L-room corridor line) would give the
    // pieces negative lengths (0.1.1 builds them so): the door then spans the whole line.
    let g = (rng.next_f32() * m + m).min(length);
    let c = rng.next_f32() * (0.5 * length - 0.5 * g);
    let (s, co) = crate::math::sin_cos(theta);
    let half = 0.5 * length;
    let left_len = half + c - 0.5 * g;
    let right_len = half - c - 0.5 * g;
    let t = p.wall_thickness;
    let at = |offset: f32| (cx + offset * co, cy + offset * s);
    // A piece the door leaves nothing of (it spans the line) is left out: a wall of no length
    // is no obstacle, and ORCA's obstacle processing refuses its zero-length edges. Any other
    // piece is built, however short, as 0.1.1 builds it.
    if left_len > 0.0 {
        let (lx, ly) = at(-half + 0.5 * left_len);
        wall(out, t, lx, ly, theta, left_len);
    }
    if right_len > 0.0 {
        let (rx, ry) = at(half - 0.5 * right_len);
        wall(out, t, rx, ry, theta, right_len);
    }
    let (dx, dy) = at(c);
    out.blockers.push((
        blocker_kind::DOOR,
        Piece {
            x: dx,
            y: dy,
            theta,
            length: g,
            width: t,
        },
    ));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> StepParams {
        StepParams::new(&crate::config::Config::default(), Default::default())
    }

    #[test]
    fn square_walls_match_golden_header() {
        // exp1/exp2 golden headers: (4.9, 0, -π/2, 10), (0, -4.9, -π, 10), (-4.9, 0, π/2, 10), (0, 4.9, 0, 10).
        let mut out = RoomLayout::default();
        let mut rng = RngStream::new(0, 0);
        build(
            &params(),
            &mut rng,
            room_shape::SQUARE,
            10.0,
            10.0,
            0,
            &mut out,
        );
        let got: Vec<_> = out
            .walls
            .as_slice()
            .iter()
            .map(|w| (w.x, w.y, w.theta, w.length))
            .collect();
        assert_eq!(
            got,
            vec![
                (4.9, 0.0, -FRAC_PI_2, 10.0),
                (0.0, -4.9, -PI, 10.0),
                (-4.9, 0.0, FRAC_PI_2, 10.0),
                (0.0, 4.9, 0.0, 10.0)
            ]
        );
        assert!(out.blockers.is_empty());
    }

    #[test]
    fn l_room_location_0_matches_golden_header() {
        // lroom_mixed seed 2: 11 m room, block removed top-right (7.333 x 3.667).
        let mut out = RoomLayout::default();
        let mut rng = RngStream::new(0, 0);
        build(&params(), &mut rng, room_shape::L, 11.0, 11.0, 0, &mut out);
        let expected = [
            (-1.833_333_3, 3.666_666_7, FRAC_PI_2, 3.666_666_5),
            (-3.666_666_5, 5.4, PI, 3.666_667),
            (-5.4, 3.666_666_5, -FRAC_PI_2, 3.666_666_5),
            (-5.4, -1.833_333_3, -FRAC_PI_2, 7.333_333),
            (-3.666_666_5, -5.4, 0.0, 3.666_666_5),
            (1.833_333_3, -5.4, 0.0, 7.333_333),
            (5.4, -1.833_333_3, FRAC_PI_2, 7.333_334),
            (1.833_333_5, 1.833_333_5, PI, 7.333_333),
        ];
        assert_eq!(out.walls.len(), 8);
        for (w, e) in out.walls.as_slice().iter().zip(expected) {
            // Golden values are f64; 1e-5 m covers their rounding to f32 and our f32 arithmetic.
            assert!(
                (w.x - e.0).abs() < 1e-5 && (w.y - e.1).abs() < 1e-5,
                "{w:?} vs {e:?}"
            );
            assert_eq!(w.theta, e.2);
            assert!((w.length - e.3).abs() < 1e-5, "{w:?} vs {e:?}");
        }
        let (_, b) = out.blockers[0];
        assert!((b.x - 1.833_333_5).abs() < 1e-5 && (b.y - 3.666_666_7).abs() < 1e-5);
    }

    #[test]
    fn corridor_doors_lie_in_their_walls() {
        let mut p = params();
        p.corridors = 1;
        p.robot_radius = 0.7;
        for k in 0..50 {
            let mut out = RoomLayout::default();
            let mut rng = RngStream::new(7 + k as u64, 0);
            build(&p, &mut rng, room_shape::RECTANGLE, 14.0, 11.0, 0, &mut out);
            assert_eq!(out.walls.len(), 8);
            assert_eq!(out.blockers.len(), 2);
            for (i, (_, door)) in out.blockers.as_slice().iter().enumerate() {
                let left = out.walls[4 + 2 * i];
                let right = out.walls[5 + 2 * i];
                // The three pieces tile the 14 m line: left piece, door, right piece.
                let total = left.length + door.length + right.length;
                assert!((total - 14.0).abs() < 1e-4, "pieces sum to {total}");
                assert!(
                    (1.9..3.8).contains(&door.length),
                    "door width {}",
                    door.length
                );
                assert!(door.x >= 0.0, "0.1.1 only places doors in the right half");
                assert!((left.x + 0.5 * left.length - (door.x - 0.5 * door.length)).abs() < 1e-4);
            }
        }
    }
}
