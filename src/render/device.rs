//! Opening a device for the renderer, and device errors as values.
//!
//! Why a module of its own: on a machine without a GPU, wgpu finds Vulkan
//! only where lavapipe (`mesa-vulkan-drivers`) is installed, and otherwise
//! Mesa's llvmpipe through GL/EGL. [`Gpu::open`] prefers Vulkan, falls back
//! to GL and honours `WGPU_BACKEND` (or the caller's explicit choice); it is
//! called once, never on a frame's path. The renderer itself still takes any
//! `&wgpu::Device`.
//!
//! wgpu's default reaction to a validation or out-of-memory error is a
//! panic. The renderer instead wraps resource and pipeline creation and each
//! frame in error scopes (`capture`) and installs an uncaptured-error
//! handler (`DeviceErrors`) as a backstop, so such errors come back as
//! [`RenderError::Device`] naming the backend, the adapter and the pass.

use std::sync::{Arc, Mutex};

use super::{RenderError, Renderer};

/// A device and queue with the renderer's optional features where the
/// adapter has them, and the adapter's description.
#[derive(Debug)]
pub struct Gpu {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter it was opened on.
    pub info: wgpu::AdapterInfo,
}

impl Gpu {
    /// Opens a device on the first backend of the candidates that has an
    /// adapter: `backends` when given, else `WGPU_BACKEND` when set, else
    /// Vulkan and then GL. The device's texture limit is the adapter's own
    /// (lavapipe: 16384), since large maps need it.
    ///
    /// # Errors
    /// [`RenderError::NoAdapter`] when no candidate has an adapter;
    /// [`RenderError::Device`] when the adapter refuses the device.
    pub fn open(backends: Option<wgpu::Backends>, label: &str) -> Result<Self, RenderError> {
        let candidates = match backends.or_else(wgpu::Backends::from_env) {
            Some(chosen) => vec![chosen],
            None => vec![wgpu::Backends::VULKAN, wgpu::Backends::GL],
        };
        let mut failures = Vec::new();
        for backends in candidates {
            let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
            descriptor.backends = backends;
            let instance = wgpu::Instance::new(descriptor);
            let adapter = match pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default())) {
                Ok(adapter) => adapter,
                Err(e) => {
                    failures.push(format!("{}: {e}", backend_names(backends)));
                    continue;
                }
            };
            return Self::on_adapter(&adapter, label);
        }
        Err(RenderError::NoAdapter { tried: failures.join("; ") })
    }

    /// Opens another device on the adapter `info` describes (same backend,
    /// vendor, device id and name): a second queue on the same GPU, as the
    /// experiment's workers use (on lavapipe, a second queue thread).
    ///
    /// # Errors
    /// [`RenderError::NoAdapter`] when no such adapter is found;
    /// [`RenderError::Device`] when it refuses the device.
    pub fn open_like(info: &wgpu::AdapterInfo, label: &str) -> Result<Self, RenderError> {
        let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        descriptor.backends = info.backend.into();
        let instance = wgpu::Instance::new(descriptor);
        let adapters = pollster::block_on(instance.enumerate_adapters(info.backend.into()));
        let same = |a: &wgpu::Adapter| {
            let other = a.get_info();
            (other.backend, other.vendor, other.device, &other.name)
                == (info.backend, info.vendor, info.device, &info.name)
        };
        match adapters.iter().find(|a| same(a)) {
            Some(adapter) => Self::on_adapter(adapter, label),
            None => Err(RenderError::NoAdapter { tried: format!("{} again for another device", describe(info)) }),
        }
    }

    /// A device on `adapter` with the renderer's optional features and the
    /// adapter's own texture limit.
    fn on_adapter(adapter: &wgpu::Adapter, label: &str) -> Result<Self, RenderError> {
        let info = adapter.get_info();
        let required_limits = wgpu::Limits {
            max_texture_dimension_2d: adapter.limits().max_texture_dimension_2d,
            ..wgpu::Limits::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some(label),
            required_features: adapter.features() & Renderer::optional_features(),
            required_limits,
            ..Default::default()
        }))
        .map_err(|e| RenderError::Device {
            backend: info.backend.to_string(),
            adapter: info.name.clone(),
            pass: "opening the device",
            message: e.to_string(),
            hint: hint(info.backend),
        })?;
        Ok(Self { device, queue, info })
    }

    /// `"<adapter> (<backend>)"`, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) (vulkan)`.
    #[must_use]
    pub fn describe(&self) -> String {
        describe(&self.info)
    }
}

/// `"<adapter> (<backend>)"`.
#[must_use]
pub fn describe(info: &wgpu::AdapterInfo) -> String {
    format!("{} ({})", info.name, info.backend)
}

fn backend_names(backends: wgpu::Backends) -> String {
    let names = [
        (wgpu::Backends::VULKAN, "vulkan"),
        (wgpu::Backends::GL, "gl"),
        (wgpu::Backends::METAL, "metal"),
        (wgpu::Backends::DX12, "dx12"),
    ];
    let known: Vec<&str> = names.iter().filter(|(b, _)| backends.contains(*b)).map(|(_, n)| *n).collect();
    if known.is_empty() {
        format!("{backends:?}")
    } else {
        known.join("+")
    }
}

/// What a user can do about a device error on `backend`, where we know.
fn hint(backend: wgpu::Backend) -> Option<&'static str> {
    (backend == wgpu::Backend::Gl)
        .then_some("the Vulkan backend is the tested one: install mesa-vulkan-drivers for lavapipe")
}

/// Runs `create` inside validation, out-of-memory and internal error scopes
/// and returns its value, or the first error as [`RenderError::Device`] for
/// `pass`.
pub(crate) fn capture<T>(
    device: &wgpu::Device,
    pass: &'static str,
    create: impl FnOnce() -> T,
) -> Result<T, RenderError> {
    let scopes = [wgpu::ErrorFilter::Validation, wgpu::ErrorFilter::OutOfMemory, wgpu::ErrorFilter::Internal]
        .map(|filter| device.push_error_scope(filter));
    let value = create();
    let mut first = None;
    // Pop innermost first.
    for scope in scopes.into_iter().rev() {
        let error = pollster::block_on(scope.pop());
        first = first.or(error);
    }
    match first {
        None => Ok(value),
        Some(error) => Err(device_error(device, pass, &error)),
    }
}

/// A wgpu error as [`RenderError::Device`].
pub(crate) fn device_error(device: &wgpu::Device, pass: &'static str, error: &wgpu::Error) -> RenderError {
    let info = device.adapter_info();
    let oom = matches!(error, wgpu::Error::OutOfMemory { .. });
    RenderError::Device {
        backend: info.backend.to_string(),
        adapter: info.name,
        pass,
        message: error.to_string(),
        hint: if oom { Some("out of GPU memory: use smaller maps or targets") } else { hint(info.backend) },
    }
}

/// Errors no scope caught, recorded by the device's uncaptured-error
/// handler instead of wgpu's default panic; the renderer hands the first
/// back from its next call.
#[derive(Clone, Debug, Default)]
pub(crate) struct DeviceErrors {
    first: Arc<Mutex<Option<String>>>,
}

impl DeviceErrors {
    /// Installs the handler on `device` (replacing any other).
    pub(crate) fn install(device: &wgpu::Device) -> Self {
        let errors = Self::default();
        let first = Arc::clone(&errors.first);
        device.on_uncaptured_error(Arc::new(move |error: wgpu::Error| {
            if let Ok(mut slot) = first.lock() {
                slot.get_or_insert_with(|| error.to_string());
            }
        }));
        errors
    }

    /// The first recorded error, as [`RenderError::Device`] for `pass`.
    pub(crate) fn take(&self, device: &wgpu::Device, pass: &'static str) -> Result<(), RenderError> {
        let message = self.first.lock().ok().and_then(|mut slot| slot.take());
        match message {
            None => Ok(()),
            Some(message) => {
                let info = device.adapter_info();
                Err(RenderError::Device {
                    backend: info.backend.to_string(),
                    adapter: info.name,
                    pass,
                    message,
                    hint: hint(info.backend),
                })
            }
        }
    }
}
