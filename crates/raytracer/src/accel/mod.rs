//! Acceleration structures: an 8-wide bounding-volume hierarchy, over the scene's primitives and
//! over the triangles of all its meshes.

pub mod wide;

pub use wide::{Box32, BoxRay, BuildParams, WideBvh};
