//! Cross-field validation of a [`Config`]: returns every problem at once, each naming the key
//! and the offending value, so a user fixes a file in one go.

use super::{Config, ObsFrame, Shape, at_most};
use crate::limits::{MAX_GROUP, MAX_PERMUTE, MAX_POLYGONS};

/// Fraction of the sampling area that the footprints of the largest entity counts may cover.
/// Random sequential placement of discs jams at about 55 % coverage (the random sequential
/// adsorption limit), so beyond it a reset cannot succeed; 0.1.1's paper rooms use about 5 %,
/// its largest derived configs about 42 %.
const MAX_FILL_FRACTION: f32 = 0.55;

/// The shortest step a config may take (s).
pub const MIN_TIME_STEP: f32 = 1e-3;

/// Every problem of `config`, as human-readable lines naming the key and value (empty if valid).
pub fn validate(config: &Config) -> Vec<String> {
    let mut v = Problems::default();
    check_scalars(config, &mut v);
    check_step_displacement(config, &mut v);
    check_group_noise(config, &mut v);
    check_laptops(config, &mut v);
    check_observation(config, &mut v);
    check_counts(config, &mut v);
    // The room checks run alongside the others, so that a room too small for what it must hold
    // is reported together with every other problem; they only need usable room sizes.
    if room_sizes_usable(config) {
        check_sizes_resolvable(config, &mut v);
        let other_problems = !v.0.is_empty();
        check_room_fits(config, other_problems, &mut v);
    }
    v.0
}

/// Whether the room size ranges and the margin are valid, so that the room checks can use them.
fn room_sizes_usable(c: &Config) -> bool {
    let range_ok = |r: [i32; 2]| r[0] >= 1 && r[0] <= r[1];
    range_ok(c.room.size_x)
        && (!uses_independent_y(c.room.shape) || range_ok(c.room.size_y))
        && c.room.margin.is_finite()
        && c.room.margin >= 0.0
}

#[derive(Default)]
struct Problems(Vec<String>);

impl Problems {
    fn positive(&mut self, key: &str, x: f32) {
        if !(x.is_finite() && x > 0.0) {
            self.0
                .push(format!("`{key}` must be a finite number > 0, got {x}"));
        }
    }
    fn non_negative(&mut self, key: &str, x: f32) {
        if !(x.is_finite() && x >= 0.0) {
            self.0
                .push(format!("`{key}` must be a finite number >= 0, got {x}"));
        }
    }
    fn probability(&mut self, key: &str, p: f32) {
        if !(0.0..=1.0).contains(&p) {
            self.0.push(format!(
                "`{key}` is a probability and must lie in [0, 1], got {p}"
            ));
        }
    }
    fn angle(&mut self, key: &str, a: f32) {
        // SocNavGym configs write 6.2831853 for "see everything"; allow 2π plus rounding slack.
        if !(a.is_finite() && a > 0.0 && a <= std::f32::consts::TAU + 1e-4) {
            self.0
                .push(format!("`{key}` must lie in (0, 2π] rad, got {a}"));
        }
    }
    fn range(&mut self, key: &str, r: [i32; 2]) {
        if r[0] < 0 {
            self.0
                .push(format!("`{key}` minimum must be >= 0, got {}", r[0]));
        }
        if r[0] > r[1] {
            self.0.push(format!(
                "`{key}` minimum {} is greater than its maximum {}",
                r[0], r[1]
            ));
        }
    }
}

/// An agent that moves farther than its own diameter in one step can pass through a wall or a
/// person between two steps (contacts are checked once a step) and leave the room: found by
/// fuzzing (`tests/suite/fuzz/configs.rs`), refused here.
fn check_step_displacement(c: &Config, v: &mut Problems) {
    let dt = c.episode.time_step;
    for (key, who, speed, diameter) in [
        (
            "robot.max_speed",
            "robot",
            c.robot.max_speed,
            2.0 * c.robot.radius,
        ),
        (
            "human.max_speed",
            "human",
            c.human.max_speed,
            c.human.diameter,
        ),
    ] {
        let step = speed * dt;
        if step.is_finite() && diameter.is_finite() && step > diameter {
            v.0.push(format!(
                "`{key}` {speed} m/s over `episode.time_step` {dt} s moves the {who} {step} m a \
                 step, more than its diameter ({diameter} m): contacts are checked once a step, so \
                 it would pass through walls and people (lower the speed or the time step)"
            ));
        }
    }
}

/// How far (m) a group member's velocity noise may walk it from its group over an episode, as
/// its typical spread σ·dt·√(steps): the noise accumulates step after step, with nothing pulling
/// the member back, and walks it through walls and out of the room beyond about this.
pub const MAX_GROUP_NOISE_DRIFT_M: f32 = 1.0;

/// A group's velocity noise must keep its members with it (see [`MAX_GROUP_NOISE_DRIFT_M`]).
fn check_group_noise(c: &Config, v: &mut Problems) {
    let (sigma, dt) = (c.group.velocity_noise_std, c.episode.time_step);
    let drift = sigma * dt * (c.episode.length as f32).sqrt();
    // A non-finite σ is the scalar checks' to report; a finite one may still overflow the product.
    if sigma.is_finite() && (drift.is_nan() || drift > MAX_GROUP_NOISE_DRIFT_M) {
        v.0.push(format!(
            "`group.velocity_noise_std` {sigma} m/s walks a group member about {drift:.3} m from \
             its group over an episode (σ × `episode.time_step` {dt} s × √`episode.length` {}), \
             more than {MAX_GROUP_NOISE_DRIFT_M} m: members would drift through walls",
            c.episode.length
        ));
    }
}

/// The farthest a laptop's user may sit from the laptop's centre (m): within reach of it. The
/// laptop lies on a table, inside the walls, and 0.1.1 checks the seat only against what it
/// overlaps, so a farther seat can land beyond the wall, outside the room (found by fuzzing:
/// `human_distance` 3 m seated users 2.6 m outside a 10 m room).
pub const MAX_SEAT_DISTANCE_M: f32 = 1.5;

/// Laptops lie on tables when a table exists (0.1.1), at an edge offset by half the difference of
/// the two sizes: a laptop larger than the table would hang outside it, and its user's seat with
/// it. Their users sit `laptop_width + human_distance` from them (see [`MAX_SEAT_DISTANCE_M`]).
fn check_laptops(c: &Config, v: &mut Problems) {
    if c.counts.max_laptops() <= 0 {
        return;
    }
    let o = &c.objects;
    if c.counts.tables[1] > 0 {
        for (key, laptop, table_key, table) in [
            (
                "objects.laptop_length",
                o.laptop_length,
                "objects.table_length",
                o.table_length,
            ),
            (
                "objects.laptop_width",
                o.laptop_width,
                "objects.table_width",
                o.table_width,
            ),
        ] {
            if laptop > table {
                v.0.push(format!(
                    "`{key}` {laptop} m is more than `{table_key}` {table} m: laptops lie on tables"
                ));
            }
        }
    }
    let seat = o.laptop_width + c.laptop_use.human_distance;
    if seat > MAX_SEAT_DISTANCE_M {
        v.0.push(format!(
            "`objects.laptop_width` {} m + `laptop_use.human_distance` {} m seats a laptop's user \
             {seat} m from it, more than {MAX_SEAT_DISTANCE_M} m: out of reach, and possibly beyond \
             the wall",
            o.laptop_width, c.laptop_use.human_distance
        ));
    }
}

/// f32 coordinates resolve about 1.2e-7 of their magnitude; a size below this fraction of the
/// room's extent (under about 80 such steps at the room's far corner) collapses an obstacle's
/// edge to a point there (found by fuzzing: a laptop 0.2 mm wide, 300 km from the origin).
const MIN_SIZE_PER_EXTENT: f32 = 1e-5;

/// Every size must be resolvable at the room's largest extent (see [`MIN_SIZE_PER_EXTENT`]).
fn check_sizes_resolvable(c: &Config, v: &mut Problems) {
    let extent = c.room.size_x[1].max(if uses_independent_y(c.room.shape) {
        c.room.size_y[1]
    } else {
        0
    }) as f32;
    let smallest = extent * MIN_SIZE_PER_EXTENT;
    let o = &c.objects;
    for (key, size) in [
        ("robot.radius", c.robot.radius),
        ("human.diameter", c.human.diameter),
        ("objects.laptop_width", o.laptop_width),
        ("objects.laptop_length", o.laptop_length),
        ("objects.plant_radius", o.plant_radius),
        ("objects.table_width", o.table_width),
        ("objects.table_length", o.table_length),
        ("objects.wall_thickness", o.wall_thickness),
        ("objects.wall_segment_size", o.wall_segment_size),
    ] {
        // A size that is not a positive number is reported by the scalar checks.
        if size > 0.0 && size < smallest {
            v.0.push(format!(
                "`{key}` {size} m is too small for a room up to {extent} m across: 32-bit \
                 coordinates there cannot resolve it (at least {smallest} m)"
            ));
        }
    }
}

fn check_scalars(c: &Config, v: &mut Problems) {
    if c.episode.length == 0 {
        v.0.push("`episode.length` must be >= 1 step, got 0".into());
    }
    // Below a millisecond a step's f32 sums lose its motion, and the SNGNN-v2 history holds
    // about 2 / dt frames an environment.
    if !(c.episode.time_step.is_finite() && c.episode.time_step >= MIN_TIME_STEP) {
        v.0.push(format!(
            "`episode.time_step` must be a finite number of at least {MIN_TIME_STEP} s, got {}",
            c.episode.time_step
        ));
    }
    v.positive("robot.radius", c.robot.radius);
    v.non_negative("robot.goal_radius", c.robot.goal_radius);
    v.non_negative("robot.max_speed", c.robot.max_speed);
    v.non_negative("robot.max_rotation", c.robot.max_rotation);
    v.positive("human.diameter", c.human.diameter);
    v.positive("human.goal_radius", c.human.goal_radius);
    v.angle("human.gaze_angle", c.human.gaze_angle);
    v.angle("human.fov_angle", c.human.fov_angle);
    v.probability("human.prob_to_avoid_robot", c.human.prob_to_avoid_robot);
    v.non_negative("human.max_speed", c.human.max_speed);
    v.non_negative("human.speed_threshold", c.human.speed_threshold);
    v.positive("group.radius", c.group.radius);
    v.positive("group.goal_radius", c.group.goal_radius);
    v.non_negative("group.velocity_noise_std", c.group.velocity_noise_std);
    v.non_negative("laptop_use.human_distance", c.laptop_use.human_distance);
    let o = &c.objects;
    v.positive("objects.laptop_width", o.laptop_width);
    v.positive("objects.laptop_length", o.laptop_length);
    v.positive("objects.plant_radius", o.plant_radius);
    v.positive("objects.table_width", o.table_width);
    v.positive("objects.table_length", o.table_length);
    v.positive("objects.wall_thickness", o.wall_thickness);
    v.positive("objects.wall_segment_size", o.wall_segment_size);
    v.non_negative("room.margin", c.room.margin);
    let e = &c.events;
    v.probability(
        "events.crowd_dispersal_probability",
        e.crowd_dispersal_probability,
    );
    v.probability(
        "events.laptop_dispersal_probability",
        e.laptop_dispersal_probability,
    );
    v.probability(
        "events.crowd_formation_probability",
        e.crowd_formation_probability,
    );
    v.probability(
        "events.laptop_formation_probability",
        e.laptop_formation_probability,
    );
    let r = &c.reward;
    for (key, x) in [
        ("reward.reach", r.reach),
        ("reward.out_of_map", r.out_of_map),
        ("reward.timeout", r.timeout),
        ("reward.collision", r.collision),
        ("reward.alive", r.alive),
        ("reward.distance_scale", r.distance_scale),
        ("reward.discomfort_factor", r.discomfort_factor),
        ("reward.personal_space_weight", r.personal_space_weight),
        ("reward.obstacle_weight", r.obstacle_weight),
        ("reward.stalled_weight", r.stalled_weight),
        ("reward.acceleration_weight", r.acceleration_weight),
    ] {
        if !x.is_finite() {
            v.0.push(format!("`{key}` must be finite, got {x}"));
        }
    }
    v.non_negative("reward.discomfort_distance", r.discomfort_distance);
    v.non_negative("reward.personal_space_distance", r.personal_space_distance);
    v.non_negative("reward.obstacle_distance", r.obstacle_distance);
    if c.render.resolution < 16 {
        v.0.push(format!(
            "`render.resolution` must be >= 16 pixels, got {}",
            c.render.resolution
        ));
    }
}

fn check_observation(c: &Config, v: &mut Problems) {
    let o = &c.observation;
    v.angle("observation.fov", o.fov);
    if let Some(range) = o.range {
        if !(range.is_finite() && range > 0.0) {
            v.0.push(format!(
                "`observation.range` must be a finite number > 0 m (omit the key for an unlimited \
                 range), got {range}"
            ));
        }
    }
    if o.robot_velocity && o.frame == ObsFrame::World {
        v.0.push(
            "`observation.robot_velocity` applies to the robot frame only: with \
             `observation.frame = \"world\"` the robot record carries the command already"
                .into(),
        );
    }
    for (key, g) in o.noise.named() {
        if !g.mean.is_finite() {
            v.0.push(format!(
                "`observation.noise.{key}.mean` must be finite, got {}",
                g.mean
            ));
        }
        v.non_negative(&format!("observation.noise.{key}.std"), g.std);
    }
}

fn check_counts(c: &Config, v: &mut Problems) {
    v.range("room.size_x", c.room.size_x);
    v.range("room.size_y", c.room.size_y);
    if c.room.size_x[0] <= 0 {
        v.0.push(format!(
            "`room.size_x` must be at least 1 m, got {:?}",
            c.room.size_x
        ));
    }
    if uses_independent_y(c.room.shape) && c.room.size_y[0] <= 0 {
        v.0.push(format!(
            "`room.size_y` must be at least 1 m, got {:?}",
            c.room.size_y
        ));
    }
    for (key, range) in c.counts.named() {
        v.range(&format!("counts.{key}"), range);
    }
    let groups_possible = c.counts.max_groups() > 0 || c.events.crowd_formation_probability > 0.0;
    if groups_possible && c.counts.group_size[0] < 2 {
        v.0.push(format!(
            "`counts.group_size` minimum must be >= 2 when groups are asked for \
             (max groups {}, crowd formation probability {}), got {}",
            c.counts.max_groups(),
            c.events.crowd_formation_probability,
            c.counts.group_size[0]
        ));
    }
    if c.counts.group_size[1] > MAX_GROUP as i32 {
        v.0.push(format!(
            "`counts.group_size` maximum must be at most {MAX_GROUP}, got {}",
            c.counts.group_size[1]
        ));
    }
    // The social events regroup an environment's entities in fixed-size scratch (no allocation
    // inside the step).
    if c.counts.max_humans() > MAX_PERMUTE as i64 {
        v.0.push(format!(
            "at most {MAX_PERMUTE} humans per environment: `counts` allow {} (static {} + \
             dynamic {} + laptop users {} + groups {} x group size {})",
            c.counts.max_humans(),
            c.counts.static_humans[1],
            c.counts.dynamic_humans[1],
            c.counts.max_laptop_users(),
            c.counts.max_groups(),
            c.counts.group_size[1]
        ));
    }
    if c.counts.max_laptops() > MAX_PERMUTE as i64 {
        v.0.push(format!(
            "at most {MAX_PERMUTE} laptops per environment: `counts` allow {} (free {} + \
             used {})",
            c.counts.max_laptops(),
            c.counts.laptops[1],
            c.counts.max_laptop_users()
        ));
    }
    let polygons = super::bounds::max_obstacle_polygons(c);
    if polygons > MAX_POLYGONS {
        v.0.push(format!(
            "at most {MAX_POLYGONS} ORCA obstacles per environment (walls, tables, laptops, \
             plants, laptop users, standing groups): `counts` allow {polygons}"
        ));
    }
    if c.counts.max_laptop_users() > 0 && c.counts.tables[0] < 1 {
        v.0.push(format!(
            "laptop users sit at tables: `counts.tables` minimum must be >= 1 when \
             `counts.laptop_users`/`laptop_users_non_dispersing` can be > 0, got {}",
            c.counts.tables[0]
        ));
    }
    let lone_humans = at_most(c.counts.dynamic_humans) + at_most(c.counts.static_humans);
    if lone_humans + c.counts.max_laptop_users() + c.counts.max_groups() > 0
        && c.human.diameter <= 0.0
    {
        v.0.push("humans are asked for but `human.diameter` is not > 0".into());
    }
}

/// Whether `size_y` is drawn separately from `size_x` for this shape.
fn uses_independent_y(shape: Shape) -> bool {
    matches!(shape, Shape::Rectangle | Shape::NoWalls | Shape::Random)
}

/// The room must hold the largest entity counts: each entity must fit in the sampling box, and
/// their footprints together must leave room for rejection sampling. The footprint estimate is
/// skipped when `other_problems` were found: it combines every size and count, and one invalid
/// value would make it meaningless.
fn check_room_fits(c: &Config, other_problems: bool, v: &mut Problems) {
    let smallest_x = c.room.size_x[0] as f32;
    let smallest_y = if uses_independent_y(c.room.shape) {
        c.room.size_y[0] as f32
    } else {
        smallest_x
    };
    let box_x = smallest_x - 2.0 * c.room.margin;
    let box_y = smallest_y - 2.0 * c.room.margin;
    let y_key = if uses_independent_y(c.room.shape) {
        format!(", `room.size_y` minimum {}", c.room.size_y[0])
    } else {
        String::new()
    };
    let room = format!(
        "the smallest room ({smallest_x} x {smallest_y} m: `room.size_x` minimum {}{y_key}) minus \
         `room.margin` {} m on each side",
        c.room.size_x[0], c.room.margin
    );
    if box_x <= 0.0 || box_y <= 0.0 {
        v.0.push(format!(
            "room too small: {room} leaves no area to place anything"
        ));
        return;
    }
    let o = &c.objects;
    let circumradius =
        |length: f32, width: f32| (0.25 * length * length + 0.25 * width * width).sqrt();
    let table_circumradius = circumradius(o.table_length, o.table_width);
    let laptop_circumradius = circumradius(o.laptop_length, o.laptop_width);
    let group_radius = c.group.radius + 0.5 * c.human.diameter;
    let side = box_x.min(box_y);
    for (what, radius, asked) in [
        ("the robot", c.robot.radius, true),
        ("a table", table_circumradius, c.counts.tables[1] > 0),
        ("a group", group_radius, c.counts.max_groups() > 0),
        ("a plant", o.plant_radius, c.counts.plants[1] > 0),
        ("a laptop", laptop_circumradius, c.counts.max_laptops() > 0),
    ] {
        // A size that is not a positive number is reported by the scalar checks.
        let usable = radius.is_finite() && radius > 0.0;
        if asked && usable && 2.0 * radius >= side {
            v.0.push(format!(
                "room too small: {what} ({:.2} m across) does not fit in the {box_x:.2} x {box_y:.2} m sampling box \
                 of {room}",
                2.0 * radius
            ));
        }
    }
    if other_problems {
        return;
    }
    let n = &c.counts;
    let disc = |r: f32| std::f32::consts::PI * r * r;
    let max_group_members = n.max_groups() * at_most(n.group_size);
    let humans = n.max_humans();
    // Entities only (goals may lie anywhere free); a group's disc covers its members; laptops on
    // tables take no floor space.
    let lone_humans = humans - max_group_members;
    let free_laptops = if n.tables[0] > 0 { 0 } else { n.laptops[1] };
    let footprint = disc(c.robot.radius)
        + lone_humans as f32 * disc(0.5 * c.human.diameter)
        + n.max_groups() as f32 * disc(group_radius)
        + n.plants[1] as f32 * disc(o.plant_radius)
        + n.tables[1] as f32 * o.table_length * o.table_width
        + free_laptops as f32 * o.laptop_length * o.laptop_width;
    let l_fraction = if c.room.shape == Shape::L {
        7.0 / 9.0
    } else {
        1.0
    };
    let area = box_x * box_y * l_fraction;
    if footprint > MAX_FILL_FRACTION * area {
        v.0.push(format!(
            "room too small: the largest counts cover about {footprint:.1} m² but {room} offers \
             {area:.1} m² to sample in; random placement jams beyond {:.0} % coverage",
            MAX_FILL_FRACTION * 100.0
        ));
    }
}
