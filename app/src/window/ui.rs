//! The egui panel of the desktop demos (feature `render`): run, pause, step, reset; the
//! step, forces, solver and collision settings; live figures and a plot of the length
//! error. What its buttons do lives in [`super::controls`], shared with the web page.

use std::ops::DerefMut;

use bevy::ecs::system::SystemParam;
use bevy::prelude::*;
use bevy_egui::{EguiContexts, EguiPlugin, EguiPrimaryContextPass, egui};
use egui_plot::{Line, Plot, PlotPoints};

use bevy_strands::metrics::LengthErrorHistory;
use bevy_strands::prelude::*;
use bevy_strands::render::DrawSettings;
use bevy_strands::world::clock::StepTiming;

use super::command::{DT_RANGE, SUBSTEPS_RANGE};
use super::controls::{FrameExport, UiKeys, reset, switch_scenario};
use super::layout::UiLayout;
use super::pace::RealTimeFactor;
use super::tools::{Tool, ToolState};
use super::{ActiveScenario, ScenarioMenu};

/// The egui panel, added by [`super::StrandsUiPlugin`] when the `render` feature is on.
pub(super) struct PanelPlugin;

impl Plugin for PanelPlugin {
    fn build(&self, app: &mut App) {
        if !app.is_plugin_added::<EguiPlugin>() {
            app.add_plugins(EguiPlugin::default());
        }
        app.add_systems(EguiPrimaryContextPass, (use_embedded_font, panel).chain());
    }
}

/// The settings the panel edits.
#[derive(SystemParam)]
struct Settings<'w> {
    step: ResMut<'w, StrandsConfig>,
    constraints: ResMut<'w, ConstraintConfig>,
    collisions: ResMut<'w, CollisionConfig>,
    draw: ResMut<'w, DrawSettings>,
}

/// The figures the panel shows.
#[derive(SystemParam)]
struct Figures<'w> {
    metrics: Res<'w, StrandMetrics>,
    clock: Res<'w, SimulationClock>,
    history: Res<'w, LengthErrorHistory>,
    timing: Res<'w, StepTiming>,
    rate: Option<Res<'w, RealTimeFactor>>,
    problems: Res<'w, InputProblems>,
    active: Option<Res<'w, ActiveScenario>>,
    menu: Option<Res<'w, ScenarioMenu>>,
    export: Res<'w, FrameExport>,
}

/// Edit a copy and write it back only if it changed, so that a frame in which nothing
/// was touched does not look like a configuration change (which rebuilds caches).
fn edit<T: Clone + PartialEq, R: DerefMut<Target = T>>(value: &mut R, change: impl FnOnce(&mut T)) {
    let mut copy = T::clone(value);
    change(&mut copy);
    if copy != **value {
        **value = copy;
    }
}

/// The panel's one font: the DejaVu Sans Mono the exporters embed, in place of egui's
/// four default fonts (1.4 MB, most of it emoji the panel never shows), for both of
/// egui's families. Its labels keep to the glyphs it has.
fn use_embedded_font(mut contexts: EguiContexts, mut done: Local<bool>) -> Result {
    if *done {
        return Ok(());
    }
    let mut fonts = egui::FontDefinitions::empty();
    fonts.font_data.insert(
        "DejaVuSansMono".to_owned(),
        std::sync::Arc::new(egui::FontData::from_static(crate::export::text::FONT)),
    );
    for family in [egui::FontFamily::Proportional, egui::FontFamily::Monospace] {
        fonts
            .families
            .insert(family, vec!["DejaVuSansMono".to_owned()]);
    }
    contexts.ctx_mut()?.set_fonts(fonts);
    *done = true;
    Ok(())
}

fn panel(
    mut contexts: EguiContexts,
    mut settings: Settings,
    figures: Figures,
    mut tools: ResMut<ToolState>,
    keys: Res<UiKeys>,
    mut layout: ResMut<UiLayout>,
    mut commands: Commands,
) -> Result {
    let ctx = contexts.ctx_mut()?;
    let title = figures
        .active
        .as_ref()
        .map_or("bevy_strands".to_string(), |a| {
            format!("bevy_strands — {}", a.scenario.name)
        });
    let height = ctx.content_rect().height() - 60.0;
    let response = egui::Window::new(title)
        .anchor(egui::Align2::RIGHT_TOP, [-8.0, 8.0])
        // egui's default window height is 420: take the screen's instead.
        .default_size([330.0, height])
        .resizable(false)
        .collapsible(true)
        .vscroll(true)
        .max_height(height)
        .show(ctx, |ui| {
            if let (Some(menu), Some(active)) = (&figures.menu, &figures.active) {
                scenario_menu(ui, menu, &active.scenario.name, &mut commands);
            }
            controls(ui, &mut settings, &mut commands);
            ui.separator();
            figures_ui(ui, &figures, &settings);
            ui.separator();
            tools_ui(ui, &mut tools);
            let help = keys.help();
            if !help.is_empty() {
                ui.small(help);
            }
            ui.separator();
            egui::CollapsingHeader::new("solver, collisions, drawing")
                .default_open(true)
                .show(ui, |ui| solver_ui(ui, &mut settings));
        });
    let panel = response.map(|r| r.response.rect);
    layout.panel_width = panel.map_or(0.0, |r| ctx.content_rect().right() - r.left());
    layout.panel_rect = panel.map(|r| Rect::new(r.left(), r.top(), r.right(), r.bottom()));
    layout.pointer_busy = ctx.egui_is_using_pointer();
    layout.keyboard_over_ui = ctx.egui_wants_keyboard_input();
    Ok(())
}

/// Switch to another scenario: it replaces the active one and the scene restarts.
fn scenario_menu(ui: &mut egui::Ui, menu: &ScenarioMenu, current: &str, commands: &mut Commands) {
    let mut chosen = current.to_string();
    egui::ComboBox::from_label("scene")
        .selected_text(current)
        .show_ui(ui, |ui| {
            for name in &menu.names {
                ui.selectable_value(&mut chosen, name.clone(), name);
            }
        });
    if chosen != current {
        commands.queue(move |world: &mut World| {
            if let Err(e) = switch_scenario(world, &chosen) {
                error!("bevy_strands: {e}");
            }
        });
    }
}

fn controls(ui: &mut egui::Ui, settings: &mut Settings, commands: &mut Commands) {
    ui.horizontal(|ui| {
        let paused = settings.step.paused;
        if ui
            .button(if paused { "▶ run" } else { "❚❚ pause" })
            .clicked()
        {
            settings.step.paused = !paused;
        }
        if ui.button("step").on_hover_text("one tick").clicked() {
            settings.step.paused = true;
            commands.queue(|world: &mut World| world.run_schedule(StrandsTick));
        }
        if ui.button("reset").clicked() {
            commands.queue(reset);
        }
    });
    edit(&mut settings.step, |step| {
        ui.horizontal(|ui| {
            ui.label("dt");
            ui.add(
                egui::DragValue::new(&mut step.dt)
                    .range(DT_RANGE)
                    .speed(1e-5)
                    .custom_formatter(|v, _| format!("1/{:.0} s", 1.0 / v)),
            );
            ui.label("substeps");
            ui.add(egui::DragValue::new(&mut step.substeps).range(SUBSTEPS_RANGE));
        });
        ui.add(egui::Slider::new(&mut step.gravity.y, -30.0..=0.0).text("gravity y"));
        ui.add(egui::Slider::new(&mut step.damping, 0.0..=5.0).text("damping"));
        ui.checkbox(&mut step.sleep.enabled, "strands at rest sleep");
    });
}

fn figures_ui(ui: &mut egui::Ui, figures: &Figures, settings: &Settings) {
    let m = &figures.metrics;
    let per_step_ms =
        1000.0 * figures.timing.last_tick_seconds / settings.step.substeps.max(1) as f64;
    egui::Grid::new("figures").num_columns(2).show(ui, |ui| {
        let mut row = |name: &str, value: String| {
            ui.label(name);
            ui.monospace(value);
            ui.end_row();
        };
        row(
            "time",
            format!(
                "{:.2} s ({} steps)",
                figures.clock.time, figures.clock.steps
            ),
        );
        row(
            "particles / strands",
            format!("{} / {}", m.particles, m.strands),
        );
        row(
            "edges (constrained)",
            format!("{} ({})", m.edges, m.constrained_edges),
        );
        row(
            "max |l−L|/L now",
            format!("{:.2e}", m.max_rel_length_error_now),
        );
        row(
            "max |l−L|/L ever",
            format!("{:.2e}", m.max_rel_length_error),
        );
        row(
            "… away from contact",
            format!("{:.2e}", m.max_rel_length_error_free),
        );
        row(
            "edge crossings",
            m.edge_crossings
                .map_or("not checked".into(), |c| c.to_string()),
        );
        row("impulses / step", format!("{}", m.collisions_last_step));
        row("fail-safe steps", format!("{}", m.failsafe_steps));
        row(
            "asleep",
            format!("{} of {} particles", m.asleep_particles, m.particles),
        );
        row("ms / step", format!("{per_step_ms:.3}"));
        row(
            "real-time factor",
            (figures.rate.as_ref().and_then(|r| r.value))
                .map_or("measuring".into(), |r| format!("{r:.2}")),
        );
    });
    // The length error over time, log scale.
    let points: PlotPoints = figures
        .history
        .samples
        .iter()
        .map(|s| [s.time, s.all.max(1e-17).log10()])
        .collect();
    Plot::new("length_error")
        .height(120.0)
        .allow_scroll(false)
        .allow_drag(false)
        .y_axis_formatter(|mark, _| format!("1e{:.0}", mark.value))
        .show(ui, |plot| plot.line(Line::new("max |l−L|/L", points)));
    if let Some(problem) = figures.problems.entries.last() {
        ui.colored_label(
            egui::Color32::LIGHT_RED,
            format!("{}: {}", problem.entity, problem.problem),
        );
    }
    if figures.export.recording() {
        ui.colored_label(
            egui::Color32::LIGHT_GREEN,
            format!("recording frames to {}", figures.export.directory.display()),
        );
    }
    if let Some(message) = &figures.export.message {
        ui.colored_label(egui::Color32::LIGHT_RED, message);
    }
}

fn tools_ui(ui: &mut egui::Ui, tools: &mut ToolState) {
    ui.horizontal_wrapped(|ui| {
        ui.label("tool");
        for tool in Tool::ALL {
            ui.selectable_value(&mut tools.tool, tool, tool.label());
        }
    });
    if tools.tool == Tool::Hair {
        ui.add(egui::Slider::new(&mut tools.hair_spacing, 0.005..=0.05).text("hair spacing"));
    }
    if let Some(message) = &tools.message {
        ui.colored_label(egui::Color32::LIGHT_RED, message);
    }
}

fn solver_ui(ui: &mut egui::Ui, settings: &mut Settings) {
    edit(&mut settings.constraints, |c| {
        egui::ComboBox::from_label("solver")
            .selected_text(c.solver.name())
            .show_ui(ui, |ui| {
                for kind in SolverKind::ALL {
                    ui.selectable_value(&mut c.solver, kind, kind.name());
                }
            });
        ui.add(
            egui::Slider::new(&mut c.tolerance, 1e-14..=1e-3)
                .logarithmic(true)
                .custom_formatter(|v, _| format!("{v:.0e}"))
                .text("tolerance"),
        );
        ui.add(egui::Slider::new(&mut c.max_iterations, 1..=50).text("iteration cap"));
    });
    edit(&mut settings.collisions, |c| {
        ui.checkbox(&mut c.enabled, "collisions");
        ui.add(
            egui::Slider::new(&mut c.thickness, 0.0005..=0.02)
                .logarithmic(true)
                .text("thickness"),
        );
        ui.add(egui::Slider::new(&mut c.friction, 0.0..=1.5).text("friction"));
        ui.add(egui::Slider::new(&mut c.restitution, 0.0..=1.0).text("restitution"));
        ui.checkbox(&mut c.check_crossings, "check crossings every step");
    });
    edit(&mut settings.draw, |d| {
        ui.checkbox(&mut d.color_by_error, "colour edges by length error");
        ui.checkbox(&mut d.show_sleep, "dim sleeping strands");
        ui.checkbox(
            &mut d.particles,
            format!("draw particles (up to {})", d.max_particle_dots),
        );
    });
}

#[cfg(test)]
mod tests {
    use ab_glyph::Font;

    /// The characters inside the string literals of `source` (comments skipped).
    fn literal_chars(source: &str) -> Vec<char> {
        let (mut found, mut chars) = (Vec::new(), source.chars().peekable());
        let mut in_string = false;
        while let Some(c) = chars.next() {
            match (in_string, c) {
                (true, '\\') => {
                    chars.next();
                }
                (true, '"') => in_string = false,
                (true, c) => found.push(c),
                (false, '"') => in_string = true,
                (false, '/') if chars.peek() == Some(&'/') => {
                    for c in chars.by_ref() {
                        if c == '\n' {
                            break;
                        }
                    }
                }
                // A character literal ('"' among them); a lifetime's quote stands alone.
                (false, '\'') => {
                    let mut ahead = chars.clone();
                    let first = ahead.next();
                    if first == Some('\\') {
                        ahead.next();
                    }
                    if ahead.next() == Some('\'') {
                        chars = ahead;
                    }
                }
                _ => {}
            }
        }
        found
    }

    /// egui draws a box for a character its font lacks: every character the panel's
    /// labels, tool names and menus are written with has a glyph in the one font.
    #[test]
    fn the_panel_font_has_a_glyph_for_every_character_its_labels_use() {
        let font = crate::export::text::font();
        let sources = [
            include_str!("ui.rs"),
            include_str!("controls.rs"),
            include_str!("tools.rs"),
            include_str!("mod.rs"),
        ];
        // The code above each file's tests (these tests write missing glyphs on purpose).
        let used: Vec<char> = (sources.iter())
            .flat_map(|s| literal_chars(s.split("#[cfg(test)]").next().unwrap_or(s)))
            .collect();
        // The scan finds the labels' own marks (so that it cannot pass by finding none).
        for mark in ['▶', '·', '−'] {
            assert!(used.contains(&mark), "{mark} not found in the labels");
        }
        let missing: Vec<char> = (used.iter().copied())
            .filter(|&c| !c.is_ascii_control() && font.glyph_id(c).0 == 0)
            .collect();
        assert!(missing.is_empty(), "no glyph for {missing:?}");
        // The scan itself: an escaped quote, a comment, a quote as a character, a lifetime.
        let sample = "let a = \"x\\\"ℓ\"; // \"⏸\"\nlet c = '\"'; let b: &'static str = \"·\";";
        assert_eq!(literal_chars(sample), ['x', 'ℓ', '·']);
    }
}
