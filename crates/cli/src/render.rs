//! `rayterra render`: renders a scene file with the ray tracer.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use raytracer::image_io::{Image, OutputFormat, check_output, write_image};

use crate::exr_layers::AovLayer;
use raytracer::integrator::aov::DEFAULT_AOV_SAMPLES;
use raytracer::integrator::photon::{self, PhotonStats};
use raytracer::integrator::sppm::SppmStats;
use raytracer::integrator::{Model, choose_model};
use raytracer::memory::parse_byte_size;
use raytracer::parts::{self, Part, PartHeader, Split};
use raytracer::render::{
    DEFAULT_PATH_SPP, MAX_DEPTH_LIMIT, MAX_RUNS, MAX_SPP, PortionPixels, Progress, RenderStats, Rows, Stage,
    render_portion_resumable,
};
use raytracer::scene::{self, Diagnostic, MAX_EMITTED_PHOTONS, MAX_KEPT_DIAGNOSTICS, Omitted, SourceFile};
use raytracer::{MemoryBudget, PreparedScene, RenderSettings, Sampling, TextureSearch};

/// The project's showcase scene, rendered when no scene file is given.
const SHOWCASE: &str = include_str!("../../../scenes/showcase.txt");
/// The name the showcase scene is reported under.
const SHOWCASE_NAME: &str = "scenes/showcase.txt (built in)";

/// Arguments of `rayterra render`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:\n  \
    rayterra render                                   the built-in showcase scene, to render.png\n  \
    rayterra render scene.txt -o scene.png --size 640x380\n  \
    rayterra render scene.txt --textures path/to/textures --spp 16\n  \
    rayterra render caustics.txt --model photon --photons 500000\n  \
    rayterra render cornell-box.txt --model path --spp 256 -o out.exr\n  \
    rayterra render caustics.txt --model sppm --passes 64 --photons 200000\n  \
    rayterra render scene.txt --tile 2/8 -o part-2.exr   one of 8 tiles, for rayterra merge\n  \
    rayterra render scene.txt --model path --spp 64 --pass auto/16 -o pass.exr   in an array job\n  \
    rayterra render cornell-box.txt --model path --spp 16 --denoise -o out.exr   Open Image Denoise\n  \
    rayterra render cornell-box.txt --model path --preview   watch it converge, fly the camera\n  \
    rayterra render cbox.xml -D spp=64 -o cbox.png     a Mitsuba 3 scene, with Mitsuba's -D\n  \
    rayterra render --check scene.txt                 validate only, print the warnings")]
pub struct RenderArgs {
    /// Scene file in the course scene language, or a Mitsuba 3 XML scene (`.xml`); without it, the
    /// built-in showcase scene.
    pub scene: Option<PathBuf>,

    /// Output image; the extension picks the format: .png, .bmp, .exr or .hdr (linear).
    #[arg(short, long, value_name = "FILE", default_value = "render.png")]
    pub output: PathBuf,

    /// Image size, overriding the scene's image_W and image_H.
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(u32, u32)>,

    /// Samples in every pixel. Classic and photon models: stratified, instead of adaptive
    /// anti-aliasing (one sample per pixel, 16 on edges, contrasts and noisy pixels); path model:
    /// the paths a pixel [default: 64].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    pub spp: Option<u32>,

    /// Worker threads [default: one per core]. The image does not depend on it.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,

    /// A folder to look for textures in, after the scene file's folder and before the working
    /// directory. May be repeated.
    #[arg(long, value_name = "DIR")]
    pub textures: Vec<PathBuf>,

    /// Encode 8-bit output as sRGB instead of the course's linear look.
    #[arg(long)]
    pub gamma: bool,

    /// Seed of the random sampling.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed: u64,

    /// Light-transport model [default: the scene's `algorithm=`, else classic]. classic: the
    /// course's ray tracer; photon: the course's photon mapper (caustics, indirect light); path:
    /// a physically based path tracer; sppm: physically based stochastic progressive photon
    /// mapping (caustics seen directly and in mirrors).
    #[arg(long, value_name = "MODEL", value_parser = parse_model)]
    pub model: Option<Model>,

    /// Photons to emit (photon model), or photons a pass (sppm), instead of the scene's
    /// `emit_photons=`.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=MAX_EMITTED_PHOTONS))]
    pub photons: Option<u64>,

    /// Classic, photon and path models: independent passes, averaged (as --runs; for the path
    /// model N passes of --spp samples are a render of N x spp samples). Sppm: its passes, instead
    /// of the scene's `iterations=`.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=scene::MAX_ITERATIONS))]
    pub passes: Option<u64>,

    /// Independent runs of the render, each with its own random numbers, averaged: what N parts
    /// rendered with `--pass K/N` merge into. Any model (for sppm, whole SPPM renders).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=MAX_RUNS as i64))]
    pub runs: Option<u32>,

    /// Render tile K of N only (K from 0; interleaved blocks of rows) and write it as a part file
    /// (.exr) for `rayterra merge`. `auto`: K and N of a Slurm array task (SLURM_ARRAY_TASK_ID,
    /// SLURM_ARRAY_TASK_COUNT); `auto/N`: K from SLURM_ARRAY_TASK_ID or a Kubernetes Indexed
    /// Job's JOB_COMPLETION_INDEX.
    #[arg(long, value_name = "K/N|auto|auto/N", value_parser = parse_split)]
    pub tile: Option<String>,

    /// Render pass K of N independent passes only (its own random numbers; see --runs) and write
    /// it as a part file (.exr) for `rayterra merge`; `auto` as for --tile. Combines with --tile.
    #[arg(long, value_name = "K/N|auto|auto/N", value_parser = parse_split)]
    pub pass: Option<String>,

    /// Keep the finished work in FILE while rendering, and go on from it if FILE exists (a render
    /// killed by a time limit, resubmitted): the image is the same bit for bit. FILE is removed
    /// once the output is written.
    #[arg(long, value_name = "FILE")]
    pub checkpoint: Option<PathBuf>,

    /// Longest light path of the path and sppm models, in segments (1: lights seen directly; 2:
    /// direct light; ...). Default: the Mitsuba scene's own `max_depth`, else 10.
    #[arg(long, value_name = "N",
          value_parser = clap::value_parser!(u32).range(1..=MAX_DEPTH_LIMIT as i64))]
    pub max_depth: Option<u32>,

    /// Most memory the scene's textures and the photon map may take together, e.g. 512M or 8G.
    #[arg(long, value_name = "SIZE", default_value = "4G", value_parser = parse_byte_size)]
    pub memory_limit: u64,

    /// Parse and validate the scene (textures included) and print the warnings; render nothing.
    #[arg(long)]
    pub check: bool,

    /// For a Mitsuba 3 scene file (XML), define NAME as VALUE for `$NAME` in the file, as
    /// Mitsuba's own `-D` (repeatable; it wins over the file's `<default>`).
    #[arg(short = 'D', long = "define", value_name = "NAME=VALUE", value_parser = parse_define)]
    pub defines: Vec<(String, String)>,

    /// Denoise the finished image with Intel Open Image Denoise (its `RT` filter, guided by the
    /// albedo and normal images). OIDN is loaded at run time from OIDN_DIR, the system's library
    /// path, or an installed `pyoidn` (`pip install pyoidn==2.5.1.0`); see docs/denoising.md.
    #[arg(long)]
    pub denoise: bool,

    /// Also write auxiliary images: albedo, normal, depth (comma-separated), at the first
    /// non-specular surface each pixel sees. With an .exr output, as its layers (`albedo.R`,
    /// `normal.X`, `depth.Z`, ...); with another, beside it as `NAME.albedo.exr` and so on.
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = parse_aov)]
    pub aov: Vec<Aov>,

    /// Show the render in a window as it converges, with a camera to fly (W/A/S/D, arrows, right
    /// button and mouse), exposure (E, Shift+E), zoom (wheel) and pan (drag); S writes the image so
    /// far, P prints the camera's pose as scene-file lines, D shows the denoised image (with
    /// --denoise). The output is written when the render finishes, as without --preview; without
    /// a display the render goes on without the window. See docs/preview.md.
    #[arg(long)]
    pub preview: bool,

    /// Print nothing but warnings and errors.
    #[arg(short, long)]
    pub quiet: bool,
}

/// Parses `-D NAME=VALUE`.
fn parse_define(text: &str) -> Result<(String, String), String> {
    scene::mitsuba::parse_define(text).map_err(|e| e.to_string())
}

/// An auxiliary image `--aov` can write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Aov {
    /// The albedo (linear RGB in [0, 1]).
    Albedo,
    /// The shading normal (world space, z-up, components in [-1, 1]).
    Normal,
    /// The distance along the camera path (scene units, in every channel).
    Depth,
}

impl Aov {
    /// Every image, in the order `--aov` lists them.
    const ALL: [Aov; 3] = [Aov::Albedo, Aov::Normal, Aov::Depth];

    /// The image's name on the command line and in its file name.
    fn name(self) -> &'static str {
        match self {
            Aov::Albedo => "albedo",
            Aov::Normal => "normal",
            Aov::Depth => "depth",
        }
    }
}

/// Parses one name of `--aov`.
fn parse_aov(text: &str) -> Result<Aov, String> {
    Aov::ALL.into_iter().find(|a| a.name() == text.trim()).ok_or_else(|| {
        format!("unknown auxiliary image `{text}`; expected albedo, normal or depth (comma-separated)")
    })
}

/// The file an auxiliary image is written to: `render.exr` gives `render.albedo.exr`.
fn aov_path(output: &Path, aov: Aov) -> PathBuf {
    let stem = output.file_stem().map_or_else(|| "render".into(), |s| s.to_string_lossy().into_owned());
    output.with_file_name(format!("{stem}.{}.exr", aov.name()))
}

/// Parses `--model`.
fn parse_model(text: &str) -> Result<Model, String> {
    Model::ALL.into_iter().find(|m| m.name() == text).ok_or_else(|| {
        let names: Vec<&str> = Model::ALL.iter().map(|m| m.name()).collect();
        format!("unknown model `{text}`; expected one of {}", names.join(", "))
    })
}

/// Parses `--size`, up to the ray tracer's largest image side.
fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = crate::size::parse_size(text, scene::MAX_IMAGE_SIDE)?;
    // The pixel count too: a size the render refuses is a malformed option (exit status 2).
    scene::check_image_size(w, h)?;
    Ok((w, h))
}

/// Checks the form of `--tile` and `--pass` (`K/N`, `auto`, `auto/N`): a malformed one is a
/// usage error (exit status 2). `auto` is resolved from the environment later.
fn parse_split(text: &str) -> Result<String, String> {
    crate::split::check_form(text)?;
    Ok(text.to_owned())
}

/// Runs `rayterra render`.
pub fn run(args: RenderArgs) -> Result<(), ExitCode> {
    let started = Instant::now();
    // A bad output path or format is found before any work, not after the render.
    let format = if args.check { OutputFormat::from_path(&args.output) } else { check_output(&args.output) }
        .map_err(|e| fail(&e.to_string()))?;
    let env = |name: &str| std::env::var(name).ok();
    let tile = args
        .tile
        .as_deref()
        .map(|t| crate::split::resolve(t, "tile", env))
        .transpose()
        .map_err(|e| fail(&e))?;
    let pass = args
        .pass
        .as_deref()
        .map(|p| crate::split::resolve(p, "pass", env))
        .transpose()
        .map_err(|e| fail(&e))?;
    let is_part = tile.is_some() || pass.is_some();
    if args.preview && (is_part || args.checkpoint.is_some()) && !args.check {
        return Err(usage(
            "--preview shows a whole render as it converges: it does not combine with --tile, --pass or --checkpoint",
        ));
    }
    if let Some(checkpoint) = &args.checkpoint {
        // The checkpoint is removed once the output is written: the same file for both would
        // delete the finished image.
        if crate::same_file::same_file(checkpoint, &args.output) {
            return Err(usage(&format!(
                "--checkpoint `{}` and -o `{}` are the same file, which would be removed once written; \
                 give the checkpoint a name of its own",
                checkpoint.display(),
                args.output.display()
            )));
        }
        if let Some(scene) = &args.scene {
            refuse_input_as(checkpoint, "--checkpoint", scene)?;
        }
    }
    if let Some(scene) = args.scene.as_ref().filter(|_| !args.check) {
        refuse_input_as(&args.output, "-o", scene)?;
    }
    if is_part && format != OutputFormat::Exr {
        return Err(fail(&format!(
            "a tile or pass is written as a part file for `rayterra merge`: name the output `.exr`, not `{}`",
            args.output.display()
        )));
    }
    let source = match &args.scene {
        Some(path) => SourceFile::read(path).map_err(|e| fail(&e.to_string()))?,
        None => SourceFile::from_text(SHOWCASE_NAME, None, SHOWCASE.to_owned()),
    };
    let mitsuba = is_mitsuba_scene(&source);
    let (scene, extra_inputs) = if mitsuba {
        let built = mitsuba_scene(&source, &args)?;
        (built.scene, built.inputs)
    } else {
        (course_scene(&source, &args)?, Vec::new())
    };

    for dir in &args.textures {
        if !dir.is_dir() {
            let what = if dir.exists() { "is not a folder" } else { "does not exist" };
            errln!("warning: --textures `{}` {what}; no texture or mesh is looked for there", dir.display());
        }
    }
    let search =
        TextureSearch { scene_dir: source.dir().map(Path::to_path_buf), extra_dirs: args.textures.clone() };
    let budget = MemoryBudget::new(args.memory_limit);
    let mut prepared = PreparedScene::with_budget(scene, &search, &budget).map_err(|errors| {
        print_diagnostics(&errors);
        fail(&format!(
            "`{}` names textures or meshes that cannot be used; nothing was rendered",
            source.name()
        ))
    })?;
    prepared.inputs.splice(0..0, extra_inputs);
    print_diagnostics(&prepared.diagnostics);
    for input in &prepared.inputs {
        if let Some(checkpoint) = &args.checkpoint {
            refuse_input_as(checkpoint, "--checkpoint", input)?;
        }
        if !args.check {
            refuse_input_as(&args.output, "-o", input)?;
        }
    }
    let prepare_time = started.elapsed();

    let mut settings = RenderSettings::for_scene(&prepared);
    if let Some((w, h)) = args.size {
        // The size rendered, instead of the file's (whose warning was left out above).
        if let Some(message) = scene::aspect_mismatch(&prepared.scene.camera, w, h) {
            errln!("warning: with --size {w}x{h}, {message}");
        }
        settings.width = w;
        settings.height = h;
    }
    if let Some(n) = args.spp {
        settings.sampling = Sampling::Uniform(n);
    }
    settings.threads = args.threads.map(|n| n as usize);
    settings.seed = args.seed;
    let (model, notes) = choose_model(&prepared.scene, args.model);
    print_diagnostics(&notes);
    settings.model = model;
    if prepared.is_physical() && model != Model::Path {
        return Err(fail(&format!(
            "`{}` has physically based materials or emitters, which only the path model renders; \
             the {} model reads the course's materials (leave out --model, or give --model path)",
            source.name(),
            model.name()
        )));
    }
    if args.spp.is_none() && model == Model::Path && prepared.scene.render.samples.is_none() {
        // The classic model's 16 samples for a lens are not the path tracer's default.
        settings.sampling = Sampling::Adaptive;
    }
    settings.photons = args.photons;
    // Else the scene's own (a Mitsuba scene's `max_depth`), or the default.
    if let Some(depth) = args.max_depth {
        settings.max_depth = depth;
    }
    (settings.passes, settings.runs) = passes_and_runs(&args, model, pass).map_err(|e| fail(&e))?;
    warn_unused_options(&args, model);
    // The photon map gets what the textures left of the memory limit.
    settings.memory_limit = budget.remaining();
    scene::check_image_size(settings.width, settings.height).map_err(|m| fail(&m))?;
    let photon_settings = settings.photon_settings(&prepared);
    let memory = match model {
        Model::Photon => photon::check_memory(&photon_settings, settings.memory_limit),
        Model::Sppm => raytracer::integrator::sppm::check_memory(
            &photon_settings,
            settings.width as u64 * settings.height as u64,
            settings.max_depth,
            settings.memory_limit,
        ),
        Model::Classic | Model::Path => Ok(()),
    };
    memory.map_err(|mut d| {
        if budget.used() > 0 {
            d.notes.push(format!(
                "the scene's textures take {} of the memory limit of {} (--memory-limit)",
                photon::format_bytes(budget.used()),
                photon::format_bytes(budget.limit())
            ));
        }
        print_diagnostics(&[d]);
        fail(&format!("`{}` asks for more memory than a render may use; nothing was rendered", source.name()))
    })?;
    if format.is_linear() && args.gamma {
        errln!("warning: --gamma has no effect on linear {} output", crate::render::format_name(format));
    }

    // OIDN is found before any work, so that a missing library costs no render.
    let denoiser = if args.denoise && !args.check {
        if is_part {
            return Err(fail(
                "--denoise works on a whole image, not a tile or pass: merge the parts with `rayterra merge`, \
                 then render the whole image with --denoise",
            ));
        }
        Some(crate::oidn::Oidn::find().map_err(|e| fail(&e))?)
    } else {
        None
    };
    if is_part && !args.aov.is_empty() {
        return Err(fail("--aov works on a whole image, not a tile or pass"));
    }

    if args.check {
        if !args.quiet {
            let scene = &prepared.scene;
            let (primitives, lights) = (scene.primitives.len(), scene.lights.len() + scene.emitters.len());
            outln!(
                "{}: ok ({primitives} primitive{}, {lights} light{}, {}x{} pixels, {} model)",
                source.name(),
                plural(primitives),
                plural(lights),
                settings.width,
                settings.height,
                settings.model.name()
            );
        }
        return Ok(());
    }

    if args.preview {
        return crate::preview::run(crate::preview::Job {
            args: &args,
            scene_name: source.name().to_owned(),
            prepared,
            settings,
            denoiser,
            prepare_time,
            syntax: if mitsuba {
                crate::preview::PoseSyntax::Mitsuba
            } else {
                crate::preview::PoseSyntax::Course
            },
        });
    }

    let bar = progress_bar(args.quiet);
    let report = |p: Progress| {
        let message = match p.stage {
            Stage::TracingPhotons => "tracing photons",
            Stage::BuildingPhotonMap => "building map",
            Stage::Tracing => "tracing rows",
            Stage::Refining => "refining pixels",
            Stage::Sampling => "samples",
            Stage::Passes => "passes",
            Stage::Chunks => "chunks",
        };
        if bar.message() != message {
            bar.set_message(message);
            bar.set_length(p.total);
            bar.set_position(0);
        }
        // Reports come from several threads and may arrive out of order.
        if p.done > bar.position() {
            bar.set_position(p.done);
        }
    };
    let (w, h) = (settings.width, settings.height);
    let runs = pass.map_or(0..settings.runs, |p| p.index..p.index + 1);
    let tile = tile.unwrap_or(Split::WHOLE);
    let pass = pass.unwrap_or(Split::WHOLE);
    // A part file holds its rows in the blocks of its tile (one tile: the whole image).
    let rows = if is_part {
        Rows::tile(w, h, tile).map_err(|e| fail(&format!("--tile {tile}: {e}")))?
    } else {
        Rows::full(w, h)
    };
    // What the part (or checkpoint) belongs to.
    let scene_digest = if is_part || args.checkpoint.is_some() {
        crate::split::scene_digest(&source, &prepared.inputs).map_err(|e| fail(&e))?
    } else {
        String::new()
    };
    let settings_line = crate::split::settings_line(&settings);
    let mut checkpoint = match &args.checkpoint {
        Some(path) => {
            let key = format!("scene {scene_digest}\nsettings {settings_line}\ntile {tile}\npass {pass}");
            let opened = crate::split::open_checkpoint(path, &key, &rows).map_err(|e| fail(&e))?;
            crate::on_interrupt_say(Some(format!(
                "note: the checkpoint `{}` is kept with the work done so far; run the same command again \
                 to go on from it",
                path.display()
            )));
            Some(opened)
        }
        None => None,
    };
    let render_started = Instant::now();
    let portion = render_portion_resumable(&prepared, &settings, &rows, runs, &report, checkpoint.as_mut())
        .map_err(|e| fail(&e.to_string()))?;
    let render_time = render_started.elapsed();
    bar.finish_and_clear();
    let stats = portion.stats;

    if is_part {
        let header = PartHeader {
            width: w,
            height: h,
            scene: scene_digest,
            settings: settings_line,
            tile,
            pass,
            samples: 1,
        };
        let part = Part::from_portion(header, &rows, portion.pixels);
        parts::write_part(&part, &args.output).map_err(|e| fail(&e.to_string()))?;
    } else {
        let PortionPixels::Final(pixels) = portion.pixels else {
            return Err(fail("internal error: a whole render gave partial sums"));
        };
        write_whole(&args, &prepared, &settings, denoiser.as_ref(), pixels)?;
    }
    if let Some(checkpoint) = checkpoint {
        crate::on_interrupt_say(None);
        let path = checkpoint.path().to_path_buf();
        if let Err(e) = checkpoint.remove() {
            errln!("warning: the render is written, but its checkpoint `{}` stays: {e}", path.display());
        }
    }
    if let Some(p) = stats.photons.filter(|p| p.emitted < p.requested) {
        errln!(
            "warning: the photon map was full (`max_photons= {}`) after {} of the {} photons; the estimate \
             still divides by all {} (as the course's renderer does), so the image is about {:.1} times \
             darker than a map that held them all\n  = note: raise `max_photons=` or lower `emit_photons=` \
             (or `--photons`)",
            p.stored,
            p.emitted,
            p.requested,
            p.requested,
            p.requested as f64 / p.emitted as f64
        );
    }
    if !args.quiet {
        let pixels = if is_part {
            format!("{} of {w}x{h} pixels (tile {tile}, pass {pass})", rows.len())
        } else {
            format!("{w}x{h} pixels")
        };
        print_summary(&args.output, &pixels, &settings, &stats, prepare_time, render_time);
    }
    Ok(())
}

/// What a finished whole render becomes: denoised (`--denoise`), its auxiliary images written
/// (`--aov`), then the output file. The preview writes its finished renders through it too.
pub fn write_whole(
    args: &RenderArgs,
    prepared: &PreparedScene,
    settings: &RenderSettings,
    denoiser: Option<&crate::oidn::Oidn>,
    mut pixels: Vec<[f32; 3]>,
) -> Result<(), ExitCode> {
    let (w, h) = (settings.width, settings.height);
    if denoiser.is_some() || !args.aov.is_empty() {
        let aov_started = Instant::now();
        let aovs = raytracer::render::render_aovs(prepared, settings, DEFAULT_AOV_SAMPLES)
            .map_err(|e| fail(&e.to_string()))?;
        let aov_time = aov_started.elapsed();
        if let Some(oidn) = denoiser {
            let started = Instant::now();
            pixels = oidn
                .denoise(w, h, &pixels, &aovs.albedo, &aovs.normal, settings.threads)
                .map_err(|e| fail(&e))?;
            if !args.quiet {
                outln!(
                    "denoised with Open Image Denoise ({}) in {:.2} s, its albedo and normal images in {:.2} s",
                    oidn.path().display(),
                    started.elapsed().as_secs_f64(),
                    aov_time.as_secs_f64()
                );
            }
        }
        if !args.aov.is_empty() && OutputFormat::from_path(&args.output).is_ok_and(|f| f == OutputFormat::Exr)
        {
            // Layers of the EXR output.
            let layers: Vec<AovLayer> = args
                .aov
                .iter()
                .map(|aov| match aov {
                    Aov::Albedo => AovLayer::from_rgb("albedo", ["R", "G", "B"], &aovs.albedo),
                    Aov::Normal => AovLayer::from_rgb("normal", ["X", "Y", "Z"], &aovs.normal),
                    Aov::Depth => AovLayer::single("depth", "Z", aovs.depth.clone()),
                })
                .collect();
            crate::exr_layers::write_with_layers(&args.output, w, h, &pixels, &layers)
                .map_err(|e| fail(&e.to_string()))?;
            if !args.quiet {
                let names: Vec<&str> = args.aov.iter().map(|a| a.name()).collect();
                outln!(
                    "{} holds the auxiliary images as layers: {}",
                    args.output.display(),
                    names.join(", ")
                );
            }
            return Ok(());
        }
        for &aov in &args.aov {
            let data = match aov {
                Aov::Albedo => aovs.albedo.clone(),
                Aov::Normal => aovs.normal.clone(),
                Aov::Depth => aovs.depth.iter().map(|&d| [d; 3]).collect(),
            };
            let path = aov_path(&args.output, aov);
            write_image(&Image::new(w, h, data), &path, false).map_err(|e| fail(&e.to_string()))?;
            if !args.quiet {
                outln!("wrote {}", path.display());
            }
        }
    }
    write_image(&Image::new(w, h, pixels), &args.output, args.gamma || prepared.scene.render.srgb_output)
        .map_err(|e| fail(&e.to_string()))?;
    Ok(())
}

/// The sppm model's passes and the render's independent runs, from `--passes`, `--runs` and
/// `--pass K/N` (which renders one of `N` runs).
fn passes_and_runs(
    args: &RenderArgs,
    model: Model,
    pass: Option<Split>,
) -> Result<(Option<u64>, u32), String> {
    let (sppm_passes, passes_as_runs) = match model {
        Model::Sppm => (args.passes, None),
        _ => (None, args.passes),
    };
    let mut runs = args.runs.map(|n| (n, "--runs"));
    if let Some(n) = passes_as_runs {
        let n = u32::try_from(n).ok().filter(|&n| n <= MAX_RUNS).ok_or_else(|| {
            format!("--passes {n}: the {} model averages at most {MAX_RUNS} passes", model.name())
        })?;
        match runs {
            Some((r, _)) if r != n => return Err(format!("--passes {n} and --runs {r} disagree: give one")),
            _ => runs = Some((n, "--passes")),
        }
    }
    if let Some(pass) = pass {
        match runs {
            Some((r, flag)) if r != pass.count => {
                return Err(format!(
                    "--pass {pass} renders one of {} passes, but {flag} says {r}: give one",
                    pass.count
                ));
            }
            _ => runs = Some((pass.count, "--pass")),
        }
    }
    Ok((sppm_passes, runs.map_or(1, |(n, _)| n)))
}

/// Warns about options the chosen model does not read.
fn warn_unused_options(args: &RenderArgs, model: Model) {
    let name = model.name();
    if args.photons.is_some() && !model.uses_photons() {
        errln!("warning: --photons has no effect on the {name} model");
    }
    if args.max_depth.is_some() && !model.is_physically_based() {
        errln!("warning: --max-depth has no effect on the {name} model, whose depth is the course's 10");
    }
    if args.spp.is_some() && model == Model::Sppm {
        errln!(
            "warning: --spp has no effect on the sppm model (one camera path a pixel a pass; use --passes)"
        );
    }
}

fn progress_bar(quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    // Draws on stderr, and only when it is a terminal.
    let bar = ProgressBar::new(1).with_message("loading");
    if let Ok(style) =
        ProgressStyle::with_template("{msg:>14} [{bar:40}] {percent:>3}% {elapsed_precise} (eta {eta})")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

/// The summary of a render of `pixels` (what was rendered, as words), after its output path.
pub fn print_summary(
    output: &Path,
    pixels: &str,
    settings: &RenderSettings,
    stats: &RenderStats,
    prepare: Duration,
    render: Duration,
) {
    outln!("wrote {}", output.display());
    if settings.model.is_physically_based() {
        print_physical_summary(pixels, settings, stats, prepare, render);
        return;
    }
    // The photon phase is reported on its own line; the pixel phase is the rest.
    let photon_phase = stats.photons.map_or(Duration::ZERO, |p| p.trace_time + p.build_time);
    if let Some(p) = &stats.photons {
        print_photon_summary(p);
    }
    let seconds = render.saturating_sub(photon_phase).as_secs_f64().max(1e-9);
    let rays_per_second = stats.rays as f64 / seconds;
    outln!(
        "{pixels} in {:.2} s (+{:.2} s to load), {} threads, {} camera samples ({} pixels refined)",
        seconds,
        prepare.as_secs_f64(),
        stats.threads,
        stats.camera_samples,
        stats.refined_pixels,
    );
    outln!(
        "{} rays, {:.1} M rays/s ({:.1} M rays/s per thread)",
        stats.rays,
        rays_per_second / 1e6,
        rays_per_second / 1e6 / stats.threads.max(1) as f64
    );
    if stats.photons.is_some() {
        outln!(
            "{} photon-map lookups, {:.2} M lookups/s",
            stats.lookups,
            stats.lookups as f64 / seconds / 1e6
        );
    }
}

/// The summary of a path or SPPM render: samples (or passes and photons) a second.
fn print_physical_summary(
    pixels: &str,
    settings: &RenderSettings,
    stats: &RenderStats,
    prepare: Duration,
    render: Duration,
) {
    let seconds = render.as_secs_f64().max(1e-9);
    let threads = stats.threads.max(1) as f64;
    outln!(
        "{pixels} in {:.2} s (+{:.2} s to load), {} threads, {} model, paths of at most {} segments",
        seconds,
        prepare.as_secs_f64(),
        stats.threads,
        settings.model.name(),
        settings.max_depth
    );
    match stats.sppm {
        Some(SppmStats { passes, photons, stored, mean_radius, photon_seconds, .. }) => {
            outln!(
                "{passes} passes of {} photons ({photons} emitted, {stored} stored, {:.1} s tracing them), \
                 {:.2} passes/s, {:.2} M photons/s; mean final radius {mean_radius:.4}",
                photons / passes.max(1),
                photon_seconds,
                passes as f64 / seconds,
                photons as f64 / seconds / 1e6,
            );
        }
        None => {
            let spp = settings.path_spp();
            let rate = stats.camera_samples as f64 / seconds;
            let default = spp == DEFAULT_PATH_SPP && settings.sampling == Sampling::Adaptive;
            let passes = match settings.runs {
                1 => String::new(),
                n => format!(" in each of {n} passes"),
            };
            outln!(
                "{spp} samples a pixel{}{passes}, {} samples, {:.2} M samples/s ({:.2} M samples/s per thread)",
                if default { " (default)" } else { "" },
                stats.camera_samples,
                rate / 1e6,
                rate / 1e6 / threads
            );
        }
    }
    outln!(
        "{} rays, {:.1} M rays/s ({:.1} M rays/s per thread)",
        stats.rays,
        stats.rays as f64 / seconds / 1e6,
        stats.rays as f64 / seconds / 1e6 / threads
    );
}

fn print_photon_summary(p: &PhotonStats) {
    let trace = p.trace_time.as_secs_f64();
    let emitted = if p.emitted < p.requested {
        format!("{} of {} photons emitted (the map was full)", p.emitted, p.requested)
    } else {
        format!("{} photons emitted", p.emitted)
    };
    outln!(
        "{emitted} in {trace:.2} s ({:.1} M photons/s), {} stored ({}), search tree built in {:.2} s",
        p.emitted as f64 / trace.max(1e-9) / 1e6,
        p.stored,
        photon::format_bytes(p.map_bytes),
        p.build_time.as_secs_f64()
    );
}

fn print_diagnostics(diagnostics: &[Diagnostic]) {
    print_diagnostics_with(diagnostics, Omitted::default());
}

/// Prints at most [`MAX_KEPT_DIAGNOSTICS`] errors and as many warnings and notes, then one line
/// counting the rest (those beyond the cap here and those the parser only counted).
fn print_diagnostics_with(diagnostics: &[Diagnostic], mut omitted: Omitted) {
    let (mut errors, mut others) = (0, 0);
    for d in diagnostics {
        let (shown, more) = if d.is_error() {
            (&mut errors, &mut omitted.errors)
        } else {
            (&mut others, &mut omitted.others)
        };
        if *shown < MAX_KEPT_DIAGNOSTICS {
            *shown += 1;
            errln!("{d}");
        } else {
            *more += 1;
        }
    }
    let mut parts = Vec::new();
    if omitted.errors > 0 {
        parts.push(format!("{} more error{}", omitted.errors, plural(omitted.errors)));
    }
    if omitted.others > 0 {
        parts.push(format!("{} more warning{} and notes", omitted.others, plural(omitted.others)));
    }
    if !parts.is_empty() {
        errln!("... and {}\n", parts.join(" and "));
    }
}

/// A course scene file parsed, its diagnostics printed.
fn course_scene(source: &SourceFile, args: &RenderArgs) -> Result<scene::Scene, ExitCode> {
    if !args.defines.is_empty() {
        errln!(
            "warning: -D applies to Mitsuba 3 scene files only; `{}` is a course scene file",
            source.name()
        );
    }
    let parsed = scene::parse(source).map_err(|e| {
        print_diagnostics_with(&e.diagnostics, e.omitted);
        let n = e.error_count();
        fail(&format!("`{}` has {n} error{}; nothing was rendered", source.name(), plural(n)))
    })?;
    // With --size, the file's own aspect warning names a size that is not rendered: it is given
    // again below for the size that is.
    let file_aspect = {
        let cam = &parsed.scene.camera;
        args.size.and_then(|_| scene::aspect_mismatch(cam, cam.image_width, cam.image_height))
    };
    let diagnostics: Vec<Diagnostic> = parsed
        .diagnostics
        .iter()
        .filter(|d| d.is_error() || file_aspect.as_deref() != Some(d.message.as_str()))
        .cloned()
        .collect();
    print_diagnostics_with(&diagnostics, parsed.omitted);

    Ok(parsed.scene)
}

/// Whether `source` is a Mitsuba 3 scene file: named `.xml`, or XML by its first character.
fn is_mitsuba_scene(source: &SourceFile) -> bool {
    Path::new(source.name()).extension().is_some_and(|e| e.eq_ignore_ascii_case("xml"))
        || source.text().trim_start_matches('\u{feff}').trim_start().starts_with('<')
}

/// A Mitsuba 3 scene file read (includes, `$name` and `-D`) and built into a scene, its warnings
/// printed; errors name the file, line and column.
fn mitsuba_scene(source: &SourceFile, args: &RenderArgs) -> Result<scene::mitsuba::Built, ExitCode> {
    let name = source.name().to_owned();
    let doc = scene::mitsuba::read_source(source.clone(), &args.defines).map_err(|e| {
        print_diagnostics(&[e.diagnostic()]);
        fail(&format!("`{name}` is not a usable Mitsuba 3 scene file; nothing was rendered"))
    })?;
    let built = scene::mitsuba::build(&doc).map_err(|diagnostics| {
        print_diagnostics(&diagnostics);
        let n = diagnostics.iter().filter(|d| d.is_error()).count();
        fail(&format!("`{name}` has {n} error{}; nothing was rendered", plural(n)))
    })?;
    print_diagnostics(&built.diagnostics);
    let mut built = built;
    // The included files are inputs too (a part's digest covers them).
    built.inputs.extend(doc.files.iter().skip(1).map(|f| PathBuf::from(f.name())));
    Ok(built)
}

fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}

/// Refuses `path` (given as `flag`) when it is the same file as `input`, a file the render reads.
fn refuse_input_as(path: &Path, flag: &str, input: &Path) -> Result<(), ExitCode> {
    if crate::same_file::same_file(path, input) {
        return Err(usage(&format!(
            "{flag} `{}` is `{}`, which the render reads; writing it would destroy an input: give another name",
            path.display(),
            input.display()
        )));
    }
    Ok(())
}

/// The name of an output format, for messages.
pub fn format_name(format: OutputFormat) -> &'static str {
    match format {
        OutputFormat::Png => "PNG",
        OutputFormat::Bmp => "BMP",
        OutputFormat::Exr => "EXR",
        OutputFormat::Hdr => "HDR",
    }
}

/// Prints an error about the command line and returns the exit code of a usage error (2).
pub fn usage(message: &str) -> ExitCode {
    errln!("error: {message}");
    ExitCode::from(2)
}

/// Prints an error and returns the failure exit code.
fn fail(message: &str) -> ExitCode {
    errln!("error: {message}");
    ExitCode::FAILURE
}
