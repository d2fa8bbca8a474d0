//! `rayterra render`: renders a scene file with the ray tracer.

use std::process::ExitCode;

/// Arguments of `rayterra render`.
#[derive(Debug, clap::Args)]
pub struct RenderArgs {}

/// Runs `rayterra render`.
pub fn run(_args: RenderArgs) -> Result<(), ExitCode> {
    eprintln!("error: the ray tracer is not built yet");
    Err(ExitCode::FAILURE)
}
