//! The SNGNN frame history in a state document: `state.sngnn_frames`, newest first, written only
//! by batches whose reward is SNGNN-v2 (other batches ignore the key, their reward needs no
//! frames).
//!
//! A frame is 0.1.1's `sngnn.frame` record (golden README section 7: `people`, `objects`,
//! `interaction`, `goal`, `command`, `timestamp`) plus `tick` and `robot` (`{x, y, theta}`, the
//! world pose the frame was taken from, which places the walls; 0.1.1's `walls` are not read),
//! so a golden frame loads once its step's tick and robot pose are added. Loading keeps the
//! newest `Caps::frames` frames (older ones can never be stacked into a graph), and every frame
//! must show the snapshot's humans and objects: totals are constant within an episode.

use serde_json::{Value, json};

use super::num;
use super::read::{Reader, capacity, err};
use crate::error::SimError;
use crate::params::StepParams;
use crate::sngnn::history::{self, FrameHead, History, Link, Object, Person};
use crate::state::BatchState;

/// The history of environment `e`, newest first.
pub(super) fn export(p: &StepParams, s: &BatchState, e: usize) -> Value {
    let h = History::of_batch(s, e);
    let frames: Vec<Value> = (0..h.len())
        .map(|age| {
            let f = h.frame(age);
            let head = f.head();
            let people: Vec<Value> = f.people().map(|p| person(&p)).collect();
            let objects: Vec<Value> = f
                .objects()
                .map(|o| {
                    let mut v = person(&o.pose);
                    v["size_x"] = num(o.size_x);
                    v["size_y"] = num(o.size_y);
                    v
                })
                .collect();
            let links: Vec<Value> = f
                .links()
                .map(|l| json!({"src": l.src, "dst": l.dst}))
                .collect();
            let [x, y, theta] = head.robot;
            json!({
                "tick": head.tick, "timestamp": history::timestamp(p.dt, head.tick),
                "robot": {"x": num(x), "y": num(y), "theta": num(theta)},
                "goal": [{"x": num(head.goal[0]), "y": num(head.goal[1])}],
                "command": head.command.map(num),
                "people": people, "objects": objects, "interaction": links,
            })
        })
        .collect();
    Value::Array(frames)
}

fn person(p: &Person) -> Value {
    json!({"id": p.id, "x": num(p.x), "y": num(p.y), "a": num(p.a),
           "vx": num(p.vx), "vy": num(p.vy), "va": num(p.va)})
}

/// Humans plus laptops, plants and tables of environment `e`: the entities with a graph node.
fn entities(s: &BatchState, e: usize) -> usize {
    (s.n_humans[e] + s.n_laptops[e] + s.n_plants[e] + s.n_tables[e]) as usize
}

/// SNGNN-v2 indexes its graph nodes by entity id, so the humans and objects of environment `e`
/// must carry the ids 1..=N, each once (0.1.1's spawn order gives exactly that: walls come
/// last). Checked for batches with the SNGNN reward only.
pub(super) fn check_entity_ids(s: &BatchState, e: usize) -> Result<(), SimError> {
    if s.strides.sngnn_entities == 0 {
        return Ok(());
    }
    let c = &s.strides;
    let cut =
        |ids: &[u32], stride: usize, n: u32| ids[e * stride..e * stride + n as usize].to_vec();
    let ids = [
        cut(&s.h_id, c.humans, s.n_humans[e]),
        cut(&s.l_id, c.laptops, s.n_laptops[e]),
        cut(&s.p_id, c.plants, s.n_plants[e]),
        cut(&s.t_id, c.tables, s.n_tables[e]),
    ]
    .concat();
    let n = ids.len();
    let mut seen = vec![false; n + 1];
    for id in ids {
        let i = id as usize;
        let problem = if i == 0 || i > n {
            "is out of range"
        } else if seen[i] {
            "appears twice"
        } else {
            seen[i] = true;
            continue;
        };
        return Err(err(
            "state",
            format!(
                "numbers its humans and objects with id {id}, which {problem}: the SNGNN-v2 \
                 reward needs the ids 1..={n} (they are its graph's node indices, docs/spec.md 7.3)"
            ),
        ));
    }
    Ok(())
}

/// Load `st.sngnn_frames` (if any) into the emptied history of environment `e`.
pub(super) fn import(st: &Reader<'_>, s: &mut BatchState, e: usize) -> Result<(), SimError> {
    if s.strides.frames == 0 {
        return Ok(());
    }
    let frames = st.list("sngnn_frames")?;
    let kept = frames.len().min(s.strides.frames);
    // Oldest first, so that the newest ends up newest.
    for r in frames[..kept].iter().rev() {
        let frame = read_frame(r, s, e)?;
        let mut chunk = s.env_chunk(e);
        let slot = history::begin_frame(&mut chunk, 0, &frame.head);
        for p in &frame.people {
            history::push_person(&mut chunk, 0, slot, p);
        }
        for o in &frame.objects {
            history::push_object(&mut chunk, 0, slot, o);
        }
        for &l in &frame.links {
            history::push_link(&mut chunk, 0, slot, l);
        }
    }
    Ok(())
}

/// One frame of a document, checked against the snapshot of environment `e`.
struct FrameRecord {
    head: FrameHead,
    people: Vec<Person>,
    objects: Vec<Object>,
    links: Vec<Link>,
}

fn read_frame(r: &Reader<'_>, s: &BatchState, e: usize) -> Result<FrameRecord, SimError> {
    let robot = r.at("robot")?;
    let goal = r.at("goal")?.items()?;
    let goal = goal
        .first()
        .ok_or_else(|| err(r.path(), "has an empty `goal` list"))?;
    let head = FrameHead {
        tick: r.u("tick")?,
        robot: [robot.f("x")?, robot.f("y")?, robot.f("theta")?],
        goal: [goal.f("x")?, goal.f("y")?],
        command: r.vec::<3>("command")?,
    };
    let n = entities(s, e) as u32;
    let id = |r: &Reader<'_>, key: &str| -> Result<u32, SimError> {
        let id = r.u(key)?;
        if id == 0 || id > n {
            return Err(err(
                r.path(),
                format!(
                    "`{key}` = {id} is not an id of the snapshot's humans and objects (1..={n})"
                ),
            ));
        }
        Ok(id)
    };
    let pose = |r: &Reader<'_>| -> Result<Person, SimError> {
        Ok(Person {
            id: id(r, "id")?,
            x: r.f("x")?,
            y: r.f("y")?,
            a: r.f("a")?,
            vx: r.f("vx")?,
            vy: r.f("vy")?,
            va: r.f("va")?,
        })
    };
    let people = r.list("people")?;
    same_count(r, "people", people.len(), s.n_humans[e] as usize, "humans")?;
    let objects = r.list("objects")?;
    let n_objects = (s.n_laptops[e] + s.n_plants[e] + s.n_tables[e]) as usize;
    same_count(
        r,
        "objects",
        objects.len(),
        n_objects,
        "laptops, plants and tables",
    )?;
    let links = r.list("interaction")?;
    capacity(
        "interaction entries in an SNGNN frame",
        links.len(),
        s.strides.frame_links,
        "two per ordered pair of group members, one per laptop user",
    )?;
    Ok(FrameRecord {
        head,
        people: people.iter().map(pose).collect::<Result<_, _>>()?,
        objects: objects
            .iter()
            .map(|o| {
                Ok(Object {
                    pose: pose(o)?,
                    size_x: o.f("size_x")?,
                    size_y: o.f("size_y")?,
                })
            })
            .collect::<Result<_, SimError>>()?,
        links: links
            .iter()
            .map(|l| {
                Ok(Link {
                    src: id(l, "src")?,
                    dst: id(l, "dst")?,
                })
            })
            .collect::<Result<_, SimError>>()?,
    })
}

/// A frame shows every human and object of the snapshot (their totals are constant within an
/// episode), which also keeps it within the frame's capacities.
fn same_count(
    r: &Reader<'_>,
    key: &str,
    n: usize,
    expected: usize,
    what: &str,
) -> Result<(), SimError> {
    if n != expected {
        return Err(err(
            r.path(),
            format!(
                "lists {n} {key}, but the snapshot has {expected} {what} (a frame shows them all)"
            ),
        ));
    }
    Ok(())
}
