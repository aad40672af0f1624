//! The discomfort heatmap figure ([`crate::heatmap`]): two panels side by side, SNGNN-v2
//! on the left and DSRNN on the right, each the room seen from above with the field painted
//! cell by cell and the scene drawn over it (the robot's goal, furniture, walls, humans with
//! their headings, group and laptop links); masked cells (the robot would touch a human, an
//! object or a wall, or stand outside the room) are grey. A title line names the config, seed,
//! grid and heading; each panel has its own title and a colour bar with its end values.
//!
//! Both panels share one colour map, from pale (no discomfort) to dark (the most discomfort the
//! term can express): SNGNN-v2's q1 from 1 down to 0, the DSRNN term from 0 down to
//! −(0.6 + human radius + robot radius)·0.5·dt, its value with the two discs touching. Text is
//! drawn with a public-domain 8 × 8 bitmap font (`font8x8`), so no font file is needed.

use tiny_skia::{Pixmap, PixmapPaint, Transform};

use super::canvas::{Canvas, Style};
use super::palette::{self, Rgb};
use super::scene::{self, Scene};
use super::view::View;
use crate::error::SimError;
use crate::geometry::Rect;
use crate::heatmap::Heatmap;
use crate::params::StepParams;
use crate::state::BatchState;

/// What to draw: a heatmap, the scene it was computed on, and the caption's words.
#[derive(Debug, Clone, Copy)]
pub struct Figure<'a> {
    /// The fields.
    pub heatmap: &'a Heatmap,
    /// Step constants of the scene.
    pub params: &'a StepParams,
    /// The scene's state (environment 0 is drawn).
    pub state: &'a BatchState,
    /// The first line of the title (e.g. the config and the seed).
    pub caption: &'a str,
    /// Longer side of each panel's room view (px).
    pub panel_px: u32,
}

/// The second title line: what grey means.
const MASK_NOTE: &str = "grey: the robot would touch a human, an object or a wall";
/// Masked cells.
const MASKED: Rgb = Rgb(150, 152, 158);
/// Text.
const INK: Rgb = Rgb(30, 32, 38);
/// The figure's background.
const PAPER: Rgb = Rgb(255, 255, 255);
/// The colour map, from no discomfort (0) to the most (1): pale yellow, orange, red, purple,
/// near black (after matplotlib's "magma", reversed).
const STOPS: [(f32, Rgb); 5] = [
    (0.0, Rgb(252, 253, 191)),
    (0.25, Rgb(254, 159, 109)),
    (0.5, Rgb(222, 73, 104)),
    (0.75, Rgb(140, 41, 129)),
    (1.0, Rgb(28, 16, 68)),
];

/// The colour of discomfort `t` in [0, 1] (clamped).
pub fn colour(t: f32) -> Rgb {
    let t = t.clamp(0.0, 1.0);
    let k = STOPS
        .windows(2)
        .position(|w| t <= w[1].0)
        .unwrap_or(STOPS.len() - 2);
    let ((t0, a), (t1, b)) = (STOPS[k], STOPS[k + 1]);
    let f = (t - t0) / (t1 - t0);
    let mix = |x: u8, y: u8| (f32::from(x) + (f32::from(y) - f32::from(x)) * f).round() as u8;
    Rgb(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Height of a text line (px): 8 font pixels at scale 2 and a gap.
const LINE_PX: f32 = 20.0;

/// The font pixel size (px) at which every one of `texts` fits in `max_w` px: 2, else 1 (text
/// that still does not fit is cut), so that lines side by side share one size.
fn fit_scale(texts: &[&str], max_w: f32) -> f32 {
    if texts.iter().all(|t| text_width(t) <= max_w) {
        2.0
    } else {
        1.0
    }
}

/// Draw `text` with its top-left corner at (x, y) (px) in font pixels of `scale` px (1 or 2),
/// cut at `max_w` px. Characters outside ASCII are drawn as '?'.
fn text(c: &mut Canvas, (x, y): (f32, f32), text: &str, scale: f32, max_w: f32) {
    let fits = (max_w / (8.0 * scale)).floor().max(0.0) as usize;
    // Smaller text sits in the middle of the line.
    let y = y + (2.0 - scale) * 4.0;
    for (k, ch) in text.chars().take(fits).enumerate() {
        let code = if ch.is_ascii() {
            ch as usize
        } else {
            '?' as usize
        };
        let glyph = font8x8::legacy::BASIC_LEGACY[code];
        let left = x + (k * 8) as f32 * scale;
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..8 {
                if bits & (1 << col) != 0 {
                    let px = left + col as f32 * scale;
                    let py = y + row as f32 * scale;
                    c.pixel_rect(px, py, scale, scale, INK);
                }
            }
        }
    }
}

/// Width of `text` (px) at the larger font size.
fn text_width(text: &str) -> f32 {
    (text.chars().count() * 16) as f32
}

/// One panel: the field of `values` mapped by `discomfort` (value → [0, 1]) over the room,
/// the scene drawn over it.
fn panel(
    f: &Figure<'_>,
    values: &[f32],
    discomfort: &dyn Fn(f32) -> f32,
) -> Result<Pixmap, SimError> {
    let h = f.heatmap;
    let view = View::new(h.map.0, h.map.1, f.panel_px);
    let mut c = Canvas::new(view, palette::OUTSIDE).ok_or_else(|| {
        SimError::shape(
            "heatmap figure",
            format!("heatmap: cannot allocate a {} px panel", f.panel_px),
        )
    })?;
    let sc = Scene {
        p: f.params,
        s: f.state,
        e: 0,
        trail: &[],
    };
    scene::floor(&mut c, &sc);
    scene::ticks(&mut c);
    let (cw, ch) = (h.map.0 / h.n as f32, h.map.1 / h.n as f32);
    for row in 0..h.n {
        for col in 0..h.n {
            let k = row * h.n + col;
            let colour = if h.mask[k] == crate::heatmap::cell::OUTSIDE {
                continue;
            } else if values[k].is_nan() {
                MASKED
            } else {
                colour(discomfort(values[k]))
            };
            let (x, y) = h.centre(row, col);
            // A hair wider than the cell, so that anti-aliased edges leave no seams.
            let cell = Rect::new(x, y, 0.0, cw + 0.01, ch + 0.01);
            let fill = Style {
                fill: Some((colour, 1.0)),
                stroke: None,
            };
            c.rect(&cell, fill);
        }
    }
    scene::draw_overlay(&mut c, &sc);
    Ok(c.pixmap)
}

/// The most negative DSRNN discomfort term (the robot and a human touching at rest).
fn dsrnn_floor(p: &StepParams) -> f32 {
    -(p.reward_discomfort_distance + p.human_radius + p.robot_radius)
        * p.reward_discomfort_factor
        * p.dt
}

/// The figure's size (px) for panels of `panel_w` × `panel_h` px: two panels, a 24 px gap and
/// 16 px of padding across; three text lines above, the colour bar and its labels below.
pub fn figure_size(panel_w: u32, panel_h: u32) -> (u32, u32) {
    let (w, h) = layout(panel_w as f32, panel_h as f32);
    (w.ceil() as u32, h.ceil() as u32)
}

const PAD: f32 = 16.0;
const GAP: f32 = 24.0;
const BAR_H: f32 = 16.0;
/// Above the panels.
const TOP: f32 = PAD + 3.4 * LINE_PX;
/// Below the panels: the bar, its labels, padding.
const BOTTOM: f32 = 12.0 + BAR_H + 6.0 + LINE_PX + PAD;

fn layout(pw: f32, ph: f32) -> (f32, f32) {
    (2.0 * pw + GAP + 2.0 * PAD, TOP + ph + BOTTOM)
}

/// Draw the figure (see the module docs).
///
/// # Errors
/// A heatmap without the SNGNN-v2 field, or a panel size outside the renderer's range.
pub fn draw(f: &Figure<'_>) -> Result<Pixmap, SimError> {
    let h = f.heatmap;
    if h.sngnn.len() != h.n * h.n {
        return Err(SimError::shape(
            "heatmap figure",
            "heatmap figure: the heatmap has no SNGNN-v2 field (compute it with a scorer)",
        ));
    }
    super::check_size("heatmap figure", "panel size", f.panel_px)?;
    let floor = dsrnn_floor(f.params);
    let left = panel(f, &h.sngnn, &|q| 1.0 - q)?;
    let right = panel(f, &h.dsrnn, &|r| r / floor)?;
    let (gap, pad, bar_h, top) = (GAP, PAD, BAR_H, TOP);
    let (pw, ph) = (left.width() as f32, left.height() as f32);
    let (width, height) = layout(pw, ph);
    let view = View::new(1.0, 1.0, 16);
    let mut c = Canvas::new(
        View {
            width: width.ceil() as u32,
            height: height.ceil() as u32,
            ..view
        },
        PAPER,
    )
    .ok_or_else(|| {
        SimError::shape(
            "heatmap figure",
            "heatmap figure: cannot allocate the image",
        )
    })?;
    let line_w = width - 2.0 * pad;
    let scale = fit_scale(&[f.caption, MASK_NOTE], line_w);
    text(&mut c, (pad, pad), f.caption, scale, line_w);
    text(&mut c, (pad, pad + LINE_PX), MASK_NOTE, scale, line_w);
    let panels = [
        (
            &left,
            "SNGNN-v2 q1 (1 = comfortable)",
            ["1.0", "0.5", "0.0"].map(String::from),
        ),
        (
            &right,
            "DSRNN discomfort term",
            [0.0, 0.5 * floor, floor].map(|v| format!("{v:.3}")),
        ),
    ];
    let title_scale = fit_scale(&[panels[0].1, panels[1].1], pw + gap);
    let all_labels: Vec<&str> = panels
        .iter()
        .flat_map(|p| p.2.iter().map(String::as_str))
        .collect();
    let ls = fit_scale(&all_labels, pw / 3.0);
    for (i, (pix, title, labels)) in panels.into_iter().enumerate() {
        let x0 = pad + i as f32 * (pw + gap);
        text(
            &mut c,
            (x0, pad + 2.3 * LINE_PX),
            title,
            title_scale,
            pw + gap,
        );
        c.pixmap.draw_pixmap(
            x0 as i32,
            top as i32,
            pix.as_ref(),
            &PixmapPaint::default(),
            Transform::identity(),
            None,
        );
        let by = top + ph + 12.0;
        let steps = 200;
        for k in 0..steps {
            let t = (k as f32 + 0.5) / steps as f32;
            let w = pw / steps as f32;
            c.pixel_rect(x0 + k as f32 * w, by, w + 0.5, bar_h, colour(t));
        }
        let ly = by + bar_h + 6.0;
        let [a, m, b] = &labels;
        let third = pw / 3.0;
        let w = |t: &str| text_width(t) * 0.5 * ls;
        text(&mut c, (x0, ly), a, ls, third);
        text(&mut c, (x0 + 0.5 * (pw - w(m)), ly), m, ls, third);
        text(&mut c, (x0 + pw - w(b), ly), b, ls, third);
    }
    Ok(c.pixmap)
}
