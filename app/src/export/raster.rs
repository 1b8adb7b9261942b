//! Drawing a frame of the simulation on the CPU: edges as lines in their kind's
//! colours, pinned particles as red dots, bodies as discs, the figures as text.

use bevy::math::DVec2;
use tiny_skia::{Color, FillRule, LineCap, Paint, PathBuilder, Pixmap, Stroke, Transform};

use bevy_strands::model::Edge;
use bevy_strands::world::strand::StrandKind;
use bevy_strands::world::topology::StrandRecord;

use super::text::draw_text;

/// The rectangle of the world a frame shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Lower-left corner (world units).
    pub min: DVec2,
    /// Upper-right corner (world units).
    pub max: DVec2,
}

impl View {
    /// The view's scale and offset for an image `width × height` pixels: the world
    /// rectangle fitted inside with a margin, y pointing up.
    fn fit(&self, width: f32, height: f32) -> (f32, DVec2) {
        let size = self.max - self.min;
        let margin = 0.04 * width.min(height);
        let scale =
            ((width - 2.0 * margin) / size.x as f32).min((height - 2.0 * margin) / size.y as f32);
        (scale, self.min)
    }
}

/// What a frame shows.
#[derive(Clone, Copy, Debug)]
pub struct FrameContent<'a> {
    /// Packed positions.
    pub position: &'a [DVec2],
    /// Which packed particles are pinned (sleeping ones not: they are drawn dimmed).
    pub pinned: &'a [bool],
    /// Which packed particles sleep.
    pub asleep: &'a [bool],
    /// All edges.
    pub edges: &'a [Edge],
    /// All strands (for their kinds).
    pub strands: &'a [StrandRecord],
    /// Discs to draw under the strands (centre, radius): bodies of furry creatures.
    pub discs: &'a [(DVec2, f64)],
    /// Collision thickness, for the stroke width.
    pub thickness: f64,
    /// Lines of text in the top-left corner.
    pub caption: &'a [String],
}

/// Background colour.
pub const BACKGROUND: [u8; 3] = [18, 18, 22];

/// Sleeping strands: a dim slate blue, as in the debug drawing.
pub const SLEEPING: [u8; 3] = [82, 97, 133];

fn paint(color: [u8; 3]) -> Paint<'static> {
    let mut paint = Paint::default();
    paint.set_color(Color::from_rgba8(color[0], color[1], color[2], 255));
    paint.anti_alias = true;
    paint
}

/// Draw `content` seen through `view` into `pixmap`.
pub fn draw_frame(pixmap: &mut Pixmap, view: &View, content: &FrameContent) {
    let (width, height) = (pixmap.width() as f32, pixmap.height() as f32);
    pixmap.fill(Color::from_rgba8(
        BACKGROUND[0],
        BACKGROUND[1],
        BACKGROUND[2],
        255,
    ));
    // A band at the top for the caption, so that text never covers the scene.
    let text_size = (height / 32.0).clamp(10.0, 22.0);
    let band = if content.caption.is_empty() {
        0.0
    } else {
        text_size * (1.25 * content.caption.len() as f32 + 0.6)
    };
    let (scale, origin) = view.fit(width, height - band);
    let size = (view.max - view.min).as_vec2() * scale;
    let offset = ((width - size.x) / 2.0, (height - band - size.y) / 2.0);
    let to_pixel = |p: DVec2| {
        let q = (p - origin).as_vec2() * scale;
        (offset.0 + q.x, height - offset.1 - q.y)
    };

    for &(centre, radius) in content.discs {
        let (x, y) = to_pixel(centre);
        if let Some(circle) = PathBuilder::from_circle(x, y, radius as f32 * scale) {
            pixmap.fill_path(
                &circle,
                &paint([70, 60, 90]),
                FillRule::Winding,
                Transform::identity(),
                None,
            );
        }
    }

    let sleeps = |i: u32| content.asleep.get(i as usize).copied().unwrap_or(false);
    let stroke = Stroke {
        width: (2.0 * content.thickness as f32 * scale).clamp(1.0, 4.0),
        line_cap: LineCap::Round,
        ..Stroke::default()
    };
    // One path per strand kind, walls first so strands draw over them.
    for kind in [
        StrandKind::Wall,
        StrandKind::Hair,
        StrandKind::Rope,
        StrandKind::Spaghetti,
        StrandKind::Meatball,
    ] {
        let mut path = PathBuilder::new();
        for strand in content.strands.iter().filter(|s| s.kind == kind) {
            let edges = content.edges[strand.edges.clone()].iter();
            for edge in edges.filter(|e| !sleeps(e.a)) {
                let (ax, ay) = to_pixel(content.position[edge.a as usize]);
                let (bx, by) = to_pixel(content.position[edge.b as usize]);
                path.move_to(ax, ay);
                path.line_to(bx, by);
            }
        }
        if let Some(path) = path.finish() {
            let width = if kind == StrandKind::Wall {
                stroke.width.max(2.0)
            } else {
                stroke.width
            };
            let stroke = Stroke {
                width,
                ..stroke.clone()
            };
            pixmap.stroke_path(
                &path,
                &paint(StrandKind::color(kind)),
                &stroke,
                Transform::identity(),
                None,
            );
        }
    }

    // Sleeping strands dimmed, over the rest.
    let mut sleeping = PathBuilder::new();
    for edge in content.edges.iter().filter(|e| sleeps(e.a)) {
        let (ax, ay) = to_pixel(content.position[edge.a as usize]);
        let (bx, by) = to_pixel(content.position[edge.b as usize]);
        sleeping.move_to(ax, ay);
        sleeping.line_to(bx, by);
    }
    if let Some(path) = sleeping.finish() {
        pixmap.stroke_path(
            &path,
            &paint(SLEEPING),
            &stroke,
            Transform::identity(),
            None,
        );
    }

    // Pinned particles in red (the wall corners too); many pins (hair roots) small, so
    // that they mark rather than cover.
    let mut dots = PathBuilder::new();
    let pinned = |i: usize| content.pinned.get(i).copied().unwrap_or(false) && !sleeps(i as u32);
    let pins = (0..content.pinned.len()).filter(|&i| pinned(i)).count();
    let radius = if pins > 100 {
        (0.5 * stroke.width).max(0.75)
    } else {
        (1.5 * stroke.width).max(2.0)
    };
    for (i, &p) in content.position.iter().enumerate() {
        if pinned(i) {
            let (x, y) = to_pixel(p);
            dots.push_circle(x, y, radius);
        }
    }
    if let Some(dots) = dots.finish() {
        pixmap.fill_path(
            &dots,
            &paint([230, 60, 50]),
            FillRule::Winding,
            Transform::identity(),
            None,
        );
    }

    for (line, text) in content.caption.iter().enumerate() {
        let y = text_size * (1.25 * (line as f32 + 1.0) - 0.1);
        draw_text(pixmap, text, 0.6 * text_size, y, text_size, [235, 235, 235]);
    }
}
