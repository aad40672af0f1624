//! The live viewer (feature `viewer`): one environment in a window, as `socnav play` and
//! Python's `render_mode="human"` show it. [`Window`] shows frames and reports keys,
//! [`controls`] turns keys and gamepad sticks into actions, [`hud`] lays the scene (the
//! renderer's frame, unchanged) beside a panel of text. The window library (minifb) loads X11 or
//! Wayland at run time, so building needs no system package; without a display
//! [`Window::open`] says so. With the `gamepad` feature (gilrs; building it needs libudev's
//! headers) `gamepad::Pads` reads a gamepad too.

pub mod controls;
#[cfg(feature = "gamepad")]
pub mod gamepad;
pub mod hud;
mod window;

pub use controls::Command;
pub use window::{Input, Window, no_display_reason};
