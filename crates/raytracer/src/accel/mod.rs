//! Acceleration structures: an 8-wide bounding-volume hierarchy over the scene's primitives and,
//! inside every triangle mesh, over its triangles.

pub mod wide;

pub use wide::{Box32, BoxRay, BuildParams, WideBvh};
