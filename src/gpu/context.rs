//! Adapter choice and device creation.

use super::array_layout::{ArrayLayout, BUFFER_LAYOUT_STORAGE_BUFFERS};
use crate::error::Error;
use crate::solver::AdapterReport;
use std::str::FromStr;

/// What `Profiler` needs: timestamps written between a pass's dispatches.
const TIMESTAMP_FEATURES: wgpu::Features =
    wgpu::Features::TIMESTAMP_QUERY.union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES);

/// Which adapter to run on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum AdapterChoice {
    /// `WGPU_ADAPTER_NAME` if set, else wgpu's high-performance choice.
    Auto,
    /// wgpu's fallback (software) adapter, e.g. Mesa lavapipe.
    Fallback,
    /// The first adapter whose name contains this text (case-insensitive).
    Named(String),
}

impl FromStr for AdapterChoice {
    type Err = std::convert::Infallible;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(match s {
            "auto" => AdapterChoice::Auto,
            "fallback" => AdapterChoice::Fallback,
            name => AdapterChoice::Named(name.to_string()),
        })
    }
}

impl std::fmt::Display for AdapterChoice {
    /// The text `FromStr` reads back.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AdapterChoice::Auto => write!(f, "auto"),
            AdapterChoice::Fallback => write!(f, "fallback"),
            AdapterChoice::Named(name) => write!(f, "{name}"),
        }
    }
}

/// What `drapekit info` reports.
#[derive(Clone, Debug)]
pub struct AdapterList {
    /// Every adapter wgpu finds.
    pub adapters: Vec<AdapterReport>,
    /// The one `AdapterChoice::Auto` takes, if any.
    pub auto: Option<AdapterReport>,
    /// Why that one (or why none).
    pub auto_reason: String,
    /// The limits of that adapter which bound what drapekit can run on it.
    pub auto_limits: Option<LimitsReport>,
}

/// The adapter limits that bound a drapekit run, as `drapekit info` prints them.
#[derive(Clone, Debug, PartialEq)]
pub struct LimitsReport {
    /// Largest 2D texture side, in texels: every array is a texture of this many rows at most.
    pub max_texture_dimension_2d: u32,
    /// The most elements one array holds: those rows of `TEXELS_PER_ROW` texels.
    pub max_array_elements: u64,
    /// About the most particles the GPU path takes (its largest array, the hinge list, holds
    /// `GPU_ELEMENTS_PER_PARTICLE` entries per particle).
    pub max_particles: u64,
    /// Workgroups per dispatch dimension (large meshes dispatch in 2D).
    pub max_compute_workgroups_per_dimension: u32,
    /// Invocations per workgroup (the kernels use 64).
    pub max_compute_invocations_per_workgroup: u32,
    /// Sampled textures per stage (a stage binds its input arrays as these).
    pub max_sampled_textures_per_shader_stage: u32,
    /// Storage textures per stage (a stage writes its outputs as these).
    pub max_storage_textures_per_shader_stage: u32,
    /// Largest buffer, in bytes.
    pub max_buffer_size: u64,
}

impl LimitsReport {
    /// The report for an adapter's limits.
    pub fn new(l: &wgpu::Limits) -> Self {
        let max_array_elements =
            l.max_texture_dimension_2d as u64 * crate::model::layout::TEXELS_PER_ROW as u64;
        LimitsReport {
            max_texture_dimension_2d: l.max_texture_dimension_2d,
            max_array_elements,
            max_particles: max_array_elements / crate::model::budget::GPU_ELEMENTS_PER_PARTICLE,
            max_compute_workgroups_per_dimension: l.max_compute_workgroups_per_dimension,
            max_compute_invocations_per_workgroup: l.max_compute_invocations_per_workgroup,
            max_sampled_textures_per_shader_stage: l.max_sampled_textures_per_shader_stage,
            max_storage_textures_per_shader_stage: l.max_storage_textures_per_shader_stage,
            max_buffer_size: l.max_buffer_size,
        }
    }
}

/// A wgpu instance on the primary backends (Vulkan, Metal, DirectX 12), or those
/// `WGPU_BACKEND` names. The OpenGL backend is left out unless asked for: its compute support
/// is too thin for the kernels' storage textures, and Mesa's EGL teardown at process exit
/// crashed a run that had failed to find its adapter ("double free or corruption").
fn instance() -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::PRIMARY;
    wgpu::Instance::new(desc.with_env())
}

/// The adapters on this machine and `auto`'s choice among them.
pub fn adapters() -> AdapterList {
    let instance = instance();
    let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()))
        .iter()
        .map(|a| report(&a.get_info()))
        .collect();
    let (auto, auto_reason) = match std::env::var("WGPU_ADAPTER_NAME") {
        Ok(name) if !name.is_empty() => {
            match GpuContext::new(&AdapterChoice::Named(name.clone())) {
                Ok(ctx) => (Some(ctx), format!("WGPU_ADAPTER_NAME={name}")),
                Err(e) => (None, e.to_string()),
            }
        }
        _ => match GpuContext::new(&AdapterChoice::Auto) {
            Ok(ctx) => (Some(ctx), "wgpu's high-performance choice".to_string()),
            Err(e) => (None, e.to_string()),
        },
    };
    AdapterList {
        adapters,
        auto: auto.as_ref().map(GpuContext::report),
        auto_reason,
        auto_limits: auto
            .as_ref()
            .map(|ctx| LimitsReport::new(&ctx.adapter_limits)),
    }
}

/// The most storage buffers one kernel of implicit Euler's solve binds (`assemble` and
/// `pcg_step`; `ImplicitSolve::new` checks every kernel against the device's limit).
pub const SOLVE_STORAGE_BUFFERS: u32 = 8;

/// A device and queue on a chosen adapter. Cheap to clone (wgpu handles are shared).
#[derive(Clone, Debug)]
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What the adapter says about itself.
    pub info: wgpu::AdapterInfo,
    /// What the adapter could give (the device asks for less: see `new`).
    pub adapter_limits: wgpu::Limits,
    /// Where the kernels' arrays live: textures or storage buffers.
    pub layout: ArrayLayout,
    /// A device loss and the first uncaptured GPU error, recorded by wgpu's callbacks (which
    /// would otherwise panic) and turned into `Error::Gpu` by `check`.
    failure: std::sync::Arc<std::sync::Mutex<[Option<String>; 2]>>,
}

impl GpuContext {
    /// Opens a device on the chosen adapter, with its arrays laid out as `DRAPEKIT_GPU_LAYOUT`
    /// says or as suits the adapter (see `ArrayLayout::choose`).
    pub fn new(choice: &AdapterChoice) -> Result<Self, Error> {
        Self::open(choice, None)
    }

    /// Opens a device on the chosen adapter with the given array layout (`None`: as `new`).
    pub fn open(choice: &AdapterChoice, layout: Option<ArrayLayout>) -> Result<Self, Error> {
        Self::open_device(choice, layout, false)
    }

    /// As `new`, with timestamp queries inside compute passes (what `Profiler` needs); an
    /// error names the adapter when it has none.
    pub fn open_with_timestamps(choice: &AdapterChoice) -> Result<Self, Error> {
        Self::open_device(choice, None, true)
    }

    fn open_device(
        choice: &AdapterChoice,
        layout: Option<ArrayLayout>,
        timestamps: bool,
    ) -> Result<Self, Error> {
        let instance = instance();
        let choice = match (choice, std::env::var("WGPU_ADAPTER_NAME")) {
            (AdapterChoice::Auto, Ok(name)) if !name.is_empty() => AdapterChoice::Named(name),
            (c, _) => c.clone(),
        };
        let adapter = match &choice {
            AdapterChoice::Named(name) => {
                let wanted = name.to_lowercase();
                let adapters =
                    pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
                let names: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
                adapters
                    .into_iter()
                    .find(|a| a.get_info().name.to_lowercase().contains(&wanted))
                    .ok_or_else(|| {
                        Error::Gpu(format!(
                            "no adapter name contains {name:?}; available: {names:?}"
                        ))
                    })?
            }
            AdapterChoice::Auto | AdapterChoice::Fallback => {
                let options = wgpu::RequestAdapterOptions {
                    power_preference: wgpu::PowerPreference::HighPerformance,
                    force_fallback_adapter: choice == AdapterChoice::Fallback,
                    ..Default::default()
                };
                pollster::block_on(instance.request_adapter(&options)).map_err(|e| {
                    Error::Gpu(format!(
                        "no {} adapter: {e}. On Debian/Ubuntu the software adapter comes with \
                         `apt-get install -y mesa-vulkan-drivers libvulkan1`",
                        if choice == AdapterChoice::Fallback {
                            "fallback"
                        } else {
                            "GPU"
                        }
                    ))
                })?
            }
        };
        let info = adapter.get_info();
        let available = adapter.limits();
        let layout = match layout {
            Some(layout) => layout.check(&info, &available),
            None => ArrayLayout::choose(&info, &available),
        }
        .map_err(Error::Gpu)?;
        // The buffer layout binds every texel array as a storage buffer.
        let storage_buffers = match layout {
            ArrayLayout::Textures => SOLVE_STORAGE_BUFFERS,
            ArrayLayout::Buffers => BUFFER_LAYOUT_STORAGE_BUFFERS,
        };
        // Kernels bind uniforms, sampled textures, write-only storage textures and storage
        // buffers. Implicit Euler's solve binds up to SOLVE_STORAGE_BUFFERS storage buffers per
        // kernel (more than the downlevel defaults' 4) and its largest arrays (the multigrid
        // hierarchy, the blocks of every level's matrix) grow with the mesh, as do textures:
        // ask for what the adapter gives there (the solver checks what it needs against it).
        let required_limits = wgpu::Limits {
            max_texture_dimension_2d: available.max_texture_dimension_2d,
            max_storage_buffers_per_shader_stage: storage_buffers
                .min(available.max_storage_buffers_per_shader_stage),
            max_storage_buffer_binding_size: available.max_storage_buffer_binding_size,
            max_buffer_size: available.max_buffer_size,
            ..wgpu::Limits::downlevel_defaults()
        };
        let required_features = match timestamps {
            false => wgpu::Features::empty(),
            true => TIMESTAMP_FEATURES,
        };
        if !adapter.features().contains(required_features) {
            return Err(Error::Gpu(format!(
                "{:?} has no timestamp queries inside compute passes: it cannot be profiled",
                info.name
            )));
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("drapekit"),
            required_limits,
            required_features,
            ..Default::default()
        }))
        .map_err(|e| Error::Gpu(format!("cannot open a device on {:?}: {e}", info.name)))?;
        let failure = std::sync::Arc::new(std::sync::Mutex::new([None, None]));
        let lost = failure.clone();
        device.set_device_lost_callback(move |reason, message| {
            if let Ok(mut f) = lost.lock() {
                let detail = if message.is_empty() {
                    String::new()
                } else {
                    format!(": {message}")
                };
                f[0].get_or_insert(format!("the GPU device was lost ({reason:?}){detail}"));
            }
        });
        let errors = failure.clone();
        device.on_uncaptured_error(std::sync::Arc::new(move |e: wgpu::Error| {
            if let Ok(mut f) = errors.lock() {
                f[1].get_or_insert(format!("the GPU reported an error: {e}"));
            }
        }));
        Ok(GpuContext {
            device,
            queue,
            info,
            adapter_limits: available,
            layout,
            failure,
        })
    }

    /// `Err` once the device was lost or reported an error: what happened, and that the frames
    /// written and the last checkpoint survive.
    pub fn check(&self) -> Result<(), Error> {
        // A loss explains the errors that follow it, so it is named first.
        let first = (self.failure.lock().ok()).and_then(|f| f[0].clone().or(f[1].clone()));
        match first {
            None => Ok(()),
            Some(what) => Err(Error::Gpu(format!(
                "{what}. The frames written so far and the last checkpoint survive: continue \
                 with drapekit resume OUT (runs with --checkpoint-every N), or use --backend cpu"
            ))),
        }
    }

    /// Maps a MAP_READ slice once the submitted work is done and hands its bytes to `read`.
    pub(super) fn map_read<T>(
        &self,
        slice: wgpu::BufferSlice,
        read: impl FnOnce(&[u8]) -> T,
    ) -> Result<T, Error> {
        self.check()?;
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("waiting for the GPU failed: {e}")))?;
        // A lost device fails the mapping below; its own message says more.
        self.check()?;
        rx.recv()
            .map_err(|e| Error::Gpu(format!("readback was dropped: {e}")))?
            .map_err(|e| Error::Gpu(format!("mapping the staging buffer failed: {e}")))?;
        let out = read(
            &slice
                .get_mapped_range()
                .map_err(|e| Error::Gpu(format!("reading the staging buffer failed: {e}")))?,
        );
        slice.buffer().unmap();
        Ok(out)
    }

    /// The most elements one array may hold: its texture's rows (the device's largest 2D
    /// texture) of `TEXELS_PER_ROW` texels (see texels.rs).
    pub fn max_texels(&self) -> u64 {
        self.device.limits().max_texture_dimension_2d as u64
            * crate::model::layout::TEXELS_PER_ROW as u64
    }

    /// Whether the device was opened with timestamp queries (`open_with_timestamps`).
    pub fn has_timestamps(&self) -> bool {
        self.device.features().contains(TIMESTAMP_FEATURES)
    }

    /// A software rasteriser (llvmpipe, lavapipe, WARP): wgpu's `DeviceType::Cpu`.
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// The adapter as reported in summaries and benchmarks.
    pub fn report(&self) -> AdapterReport {
        AdapterReport {
            array_layout: Some(self.layout.name().to_string()),
            ..report(&self.info)
        }
    }
}

/// An adapter's name, driver, backend and type, as summaries and benchmarks print them.
fn report(info: &wgpu::AdapterInfo) -> AdapterReport {
    AdapterReport {
        name: info.name.clone(),
        driver: info.driver.clone(),
        backend: format!("{:?}", info.backend).to_lowercase(),
        device_type: match info.device_type {
            wgpu::DeviceType::Other => "other",
            wgpu::DeviceType::IntegratedGpu => "integrated_gpu",
            wgpu::DeviceType::DiscreteGpu => "discrete_gpu",
            wgpu::DeviceType::VirtualGpu => "virtual_gpu",
            wgpu::DeviceType::Cpu => "cpu",
        }
        .to_string(),
        array_layout: None,
    }
}
