//! The one world → pixel mapping of a frame. The world is metres with y up and the room centred
//! on the origin (it spans `[-map_x/2, map_x/2] × [-map_y/2, map_y/2]`); the image is pixels with
//! y down. The longest image side is `size_px`, a margin of [`View::margin`] pixels frames the
//! room on every side, and both axes share one scale, so the image keeps the room's aspect ratio.

/// Where the room lies in the image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Image width (px).
    pub width: u32,
    /// Image height (px).
    pub height: u32,
    /// Pixels per metre.
    pub scale: f32,
    /// Free pixels between the room and each image edge (room for tick marks and the progress bar).
    pub margin: f32,
    /// Room size along x (m).
    pub map_x: f32,
    /// Room size along y (m).
    pub map_y: f32,
}

impl View {
    /// The view of a `map_x` × `map_y` m room whose longer image side is `size_px` pixels.
    /// `size_px` must be at least [`super::MIN_SIZE_PX`] and the room sizes positive (the caller checks).
    pub fn new(map_x: f32, map_y: f32, size_px: u32) -> Self {
        let size = size_px as f32;
        // 4 % of the image, at least 10 px: enough for the 1 m ticks and the progress bar.
        let margin = (0.04 * size).round().max(10.0);
        let scale = (size - 2.0 * margin) / map_x.max(map_y);
        let side = |m: f32| ((m * scale + 2.0 * margin).round() as u32).clamp(1, size_px.max(1));
        Self {
            width: side(map_x),
            height: side(map_y),
            scale,
            margin,
            map_x,
            map_y,
        }
    }

    /// World point (m) → pixel coordinates (x right, y down; pixel centres at +0.5).
    #[inline]
    pub fn px(&self, x: f32, y: f32) -> (f32, f32) {
        let cx = 0.5 * self.width as f32;
        let cy = 0.5 * self.height as f32;
        (cx + x * self.scale, cy - y * self.scale)
    }

    /// World length (m) → pixels.
    #[inline]
    pub fn len(&self, metres: f32) -> f32 {
        metres * self.scale
    }

    /// The width of a thin line (px): about 1/400 of the image's longer side, at least 1 px.
    pub fn line(&self) -> f32 {
        (self.width.max(self.height) as f32 / 400.0).max(1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn longest_side_is_size_and_aspect_is_kept() {
        let v = View::new(14.0, 7.0, 400);
        assert_eq!(v.width, 400);
        assert_eq!(v.margin, 16.0);
        // Room 14 m → 368 px, so 7 m → 184 px, plus two margins.
        assert_eq!(v.height, 184 + 32);
        assert_eq!(v.px(0.0, 0.0), (200.0, 108.0));
        // y up in the world is y down in the image.
        let (x, y) = v.px(7.0, 3.5);
        assert!(
            (x - 384.0).abs() < 1e-3 && (y - 16.0).abs() < 1e-3,
            "{x} {y}"
        );
    }
}
