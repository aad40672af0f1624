//! Which humans a step may push out of an object differently in socnav and in 0.1.1 (spec 4.6).
//!
//! 0.1.1 tests human–object contact on shapely polygons, a human's disc being a 64-gon that sits
//! up to 0.12 % of the radius inside the circle, while socnav tests the exact disc in f32. A human
//! that ends its motion touching an object to within that margin may be pushed by one and not by
//! the other: its position, heading and speed then differ for the rest of the step (the next step
//! starts again from the recorded state).

use serde_json::Value;

use super::{Step, num};

/// Fraction of the human radius within which the contact decision may differ: the 64-gon's
/// inset 1 − cos(π/64) = 0.12 %, and the f32 rounding of metre-scale positions well inside it.
pub const CONTACT_FLIP_FRACTION: f64 = 0.0013;

/// For each human of the step's post-motion state (observation order): whether it ended its
/// motion within the flip margin of touching a plant, wall, table or free laptop.
pub fn near_contact(header: &Value, step: &Step<'_>, dt: f64, human_radius: f64) -> Vec<bool> {
    let post = step.state_after_motion();
    let pushed: Vec<u64> = step.v["diag"]["contacts"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|c| c[0].as_u64())
        .collect();
    let margin = CONTACT_FLIP_FRACTION * human_radius;
    post["humans"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|h| {
            let (mut x, mut y) = (num(&h["x"]), num(&h["y"]));
            // A pushed human moved once more, by speed·dt along its new heading: undo it.
            if h["id"].as_u64().is_some_and(|id| pushed.contains(&id)) {
                let (speed, theta) = (num(&h["speed"]), num(&h["theta"]));
                x -= speed * dt * theta.cos();
                y -= speed * dt * theta.sin();
            }
            object_distances(header, post, x, y).any(|d| (d - human_radius).abs() <= margin)
        })
        .collect()
}

/// Distances (m) from (x, y) to every object a human can be pushed out of.
fn object_distances<'a>(
    header: &'a Value,
    post: &'a Value,
    x: f64,
    y: f64,
) -> impl Iterator<Item = f64> + 'a {
    let list = |v: &'a Value| v.as_array().map_or(&[][..], |a| &a[..]);
    let walls = list(&header["walls"])
        .iter()
        .map(move |w| rectangle_distance(w, "thickness", x, y));
    let tables = list(&post["tables"])
        .iter()
        .map(move |t| rectangle_distance(t, "width", x, y));
    let laptops = list(&post["laptops"])
        .iter()
        .filter(|l| l["hl"].is_null())
        .map(move |l| rectangle_distance(l, "width", x, y));
    let plants = list(&post["plants"])
        .iter()
        .map(move |p| (num(&p["x"]) - x).hypot(num(&p["y"]) - y) - num(&p["radius"]));
    walls.chain(tables).chain(laptops).chain(plants)
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
/// whose post-motion snapshot is `post` (spec 8.2): it touches a lone human, plant, wall, table
/// or free laptop, or a group member, laptop user or used laptop. `bug` tests the last three
/// against the real robot, as 0.1.1 does; socnav tests them against the shadow robot. `margin`
/// widens (> 0) or narrows (< 0) every contact distance by that fraction, to tell decisions
/// within the 64-gon margin ([`CONTACT_FLIP_FRACTION`]) from real differences.
pub fn shadow_collided(
    header: &Value,
    prev: &Value,
    post: &Value,
    radii: (f64, f64),
    bug: bool,
    margin: f64,
) -> bool {
    let (robot_radius, human_radius) = (radii.0 * (1.0 + margin), radii.1 * (1.0 + margin));
    let before = &prev["shadow_robot"];
    if before["collided"] == true {
        return true;
    }
    if before["reached"] == true {
        return false;
    }
    let at = |r: &Value| (num(&r["x"]), num(&r["y"]));
    let shadow = at(&post["shadow_robot"]);
    let social = if bug { at(&post["robot"]) } else { shadow };
    let touches = |(x, y): (f64, f64), h: &Value| {
        (num(&h["x"]) - x).hypot(num(&h["y"]) - y) <= robot_radius + human_radius
    };
    let humans = post["humans"].as_array().map_or(&[][..], |a| &a[..]);
    let lone = |h: &&Value| h["role"] == "static" || h["role"] == "dynamic";
    let lone_human = humans.iter().filter(lone).any(|h| touches(shadow, h));
    let social_human = humans
        .iter()
        .filter(|h| !lone(h))
        .any(|h| touches(social, h));
    let object = |(x, y): (f64, f64), used: bool| {
        post["laptops"]
            .as_array()
            .into_iter()
            .flatten()
            .filter(|l| l["hl"].is_null() != used)
            .any(|l| rectangle_distance(l, "width", x, y) <= robot_radius)
    };
    let fixed = object_distances(header, post, shadow.0, shadow.1).any(|d| d <= robot_radius);
    lone_human || social_human || fixed || object(social, true)
}
