//! Rendering: frames of a hand-written scene are checked pixel by pixel (the mapping from world
//! to image, wall and entity colours, the image size), PNGs round-trip, and a GIF of a few steps
//! decodes to one frame per drawn state. Colours are compared exactly where a pixel lies well
//! inside an opaque shape (anti-aliasing only touches edges).

use serde_json::{Value, json};
use socnav::config::Shape;
use socnav::render::{self, GifWriter, Pixmap, View, palette, palette::Rgb};
use socnav::{Actions, AutoresetMode, BatchEnv, Config, EnvOptions, SimError};

/// A 12 m x 6 m rectangular room: the config's capacities cover the scene below.
fn config() -> Config {
    let mut c = Config::default();
    c.room.shape = Shape::Rectangle;
    c.room.size_x = [12, 12];
    c.room.size_y = [6, 6];
    c.counts.static_humans = [1, 1];
    c.counts.tables = [1, 1];
    c.counts.laptops = [1, 1];
    c.counts.laptop_users = [1, 1];
    c
}

const ROBOT: (f32, f32) = (2.0, -1.0);
const STATIC_HUMAN: (f32, f32) = (-4.0, 1.5);
const WALKER: (f32, f32) = (-2.0, -1.5);
const LAPTOP_USER: (f32, f32) = (4.0, 0.65);
const IN_USE: (f32, f32) = (4.0, 1.5);
const FREE_LAPTOP: (f32, f32) = (0.0, 2.2);
const TABLE: (f32, f32) = (-1.0, 1.0);
const PLANT: (f32, f32) = (-4.5, -1.8);

/// The scene as a state document, written by hand (the format of `BatchEnv::get_state`).
fn scene_doc() -> Value {
    let wall = |id: u32, x: f32, y: f32, theta: f32, length: f32| json!({"id": id, "x": x, "y": y, "theta": theta, "length": length});
    let human = |id: u32, (x, y): (f32, f32), role: &str| json!({"id": id, "x": x, "y": y, "theta": 0.0, "speed": 0.0, "policy": "orca", "role": role});
    let mut user = human(3, LAPTOP_USER, "hl");
    user["hl"] = json!(0);
    let mut walker = human(2, WALKER, "dynamic");
    walker["goal"] = json!([3.0, -2.0]);
    let pi = std::f32::consts::PI;
    json!({
        "room": {"map_x": 12.0, "map_y": 6.0, "shape": "rectangle"},
        // Box walls as the scenario builds them: outer faces on the map border, 0.2 m thick.
        "walls": [wall(10, 5.9, 0.0, -pi / 2.0, 6.0), wall(11, 0.0, -2.9, -pi, 12.0),
                  wall(12, -5.9, 0.0, pi / 2.0, 6.0), wall(13, 0.0, 2.9, 0.0, 12.0)],
        "human_params": {"orca_neighborDist": 5.0, "orca_timeHorizon": 5.0, "orca_timeHorizonObst": 5.0,
                         "orca_maxSpeed": 0.1, "sfm_r0": 0.1, "sfm_gamma": 0.25, "sfm_n": 1.0,
                         "sfm_n_prime": 1.0, "sfm_lambda": 1.0},
        "state": {
            "tick": 50,
            "robot": {"x": ROBOT.0, "y": ROBOT.1, "theta": 0.0, "goal": [-3.0, -2.0], "vel": [0.0, 0.0, 0.0]},
            "shadow_robot": {"x": ROBOT.0, "y": ROBOT.1, "theta": 0.0, "vel": [0.0, 0.0, 0.0], "path_length": 0.0},
            "humans": [human(1, STATIC_HUMAN, "static"), walker, user],
            "hl_interactions": [{"human": 3, "laptop": 5}],
            "laptops": [{"id": 4, "x": FREE_LAPTOP.0, "y": FREE_LAPTOP.1, "theta": 0.0},
                        {"id": 5, "x": IN_USE.0, "y": IN_USE.1, "theta": 0.0, "hl": 0}],
            "tables": [{"id": 6, "x": TABLE.0, "y": TABLE.1, "theta": 0.0}],
            "plants": [{"id": 7, "x": PLANT.0, "y": PLANT.1}],
            "metrics": {"prev_goal_distance": 5.099, "failure_to_progress": 0, "stalled_time": 0.0,
                        "path_length": 0.0, "v_min": 0.0, "v_max": 0.0, "v_avg": 0.0, "prev_vel": [0.0, 0.0],
                        "a_min": 0.0, "a_max": 0.0, "a_avg": 0.0, "prev_a": [0.0, 0.0],
                        "jerk_min": 0.0, "jerk_max": 0.0, "jerk_avg": 0.0, "compliant_count": 0},
            "reward_state": {"info": {"DISCOMFORT_SNGNN": 0.0, "DISCOMFORT_DSRNN": 0.0, "distance_reward": 0.0,
                                      "alive_reward": 0.0, "sngnn_reward": 0.0}},
        },
    })
}

fn scene_env() -> BatchEnv {
    let mut env = BatchEnv::new(
        config(),
        EnvOptions {
            n_envs: 1,
            ..Default::default()
        },
    )
    .unwrap();
    env.set_state(0, &scene_doc()).unwrap();
    env
}

const SIZE: u32 = 600;

fn rgb_at(img: &Pixmap, view: &View, (x, y): (f32, f32)) -> Rgb {
    let (px, py) = view.px(x, y);
    let c = img
        .pixel(px as u32, py as u32)
        .expect("point inside the image");
    assert_eq!(c.alpha(), 255, "frames are opaque");
    Rgb(c.red(), c.green(), c.blue())
}

fn frame(env: &BatchEnv) -> (Pixmap, View) {
    let f = render::Frame {
        params: env.params(),
        state: env.state().unwrap(),
        env: 0,
        trail: &[],
        size_px: SIZE,
    };
    (f.draw().unwrap(), f.view().unwrap())
}

#[test]
fn image_size_follows_size_px_and_room_aspect() {
    let env = scene_env();
    let (img, view) = frame(&env);
    assert_eq!((img.width(), img.height()), (view.width, view.height));
    assert_eq!(img.width(), SIZE, "the longer side (x, 12 m) is size_px");
    // The room fills the image less the margins, at one scale on both axes (±1 px of rounding).
    let room_w = img.width() as f32 - 2.0 * view.margin;
    let room_h = img.height() as f32 - 2.0 * view.margin;
    assert!(
        (room_w - 2.0 * room_h).abs() <= 1.0,
        "room {room_w} x {room_h} px, expected 2:1"
    );
    // The same room turned upright gives the transposed image.
    let mut doc = scene_doc();
    doc["room"]["map_x"] = json!(6.0);
    doc["room"]["map_y"] = json!(12.0);
    // A consistent document: its walls turned with the room (mirrored in the diagonal).
    for w in doc["walls"].as_array_mut().unwrap() {
        let (x, y, theta) = (w["x"].clone(), w["y"].clone(), w["theta"].as_f64().unwrap());
        (w["x"], w["y"]) = (y, x);
        w["theta"] = json!(std::f64::consts::FRAC_PI_2 - theta);
    }
    let mut tall = scene_env();
    tall.set_state(0, &doc).unwrap();
    let f = render::Frame {
        params: tall.params(),
        state: tall.state().unwrap(),
        env: 0,
        trail: &[],
        size_px: 300,
    };
    let (img, view) = (f.draw().unwrap(), f.view().unwrap());
    assert_eq!(img.height(), 300, "the longer side (y, 12 m) is size_px");
    let room_w = img.width() as f32 - 2.0 * view.margin;
    let room_h = img.height() as f32 - 2.0 * view.margin;
    assert!(
        (2.0 * room_w - room_h).abs() <= 1.0,
        "room {room_w} x {room_h} px, expected 1:2"
    );
}

#[test]
fn robot_is_drawn_at_its_position_and_y_points_up() {
    let env = scene_env();
    let (img, view) = frame(&env);
    let r = env.params().robot_radius;
    // Half a radius behind the centre: inside the disc, clear of the heading line and the outline.
    let behind = (ROBOT.0 - 0.5 * r, ROBOT.1);
    assert_eq!(rgb_at(&img, &view, behind), palette::ROBOT);
    // Mirrored in x or y the point is plain floor: the mapping is neither flipped nor transposed.
    assert_eq!(rgb_at(&img, &view, (behind.0, -behind.1)), palette::FLOOR);
    assert_eq!(rgb_at(&img, &view, (-behind.0, behind.1)), palette::FLOOR);
    let (px, py) = view.px(ROBOT.0, ROBOT.1);
    assert!(
        px > 0.5 * img.width() as f32 && py > 0.5 * img.height() as f32,
        "robot at ({px}, {py}) px"
    );
}

#[test]
fn walls_floor_and_outside_have_their_colours() {
    let env = scene_env();
    let (img, view) = frame(&env);
    // Each wall's centre line, and the floor just inside it.
    for (wall, inside) in [
        ((5.9, 0.0), (5.6, 0.0)),
        ((0.0, -2.9), (0.0, -2.6)),
        ((-5.9, 0.5), (-5.6, 0.5)),
        ((3.0, 2.9), (3.0, 2.6)),
    ] {
        assert_eq!(rgb_at(&img, &view, wall), palette::WALL, "wall at {wall:?}");
        assert_eq!(
            rgb_at(&img, &view, inside),
            palette::FLOOR,
            "floor at {inside:?}"
        );
    }
    // The image corner lies in the margin.
    let c = img.pixel(1, 1).unwrap();
    assert_eq!(Rgb(c.red(), c.green(), c.blue()), palette::OUTSIDE);
}

#[test]
fn entities_have_their_colours() {
    use socnav::state::role;
    let env = scene_env();
    let (img, view) = frame(&env);
    let hr = env.params().human_radius;
    // Headings are 0 (+x), so half a radius towards -x is inside the disc and off the heading line.
    let body = |(x, y): (f32, f32)| (x - 0.5 * hr, y);
    assert_eq!(
        rgb_at(&img, &view, body(STATIC_HUMAN)),
        palette::human(role::STATIC)
    );
    assert_eq!(
        rgb_at(&img, &view, body(WALKER)),
        palette::human(role::DYNAMIC)
    );
    assert_eq!(
        rgb_at(&img, &view, body(LAPTOP_USER)),
        palette::human(role::LAPTOP_USER)
    );
    assert_ne!(palette::human(role::STATIC), palette::human(role::DYNAMIC));
    // Laptops: 0.6 m along x; 0.15 m beside the centre is off the user's link line.
    assert_eq!(
        rgb_at(&img, &view, (IN_USE.0 + 0.15, IN_USE.1)),
        palette::LAPTOP_IN_USE
    );
    assert_eq!(
        rgb_at(&img, &view, (FREE_LAPTOP.0 + 0.15, FREE_LAPTOP.1)),
        palette::LAPTOP
    );
    assert_eq!(rgb_at(&img, &view, TABLE), palette::TABLE);
    assert_eq!(rgb_at(&img, &view, PLANT), palette::PLANT);
}

#[test]
fn progress_bar_shows_tick_over_episode_length() {
    let env = scene_env();
    let (img, _) = frame(&env);
    // tick 50 of 200: the bottom row is dark for the first quarter, track-coloured after it.
    let y = img.height() - 1;
    let at = |x: u32| {
        let c = img.pixel(x, y).unwrap();
        Rgb(c.red(), c.green(), c.blue())
    };
    assert_eq!(at(SIZE / 4 - 3), palette::PROGRESS);
    assert_eq!(at(SIZE / 4 + 3), palette::PROGRESS_TRACK);
}

#[test]
fn bad_requests_are_errors() {
    let env = scene_env();
    let too_small = render::draw(env.params(), env.state().unwrap(), 0, &[], 8);
    assert!(
        matches!(too_small, Err(SimError::Shape { what: "render", message: m }) if m.contains("8 px"))
    );
    let no_env = render::draw(env.params(), env.state().unwrap(), 1, &[], SIZE);
    assert!(matches!(
        no_env,
        Err(SimError::EnvIndex { env: 1, n_envs: 1 })
    ));
    let missing = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("no-such-dir")
        .join("x.png");
    let (img, _) = frame(&env);
    match render::write_png(&img, &missing) {
        // The kind survives: a missing directory is NotFound (a full disk would be StorageFull).
        Err(SimError::Io {
            kind,
            path,
            message,
            ..
        }) => {
            assert_eq!(kind, std::io::ErrorKind::NotFound);
            assert_eq!(path.as_deref(), Some(missing.as_path()));
            assert!(message.contains("no-such-dir"), "{message}");
        }
        other => panic!("expected an Io error, got {other:?}"),
    }
    let mut gif =
        GifWriter::new(Vec::new(), "test.gif", img.width(), img.height() + 1, 30).unwrap();
    assert!(
        matches!(gif.push(&img), Err(SimError::Shape { what: "GIF", message: m }) if m.contains("test.gif"))
    );
}

#[test]
fn png_round_trips() {
    let env = scene_env();
    let (img, _) = frame(&env);
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("render_round_trip.png");
    render::write_png(&img, &path).unwrap();
    let back = Pixmap::load_png(&path).unwrap();
    assert_eq!((back.width(), back.height()), (img.width(), img.height()));
    assert!(back.data() == img.data(), "PNG is lossless");
}

#[test]
fn gif_of_a_few_steps_decodes_frame_by_frame() {
    let (steps, size) = (4, 160);
    let options = EnvOptions {
        n_envs: 1,
        seed: 3,
        autoreset: AutoresetMode::Disabled,
        threads: Some(1),
        ..Default::default()
    };
    let mut env = BatchEnv::new(Config::default(), options).unwrap();
    env.reset(Some(3)).unwrap();
    let s = env.state().unwrap();
    let mut trail = vec![(s.robot_x[0], s.robot_y[0])];
    // Half a robot radius behind the robot's centre at reset: robot-coloured in the first frame.
    let (sin, cos) = socnav::math::sin_cos(s.robot_theta[0]);
    let back = 0.5 * env.params().robot_radius;
    let behind = (s.robot_x[0] - back * cos, s.robot_y[0] - back * sin);
    let f = render::Frame {
        params: env.params(),
        state: s,
        env: 0,
        trail: &trail,
        size_px: size,
    };
    let (first, view) = (f.draw().unwrap(), f.view().unwrap());
    assert_eq!(rgb_at(&first, &view, behind), palette::ROBOT);
    let mut gif = GifWriter::new(Vec::new(), "memory", first.width(), first.height(), 30).unwrap();
    gif.push(&first).unwrap();
    for _ in 0..steps {
        env.step(Actions::Continuous(&[1.0, 0.0, 0.5])).unwrap();
        trail.push((
            env.state().unwrap().robot_x[0],
            env.state().unwrap().robot_y[0],
        ));
        gif.push(&render::draw(env.params(), env.state().unwrap(), 0, &trail, size).unwrap())
            .unwrap();
    }
    assert_eq!(gif.frames(), steps + 1);
    let bytes = gif.finish().unwrap();
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::RGBA);
    let mut dec = opts.read_info(bytes.as_slice()).unwrap();
    assert_eq!(
        (u32::from(dec.width()), u32::from(dec.height())),
        (first.width(), first.height())
    );
    assert_eq!(dec.repeat(), gif::Repeat::Infinite);
    let mut frames = 0;
    while let Some(f) = dec.read_next_frame().unwrap() {
        assert_eq!(f.delay, 3, "30 ms per frame");
        if frames == 0 {
            // A frame has more than 256 colours (anti-aliased edges), so edge pixels map to their
            // nearest palette colour; flat colours stay exact. Demand 99 % exact pixels (99.9 %
            // at the time of writing); a wrong or shifted frame matches far fewer.
            let n = (first.width() * first.height()) as usize;
            let exact = f.buffer.chunks_exact(4).zip(first.data().chunks_exact(4));
            let exact = exact.filter(|(a, b)| a[..3] == b[..3]).count();
            assert!(exact * 100 >= 99 * n, "only {exact} of {n} pixels exact");
            let decoded = Pixmap::from_vec(
                f.buffer.to_vec(),
                tiny_skia::IntSize::from_wh(f.width.into(), f.height.into()).unwrap(),
            )
            .unwrap();
            assert_eq!(
                rgb_at(&decoded, &view, behind),
                palette::ROBOT,
                "the robot's colour is exact"
            );
        }
        frames += 1;
    }
    assert_eq!(frames, steps + 1);
}

/// The scene of [`scene_doc`] under `config`.
fn scene_env_with(config: Config, doc: &Value) -> BatchEnv {
    let mut env = BatchEnv::new(
        config,
        EnvOptions {
            n_envs: 1,
            ..Default::default()
        },
    )
    .unwrap();
    env.set_state(0, doc).unwrap();
    env
}

/// `over` painted with opacity `alpha` on `under`, within 2 levels per channel (tiny-skia blends
/// in 8-bit premultiplied arithmetic).
fn assert_blend(got: Rgb, over: Rgb, under: Rgb, alpha: f32, what: &str) {
    let a = (alpha * 255.0).round() / 255.0;
    let mix = |o: u8, u: u8| f32::from(u) + (f32::from(o) - f32::from(u)) * a;
    let want = [
        mix(over.0, under.0),
        mix(over.1, under.1),
        mix(over.2, under.2),
    ];
    let got3 = [got.0, got.1, got.2].map(f32::from);
    assert!(
        got3.iter().zip(want).all(|(g, w)| (g - w).abs() <= 2.0),
        "{what}: got {got:?}, want about {want:?}"
    );
}

#[test]
fn the_robots_sensor_is_drawn_as_its_field_of_view_and_range() {
    let mut c = config();
    c.observation.fov = std::f32::consts::FRAC_PI_2;
    c.observation.range = Some(3.0);
    let env = scene_env_with(c, &scene_doc());
    let (img, view) = frame(&env);
    // The robot at (2, -1) faces +x: 2 m ahead lies inside the 90° wedge of 3 m.
    let ahead = (ROBOT.0 + 2.0, ROBOT.1);
    let tint = rgb_at(&img, &view, ahead);
    assert_blend(
        tint,
        palette::ROBOT,
        palette::FLOOR,
        0.07,
        "inside the sensor",
    );
    // Behind the robot, beyond its range, and outside the opening: plain floor.
    for outside in [
        (ROBOT.0 - 1.5, ROBOT.1),
        (ROBOT.0 + 3.5, ROBOT.1),
        (ROBOT.0 + 1.0, ROBOT.1 + 1.8),
    ] {
        assert_eq!(
            rgb_at(&img, &view, outside),
            palette::FLOOR,
            "at {outside:?}"
        );
    }

    // Full view, unlimited range: nothing drawn, the frame equals the default one.
    let plain = frame(&scene_env()).0;
    let mut full = config();
    full.observation.fov = std::f32::consts::TAU;
    full.observation.range = None;
    assert!(frame(&scene_env_with(full, &scene_doc())).0.data() == plain.data());

    // Unlimited range: the wedge reaches the walls but never tints the margin outside the room.
    let mut unlimited = config();
    unlimited.observation.fov = std::f32::consts::FRAC_PI_2;
    let env = scene_env_with(unlimited, &scene_doc());
    let (img, view) = frame(&env);
    assert_blend(
        rgb_at(&img, &view, (ROBOT.0 + 3.5, ROBOT.1)),
        palette::ROBOT,
        palette::FLOOR,
        0.07,
        "unlimited range, 3.5 m ahead",
    );
    let (_, py) = view.px(ROBOT.0, ROBOT.1);
    let edge = img.pixel(img.width() - 2, py as u32).unwrap();
    assert_eq!(
        Rgb(edge.red(), edge.green(), edge.blue()),
        palette::OUTSIDE,
        "the margin in front of the robot"
    );
}

#[test]
fn walkers_fields_of_view_are_drawn_when_limited() {
    let mut c = config();
    c.human.fov_angle = 1.0;
    let env = scene_env_with(c, &scene_doc());
    let (img, view) = frame(&env);
    // The walker at (-2, -1.5) faces +x; its wedge is 1.5 m long.
    assert_blend(
        rgb_at(&img, &view, (WALKER.0 + 1.0, WALKER.1)),
        palette::HUMAN_WALKING,
        palette::FLOOR,
        0.08,
        "in the walker's view",
    );
    for outside in [
        (WALKER.0 - 1.0, WALKER.1),
        (WALKER.0 + 1.0, WALKER.1 + 0.9),
        (WALKER.0 + 2.0, WALKER.1),
    ] {
        assert_eq!(
            rgb_at(&img, &view, outside),
            palette::FLOOR,
            "at {outside:?}"
        );
    }
    // Static humans and laptop users do not walk, so no view is drawn for them.
    assert_eq!(
        rgb_at(&img, &view, (STATIC_HUMAN.0 + 1.0, STATIC_HUMAN.1)),
        palette::FLOOR
    );
}

#[test]
fn a_walker_heading_to_a_laptop_seat_is_linked_to_it() {
    let seat = (1.0, -2.0);
    let mut doc = scene_doc();
    doc["state"]["hl_forming"] = json!({"human": 2, "laptop": 4, "seat": [seat.0, seat.1, 0.0]});
    // Laptop-use formation on: the walker has a laptop user's slot to take at the seat.
    let mut forming = config();
    forming.events.laptop_formation_probability = 0.01;
    let (img, view) = frame(&scene_env_with(forming, &doc));
    let (plain, _) = frame(&scene_env());
    // The seat's cross is drawn in the laptop user's colour...
    let at_seat = rgb_at(&img, &view, seat);
    assert_ne!(at_seat, palette::FLOOR);
    assert!(
        at_seat.1 < palette::FLOOR.1 && at_seat.2 < palette::FLOOR.2 && at_seat.0 > 200,
        "an orange mark at the seat: {at_seat:?}"
    );
    // ... and the midpoint of the walker's line to it changes; the rest of the room does not.
    let mid = (0.5 * (WALKER.0 + seat.0), 0.5 * (WALKER.1 + seat.1));
    assert_ne!(rgb_at(&img, &view, mid), rgb_at(&plain, &view, mid));
    assert_eq!(
        rgb_at(&img, &view, (mid.0, mid.1 + 1.0)),
        rgb_at(&plain, &view, (mid.0, mid.1 + 1.0))
    );
}

#[test]
fn a_forming_crowd_shows_its_slots_and_the_walkers_way_to_them() {
    let (slot, centre) = ((0.0, -2.0), (0.0, -1.5));
    let mut doc = scene_doc();
    doc["state"]["humans"][1]["forming_crowd"] = json!(true);
    doc["state"]["crowd_forming"] = json!({
        "slots": [[slot.0, slot.1, 1.57], [centre.0, -1.0, -1.57]],
        "slot_of": {"2": 0, "1": 1},
        "centre": [centre.0, centre.1],
        "almost_formed_count": 0,
    });
    // Capacity for a crowd of 2 (the scene itself has no group).
    let mut c = config();
    c.counts.standing_groups = [0, 1];
    c.counts.group_size = [2, 2];
    let (img, view) = frame(&scene_env_with(c, &doc));
    let (plain, _) = frame(&scene_env());
    let at_slot = rgb_at(&img, &view, slot);
    let pink = palette::HUMAN_STANDING_GROUP;
    assert!(
        at_slot != palette::FLOOR && at_slot.1 < palette::FLOOR.1 && at_slot.0 > 200,
        "a pink cross at the slot: {at_slot:?} (crowd colour {pink:?})"
    );
    // The walker's line to its slot; the static human (not walking to it) gets none.
    let mid = (0.5 * (WALKER.0 + slot.0), 0.5 * (WALKER.1 + slot.1));
    assert_ne!(rgb_at(&img, &view, mid), rgb_at(&plain, &view, mid));
    let mid_static = (
        0.5 * (STATIC_HUMAN.0 + centre.0),
        0.5 * (STATIC_HUMAN.1 - 1.0),
    );
    assert_eq!(
        rgb_at(&img, &view, mid_static),
        rgb_at(&plain, &view, mid_static)
    );
}

/// Contract: a view of 0 pixels is a 1-pixel view, not a panic (`clamp(1, 0)`).
#[test]
fn a_view_of_no_pixels_is_one_pixel() {
    let view = socnav::render::View::new(10.0, 10.0, 0);
    assert_eq!((view.width, view.height), (1, 1));
}
