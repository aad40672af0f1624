//! How the replay decides contacts (docs/spec.md 4.6, 8.1, 8.2), and which decisions may differ
//! from 0.1.1's within their conditioning.
//!
//! 0.1.1 tests every contact on shapely polygons: a disc (robot, human, plant) is a 64-gon that
//! sits up to 1 − cos(π/64) = 0.12 % of its radius inside the circle. socnav decides contacts
//! as `[model] contact_shape` says: with `"exact"` discs, a contact within that inset may be
//! decided differently (a human pushed out by one side only, a collision seen by one side only);
//! with `"polygon64"`, socnav tests the same 64-gons, and only a contact within the f32 rounding
//! of positions of the polygon's boundary may differ. The replay runs with both shapes.

use serde_json::Value;
use socnav::config::ContactShape;
use socnav::geometry::{Disc, Rect, contact_shape, disc_disc_as, disc_rect_as};

use super::{Step, num};

/// Fraction of the radii within which an exact-disc decision may differ from 0.1.1's: the
/// 64-gon's inset 1 − cos(π/64) = 0.12 %, and the f32 rounding of metre-scale positions well
/// inside it.
pub const CONTACT_FLIP_FRACTION: f64 = 0.0013;

/// Distance (m) from the polygon's boundary within which a 64-gon decision may differ from
/// 0.1.1's: socnav tests the same polygons in f32, from positions that agree with 0.1.1's within
/// the replay's position tolerance (`compare::POS`, 2e-5 m; the largest difference measured on
/// the published episodes is 2.4e-6 m). The polygon test itself rounds at ~1e-6 m
/// (`tests/suite/step/contacts/shape.rs` against shapely), inside that.
pub const POLYGON64_FLIP_DISTANCE: f64 = super::compare::POS;

/// How the replay decides a contact: the shape socnav was configured with, and how far (a
/// fraction of every disc's radius) the decision's threshold may lie from 0.1.1's.
#[derive(Debug, Clone, Copy)]
pub struct ContactRule {
    /// The shape socnav decides contacts with.
    pub shape: ContactShape,
    /// Radii scale by 1 ± this fraction to bracket the threshold.
    pub fraction: f64,
}

impl ContactRule {
    /// The rule of a replay with `shape`, for humans of `human_radius` (m), the smallest disc
    /// whose contacts are decided.
    pub fn new(shape: ContactShape, human_radius: f64) -> Self {
        let fraction = match shape {
            ContactShape::Exact => CONTACT_FLIP_FRACTION,
            ContactShape::Polygon64 => POLYGON64_FLIP_DISTANCE / human_radius,
        };
        Self { shape, fraction }
    }

    fn code(&self) -> u32 {
        match self.shape {
            ContactShape::Exact => contact_shape::EXACT,
            ContactShape::Polygon64 => contact_shape::POLYGON64,
        }
    }

    /// Does a decision `decide(scale)` of contacts between discs whose radii are multiplied by
    /// `scale` change within the rule's bracket around scale 1?
    pub fn ambiguous(&self, decide: impl Fn(f64) -> bool) -> bool {
        self.ambiguous_by(0.0, decide)
    }

    /// [`Self::ambiguous`] with the bracket widened by `extra` (a fraction of the radii, for a
    /// position known only within `extra`·radius).
    pub fn ambiguous_by(&self, extra: f64, decide: impl Fn(f64) -> bool) -> bool {
        let f = self.fraction + extra;
        decide(1.0 - f) != decide(1.0 + f)
    }

    /// Do two discs (x, y, r), radii multiplied by `scale`, touch as socnav decides with this
    /// shape (in f32, as the step does)?
    pub fn discs_touch(&self, a: (f64, f64, f64), b: (f64, f64, f64), scale: f64) -> bool {
        disc_disc_as(self.code(), &disc(a, scale), &disc(b, scale))
    }

    /// Does the disc (x, y, r), radius multiplied by `scale`, touch the rectangle `r` of the
    /// recording (`across` names its width key)?
    pub fn touches_rect(&self, d: (f64, f64, f64), r: &Value, across: &str, scale: f64) -> bool {
        disc_rect_as(self.code(), &disc(d, scale), &rect(r, across))
    }

    /// Does the disc (x, y, r), radii multiplied by `scale`, touch a plant, wall, table or free
    /// laptop of the post-motion state `post`?
    pub fn touches_object(
        &self,
        header: &Value,
        post: &Value,
        d: (f64, f64, f64),
        scale: f64,
    ) -> bool {
        let list = |v: &Value| v.as_array().cloned().unwrap_or_default();
        list(&header["walls"])
            .iter()
            .any(|w| self.touches_rect(d, w, "thickness", scale))
            || list(&post["tables"])
                .iter()
                .any(|t| self.touches_rect(d, t, "width", scale))
            || list(&post["laptops"])
                .iter()
                .filter(|l| l["hl"].is_null())
                .any(|l| self.touches_rect(d, l, "width", scale))
            || list(&post["plants"]).iter().any(|p| {
                self.discs_touch(d, (num(&p["x"]), num(&p["y"]), num(&p["radius"])), scale)
            })
    }
}

fn disc((x, y, r): (f64, f64, f64), scale: f64) -> Disc {
    Disc {
        x: x as f32,
        y: y as f32,
        r: (r * scale) as f32,
    }
}

fn rect(r: &Value, across: &str) -> Rect {
    Rect::new(
        num(&r["x"]) as f32,
        num(&r["y"]) as f32,
        num(&r["theta"]) as f32,
        num(&r["length"]) as f32,
        num(&r[across]) as f32,
    )
}

/// How a human's contact with an object at the end of its motion is determined
/// ([`near_contact`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Near {
    /// Decided the same way everywhere within the bracket.
    No,
    /// Within the rule's bracket: a contact within the 64-gon's inset with exact discs, within
    /// the position tolerance with 64-gons.
    Bracket,
    /// Only within the bracket widened for the earlier pushes of a human pushed several times
    /// in the step (F4): always a near-threshold flip, inside the budget, whatever the shape.
    Repeated,
}

/// For each human of the step's post-motion state (observation order): whether its contact
/// with a plant, wall, table or free laptop at the end of its motion is decided within the
/// rule's bracket (and may be decided differently by socnav and 0.1.1).
///
/// A pushed human (listed in `diag.contacts`) moved once more per push, by that push's speed
/// times dt along its heading: the last push is undone exactly (the recorded speed and heading
/// are the last push's). A human pushed n ≥ 2 times (wedged in a wall–table corner) was moved by
/// the n − 1 earlier pushes too, whose speeds are not recorded; each push's speed is at most the
/// human's maximum speed (docs/spec.md 4.6: min(|F|·dt, max speed)), so the position where its
/// first contact was decided lies within (n − 1)·`human_max_speed`·dt of the once-undone position.
/// Every disc within that distance is covered by widening the bracket's radii by it: the
/// decision is [`Near::Repeated`] if it changes within the widened bracket only.
pub fn near_contact(
    header: &Value,
    step: &Step<'_>,
    (dt, human_radius, human_max_speed): (f64, f64, f64),
    rule: &ContactRule,
) -> Vec<Near> {
    let post = step.state_after_motion();
    let pushed: Vec<u64> = step.v["diag"]["contacts"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|c| c[0].as_u64())
        .collect();
    post["humans"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|h| {
            let (mut x, mut y) = (num(&h["x"]), num(&h["y"]));
            let pushes = h["id"]
                .as_u64()
                .map_or(0, |id| pushed.iter().filter(|&&p| p == id).count());
            // A pushed human moved once more, by speed·dt along its new heading: undo it.
            if pushes > 0 {
                let (speed, theta) = (num(&h["speed"]), num(&h["theta"]));
                x -= speed * dt * theta.cos();
                y -= speed * dt * theta.sin();
            }
            let touches = |scale: f64| {
                rule.touches_object(header, post, (x, y, human_radius), scale.max(0.0))
            };
            if rule.ambiguous(touches) {
                return Near::Bracket;
            }
            let earlier = (pushes.saturating_sub(1)) as f64 * human_max_speed * dt / human_radius;
            if earlier > 0.0 && rule.ambiguous_by(earlier, touches) {
                return Near::Repeated;
            }
            Near::No
        })
        .collect()
}

/// Distance (m) from (x, y) to the rectangle `r` (centre `x`, `y`, heading `theta`, `length`
/// along its heading and `across` perpendicular to it); 0 inside.
pub(super) fn rectangle_distance(r: &Value, across: &str, x: f64, y: f64) -> f64 {
    let (dx, dy) = (x - num(&r["x"]), y - num(&r["y"]));
    let (s, c) = num(&r["theta"]).sin_cos();
    let (u, v) = (dx * c + dy * s, -dx * s + dy * c);
    let ex = (u.abs() - num(&r["length"]) / 2.0).max(0.0);
    let ey = (v.abs() - num(&r[across]) / 2.0).max(0.0);
    ex.hypot(ey)
}

/// Whether the ORCA shadow robot has collided by the end of a step that started from `prev` and
/// whose post-motion snapshot is `post` (docs/spec.md 8.2): it touches a lone human, plant, wall,
/// table or free laptop, or a group member, laptop user or used laptop. `bug` tests the last three
/// against the real robot, as 0.1.1 does; socnav tests them against the shadow robot. Contacts
/// are decided by `rule` with every disc's radius multiplied by `scale` (see
/// [`ContactRule::ambiguous`]).
pub fn shadow_collided(
    header: &Value,
    (prev, post): (&Value, &Value),
    radii: (f64, f64),
    bug: bool,
    rule: &ContactRule,
    scale: f64,
) -> bool {
    let (robot_radius, human_radius) = radii;
    let before = &prev["shadow_robot"];
    if before["collided"] == true {
        return true;
    }
    if before["reached"] == true {
        return false;
    }
    let at = |r: &Value| (num(&r["x"]), num(&r["y"]), robot_radius);
    let shadow = at(&post["shadow_robot"]);
    let social = if bug { at(&post["robot"]) } else { shadow };
    let touches = |robot: (f64, f64, f64), h: &Value| {
        rule.discs_touch(robot, (num(&h["x"]), num(&h["y"]), human_radius), scale)
    };
    let humans = post["humans"].as_array().map_or(&[][..], |a| &a[..]);
    let lone = |h: &&Value| h["role"] == "static" || h["role"] == "dynamic";
    let lone_human = humans.iter().filter(lone).any(|h| touches(shadow, h));
    let social_human = humans
        .iter()
        .filter(|h| !lone(h))
        .any(|h| touches(social, h));
    let used_laptop = post["laptops"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|l| !l["hl"].is_null())
        .any(|l| rule.touches_rect(social, l, "width", scale));
    let fixed = rule.touches_object(header, post, shadow, scale);
    lone_human || social_human || fixed || used_laptop
}
