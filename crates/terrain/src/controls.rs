//! The window's controls in one table: the window looks keys up in it, and the command line
//! prints it as help. Keys are physical (`KeyCode`), so W/A/S/D sit under the same fingers on any
//! keyboard layout.

use winit::event::MouseScrollDelta;
use winit::keyboard::KeyCode;

use crate::camera::Motion;

/// What a key does. Moving and boosting last while the key is held; the others happen once per
/// press.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// Move while held.
    Move(Motion),
    /// Faster top speed while held.
    Boost,
    /// Release the mouse, or capture it for looking around.
    ToggleMouse,
    /// Save a screenshot.
    Screenshot,
    /// Switch between full screen and a window.
    FullScreen,
    /// Show or hide the tuning panel.
    TogglePanel,
    /// Let the day run (the time of day advances) or stop it.
    ToggleDay,
    /// Quit.
    Quit,
}

/// A row of the controls table: the keys, their names as printed, and what they do.
#[derive(Clone, Copy, Debug)]
pub struct Binding {
    /// The physical keys.
    pub keys: &'static [KeyCode],
    /// The keys' names, for help text.
    pub names: &'static str,
    /// The action.
    pub action: Action,
    /// What the action does, for help text.
    pub effect: &'static str,
}

/// Every key binding (the spec's controls, plus boost, mouse release, screenshot, full screen
/// and the tuning panel).
pub const BINDINGS: &[Binding] = &[
    Binding {
        keys: &[KeyCode::KeyW],
        names: "W",
        action: Action::Move(Motion::Forward),
        effect: "forward along the view",
    },
    Binding {
        keys: &[KeyCode::KeyS],
        names: "S",
        action: Action::Move(Motion::Back),
        effect: "back along the view",
    },
    Binding {
        keys: &[KeyCode::KeyA, KeyCode::ArrowLeft],
        names: "A, Left",
        action: Action::Move(Motion::Left),
        effect: "sideways to the left",
    },
    Binding {
        keys: &[KeyCode::KeyD, KeyCode::ArrowRight],
        names: "D, Right",
        action: Action::Move(Motion::Right),
        effect: "sideways to the right",
    },
    Binding {
        keys: &[KeyCode::ArrowUp],
        names: "Up",
        action: Action::Move(Motion::Up),
        effect: "up in world y",
    },
    Binding {
        keys: &[KeyCode::ArrowDown],
        names: "Down",
        action: Action::Move(Motion::Down),
        effect: "down in world y",
    },
    Binding {
        keys: &[KeyCode::ShiftLeft, KeyCode::ShiftRight],
        names: "Shift",
        action: Action::Boost,
        effect: "faster while held",
    },
    Binding {
        keys: &[KeyCode::Tab],
        names: "Tab",
        action: Action::ToggleMouse,
        effect: "release or capture the mouse (a click captures it)",
    },
    Binding {
        keys: &[KeyCode::F12, KeyCode::KeyP],
        names: "F12, P",
        action: Action::Screenshot,
        effect: "save a screenshot (its file name is printed)",
    },
    Binding { keys: &[KeyCode::F11], names: "F11", action: Action::FullScreen, effect: "full screen" },
    Binding {
        keys: &[KeyCode::F1],
        names: "F1",
        action: Action::TogglePanel,
        effect: "show or hide the tuning panel (look, sun, fog, water, level of detail, frame times)",
    },
    Binding {
        keys: &[KeyCode::KeyT],
        names: "T",
        action: Action::ToggleDay,
        effect: "let the day run or stop it (modern look; from noon without a time of day)",
    },
    Binding { keys: &[KeyCode::Escape], names: "Esc", action: Action::Quit, effect: "quit" },
];

/// The mouse's part of the controls, for help text.
pub const MOUSE_HELP: &[(&str, &str)] = &[
    ("mouse", "look around (pitch within +-89 degrees)"),
    ("scroll wheel", "zoom (field of view 1-90 degrees)"),
];

/// Pixels of a touchpad's smooth scroll that count as one wheel line.
pub const PIXELS_PER_SCROLL_LINE: f64 = 40.0;

/// The action of a key, if it has one.
pub fn action_for(key: KeyCode) -> Option<Action> {
    BINDINGS.iter().find(|binding| binding.keys.contains(&key)).map(|binding| binding.action)
}

/// A scroll event in wheel lines: positive when the wheel turns away from the user.
pub fn scroll_lines(delta: MouseScrollDelta) -> f32 {
    match delta {
        MouseScrollDelta::LineDelta(_, y) => y,
        MouseScrollDelta::PixelDelta(position) => (position.y / PIXELS_PER_SCROLL_LINE) as f32,
    }
}

/// The controls as aligned help lines, keys first, one binding a line.
pub fn help() -> String {
    let rows = BINDINGS.iter().map(|b| (b.names, b.effect)).chain(MOUSE_HELP.iter().copied());
    let rows: Vec<(&str, &str)> = rows.collect();
    let width = rows.iter().map(|(keys, _)| keys.len()).max().unwrap_or(0);
    rows.iter().map(|(keys, effect)| format!("  {keys:<width$}  {effect}\n")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_spec_controls_are_bound() {
        let expected = [
            (KeyCode::KeyW, Action::Move(Motion::Forward)),
            (KeyCode::KeyS, Action::Move(Motion::Back)),
            (KeyCode::KeyA, Action::Move(Motion::Left)),
            (KeyCode::ArrowLeft, Action::Move(Motion::Left)),
            (KeyCode::KeyD, Action::Move(Motion::Right)),
            (KeyCode::ArrowRight, Action::Move(Motion::Right)),
            (KeyCode::ArrowUp, Action::Move(Motion::Up)),
            (KeyCode::ArrowDown, Action::Move(Motion::Down)),
            (KeyCode::Escape, Action::Quit),
            (KeyCode::Tab, Action::ToggleMouse),
            (KeyCode::F12, Action::Screenshot),
            (KeyCode::KeyP, Action::Screenshot),
            (KeyCode::F1, Action::TogglePanel),
            (KeyCode::KeyT, Action::ToggleDay),
        ];
        for (key, action) in expected {
            assert_eq!(action_for(key), Some(action), "{key:?}");
        }
        assert_eq!(action_for(KeyCode::KeyQ), None);
    }

    #[test]
    fn no_key_is_bound_twice() {
        let keys: Vec<KeyCode> = BINDINGS.iter().flat_map(|b| b.keys.iter().copied()).collect();
        for (i, key) in keys.iter().enumerate() {
            assert!(!keys[..i].contains(key), "{key:?} is bound twice");
        }
    }

    #[test]
    fn scrolling_counts_lines_and_smooth_pixels() {
        assert_eq!(scroll_lines(MouseScrollDelta::LineDelta(0.0, 2.0)), 2.0);
        let smooth = winit::dpi::PhysicalPosition::new(0.0, -2.0 * PIXELS_PER_SCROLL_LINE);
        assert_eq!(scroll_lines(MouseScrollDelta::PixelDelta(smooth)), -2.0);
    }

    #[test]
    fn help_lists_every_binding_aligned() {
        let text = help();
        assert_eq!(text.lines().count(), BINDINGS.len() + MOUSE_HELP.len());
        for b in BINDINGS {
            assert!(text.contains(b.names) && text.contains(b.effect), "{}", b.names);
        }
        let rows = BINDINGS.iter().map(|b| b.effect).chain(MOUSE_HELP.iter().map(|(_, effect)| *effect));
        // Every effect starts in the same column.
        let columns: Vec<usize> =
            text.lines().zip(rows).map(|(line, effect)| line.len() - effect.len()).collect();
        assert!(columns.windows(2).all(|w| w[0] == w[1]), "{text}");
    }
}
