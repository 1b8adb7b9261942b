//! Where the panel is on screen, shared by the camera fit, the tools and the panel.

use bevy::prelude::*;

/// Where the panel is, so the camera keeps the scene beside it and the tools ignore
/// clicks on it.
#[derive(Resource, Debug, Default)]
pub struct UiLayout {
    /// Width of the panel at the right edge, in logical pixels.
    pub panel_width: f32,
    /// The panel's rectangle in logical window pixels (y down), if shown.
    pub panel_rect: Option<Rect>,
    /// Whether an egui widget is being dragged or clicked (as of the last egui pass).
    pub pointer_busy: bool,
    /// Whether egui wants the keyboard this frame.
    pub keyboard_over_ui: bool,
}

impl UiLayout {
    /// Whether the pointer at `cursor` (logical window pixels) belongs to the panel.
    /// The rectangle test uses the cursor now, so a press just after leaving the panel
    /// is the scene's.
    pub fn owns_pointer(&self, cursor: Vec2) -> bool {
        self.pointer_busy || self.panel_rect.is_some_and(|r| r.contains(cursor))
    }
}
