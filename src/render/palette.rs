//! The colours of a frame (sRGB, opaque unless an alpha is given where they are used). Human
//! colours follow the role (`state::role::*`); the robot is the only red entity, so it stays easy
//! to find among humans of every role.

use crate::state::role;

/// An sRGB colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rgb(pub u8, pub u8, pub u8);

impl Rgb {
    /// The colour as a paint colour with opacity `alpha` in [0, 1].
    pub fn with_alpha(self, alpha: f32) -> tiny_skia::Color {
        let a = (alpha.clamp(0.0, 1.0) * 255.0).round() as u8;
        tiny_skia::Color::from_rgba8(self.0, self.1, self.2, a)
    }

    /// A darker shade (each channel scaled by `f` in [0, 1]), for outlines and heading lines.
    pub fn darker(self, f: f32) -> Rgb {
        let s = |c: u8| (f32::from(c) * f).round() as u8;
        Rgb(s(self.0), s(self.1), s(self.2))
    }
}

/// Outside the room: the image margin and an L room's removed block.
pub const OUTSIDE: Rgb = Rgb(196, 199, 204);
/// Room floor.
pub const FLOOR: Rgb = Rgb(250, 248, 242);
/// Walls (internal corridor walls included).
pub const WALL: Rgb = Rgb(52, 54, 60);
/// 1 m tick marks in the margin.
pub const TICK: Rgb = Rgb(110, 114, 122);
/// Tables.
pub const TABLE: Rgb = Rgb(176, 130, 84);
/// A free laptop.
pub const LAPTOP: Rgb = Rgb(128, 136, 148);
/// A laptop in use (same hue as its user).
pub const LAPTOP_IN_USE: Rgb = Rgb(255, 190, 92);
/// Plants.
pub const PLANT: Rgb = Rgb(64, 156, 72);
/// A lone human who stands still.
pub const HUMAN_STATIC: Rgb = Rgb(120, 132, 148);
/// A lone walking human.
pub const HUMAN_WALKING: Rgb = Rgb(31, 119, 180);
/// A member of a moving group.
pub const HUMAN_MOVING_GROUP: Rgb = Rgb(148, 103, 189);
/// A member of a standing group.
pub const HUMAN_STANDING_GROUP: Rgb = Rgb(214, 96, 170);
/// A human seated at a laptop.
pub const HUMAN_LAPTOP_USER: Rgb = Rgb(232, 130, 20);
/// The robot, its goal and its trail.
pub const ROBOT: Rgb = Rgb(214, 39, 40);
/// The ORCA shadow robot's outline.
pub const SHADOW: Rgb = Rgb(150, 60, 60);
/// The progress bar's track.
pub const PROGRESS_TRACK: Rgb = Rgb(160, 164, 170);
/// The progress bar's elapsed part.
pub const PROGRESS: Rgb = Rgb(52, 54, 60);

/// The colour of a human of role `r` (`state::role::*`).
pub fn human(r: u32) -> Rgb {
    match r {
        role::STATIC => HUMAN_STATIC,
        role::DYNAMIC => HUMAN_WALKING,
        role::MOVING_GROUP => HUMAN_MOVING_GROUP,
        role::STANDING_GROUP => HUMAN_STANDING_GROUP,
        _ => HUMAN_LAPTOP_USER,
    }
}
