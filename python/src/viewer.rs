//! The live viewer and SocNavGym's JSON recordings for Python: `Viewer` (a window that shows
//! frames beside a text panel and reports keys; `render_mode="human"`) and
//! `socnavgym_episode_json` (one implementation of 0.1.1's recording layout, `socnav::recording`).

use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use socnav::recording::{Step, episode_json};
use socnav::spec::ObsLayout;
use socnav::viewer::{Command, Window, hud};

use crate::py_err;

/// A window showing frames (uint8 `(H, W, 3)`) beside a panel of text lines, and the keys a
/// person presses. Opened at the first `show`, sized for that frame and number of lines; later
/// frames must have the same size.
#[pyclass(unsendable, module = "socnav._socnav")]
pub struct Viewer {
    title: String,
    window: Option<Window>,
    frame: (usize, usize),
    pixels: Vec<u32>,
    closed: bool,
}

fn pixmap_of(frame: &PyReadonlyArray3<'_, u8>) -> PyResult<socnav::render::Pixmap> {
    let rgb = frame.as_array();
    let shape = rgb.shape();
    if shape[2] != 3 {
        return Err(PyValueError::new_err(format!(
            "a frame is (H, W, 3) uint8, got {shape:?}"
        )));
    }
    let (h, w) = (shape[0], shape[1]);
    let mut pm = socnav::render::Pixmap::new(w as u32, h as u32)
        .ok_or_else(|| PyValueError::new_err(format!("cannot show a {w}x{h} frame")))?;
    for (px, (y, x)) in pm
        .data_mut()
        .chunks_exact_mut(4)
        .zip((0..h).flat_map(|y| (0..w).map(move |x| (y, x))))
    {
        px.copy_from_slice(&[rgb[[y, x, 0]], rgb[[y, x, 1]], rgb[[y, x, 2]], 255]);
    }
    Ok(pm)
}

fn command_name(c: Command) -> &'static str {
    match c {
        Command::Quit => "quit",
        Command::Restart => "restart",
        Command::Pause => "pause",
        Command::Step => "step",
        Command::Faster => "faster",
        Command::Slower => "slower",
    }
}

#[pymethods]
impl Viewer {
    #[new]
    #[pyo3(signature = (title="socnav"))]
    fn new(title: &str) -> Self {
        Self {
            title: title.to_owned(),
            window: None,
            frame: (0, 0),
            pixels: Vec::new(),
            closed: false,
        }
    }

    /// Show `frame` with `lines` of text beside it (opening the window at the first call).
    /// Raises `socnav.DisplayError` when no window can open.
    #[pyo3(signature = (frame, lines=Vec::new()))]
    fn show(&mut self, frame: PyReadonlyArray3<'_, u8>, lines: Vec<String>) -> PyResult<()> {
        if self.closed {
            return Ok(());
        }
        let pm = pixmap_of(&frame)?;
        let size = (pm.width() as usize, pm.height() as usize);
        let window = match &mut self.window {
            Some(window) => window,
            empty => {
                let (w, h) = hud::size(size.0, size.1, lines.len().max(24));
                self.frame = size;
                empty.insert(Window::open(&self.title, w, h).map_err(py_err)?)
            }
        };
        if size != self.frame {
            return Err(PyValueError::new_err(format!(
                "the viewer shows {}x{} frames, got {}x{}",
                self.frame.0, self.frame.1, size.0, size.1
            )));
        }
        hud::compose(&pm, &lines, window.size(), &mut self.pixels);
        window.show(&self.pixels).map_err(py_err)?;
        if !window.is_open() {
            self.close();
        }
        Ok(())
    }

    /// Whether the window is open (false before the first frame and after a person closed it).
    fn is_open(&self) -> bool {
        self.window.as_ref().is_some_and(Window::is_open)
    }

    /// The direction keys held (`forward`, `back`, `left`, `right`, `strafe_left`,
    /// `strafe_right`) and the viewer commands pressed since the last call (`quit`, `restart`,
    /// `pause`, `step`, `faster`, `slower`).
    fn poll(&self) -> (Vec<&'static str>, Vec<&'static str>) {
        let Some(w) = &self.window else {
            return (Vec::new(), Vec::new());
        };
        let input = w.poll();
        let h = input.held;
        let held = [
            (h.forward, "forward"),
            (h.back, "back"),
            (h.left, "left"),
            (h.right, "right"),
            (h.strafe_left, "strafe_left"),
            (h.strafe_right, "strafe_right"),
        ]
        .into_iter()
        .filter_map(|(on, name)| on.then_some(name))
        .collect();
        (held, input.commands.into_iter().map(command_name).collect())
    }

    /// Close the window (idempotent).
    fn close(&mut self) {
        self.window = None;
        self.closed = true;
    }
}

/// SocNavGym 0.1.1's JSON recording of one episode (`socnav::recording`): `obs` float32
/// `(T, dim)` (the observations the steps returned), `actions` float32 `(T, 3)`, `rewards`
/// float32 `(T,)`, with the observation layout `robot` (floats), `offsets` and `capacities` (per
/// entity type, in `humans, laptops, tables, plants, walls` order) and `dim`.
#[pyfunction]
pub fn socnavgym_episode_json(
    obs: PyReadonlyArray2<'_, f32>,
    actions: PyReadonlyArray2<'_, f32>,
    rewards: PyReadonlyArray1<'_, f32>,
    robot: usize,
    offsets: [usize; 5],
    capacities: [usize; 5],
    dim: usize,
) -> PyResult<String> {
    let (obs, actions, rewards) = (obs.as_array(), actions.as_array(), rewards.as_array());
    let t = rewards.len();
    if obs.nrows() != t || actions.nrows() != t || actions.ncols() != 3 {
        return Err(PyValueError::new_err(format!(
            "an episode of {t} rewards needs {t} observations and ({t}, 3) actions, got {:?} and {:?}",
            obs.shape(),
            actions.shape()
        )));
    }
    let layout = ObsLayout {
        robot,
        capacity: capacities,
        offset: offsets,
        dim,
        pairs: [0, 0],
    };
    let rows: Vec<Vec<f32>> = obs.rows().into_iter().map(|r| r.to_vec()).collect();
    let steps: Vec<Step<'_>> = rows
        .iter()
        .zip(actions.rows())
        .zip(rewards.iter())
        .map(|((o, a), &reward)| Step {
            obs: o,
            action: [a[0], a[1], a[2]],
            reward,
        })
        .collect();
    episode_json(&layout, &steps).map_err(py_err)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Viewer>()?;
    m.add_function(wrap_pyfunction!(socnavgym_episode_json, m)?)?;
    Ok(())
}
