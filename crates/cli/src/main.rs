//! `rayterra`: the command-line front end of the project.
//!
//! `rayterra render` drives the ray tracer (`crates/raytracer`), `rayterra terrain` the terrain
//! engine (`crates/terrain`). The libraries never print or exit; this binary turns their values,
//! errors and progress callbacks into terminal output and exit codes.

#[macro_use]
mod say;

mod exr_layers;
mod merge;
mod oidn;
mod preview;
mod render;
mod same_file;
mod size;
mod split;
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

/// Exit status after an interruption (SIGINT or SIGTERM), as shells report Ctrl-C.
const INTERRUPTED: i32 = 130;

/// What to say after an interruption about the work kept (a checkpoint), if any.
static KEPT_ON_INTERRUPT: std::sync::Mutex<Option<String>> = std::sync::Mutex::new(None);

/// Says `note` after an interruption from now on (`None`: nothing), e.g. that a checkpoint is
/// kept and how to resume from it.
pub fn on_interrupt_say(note: Option<String>) {
    *KEPT_ON_INTERRUPT.lock().unwrap_or_else(|poisoned| poisoned.into_inner()) = note;
}

/// On Ctrl-C or SIGTERM: remove the image being written, if any, say so (and what was kept) and
/// exit with 130.
fn stop_on_interrupt() {
    let installed = ctrlc::set_handler(|| {
        let removed = atomic_file::remove_unfinished();
        let what = if removed > 0 { "; the unfinished output file was removed" } else { "" };
        errln!("\nrayterra: interrupted{what}");
        if let Some(note) =
            KEPT_ON_INTERRUPT.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).as_deref()
        {
            errln!("{note}");
        }
        std::process::exit(INTERRUPTED);
    });
    if let Err(error) = installed {
        errln!("warning: cannot handle Ctrl-C: {error}");
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if matches!(&cli.command, Command::Terrain(_))
        || matches!(&cli.command, Command::Render(args) if args.preview)
    {
        terrain::quiet_vulkan_device_select();
    }
    stop_on_interrupt();
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
