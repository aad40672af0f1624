//! `[model] contact_shape = "polygon64"`: contacts decided as 0.1.1 decides them, with discs as
//! shapely's 64-gons (docs/fidelity.md).
//!
//! - The option reaches `StepParams` and, with it, the three step-time contact decisions: the
//!   robot's collision (termination), the shadow robot's, and the human push-out (contacts), each
//!   on hand-made scenes whose contacts lie inside the 64-gon's inset.
//! - The geometry agrees with shapely itself on the pairs of `tests/data/contact_shape_reference.csv`
//!   (made by `tests/data/gen_contact_shape_reference.py`), up to the f32 rounding of the
//!   threshold, and every disagreement of exact discs with shapely lies inside the inset.

use crate::common;

use std::f64::consts::PI;
use std::path::Path;

use common::scene::{load, push, scene, static_human};
use serde_json::json;
use socnav::config::ContactShape;
use socnav::geometry::{
    Disc, Rect, contact_shape, disc_disc, disc_rect, poly64_disc_disc, poly64_disc_rect,
};
use socnav::outputs::Outputs;
use socnav::pipeline::{Batch, STAGES};
use socnav::spec::{N_INFO, info};
use socnav::state::BatchState;
use socnav::{BatchEnv, Config};

// ---------------------------------------------------------------------------------------------
// The option
// ---------------------------------------------------------------------------------------------

/// Contract: the default is exact; `contact_shape = "polygon64"` reaches `StepParams`.
#[test]
fn the_option_reaches_the_step_params() {
    let exp1 = Config::from_name_or_path("exp1").unwrap();
    assert_eq!(exp1.model.contact_shape, ContactShape::Exact);
    let p = socnav::StepParams::new(&exp1, Default::default());
    assert_eq!(p.contact_shape, contact_shape::EXACT);
    let c = Config::from_toml_str("[model]\ncontact_shape = \"polygon64\"\n").unwrap();
    assert_eq!(c.model.contact_shape, ContactShape::Polygon64);
    let p = socnav::StepParams::new(&c, Default::default());
    assert_eq!(p.contact_shape, contact_shape::POLYGON64);
    // Serialised under its name, and read back.
    assert!(c.to_toml_string().contains("contact_shape = \"polygon64\""));
}

/// Contract: `geometry::POLY64_COS` holds cos(mπ/64), m = 0..63, each the f32 nearest the exact
/// value, exactly antisymmetric about m = 32, so that sin(mπ/64) = POLY64_COS[|32 − m|] is the
/// nearest f32 too (the geometry takes its sines there).
#[test]
fn the_64gon_table_is_the_rounded_cosines() {
    use socnav::geometry::POLY64_COS;
    for (m, &c) in POLY64_COS.iter().enumerate() {
        let angle = m as f64 * PI / 64.0;
        // cos(π/2) in f64 is 6e-17, not the exact 0 the table holds.
        let expected = if m == 32 { 0.0 } else { angle.cos() as f32 };
        assert_eq!(c, expected, "cos({m}π/64)");
        if m > 32 {
            assert_eq!(c, -POLY64_COS[64 - m], "symmetry at {m}");
        }
        let sin = POLY64_COS[m.abs_diff(32)];
        assert_eq!(sin, angle.sin() as f32, "sin({m}π/64)");
    }
}

// ---------------------------------------------------------------------------------------------
// The three decisions on hand-made scenes
// ---------------------------------------------------------------------------------------------

/// Experiment 1 (robot r 0.25 m, humans r 0.36 m, plants r 0.4 m, tables 3 x 1.5 m, walls
/// 0.2 m thick) with room for the scenes below, contacts shaped as `shape`.
fn scene_config(shape: ContactShape) -> Config {
    let mut c = Config::from_name_or_path("exp1").unwrap();
    c.counts.static_humans = [0, 1];
    c.counts.dynamic_humans = [0, 1];
    c.counts.plants = [0, 1];
    c.counts.tables = [0, 1];
    c.model.contact_shape = shape;
    c
}

/// Where a centre at `dist` (m) from (x, y) along `angle` (rad) lies.
fn at(x: f64, y: f64, angle: f64, dist: f64) -> (f64, f64) {
    (x + dist * angle.cos(), y + dist * angle.sin())
}

/// Between two 64-gon vertices (the edge's normal), and along a vertex.
const BETWEEN: f64 = PI / 64.0;
const VERTEX: f64 = 0.0;
/// A contact distance's fraction inside the 64-gon's inset, (cos(π/64), 1) = (0.998795, 1).
const INSET: f64 = 0.9994;

/// Run `begin_step` (which marks the environments as stepping) then stage `stage` alone over
/// every environment of `env`'s state (the other stages would move the entities of the scene);
/// the state and outputs after them.
fn run_stage(env: &BatchEnv, stage: &str) -> (BatchState, Outputs) {
    let mut state = env.state().unwrap().clone();
    let mut outputs = env.outputs().clone();
    let n_envs = state.n_envs;
    let mut b = Batch {
        s: state.chunk(),
        o: outputs.chunk(),
        actions: &[],
        sngnn: None,
        error: None,
    };
    for name in ["begin_step", stage] {
        let run = STAGES.iter().find(|s| s.name == name).unwrap().run;
        for e in 0..n_envs {
            run(env.params(), &mut b, e);
        }
    }
    assert!(b.error.is_none(), "{stage}: {:?}", b.error);
    (state, outputs)
}

/// The robot (and its shadow, which starts where it is) at the origin, goal far away, facing one
/// thing at a contact distance of `INSET` x the radii sum along `angle`: a static human, a
/// plant, or a table turned by `angle` with the robot beyond its +x face.
fn robot_scenes() -> Vec<(&'static str, f64, serde_json::Value)> {
    let mut out = Vec::new();
    for angle in [BETWEEN, VERTEX] {
        let mut human = scene(false, [0.0, 0.0, 0.0], [-3.0, -3.0]);
        let (x, y) = at(0.0, 0.0, angle, (0.25 + 0.36) * INSET);
        push(&mut human, "humans", static_human(1, x, y, 0.0));
        out.push(("human", angle, human));
        let mut plant = scene(false, [0.0, 0.0, 0.0], [-3.0, -3.0]);
        let (x, y) = at(0.0, 0.0, angle, (0.25 + 0.4) * INSET);
        push(&mut plant, "plants", json!({"id": 2, "x": x, "y": y}));
        out.push(("plant", angle, plant));
        // The table's centre 1.5 m (its half length) + the gap beyond the robot, along `angle`.
        let mut table = scene(false, [0.0, 0.0, 0.0], [-3.0, -3.0]);
        let (x, y) = at(0.0, 0.0, angle, 1.5 + 0.25 * INSET);
        push(
            &mut table,
            "tables",
            json!({"id": 3, "x": x, "y": y, "theta": angle}),
        );
        out.push(("table", angle, table));
    }
    out
}

/// Contract: the robot's collision (termination) and the shadow robot's are decided with the
/// option's shapes: inside the inset, between vertices, only exact discs touch; along a vertex
/// both do.
#[test]
fn robot_and_shadow_collisions_follow_the_option() {
    let scenes = robot_scenes();
    let docs: Vec<_> = scenes.iter().map(|s| s.2.clone()).collect();
    for shape in [ContactShape::Exact, ContactShape::Polygon64] {
        let env = load(scene_config(shape), &docs);
        let (state, outputs) = run_stage(&env, "termination");
        for (e, (what, angle, _)) in scenes.iter().enumerate() {
            let expected = shape == ContactShape::Exact || *angle == VERTEX;
            let flag = |k: usize| outputs.info[e * N_INFO + k] == 1.0;
            let key = if *what == "human" {
                info::COLLISION_HUMAN
            } else {
                info::COLLISION_OBJECT
            };
            assert_eq!(
                (flag(info::COLLISION), flag(key)),
                (expected, expected),
                "{shape:?}: robot and {what} at angle {angle}"
            );
            assert_eq!(
                state.shadow_collided[e] == 1,
                expected,
                "{shape:?}: shadow robot and {what} at angle {angle}"
            );
        }
    }
}

/// Contract: a walker resting against a plant, a table or a wall inside the inset is pushed out
/// with exact discs; with 64-gons only where a vertex faces the object.
#[test]
fn human_push_out_follows_the_option() {
    let mut docs = Vec::new();
    let mut cases = Vec::new();
    for angle in [BETWEEN, VERTEX] {
        // A walker at (0, 0); its goal far away.
        let walker = |doc: &mut serde_json::Value| {
            push(
                doc,
                "humans",
                json!({"id": 1, "x": 0.0, "y": 0.0, "theta": 0.0, "speed": 0.0,
                       "goal": [-3.0, -3.0], "policy": "orca", "role": "dynamic"}),
            );
        };
        let mut plant = scene(false, [3.0, 3.0, 0.0], [3.0, -3.0]);
        walker(&mut plant);
        let (x, y) = at(0.0, 0.0, angle, (0.36 + 0.4) * INSET);
        push(&mut plant, "plants", json!({"id": 2, "x": x, "y": y}));
        docs.push(plant);
        cases.push(("plant", angle));
        let mut table = scene(false, [3.0, 3.0, 0.0], [3.0, -3.0]);
        walker(&mut table);
        let (x, y) = at(0.0, 0.0, angle, 1.5 + 0.36 * INSET);
        push(
            &mut table,
            "tables",
            json!({"id": 3, "x": x, "y": y, "theta": angle}),
        );
        docs.push(table);
        cases.push(("table", angle));
        // A 4 m wall turned by `angle` + π/2 (its face normal along `angle`), 0.2 m thick.
        let mut wall = scene(false, [3.0, 3.0, 0.0], [3.0, -3.0]);
        walker(&mut wall);
        let (x, y) = at(0.0, 0.0, angle, 0.1 + 0.36 * INSET);
        wall["walls"] =
            json!([{"id": 100, "x": x, "y": y, "theta": angle + PI / 2.0, "length": 4.0}]);
        docs.push(wall);
        cases.push(("wall", angle));
    }
    for shape in [ContactShape::Exact, ContactShape::Polygon64] {
        let env = load(scene_config(shape), &docs);
        let before = env.state().unwrap().clone();
        let (after, _) = run_stage(&env, "contacts");
        for (e, (what, angle)) in cases.iter().enumerate() {
            let i = e * after.strides.humans;
            let pushed = (after.h_x[i], after.h_y[i]) != (before.h_x[i], before.h_y[i]);
            let expected = shape == ContactShape::Exact || *angle == VERTEX;
            assert_eq!(
                pushed, expected,
                "{shape:?}: human against a {what} at angle {angle}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Shapely's verdicts
// ---------------------------------------------------------------------------------------------

/// One pair of the reference file: a disc against a disc or a rectangle, and shapely's verdict.
struct Pair {
    disc: Disc,
    other: Other,
    shapely: bool,
    /// The largest magnitude among the pair's coordinates and sizes (m), the scale of f32
    /// rounding.
    scale: f64,
}

enum Other {
    Disc(Disc),
    /// The rectangle as socnav builds it, and its heading, length and width as shapely got them.
    Rect(Rect, [f32; 3]),
}

fn reference_pairs() -> Vec<Pair> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/contact_shape_reference.csv");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    text.lines()
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            let v: Vec<f32> = f[1..f.len() - 1]
                .iter()
                .map(|x| x.parse().unwrap())
                .collect();
            let shapely = f[f.len() - 1] == "1";
            let disc = Disc {
                x: v[0],
                y: v[1],
                r: v[2],
            };
            let biggest = |xs: &[f32]| xs.iter().map(|x| f64::from(x.abs())).fold(0.0, f64::max);
            match f[0] {
                "disc" => Pair {
                    disc,
                    other: Other::Disc(Disc {
                        x: v[3],
                        y: v[4],
                        r: v[5],
                    }),
                    shapely,
                    scale: biggest(&v[..]) + f64::from(v[2] + v[5]),
                },
                "rect" => Pair {
                    disc,
                    other: Other::Rect(Rect::new(v[3], v[4], v[5], v[6], v[7]), [v[5], v[6], v[7]]),
                    shapely,
                    scale: biggest(&[v[0], v[1], v[3], v[4]])
                        + f64::from(v[2] + 0.5 * v[6] + 0.5 * v[7]),
                },
                other => panic!("unknown pair kind {other}"),
            }
        })
        .collect()
}

/// The unit vector at m·π/64 (f64).
fn unit(m: usize) -> (f64, f64) {
    let a = m as f64 * PI / 64.0;
    (a.cos(), a.sin())
}

/// The exact 64-gons' separation (m) in f64: the largest gap along the separating-axis
/// candidates (the 64-gon's 32 edge normals, and a rectangle's 2 normals); > 0 apart, ≤ 0 they
/// intersect (touching counts). Its magnitude is how far the pair is from the threshold along
/// that axis.
fn separation(p: &Pair) -> f64 {
    let (x, y, r) = (
        f64::from(p.disc.x),
        f64::from(p.disc.y),
        f64::from(p.disc.r),
    );
    let apothem = |radius: f64| radius * (PI / 64.0).cos();
    match &p.other {
        Other::Disc(b) => {
            let (dx, dy) = (x - f64::from(b.x), y - f64::from(b.y));
            let radius = r + f64::from(b.r);
            (0..32)
                .map(|k| {
                    let (c, s) = unit(2 * k + 1);
                    (dx * c + dy * s).abs() - apothem(radius)
                })
                .fold(f64::MIN, f64::max)
        }
        Other::Rect(rect, [theta, length, width]) => {
            let (rc, rs) = (f64::from(*theta).cos(), f64::from(*theta).sin());
            let (hl, hw) = (0.5 * f64::from(*length), 0.5 * f64::from(*width));
            let (dx, dy) = (x - f64::from(rect.x), y - f64::from(rect.y));
            // The unit 64-gon's half-width along u: its largest vertex projection.
            let support = |ux: f64, uy: f64| {
                (0..32)
                    .map(|k| {
                        let (c, s) = unit(2 * k);
                        (c * ux + s * uy).abs()
                    })
                    .fold(0.0, f64::max)
            };
            let rect_axes = [
                (dx * rc + dy * rs).abs() - (hl + r * support(rc, rs)),
                (dy * rc - dx * rs).abs() - (hw + r * support(-rs, rc)),
            ];
            let polygon_axes = (0..32).map(|k| {
                let (c, s) = unit(2 * k + 1);
                let half = hl * (rc * c + rs * s).abs() + hw * (rc * s - rs * c).abs();
                (dx * c + dy * s).abs() - (apothem(r) + half)
            });
            rect_axes
                .into_iter()
                .chain(polygon_axes)
                .fold(f64::MIN, f64::max)
        }
    }
}

/// Distance (m, f64) from the disc's centre to the other shape's exact boundary region, and the
/// radius that exact discs compare it with.
fn exact_distance(p: &Pair) -> (f64, f64) {
    let (x, y, r) = (
        f64::from(p.disc.x),
        f64::from(p.disc.y),
        f64::from(p.disc.r),
    );
    match &p.other {
        Other::Disc(b) => (
            (x - f64::from(b.x)).hypot(y - f64::from(b.y)),
            r + f64::from(b.r),
        ),
        Other::Rect(rect, [theta, length, width]) => {
            let (rc, rs) = (f64::from(*theta).cos(), f64::from(*theta).sin());
            let (dx, dy) = (x - f64::from(rect.x), y - f64::from(rect.y));
            let (lx, ly) = (dx * rc + dy * rs, dy * rc - dx * rs);
            let ex = (lx.abs() - 0.5 * f64::from(*length)).max(0.0);
            let ey = (ly.abs() - 0.5 * f64::from(*width)).max(0.0);
            (ex.hypot(ey), r)
        }
    }
}

/// Bound on how far f32 rounding moves the contact threshold, as a fraction of the pair's
/// scale (its largest coordinate or size, ≤ 12 m here). Each tested quantity (a projection
/// |d·n| against a limit such as r·cos(π/64) + hl·|a·n| + hw·|b·n|) is computed in f32 from
/// inputs that are exact f32 values: the centre difference rounds once (2^-24 relative), the
/// table's cos and sin are within 2^-25 of the exact values, each product and sum rounds once
/// (5 roundings on a side at most), and a rectangle's heading cosine and sine come from
/// `math::sin_cos` within 2 ulps, against shapely's float64 corners; with the float64
/// vertices of shapely (1e-16 relative) beside these, each side is within 8·2^-24 of the scale
/// of its exact value, and the two sides of the comparison within 16·2^-24 = 2^-20. A pair
/// whose exact separation exceeds this cannot be decided differently from shapely.
const F32_BOUND: f64 = 1.0 / (1u64 << 20) as f64;

/// Contract: with `polygon64`, socnav's disc-disc and disc-rectangle tests give shapely's
/// verdict on every reference pair except those within the f32 bound of the threshold (a few);
/// exact discs disagree with shapely only inside the 64-gon's inset, always by touching where
/// the 64-gon does not, and the sample holds many such pairs.
#[test]
fn polygon64_agrees_with_shapely() {
    let pairs = reference_pairs();
    assert_eq!(pairs.len(), 640, "the reference file's pairs");
    let (mut excluded, mut excluded_disagree, mut exact_disagree) = (0, 0, 0);
    for (n, p) in pairs.iter().enumerate() {
        let (polygon, exact) = match &p.other {
            Other::Disc(b) => (poly64_disc_disc(&p.disc, b), disc_disc(&p.disc, b)),
            Other::Rect(rect, _) => (poly64_disc_rect(&p.disc, rect), disc_rect(&p.disc, rect)),
        };
        let bound = F32_BOUND * p.scale;
        let sep = separation(p);
        // The float64 model is shapely's polygon: it agrees except within float64 rounding.
        if sep.abs() > 1e-12 * p.scale {
            assert_eq!(
                sep <= 0.0,
                p.shapely,
                "pair {n}: float64 64-gon model vs shapely"
            );
        }
        if sep.abs() <= bound {
            excluded += 1;
            excluded_disagree += usize::from(polygon != p.shapely);
        } else {
            assert_eq!(
                polygon, p.shapely,
                "pair {n}: polygon64 vs shapely (sep {sep:e})"
            );
        }
        if exact != p.shapely {
            exact_disagree += 1;
            let (dist, radius) = exact_distance(p);
            assert!(
                exact && !p.shapely,
                "pair {n}: a 64-gon inside its disc cannot touch more"
            );
            assert!(
                dist > radius * (PI / 64.0).cos() - bound && dist <= radius + bound,
                "pair {n}: exact discs disagree outside the inset (distance {dist}, radius {radius})"
            );
        }
    }
    println!(
        "{} pairs: {excluded} within the f32 bound of the threshold ({excluded_disagree} of them \
         decided differently from shapely), {exact_disagree} decided differently by exact discs",
        pairs.len()
    );
    assert!(
        excluded <= pairs.len() / 50,
        "{excluded} pairs within the bound"
    );
    assert!(
        exact_disagree >= pairs.len() / 8,
        "only {exact_disagree} pairs inside the inset"
    );
}
