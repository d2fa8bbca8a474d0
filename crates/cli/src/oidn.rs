//! Intel Open Image Denoise (OIDN 2.x), loaded at run time: the `RT` filter over a linear image
//! with albedo and normal auxiliary images (`rayterra render --denoise`).
//!
//! Nothing is needed at build time. The library is looked for, in this order (the first that
//! loads and has every function used here wins):
//! 1. `OIDN_DIR`: a folder holding `libOpenImageDenoise.so.2` (or its `lib/` subfolder), or the
//!    library file itself;
//! 2. `system`: `libOpenImageDenoise.so.2` on the system's library path (`LD_LIBRARY_PATH`, the
//!    loader's cache);
//! 3. `venv`: the `pyoidn` wheel installed in a virtual environment `target/*-venv` of the
//!    repository (found from the folders above the executable and the working directory);
//! 4. `python`: the `pyoidn` package that `python3` on the `PATH` finds.
//!
//! `RAYTERRA_OIDN_SEARCH` (a comma-separated list of `system`, `venv`, `python`, or `none`)
//! replaces the list after `OIDN_DIR`, for tests and for users who want to pin the library.
//!
//! This is the one module of the workspace with `unsafe` code: calls into the C library through
//! function pointers checked at load time. A library that is missing, is not OIDN, or fails
//! (every call is followed by `oidnGetDeviceError`) gives an error, never a crash.
#![allow(unsafe_code)]

use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::path::{Path, PathBuf};

use libloading::Library;

/// The library's file name (the 2.x ABI).
pub const LIBRARY: &str = "libOpenImageDenoise.so.2";
/// The `pyoidn` wheel that carries the library, as the error message recommends it.
pub const PYOIDN: &str = "pyoidn==2.5.1.0";

/// `OIDN_DEVICE_TYPE_CPU`.
const DEVICE_TYPE_CPU: c_int = 1;
/// `OIDN_FORMAT_FLOAT3`.
const FORMAT_FLOAT3: c_int = 3;
/// `OIDN_ERROR_NONE`.
const ERROR_NONE: c_int = 0;

type Device = *mut c_void;
type Filter = *mut c_void;

/// The entry points used, copied out of the library (valid while it stays loaded).
struct Api {
    new_device: unsafe extern "C" fn(c_int) -> Device,
    set_device_int: unsafe extern "C" fn(Device, *const c_char, c_int),
    commit_device: unsafe extern "C" fn(Device),
    get_device_error: unsafe extern "C" fn(Device, *mut *const c_char) -> c_int,
    release_device: unsafe extern "C" fn(Device),
    new_filter: unsafe extern "C" fn(Device, *const c_char) -> Filter,
    set_shared_filter_image:
        unsafe extern "C" fn(Filter, *const c_char, *mut c_void, c_int, usize, usize, usize, usize, usize),
    set_filter_bool: unsafe extern "C" fn(Filter, *const c_char, bool),
    commit_filter: unsafe extern "C" fn(Filter),
    execute_filter: unsafe extern "C" fn(Filter),
    release_filter: unsafe extern "C" fn(Filter),
}

/// A loaded OIDN library.
pub struct Oidn {
    api: Api,
    path: PathBuf,
    // Last, so that it is unloaded after everything else (the function pointers point into it).
    _library: Library,
}

impl std::fmt::Debug for Oidn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Oidn").field("path", &self.path).finish_non_exhaustive()
    }
}

/// Where to look for the library (see the module notes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Source {
    System,
    Venv,
    Python,
}

impl Oidn {
    /// Finds and loads the library (see the module notes), or says what was tried and how to
    /// install it.
    pub fn find() -> Result<Oidn, String> {
        let mut tried = Vec::new();
        if let Some(dir) = std::env::var_os("OIDN_DIR").filter(|d| !d.is_empty()) {
            let dir = PathBuf::from(dir);
            let candidates = if dir.is_file() {
                vec![dir.clone()]
            } else {
                vec![dir.join(LIBRARY), dir.join("lib").join(LIBRARY)]
            };
            for path in candidates {
                match Oidn::load(&path) {
                    Ok(oidn) => return Ok(oidn),
                    Err(e) => tried.push(format!("OIDN_DIR: {e}")),
                }
            }
        }
        let sources = match std::env::var("RAYTERRA_OIDN_SEARCH") {
            Ok(list) => parse_sources(&list)?,
            Err(_) => vec![Source::System, Source::Venv, Source::Python],
        };
        for source in sources {
            let paths = match source {
                Source::System => vec![PathBuf::from(LIBRARY)],
                Source::Venv => venv_candidates(),
                Source::Python => python_candidates(),
            };
            if paths.is_empty() {
                tried.push(format!("{}: no pyoidn found", source_name(source)));
            }
            for path in paths {
                match Oidn::load(&path) {
                    Ok(oidn) => return Ok(oidn),
                    Err(e) => tried.push(format!("{}: {e}", source_name(source))),
                }
            }
        }
        let mut message = format!(
            "--denoise needs Intel Open Image Denoise ({LIBRARY}), which was not found; install it with \
             `pip install {PYOIDN}` (into the `python3` on your PATH or a virtual environment under \
             target/), or set OIDN_DIR to the folder that holds {LIBRARY}"
        );
        for t in tried {
            message.push_str("\n  = tried ");
            message.push_str(&t);
        }
        Err(message)
    }

    /// Loads the library at `path` (a bare file name: the system's search) and looks up every
    /// function used.
    fn load(path: &Path) -> Result<Oidn, String> {
        // SAFETY: loading a shared library runs its initialisers. The paths are the ones the user
        // pointed at (OIDN_DIR) or OIDN's own file name in the places it is installed; the
        // official library's initialisers only register its devices.
        let library = unsafe { Library::new(path) }.map_err(|e| format!("`{}`: {e}", path.display()))?;
        macro_rules! symbol {
            ($name:literal) => {
                // SAFETY: the type is the one OIDN 2.x's header (oidn.h) declares for this function;
                // the pointer is copied out and used only while `library` is kept loaded (in `Oidn`).
                *unsafe { library.get(concat!($name, "\0").as_bytes()) }.map_err(|e| {
                    format!("`{}` is not Open Image Denoise 2.x (no `{}`: {e})", path.display(), $name)
                })?
            };
        }
        let api = Api {
            new_device: symbol!("oidnNewDevice"),
            set_device_int: symbol!("oidnSetDeviceInt"),
            commit_device: symbol!("oidnCommitDevice"),
            get_device_error: symbol!("oidnGetDeviceError"),
            release_device: symbol!("oidnReleaseDevice"),
            new_filter: symbol!("oidnNewFilter"),
            set_shared_filter_image: symbol!("oidnSetSharedFilterImage"),
            set_filter_bool: symbol!("oidnSetFilterBool"),
            commit_filter: symbol!("oidnCommitFilter"),
            execute_filter: symbol!("oidnExecuteFilter"),
            release_filter: symbol!("oidnReleaseFilter"),
        };
        Ok(Oidn { api, path: path.to_path_buf(), _library: library })
    }

    /// The file the library was loaded from (a bare name when the system's search found it).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Denoises the linear HDR image `color` (`width * height` pixels, top row first) with the
    /// `RT` filter in `hdr` mode, guided by `albedo` (in [0, 1]) and `normal` (world space), on a
    /// CPU device of `threads` threads (OIDN's choice when `None`).
    pub fn denoise(
        &self,
        width: u32,
        height: u32,
        color: &[[f32; 3]],
        albedo: &[[f32; 3]],
        normal: &[[f32; 3]],
        threads: Option<usize>,
    ) -> Result<Vec<[f32; 3]>, String> {
        let n = width as usize * height as usize;
        if n == 0 || color.len() != n || albedo.len() != n || normal.len() != n {
            return Err(format!("internal error: the images to denoise are not all {width}x{height} pixels"));
        }
        let threads = threads.map(|t| c_int::try_from(t).unwrap_or(c_int::MAX));
        // OIDN reads its inputs through mutable pointers: give it copies of its own.
        let mut color = color.to_vec();
        let mut albedo = albedo.to_vec();
        let mut normal = normal.to_vec();
        let mut output = vec![[0f32; 3]; n];
        let api = &self.api;
        // SAFETY: `oidnNewDevice` takes a device type and returns a handle or null.
        let device = DeviceGuard { api, device: unsafe { (api.new_device)(DEVICE_TYPE_CPU) } };
        if device.device.is_null() {
            return Err(format!(
                "Open Image Denoise has no CPU device: {}",
                self.error(std::ptr::null_mut())
            ));
        }
        let d = device.device;
        if let Some(t) = threads {
            // SAFETY: a live device and a NUL-terminated parameter name.
            unsafe { (api.set_device_int)(d, c"numThreads".as_ptr(), t) };
            self.check(d, "setting its thread count")?;
        }
        // SAFETY: a live device, not yet committed.
        unsafe { (api.commit_device)(d) };
        self.check(d, "starting the CPU device")?;
        // SAFETY: a live, committed device and a NUL-terminated filter type.
        let filter = FilterGuard { api, filter: unsafe { (api.new_filter)(d, c"RT".as_ptr()) } };
        self.check(d, "creating the RT filter")?;
        if filter.filter.is_null() {
            return Err("Open Image Denoise made no RT filter".into());
        }
        let f = filter.filter;
        for (name, image) in
            [("color", &mut color), ("albedo", &mut albedo), ("normal", &mut normal), ("output", &mut output)]
        {
            let name = CString::new(name).map_err(|e| e.to_string())?;
            // SAFETY: `image` holds `width * height` packed FLOAT3 pixels (12 bytes, rows of
            // `width`: strides 0 ask OIDN to compute exactly these) and outlives the filter,
            // which is released (by its guard) before these vectors are dropped.
            unsafe {
                (api.set_shared_filter_image)(
                    f,
                    name.as_ptr(),
                    image.as_mut_ptr().cast(),
                    FORMAT_FLOAT3,
                    width as usize,
                    height as usize,
                    0,
                    0,
                    0,
                )
            };
            self.check(d, "setting its images")?;
        }
        // SAFETY: a live filter and a NUL-terminated parameter name.
        unsafe { (api.set_filter_bool)(f, c"hdr".as_ptr(), true) };
        self.check(d, "setting hdr mode")?;
        // SAFETY: a live filter whose images were all set above.
        unsafe { (api.commit_filter)(f) };
        self.check(d, "preparing the filter")?;
        // SAFETY: a committed filter; it runs synchronously and writes `output` only.
        unsafe { (api.execute_filter)(f) };
        self.check(d, "denoising")?;
        drop(filter);
        drop(device);
        Ok(output)
    }

    /// The device's pending error as `Err`, naming what was being done.
    fn check(&self, device: Device, doing: &str) -> Result<(), String> {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: `device` is live (or null, which OIDN accepts); `message` is a valid out pointer.
        let code = unsafe { (self.api.get_device_error)(device, &mut message) };
        if code == ERROR_NONE {
            return Ok(());
        }
        Err(format!("Open Image Denoise failed {doing}: {} (error {code})", message_text(message)))
    }

    /// The pending error of `device` (null: of the last device creation), as text.
    fn error(&self, device: Device) -> String {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: as in `check`.
        let code = unsafe { (self.api.get_device_error)(device, &mut message) };
        format!("{} (error {code})", message_text(message))
    }
}

/// The text of an OIDN error message (null: none).
fn message_text(message: *const c_char) -> String {
    if message.is_null() {
        return "no message".into();
    }
    // SAFETY: OIDN returns a NUL-terminated string that stays valid until the next call on the
    // device; it is copied at once.
    unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned()
}

/// Releases a device when dropped.
struct DeviceGuard<'a> {
    api: &'a Api,
    device: Device,
}

impl Drop for DeviceGuard<'_> {
    fn drop(&mut self) {
        if !self.device.is_null() {
            // SAFETY: a device handle from `oidnNewDevice`, released once.
            unsafe { (self.api.release_device)(self.device) };
        }
    }
}

/// Releases a filter when dropped.
struct FilterGuard<'a> {
    api: &'a Api,
    filter: Filter,
}

impl Drop for FilterGuard<'_> {
    fn drop(&mut self) {
        if !self.filter.is_null() {
            // SAFETY: a filter handle from `oidnNewFilter`, released once.
            unsafe { (self.api.release_filter)(self.filter) };
        }
    }
}

fn source_name(source: Source) -> &'static str {
    match source {
        Source::System => "system",
        Source::Venv => "venv",
        Source::Python => "python",
    }
}

/// Reads `RAYTERRA_OIDN_SEARCH`.
fn parse_sources(list: &str) -> Result<Vec<Source>, String> {
    let mut sources = Vec::new();
    for word in list.split(',').map(str::trim).filter(|w| !w.is_empty()) {
        match word {
            "none" => {}
            "system" => sources.push(Source::System),
            "venv" => sources.push(Source::Venv),
            "python" => sources.push(Source::Python),
            other => {
                return Err(format!(
                    "RAYTERRA_OIDN_SEARCH: unknown place `{other}`; expected a comma-separated list of \
                     system, venv, python, or none"
                ));
            }
        }
    }
    Ok(sources)
}

/// The library in a `pyoidn` package folder.
fn in_package(package: &Path) -> PathBuf {
    package.join("oidn").join("lib").join(LIBRARY)
}

/// `pyoidn` in the virtual environments `target/*-venv` of the repositories above the executable
/// and the working directory, sorted by path (so the choice does not depend on the file system's
/// order).
fn venv_candidates() -> Vec<PathBuf> {
    let mut starts = Vec::new();
    if let Ok(exe) = std::env::current_exe() {
        starts.push(exe);
    }
    if let Ok(dir) = std::env::current_dir() {
        starts.push(dir);
    }
    let mut found = Vec::new();
    for start in &starts {
        for dir in start.ancestors() {
            let target = if dir.file_name().is_some_and(|n| n == "target") {
                dir.to_path_buf()
            } else {
                dir.join("target")
            };
            for venv in sorted_entries(&target)
                .into_iter()
                .filter(|p| p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.ends_with("-venv")))
            {
                for lib in sorted_entries(&venv.join("lib")) {
                    let package = lib.join("site-packages").join("pyoidn");
                    let path = in_package(&package);
                    if path.is_file() && !found.contains(&path) {
                        found.push(path);
                    }
                }
            }
        }
    }
    found
}

/// The entries of a folder, sorted (none when it cannot be read).
fn sorted_entries(dir: &Path) -> Vec<PathBuf> {
    let mut entries: Vec<PathBuf> = match std::fs::read_dir(dir) {
        Ok(read) => read.filter_map(|e| e.ok().map(|e| e.path())).collect(),
        Err(_) => Vec::new(),
    };
    entries.sort();
    entries
}

/// `pyoidn` as `python3` on the `PATH` finds it (without importing it, which would need numpy).
fn python_candidates() -> Vec<PathBuf> {
    let script = "import importlib.util as u\ns = u.find_spec('pyoidn')\n\
                  print(s.submodule_search_locations[0] if s and s.submodule_search_locations else '')";
    let Ok(out) = std::process::Command::new("python3")
        .args(["-c", script])
        .stdin(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .output()
    else {
        return Vec::new();
    };
    let text = String::from_utf8_lossy(&out.stdout);
    let dir = text.trim();
    if !out.status.success() || dir.is_empty() {
        return Vec::new();
    }
    vec![in_package(Path::new(dir))]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_search_list_is_read_strictly() {
        assert_eq!(parse_sources("none"), Ok(vec![]));
        assert_eq!(parse_sources("venv, system"), Ok(vec![Source::Venv, Source::System]));
        assert!(parse_sources("pip").is_err_and(|e| e.contains("`pip`")));
    }

    #[test]
    fn a_library_that_is_not_oidn_is_refused_without_a_crash() {
        // The C library loads, but has none of OIDN's functions.
        let e = Oidn::load(Path::new("libc.so.6")).expect_err("not OIDN");
        assert!(e.contains("is not Open Image Denoise 2.x (no `oidnNewDevice`"), "{e}");
        let dir = tempfile::tempdir().expect("a temporary folder");
        let fake = dir.path().join(LIBRARY);
        std::fs::write(&fake, b"not a library").expect("written");
        let e = Oidn::load(&fake).expect_err("not a library");
        assert!(e.contains(&fake.display().to_string()), "{e}");
    }
}
