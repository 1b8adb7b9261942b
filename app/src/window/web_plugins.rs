//! The page's Bevy plugins (wasm32 with the `web` feature): `DefaultPlugins` as the
//! `window` feature's Bevy parts make it, with one change. Bevy's `LogPlugin` filters by
//! `EnvFilter`, whose regular-expression engine and Unicode tables are a tenth of a
//! megabyte gzipped in the page's download, for a filter a page has no environment to
//! read; the page's logger sends warnings and errors (nothing below is compiled into
//! the page) straight to the browser's console. A plugin group disabled with
//! `PluginGroupBuilder::disable` would still be linked: the list is written out here, in
//! `DefaultPlugins`' order.

use bevy::app::PluginGroupBuilder;
use bevy::log::tracing_subscriber::{Registry, layer::SubscriberExt};
use bevy::prelude::*;

/// The page's plugins (set its `WindowPlugin` to the page's canvas, as with
/// `DefaultPlugins`).
pub struct WebPlugins;

impl PluginGroup for WebPlugins {
    fn build(self) -> PluginGroupBuilder {
        PluginGroupBuilder::start::<Self>()
            .add(bevy::app::PanicHandlerPlugin)
            .add(ConsoleLogPlugin)
            .add(bevy::app::TaskPoolPlugin::default())
            .add(bevy::diagnostic::FrameCountPlugin)
            .add(bevy::time::TimePlugin)
            .add(bevy::transform::TransformPlugin)
            .add(bevy::diagnostic::DiagnosticsPlugin)
            .add(bevy::input::InputPlugin)
            .add(WindowPlugin::default())
            .add(bevy::a11y::AccessibilityPlugin)
            .add(bevy::asset::AssetPlugin::default())
            .add(bevy::winit::WinitPlugin::default())
            .add(bevy::render::RenderPlugin::default())
            .add(bevy::image::ImagePlugin::default())
            .add(bevy::mesh::MeshPlugin)
            .add(bevy::camera::CameraPlugin)
            .add(bevy::core_pipeline::CorePipelinePlugin)
            .add(bevy::sprite::SpritePlugin)
            .add(bevy::sprite_render::SpriteRenderPlugin)
            .add(bevy::gizmos::GizmoPlugin)
            .add(bevy::gizmos_render::GizmoRenderPlugin)
    }
}

/// Warnings and errors to the browser's console, from `tracing` and from `log` (which
/// wgpu writes to).
struct ConsoleLogPlugin;

impl Plugin for ConsoleLogPlugin {
    fn build(&self, _app: &mut App) {
        let console = tracing_wasm::WASMLayer::new(
            tracing_wasm::WASMLayerConfigBuilder::new()
                .set_max_level(bevy::log::Level::WARN)
                .build(),
        );
        // A second app in the same page keeps the first one's logger.
        let _ = tracing_log::LogTracer::init();
        let _ =
            bevy::log::tracing::subscriber::set_global_default(Registry::default().with(console));
    }
}
