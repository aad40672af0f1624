//! Fixed capacities of the batched state, taken from a config's maximum counts. Every per-entity
//! column has one of these strides; the GPU backend sizes its buffers and shader arrays from them.

use crate::config::bounds::{SocialSlots, max_obstacle_polygons, max_walls, social_slots};
use crate::config::{Config, RewardKind, Shape};
use crate::params::StepParams;
use crate::room::{self, RoomLayout, room_shape};

/// Capacities (slots per environment) of every entity kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Caps {
    /// Humans of every role: lone static and walking humans, group members, laptop users.
    pub humans: usize,
    /// Groups, moving and standing (including crowds formed during an episode).
    pub groups: usize,
    /// Members of one group.
    pub group_size: usize,
    /// Human-laptop interactions (laptop users), including those formed during an episode.
    pub laptop_users: usize,
    /// Laptops, free and in use.
    pub laptops: usize,
    /// Tables.
    pub tables: usize,
    /// Plants.
    pub plants: usize,
    /// Walls (rectangles), internal corridor walls included.
    pub walls: usize,
    /// Observed wall segments.
    pub wall_segments: usize,
    /// Invisible spawn blockers (the L room's removed block, corridor doors).
    pub blockers: usize,
    /// ORCA obstacle vertices after RVO2's processing (which may split edges).
    pub obstacle_vertices: usize,
    /// Frames the SNGNN frame history holds ([`capacity_for`] the time step); 0 without the SNGNN
    /// reward, so that other configs carry no SNGNN columns at all.
    pub frames: usize,
    /// People per frame: every human (0 without the SNGNN reward).
    pub frame_people: usize,
    /// Objects per frame: laptops, plants and tables (0 without the SNGNN reward).
    pub frame_objects: usize,
    /// Interaction entries per frame: two per ordered pair of group members, one per laptop
    /// user (0 without the SNGNN reward).
    pub frame_links: usize,
    /// Entities whose previous pose the SNGNN frame needs, by id: ids 1 to humans + laptops +
    /// plants + tables (0 without the SNGNN reward).
    pub sngnn_entities: usize,
}

/// Extra obstacle vertices allowed for edges that RVO2's obstacle tree splits, per polygon vertex.
/// Splits happen where one rectangle's edge line crosses another rectangle (room corners do);
/// `tests/suite/whole_step/scenario_props.rs` checks the largest count seen over many scenarios
/// stays below this.
const SPLIT_VERTICES_PER_VERTEX: usize = 1;

/// The most observed wall segments any room of the config can have: exact for the outer walls
/// (every room size, shape and L location is built), bounded for corridor walls (their doors are
/// continuous draws: each corridor line gives at most ceil(L / s) + 2 segments).
fn max_wall_segments(c: &Config) -> usize {
    let step = c.objects.wall_segment_size;
    let mut most = 0u32;
    for_each_room(c, |room, x, y| {
        let mut n: u32 = room
            .walls
            .as_slice()
            .iter()
            .map(|w| room::segment_count(w.length, step))
            .sum();
        if c.room.corridors {
            let line = x.max(y);
            n += 2 * ((line / step).ceil() as u32 + 2);
        }
        most = most.max(n);
    });
    most as usize
}

/// Call `visit` with the outer walls of every room the config can build (each size, shape and
/// L location, corridors left out) and its size (m): what capacities that depend on the walls
/// take their maximum over.
pub(crate) fn for_each_room(c: &Config, mut visit: impl FnMut(&RoomLayout, f32, f32)) {
    let mut p = StepParams::new(c, Default::default());
    p.corridors = 0;
    let shapes: &[u32] = match c.room.shape {
        Shape::Square => &[room_shape::SQUARE],
        Shape::Rectangle => &[room_shape::RECTANGLE],
        Shape::L => &[room_shape::L],
        Shape::NoWalls => return,
        Shape::Random => &[room_shape::RECTANGLE, room_shape::SQUARE, room_shape::L],
    };
    let mut rng = crate::rng::RngStream::new(0, 0);
    let mut layout = RoomLayout::default();
    for &shape in shapes {
        let square = shape != room_shape::RECTANGLE;
        for x in c.room.size_x[0]..=c.room.size_x[1] {
            let ys = if square {
                x..=x
            } else {
                c.room.size_y[0]..=c.room.size_y[1]
            };
            for y in ys {
                let locations = if shape == room_shape::L { 0..4 } else { 0..1 };
                for loc in locations {
                    let (x, y) = (x as f32, y as f32);
                    room::build(&p, &mut rng, shape, x, y, loc, &mut layout);
                    visit(&layout, x, y);
                }
            }
        }
    }
}

/// Frames stacked in one SNGNN graph at most (0.1.1's `N_INTERVALS`).
pub const MAX_GRAPH_FRAMES: usize = 3;

/// Frames the SNGNN frame history must hold so that [`select`](crate::sngnn::history::select)
/// finds every frame it would take in 0.1.1's unbounded list, at time step `dt` (s). The last
/// frame taken lies two intervals back; an interval is ⌈1 s / dt⌉ steps, or one more where dt
/// divides 1 s in decimal but not in binary (dt = 0.1 or 0.2: 0.1.1's f64 timestamps can fall a
/// rounding short of 1 s apart), so F = 2 (⌈1/dt⌉ + 1) + 1 (25 frames at dt = 0.1 s). At
/// dt ≥ 1 s every step is an interval: F = 3.
pub fn capacity_for(dt: f32) -> usize {
    if dt >= 1.0 {
        return MAX_GRAPH_FRAMES;
    }
    let interval_steps = (1.0 / f64::from(dt)).ceil() as usize + 1;
    (MAX_GRAPH_FRAMES - 1) * interval_steps + 1
}

/// Capacities of the SNGNN frame history and previous-pose cache (docs/spec.md 7.2-7.4).
struct SngnnCaps {
    frames: usize,
    people: usize,
    objects: usize,
    links: usize,
    entities: usize,
}

/// All zero unless the config's reward is SNGNN-v2, so that every other config keeps its memory.
fn sngnn_caps(
    c: &Config,
    humans: usize,
    laptops: usize,
    laptop_users: usize,
    group_size: usize,
) -> SngnnCaps {
    if c.reward.kind != RewardKind::Sngnn {
        return SngnnCaps {
            frames: 0,
            people: 0,
            objects: 0,
            links: 0,
            entities: 0,
        };
    }
    let max = |r: [i32; 2]| r[1].max(0) as usize;
    let objects = laptops + max(c.counts.plants) + max(c.counts.tables);
    SngnnCaps {
        frames: capacity_for(c.episode.time_step),
        people: humans,
        objects,
        // A group of n members gives n (n − 1) entries (each pair twice, docs/spec.md 7.2): at most
        // group size − 1 per grouped human.
        links: humans * group_size.saturating_sub(1) + laptop_users,
        entities: humans + objects,
    }
}

impl Caps {
    /// Capacities for `config`.
    pub fn from_config(c: &Config) -> Self {
        let n = &c.counts;
        let max = |r: [i32; 2]| r[1].max(0) as usize;
        let SocialSlots {
            humans,
            groups,
            laptops,
            laptop_users,
        } = social_slots(c);
        let walls = max_walls(c);
        let corridors = c.room.corridors && c.room.shape != Shape::NoWalls;
        let wall_segments = max_wall_segments(c);
        let blockers = usize::from(matches!(c.room.shape, Shape::L | Shape::Random))
            + if corridors { 2 } else { 0 };
        let polygons = max_obstacle_polygons(c);
        let obstacle_vertices = 4 * polygons * (1 + SPLIT_VERTICES_PER_VERTEX);
        let group_size = max(n.group_size);
        let sngnn = sngnn_caps(c, humans, laptops, laptop_users, group_size);
        Self {
            humans,
            groups,
            group_size,
            laptop_users,
            laptops,
            tables: max(n.tables),
            plants: max(n.plants),
            walls,
            wall_segments,
            blockers,
            obstacle_vertices,
            frames: sngnn.frames,
            frame_people: sngnn.people,
            frame_objects: sngnn.objects,
            frame_links: sngnn.links,
            sngnn_entities: sngnn.entities,
        }
    }

    /// Stride of per-environment columns.
    pub fn env(&self) -> usize {
        1
    }
    /// Stride of per-human columns.
    pub fn human(&self) -> usize {
        self.humans
    }
    /// Stride of per-group columns.
    pub fn group(&self) -> usize {
        self.groups
    }
    /// Stride of per-slot columns of a forming crowd.
    pub fn crowd_slot(&self) -> usize {
        self.group_size
    }
    /// Stride of per-laptop-user columns.
    pub fn laptop_user(&self) -> usize {
        self.laptop_users
    }
    /// Stride of per-laptop columns.
    pub fn laptop(&self) -> usize {
        self.laptops
    }
    /// Stride of per-table columns.
    pub fn table(&self) -> usize {
        self.tables
    }
    /// Stride of per-plant columns.
    pub fn plant(&self) -> usize {
        self.plants
    }
    /// Stride of per-wall columns.
    pub fn wall(&self) -> usize {
        self.walls
    }
    /// Stride of per-blocker columns.
    pub fn blocker(&self) -> usize {
        self.blockers
    }
    /// Stride of per-obstacle-vertex columns.
    pub fn obstacle_vertex(&self) -> usize {
        self.obstacle_vertices
    }
    /// Stride of the SNGNN per-environment columns: 1 with the SNGNN reward, else 0.
    pub fn sngnn(&self) -> usize {
        usize::from(self.frames > 0)
    }
    /// Stride of per-frame columns of the SNGNN history.
    pub fn frame(&self) -> usize {
        self.frames
    }
    /// Stride of the history's per-person columns (every frame's people).
    pub fn frame_person(&self) -> usize {
        self.frames * self.frame_people
    }
    /// Stride of the history's per-object columns.
    pub fn frame_object(&self) -> usize {
        self.frames * self.frame_objects
    }
    /// Stride of the history's per-interaction columns.
    pub fn frame_link(&self) -> usize {
        self.frames * self.frame_links
    }
    /// Stride of the SNGNN previous-pose cache (indexed by entity id − 1).
    pub fn sngnn_entity(&self) -> usize {
        self.sngnn_entities
    }
}
