//! The terrain engine: a height-mapped island standing in a translucent, reflecting sea under a
//! sky box, drawn with wgpu. World convention: **y-up**, the water is the plane y = 0.
//!
//! The modules in tiers, bottom up (no module imports from a tier above its own:
//! `crates/raytracer/tests/layers.rs` checks both crates; `docs/architecture.md` has the map):
//! - base: [`camera`] (the fly camera, a pure state machine fed with input and time, and its
//!   frustum), [`output`] (writing files), [`heap`] (the allocator's settings);
//! - [`config`]: the scene's numbers (the course's by default);
//! - [`world`]: the data to draw (heightmap, textures, sky), loaded or generated. No GPU.
//! - [`settings`]: how a frame looks (the course's look or the modern one, and its tunables), and
//!   [`controls`]: the window's key bindings, in one table;
//! - [`render`]: the wgpu renderer, drawing into any texture;
//! - [`headless`]: one frame off-screen, read back as an image, and [`overlay`]: egui drawn over a
//!   frame (the panel's host in the window and in a web page);
//! - [`panel`]: the window's tuning panel (egui, F1);
//! - [`window`]: the interactive window (winit), using the same renderer.
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
