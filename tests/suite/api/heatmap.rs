//! The discomfort heatmap (`socnav::heatmap`, `socnav heatmap`): the DSRNN field against a
//! hand computation of docs/spec.md 6.2 (no weights needed), the SNGNN-v2 field's range, masks,
//! determinism and its shape around people (needs the weights: skipped loudly without them
//! unless `REQUIRE_SNGNN=1`), and the command's output and errors.

use crate::common;

use std::process::Command;

use socnav::Config;
use socnav::heatmap::{Heatmap, Scene, cell};
use socnav::sngnn::Scorer;

fn no_progress(_: usize) {}

fn dist(dx: f32, dy: f32) -> f32 {
    (dx * dx + dy * dy).sqrt()
}

/// docs/spec.md 6.2 by hand, in f64: each human's relative position p and velocity v (the robot at
/// rest), the closest point of p + v·t for t in [0, dt], minus both radii; the term of the
/// smallest clearance.
fn dsrnn_by_hand(scene: &Scene, x: f64, y: f64) -> f64 {
    let (p, s) = (scene.params(), scene.state());
    let dt = f64::from(p.dt);
    let mut d_min = f64::INFINITY;
    for i in 0..s.n_humans[0] as usize {
        let (px, py) = (f64::from(s.h_x[i]) - x, f64::from(s.h_y[i]) - y);
        let (vx, vy) = (f64::from(s.h_vx[i]), f64::from(s.h_vy[i]));
        let vv = vx * vx + vy * vy;
        let t = if vv > 0.0 {
            (-(px * vx + py * vy) / vv).clamp(0.0, dt)
        } else {
            0.0
        };
        let (cx, cy) = (px + vx * t, py + vy * t);
        let d = (cx * cx + cy * cy).sqrt() - f64::from(p.human_radius) - f64::from(p.robot_radius);
        d_min = d_min.min(d);
    }
    if d_min < 0.6 {
        (d_min - 0.6) * 0.5 * dt
    } else {
        0.0
    }
}

/// exp1 seed 5: lone humans only (no groups or laptop users, whose pseudo-humans the hand
/// computation leaves out).
fn exp1_scene() -> Scene {
    let scene = Scene::new(&Config::from_name_or_path("exp1").unwrap(), 5).unwrap();
    let s = scene.state();
    assert!(s.n_humans[0] > 0, "the scene needs humans");
    assert_eq!((s.n_groups[0], s.n_laptop_users[0]), (0, 0));
    scene
}

#[test]
fn dsrnn_field_matches_hand_computation() {
    let scene = exp1_scene();
    let h = scene.heatmap(24, 0.3, None, &no_progress).unwrap();
    assert!(h.sngnn.is_empty(), "no scorer, no SNGNN-v2 field");
    let mut nonzero = 0;
    for row in 0..h.n {
        for col in 0..h.n {
            let k = row * h.n + col;
            let v = h.dsrnn[k];
            if h.mask[k] != cell::FREE {
                assert!(v.is_nan(), "masked cell {row},{col} holds {v}");
                continue;
            }
            let (x, y) = h.centre(row, col);
            let want = dsrnn_by_hand(&scene, f64::from(x), f64::from(y));
            // f32 arithmetic against f64 on distances of a few metres.
            assert!(
                (f64::from(v) - want).abs() < 2e-6,
                "cell {row},{col} at ({x}, {y}): {v} vs {want}"
            );
            nonzero += usize::from(v != 0.0);
        }
    }
    assert!(
        nonzero >= 4,
        "only {nonzero} cells with discomfort: a weak test"
    );
}

#[test]
fn cells_touching_a_human_are_masked_as_human() {
    let scene = exp1_scene();
    let h = scene.heatmap(30, 0.0, None, &no_progress).unwrap();
    let (p, s) = (scene.params(), scene.state());
    let reach = p.human_radius + p.robot_radius;
    let mut touching = 0;
    for row in 0..h.n {
        for col in 0..h.n {
            let (x, y) = h.centre(row, col);
            let touches = (0..s.n_humans[0] as usize)
                .any(|i| dist(s.h_x[i] - x, s.h_y[i] - y) < reach - 1e-4);
            if touches {
                touching += 1;
                assert_eq!(h.mask[row * h.n + col], cell::HUMAN, "cell {row},{col}");
            }
        }
    }
    assert!(touching > 0);
}

#[test]
fn bad_grid_and_heading_are_errors() {
    let scene = exp1_scene();
    for n in [0, 1, 401] {
        let e = scene.heatmap(n, 0.0, None, &no_progress).unwrap_err();
        assert!(e.to_string().contains("grid size"), "{e}");
    }
    // Past a million radians an f32 angle keeps no fraction of a turn (sin_cos gives NaN).
    for heading in [f32::NAN, f32::INFINITY, 2e6] {
        let e = scene.heatmap(8, heading, None, &no_progress).unwrap_err();
        assert!(e.to_string().contains("heading"), "{e}");
    }
    assert!(scene.heatmap(8, -1e6, None, &no_progress).is_ok());
}

/// The SNGNN-v2 heatmap of exp2_sngnn seed 3 (two groups and a walker), or `None` without
/// the weights.
fn exp2_heatmap(n: usize) -> Option<(Scene, Heatmap)> {
    common::sngnn::real_weights()?;
    let config = Config::from_name_or_path("exp2_sngnn").unwrap();
    let scorer = Scorer::for_config(&config).unwrap();
    let scene = Scene::new(&config, 3).unwrap();
    let h = scene
        .heatmap(n, scene.robot_heading(), Some(&scorer), &no_progress)
        .unwrap();
    Some((scene, h))
}

#[test]
fn sngnn_field_is_in_unit_range_masked_where_dsrnn_is() {
    let Some((_, h)) = exp2_heatmap(20) else {
        return;
    };
    assert_eq!(h.sngnn.len(), 400);
    for k in 0..400 {
        let (q, d) = (h.sngnn[k], h.dsrnn[k]);
        if h.mask[k] == cell::FREE {
            assert!((0.0..=1.0).contains(&q), "cell {k}: q1 {q}");
            assert!(d <= 0.0, "cell {k}: DSRNN {d}");
        } else {
            assert!(q.is_nan() && d.is_nan(), "masked cell {k}: {q} {d}");
        }
    }
    assert!(h.mask.contains(&cell::HUMAN));
}

#[test]
fn sngnn_discomfort_is_higher_near_people() {
    let Some((scene, h)) = exp2_heatmap(24) else {
        return;
    };
    let (p, s) = (scene.params(), scene.state());
    let nearest_human = |x: f32, y: f32| {
        (0..s.n_humans[0] as usize)
            .map(|i| dist(s.h_x[i] - x, s.h_y[i] - y) - p.human_radius - p.robot_radius)
            .fold(f32::INFINITY, f32::min)
    };
    let (mut near, mut far) = (Vec::new(), Vec::new());
    for row in 0..h.n {
        for col in 0..h.n {
            let q = h.sngnn[row * h.n + col];
            if q.is_nan() {
                continue;
            }
            let (x, y) = h.centre(row, col);
            match nearest_human(x, y) {
                d if d < 0.5 => near.push(q),
                d if d > 2.5 => far.push(q),
                _ => {}
            }
        }
    }
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    assert!(near.len() >= 5 && far.len() >= 5, "{near:?} {far:?}");
    // q1 is comfort (the reward term is q1 - 1): lower next to people.
    let (near, far) = (mean(&near), mean(&far));
    assert!(
        near + 0.2 < far,
        "mean q1 within 0.5 m of a person {near}, beyond 2.5 m {far}"
    );
}

#[test]
fn sngnn_heatmap_is_deterministic_across_thread_counts() {
    let Some((_, a)) = exp2_heatmap(12) else {
        return;
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let b = one.install(|| exp2_heatmap(12).unwrap().1);
    let bits = |h: &Heatmap| -> Vec<u32> {
        h.sngnn
            .iter()
            .chain(&h.dsrnn)
            .map(|v| v.to_bits())
            .collect()
    };
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(a.mask, b.mask);
}

fn socnav(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_socnav"))
        .arg("heatmap")
        .args(args)
        .output()
        .expect("socnav runs")
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn cli_rejects_bad_input_clearly() {
    let dir = std::env::temp_dir().join(format!("socnav-heatmap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("h.png");
    let png = png.to_str().unwrap();
    let cases: [(&[&str], &str); 4] = [
        (
            &["--config", "exp2", "--out", png],
            "reward.kind = \"sngnn\"",
        ),
        (
            &["--config", "exp2_sngnn", "--grid", "1", "--out", png],
            "grid size 1",
        ),
        (&["--config", "exp2_sngnn", "--out", "h.gif"], "use .png"),
        (
            &["--config", "no_such_config", "--out", png],
            "no_such_config",
        ),
    ];
    for (args, want) in cases {
        let o = socnav(args);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(stderr(&o).contains(want), "{args:?}: {}", stderr(&o));
    }
    let o = Command::new(env!("CARGO_BIN_EXE_socnav"))
        .args(["heatmap", "--config", "exp2_sngnn", "--out", png])
        .env("SOCNAV_SNGNN_WEIGHTS", dir.join("missing.tch"))
        .output()
        .expect("socnav runs");
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("socnav sngnn install"),
        "{}",
        stderr(&o)
    );
    assert!(!std::path::Path::new(png).exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn cli_writes_the_figure() {
    if common::sngnn::real_weights().is_none() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("socnav-heatmap-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("fig.png");
    let o = socnav(&[
        "--config",
        "exp1_sngnn",
        "--seed",
        "2",
        "--grid",
        "10",
        "--size",
        "200",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("100/100 placements"), "{}", stderr(&o));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    // IHDR: width and height, big-endian, at bytes 16..24. exp1's room is square: two
    // 200 x 200 px panels.
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    assert_eq!((w, h), socnav::render::heatmap::figure_size(200, 200));
    assert_eq!((w, h), (456, 354));
    std::fs::remove_dir_all(&dir).unwrap();
}
