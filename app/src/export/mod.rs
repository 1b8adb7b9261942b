//! Pictures from headless runs: frames drawn on the CPU ([`raster`]), written as PNG
//! files or an animated GIF, and plots of the length error over time ([`plot`]), so
//! that results can be seen on a machine with no display or GPU.

pub mod plot;
pub mod raster;
pub mod text;

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use bevy::math::DVec2;
use bevy::prelude::*;
use thiserror::Error;
use tiny_skia::Pixmap;

use bevy_strands::prelude::*;
use bevy_strands::sleeping::SleepState;

use crate::scenes::Disc;
use raster::{FrameContent, View, draw_frame};

/// Why pictures could not be written.
#[derive(Debug, Error)]
pub enum ExportError {
    /// A file or directory could not be written.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
    /// The GIF encoder failed.
    #[error("{path}: GIF encoding failed: {message}")]
    Gif {
        /// The GIF file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The plot could not be drawn.
    #[error("{path}: plotting failed: {message}")]
    Plot {
        /// The plot file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A size or rate is out of range.
    #[error("{0}")]
    Settings(String),
}

fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> ExportError + '_ {
    move |source| ExportError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Frame size and rate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameSettings {
    /// Frames per simulated second.
    pub fps: f64,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Default for FrameSettings {
    fn default() -> Self {
        Self {
            fps: 30.0,
            width: 512,
            height: 512,
        }
    }
}

impl FrameSettings {
    /// Refuse sizes and rates that cannot make a picture (GIF limits sizes to 65535).
    pub fn validate(&self) -> Result<(), ExportError> {
        if !(self.fps.is_finite() && self.fps > 0.0 && self.fps <= 1000.0) {
            return Err(ExportError::Settings(format!(
                "--fps {} must be above 0 and at most 1000",
                self.fps
            )));
        }
        for (name, value) in [("width", self.width), ("height", self.height)] {
            if !(16..=8192).contains(&value) {
                return Err(ExportError::Settings(format!(
                    "frame {name} {value} must be between 16 and 8192 pixels"
                )));
            }
        }
        Ok(())
    }
}

/// Draws frames of a running world at a fixed simulated rate into PNG files and/or an
/// animated GIF.
pub struct Recorder {
    settings: FrameSettings,
    view: View,
    title: String,
    gif: Option<(PathBuf, gif::Encoder<BufWriter<File>>)>,
    directory: Option<PathBuf>,
    pixmap: Pixmap,
    rgba: Vec<u8>,
    next_time: f64,
    frames: usize,
}

impl Recorder {
    /// Start recording `view` of the scenario `title` to a GIF at `gif` and/or PNG
    /// files in `directory` (created if missing).
    pub fn new(
        settings: FrameSettings,
        view: View,
        title: &str,
        gif: Option<&Path>,
        directory: Option<&Path>,
    ) -> Result<Self, ExportError> {
        settings.validate()?;
        let encoder = match gif {
            Some(path) => {
                let file = File::create(path).map_err(io_error(path))?;
                let mut encoder = gif::Encoder::new(
                    BufWriter::new(file),
                    settings.width as u16,
                    settings.height as u16,
                    &[],
                )
                .map_err(|e| ExportError::Gif {
                    path: path.to_path_buf(),
                    message: e.to_string(),
                })?;
                encoder
                    .set_repeat(gif::Repeat::Infinite)
                    .map_err(|e| ExportError::Gif {
                        path: path.to_path_buf(),
                        message: e.to_string(),
                    })?;
                Some((path.to_path_buf(), encoder))
            }
            None => None,
        };
        if let Some(directory) = directory {
            std::fs::create_dir_all(directory).map_err(io_error(directory))?;
        }
        Ok(Self {
            settings,
            view,
            title: title.to_string(),
            gif: encoder,
            directory: directory.map(Path::to_path_buf),
            pixmap: Pixmap::new(settings.width, settings.height).expect("validated size"),
            rgba: Vec::new(),
            next_time: 0.0,
            frames: 0,
        })
    }

    /// Frames written so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Draw and write a frame if the simulated time has reached the next one.
    pub fn capture_if_due(&mut self, world: &mut World) -> Result<(), ExportError> {
        let time = world.resource::<SimulationClock>().time;
        if time + 1e-9 >= self.next_time {
            self.capture(world)?;
            // Skip frames a long tick jumped over rather than bunching them up.
            while self.next_time <= time + 1e-9 {
                self.next_time += 1.0 / self.settings.fps;
            }
        }
        Ok(())
    }

    /// Draw and write a frame of the world as it is.
    pub fn capture(&mut self, world: &mut World) -> Result<(), ExportError> {
        let discs: Vec<(DVec2, f64)> = world
            .query::<&Disc>()
            .iter(world)
            .map(|d| (d.centre, d.radius))
            .collect();
        let metrics = world.resource::<StrandMetrics>();
        let clock = world.resource::<SimulationClock>();
        let caption = vec![
            format!("{}   t = {:.2} s", self.title, clock.time),
            format!(
                "strands {}   particles {}",
                metrics.strands, metrics.particles
            ),
            format!(
                "max rel. length error so far {:.1e}",
                metrics.max_rel_length_error
            ),
        ];
        let state = world.resource::<ParticleState>();
        let topology = world.resource::<Topology>();
        let asleep: Vec<bool> = match world.get_resource::<SleepState>() {
            Some(sleep) => (0..state.len()).map(|i| sleep.is_asleep(i)).collect(),
            None => Vec::new(),
        };
        let content = FrameContent {
            position: &state.position,
            pinned: &topology.pinned,
            asleep: &asleep,
            edges: &topology.edges,
            strands: &topology.strands,
            discs: &discs,
            thickness: world
                .get_resource::<CollisionConfig>()
                .map_or(0.004, |c| c.thickness),
            caption: &caption,
        };
        draw_frame(&mut self.pixmap, &self.view, &content);
        self.write_frame()
    }

    fn write_frame(&mut self) -> Result<(), ExportError> {
        if let Some(directory) = &self.directory {
            let path = directory.join(format!("frame_{:05}.png", self.frames));
            self.pixmap.save_png(&path).map_err(|e| ExportError::Io {
                path: path.clone(),
                source: std::io::Error::other(e.to_string()),
            })?;
        }
        if let Some((path, encoder)) = &mut self.gif {
            // The frames are opaque: premultiplied RGBA is plain RGBA.
            self.rgba.clear();
            self.rgba.extend_from_slice(self.pixmap.data());
            let (w, h) = (self.settings.width as u16, self.settings.height as u16);
            let mut frame = gif::Frame::from_rgba_speed(w, h, &mut self.rgba, 10);
            frame.delay = (100.0 / self.settings.fps).round().max(1.0) as u16;
            encoder.write_frame(&frame).map_err(|e| ExportError::Gif {
                path: path.clone(),
                message: e.to_string(),
            })?;
        }
        self.frames += 1;
        Ok(())
    }

    /// Finish the files; returns the number of frames written.
    pub fn finish(self) -> Result<usize, ExportError> {
        if let Some((path, encoder)) = self.gif {
            encoder
                .into_inner()
                .map_err(|e| ExportError::Gif {
                    path: path.clone(),
                    message: e.to_string(),
                })?
                .into_inner()
                .map_err(|e| io_error(&path)(e.into_error()))?;
        }
        Ok(self.frames)
    }
}
