//! `rayterra merge`: assembles the part files of a render split with `--tile` and `--pass` into
//! the full image.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use raytracer::image_io::{check_output, write_image};
use raytracer::parts::{self, Part};

/// Arguments of `rayterra merge`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:\n  \
    rayterra merge parts/part-*.exr -o final.png\n  \
    rayterra merge tile-*.exr -o poster.exr          keep the linear values")]
pub struct MergeArgs {
    /// Part files written by `rayterra render --tile K/N` and/or `--pass K/N` (EXR), in any order.
    #[arg(required = true, value_name = "PART")]
    pub parts: Vec<PathBuf>,

    /// The merged image; the extension picks the format: .png, .bmp, .exr or .hdr (linear).
    #[arg(short, long, value_name = "FILE", default_value = "render.png")]
    pub output: PathBuf,

    /// Encode 8-bit output as sRGB instead of the course's linear look.
    #[arg(long)]
    pub gamma: bool,

    /// Print nothing but warnings and errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Runs `rayterra merge`.
pub fn run(args: MergeArgs) -> Result<(), ExitCode> {
    let started = Instant::now();
    let format = check_output(&args.output).map_err(|e| fail(&e.to_string()))?;
    if format.is_linear() && args.gamma {
        errln!("warning: --gamma has no effect on linear {} output", crate::render::format_name(format));
    }
    if let Some(input) = args.parts.iter().find(|p| same_file(p, &args.output)) {
        return Err(fail(&format!(
            "the output `{}` is the part `{}`: merging would overwrite one of its own inputs; name another output",
            args.output.display(),
            input.display()
        )));
    }
    let mut parts: Vec<(PathBuf, Part)> = Vec::with_capacity(args.parts.len());
    for path in &args.parts {
        let part = parts::read_part(path).map_err(|e| fail(&e.to_string()))?;
        parts.push((path.clone(), part));
    }
    let image = parts::merge(&parts).map_err(|e| fail(&e.to_string()))?;
    write_image(&image, &args.output, args.gamma).map_err(|e| fail(&e.to_string()))?;
    if !args.quiet {
        let h = &parts[0].1.header;
        outln!("wrote {}", args.output.display());
        outln!(
            "{}x{} pixels from {} parts ({} tile{} x {} pass{}) in {:.2} s",
            h.width,
            h.height,
            parts.len(),
            h.tile.count,
            if h.tile.count == 1 { "" } else { "s" },
            h.pass.count,
            if h.pass.count == 1 { "" } else { "es" },
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

/// Whether `a` and `b` name the same existing file (the same file, not the same string:
/// `./x.exr`, `x.exr`, a link to it and a path through a linked folder all are).
fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (std::fs::metadata(a), std::fs::metadata(b)) {
            (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
            (Ok(x), Ok(y)) => x == y,
            _ => false,
        }
    }
}

/// Prints an error and returns the failure exit code.
fn fail(message: &str) -> ExitCode {
    errln!("error: {message}");
    ExitCode::FAILURE
}
