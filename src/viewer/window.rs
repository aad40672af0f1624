//! A window on the screen (minifb: X11 or Wayland, loaded at run time, so building needs no
//! system package): shows 0RGB frames and reports the keys a person presses.

use minifb::{Key, KeyRepeat, WindowOptions};

use super::controls::{Command, Held};
use crate::error::SimError;

/// What the person did since the last poll.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Input {
    /// The direction keys held now.
    pub held: Held,
    /// Viewer commands pressed since the last poll, in order.
    pub commands: Vec<Command>,
}

/// Why no window can open here, if that is known before trying: neither `DISPLAY` (X11) nor
/// `WAYLAND_DISPLAY` is set.
pub fn no_display_reason() -> Option<String> {
    let set = |v: &str| std::env::var_os(v).is_some_and(|s| !s.is_empty());
    if set("DISPLAY") || set("WAYLAND_DISPLAY") {
        None
    } else {
        Some(
            "no display: neither DISPLAY nor WAYLAND_DISPLAY is set (run it in a desktop \
             session, or under a virtual display such as `xvfb-run`)"
                .into(),
        )
    }
}

/// An open window.
pub struct Window {
    inner: minifb::Window,
    size: (usize, usize),
}

impl std::fmt::Debug for Window {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Window")
            .field("size", &self.size)
            .finish_non_exhaustive()
    }
}

impl Window {
    /// Open a `width` × `height` px window titled `title`.
    ///
    /// # Errors
    /// [`SimError::Display`] when there is no display or the window cannot be opened.
    pub fn open(title: &str, width: usize, height: usize) -> Result<Self, SimError> {
        if let Some(reason) = no_display_reason() {
            return Err(SimError::Display(reason));
        }
        let mut inner = minifb::Window::new(title, width, height, WindowOptions::default())
            .map_err(|e| {
                SimError::Display(format!(
                    "cannot open a {width}x{height} window: {}",
                    minifb_reason(&e)
                ))
            })?;
        // The caller paces the frames itself.
        inner.set_target_fps(0);
        Ok(Self {
            inner,
            size: (width, height),
        })
    }

    /// Whether the window is still open (a person can close it).
    pub fn is_open(&self) -> bool {
        self.inner.is_open()
    }

    /// The window's size (px).
    pub fn size(&self) -> (usize, usize) {
        self.size
    }

    /// Show `pixels` (0RGB, row-major, the window's size) and process the window's events.
    ///
    /// # Errors
    /// [`SimError::Shape`] when `pixels` is not the window's size; [`SimError::Display`] when
    /// the display refuses the frame.
    pub fn show(&mut self, pixels: &[u32]) -> Result<(), SimError> {
        let (w, h) = self.size;
        if pixels.len() != w * h {
            return Err(SimError::shape(
                "viewer frame",
                format!(
                    "viewer: a frame of {} pixels for a {w}x{h} window",
                    pixels.len()
                ),
            ));
        }
        self.inner
            .update_with_buffer(pixels, w, h)
            .map_err(|e| SimError::Display(format!("cannot show a frame: {}", minifb_reason(&e))))
    }

    /// The keys held and the commands pressed since the last call (see [`Command`]; the
    /// direction keys are in [`super::controls`]).
    pub fn poll(&self) -> Input {
        let down = self.inner.get_keys();
        let is = |keys: &[Key]| keys.iter().any(|k| down.contains(k));
        let held = Held {
            forward: is(&[Key::Up, Key::W]),
            back: is(&[Key::Down, Key::S]),
            left: is(&[Key::Left, Key::A]),
            right: is(&[Key::Right, Key::D]),
            strafe_left: is(&[Key::Q]),
            strafe_right: is(&[Key::E]),
        };
        let commands = self
            .inner
            .get_keys_pressed(KeyRepeat::No)
            .into_iter()
            .filter_map(command_of)
            .collect();
        Input { held, commands }
    }
}

/// minifb's error with its reason: its `Display` says only "Failed to create window" and drops
/// which X11 call failed (`XOpenDisplay failed`, `Failed to setup X IM via XOpenIM.`, ...).
fn minifb_reason(e: &minifb::Error) -> String {
    match e {
        minifb::Error::WindowCreate(why) | minifb::Error::UpdateFailed(why) => {
            format!("{e} ({why})")
        }
        other => other.to_string(),
    }
}

fn command_of(key: Key) -> Option<Command> {
    Some(match key {
        Key::Escape => Command::Quit,
        Key::R => Command::Restart,
        Key::Space => Command::Pause,
        Key::N | Key::Period => Command::Step,
        Key::Equal | Key::NumPadPlus => Command::Faster,
        Key::Minus | Key::NumPadMinus => Command::Slower,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_errors_keep_the_failing_x11_call() {
        let e = minifb::Error::WindowCreate("XOpenDisplay failed".into());
        assert_eq!(
            minifb_reason(&e),
            "Failed to create window (XOpenDisplay failed)"
        );
        assert_eq!(
            minifb_reason(&minifb::Error::MenusNotSupported),
            "Menus not supported"
        );
    }
}
