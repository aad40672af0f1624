//! Finding and opening a GPU for the GPU backend (docs/spec.md, adapters).
//!
//! Policy:
//! - [`AdapterPolicy::Hardware`] (`--backend auto`) takes a discrete or integrated GPU only: a
//!   software adapter (lavapipe, llvmpipe) is slower than the CPU backend, so it is used only when
//!   asked for.
//! - [`AdapterPolicy::Any`] (`--backend gpu`) takes the best adapter there is, software included.
//! - `WGPU_ADAPTER_NAME` (a case-insensitive part of the adapter's name) picks an adapter by name
//!   under either policy, software ones included; no match is an error that lists the adapters.
//! - `WGPU_BACKEND` (`vulkan`, `metal`, `dx12`, `gl`, comma separated) restricts the APIs searched.
//!   wgpu's GL backend is skipped unless `WGPU_BACKEND` names it: its `dot`/`length` round
//!   differently from Vulkan's, so the CPU/GPU parity contract does not hold there.
//!
//! wgpu reports validation errors through a handler that panics by default; the device installed
//! here records them instead ([`GpuDevice::take_errors`]), so a shader or buffer mistake becomes an
//! error the caller sees, never a crash of the host (or of a Python interpreter). A lost device
//! (a driver reset, an unplugged GPU, [`wgpu::Device::destroy`]) is recorded the same way
//! ([`GpuDevice::lost`]): every later call of a batch on it is a `SimError::Device`, and the next
//! [`GpuDevice::open`] opens a new device instead of handing the lost one out again.

use std::sync::{Arc, Mutex};

use super::paths::GpuPaths;
use super::pipelines::{Compiler, DiskCache, PipelineCache};
use super::spirv::{BufferBounds, Contraction};
use super::vulkan;
use crate::error::SimError;

/// Which adapters may be used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AdapterPolicy {
    /// Discrete or integrated GPUs only (`--backend auto`).
    Hardware,
    /// Any adapter, software ones included (`--backend gpu`).
    Any,
}

/// What the user reads when no adapter can be used. The loader and glvnd are named because a
/// container with NVIDIA's driver mounted but neither of them (seen on an H200 machine) lists no
/// adapter, with no other sign of why: the driver's Vulkan library needs glvnd's dispatch.
const INSTALL_HINT: &str = "install a Vulkan driver: your GPU vendor's driver with the Vulkan \
loader (Debian/Ubuntu: `libvulkan1`; NVIDIA's driver also needs `libglvnd0`), or Mesa's software \
driver for testing (Debian/Ubuntu: `apt-get install mesa-vulkan-drivers`); `socnav devices` lists \
the adapters wgpu finds";

/// An adapter as the user sees it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AdapterSummary {
    /// Adapter name, e.g. "NVIDIA H100 80GB HBM3" or "llvmpipe (LLVM 15.0.6, 256 bits)".
    pub name: String,
    /// Graphics API: "Vulkan", "Metal", "Dx12", "Gl".
    pub backend: String,
    /// "DiscreteGpu", "IntegratedGpu", "VirtualGpu", "Cpu" or "Other".
    pub device_type: String,
    /// Driver name and version.
    pub driver: String,
    /// Whether the adapter is a hardware GPU.
    pub hardware: bool,
}

impl AdapterSummary {
    fn of(info: &wgpu::AdapterInfo) -> Self {
        Self {
            name: info.name.clone(),
            backend: format!("{:?}", info.backend),
            device_type: format!("{:?}", info.device_type),
            driver: format!("{} {}", info.driver, info.driver_info)
                .trim()
                .to_owned(),
            hardware: is_hardware(info.device_type),
        }
    }
}

impl std::fmt::Display for AdapterSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} ({}, {}, {})",
            self.name, self.backend, self.device_type, self.driver
        )
    }
}

fn is_hardware(t: wgpu::DeviceType) -> bool {
    matches!(
        t,
        wgpu::DeviceType::DiscreteGpu | wgpu::DeviceType::IntegratedGpu
    )
}

/// Preference among usable adapters: discrete, integrated, virtual, other, software.
fn rank(t: wgpu::DeviceType) -> u8 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    }
}

/// The wgpu instance and the backends socnav looks at: every backend but OpenGL, unless
/// `WGPU_BACKEND` asks for it. socnav never computes on OpenGL unless asked, and probing it
/// makes Mesa's EGL print `XDG_RUNTIME_DIR is invalid` lines as errors on machines without a
/// desktop session.
fn instance() -> (wgpu::Instance, wgpu::Backends) {
    let gl_requested = wgpu::Backends::from_env().is_some_and(|b| b.contains(wgpu::Backends::GL));
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    if !gl_requested {
        desc.backends.remove(wgpu::Backends::GL);
    }
    let backends = desc.backends;
    (wgpu::Instance::new(desc), backends)
}

/// Every adapter socnav can use (honouring `WGPU_BACKEND`), for `socnav devices`.
pub fn list_adapters() -> Vec<AdapterSummary> {
    let (instance, backends) = instance();
    pollster::block_on(instance.enumerate_adapters(backends))
        .iter()
        .map(|a| AdapterSummary::of(&a.get_info()))
        .collect()
}

/// The environment variable that chooses how pipelines are built on Vulkan: `spirv` (the
/// default, also when unset or empty) from the backend's own SPIR-V (`super::spirv`: the ORCA
/// lists not zeroed at every call, no product and sum fused into a multiply-add), `spirv-fma` from
/// the same SPIR-V with the driver free to fuse them (what that freedom buys, measured), `wgsl`
/// from the WGSL as wgpu compiles it, the way every other API does. The last is the way back
/// should a driver refuse the first, and the other half of a comparison of the two on hardware
/// (`scripts/bench-gpu`).
pub const SHADERS_VAR: &str = "SOCNAV_SHADERS";

/// The environment variable that chooses the paths of the devices this process opens: `device`
/// (the default) takes the adapter's (on a hardware GPU the observation staged through workgroup
/// memory, each reset and each regrouping on a workgroup's lanes, each obstacle rebuild in
/// workgroup memory, the observation's entity records a lane each, the reset's obstacles
/// rebuilt on the device and the readback submitted before the host's work:
/// `GpuPaths::stage_observations`, `GpuPaths::resets_in_workgroups`,
/// `GpuPaths::regroups_in_workgroups`, `GpuPaths::obstacles_in_workgroups`,
/// `GpuPaths::records_in_lanes`, `GpuPaths::obstacles_after_resets`,
/// `GpuPaths::readback_before_host_work`), `lane` a software adapter's on any adapter: the way
/// back should a driver refuse a hardware path's pipeline.
pub const PATHS_VAR: &str = "SOCNAV_GPU_PATHS";

/// Whether [`PATHS_VAR`] asks for a software adapter's paths on every adapter.
fn lane_paths_wanted() -> Result<bool, SimError> {
    lane_paths_from(std::env::var(PATHS_VAR).ok().as_deref())
}

/// Whether a value of [`PATHS_VAR`] asks for a software adapter's paths; an error names a value
/// that is neither `device` nor `lane`.
fn lane_paths_from(value: Option<&str>) -> Result<bool, SimError> {
    choice(PATHS_VAR, value, &["device", "lane"]).map(|k| k == 1)
}

/// What [`SHADERS_VAR`] asks for ([`shaders_from`]).
fn shaders_wanted() -> Result<Option<Contraction>, SimError> {
    shaders_from(std::env::var(SHADERS_VAR).ok().as_deref())
}

/// The backend's own SPIR-V, and whether its products and sums may be fused, that a value of
/// [`SHADERS_VAR`] asks for (`None`: the WGSL through wgpu); an error names a value that is none
/// of `spirv`, `spirv-fma` and `wgsl`.
fn shaders_from(value: Option<&str>) -> Result<Option<Contraction>, SimError> {
    let k = choice(SHADERS_VAR, value, &["spirv", "spirv-fma", "wgsl"])?;
    Ok([
        Some(Contraction::Forbidden),
        Some(Contraction::Allowed),
        None,
    ][k])
}

/// Which of `values` environment variable `var` chooses, by index (unset or empty: the first,
/// the default); an error names any other value.
fn choice(var: &str, value: Option<&str>, values: &[&str]) -> Result<usize, SimError> {
    match value {
        None | Some("") => Ok(0),
        Some(v) => values.iter().position(|&w| w == v).ok_or_else(|| {
            let others: Vec<String> = values[1..].iter().map(|w| format!("{w:?}")).collect();
            SimError::Usage(format!(
                "{var}={v:?}: expected {:?} (the default) or {}",
                values[0],
                others.join(" or ")
            ))
        }),
    }
}

/// An open device and its queue, with the adapter it came from. Clones share the device.
#[derive(Clone)]
pub struct GpuDevice {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter, as the user sees it.
    pub adapter: AdapterSummary,
    /// The limits the device was opened with (the adapter's own).
    pub limits: wgpu::Limits,
    /// The paths a batch made with this handle takes ([`GpuPaths`]): the adapter's by default; a
    /// clone of the handle with other paths makes a batch take those (the device itself is
    /// shared).
    pub paths: GpuPaths,
    /// Whether pipelines are built from the backend's own SPIR-V (`super::spirv`: the ORCA
    /// lists not zeroed at every call, and no multiply-add fused unless [`Self::contraction`]
    /// allows it), which takes a Vulkan adapter with `PASSTHROUGH_SHADERS`
    /// (every one wgpu 30 opens); otherwise from the WGSL as wgpu compiles it.
    pub(crate) own_spirv: bool,
    /// Whether that SPIR-V lets the driver fuse a float product and a sum into one multiply-add
    /// (`super::spirv::Contraction`; [`SHADERS_VAR`]); unused where the pipelines are built from
    /// the WGSL.
    pub(crate) contraction: Contraction,
    /// Whether the device enabled Vulkan's `robustBufferAccess2` (`VK_EXT_robustness2`), which
    /// makes every storage-buffer access out of bounds read zero and write nothing: wgpu then
    /// leaves buffer bounds to the driver, and so does the backend's own SPIR-V
    /// (`super::spirv::BufferBounds`).
    pub(crate) driver_checks_buffers: bool,
    /// The memory the step's mapped readback lives in (`vulkan::readback_memory`), where the device
    /// says.
    readback_memory: Option<String>,
    /// The memory wgpu's staging buffers live in (`vulkan::staging_memory`), where the device
    /// says.
    staging_memory: Option<String>,
    errors: Arc<Mutex<Vec<String>>>,
    /// Why the device was lost, once it has been.
    lost: Arc<Mutex<Option<String>>>,
    /// The pipelines compiled on this device ([`PipelineCache`]).
    pub(crate) pipelines: Arc<PipelineCache>,
}

impl std::fmt::Debug for GpuDevice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuDevice")
            .field("adapter", &self.adapter)
            .finish_non_exhaustive()
    }
}

impl GpuDevice {
    /// This device with the paths a software adapter takes, whatever the adapter: observations
    /// written in place, each reset and regrouping on one lane, each obstacle rebuild over
    /// `scratch`, the entity records in the observing lane, each reset's obstacles built on the
    /// host, the readback submitted after the host's work ([`PATHS_VAR`]`=lane`, `socnav bench
    /// --lane-paths`).
    #[must_use]
    pub fn with_lane_paths(mut self) -> Self {
        self.paths = self.paths.lane();
        self
    }

    /// The device of the best adapter the policy allows (see the module docs), opened on the
    /// first call and shared by every later call with the same policy and the same
    /// `WGPU_ADAPTER_NAME`/`WGPU_BACKEND`/[`SHADERS_VAR`]/[`PATHS_VAR`], so that batches reuse the pipelines
    /// it compiled ([`GpuDevice::pipeline_builds`]). A shared device that was lost is forgotten,
    /// and a new one opened in its place.
    pub fn open(policy: AdapterPolicy) -> Result<Self, SimError> {
        type Key = (
            AdapterPolicy,
            Option<String>,
            Option<String>,
            Option<String>,
            Option<String>,
        );
        static OPEN: Mutex<Vec<(Key, GpuDevice)>> = Mutex::new(Vec::new());
        let var = |name: &str| std::env::var(name).ok().filter(|s| !s.is_empty());
        let key = (
            policy,
            var("WGPU_ADAPTER_NAME"),
            var("WGPU_BACKEND"),
            var(SHADERS_VAR),
            var(PATHS_VAR),
        );
        // Held while opening, so that threads asking at once share one device.
        let mut open = OPEN
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        open.retain(|(_, dev)| dev.lost().is_none());
        if let Some((_, dev)) = open.iter().find(|(k, _)| *k == key) {
            return Ok(dev.clone());
        }
        let dev = Self::open_private(policy)?;
        open.push((key, dev.clone()));
        Ok(dev)
    }

    /// A device of its own, on the adapter [`GpuDevice::open`] would choose, shared with no other
    /// caller: its pipelines are compiled anew (or read from the pipeline cache on disk), and its
    /// loss or destruction touches only the batches made on it
    /// ([`crate::BatchEnv::on_device`]).
    pub fn open_private(policy: AdapterPolicy) -> Result<Self, SimError> {
        let shaders = shaders_wanted()?;
        let lane_paths = lane_paths_wanted()?;
        let (instance, backends) = instance();
        let adapters = pollster::block_on(instance.enumerate_adapters(backends));
        let name_filter = std::env::var("WGPU_ADAPTER_NAME")
            .ok()
            .filter(|s| !s.is_empty());
        let chosen = choose(&adapters, policy, name_filter.as_deref())?;
        let adapter = &adapters[chosen];
        let info = adapter.get_info();
        // The adapter's own limits: large batches need storage bindings beyond WebGPU's defaults.
        let limits = adapter.limits();
        // wgpu's pipeline cache, where the backend has one (`pipelines::DiskCache`), and timestamp
        // queries, which time the passes for `socnav bench` (`GpuStages::time_passes`) and,
        // written between commands, a delivered step's readback copies (`timeline`).
        // Shader passthrough, for the backend's own SPIR-V (`super::spirv`): on Vulkan only, and
        // unless SHADERS_VAR says `wgsl` (elsewhere passthrough takes the platform's own shader
        // languages, not SPIR-V).
        let mut wanted = wgpu::Features::PIPELINE_CACHE
            | wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
        if shaders.is_some() && info.backend == wgpu::Backend::Vulkan {
            wanted |= wgpu::Features::PASSTHROUGH_SHADERS;
        }
        let features = adapter.features() & wanted;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("socnav"),
            required_features: features,
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| {
            SimError::BackendUnavailable(format!("cannot open GPU device {}: {e}", info.name))
        })?;
        let errors = Arc::new(Mutex::new(Vec::new()));
        let sink = Arc::clone(&errors);
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            sink.lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .push(e.to_string());
        }));
        let lost = Arc::new(Mutex::new(None));
        let sink = Arc::clone(&lost);
        device.set_device_lost_callback(move |reason, message| {
            *sink
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner) =
                Some(format!("{message} ({reason:?})"));
        });
        let disk = DiskCache::open(&device, features, &info);
        let adapter = AdapterSummary::of(&info);
        let own_spirv = features.contains(wgpu::Features::PASSTHROUGH_SHADERS);
        let dev = Self {
            driver_checks_buffers: own_spirv && vulkan::robust_buffer_access2(&device),
            readback_memory: vulkan::readback_memory(&device),
            staging_memory: vulkan::staging_memory(&device),
            device,
            queue,
            paths: GpuPaths::of_adapter(adapter.hardware),
            own_spirv,
            contraction: shaders.unwrap_or(Contraction::Forbidden),
            adapter,
            limits,
            errors,
            lost,
            pipelines: Arc::new(PipelineCache::new(disk)),
        };
        Ok(if lane_paths {
            dev.with_lane_paths()
        } else {
            dev
        })
    }

    /// The file wgpu's pipeline cache of this device is kept in between processes: on Vulkan
    /// adapters, `pipelines/<adapter key>` in socnav's cache directory (`$SOCNAV_CACHE_DIR`, else
    /// `$XDG_CACHE_HOME/socnav`, else `~/.cache/socnav`); `None` on other backends or with
    /// `SOCNAV_PIPELINE_CACHE=0`.
    pub fn pipeline_cache_file(&self) -> Option<&std::path::Path> {
        self.pipelines.disk_path()
    }

    /// The memory type a mapped readback buffer of this device lives in, with its flags and its
    /// heap's (`GpuDevice::device_description` says it too); `None` off Vulkan.
    pub fn readback_memory(&self) -> Option<&str> {
        self.readback_memory.as_deref()
    }

    /// The memory type wgpu's staging buffers of this device live in (every queue write's: the
    /// step's actions, the reset pool's rows), with its flags and its heap's
    /// (`GpuDevice::device_description` says it too); `None` off Vulkan.
    pub fn staging_memory(&self) -> Option<&str> {
        self.staging_memory.as_deref()
    }

    /// The shader module of entry point `entry` of compute shader `source` (WGSL), built as the
    /// backend builds its stages' (on Vulkan from socnav's SPIR-V, as [`SHADERS_VAR`] says;
    /// elsewhere from the WGSL through wgpu), so that a test kernel runs the code the stages
    /// run. `SimError::Internal` names a shader naga cannot compile.
    pub fn compute_module(
        &self,
        label: &str,
        source: &str,
        entry: &str,
    ) -> Result<wgpu::ShaderModule, SimError> {
        super::pipelines::shader_module(self, label, source, entry)
    }

    /// Compute pipelines compiled on this device so far, by every batch that shares it.
    pub fn pipeline_builds(&self) -> usize {
        self.pipelines.builds()
    }

    /// Why the device was lost, or `None` while it works.
    pub fn lost(&self) -> Option<String> {
        self.lost
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .clone()
    }

    /// `SimError::Device` when the device was lost (see the module docs).
    pub fn check_lost(&self) -> Result<(), SimError> {
        match self.lost() {
            None => Ok(()),
            Some(why) => Err(SimError::Device(format!(
                "the GPU device ({}) was lost: {why}; drop this batch and make a new one",
                self.adapter.name
            ))),
        }
    }

    /// The validation errors wgpu reported since the last call, as one error; the loss of the
    /// device first.
    pub fn take_errors(&self) -> Result<(), SimError> {
        self.check_lost()?;
        let mut errors = self
            .errors
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if errors.is_empty() {
            return Ok(());
        }
        let msg = errors.join("; ");
        errors.clear();
        Err(SimError::Device(format!("the GPU device reported: {msg}")))
    }
}

impl Compiler for GpuDevice {
    fn wgpu(&self) -> &wgpu::Device {
        &self.device
    }

    fn own_spirv(&self) -> Option<(BufferBounds, Contraction)> {
        let bounds = if self.driver_checks_buffers {
            BufferBounds::Driver
        } else {
            BufferBounds::Clamped
        };
        self.own_spirv.then_some((bounds, self.contraction))
    }

    fn pipeline_errors(&self, label: &str) -> Result<(), SimError> {
        self.take_errors().map_err(|e| match e {
            SimError::Device(msg) if self.own_spirv => SimError::Device(format!(
                "{msg} (pipeline {label} built from socnav's SPIR-V; {SHADERS_VAR}=wgsl builds it \
                 from the WGSL through wgpu instead, and {PATHS_VAR}=lane takes a software \
                 adapter's paths)"
            )),
            SimError::Device(msg) => SimError::Device(format!(
                "{msg} (pipeline {label}; {PATHS_VAR}=lane takes a software adapter's paths)"
            )),
            e => e,
        })
    }
}

/// Index of the adapter to open, or why there is none.
fn choose(
    adapters: &[wgpu::Adapter],
    policy: AdapterPolicy,
    name_filter: Option<&str>,
) -> Result<usize, SimError> {
    let infos: Vec<wgpu::AdapterInfo> = adapters.iter().map(wgpu::Adapter::get_info).collect();
    let listing = || {
        if infos.is_empty() {
            "none".to_owned()
        } else {
            infos
                .iter()
                .map(|i| AdapterSummary::of(i).to_string())
                .collect::<Vec<_>>()
                .join("; ")
        }
    };
    let candidates: Vec<usize> = match name_filter {
        Some(name) => {
            let needle = name.to_lowercase();
            let found: Vec<usize> = (0..infos.len())
                .filter(|&k| infos[k].name.to_lowercase().contains(&needle))
                .collect();
            if found.is_empty() {
                return Err(SimError::BackendUnavailable(format!(
                    "WGPU_ADAPTER_NAME={name:?} matches no usable adapter (adapters: {})",
                    listing()
                )));
            }
            found
        }
        None => (0..infos.len())
            .filter(|&k| policy == AdapterPolicy::Any || is_hardware(infos[k].device_type))
            .collect(),
    };
    candidates
        .into_iter()
        .min_by_key(|&k| rank(infos[k].device_type))
        .ok_or_else(|| {
            // A machine with only a software adapter (Mesa's lavapipe) has its driver: it just
            // has no hardware GPU, which `--backend auto` needs.
            SimError::BackendUnavailable(match policy {
                AdapterPolicy::Hardware if !infos.is_empty() => "no hardware GPU found".to_owned(),
                AdapterPolicy::Hardware => format!("no GPU found; {INSTALL_HINT}"),
                AdapterPolicy::Any => format!("no GPU adapter found; {INSTALL_HINT}"),
            })
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shaders_variable_chooses_the_spirv_or_names_its_bad_value() {
        for value in [None, Some(""), Some("spirv")] {
            assert_eq!(
                shaders_from(value).unwrap(),
                Some(Contraction::Forbidden),
                "{value:?}"
            );
        }
        assert_eq!(
            shaders_from(Some("spirv-fma")).unwrap(),
            Some(Contraction::Allowed)
        );
        assert_eq!(shaders_from(Some("wgsl")).unwrap(), None);
        let e = shaders_from(Some("SPIR-V")).unwrap_err().to_string();
        assert!(e.contains(SHADERS_VAR) && e.contains("\"SPIR-V\""), "{e}");
        assert!(e.contains("\"spirv-fma\" or \"wgsl\""), "{e}");
    }

    #[test]
    fn the_paths_variable_chooses_the_lane_paths_or_names_its_bad_value() {
        for value in [None, Some(""), Some("device")] {
            assert!(!lane_paths_from(value).unwrap(), "{value:?}");
        }
        assert!(lane_paths_from(Some("lane")).unwrap());
        let e = lane_paths_from(Some("lanes")).unwrap_err().to_string();
        assert!(e.contains(PATHS_VAR) && e.contains("\"lanes\""), "{e}");
    }
}
