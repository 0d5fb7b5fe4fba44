//! Blocking reads of the last frame's images for pictures, tests and
//! experiments (never used by the frame loop itself), and shadow-map
//! visualisation.

use super::depth_copy::DepthCopy;
use super::{device, RenderError, Renderer};
use crate::mesh::ShadowMasks;

/// A shadow map read back: depth per texel, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthImage {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Depth in `[0, 1]` per texel (1 where nothing was drawn).
    pub depth: Vec<f32>,
}

/// A picture of a shadow map: depth mapped to grey, nearest to the light
/// brightest, normalised over the drawn texels; texels where nothing was
/// drawn (depth 1, the clear value) are dark blue.
#[must_use]
pub fn shadow_map_image(map: &DepthImage) -> image::RgbaImage {
    let empty = 1.0;
    let drawn = || map.depth.iter().copied().filter(move |&d| d != empty);
    let lo = drawn().fold(f32::INFINITY, f32::min);
    let hi = drawn().fold(f32::NEG_INFINITY, f32::max);
    let span = if hi > lo { hi - lo } else { 1.0 };
    image::RgbaImage::from_fn(map.width, map.height, |x, y| {
        let d = map.depth[(y * map.width + x) as usize];
        if d == empty {
            return image::Rgba([20, 24, 60, 255]);
        }
        let t = 1.0 - (d - lo) / span;
        let g = (40.0 + 215.0 * t).round() as u8;
        image::Rgba([g, g, g, 255])
    })
}

impl Renderer {
    /// The last frame's colour image (sRGB). Blocks until the GPU is done.
    ///
    /// # Errors
    /// [`RenderError::NothingRendered`] before the first frame; mapping or
    /// polling failures.
    pub fn read_color(&self) -> Result<image::RgbaImage, RenderError> {
        let targets = self.camera_targets.as_ref().ok_or(RenderError::NothingRendered)?;
        let bytes =
            self.read_texture(&targets.color.texture, wgpu::TextureAspect::All, 0, targets.width, targets.height, 4)?;
        image::RgbaImage::from_raw(targets.width, targets.height, bytes).ok_or(RenderError::NothingRendered)
    }

    /// The last frame's full-resolution masks. Only meaningful when that
    /// frame was rendered with [`Frame::masks`](super::Frame::masks) set.
    /// Blocks until the GPU is done.
    ///
    /// # Errors
    /// [`RenderError::NothingRendered`] before the first frame; mapping or
    /// polling failures.
    pub fn read_masks(&self) -> Result<ShadowMasks, RenderError> {
        let targets = self.camera_targets.as_ref().ok_or(RenderError::NothingRendered)?;
        let bytes =
            self.read_texture(&targets.masks.texture, wgpu::TextureAspect::All, 0, targets.width, targets.height, 16)?;
        let words: &[u32] = bytemuck::cast_slice(&bytes);
        Ok(ShadowMasks {
            width: targets.width,
            height: targets.height,
            depth: words.chunks_exact(4).map(|t| f32::from_bits(t[0])).collect(),
            shadow: words.chunks_exact(4).map(|t| t[1]).collect(),
            facing: words.chunks_exact(4).map(|t| t[2]).collect(),
        })
    }

    /// Light `light`'s shadow map from the last frame. Blocks until the GPU
    /// is done. The depth goes through a colour target (see `depth_copy.rs`),
    /// so this works on the GL backend too.
    ///
    /// # Errors
    /// [`RenderError::NoSuchLight`]; device, mapping or polling failures.
    pub fn read_shadow_map(&self, light: usize) -> Result<DepthImage, RenderError> {
        let matrix =
            self.last_lights.get(light).ok_or(RenderError::NoSuchLight { light, count: self.last_lights.len() })?;
        let (width, height) = (matrix.map_size.width, matrix.map_size.height);
        let maps = &self.lookups[self.last_lookup.ok_or(RenderError::NothingRendered)?].maps;
        let copy = match self.depth_copy.get() {
            Some(copy) => copy,
            None => {
                let copy =
                    device::capture(&self.device, "shadow-map readback pipeline", || DepthCopy::new(&self.device))?;
                self.depth_copy.get_or_init(|| copy)
            }
        };
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("lixel shadow-map readback") });
        let target = device::capture(&self.device, "shadow-map readback", || {
            copy.encode(&self.device, &mut encoder, &maps.depth_array, light as u32, width, height)
        })?;
        self.queue.submit([encoder.finish()]);
        let bytes = self.read_texture(&target.texture, wgpu::TextureAspect::All, 0, width, height, 4)?;
        let depth = bytemuck::cast_slice::<u8, u32>(&bytes).iter().map(|&bits| f32::from_bits(bits)).collect();
        Ok(DepthImage { width, height, depth })
    }

    /// Light `light`'s per-texel words from the last frame, for lookup modes
    /// that store more than depth (SPSM: see
    /// [`spsm::packing`](super::spsm::packing)); row-major, rows top to
    /// bottom. `Ok(None)` when the last frame's mode has only depth. Blocks
    /// until the GPU is done.
    ///
    /// # Errors
    /// [`RenderError::NoSuchLight`]; [`RenderError::NothingRendered`];
    /// mapping or polling failures.
    pub fn read_map_words(&self, light: usize) -> Result<Option<Vec<[u32; 4]>>, RenderError> {
        let matrix =
            self.last_lights.get(light).ok_or(RenderError::NoSuchLight { light, count: self.last_lights.len() })?;
        let maps = &self.lookups[self.last_lookup.ok_or(RenderError::NothingRendered)?].maps;
        let Some(texture) = &maps.color else { return Ok(None) };
        if texture.format() != wgpu::TextureFormat::Rgba32Uint {
            return Ok(None);
        }
        let (width, height) = (matrix.map_size.width, matrix.map_size.height);
        let bytes = self.read_texture(texture, wgpu::TextureAspect::All, light as u32, width, height, 16)?;
        Ok(Some(bytemuck::cast_slice::<u8, [u32; 4]>(&bytes).to_vec()))
    }

    /// Copies the top-left `width x height` texels of one layer into a
    /// buffer and waits for it. Returns tightly packed rows.
    pub(super) fn read_texture(
        &self,
        texture: &wgpu::Texture,
        aspect: wgpu::TextureAspect,
        layer: u32,
        width: u32,
        height: u32,
        texel_bytes: u32,
    ) -> Result<Vec<u8>, RenderError> {
        let row = width * texel_bytes;
        let padded = row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lixel blocking readback"),
            size: u64::from(padded) * u64::from(height),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("lixel blocking readback") });
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d { x: 0, y: 0, z: layer },
                aspect,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(height),
                },
            },
            wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        );
        self.queue.submit([encoder.finish()]);
        let (sender, receiver) = std::sync::mpsc::channel();
        buffer.map_async(wgpu::MapMode::Read, .., move |result| {
            let _ = sender.send(result);
        });
        self.device.poll(wgpu::PollType::wait_indefinitely())?;
        self.errors.take(&self.device, "reading back a texture")?;
        receiver.recv().map_err(|_| RenderError::Map(wgpu::BufferAsyncError))??;
        let mut out = Vec::with_capacity((row * height) as usize);
        {
            let view = buffer.get_mapped_range(..).map_err(|_| RenderError::Map(wgpu::BufferAsyncError))?;
            for y in 0..height as usize {
                out.extend_from_slice(&view[y * padded as usize..y * padded as usize + row as usize]);
            }
        }
        buffer.unmap();
        Ok(out)
    }
}

/// A picture of shadow masks: background black; visible pixels grey, with
/// light 0's shadow in red, light 1's in green and light 2's in blue
/// (further lights are not shown); pixels facing away from every light dark.
#[must_use]
pub fn masks_image(masks: &ShadowMasks) -> image::RgbaImage {
    image::RgbaImage::from_fn(masks.width, masks.height, |x, y| {
        let i = (y * masks.width + x) as usize;
        if !masks.visible(i) {
            return image::Rgba([0, 0, 0, 255]);
        }
        let base: u8 = if masks.facing[i] == 0 { 60 } else { 150 };
        let channel = |light: u32| if masks.shadow[i] >> light & 1 == 1 { 255 } else { base };
        image::Rgba([channel(0), channel(1), channel(2), 255])
    })
}
