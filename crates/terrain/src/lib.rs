//! The terrain engine: a height-mapped island standing in a translucent, reflecting sea under a
//! sky box, drawn with wgpu. World convention: **y-up**, the water is the plane y = 0.
//!
//! - [`world`]: the data to draw (heightmap, textures, sky), loaded or generated. No GPU.
//! - [`camera`]: the fly camera, a pure state machine fed with input and time.
//! - [`config`]: the scene's numbers (the course's by default).
//! - [`settings`]: how a frame looks (the course's look or the modern one, and its tunables).
//! - [`controls`]: the window's key bindings, in one table.
//! - [`render`]: the wgpu renderer, drawing into any texture.
//! - [`headless`]: one frame off-screen, read back as an image.
//! - [`window`]: the interactive window (winit), using the same renderer.
//! - [`panel`]: the window's tuning panel (egui, F1).
//! - [`overlay`]: egui drawn over a frame (the panel's host in the window and in a web page).
//!
//! The crate also builds for `wasm32-unknown-unknown` (the web page, `web/`): there the GPU is
//! opened with [`render::Gpu::open_async`], the window ([`window`]) and the blocking
//! functions are left out, and off-screen images are read back without waiting
//! ([`headless::OffscreenTarget::request_read`]).
//!
//! The library never prints, exits or parses command lines: it returns values and typed errors.

pub mod camera;
pub mod config;
pub mod controls;
pub mod headless;
pub mod heap;
pub mod output;
pub mod overlay;
pub mod panel;
pub mod render;
pub mod settings;
#[cfg(not(target_arch = "wasm32"))]
pub mod window;
pub mod world;

pub use config::SceneConfig;
pub use settings::{Look, Settings};
