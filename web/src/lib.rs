//! The terrain engine in a web page: the [`terrain`] crate built for `wasm32-unknown-unknown`,
//! drawing with WebGPU where the browser has it and WebGL2 otherwise, with the window's controls
//! and tuning panel. `web/build.sh` builds the page into `web/dist/`, `web/serve.sh` serves it.
//!
//! - [`address`]: the page's options, read from its address (`?seed=3&look=course`).
//! - [`file_world`]: the world of a file picked or dropped on the page (elevation data or a
//!   heightmap image), as `rayterra terrain --heightmap FILE` builds it, with its scene.
//! - [`transfer`]: a world taken apart into plain layers and put back together, to cross from
//!   the worker that generates it (so the page never freezes) to the page that draws it.
//! - `browser` (WebAssembly only): the page itself (the winit app on the canvas, the GPU, the
//!   worker's entry points, the page's status lines).

pub mod address;
pub mod file_world;
pub mod transfer;

#[cfg(target_arch = "wasm32")]
mod browser;
