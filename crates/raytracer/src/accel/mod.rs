//! Acceleration structures: a bounding-volume hierarchy over the bounded shapes.

mod bvh;

pub use bvh::Bvh;
