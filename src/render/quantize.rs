//! Colour quantisation of a frame for GIF (at most 256 colours per frame). A frame is a few
//! dozen flat colours plus the blends that anti-aliasing puts on their edges, so the palette is
//! simply the 256 most frequent colours and every other colour maps to its nearest palette entry.
//! Unlike NeuQuant (`gif::Frame::from_rgba_speed`), which learns a palette weighted by pixel
//! counts, this keeps every flat colour exact however few pixels it covers: with NeuQuant a lone
//! walker of a 1000 px frame (0.1 % of the pixels) came out grey and the robot's trail pink.
//! Ties are broken by colour value, so the output is deterministic.

use std::collections::HashMap;

/// Most colours of a GIF frame's palette.
const MAX_COLOURS: usize = 256;

/// Reusable buffers of the quantiser (no allocation per frame once warmed up).
#[derive(Debug, Default)]
pub struct Quantizer {
    /// Pixel count per colour (0xRRGGBB), then palette index per colour.
    table: HashMap<u32, u32>,
    /// (count, colour), most frequent first.
    ranked: Vec<(u32, u32)>,
    /// The palette: `r, g, b` per entry.
    pub palette: Vec<u8>,
    /// One palette index per pixel.
    pub indices: Vec<u8>,
}

#[inline]
fn key(px: &[u8]) -> u32 {
    (u32::from(px[0]) << 16) | (u32::from(px[1]) << 8) | u32::from(px[2])
}

fn dist_sq(a: u32, b: u32) -> i32 {
    let d = |s: u32| ((a >> s) & 0xff) as i32 - ((b >> s) & 0xff) as i32;
    d(16) * d(16) + d(8) * d(8) + d(0) * d(0)
}

impl Quantizer {
    /// Quantise opaque RGBA pixels (alpha ignored) into [`Quantizer::palette`] and
    /// [`Quantizer::indices`].
    pub fn run(&mut self, rgba: &[u8]) {
        self.table.clear();
        // Runs of one colour are the common case: count them without hashing every pixel.
        let mut run = (u32::MAX, 0u32);
        for px in rgba.chunks_exact(4) {
            let k = key(px);
            if k != run.0 {
                if run.1 > 0 {
                    *self.table.entry(run.0).or_default() += run.1;
                }
                run = (k, 0);
            }
            run.1 += 1;
        }
        if run.1 > 0 {
            *self.table.entry(run.0).or_default() += run.1;
        }
        self.ranked.clear();
        self.ranked
            .extend(self.table.iter().map(|(&colour, &count)| (count, colour)));
        self.ranked
            .sort_unstable_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
        let n = self.ranked.len().min(MAX_COLOURS);
        self.palette.clear();
        for &(_, c) in &self.ranked[..n] {
            self.palette
                .extend_from_slice(&[(c >> 16) as u8, (c >> 8) as u8, c as u8]);
        }
        // Each colour's index depends on that colour alone, so the map's order does not matter.
        let top = &self.ranked[..n];
        for (&colour, slot) in self.table.iter_mut() {
            *slot = nearest(top, colour);
        }
        self.indices.clear();
        let mut last = (u32::MAX, 0u8);
        for px in rgba.chunks_exact(4) {
            let k = key(px);
            if k != last.0 {
                last = (k, self.table[&k] as u8);
            }
            self.indices.push(last.1);
        }
    }
}

/// Index of the palette entry nearest to `colour` (squared RGB distance; the first on ties).
fn nearest(palette: &[(u32, u32)], colour: u32) -> u32 {
    let mut best = (i32::MAX, 0u32);
    for (i, &(_, c)) in palette.iter().enumerate() {
        let d = dist_sq(c, colour);
        if d < best.0 {
            best = (d, i as u32);
            if d == 0 {
                break;
            }
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;

    fn colour_of(q: &Quantizer, i: usize) -> [u8; 3] {
        let p = usize::from(q.indices[i]) * 3;
        [q.palette[p], q.palette[p + 1], q.palette[p + 2]]
    }

    #[test]
    fn up_to_256_colours_are_exact() {
        // 256 distinct colours, each repeated, in no particular order.
        let rgba: Vec<u8> = (0..4000u32)
            .flat_map(|i| [(i * 7 % 256) as u8, 3, 7, 255])
            .collect();
        let mut q = Quantizer::default();
        q.run(&rgba);
        assert_eq!(q.palette.len(), 3 * MAX_COLOURS);
        for (i, px) in rgba.chunks_exact(4).enumerate() {
            assert_eq!(colour_of(&q, i), [px[0], px[1], px[2]]);
        }
    }

    #[test]
    fn rare_flat_colours_survive_and_the_rest_map_to_the_nearest_entry() {
        // 1000 white pixels, 3 blue ones, then 400 distinct singletons (more than a palette holds).
        let mut rgba = vec![255u8; 4 * 1000];
        rgba.extend([31, 119, 180, 255].repeat(3));
        for g in 0..400u32 {
            rgba.extend([(g % 200) as u8, 100, (g / 200) as u8 * 60, 255]);
        }
        let mut q = Quantizer::default();
        q.run(&rgba);
        assert_eq!(q.indices.len(), rgba.len() / 4);
        assert_eq!(q.palette.len(), 3 * MAX_COLOURS);
        assert_eq!(
            colour_of(&q, 0),
            [255, 255, 255],
            "the most frequent colour is exact"
        );
        assert_eq!(
            colour_of(&q, 1000),
            [31, 119, 180],
            "a colour of 3 pixels is exact"
        );
        let d = |a: &[u8], b: &[u8]| {
            (0..3)
                .map(|k| (i32::from(a[k]) - i32::from(b[k])).pow(2))
                .sum::<i32>()
        };
        for (i, px) in rgba.chunks_exact(4).enumerate() {
            let got = d(&colour_of(&q, i), px);
            let best = q.palette.chunks_exact(3).map(|c| d(c, px)).min().unwrap();
            assert_eq!(
                got, best,
                "pixel {i} {px:?} not mapped to its nearest palette colour"
            );
        }
    }
}
