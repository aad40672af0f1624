//! What the GPU backend asks a Vulkan device's driver itself, through the handles wgpu-hal
//! exposes (wgpu's `vulkan` feature covers Windows, Linux, Android and FreeBSD): whether buffer
//! bounds are the driver's, and which memory the mapped buffers live in (the bench's device line).
//! Elsewhere nothing is asked.

/// On a platform with wgpu's Vulkan backend.
#[cfg(any(
    windows,
    target_os = "linux",
    target_os = "android",
    target_os = "freebsd"
))]
#[expect(
    unsafe_code,
    reason = "wgpu exposes the Vulkan handles only through the unsafe `as_hal`; sound, see each use"
)]
mod imp {
    /// Whether `device` is a Vulkan device that wgpu opened with `robustBufferAccess2` enabled:
    /// wgpu-hal enables `VK_EXT_robustness2` wherever the driver offers it, with that feature
    /// where the physical device has it (its adapter's `naga_options` then leave buffer bounds
    /// unchecked), but does not say so; this asks the driver the same question.
    pub(crate) fn robust_buffer_access2(device: &wgpu::Device) -> bool {
        use ash::vk;
        // SAFETY: the handles are only read, to query features of the physical device, while the
        // guard keeps the device alive; nothing is created or destroyed.
        let Some(hal) = (unsafe { device.as_hal::<wgpu::hal::api::Vulkan>() }) else {
            return false;
        };
        if !hal
            .enabled_device_extensions()
            .contains(&ash::ext::robustness2::NAME)
        {
            return false;
        }
        let shared = hal.shared_instance();
        let mut robustness2 = vk::PhysicalDeviceRobustness2FeaturesEXT::default();
        let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut robustness2);
        if shared.instance_api_version() >= vk::API_VERSION_1_1 {
            // SAFETY: a Vulkan 1.1 instance has the entry point; the physical device is its own.
            unsafe {
                shared
                    .raw_instance()
                    .get_physical_device_features2(hal.raw_physical_device(), &mut features);
            }
        } else if shared
            .extensions()
            .contains(&ash::khr::get_physical_device_properties2::NAME)
        {
            let loader = ash::khr::get_physical_device_properties2::Instance::new(
                shared.entry(),
                shared.raw_instance(),
            );
            // SAFETY: the instance enabled the extension; the physical device is its own.
            unsafe {
                loader.get_physical_device_features2(hal.raw_physical_device(), &mut features)
            };
        } else {
            return false;
        }
        robustness2.robust_buffer_access2 == vk::TRUE
    }

    /// The memory a mapped readback buffer of `device` lives in (`MAP_READ | COPY_DST`, every
    /// step readback piece), as wgpu's allocator (gpu-allocator, `MemoryLocation::GpuToCpu`)
    /// picks it: the first memory type the buffer allows that is host-visible, coherent and
    /// cached, else the first host-visible and coherent one. The copy out of the step's readback
    /// is one of the delivered step's longest parts on hardware, and reads from uncached memory
    /// would explain its speed (docs/performance.md), so the bench's device line says which it
    /// is.
    pub(crate) fn readback_memory(device: &wgpu::Device) -> Option<String> {
        mapped_memory(
            device,
            ash::vk::BufferUsageFlags::TRANSFER_DST,
            ash::vk::MemoryPropertyFlags::HOST_CACHED,
        )
    }

    /// The memory wgpu's staging buffers of `device` live in (`MAP_WRITE | COPY_SRC`: every
    /// queue write's, the step's actions and pool rows among them), as its allocator
    /// (`MemoryLocation::CpuToGpu`) picks it: host-visible, coherent and device-local first (on
    /// a discrete GPU, device memory the host writes across the bus, uncached), else host-visible
    /// and coherent. The large writes are split over the host's threads for the first
    /// (`kit::write_buffer_split`), and the bench's device line says which it is.
    pub(crate) fn staging_memory(device: &wgpu::Device) -> Option<String> {
        mapped_memory(
            device,
            ash::vk::BufferUsageFlags::TRANSFER_SRC,
            ash::vk::MemoryPropertyFlags::DEVICE_LOCAL,
        )
    }

    /// The memory type gpu-allocator picks for a mapped buffer of `usage` on `device`: the first
    /// the buffer allows that is host-visible, coherent and `preferred`, else the first
    /// host-visible and coherent one; with its flags and its heap's.
    fn mapped_memory(
        device: &wgpu::Device,
        usage: ash::vk::BufferUsageFlags,
        preferred: ash::vk::MemoryPropertyFlags,
    ) -> Option<String> {
        use ash::vk;
        // SAFETY: a probe buffer is created on the device and destroyed before the guard is
        // dropped, never bound or used; everything else is a query of the physical device.
        let hal = unsafe { device.as_hal::<wgpu::hal::api::Vulkan>() }?;
        let raw = hal.raw_device();
        let probe = vk::BufferCreateInfo::default()
            .size(1 << 16)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: see above.
        let buffer = unsafe { raw.create_buffer(&probe, None) }.ok()?;
        // SAFETY: the buffer is this device's and alive.
        let allowed = unsafe { raw.get_buffer_memory_requirements(buffer) }.memory_type_bits;
        // SAFETY: the buffer is this device's, unbound and unused.
        unsafe { raw.destroy_buffer(buffer, None) };
        // SAFETY: the physical device is the instance's own.
        let memory = unsafe {
            hal.shared_instance()
                .raw_instance()
                .get_physical_device_memory_properties(hal.raw_physical_device())
        };
        let types = &memory.memory_types[..memory.memory_type_count as usize];
        let visible =
            vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        let pick = |wanted: vk::MemoryPropertyFlags| {
            (0..types.len())
                .find(|&i| allowed & (1 << i) != 0 && types[i].property_flags.contains(wanted))
        };
        let i = pick(visible | preferred).or_else(|| pick(visible))?;
        let heap = memory.memory_heaps[types[i].heap_index as usize];
        Some(format!(
            "memory type {i} ({:?}) of heap {} ({} MiB, {:?})",
            types[i].property_flags,
            types[i].heap_index,
            heap.size >> 20,
            heap.flags
        ))
    }
}

/// No Vulkan backend on this platform: nothing to ask.
#[cfg(not(any(
    windows,
    target_os = "linux",
    target_os = "android",
    target_os = "freebsd"
)))]
mod imp {
    pub(crate) fn robust_buffer_access2(_: &wgpu::Device) -> bool {
        false
    }

    pub(crate) fn readback_memory(_: &wgpu::Device) -> Option<String> {
        None
    }

    pub(crate) fn staging_memory(_: &wgpu::Device) -> Option<String> {
        None
    }
}

pub(crate) use imp::{readback_memory, robust_buffer_access2, staging_memory};
