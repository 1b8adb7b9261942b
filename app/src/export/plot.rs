//! The length-error plot: the largest relative length error of each tick over time,
//! log scale, for all edges and for edges away from contacts (plotters, drawn into a
//! buffer and written as PNG).

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use plotters::prelude::*;

use super::{ExportError, io_error};
use bevy_strands::metrics::ErrorSample;

/// Errors below this are drawn at it (a log scale has no zero).
pub const PLOT_FLOOR: f64 = 1e-17;

/// plotters draws text only in fonts registered with it, once per process.
#[cfg(not(target_arch = "wasm32"))]
fn register_font() -> Result<(), String> {
    use plotters::style::FontStyle;
    use std::sync::Once;
    static FONT_REGISTERED: Once = Once::new();
    FONT_REGISTERED.call_once(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, super::text::FONT)
            .unwrap_or_else(|_| panic!("the embedded font parses"));
    });
    Ok(())
}

/// plotters has no font registry on wasm32 (and a web page has no files to write).
#[cfg(target_arch = "wasm32")]
fn register_font() -> Result<(), String> {
    Err("plots cannot be drawn on wasm32: plotters has no font registry there".into())
}

/// Draw the history into a PNG file of `width × height` pixels.
pub fn plot_length_error(
    path: &Path,
    title: &str,
    samples: &[ErrorSample],
    (width, height): (u32, u32),
) -> Result<(), ExportError> {
    let fail = |message: String| ExportError::Plot {
        path: path.to_path_buf(),
        message,
    };
    register_font().map_err(fail)?;
    // The largest error in each time bucket, two pixel columns wide: thousands of
    // zigzagging points per column draw as noise, and plotters' bitmap rasterizer
    // draws exactly vertical segments (two points in one column) with false spikes.
    let samples = envelope(samples, width as usize / 2);
    let samples = &samples[..];
    let end = samples.last().map_or(1.0, |s| s.time).max(1e-6);
    let floor = |e: f64| e.max(PLOT_FLOOR);
    let top = samples.iter().map(|s| floor(s.all)).fold(1e-12, f64::max) * 10.0;
    let bottom = samples
        .iter()
        .map(|s| floor(s.free.min(s.all)))
        .fold(1.0, f64::min)
        .max(PLOT_FLOOR)
        / 10.0;

    let mut buffer = vec![255u8; (width * height * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail(e.to_string()))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("{title}: largest relative length error per tick"),
                ("sans-serif", 18),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..end, (bottom..top).log_scale())
            .map_err(|e| fail(e.to_string()))?;
        chart
            .configure_mesh()
            .x_desc("simulated time (s)")
            .y_desc("max |l - L| / L")
            .y_label_formatter(&|y| format!("{y:.0e}"))
            .draw()
            .map_err(|e| fail(e.to_string()))?;
        let all_color = RGBColor(220, 110, 20);
        let free_color = RGBColor(30, 120, 200);
        chart
            .draw_series(LineSeries::new(
                samples.iter().map(|s| (s.time, floor(s.all))),
                all_color.stroke_width(2),
            ))
            .map_err(|e| fail(e.to_string()))?
            .label("all edges")
            .legend(move |(x, y)| {
                PathElement::new([(x, y), (x + 20, y)], all_color.stroke_width(2))
            });
        chart
            .draw_series(LineSeries::new(
                samples.iter().map(|s| (s.time, floor(s.free))),
                free_color,
            ))
            .map_err(|e| fail(e.to_string()))?
            .label("edges away from contact")
            .legend(move |(x, y)| {
                PathElement::new([(x, y), (x + 20, y)], free_color.stroke_width(2))
            });
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(|e| fail(e.to_string()))?;
        root.present().map_err(|e| fail(e.to_string()))?;
    }
    write_png(path, &buffer, width, height)
}

/// The samples reduced to at most `buckets` points: per equal stretch of time, the
/// largest errors and the stretch's last time.
pub fn envelope(samples: &[ErrorSample], buckets: usize) -> Vec<ErrorSample> {
    let Some(last) = samples.last() else {
        return Vec::new();
    };
    if samples.len() <= buckets || buckets == 0 {
        return samples.to_vec();
    }
    let width = last.time / buckets as f64;
    let mut out: Vec<ErrorSample> = Vec::with_capacity(buckets);
    let mut bucket = usize::MAX;
    for s in samples {
        let b = ((s.time / width) as usize).min(buckets - 1);
        match out.last_mut() {
            Some(current) if b == bucket => {
                current.time = s.time;
                current.all = current.all.max(s.all);
                current.free = current.free.max(s.free);
            }
            _ => {
                out.push(*s);
                bucket = b;
            }
        }
    }
    out
}

/// Write an RGB buffer as a PNG file.
pub fn write_png(path: &Path, rgb: &[u8], width: u32, height: u32) -> Result<(), ExportError> {
    let file = File::create(path).map_err(io_error(path))?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder
        .write_header()
        .map_err(|e| io_error(path)(e.into()))?;
    writer
        .write_image_data(rgb)
        .map_err(|e| io_error(path)(e.into()))?;
    writer.finish().map_err(|e| io_error(path)(e.into()))
}
