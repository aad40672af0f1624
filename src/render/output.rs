//! Writing frames: PNG files through tiny-skia, animated GIFs through the `gif` crate. Every
//! failure to write is a [`SimError::Io`] naming the file, with the kind of the operating system's
//! error when there is one (a full disk is `StorageFull`, not "not found").

use std::borrow::Cow;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use tiny_skia::Pixmap;

use super::quantize::Quantizer;
use crate::error::SimError;

/// Shortest frame delay written (centiseconds). Browsers show delays of 0 and 1 cs as 10 cs, so
/// shorter requests are raised to 2 cs (20 ms) rather than silently slowed down fivefold.
const MIN_DELAY_CS: u16 = 2;

/// Write `pixmap` to `path` as a PNG.
pub fn write_png(pixmap: &Pixmap, path: &Path) -> Result<(), SimError> {
    let bytes = pixmap.encode_png().map_err(|e| {
        SimError::io_other(
            Some(path),
            format!("cannot encode PNG {}: {e}", path.display()),
        )
    })?;
    std::fs::write(path, bytes).map_err(|e| SimError::io("cannot write PNG", path, &e))
}

/// A GIF encoder's failure writing `name`, keeping the operating system's error kind.
fn gif_error(name: &str, e: &gif::EncodingError) -> SimError {
    let kind = match e {
        gif::EncodingError::Io(io) => io.kind(),
        _ => std::io::ErrorKind::Other,
    };
    SimError::Io {
        path: None,
        kind,
        message: format!("cannot write GIF {name}: {e}"),
    }
}

/// Appends frames to an animated GIF that loops forever, each with its own palette of at most
/// 256 colours (the frame's most frequent colours; see `quantize`). Every frame must have the size given
/// at creation. Call [`GifWriter::finish`] to write the trailer; a writer dropped without it leaves
/// a truncated file.
pub struct GifWriter<W: Write = BufWriter<File>> {
    encoder: gif::Encoder<W>,
    name: String,
    width: u16,
    height: u16,
    delay_cs: u16,
    frames: usize,
    quantizer: Quantizer,
}

impl<W: Write> std::fmt::Debug for GifWriter<W> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GifWriter")
            .field("name", &self.name)
            .field("size", &(self.width, self.height))
            .field("delay_cs", &self.delay_cs)
            .field("frames", &self.frames)
            .finish()
    }
}

impl GifWriter {
    /// Create (or truncate) `path` for a `width` × `height` px animation showing each frame for
    /// `frame_ms` milliseconds (rounded to the GIF's centiseconds, at least 20 ms).
    pub fn create(path: &Path, width: u32, height: u32, frame_ms: u32) -> Result<Self, SimError> {
        let file = File::create(path).map_err(|e| SimError::io("cannot create", path, &e))?;
        GifWriter::new(
            BufWriter::new(file),
            &path.display().to_string(),
            width,
            height,
            frame_ms,
        )
    }
}

impl<W: Write> GifWriter<W> {
    /// A GIF written to `writer`; `name` (a path, say) labels its errors. See [`GifWriter::create`].
    pub fn new(
        writer: W,
        name: &str,
        width: u32,
        height: u32,
        frame_ms: u32,
    ) -> Result<Self, SimError> {
        let err = |e: gif::EncodingError| gif_error(name, &e);
        let side = |v: u32| {
            u16::try_from(v).ok().filter(|&v| v > 0).ok_or_else(|| {
                SimError::shape(
                    "GIF",
                    format!("cannot write GIF {name}: a side of {v} px is outside 1..=65535"),
                )
            })
        };
        let (w, h) = (side(width)?, side(height)?);
        let mut encoder = gif::Encoder::new(writer, w, h, &[]).map_err(err)?;
        encoder.set_repeat(gif::Repeat::Infinite).map_err(err)?;
        let delay_cs = u16::try_from(frame_ms.div_ceil(10))
            .unwrap_or(u16::MAX)
            .max(MIN_DELAY_CS);
        Ok(Self {
            encoder,
            name: name.to_string(),
            width: w,
            height: h,
            delay_cs,
            frames: 0,
            quantizer: Quantizer::default(),
        })
    }

    /// Append `pixmap` as the next frame.
    pub fn push(&mut self, pixmap: &Pixmap) -> Result<(), SimError> {
        if (pixmap.width(), pixmap.height()) != (u32::from(self.width), u32::from(self.height)) {
            return Err(SimError::shape(
                "GIF",
                format!(
                    "cannot write GIF {}: frame of {}x{} px in an animation of {}x{} px",
                    self.name,
                    pixmap.width(),
                    pixmap.height(),
                    self.width,
                    self.height
                ),
            ));
        }
        // Frames are drawn on an opaque background, so premultiplied RGBA is plain RGBA.
        let q = &mut self.quantizer;
        q.run(pixmap.data());
        let frame = gif::Frame {
            width: self.width,
            height: self.height,
            delay: self.delay_cs,
            buffer: Cow::Borrowed(&q.indices),
            palette: Some(q.palette.clone()),
            ..gif::Frame::default()
        };
        self.encoder
            .write_frame(&frame)
            .map_err(|e| gif_error(&self.name, &e))?;
        self.frames += 1;
        Ok(())
    }

    /// Frames appended so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// The delay written with each frame (centiseconds).
    pub fn delay_cs(&self) -> u16 {
        self.delay_cs
    }

    /// Write the trailer, flush, and return the writer.
    pub fn finish(self) -> Result<W, SimError> {
        let name = self.name;
        let err = |e: std::io::Error| gif_error(&name, &gif::EncodingError::Io(e));
        let mut w = self.encoder.into_inner().map_err(|e| match e {
            gif::EncodingError::Io(io) => err(io),
            other => gif_error(&name, &other),
        })?;
        w.flush().map_err(err)?;
        Ok(w)
    }
}
