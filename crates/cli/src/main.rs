//! `rayterra`: the command-line front end of the project.
//!
//! `rayterra render` drives the ray tracer (`crates/raytracer`), `rayterra terrain` the terrain
//! engine (`crates/terrain`). The libraries never print or exit; this binary turns their values,
//! errors and progress callbacks into terminal output and exit codes.

mod merge;
mod render;
mod size;
mod terrain;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// The course ray tracer and terrain engine, in one command.
#[derive(Debug, Parser)]
#[command(name = "rayterra", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Render a scene file (course scene language) to an image.
    Render(render::RenderArgs),
    /// Merge the part files of a render split with `render --tile` or `--pass` into one image.
    Merge(merge::MergeArgs),
    /// Explore the terrain engine's island in a window, or render one frame off-screen.
    Terrain(terrain::TerrainArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render::run(args),
        Command::Merge(args) => merge::run(args),
        Command::Terrain(args) => terrain::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(code) => code,
    }
}
