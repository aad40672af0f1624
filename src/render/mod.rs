//! Episode rendering (feature `render`): a top view of one environment of a batch as an
//! anti-aliased RGBA image ([`draw`]), written as PNG ([`write_png`]) or appended to a looping
//! animated GIF ([`GifWriter`]). `socnav render` draws whole episodes with it.
//!
//! What a frame shows, bottom to top (colours in [`palette`]):
//! - the room floor (light) inside the outside colour; an L room's removed block is outside;
//!   1 m tick marks (every 5th longer) in the margin along the bottom and left room edges;
//! - fields of view, clipped to the room: the robot's sensor (a faint red wedge of the
//!   observation's `fov` and `range`) when the observation is partial; each lone walker's view
//!   (a faint blue wedge of `human.fov_angle`, 1.5 m long: humans see without a range limit,
//!   so the wedge shows direction and opening) when that angle leaves anything out;
//! - the robot's goal: a red disc outline of `goal_radius`; lone walkers' goals and moving groups'
//!   goals as faint crosses in their colour; each group's stored centre (`g_x`, `g_y`) as a faint
//!   circle of `group_radius`;
//! - formations in progress: a forming crowd's spot (faint pink circle), its slots (crosses) and
//!   a line from each walker to its slot; a walker's laptop seat (orange cross) and its line;
//! - tables (brown), laptops (grey; in use: amber with an orange rim), plants (green discs);
//! - walls (dark rectangles, corridor walls included; spawn blockers are invisible and not drawn);
//! - the robot's trail (red polyline);
//! - links: lines between the members of each group, and from each laptop user to the laptop;
//! - humans: discs of `human_radius` with a heading line, coloured by role: lone static
//!   (grey-blue), lone walking (blue), moving-group member (purple), standing-group member (pink),
//!   laptop user (orange);
//! - the ORCA shadow robot (faint outline with heading) and the robot (red disc with heading);
//! - a progress bar along the bottom edge: `tick / episode_length`.
//!
//! Episode frames carry no text. [`heatmap`] draws the discomfort heatmap figure (titles and
//! colour bars, in a bitmap font). Rendering only reads the state, so it
//! never changes a trajectory.
//!
//! ```
//! use socnav::{BatchEnv, Config, EnvOptions, render};
//! let mut env = BatchEnv::new(Config::default(), EnvOptions::default()).unwrap();
//! env.reset(Some(3)).unwrap();
//! let frame = render::draw(env.params(), env.state().unwrap(), 0, &[], 200).unwrap();
//! assert_eq!((frame.width(), frame.height()), (200, 200)); // exp1's room is square
//! ```

mod canvas;
pub mod heatmap;
mod output;
pub mod palette;
mod quantize;
mod scene;
mod view;

pub use output::{GifWriter, write_png};
pub use tiny_skia::Pixmap;
pub use view::View;

use crate::error::SimError;
use crate::params::StepParams;
use crate::state::BatchState;

/// Smallest image side accepted (px); the config's `render.resolution` has the same floor.
pub const MIN_SIZE_PX: u32 = 16;
/// Largest image side accepted (px): a GIF side is at most 65535 px, and 8192 px keeps one RGBA
/// frame at 256 MiB.
pub const MAX_SIZE_PX: u32 = 8192;

/// `size_px` as an image side, or a `SimError::Shape` about `what` (the call) naming the `side`
/// (what the size is of) and the accepted range.
///
/// # Errors
/// As said, when `size_px` is outside `MIN_SIZE_PX..=MAX_SIZE_PX`.
pub fn check_size(what: &'static str, side: &str, size_px: u32) -> Result<(), SimError> {
    if (MIN_SIZE_PX..=MAX_SIZE_PX).contains(&size_px) {
        return Ok(());
    }
    Err(SimError::shape(
        what,
        format!("{what}: {side} {size_px} px is outside {MIN_SIZE_PX}..={MAX_SIZE_PX}"),
    ))
}

/// One frame to draw: environment `env` of a batch, with the robot's trail so far.
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    /// Step constants (sizes, radii, episode length).
    pub params: &'a StepParams,
    /// The batch state.
    pub state: &'a BatchState,
    /// Environment to draw.
    pub env: usize,
    /// Robot positions (m, world frame), oldest first; drawn as a polyline when 2 or more.
    pub trail: &'a [(f32, f32)],
    /// Longer image side (px), in `MIN_SIZE_PX..=MAX_SIZE_PX`.
    pub size_px: u32,
}

impl Frame<'_> {
    /// The image's world → pixel mapping, or why this frame cannot be drawn.
    pub fn view(&self) -> Result<View, SimError> {
        let s = self.state;
        if self.env >= s.n_envs {
            return Err(SimError::EnvIndex {
                env: self.env,
                n_envs: s.n_envs,
            });
        }
        check_size("render", "image size", self.size_px)?;
        let (mx, my) = (s.map_x[self.env], s.map_y[self.env]);
        if !(mx.is_finite() && my.is_finite() && mx > 0.0 && my > 0.0) {
            return Err(SimError::shape(
                "render",
                format!(
                    "render: environment {} has room size {mx} x {my} m (reset it before drawing)",
                    self.env
                ),
            ));
        }
        Ok(View::new(mx, my, self.size_px))
    }

    /// Draw the frame.
    pub fn draw(&self) -> Result<Pixmap, SimError> {
        let view = self.view()?;
        let mut canvas = canvas::Canvas::new(view, palette::OUTSIDE).ok_or_else(|| {
            SimError::shape(
                "render",
                format!(
                    "render: cannot allocate a {}x{} px image",
                    view.width, view.height
                ),
            )
        })?;
        let scene = scene::Scene {
            p: self.params,
            s: self.state,
            e: self.env,
            trail: self.trail,
        };
        scene::draw_scene(&mut canvas, &scene);
        Ok(canvas.pixmap)
    }
}

/// Draw environment `env` of `s` (see the module docs for what is shown) with the robot's
/// `trail`; the longer image side is `size_px` pixels. Shorthand for [`Frame::draw`].
pub fn draw(
    p: &StepParams,
    s: &BatchState,
    env: usize,
    trail: &[(f32, f32)],
    size_px: u32,
) -> Result<Pixmap, SimError> {
    Frame {
        params: p,
        state: s,
        env,
        trail,
        size_px,
    }
    .draw()
}
