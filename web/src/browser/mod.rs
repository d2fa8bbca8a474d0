//! The page (WebAssembly only): what `index.html`'s scripts call.
//!
//! - On the page: [`start`] opens the winit app on the canvas (`app`), [`deliver_world`] hands
//!   it a world with its scene, [`page_state`] tells what it is doing (for people and for the
//!   browser test).
//! - In the worker (`worker.js`): [`generate_world`] and [`heightmap_world`] build a world
//!   without freezing the page, reporting progress, and return it as transferable layers (the
//!   scene's numbers among them: a world from elevation data brings its own).

mod app;
mod layers;
mod page;

use std::cell::RefCell;

use js_sys::{Array, Function, Object, Reflect};
use terrain::SceneConfig;
use terrain::world::World;
use terrain::world::procedural::{self, ProceduralOptions, Progress};
use wasm_bindgen::prelude::*;
use winit::event_loop::EventLoop;
use winit::platform::web::EventLoopExtWebSys;

use crate::address::{MAX_PAGE_SIDE, PageOptions};
use crate::file_world::world_from_file;
use crate::transfer::{world_from_layers, world_into_layers};

/// What the app reports, read by [`page_state`].
#[derive(Debug, Clone, Default)]
struct PageState {
    /// `WebGPU` or `WebGL2`, once the GPU is open.
    api: Option<&'static str>,
    /// The adapter's description.
    adapter: Option<String>,
    /// Frames drawn with a world.
    frames: u64,
    /// The camera: x, y, z (world units), yaw and pitch (degrees).
    camera: [f32; 5],
    /// The world drawn, e.g. `procedural island, seed 1, 512x512`.
    world: Option<String>,
    /// The scene of the world drawn (its sea, camera start, height mapping).
    scene: Option<SceneConfig>,
    /// What the world drawn knows of its elevation data, with its heightmap's size, if it was
    /// made from some.
    elevation: Option<(terrain::world::dem::place::ElevationInfo, u32, u32)>,
    /// Why the page stopped, if it did.
    error: Option<String>,
}

thread_local! {
    static STATE: RefCell<PageState> = RefCell::new(PageState::default());
    /// A world handed over by [`deliver_world`], with its scene, not yet taken by the app.
    static INBOX: RefCell<Option<Delivered>> = const { RefCell::new(None) };
    /// The promises of [`capture`] calls, not yet answered: resolve and reject.
    static CAPTURES: RefCell<Vec<(Function, Function)>> = const { RefCell::new(Vec::new()) };
}

/// The next frame, read back from the GPU: a promise of `{ width, height, data }` (RGBA
/// bytes, rows from the top). A page's compositor may not show a WebGPU canvas to a headless
/// browser's screenshots; this reads what the engine drew, on any API.
#[wasm_bindgen]
pub fn capture() -> js_sys::Promise {
    js_sys::Promise::new(&mut |resolve, reject| {
        CAPTURES.with(|captures| captures.borrow_mut().push((resolve, reject)));
    })
}

/// The [`capture`] promises waiting for a frame.
fn take_capture_requests() -> Vec<(Function, Function)> {
    CAPTURES.with(|captures| std::mem::take(&mut *captures.borrow_mut()))
}

/// Answers `requests` with `image`, or rejects them with the error.
fn answer_captures(requests: Vec<(Function, Function)>, image: Result<image::RgbaImage, String>) {
    let answer = match &image {
        Ok(image) => {
            let object = Object::new();
            let data = js_sys::Uint8Array::from(image.as_raw().as_slice());
            let _ = Reflect::set(&object, &"width".into(), &image.width().into());
            let _ = Reflect::set(&object, &"height".into(), &image.height().into());
            let _ = Reflect::set(&object, &"data".into(), &data);
            Ok(JsValue::from(object))
        }
        Err(message) => Err(JsValue::from(js_sys::Error::new(message))),
    };
    for (resolve, reject) in requests {
        let _ = match &answer {
            Ok(value) => resolve.call1(&JsValue::NULL, value),
            Err(error) => reject.call1(&JsValue::NULL, error),
        };
    }
}

fn report(update: impl FnOnce(&mut PageState)) {
    STATE.with(|state| update(&mut state.borrow_mut()));
}

/// Reports a stop on the page and in [`page_state`]. The message stays (the page's script keeps
/// it over the worker's later news); the status line, if it still says the GPU is starting,
/// says instead that the page stopped.
fn fail(message: String) {
    fail_with_status(message, "stopped (see below)");
}

/// [`fail`], with `status` for the status line if the GPU had not opened.
fn fail_with_status(message: String, status: &str) {
    page::show_error(&message);
    // (`try_borrow`: a panic while the state is being updated must still show its message.)
    let opened = STATE.with(|state| state.try_borrow().is_ok_and(|state| state.api.is_some()));
    if !opened {
        page::set_text("api", status);
    }
    report(|state| state.error = Some(message));
}

/// Shows panics on the page (and in the console) instead of a silent stop.
fn install_panic_hook() {
    std::panic::set_hook(Box::new(|info| {
        let message = format!("rayterra stopped on an internal error: {info}");
        fail(message);
    }));
}

/// Starts the page: reads the options from the address's `query`, opens the app on the canvas
/// `#terrain`, and returns what the page's script needs to ask the worker for the world:
/// `{ seed, grid, width, height }` (`width` and `height` are 0 when the canvas fills the page).
/// A bad address is an error naming the option.
#[wasm_bindgen]
pub fn start(query: &str) -> Result<Object, JsError> {
    install_panic_hook();
    let options = PageOptions::from_query(query).map_err(|error| JsError::new(&error.to_string()))?;
    let (width, height) = options.canvas_size.unwrap_or((0, 0));
    let answer = Object::new();
    for (key, value) in [("seed", options.seed), ("grid", options.grid), ("width", width), ("height", height)]
    {
        let _ = Reflect::set(&answer, &key.into(), &value.into());
    }
    page::list_controls();
    let event_loop =
        EventLoop::new().map_err(|error| JsError::new(&format!("cannot start on this page: {error}")))?;
    event_loop.spawn_app(app::PageApp::new(options));
    Ok(answer)
}

/// A world the worker built, put back together on the page.
struct Delivered {
    world: World,
    /// The scene it is drawn in.
    config: SceneConfig,
    /// What the page says of it.
    description: String,
}

/// Hands the app a world (layers from the worker, the scene's numbers among them) described as
/// `description`.
#[wasm_bindgen]
pub fn deliver_world(layers: &Array, description: &str) -> Result<(), JsError> {
    let layers = layers::from_js(layers).map_err(|message| JsError::new(&message))?;
    let (world, config) = world_from_layers(layers).map_err(|error| JsError::new(&error.to_string()))?;
    let description = description.to_string();
    INBOX.with(|inbox| *inbox.borrow_mut() = Some(Delivered { world, config, description }));
    Ok(())
}

/// The world handed over since the last call, if any.
fn take_delivered() -> Option<Delivered> {
    INBOX.with(|inbox| inbox.borrow_mut().take())
}

/// An object of numbers and other values.
fn object_of(entries: &[(&str, JsValue)]) -> Object {
    let object = Object::new();
    for (key, value) in entries {
        let _ = Reflect::set(&object, &(*key).into(), value);
    }
    object
}

fn numbers(values: &[f32]) -> JsValue {
    values.iter().map(|&value| JsValue::from(value)).collect::<Array>().into()
}

/// What the page is doing: `{ api, adapter, frames, camera: [x, y, z, yaw, pitch], world,
/// scene, elevation, error }` (`null` where not known yet). `scene` is the drawn world's
/// `{ sea, start: [x, y, z, yaw, pitch], unitHeight, levelOffset }` (world units, degrees);
/// `elevation`, for a world made from elevation data, is `{ columns, rows, cellSize, low, high,
/// sea, baseMetres, voids }` (the heightmap drawn, in samples; metres; `voids` counts its samples
/// that were voids, filled), `null` otherwise.
#[wasm_bindgen]
pub fn page_state() -> Object {
    let state = STATE.with(|state| state.borrow().clone());
    let scene = state.scene.map_or(JsValue::NULL, |config| {
        let pose = config.camera_start;
        let start = [pose.position.x, pose.position.y, pose.position.z, pose.yaw_degrees, pose.pitch_degrees];
        object_of(&[
            ("sea", config.sea.into()),
            ("start", numbers(&start)),
            ("unitHeight", config.unit_height.into()),
            ("levelOffset", config.level_offset.into()),
        ])
        .into()
    });
    let elevation = state.elevation.map_or(JsValue::NULL, |(info, columns, rows)| {
        object_of(&[
            ("columns", columns.into()),
            ("rows", rows.into()),
            ("cellSize", info.cell_size_metres.into()),
            ("low", info.range_metres.0.into()),
            ("high", info.range_metres.1.into()),
            ("sea", info.sea.into()),
            ("baseMetres", info.base_metres.into()),
            ("voids", (info.void_count() as f64).into()),
        ])
        .into()
    });
    object_of(&[
        ("api", state.api.map_or(JsValue::NULL, JsValue::from)),
        ("adapter", state.adapter.map_or(JsValue::NULL, JsValue::from)),
        ("frames", JsValue::from(state.frames as f64)),
        ("camera", numbers(&state.camera)),
        ("world", state.world.map_or(JsValue::NULL, JsValue::from)),
        ("scene", scene),
        ("elevation", elevation),
        ("error", state.error.map_or(JsValue::NULL, JsValue::from)),
    ])
}

/// A world's layers and the page's line about it, as the worker hands them over:
/// `{ layers, description }`.
fn built(layers: Array, description: &str) -> Object {
    object_of(&[("layers", layers.into()), ("description", description.into())])
}

/// Calls `progress(fraction, stage)` from the worker (fraction of the whole world, 0 to 1).
fn progress_to(callback: &Function) -> impl FnMut(Progress) + '_ {
    let mut last = -1.0_f32;
    move |progress: Progress| {
        let overall = progress.overall();
        // A report a percent at most: each one is a message to the page.
        if overall - last >= 0.01 || overall >= 1.0 {
            last = overall;
            let _ = callback.call2(&JsValue::NULL, &overall.into(), &progress.stage.describe().into());
        }
    }
}

/// Generates the procedural world of `seed` with a `grid` x `grid` heightmap (in the worker),
/// calling `progress(fraction, stage)` as it goes. Returns `{ layers, description }`.
#[wasm_bindgen]
pub fn generate_world(seed: u32, grid: u32, progress: &Function) -> Result<Object, JsError> {
    install_panic_hook();
    if !(2..=MAX_PAGE_SIDE).contains(&grid) {
        return Err(JsError::new(&format!(
            "a {grid}-sample heightmap is outside the page's 2 to {MAX_PAGE_SIDE}"
        )));
    }
    let options = ProceduralOptions { seed, heightmap_size: grid };
    let config = SceneConfig::default();
    let world = procedural::generate(options, &config, &mut progress_to(progress))
        .map_err(|error| JsError::new(&error.to_string()))?;
    let description = format!("procedural island, seed {seed}, {grid}x{grid}");
    Ok(built(layers::to_js(world_into_layers(world, &config)), &description))
}

/// Builds the world of the file `bytes` named `name` (in the worker) as `rayterra terrain
/// --heightmap` does: elevation data (GeoTIFF, SRTM .hgt, Esri ASCII grid, OpenEXR) with its own
/// scene, placed with the address's `water-level`, `vertical-exaggeration` and `cell-size`, or
/// a heightmap image (8- or 16-bit PNG, BMP, ...), with the textures of the address's `seed`
/// (`query` is the page's address query). Returns `{ layers, description }`; a file that is not
/// a usable heightmap is an error naming it.
#[wasm_bindgen]
pub fn heightmap_world(
    bytes: &[u8],
    name: &str,
    query: &str,
    progress: &Function,
) -> Result<Object, JsError> {
    install_panic_hook();
    let options = PageOptions::from_query(query).map_err(|error| JsError::new(&error.to_string()))?;
    let loaded = world_from_file(bytes, name, options.seed, &options.elevation, &mut progress_to(progress))
        .map_err(|message| JsError::new(&message))?;
    Ok(built(layers::to_js(world_into_layers(loaded.world, &loaded.config)), &loaded.description))
}
