//! A ray tracer for the course scene language: a scene file in, an image out.
//!
//! World convention: **z-up**, right-handed. Colours are linear RGB.
//!
//! Data flows one way: scene text -> [`scene::parse`] (with positions for diagnostics) ->
//! [`scene::Scene`] (plain data) -> [`PreparedScene`] (textures loaded, BVH built) ->
//! [`render::render`] (pixels in parallel, per-pixel random numbers) -> [`Image`] (linear) ->
//! [`image_io::write_image`] (PNG, BMP, EXR, HDR).
//!
//! The library never prints and never exits: it returns values and typed errors, and reports
//! progress through a callback.

pub mod accel;
pub mod base;
pub mod camera;
pub mod geometry;
pub mod integrator;
pub mod light;
pub mod material;
pub mod parts;
pub mod prepare;
pub mod procedural;
pub mod render;
pub mod scene;
pub mod texture;

pub use base::{error, image_io, memory, sampler, sampling};

pub use image_io::Image;
pub use memory::MemoryBudget;
pub use prepare::{PreparedScene, TextureSearch};
pub use render::{RenderSettings, Rendered, Sampling, render};
