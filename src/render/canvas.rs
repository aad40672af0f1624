//! Drawing primitives in world coordinates: a [`Canvas`] owns the pixmap and the [`View`], turns
//! metres into pixels once, and draws anti-aliased discs, rotated rectangles, lines and crosses.
//! Line widths are in units of [`View::line`], so frames of every size look alike.

use tiny_skia::{FillRule, LineCap, Mask, Paint, Path, PathBuilder, Pixmap, Stroke, Transform};

use super::palette::Rgb;
use super::view::View;
use crate::geometry::Rect;
use crate::math;

/// A fill and/or an outline.
#[derive(Debug, Clone, Copy)]
pub struct Style {
    /// Fill colour and opacity.
    pub fill: Option<(Rgb, f32)>,
    /// Outline colour, opacity and width (in [`View::line`] units).
    pub stroke: Option<(Rgb, f32, f32)>,
}

impl Style {
    /// An opaque fill with a darker outline of width 1.
    pub fn solid(c: Rgb) -> Self {
        Self {
            fill: Some((c, 1.0)),
            stroke: Some((c.darker(0.55), 1.0, 1.0)),
        }
    }

    /// An outline only.
    pub fn outline(c: Rgb, alpha: f32, width: f32) -> Self {
        Self {
            fill: None,
            stroke: Some((c, alpha, width)),
        }
    }
}

/// A pixmap being drawn through a view.
#[derive(Debug)]
pub struct Canvas {
    /// The image.
    pub pixmap: Pixmap,
    /// The world → pixel mapping.
    pub view: View,
    /// While set, drawing only touches pixels inside this mask ([`Canvas::clip_to`]).
    clip: Option<Mask>,
}

fn paint(c: Rgb, alpha: f32) -> Paint<'static> {
    let mut p = Paint::default();
    p.set_color(c.with_alpha(alpha));
    p.anti_alias = true;
    p
}

impl Canvas {
    /// A canvas of `view`'s size filled with `background`; `None` when tiny-skia cannot allocate it.
    pub fn new(view: View, background: Rgb) -> Option<Self> {
        let mut pixmap = Pixmap::new(view.width, view.height)?;
        pixmap.fill(background.with_alpha(1.0));
        Some(Self {
            pixmap,
            view,
            clip: None,
        })
    }

    /// Clip what is drawn next to the rectangle `r` (m), or stop clipping (`None`). Views that
    /// reach across the whole room are clipped to it so that they never tint the margin.
    pub fn clip_to(&mut self, r: Option<&Rect>) {
        self.clip = r.and_then(|r| {
            let path = self.rect_path(r)?;
            let mut mask = Mask::new(self.view.width, self.view.height)?;
            mask.fill_path(&path, FillRule::Winding, true, Transform::identity());
            Some(mask)
        });
    }

    fn draw(&mut self, path: &Path, style: Style) {
        if let Some((c, a)) = style.fill {
            self.pixmap.fill_path(
                path,
                &paint(c, a),
                FillRule::Winding,
                Transform::identity(),
                self.clip.as_ref(),
            );
        }
        if let Some((c, a, w)) = style.stroke {
            let stroke = Stroke {
                width: w * self.view.line(),
                line_cap: LineCap::Round,
                ..Stroke::default()
            };
            self.pixmap.stroke_path(
                path,
                &paint(c, a),
                &stroke,
                Transform::identity(),
                self.clip.as_ref(),
            );
        }
    }

    /// A disc of radius `r` (m) centred at (x, y) (m).
    pub fn disc(&mut self, x: f32, y: f32, r: f32, style: Style) {
        let (px, py) = self.view.px(x, y);
        if let Some(path) = PathBuilder::from_circle(px, py, self.view.len(r).max(0.5)) {
            self.draw(&path, style);
        }
    }

    /// A rotated rectangle (m).
    pub fn rect(&mut self, r: &Rect, style: Style) {
        if let Some(path) = self.rect_path(r) {
            self.draw(&path, style);
        }
    }

    fn rect_path(&self, r: &Rect) -> Option<Path> {
        let mut pb = PathBuilder::new();
        for k in 0..4 {
            let (x, y) = r.corner(k);
            let (px, py) = self.view.px(x, y);
            if k == 0 {
                pb.move_to(px, py)
            } else {
                pb.line_to(px, py)
            }
        }
        pb.close();
        pb.finish()
    }

    /// A circular sector with apex (x, y) (m) and radius `r` (m), centred on `heading` (rad) and
    /// opening `fov` (rad); a full disc when `fov` ≥ 2π. The arc is a polyline of at most π/64
    /// rad per segment, which stays within a pixel of the circle for any radius inside the frame.
    pub fn wedge(&mut self, (x, y): (f32, f32), heading: f32, fov: f32, r: f32, style: Style) {
        if fov >= math::TAU {
            self.disc(x, y, r, style);
            return;
        }
        let fov = fov.max(0.0);
        let segments = ((fov / (math::PI / 64.0)).ceil() as usize).max(1);
        let mut pb = PathBuilder::new();
        let (px, py) = self.view.px(x, y);
        pb.move_to(px, py);
        for k in 0..=segments {
            let a = heading - 0.5 * fov + fov * k as f32 / segments as f32;
            let (sn, cs) = math::sin_cos(a);
            let (qx, qy) = self.view.px(x + r * cs, y + r * sn);
            pb.line_to(qx, qy);
        }
        pb.close();
        if let Some(path) = pb.finish() {
            self.draw(&path, style);
        }
    }

    /// An open polyline through `points` (m) in colour `c`, opacity `alpha`, width `w` line units.
    pub fn polyline(&mut self, points: &[(f32, f32)], c: Rgb, alpha: f32, w: f32) {
        let mut pb = PathBuilder::new();
        for (k, &(x, y)) in points.iter().enumerate() {
            let (px, py) = self.view.px(x, y);
            if k == 0 {
                pb.move_to(px, py)
            } else {
                pb.line_to(px, py)
            }
        }
        if let Some(path) = pb.finish() {
            self.draw(&path, Style::outline(c, alpha, w));
        }
    }

    /// A segment from `a` to `b` (m).
    pub fn line(&mut self, a: (f32, f32), b: (f32, f32), c: Rgb, alpha: f32, w: f32) {
        self.polyline(&[a, b], c, alpha, w);
    }

    /// An ×-shaped cross of half-size `h` (m) centred at (x, y).
    pub fn cross(&mut self, x: f32, y: f32, h: f32, c: Rgb, alpha: f32) {
        self.line((x - h, y - h), (x + h, y + h), c, alpha, 1.5);
        self.line((x - h, y + h), (x + h, y - h), c, alpha, 1.5);
    }

    /// An axis-aligned rectangle in pixels (for the margin's ticks and progress bar).
    pub fn pixel_rect(&mut self, x: f32, y: f32, w: f32, h: f32, c: Rgb) {
        if let Some(r) = tiny_skia::Rect::from_xywh(x, y, w, h) {
            self.pixmap
                .fill_rect(r, &paint(c, 1.0), Transform::identity(), None);
        }
    }
}
