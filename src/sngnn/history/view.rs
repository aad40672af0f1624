//! Reading a history: one environment's columns cut to it, frame by frame.

use super::{FrameHead, Link, Object, Person};
use crate::state::{BatchState, Caps, StateChunk};

/// One environment's history, read-only: its columns cut to the environment.
#[derive(Debug, Clone, Copy)]
pub struct History<'a> {
    caps: Caps,
    count: usize,
    newest: usize,
    tick: &'a [u32],
    head: [&'a [f32]; 8],
    counts: [&'a [u32]; 3],
    person_id: &'a [u32],
    person: [&'a [f32]; 6],
    object_id: &'a [u32],
    object: [&'a [f32]; 8],
    link: [&'a [u32]; 2],
}

/// The history of environment `e` of a state table (`BatchState` or `StateChunk`): both have
/// the same column names.
macro_rules! history_of {
    ($s:expr, $e:expr) => {{
        let (s, e) = ($s, $e);
        let caps = s.strides;
        let cut = |stride: usize| e * stride..(e + 1) * stride;
        let f = cut(caps.frame());
        let (p, o, l) = (
            cut(caps.frame_person()),
            cut(caps.frame_object()),
            cut(caps.frame_link()),
        );
        let held = caps.frames > 0;
        History {
            caps,
            count: if held { s.sn_frame_count[e] as usize } else { 0 },
            newest: if held { s.sn_newest[e] as usize } else { 0 },
            tick: &s.sf_tick[f.clone()],
            head: [
                &s.sf_robot_x[f.clone()],
                &s.sf_robot_y[f.clone()],
                &s.sf_robot_theta[f.clone()],
                &s.sf_goal_x[f.clone()],
                &s.sf_goal_y[f.clone()],
                &s.sf_advance[f.clone()],
                &s.sf_lateral[f.clone()],
                &s.sf_rotation[f.clone()],
            ],
            counts: [
                &s.sf_n_people[f.clone()],
                &s.sf_n_objects[f.clone()],
                &s.sf_n_links[f],
            ],
            person_id: &s.fp_id[p.clone()],
            person: [
                &s.fp_x[p.clone()],
                &s.fp_y[p.clone()],
                &s.fp_a[p.clone()],
                &s.fp_vx[p.clone()],
                &s.fp_vy[p.clone()],
                &s.fp_va[p],
            ],
            object_id: &s.fo_id[o.clone()],
            object: [
                &s.fo_x[o.clone()],
                &s.fo_y[o.clone()],
                &s.fo_a[o.clone()],
                &s.fo_vx[o.clone()],
                &s.fo_vy[o.clone()],
                &s.fo_va[o.clone()],
                &s.fo_size_x[o.clone()],
                &s.fo_size_y[o],
            ],
            link: [&s.fl_src[l.clone()], &s.fl_dst[l]],
        }
    }};
}

impl<'a> History<'a> {
    /// The history of local environment `e` of a chunk.
    pub fn of_chunk(s: &'a StateChunk<'_>, e: usize) -> Self {
        history_of!(s, e)
    }

    /// The history of environment `e` of a batch.
    pub fn of_batch(s: &'a BatchState, e: usize) -> Self {
        history_of!(s, e)
    }

    /// Frames held.
    pub fn len(&self) -> usize {
        self.count
    }

    /// Whether no frame is held.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// The frame taken `age` non-terminal steps ago (0: the newest); `age < len()`.
    pub fn frame(&self, age: usize) -> Frame<'_> {
        assert!(
            age < self.count,
            "frame {age} of a history of {}",
            self.count
        );
        let f = self.caps.frames;
        self.at_slot((self.newest + f - age) % f)
    }

    /// The frame in ring slot `slot`.
    pub fn at_slot(&self, slot: usize) -> Frame<'_> {
        Frame { h: self, slot }
    }
}

/// One frame of a history.
#[derive(Debug, Clone, Copy)]
pub struct Frame<'h> {
    h: &'h History<'h>,
    slot: usize,
}

impl Frame<'_> {
    /// Its ring slot.
    pub fn slot(&self) -> usize {
        self.slot
    }

    /// Tick, robot pose, goal and command.
    pub fn head(&self) -> FrameHead {
        let v = |k: usize| self.h.head[k][self.slot];
        FrameHead {
            tick: self.h.tick[self.slot],
            robot: [v(0), v(1), v(2)],
            goal: [v(3), v(4)],
            command: [v(5), v(6), v(7)],
        }
    }

    /// Number of people.
    pub fn n_people(&self) -> usize {
        self.h.counts[0][self.slot] as usize
    }

    /// Number of objects.
    pub fn n_objects(&self) -> usize {
        self.h.counts[1][self.slot] as usize
    }

    /// Number of interaction entries.
    pub fn n_links(&self) -> usize {
        self.h.counts[2][self.slot] as usize
    }

    /// Person `j` (`j < n_people()`), in 0.1.1's order.
    pub fn person(&self, j: usize) -> Person {
        let i = self.slot * self.h.caps.frame_people + j;
        let v = |k: usize| self.h.person[k][i];
        Person {
            id: self.h.person_id[i],
            x: v(0),
            y: v(1),
            a: v(2),
            vx: v(3),
            vy: v(4),
            va: v(5),
        }
    }

    /// Object `j` (`j < n_objects()`), in 0.1.1's order.
    pub fn object(&self, j: usize) -> Object {
        let i = self.slot * self.h.caps.frame_objects + j;
        let v = |k: usize| self.h.object[k][i];
        Object {
            pose: Person {
                id: self.h.object_id[i],
                x: v(0),
                y: v(1),
                a: v(2),
                vx: v(3),
                vy: v(4),
                va: v(5),
            },
            size_x: v(6),
            size_y: v(7),
        }
    }

    /// Interaction entry `j` (`j < n_links()`).
    pub fn link(&self, j: usize) -> Link {
        let i = self.slot * self.h.caps.frame_links + j;
        Link {
            src: self.h.link[0][i],
            dst: self.h.link[1][i],
        }
    }

    /// The people, in order.
    pub fn people(&self) -> impl Iterator<Item = Person> + '_ {
        (0..self.n_people()).map(|j| self.person(j))
    }

    /// The objects, in order.
    pub fn objects(&self) -> impl Iterator<Item = Object> + '_ {
        (0..self.n_objects()).map(|j| self.object(j))
    }

    /// The interaction entries, in order.
    pub fn links(&self) -> impl Iterator<Item = Link> + '_ {
        (0..self.n_links()).map(|j| self.link(j))
    }
}
