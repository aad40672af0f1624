//! Gamepads (feature `gamepad`: gilrs, which reads Linux's evdev devices and needs libudev's
//! headers to build, `apt-get install libudev-dev`): the first connected pad's sticks and button
//! presses, mapped by [`super::controls`].

use gilrs::{Axis, Button, EventType, Gilrs};

use super::controls::{Command, PadButton, Sticks, gamepad_command};

/// What the pads did since the last poll.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PadInput {
    /// The sticks of the first connected pad; `None` when no pad is connected.
    pub sticks: Option<Sticks>,
    /// Viewer commands from button presses, in order.
    pub commands: Vec<Command>,
}

/// The gamepads of this machine.
pub struct Pads {
    gilrs: Gilrs,
}

impl std::fmt::Debug for Pads {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Pads").finish_non_exhaustive()
    }
}

fn pad_button(b: Button) -> PadButton {
    match b {
        Button::Start => PadButton::Start,
        Button::Select => PadButton::Select,
        Button::South => PadButton::South,
        Button::RightTrigger => PadButton::RightBumper,
        Button::LeftTrigger => PadButton::LeftBumper,
        _ => PadButton::Other,
    }
}

impl Pads {
    /// The gamepad subsystem, or why it is unavailable (the viewer then drives by keyboard only).
    ///
    /// # Errors
    /// A message saying why gilrs could not start.
    pub fn open() -> Result<Self, String> {
        Gilrs::new()
            .map(|gilrs| Self { gilrs })
            .map_err(|e| format!("gamepads unavailable: {e}"))
    }

    /// The sticks of the first connected pad and the commands pressed since the last call.
    pub fn poll(&mut self) -> PadInput {
        let mut commands = Vec::new();
        while let Some(event) = self.gilrs.next_event() {
            if let EventType::ButtonPressed(b, _) = event.event {
                commands.extend(gamepad_command(pad_button(b)));
            }
        }
        let sticks = self.gilrs.gamepads().next().map(|(_, pad)| Sticks {
            left_x: pad.value(Axis::LeftStickX),
            left_y: pad.value(Axis::LeftStickY),
            right_x: pad.value(Axis::RightStickX),
        });
        PadInput { sticks, commands }
    }
}
