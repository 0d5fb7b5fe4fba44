//! Brute-force supersampling of the standard lookup
//! ([`ShadowLookup::Supersampled`]): the baseline the antialiased lookup's
//! cost goal is stated against (issue 18: "≥ 5× cheaper than a 32-sample
//! supersampled standard pipeline giving the same error").
//!
//! What a renderer without the paper's machinery does for N-sample
//! antialiasing of shadows is to shade N sub-samples per pixel: here the
//! camera pass is drawn N more times, each with the projection shifted so
//! that the pixel centres fall on one sub-sample position of
//! [`SAMPLE_POSITIONS`] (the positions the coverage
//! truth traces), into targets of its own; after each pass a compute pass
//! (`shaders/aa_supersample.wgsl`) gathers that pass's shadow and
//! light-facing bits into per-pixel words. The shadow maps are rendered
//! once per frame, as for every other mode. Each sub-sample sees its own
//! surface (as the truth's primary rays do), so the words answer the
//! truth's question — lit among the sub-samples facing the light — with
//! the depth compare instead of a shadow ray: the only error left is the
//! map's. The frame's ordinary (centre) camera pass still runs, for the
//! picture, the masks and the binary bit: N + 1 camera passes in all.
//!
//! The jittered passes switch matrices by copying prepared camera uniforms
//! into the camera buffer between passes (copies are ordered with passes),
//! so one submission holds the whole frame.
//!
//! [`ShadowLookup::Supersampled`]: crate::render::ShadowLookup::Supersampled

use std::borrow::Cow;

use glam::{DMat4, DVec3};

use super::{AaSamples, SAMPLE_POSITIONS};
use crate::render::encode::CameraOutput;
use crate::render::passes::{storage_entry, CameraTargets};
use crate::render::uniforms::CameraRaw;
use crate::render::{device, RenderError, Renderer};
use crate::Camera;

/// Dynamic-offset stride of the per-sample parameters.
const PARAM_STRIDE: u64 = 256;

/// One light's words of the last supersampled frame, one per camera pixel
/// (row-major, row 0 at the top); bit `s` is sub-sample `s` of
/// [`SAMPLE_POSITIONS`] (only the pattern's bits).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct SupersampledWords {
    /// The sub-sample's surface faces the light (inside a spot's cone).
    pub valid: Vec<u32>,
    /// The sub-sample is valid and the depth compare shadows it.
    pub occluded: Vec<u32>,
}

impl SupersampledWords {
    /// Pixel `i`'s visibility: the share of its valid sub-samples that are
    /// not occluded; `None` when none is valid.
    #[must_use]
    pub fn visibility(&self, i: usize) -> Option<f64> {
        let valid = *self.valid.get(i)?;
        let lit = valid & !self.occluded[i];
        (valid != 0).then(|| f64::from(lit.count_ones()) / f64::from(valid.count_ones()))
    }
}

/// `Params` in the shader.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ParamsRaw {
    sample: u32,
    width: u32,
    height: u32,
    lights: u32,
}

/// Targets and words for one viewport and light count.
struct Sized {
    width: u32,
    height: u32,
    lights: u32,
    targets: CameraTargets,
    words: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// The gather pipeline and the per-frame buffers.
pub(crate) struct SupersamplePass {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    /// 33 `CameraRaw`: the jittered ones, then the centre one.
    cameras: wgpu::Buffer,
    sized: Option<Sized>,
    /// (lights gathered, samples) of the last frame.
    last: Option<(u32, AaSamples)>,
}

/// The clip matrix whose pixel centres fall on sub-sample `offset` (pixel
/// coordinates from the pixel's top-left corner, `y` down) of `clip`.
#[must_use]
pub(crate) fn jittered(clip: &DMat4, offset: glam::DVec2, width: u32, height: u32) -> DMat4 {
    let dx = -(2.0 * offset.x - 1.0) / f64::from(width);
    let dy = (2.0 * offset.y - 1.0) / f64::from(height);
    DMat4::from_translation(DVec3::new(dx, dy, 0.0)) * *clip
}

impl SupersamplePass {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lixel supersample group"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: true,
                        min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<ParamsRaw>() as u64),
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Uint,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                storage_entry(2, wgpu::ShaderStages::COMPUTE, false, false),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lixel supersample pipeline layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("lixel supersample gather"),
            source: wgpu::ShaderSource::Wgsl(Cow::Borrowed(include_str!("../../../shaders/aa_supersample.wgsl"))),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("lixel supersample gather"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("gather"),
            compilation_options: Default::default(),
            cache: None,
        });
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lixel supersample parameters"),
            size: PARAM_STRIDE * SAMPLE_POSITIONS.len() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let cameras = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lixel supersample cameras"),
            size: (SAMPLE_POSITIONS.len() as u64 + 1) * std::mem::size_of::<CameraRaw>() as u64,
            usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self { layout, pipeline, params, cameras, sized: None, last: None }
    }

    fn ensure(&mut self, device: &wgpu::Device, width: u32, height: u32, lights: u32) {
        if self.sized.as_ref().is_some_and(|s| (s.width, s.height, s.lights) == (width, height, lights)) {
            return;
        }
        let targets = CameraTargets::new(device, "lixel supersample", width, height);
        let words = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lixel supersample words"),
            size: 8 * u64::from(width) * u64::from(height) * u64::from(lights.max(1)),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lixel supersample group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &self.params,
                        offset: 0,
                        size: wgpu::BufferSize::new(std::mem::size_of::<ParamsRaw>() as u64),
                    }),
                },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&targets.masks.view) },
                wgpu::BindGroupEntry { binding: 2, resource: words.as_entire_binding() },
            ],
        });
        self.sized = Some(Sized { width, height, lights, targets, words, bind_group });
    }
}

impl Renderer {
    /// The lights whose words fit one storage binding of this device (8
    /// bytes per pixel and light); later lights are not gathered.
    fn supersample_lights(&self, lights: usize, pixels: u64) -> u32 {
        let limit = self.device.limits().max_storage_buffer_binding_size;
        (lights as u64).min(limit / (8 * pixels).max(1)) as u32
    }

    /// Encodes the jittered camera passes and the gathers of one
    /// supersampled frame (after its centre camera pass; the camera
    /// uniforms hold the centre camera again afterwards). `lookup`: the
    /// index of the mode's pipelines.
    pub(crate) fn encode_supersampled(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        lookup: usize,
        camera: &Camera,
        lights: usize,
        samples: AaSamples,
    ) {
        let Some(mut pass) = self.ss.take() else { return };
        let viewport = camera.viewport();
        let (width, height) = (viewport.x, viewport.y);
        let gathered = self.supersample_lights(lights, u64::from(width) * u64::from(height));
        pass.ensure(&self.device, width, height, gathered);
        let sized = pass.sized.as_ref().expect("ensured");
        let (ambient, analysis) = (self.options.ambient, self.options.analysis_size);
        let centre = camera.clip_from_world();
        let raw_size = std::mem::size_of::<CameraRaw>() as u64;
        let n = samples.count() as usize;
        let clips: Vec<DMat4> =
            samples.positions().iter().map(|&offset| jittered(&centre, offset, width, height)).collect();
        for (k, clip) in clips.iter().enumerate() {
            let raw = CameraRaw::with_clip(camera, *clip, ambient, analysis);
            self.queue.write_buffer(&pass.cameras, k as u64 * raw_size, bytemuck::bytes_of(&raw));
            let params = ParamsRaw { sample: k as u32, width, height, lights: gathered };
            self.queue.write_buffer(&pass.params, k as u64 * PARAM_STRIDE, bytemuck::bytes_of(&params));
        }
        let raw = CameraRaw::to_raw(camera, ambient, analysis);
        self.queue.write_buffer(&pass.cameras, n as u64 * raw_size, bytemuck::bytes_of(&raw));
        encoder.clear_buffer(&sized.words, 0, None);
        let state = &self.lookups[lookup];
        let groups = (width.div_ceil(8), height.div_ceil(8));
        for (k, clip) in clips.iter().enumerate() {
            encoder.copy_buffer_to_buffer(&pass.cameras, k as u64 * raw_size, &self.camera_uniforms, 0, raw_size);
            self.encode_camera_pass_into(encoder, state, clip, &sized.targets, CameraOutput::ColorAndMasks, None, None);
            let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("lixel supersample gather"),
                timestamp_writes: None,
            });
            compute.set_pipeline(&pass.pipeline);
            compute.set_bind_group(0, &sized.bind_group, &[(k as u64 * PARAM_STRIDE) as u32]);
            compute.dispatch_workgroups(groups.0, groups.1, 1);
        }
        encoder.copy_buffer_to_buffer(&pass.cameras, n as u64 * raw_size, &self.camera_uniforms, 0, raw_size);
        pass.last = Some((gathered, samples));
        self.ss = Some(pass);
    }

    /// Builds the supersampled mode's gather pass on first use.
    pub(crate) fn ensure_supersample(&mut self) -> Result<(), RenderError> {
        if self.ss.is_none() {
            let pass = device::capture(&self.device, "supersample gather", || SupersamplePass::new(&self.device))?;
            self.ss = Some(pass);
        }
        Ok(())
    }

    /// Light `light`'s sub-sample words of the last frame rendered with
    /// [`ShadowLookup::Supersampled`](crate::render::ShadowLookup::Supersampled).
    /// Blocks until done.
    ///
    /// # Errors
    /// [`RenderError::NothingRendered`] when no frame used the mode;
    /// [`RenderError::NoSuchLight`] for a light the frame did not have (or
    /// whose words did not fit one storage binding); device, mapping or
    /// polling failures.
    pub fn read_supersampled(&self, light: usize) -> Result<SupersampledWords, RenderError> {
        let pass = self.ss.as_ref().ok_or(RenderError::NothingRendered)?;
        let ((gathered, samples), sized) = pass.last.zip(pass.sized.as_ref()).ok_or(RenderError::NothingRendered)?;
        if light >= gathered as usize {
            return Err(RenderError::NoSuchLight { light, count: gathered as usize });
        }
        let pixels = u64::from(sized.width) * u64::from(sized.height);
        let lights = u64::from(sized.lights);
        let mask = samples.mask();
        let read = |first: u64| -> Result<Vec<u32>, RenderError> {
            Ok(self.read_buffer_words(&sized.words, first, pixels)?.into_iter().map(|w| w & mask).collect())
        };
        Ok(SupersampledWords { occluded: read(light as u64 * pixels)?, valid: read((lights + light as u64) * pixels)? })
    }
}

#[cfg(test)]
mod tests {
    use glam::{DVec2, DVec4};

    use super::*;

    #[test]
    fn jittered_pixel_centres_fall_on_the_sub_samples() {
        // A perspective projection (w = z) looking down +z, turned a little.
        let projection = DMat4::from_cols(
            DVec4::new(1.2, 0.0, 0.0, 0.0),
            DVec4::new(0.0, 1.6, 0.0, 0.0),
            DVec4::new(0.0, 0.0, 1.0, 1.0),
            DVec4::new(0.0, 0.0, -0.1, 0.0),
        );
        let clip = projection * DMat4::from_rotation_y(0.3);
        let (w, h) = (37u32, 23u32);
        let to_pixel = |m: &DMat4, p: DVec3| {
            let c = *m * DVec4::from((p, 1.0));
            let ndc = c.truncate().truncate() / c.w;
            DVec2::new((ndc.x + 1.0) * 0.5 * f64::from(w), (1.0 - ndc.y) * 0.5 * f64::from(h))
        };
        for &offset in &SAMPLE_POSITIONS {
            let m = jittered(&clip, offset, w, h);
            for p in [DVec3::new(0.3, -0.2, 4.0), DVec3::new(-1.0, 0.5, 9.0)] {
                // A point seen at pixel position q through `clip` is seen at
                // q - offset + (0.5, 0.5) through the jittered matrix.
                let want = to_pixel(&clip, p) - offset + DVec2::splat(0.5);
                assert!(to_pixel(&m, p).distance(want) < 1e-9, "{offset}");
            }
        }
    }
}
