//! # bevy_strands_app
//!
//! Everything around the `bevy_strands` library that a game does not need: scenario
//! files ([`scenario`], [`spawn`], the [`builtin`] ones), the demo factories and the furry creature
//! ([`scenes`]), the headless runner, its report and its snapshots ([`runner`],
//! [`report`], [`snapshot`]), pictures
//! of runs ([`export`]), the windowed demos (features `window` and `render`, [`window`]), and the
//! fixtures the tests and benchmarks share ([`fixtures`]). The `strands` binary is a
//! thin command line over [`runner::run`].

#![warn(missing_docs)]

pub mod builtin;
pub mod energy;
pub mod export;
pub mod fixtures;
pub mod free;
pub mod initial_state;
pub mod profile;
pub mod report;
pub mod runner;
pub mod scenario;
pub mod scenes;
pub mod shape;
pub mod snapshot;
pub mod spawn;
#[cfg(feature = "window")]
pub mod window;
pub mod worlds;
