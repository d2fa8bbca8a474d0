//! The base tier: what every other part of the ray tracer builds on, importing nothing from the
//! crate outside this folder.
//!
//! - [`source`] and [`diagnostic`]: scene-file text, positions in it, and messages about it;
//! - [`ray`] and [`bounds`]: rays (z-up world, `f64`) and axis-aligned boxes;
//! - [`error`]: invalid shape parameters, and the vector checks behind them;
//! - [`rows`]: sets of image rows and how they are cut into tiles;
//! - [`checksum`]: the hash that tells a damaged checkpoint or part file;
//! - [`memory`]: the memory budget and byte counts for messages;
//! - [`sampler`] and [`sampling`]: per-pixel random streams, exact sums, and warping of uniform
//!   numbers to directions;
//! - [`image_io`]: linear images and their files (PNG, BMP, EXR, HDR);
//! - [`color`]: colour arithmetic (luminance).
//!
//! The rest of the crate keeps its public paths (`raytracer::image_io`, `raytracer::sampler`,
//! `raytracer::scene::Location`, ...) by re-exporting these modules.

pub mod bounds;
pub mod checksum;
pub mod color;
pub mod diagnostic;
pub mod error;
pub mod image_io;
pub mod memory;
pub mod ray;
pub mod rows;
pub mod sampler;
pub mod sampling;
pub mod source;
