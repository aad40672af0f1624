//! The most of each entity one environment of a config can hold, formations during an episode
//! included: what the state's capacities (`state::Caps`) are sized by and what validation checks
//! against the step's fixed bounds (`crate::limits`).

use super::{Config, Shape};

/// Slots for humans, groups, laptops and laptop users, formations during an episode included.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SocialSlots {
    /// Humans of every role.
    pub humans: usize,
    /// Groups, crowds formed during an episode included.
    pub groups: usize,
    /// Laptops, free and in use.
    pub laptops: usize,
    /// Laptop users, laptop-use formations included.
    pub laptop_users: usize,
}

/// The social slots an environment of `c` can need.
pub fn social_slots(c: &Config) -> SocialSlots {
    let n = &c.counts;
    let humans = n.max_humans().max(0) as usize;
    let configured_groups = n.max_groups().max(0) as usize;
    // Crowd formation turns lone walkers into new groups of at least 2 members.
    let groups = if c.events.crowd_formation_probability > 0.0 {
        configured_groups.max(humans / 2)
    } else {
        configured_groups
    };
    let laptops = n.max_laptops().max(0) as usize;
    // Laptop-use formation seats walkers at free laptops: at most one user per laptop.
    let laptop_users = if c.events.laptop_formation_probability > 0.0 {
        laptops
    } else {
        n.max_laptop_users().max(0) as usize
    };
    SocialSlots {
        humans,
        groups,
        laptops,
        laptop_users,
    }
}

/// The most ORCA obstacle polygons an environment of `c` can have: walls, tables, laptops,
/// plants, laptop users and standing groups (validation bounds it by the step's scratch).
pub fn max_obstacle_polygons(c: &Config) -> usize {
    let max = |r: [i32; 2]| r[1].max(0) as usize;
    let k = social_slots(c);
    max_walls(c)
        + max(c.counts.tables)
        + k.laptops
        + max(c.counts.plants)
        + k.laptop_users
        + k.groups
}

/// Wall rectangles: the room's outline (4, or 8 for an L) and 4 corridor walls.
pub fn max_walls(c: &Config) -> usize {
    let base = match c.room.shape {
        Shape::NoWalls => 0,
        Shape::Square | Shape::Rectangle => 4,
        Shape::L | Shape::Random => 8,
    };
    let corridors = if c.room.corridors && base > 0 { 4 } else { 0 };
    base + corridors
}
