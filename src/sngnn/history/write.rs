//! Writing a history: emptying it and appending frames (the ring drops the oldest).

use super::{FrameHead, Link, Object, Person};
use crate::state::StateChunk;

/// Empty the history of local environment `e`: no frame held, every row zero.
pub fn clear(s: &mut StateChunk, e: usize) {
    let c = s.strides;
    if c.frames == 0 {
        return;
    }
    s.sn_frame_count[e] = 0;
    s.sn_newest[e] = 0;
    for slot in 0..c.frames {
        clear_slot(s, e, slot);
    }
}

/// Zero every row of ring slot `slot` of local environment `e`.
fn clear_slot(s: &mut StateChunk, e: usize, slot: usize) {
    let c = s.strides;
    let f = e * c.frames + slot;
    s.sf_tick[f] = 0;
    for col in [
        &mut *s.sf_robot_x,
        &mut *s.sf_robot_y,
        &mut *s.sf_robot_theta,
        &mut *s.sf_goal_x,
        &mut *s.sf_goal_y,
        &mut *s.sf_advance,
        &mut *s.sf_lateral,
        &mut *s.sf_rotation,
    ] {
        col[f] = 0.0;
    }
    s.sf_n_people[f] = 0;
    s.sf_n_objects[f] = 0;
    s.sf_n_links[f] = 0;
    let people = f * c.frame_people..(f + 1) * c.frame_people;
    s.fp_id[people.clone()].fill(0);
    for col in [
        &mut *s.fp_x,
        &mut *s.fp_y,
        &mut *s.fp_a,
        &mut *s.fp_vx,
        &mut *s.fp_vy,
        &mut *s.fp_va,
    ] {
        col[people.clone()].fill(0.0);
    }
    let objects = f * c.frame_objects..(f + 1) * c.frame_objects;
    s.fo_id[objects.clone()].fill(0);
    for col in [
        &mut *s.fo_x,
        &mut *s.fo_y,
        &mut *s.fo_a,
        &mut *s.fo_vx,
        &mut *s.fo_vy,
        &mut *s.fo_va,
        &mut *s.fo_size_x,
        &mut *s.fo_size_y,
    ] {
        col[objects.clone()].fill(0.0);
    }
    let links = f * c.frame_links..(f + 1) * c.frame_links;
    s.fl_src[links.clone()].fill(0);
    s.fl_dst[links].fill(0);
}

/// Start a new newest frame of local environment `e` with `head` and no entities, dropping the
/// oldest frame when the ring is full; returns its ring slot for [`push_person`],
/// [`push_object`] and [`push_link`]. Panics without a history (a config without the SNGNN
/// reward).
pub fn begin_frame(s: &mut StateChunk, e: usize, head: &FrameHead) -> usize {
    let c = s.strides;
    assert!(
        c.frames > 0,
        "the SNGNN frame history has no capacity: the config's reward is not SNGNN-v2"
    );
    let count = s.sn_frame_count[e] as usize;
    let slot = if count == 0 {
        0
    } else {
        (s.sn_newest[e] as usize + 1) % c.frames
    };
    clear_slot(s, e, slot);
    s.sn_newest[e] = slot as u32;
    s.sn_frame_count[e] = (count + 1).min(c.frames) as u32;
    let f = e * c.frames + slot;
    s.sf_tick[f] = head.tick;
    [s.sf_robot_x[f], s.sf_robot_y[f], s.sf_robot_theta[f]] = head.robot;
    [s.sf_goal_x[f], s.sf_goal_y[f]] = head.goal;
    [s.sf_advance[f], s.sf_lateral[f], s.sf_rotation[f]] = head.command;
    slot
}

/// Append a person to the frame in ring slot `slot` of local environment `e`.
pub fn push_person(s: &mut StateChunk, e: usize, slot: usize, p: &Person) {
    let c = s.strides;
    let f = e * c.frames + slot;
    let j = s.sf_n_people[f] as usize;
    assert!(
        j < c.frame_people,
        "an SNGNN frame with more than {} people (Caps::frame_people)",
        c.frame_people
    );
    let i = f * c.frame_people + j;
    s.fp_id[i] = p.id;
    s.fp_x[i] = p.x;
    s.fp_y[i] = p.y;
    s.fp_a[i] = p.a;
    s.fp_vx[i] = p.vx;
    s.fp_vy[i] = p.vy;
    s.fp_va[i] = p.va;
    s.sf_n_people[f] += 1;
}

/// Append an object to the frame in ring slot `slot` of local environment `e`.
pub fn push_object(s: &mut StateChunk, e: usize, slot: usize, o: &Object) {
    let c = s.strides;
    let f = e * c.frames + slot;
    let j = s.sf_n_objects[f] as usize;
    assert!(
        j < c.frame_objects,
        "an SNGNN frame with more than {} objects (Caps::frame_objects)",
        c.frame_objects
    );
    let i = f * c.frame_objects + j;
    s.fo_id[i] = o.pose.id;
    s.fo_x[i] = o.pose.x;
    s.fo_y[i] = o.pose.y;
    s.fo_a[i] = o.pose.a;
    s.fo_vx[i] = o.pose.vx;
    s.fo_vy[i] = o.pose.vy;
    s.fo_va[i] = o.pose.va;
    s.fo_size_x[i] = o.size_x;
    s.fo_size_y[i] = o.size_y;
    s.sf_n_objects[f] += 1;
}

/// Append an interaction entry to the frame in ring slot `slot` of local environment `e`.
pub fn push_link(s: &mut StateChunk, e: usize, slot: usize, link: Link) {
    let c = s.strides;
    let f = e * c.frames + slot;
    let j = s.sf_n_links[f] as usize;
    assert!(
        j < c.frame_links,
        "an SNGNN frame with more than {} interaction entries (Caps::frame_links)",
        c.frame_links
    );
    let i = f * c.frame_links + j;
    s.fl_src[i] = link.src;
    s.fl_dst[i] = link.dst;
    s.sf_n_links[f] += 1;
}
