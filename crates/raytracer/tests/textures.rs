//! Texture files as a hostile user could give them: huge pictures in small files, folders and
//! devices, and the course's paths with folders in them.

use std::path::Path;

use raytracer::scene::{self, Diagnostic, Severity, SourceFile};
use raytracer::texture::{MAX_TEXTURE_SIDE, Texture, TextureError};
use raytracer::{MemoryBudget, PreparedScene, TextureSearch};

/// A scene with one textured sphere per texture name, the `i`-th texture on line `8 + 5 i`.
fn scene_with_textures(names: &[&str]) -> String {
    let mut text = String::from("light point\n O= 0 0 5\n color= 1 1 1\nend\n");
    for (i, name) in names.iter().enumerate() {
        text.push_str(&format!("primitive sphere\n O= {i} 3 0\n R= 0.4\n texture= {name}\nend\n"));
    }
    text
}

/// Prepares scene text as if read from `dir/scene.txt`.
fn prepare(dir: &Path, text: &str, budget: &MemoryBudget) -> Result<PreparedScene, Vec<Diagnostic>> {
    std::fs::write(dir.join("scene.txt"), text).expect("write scene");
    let source = SourceFile::read(&dir.join("scene.txt")).expect("readable");
    let parsed = scene::parse(&source).unwrap_or_else(|e| panic!("{e}"));
    let search = TextureSearch { scene_dir: source.dir().map(Path::to_path_buf), extra_dirs: Vec::new() };
    PreparedScene::with_budget(parsed.scene, &search, budget)
}

/// A PNG file whose header claims `width` x `height` pixels (a valid header, no picture).
fn png_header(width: u32, height: u32) -> Vec<u8> {
    fn crc32(bytes: &[u8]) -> u32 {
        let mut crc = !0u32;
        for &b in bytes {
            crc ^= u32::from(b);
            for _ in 0..8 {
                crc = if crc & 1 == 1 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
            }
        }
        !crc
    }
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut header = width.to_be_bytes().to_vec();
    header.extend(height.to_be_bytes());
    header.extend([8, 2, 0, 0, 0]); // 8-bit RGB
    // The header, then an empty picture.
    for (kind, data) in [(b"IHDR", &header[..]), (b"IDAT", &[][..]), (b"IEND", &[][..])] {
        let mut chunk = kind.to_vec();
        chunk.extend(data);
        png.extend((data.len() as u32).to_be_bytes());
        png.extend(&chunk);
        png.extend(crc32(&chunk).to_be_bytes());
    }
    png
}

#[test]
fn textures_over_the_memory_budget_are_refused_at_their_line_before_decoding() {
    let dir = tempfile::tempdir().expect("temp dir");
    // Small files that decode to 1024x1024 grey: 4 MiB kept each, 1 MiB more to decode and 3 MiB to
    // convert to RGB.
    for name in ["a.png", "b.png", "c.png"] {
        image::GrayImage::new(1024, 1024).save(dir.path().join(name)).expect("png");
    }
    let text = scene_with_textures(&["a.png", "b.png", "c.png"]);
    let budget = MemoryBudget::new(16 << 20);
    let errors = prepare(dir.path(), &text, &budget).expect_err("over budget");
    assert_eq!(errors.len(), 1, "{errors:?}");
    let error = errors[0].to_string();
    assert!(error.contains("--> "), "{error}");
    assert!(error.contains("scene.txt:18:11"), "the third texture's line: {error}");
    assert!(
        error.contains("texture `c.png` (1024x1024 pixels) needs 8.0 MiB; with the 16.0 MiB already used, that is over the memory limit of 16.0 MiB"),
        "{error}"
    );
    assert_eq!(budget.used(), 0, "a refused scene gives its memory back");
    // With room for all three, the textures keep 12 MiB of the budget.
    let budget = MemoryBudget::new(32 << 20);
    let prepared = prepare(dir.path(), &text, &budget).expect("fits");
    assert_eq!((prepared.memory_used, budget.used()), (12 << 20, 12 << 20));
}

#[test]
fn a_huge_size_in_a_tiny_file_is_refused_from_its_header() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("bomb.png"), png_header(100_000, 100_000)).expect("write");
    let err = Texture::load(&dir.path().join("bomb.png")).expect_err("too large");
    assert!(matches!(err, TextureError::TooLarge { width: 100_000, height: 100_000, .. }), "{err}");
    let message = err.to_string();
    assert!(message.contains("is 100000x100000 pixels, larger than the 16384 pixels a side"), "{message}");
    // At the limit the header is fine; the missing picture data is the error then.
    let side = MAX_TEXTURE_SIDE;
    std::fs::write(dir.path().join("edge.png"), png_header(side, side)).expect("write");
    let info = Texture::probe(&dir.path().join("edge.png")).expect("a valid header");
    assert_eq!((info.width, info.height, info.kept_bytes), (side, side, 1 << 30));
    assert!(matches!(Texture::load(&dir.path().join("edge.png")), Err(TextureError::Unreadable { .. })));
}

#[test]
fn folders_and_devices_are_named_as_such() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::create_dir(dir.path().join("textures")).expect("mkdir");
    let mut names = vec!["textures"];
    if cfg!(unix) {
        names.push("/dev/zero");
    }
    let errors =
        prepare(dir.path(), &scene_with_textures(&names), &MemoryBudget::default()).expect_err("errors");
    let messages: Vec<String> = errors.iter().map(|d| d.message.clone()).collect();
    assert!(
        messages[0].starts_with("texture `")
            && messages[0].ends_with("textures` is a directory, not an image file"),
        "{messages:?}"
    );
    if cfg!(unix) {
        assert_eq!(messages[1], "texture `/dev/zero` is not a regular file");
    }
}

#[test]
fn course_paths_with_folders_fall_back_to_the_file_name_with_a_note() {
    let dir = tempfile::tempdir().expect("temp dir");
    image::RgbImage::from_pixel(4, 4, image::Rgb([200, 100, 50]))
        .save(dir.path().join("floor.bmp"))
        .expect("bmp");
    let text = scene_with_textures(&["src/floor.bmp", "Raytracing_Implementation/floor.bmp", "floor.bmp"]);
    let prepared = prepare(dir.path(), &text, &MemoryBudget::default()).expect("found by file name");
    let notes = &prepared.diagnostics;
    assert_eq!(notes.len(), 2, "{notes:?}");
    assert_eq!(notes[0].severity, Severity::Note);
    let first = notes[0].to_string();
    assert!(first.contains("`src/floor.bmp` is not there as written; using `"), "{first}");
    assert!(first.contains("floor.bmp`, found by its file name"), "{first}");
    assert!(first.contains("scene.txt:8:11"), "{first}");
    // Not found either way: the message lists both the paths as written and by name.
    let errors = prepare(dir.path(), &scene_with_textures(&["src/wall.bmp"]), &MemoryBudget::default())
        .expect_err("missing");
    let message = &errors[0].message;
    assert!(message.contains("src/wall.bmp") && message.contains("/wall.bmp`"), "{message}");
}

/// Parses and prepares scene `text`, renders it at 80 x 60 with 4 samples a pixel, and returns the
/// 8-bit pixels.
fn render_file_text(text: &str) -> Vec<u8> {
    let source = SourceFile::from_text("nomal.txt", None, text.to_owned());
    let parsed = scene::parse(&source).unwrap_or_else(|e| panic!("{e}"));
    let scene = PreparedScene::new(parsed.scene, &TextureSearch::default()).expect("prepared");
    let settings = raytracer::RenderSettings {
        width: 80,
        height: 60,
        sampling: raytracer::Sampling::Uniform(4),
        threads: Some(2),
        seed: 0,
        ..raytracer::RenderSettings::for_scene(&scene)
    };
    let rendered =
        raytracer::render(&scene, &settings, &|_: raytracer::render::Progress| {}).expect("render");
    rendered.image.to_rgb8(false).into_raw()
}

#[test]
fn nomal_ball_and_nomal_plane_render_as_normal_mapped_sphere_and_plane() {
    // scenes/nomal-shapes.txt, the example of docs/scene-language.md, renders as the same scene
    // written with `primitive sphere` and `primitive plane`, and its normal maps show (without
    // `NT=` the picture differs).
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/nomal-shapes.txt");
    let text = std::fs::read_to_string(&path).expect("scenes/nomal-shapes.txt");
    assert!(text.contains("primitive NomalBall") && text.contains("primitive NomalPlane"));
    let aliased = render_file_text(&text);
    let plain = text
        .replace("primitive NomalBall", "primitive sphere")
        .replace("primitive NomalPlane", "primitive plane");
    assert!(aliased == render_file_text(&plain), "NomalBall/NomalPlane differ from sphere/plane with `NT=`");
    let flat: String =
        plain.lines().filter(|l| !l.trim_start().starts_with("NT=")).map(|l| format!("{l}\n")).collect();
    let unmapped = render_file_text(&flat);
    let changed = aliased.chunks(3).zip(unmapped.chunks(3)).filter(|(a, b)| a != b).count();
    assert!(changed > 80 * 60 / 10, "the normal maps change {changed} pixels of 4800");
}
