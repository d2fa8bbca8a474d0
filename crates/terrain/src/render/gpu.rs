//! The GPU: a wgpu instance, adapter, device and queue on a chosen backend.

use std::fmt;
use std::str::FromStr;
use std::sync::{Arc, Mutex};

/// Which graphics API to draw with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Backend {
    /// The platform's primary APIs (Vulkan, Metal, Direct3D 12, or WebGPU), best adapter first.
    Auto,
    /// Vulkan only (on Linux without a GPU: Mesa's lavapipe).
    Vulkan,
    /// OpenGL / OpenGL ES only, through EGL on Linux (without a GPU: Mesa's llvmpipe).
    Gl,
    /// Metal only (macOS).
    Metal,
    /// Direct3D 12 only (Windows).
    Dx12,
}

impl Backend {
    /// Every choice, in the order a help text lists them.
    pub const ALL: [Backend; 5] =
        [Backend::Auto, Backend::Vulkan, Backend::Gl, Backend::Metal, Backend::Dx12];

    /// The wgpu backends this choice allows.
    pub fn backends(self) -> wgpu::Backends {
        match self {
            Backend::Auto => wgpu::Backends::PRIMARY,
            Backend::Vulkan => wgpu::Backends::VULKAN,
            Backend::Gl => wgpu::Backends::GL,
            Backend::Metal => wgpu::Backends::METAL,
            Backend::Dx12 => wgpu::Backends::DX12,
        }
    }

    /// The name used on command lines: `auto`, `vulkan`, `gl`, `metal` or `dx12`.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Auto => "auto",
            Backend::Vulkan => "vulkan",
            Backend::Gl => "gl",
            Backend::Metal => "metal",
            Backend::Dx12 => "dx12",
        }
    }
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Backend {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        Backend::ALL.into_iter().find(|backend| backend.name().eq_ignore_ascii_case(text)).ok_or_else(|| {
            let names: Vec<_> = Backend::ALL.iter().map(|b| b.name()).collect();
            format!("unknown backend `{text}` (expected one of: {})", names.join(", "))
        })
    }
}

/// Why the GPU could not be set up or used.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter exists for the backend (no driver, or no device it can use).
    #[error(
        "no graphics adapter found for the {backend} backend ({reason}); on Linux without a GPU, install Mesa's software drivers (mesa-vulkan-drivers for Vulkan, libegl1 and libgl1-mesa-dri for GL)"
    )]
    NoAdapter {
        /// The backend asked for.
        backend: Backend,
        /// What wgpu said.
        reason: String,
    },
    /// The adapter refused to open a device.
    #[error("the graphics adapter {adapter} refused to open a device: {source}")]
    Device {
        /// The adapter.
        adapter: String,
        /// What wgpu said.
        source: wgpu::RequestDeviceError,
    },
    /// The device reported errors (validation, out of memory or internal).
    #[error("the GPU reported: {}", messages.join("; "))]
    Reported {
        /// The errors, in the order they happened.
        messages: Vec<String>,
    },
    /// The GPU ran out of memory creating or filling something.
    #[error("the GPU ran out of memory for the {what}: {message}{}", advice())]
    OutOfMemory {
        /// What was being made.
        what: String,
        /// What wgpu said.
        message: String,
    },
    /// What a world needs does not fit in the memory at hand, checked before it is made.
    #[error(
        "the {what} needs about {} but only {} {}{}",
        megabytes(*needed),
        megabytes(*available),
        where_from,
        advice()
    )]
    NotEnoughMemory {
        /// What would be made.
        what: String,
        /// Bytes it needs.
        needed: u64,
        /// Bytes at hand.
        available: u64,
        /// Which limit gives `available` (e.g. "are free in the address space (ulimit -v)").
        where_from: String,
    },
    /// The device could not finish its work.
    #[error("waiting for the GPU failed: {0}")]
    Poll(#[from] wgpu::PollError),
    /// Reading back a rendered image failed.
    #[error("reading the image back from the GPU failed: {0}")]
    Readback(String),
}

/// An open GPU device. Errors the device reports are collected, not fatal: check them with
/// [`Gpu::check`] after a piece of work.
#[derive(Debug)]
pub struct Gpu {
    /// The wgpu instance the adapter comes from.
    pub instance: wgpu::Instance,
    /// The adapter in use.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// The device's queue.
    pub queue: wgpu::Queue,
    backend: Backend,
    errors: Arc<Mutex<Vec<String>>>,
}

impl Gpu {
    /// A wgpu instance limited to `backend` (never silently falling back to another API).
    /// `display` is the windowing system's display handle (required by GL to present; `None`
    /// off-screen).
    pub fn instance(
        backend: Backend,
        display: Option<Box<dyn wgpu::wgt::WgpuHasDisplayHandle>>,
    ) -> wgpu::Instance {
        let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle();
        descriptor.backends = backend.backends();
        descriptor.display = display;
        wgpu::Instance::new(descriptor)
    }

    /// Opens a device for drawing off-screen on `backend`.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn headless(backend: Backend) -> Result<Self, GpuError> {
        Self::open(Self::instance(backend, None), backend, None)
    }

    /// Opens a device from `instance` on `backend`, able to present to `surface` if given.
    /// The device gets the adapter's full limits, so large heightmaps fit where the GPU allows.
    /// Blocks until the device is open (in a browser, use [`Gpu::open_async`]).
    #[cfg(not(target_arch = "wasm32"))]
    pub fn open(
        instance: wgpu::Instance,
        backend: Backend,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Self, GpuError> {
        pollster::block_on(Self::open_async(instance, backend, surface))
    }

    /// [`Gpu::open`] without blocking: what a web page awaits (a browser cannot block).
    pub async fn open_async(
        instance: wgpu::Instance,
        backend: Backend,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Self, GpuError> {
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: surface,
                apply_limit_buckets: false,
            })
            .await
            .map_err(|error| GpuError::NoAdapter { backend, reason: error.to_string() })?;
        // Wireframe where the GPU can draw lines (the tuning panel's switch).
        let optional = wgpu::Features::POLYGON_MODE_LINE;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("rayterra terrain"),
                required_features: adapter.features() & optional,
                required_limits: adapter.limits(),
                experimental_features: wgpu::ExperimentalFeatures::disabled(),
                memory_hints: wgpu::MemoryHints::Performance,
                trace: wgpu::Trace::Off,
            })
            .await
            .map_err(|source| GpuError::Device { adapter: describe(&adapter.get_info()), source })?;
        let errors = Arc::new(Mutex::new(Vec::new()));
        let sink = Arc::clone(&errors);
        device.on_uncaptured_error(Arc::new(move |error: wgpu::Error| {
            if let Ok(mut list) = sink.lock() {
                list.push(error.to_string());
            }
        }));
        Ok(Self { instance, adapter, device, queue, backend, errors })
    }

    /// The backend this device was asked for.
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// The adapter's name, driver and API, e.g. `llvmpipe (LLVM 19.1.7, 256 bits) [Vulkan, Cpu]`.
    pub fn describe(&self) -> String {
        describe(&self.adapter.get_info())
    }

    /// Whether the device can draw the terrain's triangle edges (wireframe).
    pub fn has_wireframe(&self) -> bool {
        self.device.features().contains(wgpu::Features::POLYGON_MODE_LINE)
    }

    /// Whether the adapter is a software rasteriser (e.g. Mesa's lavapipe or llvmpipe).
    pub fn is_software(&self) -> bool {
        self.adapter.get_info().device_type == wgpu::DeviceType::Cpu
    }

    /// The errors the device reported since the last check, as an error (none: `Ok`).
    pub fn check(&self) -> Result<(), GpuError> {
        let messages = match self.errors.lock() {
            Ok(mut list) => std::mem::take(&mut *list),
            Err(poisoned) => std::mem::take(&mut *poisoned.into_inner()),
        };
        if messages.is_empty() { Ok(()) } else { Err(GpuError::Reported { messages }) }
    }

    /// Runs `make` (creating and filling GPU resources for the `what`) inside error scopes, so
    /// that running out of memory, or anything the device refuses, becomes an error naming
    /// `what` instead of an invalid resource that fails (or panics) when it is first used.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn scoped<T>(&self, what: &str, make: impl FnOnce() -> T) -> Result<T, GpuError> {
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let internal = self.device.push_error_scope(wgpu::ErrorFilter::Internal);
        let memory = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let made = make();
        // Scopes pop in the reverse order of their pushing.
        let memory = pollster::block_on(memory.pop());
        let internal = pollster::block_on(internal.pop());
        let validation = pollster::block_on(validation.pop());
        match (memory, internal, validation) {
            (Some(error), _, _) => {
                Err(GpuError::OutOfMemory { what: what.to_string(), message: error.to_string() })
            }
            (None, Some(error), _) | (None, None, Some(error)) => Err(scope_error(what, &error)),
            (None, None, None) => Ok(made),
        }
    }

    /// In a browser the scopes' answers come later (a page cannot wait for them): what they
    /// report, naming `what`, joins the errors [`Gpu::check`] returns after the next frames.
    #[cfg(target_arch = "wasm32")]
    pub fn scoped<T>(&self, what: &str, make: impl FnOnce() -> T) -> Result<T, GpuError> {
        let filters =
            [wgpu::ErrorFilter::Validation, wgpu::ErrorFilter::Internal, wgpu::ErrorFilter::OutOfMemory];
        let scopes = filters.map(|filter| self.device.push_error_scope(filter));
        let made = make();
        // Scopes pop in the reverse order of their pushing.
        let answers: Vec<_> = scopes.into_iter().rev().map(|scope| scope.pop()).collect();
        let (what, sink) = (what.to_string(), Arc::clone(&self.errors));
        wasm_bindgen_futures::spawn_local(async move {
            for (answer, out_of_memory) in answers.into_iter().zip([true, false, false]) {
                let Some(error) = answer.await else { continue };
                let error = if out_of_memory {
                    GpuError::OutOfMemory { what: what.clone(), message: error.to_string() }
                } else {
                    scope_error(&what, &error)
                };
                if let Ok(mut list) = sink.lock() {
                    list.push(error.to_string());
                }
            }
        });
        Ok(made)
    }

    /// Checks that `bytes` more for the `what` fit in the memory at hand. A software adapter
    /// (lavapipe, llvmpipe) keeps its "GPU" memory in this process, so there the memory the
    /// system has free and the room left under the address-space limit (`ulimit -v`) are
    /// checked; a hardware GPU's own memory cannot be queried portably, and is left to the
    /// error scopes of [`Gpu::scoped`].
    pub fn reserve(&self, what: &str, bytes: u64) -> Result<(), GpuError> {
        if !self.is_software() {
            return Ok(());
        }
        match super::memory::at_hand() {
            Some((available, where_from)) if bytes > available => Err(GpuError::NotEnoughMemory {
                what: what.to_string(),
                needed: bytes,
                available,
                where_from: where_from.to_string(),
            }),
            _ => Ok(()),
        }
    }

    /// Blocks until the GPU has finished all submitted work, then reports its errors.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn finish(&self) -> Result<(), GpuError> {
        self.device.poll(wgpu::PollType::wait_indefinitely())?;
        self.check()
    }
}

/// An error a scope caught while making the `what`.
fn scope_error(what: &str, error: &wgpu::Error) -> GpuError {
    GpuError::Reported { messages: vec![format!("making the {what}: {error}")] }
}

fn megabytes(bytes: u64) -> String {
    format!("{:.0} MB", bytes as f64 / 1e6)
}

fn advice() -> &'static str {
    "; try a smaller heightmap (--grid, --heightmap), a smaller --size, or close other programs"
}

fn describe(info: &wgpu::AdapterInfo) -> String {
    let driver = if info.driver_info.is_empty() { String::new() } else { format!(" ({})", info.driver_info) };
    let device = match info.device_type {
        wgpu::DeviceType::IntegratedGpu => "integrated GPU",
        wgpu::DeviceType::DiscreteGpu => "discrete GPU",
        wgpu::DeviceType::VirtualGpu => "virtual GPU",
        wgpu::DeviceType::Cpu => "software, on the CPU",
        wgpu::DeviceType::Other => "other device",
    };
    let backend = match info.backend {
        wgpu::Backend::Vulkan => "Vulkan",
        wgpu::Backend::Metal => "Metal",
        wgpu::Backend::Dx12 => "Direct3D 12",
        wgpu::Backend::Gl => "OpenGL",
        wgpu::Backend::BrowserWebGpu => "WebGPU",
        wgpu::Backend::Noop => "no backend",
    };
    format!("{}{driver} [{backend}, {device}]", info.name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backend_names_round_trip() {
        for backend in Backend::ALL {
            assert_eq!(backend.name().parse::<Backend>(), Ok(backend));
        }
        assert_eq!("Vulkan".parse::<Backend>(), Ok(Backend::Vulkan));
        let error = "glide".parse::<Backend>().expect_err("unknown");
        assert!(error.contains("vulkan"), "{error}");
    }
}
