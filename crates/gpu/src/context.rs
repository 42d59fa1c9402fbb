//! The device: adapter choice checked against a pipeline's requirements, the device and
//! queue, validation errors as Rust errors (see the crate docs).

use std::sync::{Arc, Mutex};

use crate::requirements::{Requirements, Verdict};

/// Errors of the GPU layer.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter could be found or created.
    #[error("no GPU adapter found ({tried}); {hint}")]
    NoAdapter {
        /// What was tried.
        tried: String,
        /// What to install or set.
        hint: String,
    },
    /// The adapter refused to create a device.
    #[error("cannot create a device on {adapter}: {message}")]
    RequestDevice {
        /// Adapter name.
        adapter: String,
        /// wgpu's message.
        message: String,
    },
    /// wgpu reported a validation, out-of-memory or internal error.
    #[error("wgpu {kind} error in {label}: {message}")]
    Wgpu {
        /// What was being done.
        label: String,
        /// "validation", "out-of-memory" or "internal".
        kind: &'static str,
        /// wgpu's message.
        message: String,
    },
    /// Adapters exist, but none has what the pipeline needs.
    #[error("no adapter can run this pipeline ({details}); {hint}")]
    NoSuitableAdapter {
        /// Each adapter seen (name, backend) with what it lacks.
        details: String,
        /// What to install or set.
        hint: String,
    },
    /// The driver refused an allocation (or [`GpuContext::refuse_allocation`] made it).
    #[error(
        "out of GPU memory: the driver refused {} for {resource}",
        crate::alloc::mib_text(*bytes)
    )]
    OutOfMemory {
        /// What was being allocated (the buffer's or texture's label).
        resource: String,
        /// Its size in bytes.
        bytes: u64,
    },
    /// Waiting for the device or mapping a buffer failed.
    #[error("GPU readback of {label} failed: {message}")]
    Readback {
        /// What was being read.
        label: String,
        /// Why.
        message: String,
    },
    /// The device was lost: a driver reset, the GPU removed or switched, or
    /// [`GpuContext::inject_device_loss`].
    #[error("the GPU device was lost ({reason}); every GPU resource is gone")]
    DeviceLost {
        /// wgpu's reason and message.
        reason: String,
    },
    /// Writing an image failed.
    #[error("cannot write {path}: {message}")]
    Write {
        /// The file.
        path: String,
        /// Why.
        message: String,
    },
}

/// What adapter a context runs on, for reports and benchmark output.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AdapterReport {
    /// Adapter name (e.g. `llvmpipe (LLVM 15.0.6, 256 bits)`).
    pub name: String,
    /// Backend (Vulkan, Gl, …).
    pub backend: String,
    /// Device type (DiscreteGpu, Cpu, …).
    pub device_type: String,
    /// Driver and driver info.
    pub driver: String,
    /// Whether it is a software rasterizer (absolute timings mean little there).
    pub is_software: bool,
    /// Whether GPU timestamp queries are enabled (inside passes as well).
    pub timestamps: bool,
    /// Format substitutions taken because the adapter lacks the pipeline's format:
    /// `wanted -> used (who)`.
    pub fallbacks: Vec<String>,
    /// The limits the device was created with (`adapter` or `webgpu`).
    pub limits: &'static str,
}

impl AdapterReport {
    /// The report of an adapter whose device has `features`, with the format `fallbacks`
    /// taken.
    fn new(info: &wgpu::AdapterInfo, features: wgpu::Features, fallbacks: Vec<String>) -> Self {
        AdapterReport {
            // Browsers may hide the adapter's name (WebGPU's privacy rules).
            name: if info.name.is_empty() {
                "unnamed adapter".to_string()
            } else {
                info.name.clone()
            },
            backend: format!("{:?}", info.backend),
            device_type: format!("{:?}", info.device_type),
            driver: driver_text(info),
            is_software: is_software(info),
            // Passes write timestamps only at their begin and end, which WebGPU's
            // `timestamp-query` allows; natively the encoder-level feature is asked too.
            timestamps: features.contains(if cfg!(target_arch = "wasm32") {
                wgpu::Features::TIMESTAMP_QUERY
            } else {
                wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
            }),
            fallbacks,
            limits: DeviceLimits::Adapter.name(),
        }
    }
}

/// An adapter's driver and driver info, as reports name it.
fn driver_text(info: &wgpu::AdapterInfo) -> String {
    format!("{} {}", info.driver, info.driver_info)
        .trim()
        .to_string()
}

impl std::fmt::Display for AdapterReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} ({}, {}{}{}{})",
            self.name,
            self.backend,
            self.device_type,
            if self.driver.is_empty() {
                String::new()
            } else {
                format!(", {}", self.driver)
            },
            if self.is_software {
                ", software: timings are not representative"
            } else {
                ""
            },
            if self.limits == DeviceLimits::WebGpuDefaults.name() {
                ", WebGPU default limits"
            } else {
                ""
            }
        )
    }
}

/// Options for creating a context.
#[derive(Debug, Clone, Default)]
pub struct ContextOptions {
    /// Adapter preference; `None` reads `SSBVB_ADAPTER` from the environment.
    pub adapter: Option<AdapterChoice>,
    /// What the pipeline needs; adapters lacking any of it are skipped. `None`: any adapter.
    pub requirements: Option<Requirements>,
    /// The limits and features the device is created with.
    pub limits: DeviceLimits,
}

/// Which limits and optional features a device is created with.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum DeviceLimits {
    /// The adapter's own limits and the optional features ssbvb uses where present
    /// (timestamps, `Depth32FloatStencil8`, f64 shaders, …).
    #[default]
    Adapter,
    /// WebGPU's default limits (`wgpu::Limits::default()`) and no optional feature: what
    /// a browser, and many mobile drivers, guarantee. Pipelines are checked against these
    /// limits; GPU timestamps (per-pass GPU times) and f64 shaders (the exact GPU
    /// voxelization) are then not available.
    WebGpuDefaults,
}

impl DeviceLimits {
    /// The limits a device is created with on `adapter`.
    pub fn on(&self, adapter: &wgpu::Adapter) -> wgpu::Limits {
        match self {
            DeviceLimits::Adapter => adapter.limits(),
            DeviceLimits::WebGpuDefaults => wgpu::Limits::default(),
        }
    }

    /// As reports name it (`render --json`'s `limits`): `adapter` or `webgpu`.
    pub fn name(&self) -> &'static str {
        match self {
            DeviceLimits::Adapter => "adapter",
            DeviceLimits::WebGpuDefaults => "webgpu",
        }
    }
}

/// One adapter and whether it can run a pipeline (`ssbvb adapter` lists these).
#[derive(Debug, Clone)]
pub struct AdapterVerdict {
    /// Name.
    pub name: String,
    /// Backend.
    pub backend: String,
    /// Device type.
    pub device_type: String,
    /// Driver and driver info.
    pub driver: String,
    /// Whether the adapter choice (`SSBVB_ADAPTER`) allows it.
    pub allowed: bool,
    /// What it lacks and which fallbacks it would take.
    pub verdict: Verdict,
}

/// Which adapter to prefer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum AdapterChoice {
    /// The best hardware adapter, else software (the default).
    Auto,
    /// Only a real GPU.
    Hardware,
    /// Only a software adapter (lavapipe, then llvmpipe).
    Software,
    /// The first adapter whose name contains this (case-insensitive).
    Named(String),
}

impl AdapterChoice {
    /// Whether this choice allows the adapter.
    pub fn allows(&self, info: &wgpu::AdapterInfo) -> bool {
        match self {
            AdapterChoice::Auto => true,
            AdapterChoice::Hardware => !is_software(info),
            AdapterChoice::Software => is_software(info),
            AdapterChoice::Named(n) => info
                .name
                .to_ascii_lowercase()
                .contains(&n.to_ascii_lowercase()),
        }
    }

    /// Parses `SSBVB_ADAPTER`-style text: `auto`, `hardware`, `software`, or a name.
    pub fn parse(s: &str) -> Self {
        match s.trim().to_ascii_lowercase().as_str() {
            "" | "auto" => AdapterChoice::Auto,
            "hardware" | "gpu" => AdapterChoice::Hardware,
            "software" | "cpu" => AdapterChoice::Software,
            _ => AdapterChoice::Named(s.trim().to_string()),
        }
    }
}

/// Device memory and object counts ([`GpuContext::memory_counters`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MemoryCounters {
    /// Bytes of device memory allocated for buffers.
    pub buffer_bytes: u64,
    /// Bytes of device memory allocated for textures.
    pub texture_bytes: u64,
    /// Live buffers.
    pub buffers: u64,
    /// Live textures.
    pub textures: u64,
    /// Live bind groups.
    pub bind_groups: u64,
}

/// A device with its queue and what it can do.
pub struct GpuContext {
    /// The wgpu instance (kept for surfaces).
    pub instance: wgpu::Instance,
    /// The chosen adapter.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    report: AdapterReport,
    uncaptured: Arc<Mutex<Vec<String>>>,
    /// Why the device was lost, once it is (set by wgpu's device-lost callback).
    lost: Arc<Mutex<Option<String>>>,
    /// The size from which the next checked allocation is refused (`crate::alloc`'s fault
    /// injection; `u64::MAX`: none).
    pub(crate) refuse_from: Arc<std::sync::atomic::AtomicU64>,
    /// Per kind of submission, how long they took (`crate::submissions`; `None`: not timed).
    pub(crate) submission_log: crate::submissions::SubmissionLog,
}

impl std::fmt::Debug for GpuContext {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuContext")
            .field("adapter", &self.report)
            .finish()
    }
}

/// Hint printed when no adapter fits under WebGPU's default limits.
pub const WEBGPU_LIMITS_HINT: &str = "under WebGPU's default limits (--limits webgpu) the \
     pipeline needs more than they allow (see `docs/architecture.md`, \"What each pass \
     needs\"); without --limits the adapter's own limits are used";

/// Hint printed when no adapter exists or none fits.
pub const NO_ADAPTER_HINT: &str = "install a Vulkan driver (on Debian/Ubuntu without a GPU: \
     `sudo apt-get install -y mesa-vulkan-drivers libvulkan1` for Mesa's lavapipe), or run \
     `cargo xtask test`, which installs it when it can";

/// Makes wgpu's GL backend use OpenGL ES on Mesa (Mesa's GL driver, llvmpipe included),
/// by capping Mesa's desktop GL version below the 3.3 core profile wgpu asks for first
/// (`MESA_GL_VERSION_OVERRIDE=3.0`; wgpu then falls back to GLES 3.2). On desktop GL, wgpu
/// reports no float render targets (a core profile lists no `*_color_buffer_float`
/// extension, which wgpu looks for), so `Rgba32Float` attachments, which every SSBVB
/// pipeline has, would be refused; on GLES they render. Does nothing when the variable is
/// set already; Vulkan and the other backends ignore it.
///
/// # Safety
///
/// Sets an environment variable: call it before any other thread may read or write the
/// environment (first thing in `main`, or before a test binary's first device).
pub unsafe fn prefer_gles_on_mesa() {
    if std::env::var_os("MESA_GL_VERSION_OVERRIDE").is_none() {
        // SAFETY: the caller guarantees no other thread touches the environment.
        unsafe { std::env::set_var("MESA_GL_VERSION_OVERRIDE", "3.0") };
    }
}

/// The instance headless commands use: every native backend (narrowed by
/// `WGPU_BACKEND`), validation on (off with `WGPU_VALIDATION=0`), and no window-system
/// display, so commands that open no window do not probe X11 or Wayland.
fn headless_instance() -> (wgpu::Instance, wgpu::Backends) {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends =
        wgpu::Backends::VULKAN | wgpu::Backends::GL | wgpu::Backends::METAL | wgpu::Backends::DX12;
    desc.flags = wgpu::InstanceFlags::VALIDATION | wgpu::InstanceFlags::DEBUG;
    let all = desc.backends;
    let mut desc = desc.with_env();
    // `WGPU_BACKEND=` (set but empty) means no preference, not no backend.
    if desc.backends.is_empty() {
        desc.backends = all;
    }
    let backends = desc.backends;
    (wgpu::Instance::new(desc), backends)
}

/// The first of `adapters` (best first) that has what `req` asks, with its verdict; else
/// one line per adapter saying what it lacks. Skipped adapters are logged at info level.
pub fn first_fitting(
    adapters: Vec<wgpu::Adapter>,
    req: &Requirements,
    limits: DeviceLimits,
) -> Result<(wgpu::Adapter, Verdict), Vec<String>> {
    let mut refused = Vec::new();
    for adapter in adapters {
        let verdict = req.check_under(&adapter, &limits.on(&adapter));
        if verdict.fits() {
            return Ok((adapter, verdict));
        }
        let info = adapter.get_info();
        let line = format!(
            "{} [{:?}] lacks: {}",
            info.name,
            info.backend,
            verdict.missing.join("; ")
        );
        log::info!("adapter skipped: {line}");
        refused.push(line);
    }
    Err(refused)
}

/// Rank of an adapter for `Auto`: lower is better. Public for the viewer, which ranks the
/// adapters that can present to its window the same way.
pub fn rank(info: &wgpu::AdapterInfo) -> (u8, u8) {
    let ty = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    };
    // Among equals, Vulkan first (lavapipe before GL llvmpipe), GL last.
    let backend = match info.backend {
        wgpu::Backend::Vulkan => 0,
        wgpu::Backend::Metal | wgpu::Backend::Dx12 => 1,
        wgpu::Backend::Gl => 3,
        _ => 2,
    };
    (ty, backend)
}

fn is_software(info: &wgpu::AdapterInfo) -> bool {
    info.device_type == wgpu::DeviceType::Cpu
        || ["llvmpipe", "lavapipe", "swiftshader", "warp", "software"]
            .iter()
            .any(|s| info.name.to_ascii_lowercase().contains(s))
}

impl GpuContext {
    /// Creates a headless context on the preferred adapter that has what
    /// `options.requirements` asks (see the crate docs).
    pub fn new_headless(options: &ContextOptions) -> Result<Self, GpuError> {
        let choice = options.adapter.clone().unwrap_or_else(|| {
            AdapterChoice::parse(&std::env::var("SSBVB_ADAPTER").unwrap_or_default())
        });
        let (instance, backends) = headless_instance();
        let mut adapters = pollster::block_on(instance.enumerate_adapters(backends));
        let seen: Vec<String> = adapters
            .iter()
            .map(|a| format!("{} [{:?}]", a.get_info().name, a.get_info().backend))
            .collect();
        adapters.retain(|a| choice.allows(&a.get_info()));
        adapters.sort_by_key(|a| rank(&a.get_info()));
        if adapters.is_empty() {
            return Err(GpuError::NoAdapter {
                tried: format!(
                    "backends {backends:?}, choice {choice:?}, adapters seen: {}",
                    if seen.is_empty() {
                        "none".to_string()
                    } else {
                        seen.join(", ")
                    }
                ),
                hint: NO_ADAPTER_HINT.to_string(),
            });
        }
        let Some(req) = &options.requirements else {
            let adapter = adapters.swap_remove(0);
            return Self::from_adapter_with(instance, adapter, Vec::new(), options.limits);
        };
        match first_fitting(adapters, req, options.limits) {
            Ok((adapter, verdict)) => {
                Self::from_adapter_with(instance, adapter, verdict.fallback_notes(), options.limits)
            }
            Err(refused) => Err(GpuError::NoSuitableAdapter {
                details: refused.join(" | "),
                hint: match options.limits {
                    DeviceLimits::Adapter => NO_ADAPTER_HINT.to_string(),
                    DeviceLimits::WebGpuDefaults => WEBGPU_LIMITS_HINT.to_string(),
                },
            }),
        }
    }

    /// Every adapter the headless instance sees, best first, each with its verdict on
    /// `requirements` and whether `SSBVB_ADAPTER` allows it.
    pub fn list_adapters(requirements: &Requirements, limits: DeviceLimits) -> Vec<AdapterVerdict> {
        Self::list_adapters_for(std::slice::from_ref(requirements), limits)
            .pop()
            .unwrap_or_default()
    }

    /// [`GpuContext::list_adapters`] for several requirements at once, the adapters
    /// enumerated once (an instance and its adapters cost a driver's start-up each time):
    /// per requirement, every adapter best first with its verdict.
    pub fn list_adapters_for(
        requirements: &[Requirements],
        limits: DeviceLimits,
    ) -> Vec<Vec<AdapterVerdict>> {
        let choice = AdapterChoice::parse(&std::env::var("SSBVB_ADAPTER").unwrap_or_default());
        let (instance, backends) = headless_instance();
        let mut adapters = pollster::block_on(instance.enumerate_adapters(backends));
        adapters.sort_by_key(|a| rank(&a.get_info()));
        requirements
            .iter()
            .map(|req| {
                adapters
                    .iter()
                    .map(|a| {
                        let info = a.get_info();
                        AdapterVerdict {
                            name: info.name.clone(),
                            backend: format!("{:?}", info.backend),
                            device_type: format!("{:?}", info.device_type),
                            driver: driver_text(&info),
                            allowed: choice.allows(&info),
                            verdict: req.check_under(a, &limits.on(a)),
                        }
                    })
                    .collect()
            })
            .collect()
    }

    /// Creates the device on a chosen adapter with the features ssbvb uses when present.
    /// `fallbacks` lists the format substitutions the requirements check chose.
    pub fn from_adapter(
        instance: wgpu::Instance,
        adapter: wgpu::Adapter,
        fallbacks: Vec<String>,
    ) -> Result<Self, GpuError> {
        Self::from_adapter_with(instance, adapter, fallbacks, DeviceLimits::Adapter)
    }

    /// [`GpuContext::from_adapter`] with the device's limits and features chosen by
    /// `limits`.
    pub fn from_adapter_with(
        instance: wgpu::Instance,
        adapter: wgpu::Adapter,
        fallbacks: Vec<String>,
        limits: DeviceLimits,
    ) -> Result<Self, GpuError> {
        pollster::block_on(Self::from_adapter_async(
            instance, adapter, fallbacks, limits,
        ))
    }

    /// [`GpuContext::from_adapter_with`] awaiting the device: the form for the browser,
    /// whose thread must not block.
    pub async fn from_adapter_async(
        instance: wgpu::Instance,
        adapter: wgpu::Adapter,
        fallbacks: Vec<String>,
        limits: DeviceLimits,
    ) -> Result<Self, GpuError> {
        let info = adapter.get_info();
        let wanted = wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES
            | wgpu::Features::DEPTH32FLOAT_STENCIL8
            | wgpu::Features::INDIRECT_FIRST_INSTANCE
            | wgpu::Features::FLOAT32_FILTERABLE
            // Counters (fragments shaded per pass) where the adapter has them.
            | wgpu::Features::PIPELINE_STATISTICS_QUERY
            // The exact GPU voxelization (f64 separating-axis test) where present.
            | wgpu::Features::SHADER_F64
            // The compute splat's one-step form (64-bit atomics) where present.
            | wgpu::Features::SHADER_INT64
            | wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS;
        let features = match limits {
            DeviceLimits::Adapter => adapter.features() & wanted,
            DeviceLimits::WebGpuDefaults => wgpu::Features::empty(),
        };
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("ssbvb"),
                required_features: features,
                required_limits: limits.on(&adapter),
                ..Default::default()
            })
            .await
            .map_err(|e| GpuError::RequestDevice {
                adapter: info.name.clone(),
                message: e.to_string(),
            })?;
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            log::error!("uncaptured wgpu error: {e}");
            if let Ok(mut v) = sink.lock() {
                v.push(e.to_string());
            }
        }));
        let lost = Arc::new(Mutex::new(None));
        let lost_sink = lost.clone();
        device.set_device_lost_callback(move |reason, message| {
            log::error!("GPU device lost: {reason:?}: {message}");
            if let Ok(mut l) = lost_sink.lock() {
                *l = Some(format!("{reason:?}: {message}"));
            }
        });
        let mut report = AdapterReport::new(&info, features, fallbacks);
        report.limits = limits.name();
        Ok(Self {
            instance,
            adapter,
            device,
            queue,
            report,
            uncaptured,
            lost,
            refuse_from: Arc::new(std::sync::atomic::AtomicU64::new(u64::MAX)),
            submission_log: Default::default(),
        })
    }

    /// Wraps a device the caller already has (embedding ssbvb in an existing wgpu
    /// renderer). The device keeps the caller's features and limits; errors outside error
    /// scopes go to the caller's own handler, not to [`GpuContext::take_uncaptured_errors`].
    pub fn from_parts(
        instance: wgpu::Instance,
        adapter: wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Self {
        let report = AdapterReport::new(&adapter.get_info(), device.features(), Vec::new());
        Self {
            instance,
            adapter,
            device,
            queue,
            report,
            uncaptured: Arc::new(Mutex::new(Vec::new())),
            // The caller's device-lost callback stays the caller's.
            lost: Arc::new(Mutex::new(None)),
            refuse_from: Arc::new(std::sync::atomic::AtomicU64::new(u64::MAX)),
            submission_log: Default::default(),
        }
    }

    /// The adapter this context runs on.
    pub fn report(&self) -> &AdapterReport {
        &self.report
    }

    /// Whether the device has `feature`.
    pub fn has(&self, feature: wgpu::Features) -> bool {
        self.device.features().contains(feature)
    }

    /// The best depth-stencil format: `Depth32FloatStencil8` when available (32-bit depth
    /// for precision at 4096³), else `Depth24PlusStencil8` (always available).
    pub fn depth_stencil_format(&self) -> wgpu::TextureFormat {
        if self.has(wgpu::Features::DEPTH32FLOAT_STENCIL8) {
            wgpu::TextureFormat::Depth32FloatStencil8
        } else {
            wgpu::TextureFormat::Depth24PlusStencil8
        }
    }

    /// Runs `f` inside validation, out-of-memory and internal error scopes and turns the
    /// first error into [`GpuError::Wgpu`] naming `label`.
    ///
    /// In the browser an error scope's result arrives only after the thread yields, so
    /// there `f` runs without scopes: its errors reach the uncaptured-error handler, which
    /// [`GpuContext::take_uncaptured_errors`] reads (the page does after every frame).
    pub fn validated<T>(
        &self,
        label: &str,
        f: impl FnOnce(&wgpu::Device) -> T,
    ) -> Result<T, GpuError> {
        if cfg!(target_arch = "wasm32") {
            let _ = label;
            return Ok(f(&self.device));
        }
        let internal = self.device.push_error_scope(wgpu::ErrorFilter::Internal);
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let out = f(&self.device);
        let errors = [
            ("validation", pollster::block_on(validation.pop())),
            ("out-of-memory", pollster::block_on(oom.pop())),
            ("internal", pollster::block_on(internal.pop())),
        ];
        for (kind, e) in errors {
            if let Some(e) = e {
                return Err(GpuError::Wgpu {
                    label: label.to_string(),
                    kind,
                    message: e.to_string(),
                });
            }
        }
        Ok(out)
    }

    /// What the device holds now, from wgpu's internal counters (the `counters` feature;
    /// backends that do not count report zeros): the soak's leak check.
    pub fn memory_counters(&self) -> MemoryCounters {
        let hal = self.device.get_internal_counters().hal;
        let n = |v: isize| v.max(0) as u64;
        MemoryCounters {
            buffer_bytes: n(hal.buffer_memory.read()),
            texture_bytes: n(hal.texture_memory.read()),
            buffers: n(hal.buffers.read()),
            textures: n(hal.textures.read()),
            bind_groups: n(hal.bind_groups.read()),
        }
    }

    /// Errors wgpu reported outside any error scope since the last call (empty is good).
    pub fn take_uncaptured_errors(&self) -> Vec<String> {
        self.uncaptured
            .lock()
            .map(|mut v| std::mem::take(&mut *v))
            .unwrap_or_default()
    }

    /// Blocks until all submitted work is done; [`GpuError::DeviceLost`] when the device
    /// was lost (wgpu drops the errors of a lost device's operations, so this is where a
    /// loss surfaces).
    pub fn wait_idle(&self) -> Result<(), GpuError> {
        let polled = self.device.poll(wgpu::PollType::wait_indefinitely());
        if let Some(reason) = self.lost() {
            return Err(GpuError::DeviceLost { reason });
        }
        polled.map(|_| ()).map_err(|e| GpuError::Readback {
            label: "device poll".into(),
            message: e.to_string(),
        })
    }

    /// Why the device was lost, if it was (wgpu reports a loss while the device is polled;
    /// this polls once without waiting). `None` for a device from [`GpuContext::from_parts`],
    /// whose loss its owner handles.
    pub fn lost(&self) -> Option<String> {
        let _ = self.device.poll(wgpu::PollType::Poll);
        self.lost.lock().ok().and_then(|l| l.clone())
    }

    /// Destroys the device as a driver reset would: every later operation on it is a no-op
    /// and [`GpuContext::lost`] says so. Fault injection (`--inject-fault device-lost@N`).
    pub fn inject_device_loss(&self) {
        self.device.destroy();
    }

    /// Creates a shader module from WGSL, failing with the compiler's message (file, line)
    /// instead of a panic or a deferred error.
    pub fn shader(&self, label: &str, wgsl: &str) -> Result<wgpu::ShaderModule, GpuError> {
        self.validated(label, |d| {
            d.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(wgsl.into()),
            })
        })
    }
}
