//! A ray tracer for the course scene language: a scene file in, an image out.
//!
//! World convention: **z-up**, right-handed. Colours are linear RGB.
//!
//! Data flows one way: scene text -> [`scene::parse`] (the course language's front end,
//! [`scene::course`], with positions for diagnostics) -> [`scene::Scene`] (plain data) ->
//! [`PreparedScene`] (meshes read, textures loaded, BVH built) -> a model of [`integrator`] over
//! rows of pixels, driven by [`render::render`] (per-pixel random numbers) -> [`Image`] (linear) ->
//! [`image_io::write_image`] (PNG, BMP, EXR, HDR).
//!
//! The modules stand in tiers, bottom up: [`base`]; [`geometry`] and [`accel`]; the scene
//! description ([`scene`], [`material`], [`light`]); the scene formats ([`scene::course`]);
//! preparation ([`prepare`], [`texture`], [`procedural`], [`camera`]); the models
//! ([`integrator`]); the driver and split renders ([`render`](mod@render), [`parts`]). No module
//! imports from a tier above its own (`tests/layers.rs` checks it; `docs/architecture.md` has the
//! code map).
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
