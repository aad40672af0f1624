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

use serde::{Deserialize, Serialize};

use super::values::{F32, Lazy, List, U32, Vector, capacity, err, object};
use crate::error::SimError;
use crate::params::StepParams;
use crate::sngnn::history::{self, FrameHead, History, Link, Object, Person};
use crate::state::BatchState;

/// One frame of the history.
#[derive(Clone, Serialize, Deserialize)]
#[serde(remote = "Self")]
pub(super) struct Frame {
    robot: FrameRobot,
    /// 0.1.1's list of one goal; only the first is read.
    goal: List<Lazy<Point>, true>,
    tick: U32,
    /// Seconds since the episode began (0.1.1's); not read.
    #[serde(skip_deserializing)]
    timestamp: f64,
    command: Vector<3>,
    #[serde(default)]
    people: List<Pose>,
    #[serde(default)]
    objects: List<ObjectPose>,
    #[serde(default)]
    interaction: List<LinkIds>,
}

/// The world pose a frame was taken from (m, m, rad).
#[derive(Clone, Serialize, Deserialize)]
#[serde(remote = "Self")]
struct FrameRobot {
    x: F32,
    y: F32,
    theta: F32,
}

#[derive(Clone, Serialize, Deserialize)]
#[serde(remote = "Self")]
struct Point {
    x: F32,
    y: F32,
}

/// A person of a frame ([`Person`]).
#[derive(Clone, Serialize, Deserialize)]
#[serde(remote = "Self")]
struct Pose {
    id: U32,
    x: F32,
    y: F32,
    a: F32,
    vx: F32,
    vy: F32,
    va: F32,
}

/// An object of a frame ([`Object`]): a pose and a size.
#[derive(Clone, Serialize, Deserialize)]
#[serde(remote = "Self")]
struct ObjectPose {
    id: U32,
    x: F32,
    y: F32,
    a: F32,
    vx: F32,
    vy: F32,
    va: F32,
    size_x: F32,
    size_y: F32,
}

#[derive(Clone, Serialize, Deserialize)]
#[serde(remote = "Self")]
struct LinkIds {
    src: U32,
    dst: U32,
}

object!(
    Frame: "robot",
    FrameRobot: "x",
    Point: "x",
    Pose: "id",
    ObjectPose: "id",
    LinkIds: "src",
);

fn pose(p: &Person) -> Pose {
    Pose {
        id: U32(p.id),
        x: F32(p.x),
        y: F32(p.y),
        a: F32(p.a),
        vx: F32(p.vx),
        vy: F32(p.vy),
        va: F32(p.va),
    }
}

/// The history of environment `e`, newest first.
pub(super) fn export(p: &StepParams, s: &BatchState, e: usize) -> List<Lazy<Frame>> {
    let h = History::of_batch(s, e);
    let frames = (0..h.len())
        .map(|age| {
            let f = h.frame(age);
            let head = f.head();
            let [x, y, theta] = head.robot;
            Lazy::Ready(Frame {
                tick: U32(head.tick),
                timestamp: history::timestamp(p.dt, head.tick),
                robot: FrameRobot {
                    x: F32(x),
                    y: F32(y),
                    theta: F32(theta),
                },
                goal: List(vec![Lazy::Ready(Point {
                    x: F32(head.goal[0]),
                    y: F32(head.goal[1]),
                })]),
                command: Vector(head.command),
                people: List(f.people().map(|p| pose(&p)).collect()),
                objects: List(
                    f.objects()
                        .map(|o| ObjectPose {
                            id: U32(o.pose.id),
                            x: F32(o.pose.x),
                            y: F32(o.pose.y),
                            a: F32(o.pose.a),
                            vx: F32(o.pose.vx),
                            vy: F32(o.pose.vy),
                            va: F32(o.pose.va),
                            size_x: F32(o.size_x),
                            size_y: F32(o.size_y),
                        })
                        .collect(),
                ),
                interaction: List(
                    f.links()
                        .map(|l| LinkIds {
                            src: U32(l.src),
                            dst: U32(l.dst),
                        })
                        .collect(),
                ),
            })
        })
        .collect();
    List(frames)
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

/// Load `state.sngnn_frames` (if any) into the emptied history of environment `e`.
pub(super) fn import(
    frames: Option<&Lazy<List<Lazy<Frame>>>>,
    s: &mut BatchState,
    e: usize,
) -> Result<(), SimError> {
    if s.strides.frames == 0 {
        return Ok(());
    }
    let path = "state.sngnn_frames";
    let frames = match frames {
        Some(f) => f.get(path)?.0,
        None => Vec::new(),
    };
    let kept = frames.len().min(s.strides.frames);
    // Oldest first, so that the newest ends up newest.
    for (i, f) in frames[..kept].iter().enumerate().rev() {
        let frame = check_frame(&f.get(&format!("{path}[{i}]"))?, i, s, e)?;
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

/// Frame `i` of the document, checked against the snapshot of environment `e`.
fn check_frame(f: &Frame, i: usize, s: &BatchState, e: usize) -> Result<FrameRecord, SimError> {
    let path = format!("state.sngnn_frames[{i}]");
    let goal = f
        .goal
        .0
        .first()
        .ok_or_else(|| err(&path, "has an empty `goal` list"))?
        .get(&format!("{path}.goal[0]"))?;
    let head = FrameHead {
        tick: f.tick.0,
        robot: [f.robot.x.0, f.robot.y.0, f.robot.theta.0],
        goal: [goal.x.0, goal.y.0],
        command: f.command.0,
    };
    let n = entities(s, e) as u32;
    let id = |list: &str, k: usize, key: &str, id: U32| -> Result<u32, SimError> {
        if id.0 == 0 || id.0 > n {
            return Err(err(
                &format!("{path}.{list}[{k}]"),
                format!(
                    "`{key}` = {} is not an id of the snapshot's humans and objects (1..={n})",
                    id.0
                ),
            ));
        }
        Ok(id.0)
    };
    let people = &f.people.0;
    same_count(
        &path,
        "people",
        people.len(),
        s.n_humans[e] as usize,
        "humans",
    )?;
    let objects = &f.objects.0;
    let n_objects = (s.n_laptops[e] + s.n_plants[e] + s.n_tables[e]) as usize;
    same_count(
        &path,
        "objects",
        objects.len(),
        n_objects,
        "laptops, plants and tables",
    )?;
    let links = &f.interaction.0;
    capacity(
        "interaction entries in an SNGNN frame",
        links.len(),
        s.strides.frame_links,
        "two per ordered pair of group members, one per laptop user",
    )?;
    Ok(FrameRecord {
        head,
        people: people
            .iter()
            .enumerate()
            .map(|(k, p)| {
                Ok(Person {
                    id: id("people", k, "id", p.id)?,
                    x: p.x.0,
                    y: p.y.0,
                    a: p.a.0,
                    vx: p.vx.0,
                    vy: p.vy.0,
                    va: p.va.0,
                })
            })
            .collect::<Result<_, SimError>>()?,
        objects: objects
            .iter()
            .enumerate()
            .map(|(k, o)| {
                Ok(Object {
                    pose: Person {
                        id: id("objects", k, "id", o.id)?,
                        x: o.x.0,
                        y: o.y.0,
                        a: o.a.0,
                        vx: o.vx.0,
                        vy: o.vy.0,
                        va: o.va.0,
                    },
                    size_x: o.size_x.0,
                    size_y: o.size_y.0,
                })
            })
            .collect::<Result<_, SimError>>()?,
        links: links
            .iter()
            .enumerate()
            .map(|(k, l)| {
                Ok(Link {
                    src: id("interaction", k, "src", l.src)?,
                    dst: id("interaction", k, "dst", l.dst)?,
                })
            })
            .collect::<Result<_, SimError>>()?,
    })
}

/// A frame shows every human and object of the snapshot (their totals are constant within an
/// episode), which also keeps it within the frame's capacities.
fn same_count(
    path: &str,
    key: &str,
    n: usize,
    expected: usize,
    what: &str,
) -> Result<(), SimError> {
    if n != expected {
        return Err(err(
            path,
            format!(
                "lists {n} {key}, but the snapshot has {expected} {what} (a frame shows them all)"
            ),
        ));
    }
    Ok(())
}
