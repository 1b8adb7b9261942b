//! An opt-in screenshot for scripted checks: with `STRANDS_SCREENSHOT=path.png` set,
//! the app saves a screenshot of its window after `STRANDS_SCREENSHOT_FRAME` frames
//! (default 90) through Bevy's screenshot API and exits. If the screenshot has not been
//! written `STRANDS_SCREENSHOT_TIMEOUT` frames later (default 900), the app exits with
//! an error, so a script can never hang.

use std::path::PathBuf;

use bevy::diagnostic::FrameCount;
use bevy::prelude::*;
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured, save_to_disk};

/// The screenshot request read from the environment.
#[derive(Resource, Clone, Debug)]
struct ScreenshotRequest {
    path: PathBuf,
    frame: u32,
    timeout: u32,
}

/// Screenshot-and-exit, when asked for by the environment.
pub struct ScreenshotPlugin;

impl Plugin for ScreenshotPlugin {
    fn build(&self, app: &mut App) {
        let Ok(path) = std::env::var("STRANDS_SCREENSHOT") else {
            return;
        };
        let number = |name: &str, default: u32| {
            std::env::var(name)
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(default)
        };
        let frame = number("STRANDS_SCREENSHOT_FRAME", 90);
        app.insert_resource(ScreenshotRequest {
            path: PathBuf::from(path),
            frame,
            timeout: frame + number("STRANDS_SCREENSHOT_TIMEOUT", 900),
        })
        .add_systems(Update, take_screenshot);
    }
}

fn take_screenshot(
    mut commands: Commands,
    frames: Res<FrameCount>,
    request: Res<ScreenshotRequest>,
    mut exit: MessageWriter<AppExit>,
) {
    if frames.0 == request.frame {
        info!(
            "bevy_strands: taking a screenshot to {}",
            request.path.display()
        );
        commands
            .spawn(Screenshot::primary_window())
            .observe(save_to_disk(request.path.clone()))
            .observe(
                |_: On<ScreenshotCaptured>, mut exit: MessageWriter<AppExit>| {
                    exit.write(AppExit::Success);
                },
            );
    } else if frames.0 > request.timeout {
        error!("bevy_strands: the screenshot was not captured in time");
        exit.write(AppExit::error());
    }
}
