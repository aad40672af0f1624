//! What a person's input means to the robot: keys held and gamepad sticks mapped to socnav's
//! actions. Pure functions, so the mappings are tested without a keyboard or a gamepad.
//!
//! Keyboard (arrow keys or WASD; Q/E strafe a holonomic robot):
//! - continuous: forward = up − down, lateral = Q − E (0 for a differential-drive robot),
//!   rotation = left − right, each in {−1, 0, 1} of the action's range;
//! - discrete (0.1.1's `DiscreteActions`, docs/spec.md 9.1): left alone 0 (turn left), right alone
//!   1 (turn right), up + left 2, up + right 3, up 4 (forward), down 5 (backward), nothing 6
//!   (stop).
//!
//! Gamepad, as 0.1.1's `manual_control_js.py` reads a joystick (docs/spec.md 9.2): forward from the
//! left stick's vertical axis, lateral from its horizontal axis (0 for a differential-drive robot),
//! rotation from the right stick's horizontal axis, each pushed left or up meaning positive
//! (counter-clockwise rotation, leftward strafe), after a dead zone. Its buttons command the
//! viewer ([`gamepad_command`]): Start pauses, Select restarts, South (A / cross) steps once,
//! the right and left bumpers play faster and slower.

/// A key or button press that commands the viewer rather than the robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Command {
    /// Escape: close.
    Quit,
    /// R: restart (the next episode).
    Restart,
    /// Space: pause or resume.
    Pause,
    /// N or `.`: one step while paused.
    Step,
    /// `+` or `=`: twice as fast.
    Faster,
    /// `-`: half as fast.
    Slower,
}

/// The direction keys held down.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Held {
    /// Up arrow or W.
    pub forward: bool,
    /// Down arrow or S.
    pub back: bool,
    /// Left arrow or A.
    pub left: bool,
    /// Right arrow or D.
    pub right: bool,
    /// Q: strafe left (holonomic robots).
    pub strafe_left: bool,
    /// E: strafe right (holonomic robots).
    pub strafe_right: bool,
}

fn axis(positive: bool, negative: bool) -> f32 {
    f32::from(u8::from(positive)) - f32::from(u8::from(negative))
}

/// The continuous action `[forward, lateral, rotation]` (each in [−1, 1]) of the keys held.
pub fn keyboard_action(held: Held, holonomic: bool) -> [f32; 3] {
    let lateral = if holonomic {
        axis(held.strafe_left, held.strafe_right)
    } else {
        0.0
    };
    [
        axis(held.forward, held.back),
        lateral,
        axis(held.left, held.right),
    ]
}

/// The discrete action (0..7, see the module docs) of the keys held.
pub fn keyboard_discrete(held: Held) -> u32 {
    let turn = axis(held.left, held.right);
    let drive = axis(held.forward, held.back);
    match (drive, turn) {
        (d, t) if d > 0.0 && t > 0.0 => 2,
        (d, t) if d > 0.0 && t < 0.0 => 3,
        (d, _) if d > 0.0 => 4,
        (d, _) if d < 0.0 => 5,
        (_, t) if t > 0.0 => 0,
        (_, t) if t < 0.0 => 1,
        _ => 6,
    }
}

/// The continuous action of a discrete one ([`crate::spec::DISCRETE_ACTIONS`]; stop for an
/// out-of-range one), for display and recording.
pub fn discrete_to_continuous(action: u32) -> [f32; 3] {
    let stop = crate::spec::DISCRETE_ACTIONS[6];
    crate::spec::DISCRETE_ACTIONS
        .get(action as usize)
        .copied()
        .unwrap_or(stop)
}

/// A gamepad's sticks, each axis in [−1, 1] with up and right positive (as gilrs reports them).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Sticks {
    /// Left stick, horizontal.
    pub left_x: f32,
    /// Left stick, vertical.
    pub left_y: f32,
    /// Right stick, horizontal.
    pub right_x: f32,
}

/// The default dead zone: stick deflections below this fraction of the range count as 0 (worn
/// sticks rest a few percent off centre).
pub const DEAD_ZONE: f32 = 0.15;

/// `v` with the dead zone cut out and the rest stretched back to [−1, 1], so the action grows
/// from 0 at the zone's edge; non-finite input is 0.
pub fn dead_zone(v: f32, zone: f32) -> f32 {
    if !v.is_finite() || v.abs() <= zone {
        return 0.0;
    }
    let zone = zone.clamp(0.0, 0.99);
    (v.signum() * (v.abs().min(1.0) - zone) / (1.0 - zone)).clamp(-1.0, 1.0)
}

/// The continuous action of the sticks (see the module docs).
pub fn gamepad_action(s: Sticks, zone: f32, holonomic: bool) -> [f32; 3] {
    let lateral = if holonomic {
        -dead_zone(s.left_x, zone)
    } else {
        0.0
    };
    [
        dead_zone(s.left_y, zone),
        lateral,
        -dead_zone(s.right_x, zone),
    ]
}

/// The gamepad buttons the viewer reads (gilrs's names; the `gamepad` feature maps gilrs's
/// events to these).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PadButton {
    /// Start (menu).
    Start,
    /// Select (back, view).
    Select,
    /// The bottom face button (A, cross).
    South,
    /// The right bumper (R1, RB).
    RightBumper,
    /// The left bumper (L1, LB).
    LeftBumper,
    /// Any other button.
    Other,
}

/// The viewer command of a gamepad button, if it has one (see the module docs).
pub fn gamepad_command(button: PadButton) -> Option<Command> {
    match button {
        PadButton::Start => Some(Command::Pause),
        PadButton::Select => Some(Command::Restart),
        PadButton::South => Some(Command::Step),
        PadButton::RightBumper => Some(Command::Faster),
        PadButton::LeftBumper => Some(Command::Slower),
        PadButton::Other => None,
    }
}

/// The keys a continuous action stands for (a component beyond ±0.5 holds its key), so a gamepad
/// can drive with the discrete actions too.
pub fn held_of(action: [f32; 3]) -> Held {
    Held {
        forward: action[0] > 0.5,
        back: action[0] < -0.5,
        left: action[2] > 0.5,
        right: action[2] < -0.5,
        strafe_left: action[1] > 0.5,
        strafe_right: action[1] < -0.5,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn held(f: bool, b: bool, l: bool, r: bool) -> Held {
        Held {
            forward: f,
            back: b,
            left: l,
            right: r,
            ..Held::default()
        }
    }

    #[test]
    fn keys_give_the_continuous_action() {
        assert_eq!(
            keyboard_action(held(true, false, true, false), false),
            [1.0, 0.0, 1.0]
        );
        assert_eq!(
            keyboard_action(held(false, true, false, true), false),
            [-1.0, 0.0, -1.0]
        );
        // Opposite keys cancel.
        assert_eq!(
            keyboard_action(held(true, true, true, true), false),
            [0.0, 0.0, 0.0]
        );
        let strafe = Held {
            strafe_left: true,
            ..Held::default()
        };
        assert_eq!(keyboard_action(strafe, true), [0.0, 1.0, 0.0]);
        assert_eq!(keyboard_action(strafe, false), [0.0, 0.0, 0.0]);
    }

    #[test]
    fn keys_give_0_1_1s_discrete_actions() {
        let cases = [
            (held(false, false, true, false), 0),
            (held(false, false, false, true), 1),
            (held(true, false, true, false), 2),
            (held(true, false, false, true), 3),
            (held(true, false, false, false), 4),
            (held(false, true, false, false), 5),
            (held(false, false, false, false), 6),
            (held(false, false, true, true), 6),
        ];
        for (h, want) in cases {
            assert_eq!(keyboard_discrete(h), want, "{h:?}");
            // The discrete action means what the continuous keys would (driving wins over a
            // turn for backward, as 0.1.1 has no backward turns).
            let c = discrete_to_continuous(want);
            assert_eq!(c[0], keyboard_action(h, false)[0], "{h:?}");
        }
    }

    #[test]
    fn sticks_map_as_0_1_1s_joystick_script() {
        // Left stick up: forward; left: strafe left (holonomic only); right stick left: turn left.
        let s = Sticks {
            left_x: -1.0,
            left_y: 1.0,
            right_x: -1.0,
        };
        assert_eq!(gamepad_action(s, DEAD_ZONE, true), [1.0, 1.0, 1.0]);
        assert_eq!(gamepad_action(s, DEAD_ZONE, false), [1.0, 0.0, 1.0]);
        // Inside the dead zone nothing moves; outside it the action grows from 0.
        let rest = Sticks {
            left_x: 0.1,
            left_y: -0.14,
            right_x: 0.05,
        };
        assert_eq!(gamepad_action(rest, DEAD_ZONE, true), [0.0, 0.0, 0.0]);
        assert_eq!(dead_zone(0.15, 0.15), 0.0);
        assert!((dead_zone(0.575, 0.15) - 0.5).abs() < 1e-6);
        assert!((dead_zone(-0.575, 0.15) + 0.5).abs() < 1e-6);
        assert_eq!(dead_zone(1.7, 0.15), 1.0);
        assert_eq!(dead_zone(f32::NAN, 0.15), 0.0);
    }

    #[test]
    fn buttons_command_the_viewer() {
        assert_eq!(gamepad_command(PadButton::Start), Some(Command::Pause));
        assert_eq!(gamepad_command(PadButton::Select), Some(Command::Restart));
        assert_eq!(gamepad_command(PadButton::South), Some(Command::Step));
        assert_eq!(
            gamepad_command(PadButton::RightBumper),
            Some(Command::Faster)
        );
        assert_eq!(
            gamepad_command(PadButton::LeftBumper),
            Some(Command::Slower)
        );
        assert_eq!(gamepad_command(PadButton::Other), None);
        // A stick pushed up and right drives the discrete "forward + right" (3).
        let a = gamepad_action(
            Sticks {
                left_x: 0.0,
                left_y: 0.9,
                right_x: 0.9,
            },
            DEAD_ZONE,
            false,
        );
        assert_eq!(keyboard_discrete(held_of(a)), 3);
    }
}
