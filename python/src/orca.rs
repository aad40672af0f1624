//! `socnav._socnav.orca_compute_velocities` and `orca_compute_velocities_batch`: the core's
//! standalone ORCA solver (`socnav::orca::compute_velocities`, the new velocities of one RVO2
//! 2.0.3 `doStep`) over numpy arrays.
//!
//! The public entry point is the Python module `socnav.orca`: it broadcasts scalar parameters,
//! converts dtypes and checks ranks, then calls these with float32 `(n, 2)` / `(n,)` arrays
//! (int64 for `max_neighbors`). Shapes and values are checked again here because these
//! functions can be called directly: every bad input is a `ValueError` that names the Python
//! argument and the value, never a panic.

use ndarray::{ArrayView1, ArrayView2};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use socnav::orca::{
    ObstacleScratch, ObstacleSet, OrcaAgent, OrcaError, Scene, compute_velocities,
    compute_velocities_batch, process_obstacles,
};

/// Adds the ORCA functions to the extension module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(orca_compute_velocities, m)?)?;
    m.add_function(wrap_pyfunction!(orca_compute_velocities_batch, m)?)?;
    Ok(())
}

/// One scene's arguments, viewed while the GIL is held.
struct SceneArgs<'a> {
    positions: ArrayView2<'a, f32>,
    velocities: ArrayView2<'a, f32>,
    pref_velocities: ArrayView2<'a, f32>,
    radius: ArrayView1<'a, f32>,
    max_speed: ArrayView1<'a, f32>,
    neighbor_dist: ArrayView1<'a, f32>,
    max_neighbors: ArrayView1<'a, i64>,
    time_horizon: ArrayView1<'a, f32>,
    time_horizon_obst: ArrayView1<'a, f32>,
    time_step: f32,
    obstacles: Vec<ArrayView2<'a, f32>>,
}

/// Copies the arguments into a core [`Scene`], checking every shape and the integer range of
/// `max_neighbors`; the float values are checked by the core (`Scene::validate`).
fn build_scene(a: &SceneArgs<'_>) -> Result<Scene, String> {
    let n = a.positions.nrows();
    if a.positions.ncols() != 2 {
        return Err(format!(
            "positions must have shape (n, 2), got {:?}",
            a.positions.shape()
        ));
    }
    for (name, v) in [
        ("velocities", &a.velocities),
        ("pref_velocities", &a.pref_velocities),
    ] {
        if v.shape() != [n, 2] {
            return Err(format!(
                "{name} must have shape ({n}, 2) like positions, got {:?}",
                v.shape()
            ));
        }
    }
    let per_agent = [
        ("radius", a.radius.len()),
        ("max_speed", a.max_speed.len()),
        ("neighbor_dist", a.neighbor_dist.len()),
        ("max_neighbors", a.max_neighbors.len()),
        ("time_horizon", a.time_horizon.len()),
        ("time_horizon_obst", a.time_horizon_obst.len()),
    ];
    for (name, len) in per_agent {
        if len != n {
            return Err(format!(
                "{name} must have shape ({n},), one value per agent, got ({len},)"
            ));
        }
    }
    let mut agents = Vec::with_capacity(n);
    for i in 0..n {
        let k = a.max_neighbors[i];
        // RVO2 takes a size_t; the core keeps u32, which no real scene comes near.
        let max_neighbors = u32::try_from(k).map_err(|_| {
            format!(
                "max_neighbors[{i}] = {k}: must be an integer in [0, {}]",
                u32::MAX
            )
        })?;
        let row = |m: &ArrayView2<'_, f32>| [m[[i, 0]], m[[i, 1]]];
        agents.push(OrcaAgent {
            pos: row(&a.positions),
            vel: row(&a.velocities),
            pref_vel: row(&a.pref_velocities),
            radius: a.radius[i],
            max_speed: a.max_speed[i],
            neighbor_dist: a.neighbor_dist[i],
            max_neighbors,
            time_horizon: a.time_horizon[i],
            time_horizon_obst: a.time_horizon_obst[i],
        });
    }
    let mut obstacles = Vec::with_capacity(a.obstacles.len());
    for (p, poly) in a.obstacles.iter().enumerate() {
        if poly.ncols() != 2 {
            return Err(format!(
                "obstacles[{p}] must have shape (k, 2), k vertices, got {:?}",
                poly.shape()
            ));
        }
        obstacles.push(poly.rows().into_iter().map(|v| [v[0], v[1]]).collect());
    }
    Ok(Scene {
        time_step: a.time_step,
        agents,
        obstacles,
    })
}

/// The Python argument that a core parameter name comes from.
fn python_name(core_name: &str) -> &str {
    match core_name {
        "pos" => "positions",
        "vel" => "velocities",
        "pref_vel" => "pref_velocities",
        other => other,
    }
}

/// A core error as a message in the caller's terms: Python argument names, indices into the
/// arrays and lists as passed, and the offending values (read back from `scene`).
fn orca_message(e: &OrcaError, scene: &Scene) -> String {
    match *e {
        OrcaError::TooFewVertices { polygon, count } => format!(
            "obstacles[{polygon}] has {count} vertices; at least 2 are needed (2 vertices make a \
             line segment)"
        ),
        OrcaError::NonFiniteVertex {
            polygon,
            vertex,
            x,
            y,
        } => format!("obstacles[{polygon}][{vertex}] = ({x}, {y}): vertices must be finite"),
        OrcaError::InvalidParameter {
            agent: Some(i),
            name,
            value,
            reason,
        } => {
            let a = scene.agents.get(i);
            let vector = match name {
                "pos" => a.map(|a| a.pos),
                "vel" => a.map(|a| a.vel),
                "pref_vel" => a.map(|a| a.pref_vel),
                _ => None,
            };
            let arg = python_name(name);
            match vector {
                Some([x, y]) => format!("{arg}[{i}] = ({x}, {y}): {reason}"),
                None => format!("{arg}[{i}] = {value}: {reason}"),
            }
        }
        OrcaError::InvalidParameter {
            agent: None,
            name,
            value,
            reason,
        } => format!("{} = {value}: {reason}", python_name(name)),
    }
}

/// `(n, 2)` float32 array of `velocities`.
fn to_numpy<'py>(py: Python<'py>, velocities: &[[f32; 2]]) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let flat: Vec<f32> = velocities.iter().flatten().copied().collect();
    PyArray1::from_vec(py, flat).reshape([velocities.len(), 2])
}

/// New velocities (m/s), float32 `(n, 2)`, of one RVO2 `doStep` on one scene (see
/// `socnav.orca.compute_velocities`). The GIL is released while ORCA runs.
#[pyfunction]
#[pyo3(signature = (positions, velocities, pref_velocities, radius, max_speed, neighbor_dist,
    max_neighbors, time_horizon, time_horizon_obst, time_step, obstacles=None))]
#[allow(
    clippy::too_many_arguments,
    reason = "mirrors RVO2's per-agent parameters one argument each, as the Python API does"
)]
fn orca_compute_velocities<'py>(
    py: Python<'py>,
    positions: PyReadonlyArray2<'py, f32>,
    velocities: PyReadonlyArray2<'py, f32>,
    pref_velocities: PyReadonlyArray2<'py, f32>,
    radius: PyReadonlyArray1<'py, f32>,
    max_speed: PyReadonlyArray1<'py, f32>,
    neighbor_dist: PyReadonlyArray1<'py, f32>,
    max_neighbors: PyReadonlyArray1<'py, i64>,
    time_horizon: PyReadonlyArray1<'py, f32>,
    time_horizon_obst: PyReadonlyArray1<'py, f32>,
    time_step: f32,
    obstacles: Option<Vec<PyReadonlyArray2<'py, f32>>>,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let obstacles = obstacles.unwrap_or_default();
    let args = SceneArgs {
        positions: positions.as_array(),
        velocities: velocities.as_array(),
        pref_velocities: pref_velocities.as_array(),
        radius: radius.as_array(),
        max_speed: max_speed.as_array(),
        neighbor_dist: neighbor_dist.as_array(),
        max_neighbors: max_neighbors.as_array(),
        time_horizon: time_horizon.as_array(),
        time_horizon_obst: time_horizon_obst.as_array(),
        time_step,
        obstacles: obstacles.iter().map(PyReadonlyArray2::as_array).collect(),
    };
    let scene = build_scene(&args).map_err(PyValueError::new_err)?;
    let result = py.detach(|| compute_velocities(&scene));
    let new_vel = result.map_err(|e| PyValueError::new_err(orca_message(&e, &scene)))?;
    to_numpy(py, &new_vel)
}

/// [`orca_compute_velocities`] for many scenes at once, solved in parallel (rayon) with the
/// GIL released: every argument is a list with one entry per scene (`obstacles`: a list of
/// polygon lists). Returns a list of float32 `(n_s, 2)` arrays in scene order; results do not
/// depend on the thread count.
#[pyfunction]
#[pyo3(signature = (positions, velocities, pref_velocities, radius, max_speed, neighbor_dist,
    max_neighbors, time_horizon, time_horizon_obst, time_step, obstacles))]
#[allow(
    clippy::too_many_arguments,
    reason = "mirrors RVO2's per-agent parameters one argument each, as the Python API does"
)]
fn orca_compute_velocities_batch<'py>(
    py: Python<'py>,
    positions: Vec<PyReadonlyArray2<'py, f32>>,
    velocities: Vec<PyReadonlyArray2<'py, f32>>,
    pref_velocities: Vec<PyReadonlyArray2<'py, f32>>,
    radius: Vec<PyReadonlyArray1<'py, f32>>,
    max_speed: Vec<PyReadonlyArray1<'py, f32>>,
    neighbor_dist: Vec<PyReadonlyArray1<'py, f32>>,
    max_neighbors: Vec<PyReadonlyArray1<'py, i64>>,
    time_horizon: Vec<PyReadonlyArray1<'py, f32>>,
    time_horizon_obst: Vec<PyReadonlyArray1<'py, f32>>,
    time_step: Vec<f32>,
    obstacles: Vec<Vec<PyReadonlyArray2<'py, f32>>>,
) -> PyResult<Vec<Bound<'py, PyArray2<f32>>>> {
    let s = positions.len();
    let lengths = [
        ("velocities", velocities.len()),
        ("pref_velocities", pref_velocities.len()),
        ("radius", radius.len()),
        ("max_speed", max_speed.len()),
        ("neighbor_dist", neighbor_dist.len()),
        ("max_neighbors", max_neighbors.len()),
        ("time_horizon", time_horizon.len()),
        ("time_horizon_obst", time_horizon_obst.len()),
        ("time_step", time_step.len()),
        ("obstacles", obstacles.len()),
    ];
    for (name, len) in lengths {
        if len != s {
            return Err(PyValueError::new_err(format!(
                "{name} has {len} entries but positions has {s}: one entry per scene"
            )));
        }
    }
    let mut scenes = Vec::with_capacity(s);
    for i in 0..s {
        let args = SceneArgs {
            positions: positions[i].as_array(),
            velocities: velocities[i].as_array(),
            pref_velocities: pref_velocities[i].as_array(),
            radius: radius[i].as_array(),
            max_speed: max_speed[i].as_array(),
            neighbor_dist: neighbor_dist[i].as_array(),
            max_neighbors: max_neighbors[i].as_array(),
            time_horizon: time_horizon[i].as_array(),
            time_horizon_obst: time_horizon_obst[i].as_array(),
            time_step: time_step[i],
            obstacles: obstacles[i]
                .iter()
                .map(PyReadonlyArray2::as_array)
                .collect(),
        };
        let scene =
            build_scene(&args).map_err(|m| PyValueError::new_err(format!("scenes[{i}]: {m}")))?;
        scenes.push(scene);
    }
    // Parameter errors are cheap to find before the solve; obstacle errors show up in it (or
    // in `first_error`, which only runs on the error path).
    if let Some(bad) = scenes.iter().position(|scene| scene.validate().is_err()) {
        return Err(first_error(&scenes[..=bad]));
    }
    match py.detach(|| compute_velocities_batch(&scenes)) {
        Ok(all) => all.iter().map(|v| to_numpy(py, v)).collect(),
        Err(_) => Err(first_error(&scenes)),
    }
}

/// The error of the first scene that has one, parameters or obstacles, as `compute_velocities`
/// would report it, prefixed with the scene's index. Only called when some scene fails.
fn first_error(scenes: &[Scene]) -> PyErr {
    let failure = scenes.iter().enumerate().find_map(|(i, scene)| {
        scene
            .validate()
            .and_then(|()| {
                process_obstacles(
                    &scene.obstacles,
                    &mut ObstacleScratch::new(),
                    &mut ObstacleSet::new(),
                )
            })
            .err()
            .map(|e| (i, e))
    });
    PyValueError::new_err(match failure {
        Some((i, e)) => format!("scenes[{i}]: {}", orca_message(&e, &scenes[i])),
        // Not reached: the caller saw a failure, and these are compute_velocities' two checks.
        None => "compute_velocities_batch failed on a scene that is valid".to_owned(),
    })
}
