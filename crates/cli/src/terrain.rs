//! `rayterra terrain`: the terrain engine's command (window and off-screen screenshot).

use std::process::ExitCode;

/// Arguments of `rayterra terrain`.
#[derive(Debug, clap::Args)]
pub struct TerrainArgs {}

/// Runs `rayterra terrain`.
pub fn run(_args: TerrainArgs) -> Result<(), ExitCode> {
    eprintln!("error: the terrain engine is not built yet");
    Err(ExitCode::FAILURE)
}
