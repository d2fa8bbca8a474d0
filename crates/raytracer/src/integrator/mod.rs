//! Shading models. `classic` is the course template's model (spec section 5), the default for
//! course scene files.

pub mod classic;

pub use classic::Classic;
