//! The page in a real browser: builds it (`web/build.sh`), serves it on 127.0.0.1, and has
//! `browser.mjs` drive Debian's headless Chromium with WebGPU, with WebGL2 only, and with
//! neither; then checks what it saw: both looks on both APIs, elevation data picked in the file
//! input drawn as the native program draws it (its scene, its camera start), and messages that
//! stay. Needs Debian's `rustc-web cargo-web rust-web-src lld-22
//! chromium`, `wasm-bindgen-cli` and `npm ci` in `web/tests` (as `.ci/run` installs); skipped
//! loudly without them, except under CI.

use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use image::RgbaImage;
use serde_json::Value;
use terrain::render::{Backend, FrameView, Gpu};
use terrain::world::dem;
use terrain::world::procedural::{self, ProceduralOptions};
use terrain::{SceneConfig, Settings};

fn web_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

/// What the test needs that a machine may lack.
fn missing_tools() -> Vec<String> {
    let mut missing = Vec::new();
    for (path, what) in [
        ("/usr/bin/chromium", "chromium"),
        ("/usr/bin/wasm-ld-22", "lld-22"),
        ("/usr/lib/rustlib/src/rust/library/std", "rust-web-src"),
    ] {
        if !Path::new(path).exists() {
            missing.push(what.to_string());
        }
    }
    if !web_dir().join("tests/node_modules/puppeteer-core").is_dir() {
        missing.push("puppeteer-core (npm ci in web/tests)".into());
    }
    if Command::new("wasm-bindgen").arg("--version").output().is_err() {
        missing.push("wasm-bindgen-cli".into());
    }
    missing
}

/// A static file server on a free port of 127.0.0.1, stopped when dropped.
struct Server {
    child: Child,
    port: u16,
}

impl Server {
    fn start(dir: &Path) -> Self {
        let port = TcpListener::bind("127.0.0.1:0").and_then(|l| l.local_addr()).expect("a free port").port();
        let child = Command::new(web_dir().join("serve.sh"))
            .arg(port.to_string())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("web/serve.sh starts");
        let started = Instant::now();
        while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
            assert!(started.elapsed() < Duration::from_secs(30), "the server did not start");
            std::thread::sleep(Duration::from_millis(100));
        }
        assert!(dir.join("index.html").is_file());
        Self { child, port }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        // serve.sh execs Python: killing it stops the server.
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn read_json(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|error| panic!("{}: {error}", path.display()));
    serde_json::from_str(&text).expect("valid JSON")
}

/// A frame `browser.mjs` read back from the page.
fn read_frame(dir: &Path, name: &str, info: &Value) -> RgbaImage {
    let (width, height) =
        (info["width"].as_u64().expect("width") as u32, info["height"].as_u64().expect("height") as u32);
    let bytes = std::fs::read(dir.join(format!("{name}.rgba"))).expect("frame bytes");
    RgbaImage::from_raw(width, height, bytes).expect("a whole frame")
}

/// Mean absolute difference of two images' colour channels, in 8-bit steps.
fn mean_difference(a: &RgbaImage, b: &RgbaImage) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    let sum: u64 = a
        .pixels()
        .zip(b.pixels())
        .flat_map(|(p, q)| (0..3).map(move |c| u64::from(p[c].abs_diff(q[c]))))
        .sum();
    sum as f64 / (3.0 * f64::from(a.width()) * f64::from(a.height()))
}

/// The mean colour of a block of `image` centred on (`x`, `y`).
fn mean_colour(image: &RgbaImage, x: u32, y: u32) -> [f64; 3] {
    let mut sum = [0.0; 3];
    let mut count = 0.0;
    for j in y - 4..=y + 4 {
        for i in x - 4..=x + 4 {
            let pixel = image.get_pixel(i, j);
            for c in 0..3 {
                sum[c] += f64::from(pixel[c]);
            }
            count += 1.0;
        }
    }
    sum.map(|s| s / count)
}

/// Sky at the top, land below it, sea at the horizon, where the native render has them.
fn check_layout(image: &RgbaImage, what: &str) {
    let sky = mean_colour(image, 100, 40);
    assert!(sky[2] > sky[0] + 20.0 && sky[2] > 120.0, "{what}: no sky at the top: {sky:?}");
    let land = mean_colour(image, 160, 320);
    assert!(land[1] > land[2] + 10.0, "{what}: no green land in front: {land:?}");
    let sea = mean_colour(image, 330, 200);
    assert!(sea[2] > sea[0] && sea[1] > sea[0], "{what}: no sea at the horizon: {sea:?}");
}

/// The elevation data the page is given: the shared South Tyrol GeoTIFF (252 x 194 float32
/// samples, 250 m apart, 445 voids, 388 to 3863 m), or where the shared data is missing (a loud
/// skip of that file; a failure under CI) an Esri ASCII grid written here: a ridge from about
/// 800 m up to 2.5 km (valleys below the lake run's 1500 m), 30 m cells.
fn elevation_file(dir: &Path) -> PathBuf {
    let shared = test_skips::shared_data(&web_dir(), "terrain-dem", "the browser test's real DEM");
    if let Some(shared) = shared {
        return shared.join("vinschgau_f32_lzw_utm32n_nodata.tif");
    }
    let (columns, rows) = (160u32, 120u32);
    let mut text = format!(
        "ncols {columns}\nnrows {rows}\nxllcorner 500000\nyllcorner 5000000\ncellsize 30\nNODATA_value -9999\n"
    );
    for row in 0..rows {
        let line: Vec<String> = (0..columns)
            .map(|column| {
                let (x, y) =
                    (f64::from(column) / f64::from(columns) - 0.5, f64::from(row) / f64::from(rows) - 0.5);
                format!(
                    "{:.1}",
                    1000.0 + 1500.0 * (-(x * x * 12.0 + y * y * 3.0)).exp() + 200.0 * (x * 20.0).sin()
                )
            })
            .collect();
        text += &line.join(" ");
        text += "\n";
    }
    let path = dir.join("ridge.asc");
    std::fs::write(&path, text).expect("elevation file");
    path
}

#[test]
fn the_page_draws_moves_and_reports_errors_in_chromium() {
    let missing = missing_tools();
    if !missing.is_empty() {
        let reason = format!("missing {}", missing.join(", "));
        assert!(std::env::var_os("CI").is_none(), "the browser test cannot run under CI: {reason}");
        test_skips::skip("web page in headless Chromium", &reason);
        return;
    }
    let built = Command::new(web_dir().join("build.sh")).status().expect("web/build.sh runs");
    assert!(built.success(), "web/build.sh failed");
    let server = Server::start(&web_dir().join("dist"));
    let out = tempfile::tempdir().expect("temp dir");
    let corrupt = out.path().join("broken-heightmap.png");
    let mut bytes = b"\x89PNG\r\n\x1a\n".to_vec();
    bytes.extend((0..300u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8));
    std::fs::write(&corrupt, bytes).expect("corrupt file");
    let dem_path = elevation_file(out.path());
    let dem_bytes = std::fs::read(&dem_path).expect("elevation data");
    // The same file cut in half: what the native reader says of it, the page must say.
    let corrupt_dem = out
        .path()
        .join(format!("cut-{}", dem_path.file_name().and_then(|name| name.to_str()).expect("a file name")));
    std::fs::write(&corrupt_dem, &dem_bytes[..dem_bytes.len() / 2]).expect("corrupt elevation file");
    let corrupt_dem_name = corrupt_dem.file_name().and_then(|name| name.to_str()).expect("a file name");
    let corrupt_dem_message =
        dem::load_bytes(&dem_bytes[..dem_bytes.len() / 2], corrupt_dem_name, &dem::LoadOptions::default())
            .expect_err("half a file is broken")
            .to_string();
    let status = Command::new("node")
        .arg(web_dir().join("tests/browser.mjs"))
        .args(["--url", &format!("http://127.0.0.1:{}", server.port)])
        .arg("--out")
        .arg(out.path())
        .arg("--corrupt")
        .arg(&corrupt)
        .arg("--dem")
        .arg(&dem_path)
        .arg("--corrupt-dem")
        .arg(&corrupt_dem)
        .current_dir(web_dir().join("tests"))
        .status()
        .expect("node runs");
    drop(server);
    assert!(status.success(), "browser.mjs failed");

    // The same world, camera and time, rendered natively.
    let options = ProceduralOptions { seed: 1, heightmap_size: 512 };
    let config = SceneConfig::default();
    let world = procedural::generate(options, &config, &mut |_| {}).expect("world");
    let gpu = Gpu::headless(Backend::Auto).expect("a GPU (Mesa's lavapipe)");
    let view = FrameView { pose: config.camera_start, field_of_view_degrees: 45.0, time_seconds: 3.0 };
    let native =
        terrain::headless::render_image(&gpu, &world, &config, &Settings::default(), (640, 360), &view)
            .expect("native frame");
    check_layout(&native, "native render");

    // The elevation data as `rayterra terrain --heightmap FILE --screenshot` draws it: its own
    // scene (no sea: it lies above 0 m), from its own camera start.
    let dem_name = dem_path.file_name().and_then(|name| name.to_str()).expect("a file name");
    let loaded = dem::load_bytes(&dem_bytes, dem_name, &dem::LoadOptions::default()).expect("elevation data");
    let dem::DemScene { heightmap, config: dem_config, info } = loaded.scene;
    assert!(!dem_config.sea, "the test's elevation data lies above the sea");
    let (dem_columns, dem_rows) = (heightmap.columns(), heightmap.rows());
    let dem_world = procedural::dress_heightmap(heightmap, 1, &dem_config, &mut |_| {});
    let dem_view = FrameView { pose: dem_config.camera_start, ..view };
    let dem_native = terrain::headless::render_image(
        &gpu,
        &dem_world,
        &dem_config,
        &Settings::default(),
        (640, 360),
        &dem_view,
    )
    .expect("native elevation frame");
    assert!(mean_difference(&dem_native, &native) > 10.0, "the elevation data looks like the island");

    for (mode, api) in [("webgpu", "WebGPU"), ("webgl", "WebGL2")] {
        let report = read_json(&out.path().join(format!("{mode}.json")));
        assert!(report["failure"].is_null(), "{mode}: {}", report["failure"]);
        assert_eq!(report["pageErrors"], serde_json::json!([]), "{mode}: errors on the page");
        let before = &report["before"];
        assert_eq!(before["api"], api, "{mode}: the page reports its API");
        assert!(before["error"].is_null(), "{mode}: {}", before["error"]);
        assert_eq!(before["world"], "procedural island, seed 1, 512x512");
        // Held W: forward is -z at yaw 0.
        let z = |state: &Value| state["camera"][2].as_f64().expect("camera z");
        assert_eq!(z(before), 10.0);
        assert!(z(&report["after"]) < 9.0, "{mode}: W did not move the camera: {}", report["after"]);
        assert!(report["heldFrames"].as_u64().expect("frames") > 3, "{mode}: no frames while W was held");
        // A click captures the mouse; 100 pixels to the right turn the camera to the right.
        let yaw = report["turned"]["camera"][3].as_f64().expect("yaw");
        assert!(yaw > 5.0, "{mode}: the mouse did not turn the camera: {}", report["turned"]);
        let corrupt_message = report["corrupt"].as_str().expect("a message for the corrupt file");
        assert!(
            corrupt_message.contains("broken-heightmap.png is not a readable image"),
            "{mode}: {corrupt_message}"
        );
        assert!(report["afterCorrupt"]["error"].is_null(), "{mode}: the page stopped after the bad file");

        // The elevation data picked in the file input: the page reports its size, cell size and
        // sea, draws it in its own scene and puts the camera at its start.
        let dem_report = &report["dem"];
        let state = &dem_report["state"];
        assert!(state["error"].is_null() && state["failure"].is_null(), "{mode}: elevation data: {state}");
        let world = state["world"].as_str().expect("the world's line");
        assert!(world.starts_with(&format!("elevation data {dem_name}: ")), "{mode}: {world}");
        assert!(world.contains("no sea"), "{mode}: {world}");
        assert_eq!(dem_report["hud"].as_str(), Some(world), "{mode}: the page's status box");
        let elevation = &state["elevation"];
        assert_eq!(elevation["columns"].as_u64(), Some(u64::from(dem_columns)), "{mode}: {elevation}");
        assert_eq!(elevation["rows"].as_u64(), Some(u64::from(dem_rows)), "{mode}: {elevation}");
        assert_eq!(elevation["cellSize"].as_f64(), Some(info.cell_size_metres), "{mode}: {elevation}");
        assert_eq!(elevation["sea"], false, "{mode}: {elevation}");
        assert_eq!(elevation["voids"].as_u64(), Some(info.void_count() as u64), "{mode}: {elevation}");
        assert_eq!(state["scene"]["sea"], false, "{mode}: the page draws a sea: {}", state["scene"]);
        let start = dem_config.camera_start;
        let expected =
            [start.position.x, start.position.y, start.position.z, start.yaw_degrees, start.pitch_degrees];
        for (what, reported) in [("scene's start", &state["scene"]["start"]), ("camera", &state["camera"])] {
            let reported: Vec<f64> =
                reported.as_array().expect("numbers").iter().map(|n| n.as_f64().expect("a number")).collect();
            let close = reported.len() == 5
                && reported.iter().zip(expected).all(|(&got, want)| (got - f64::from(want)).abs() < 1e-4);
            assert!(close, "{mode}: the page's {what} {reported:?}, the native start {expected:?}");
        }
        // A broken elevation file: the native reader's message, naming it; the data stays drawn.
        assert_eq!(dem_report["corrupt"].as_str(), Some(corrupt_dem_message.as_str()), "{mode}");
        assert!(corrupt_dem_message.starts_with(&format!("{corrupt_dem_name}: ")), "{corrupt_dem_message}");
        assert!(dem_report["afterCorrupt"]["error"].is_null(), "{mode}: the page stopped after the bad file");
        assert_eq!(dem_report["afterCorrupt"]["world"].as_str(), Some(world), "{mode}");
        let island_screenshot =
            image::open(out.path().join(format!("{mode}-screenshot.png"))).expect("screenshot").to_rgba8();
        let dem_screenshot = image::open(out.path().join(format!("{mode}-dem-screenshot.png")))
            .expect("screenshot")
            .to_rgba8();
        let apart = mean_difference(&dem_screenshot, &island_screenshot);
        eprintln!("{mode}: the elevation data's screenshot differs from the island's by {apart:.2}");
        assert!(apart > 10.0, "{mode}: the screenshot with the elevation data looks like the island's");
        if dem_report["frame"]["error"].is_string() {
            eprintln!("{mode}: frames cannot be read back here ({})", dem_report["frame"]["error"]);
        } else {
            let frame = read_frame(out.path(), &format!("{mode}-dem-frame"), &dem_report["frame"]);
            let difference = mean_difference(&frame, &dem_native);
            eprintln!("{mode}: elevation data: mean difference from the native render {difference:.2}");
            assert!(
                difference < 1.0,
                "{mode}: the page's elevation frame differs from the native render by {difference:.2}"
            );
        }

        if report["frame"]["error"].is_string() {
            // See browser.mjs: SwiftShader's WebGPU in headless Chromium cannot read frames back.
            eprintln!(
                "{mode}: frames cannot be read back here ({}); pixels checked on WebGL2",
                report["frame"]["error"]
            );
            continue;
        }
        let frame = read_frame(out.path(), &format!("{mode}-frame"), &report["frame"]);
        check_layout(&frame, &format!("{mode} frame"));
        let difference = mean_difference(&frame, &native);
        eprintln!("{mode}: mean difference from the native render {difference:.2} (8-bit steps)");
        assert!(
            difference < 1.0,
            "{mode}: the page's frame differs from the native render by {difference:.2}"
        );
        let moved = read_frame(out.path(), &format!("{mode}-moved"), &report["moved"]);
        assert!(
            mean_difference(&moved, &frame) > 5.0,
            "{mode}: the picture did not change as the camera moved"
        );
        // What the compositor shows (the page's status box covers the top right).
        let screenshot =
            image::open(out.path().join(format!("{mode}-screenshot.png"))).expect("screenshot").to_rgba8();
        check_layout(&screenshot, &format!("{mode} screenshot"));
    }
    // The course look on each API, against the native course render.
    let course =
        terrain::headless::render_image(&gpu, &world, &config, &Settings::course(), (640, 360), &view)
            .expect("native course frame");
    for (mode, run, api) in
        [("webgpu", "course", "WebGPU"), ("webgl", "course", "WebGL2"), ("webgl", "course-webgl", "WebGL2")]
    {
        let what = format!("{mode} browser, {run}");
        let report = &read_json(&out.path().join(format!("{mode}.json")))[run];
        assert!(report["failure"].is_null(), "{what}: {}", report["failure"]);
        assert_eq!(report["pageErrors"], serde_json::json!([]), "{what}: errors on the page");
        for state in [&report["state"], &report["later"]] {
            assert!(state["error"].is_null(), "{what}: the page stopped: {}", state["error"]);
            assert_eq!(state["api"], api, "{what}: the page reports its API");
        }
        let frames = |state: &Value| state["frames"].as_u64().expect("frames");
        assert!(frames(&report["later"]) > frames(&report["state"]), "{what}: no frames after the first");
        if report["frame"]["error"].is_string() && api == "WebGPU" {
            eprintln!("{what}: frames cannot be read back here ({})", report["frame"]["error"]);
            continue;
        }
        assert!(report["frame"]["error"].is_null(), "{what}: {}", report["frame"]["error"]);
        let frame = read_frame(out.path(), &format!("{mode}-{run}-frame"), &report["frame"]);
        let difference = mean_difference(&frame, &course);
        eprintln!("{what}: mean difference from the native course render {difference:.2} (8-bit steps)");
        assert!(
            difference < 1.0,
            "{what}: the frame differs from the native course render by {difference:.2}"
        );
    }

    // The elevation data with the address's `water-level=1500`: a sea over its valleys, drawn as
    // `--water-level 1500` draws it.
    let place =
        dem::PlaceOptions { water_level: dem::WaterLevel::Metres(1500.0), ..dem::PlaceOptions::default() };
    let lake_options = dem::LoadOptions { place, ..dem::LoadOptions::default() };
    let lake = dem::load_bytes(&dem_bytes, dem_name, &lake_options).expect("elevation data").scene;
    assert!(lake.config.sea);
    let lake_view = FrameView { pose: lake.config.camera_start, ..view };
    let lake_world = procedural::dress_heightmap(lake.heightmap, 1, &lake.config, &mut |_| {});
    let lake_native = terrain::headless::render_image(
        &gpu,
        &lake_world,
        &lake.config,
        &Settings::default(),
        (640, 360),
        &lake_view,
    )
    .expect("native lake frame");
    let report = &read_json(&out.path().join("webgl.json"))["dem-lake"];
    assert!(report["failure"].is_null(), "lake: {}", report["failure"]);
    assert_eq!(report["pageErrors"], serde_json::json!([]), "lake: errors on the page");
    let state = &report["state"];
    assert!(state["failure"].is_null(), "lake: {}", state["failure"]);
    assert_eq!(state["scene"]["sea"], true, "lake: no sea drawn: {}", state["scene"]);
    assert_eq!(state["elevation"]["baseMetres"].as_f64(), Some(1500.0), "lake: {}", state["elevation"]);
    let world = state["world"].as_str().expect("the world's line");
    assert!(world.ends_with("; sea at 1500 m"), "lake: {world}");
    assert!(report["frame"]["error"].is_null(), "lake: {}", report["frame"]["error"]);
    let frame = read_frame(out.path(), "webgl-dem-lake-frame", &report["frame"]);
    let difference = mean_difference(&frame, &lake_native);
    eprintln!(
        "webgl: elevation data with water at 1500 m: mean difference from the native render {difference:.2}"
    );
    assert!(difference < 1.0, "lake: the page's frame differs from the native render by {difference:.2}");
    assert!(mean_difference(&lake_native, &dem_native) > 5.0, "the water at 1500 m changes nothing");

    let none = read_json(&out.path().join("none.json"));
    assert!(none["failure"].is_null(), "none: {}", none["failure"]);
    let message = none["error"].as_str().expect("a message without WebGPU and WebGL2");
    assert!(message.contains("neither WebGPU nor WebGL2"), "{message}");
    // Messages that stay: without either API (after the worker's world has come), without
    // WebGL2 when the address asks for it, and for a bad address.
    for (run, says, status, world) in [
        ("no-api", "neither WebGPU nor WebGL2", "no WebGPU or WebGL2", true),
        ("no-webgl", "offers no WebGL2", "no WebGPU or WebGL2", true),
        ("bad-address", "`seed=one` is not a whole number", "the address has an error", false),
    ] {
        let report = &none[run];
        assert!(report["failure"].is_null(), "{run}: {}", report["failure"]);
        assert_eq!(report["pageErrors"], serde_json::json!([]), "{run}: errors on the page");
        let first = report["first"].as_str().expect("a message");
        assert!(first.contains(says), "{run}: {first}");
        let built = report["worldsBuilt"].as_u64().expect("worlds built");
        assert_eq!(built >= 1, world, "{run}: {built} worlds built");
        let later = &report["later"];
        assert_eq!(later["error"].as_str(), Some(first), "{run}: the message did not stay");
        let shown_status = later["status"].as_str().expect("a status line");
        assert!(shown_status.contains(status), "{run}: the status line says {shown_status:?}");
        assert_eq!(later["progress"], false, "{run}: progress shown over the message");
    }
}
