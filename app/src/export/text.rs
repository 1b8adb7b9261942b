//! Text on pictures, rasterized from the embedded DejaVu Sans Mono font
//! (`assets/fonts/`, DejaVu licence) so that no system font is needed.

use ab_glyph::{Font, FontRef, PxScale, ScaleFont};
use tiny_skia::Pixmap;

/// The embedded font's bytes.
pub const FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSansMono.ttf");

/// The embedded font.
pub fn font() -> FontRef<'static> {
    FontRef::try_from_slice(FONT).expect("the embedded font parses")
}

/// Draw `text` with its baseline's left end at (x, y) pixels, `size` pixels tall, in
/// `color` (straight RGB), blending by glyph coverage.
pub fn draw_text(pixmap: &mut Pixmap, text: &str, x: f32, y: f32, size: f32, color: [u8; 3]) {
    let font = font();
    let scaled = font.as_scaled(PxScale::from(size));
    let (width, height) = (pixmap.width() as i32, pixmap.height() as i32);
    let pixels = pixmap.pixels_mut();
    let mut caret = x;
    let mut previous = None;
    for c in text.chars() {
        let id = scaled.glyph_id(c);
        if let Some(previous) = previous {
            caret += scaled.kern(previous, id);
        }
        let glyph = id.with_scale_and_position(PxScale::from(size), ab_glyph::point(caret, y));
        caret += scaled.h_advance(id);
        previous = Some(id);
        let Some(outline) = font.outline_glyph(glyph) else {
            continue;
        };
        let bounds = outline.px_bounds();
        outline.draw(|gx, gy, coverage| {
            let px = bounds.min.x as i32 + gx as i32;
            let py = bounds.min.y as i32 + gy as i32;
            if px < 0 || py < 0 || px >= width || py >= height {
                return;
            }
            let pixel = &mut pixels[(py * width + px) as usize];
            let a = coverage.clamp(0.0, 1.0);
            let blend =
                |under: u8, over: u8| (under as f32 * (1.0 - a) + over as f32 * a).round() as u8;
            // The frames are opaque, so premultiplied and straight colours agree.
            *pixel = tiny_skia::PremultipliedColorU8::from_rgba(
                blend(pixel.red(), color[0]),
                blend(pixel.green(), color[1]),
                blend(pixel.blue(), color[2]),
                255,
            )
            .expect("opaque colours are valid");
        });
    }
}
