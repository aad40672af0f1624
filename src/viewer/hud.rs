//! The window's picture: the scene exactly as `socnav::render` draws it (the `rgb_array` frame,
//! pixel for pixel) at the top left, and a heads-up panel of text lines to its right.

use crate::render::Pixmap;

/// Width of the text panel (px): 40 characters of the 8 px font.
pub const HUD_WIDTH_PX: usize = 336;
/// Height of a text line (px).
const LINE_PX: usize = 12;
const PAD_PX: usize = 8;
const PANEL: u32 = 0x1e_22_28;
const INK: u32 = 0xe6_e6_e6;
/// Lines that start with this are drawn in the accent colour (an episode's outcome).
pub const ACCENT_MARK: char = '!';
const ACCENT: u32 = 0xff_c0_40;

/// The window's size (px) for a scene of `scene_w` × `scene_h` and `lines` text lines.
pub fn size(scene_w: usize, scene_h: usize, lines: usize) -> (usize, usize) {
    (
        scene_w + HUD_WIDTH_PX,
        scene_h.max(2 * PAD_PX + lines * LINE_PX),
    )
}

/// `scene` and the text `lines` into `out` (0RGB pixels, row-major, `width` × `height` from
/// [`size`]); text that does not fit the panel is cut.
pub fn compose(
    scene: &Pixmap,
    lines: &[String],
    (width, height): (usize, usize),
    out: &mut Vec<u32>,
) {
    out.clear();
    out.resize(width * height, PANEL);
    let (sw, sh) = (scene.width() as usize, scene.height() as usize);
    for (y, row) in scene
        .data()
        .chunks_exact(4 * sw)
        .enumerate()
        .take(height.min(sh))
    {
        for (x, px) in row.chunks_exact(4).enumerate() {
            // The scene is opaque (the renderer fills its background), so premultiplied RGBA is
            // plain RGB.
            out[y * width + x] = u32::from(px[0]) << 16 | u32::from(px[1]) << 8 | u32::from(px[2]);
        }
    }
    let left = sw + PAD_PX;
    for (k, line) in lines.iter().enumerate() {
        let top = PAD_PX + k * LINE_PX;
        if top + 8 > height {
            break;
        }
        let (text, colour) = match line.strip_prefix(ACCENT_MARK) {
            Some(rest) => (rest, ACCENT),
            None => (line.as_str(), INK),
        };
        text_at(out, width, (left, top), text, colour);
    }
}

/// `text` in the 8 × 8 font with its top left at `(x, y)`, cut at the buffer's right edge.
fn text_at(out: &mut [u32], width: usize, (x, y): (usize, usize), text: &str, colour: u32) {
    for (k, ch) in text.chars().enumerate() {
        let left = x + 8 * k;
        if left + 8 > width {
            break;
        }
        let code = if ch.is_ascii() {
            ch as usize
        } else {
            '?' as usize
        };
        for (row, bits) in font8x8::legacy::BASIC_LEGACY[code].iter().enumerate() {
            for col in 0..8 {
                if bits & (1 << col) != 0 {
                    out[(y + row) * width + left + col] = colour;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scene_is_copied_pixel_for_pixel_and_the_text_beside_it() {
        let mut scene = Pixmap::new(20, 10).expect("pixmap");
        scene.fill(tiny_skia::Color::from_rgba8(10, 20, 30, 255));
        let lines = vec!["step 1".to_string(), "!success".to_string()];
        let (w, h) = size(20, 10, lines.len());
        assert_eq!((w, h), (20 + HUD_WIDTH_PX, 2 * PAD_PX + 2 * LINE_PX));
        let mut out = Vec::new();
        compose(&scene, &lines, (w, h), &mut out);
        assert_eq!(out.len(), w * h);
        assert!((0..10).all(|y| (0..20).all(|x| out[y * w + x] == 0x0a_14_1e)));
        // Below the scene and in the panel: the panel colour, with ink and accent pixels.
        assert_eq!(out[15 * w + 3], PANEL);
        let panel: Vec<u32> = (0..h)
            .flat_map(|y| out[y * w + 20..(y + 1) * w].to_vec())
            .collect();
        assert!(panel.contains(&INK) && panel.contains(&ACCENT));
    }
}
