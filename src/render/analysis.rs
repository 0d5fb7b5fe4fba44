//! The analysis pass's read-back data, decoded.

use glam::{DVec3, Vec2, Vec3};

use super::readback::{Readback, ReadbackLatency};
use crate::mesh::ShadowMasks;
use crate::{Camera, LightMatrix};

/// Bytes per texel of the masks target (`Rgba32Uint`).
pub(crate) const MASK_TEXEL_BYTES: u64 = 16;

/// Bytes per row of a `width`-texel masks copy, padded to wgpu's 256.
pub(crate) fn padded_row_bytes(width: u32) -> u64 {
    let unpadded = u64::from(width) * MASK_TEXEL_BYTES;
    unpadded.div_ceil(u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)) * u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
}

/// What an analysis readback was rendered with.
#[derive(Clone, Debug)]
pub struct AnalysisMeta {
    pub(crate) camera: Camera,
    pub(crate) lights: Vec<LightMatrix>,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) tag: u32,
}

/// One analysis pass read back: the camera's view at low resolution with
/// depth, shadow and light-facing bits and normals, plus the camera and
/// matrices it was rendered with.
#[derive(Clone, Debug)]
pub struct AnalysisReadback {
    /// Frame the pass was rendered in.
    pub frame: u64,
    /// How late it arrived.
    pub latency: ReadbackLatency,
    /// The camera of that frame (its viewport is the full resolution).
    pub camera: Camera,
    /// The matrices whose maps the shadow bits were looked up in.
    pub lights: Vec<LightMatrix>,
    /// The tag of the request.
    pub tag: u32,
    /// Depth, shadow and facing bits at the analysis resolution.
    pub masks: ShadowMasks,
    /// Unit surface normals, one per pixel, row by row (zero for
    /// background); decoded once from the pass's 2x16-bit octahedral words.
    pub normals: Vec<[f32; 3]>,
}

impl AnalysisReadback {
    pub(crate) fn decode(readback: Readback<AnalysisMeta>) -> Self {
        let Readback { meta, frame, bytes, latency } = readback;
        let (w, h) = (meta.width as usize, meta.height as usize);
        let row = padded_row_bytes(meta.width) as usize;
        let mut masks = ShadowMasks {
            width: meta.width,
            height: meta.height,
            depth: Vec::with_capacity(w * h),
            shadow: Vec::with_capacity(w * h),
            facing: Vec::with_capacity(w * h),
        };
        let mut normals = Vec::with_capacity(w * h);
        for y in 0..h {
            let words: &[u32] = bytemuck::cast_slice(&bytes[y * row..y * row + w * MASK_TEXEL_BYTES as usize]);
            for texel in words.chunks_exact(4) {
                let depth = f32::from_bits(texel[0]);
                masks.depth.push(depth);
                masks.shadow.push(texel[1]);
                masks.facing.push(texel[2]);
                let visible = depth < 1.0;
                normals.push(if visible { unpack_normal(texel[3]).to_array() } else { [0.0; 3] });
            }
        }
        Self { frame, latency, camera: meta.camera, lights: meta.lights, tag: meta.tag, masks, normals }
    }

    /// What [`Samples::from_readback`](crate::Samples::from_readback) takes
    /// as shadow bits: per pixel, bit `i` set when light `i` does not light
    /// it (shadowed, or facing away, as a shadow-map test finds it).
    #[must_use]
    pub fn optimizer_bits(&self) -> Vec<u32> {
        let mut bits = Vec::new();
        self.optimizer_bits_into(&mut bits);
        bits
    }

    /// [`optimizer_bits`](Self::optimizer_bits) into `out` (its buffer reused).
    pub fn optimizer_bits_into(&self, out: &mut Vec<u32>) {
        let masks = &self.masks;
        out.clear();
        out.extend(
            masks
                .shadow
                .iter()
                .zip(&masks.facing)
                .enumerate()
                .map(|(i, (&s, &f))| if masks.visible(i) { s | !f } else { 0 }),
        );
    }

    /// The optimizer's input, with `bits` from [`optimizer_bits`](Self::optimizer_bits).
    #[must_use]
    pub fn optimizer_input<'a>(&'a self, bits: &'a [u32]) -> crate::optimize::Readback<'a> {
        crate::optimize::Readback {
            width: self.masks.width,
            height: self.masks.height,
            depth: &self.masks.depth,
            shadow_bits: bits,
            normals: Some(&self.normals),
            layout: crate::optimize::ReadbackLayout::default(),
        }
    }

    /// The optimizer's samples of light `index` (`light` itself, scene
    /// `bounds`, map size `map`), for the camera this pass was rendered with.
    /// For several lights, [`samples_all`](Self::samples_all) shares the work.
    ///
    /// # Errors
    /// Whatever [`ShadowProblem::new`](crate::ShadowProblem::new) or
    /// [`Samples::from_readback`](crate::Samples::from_readback) reports.
    pub fn samples(
        &self,
        light: crate::Light,
        bounds: crate::SceneBounds,
        map: crate::ShadowMapSize,
        index: u32,
    ) -> crate::Result<crate::Samples> {
        let bits = self.optimizer_bits();
        Self::samples_from(&self.optimizer_input(&bits), self.camera, light, bounds, map, index)
    }

    /// The samples of every light: `lights[i]` is bit `i` of the pass. One
    /// pass over the readback serves every light
    /// ([`Samples::from_readback_all`](crate::Samples::from_readback_all));
    /// a light whose problem cannot be built gets its error and the others
    /// their samples.
    #[must_use]
    pub fn samples_all(
        &self,
        lights: &[crate::Light],
        bounds: crate::SceneBounds,
        map: crate::ShadowMapSize,
    ) -> Vec<crate::Result<crate::Samples>> {
        let bits = self.optimizer_bits();
        let input = self.optimizer_input(&bits);
        let lights = &lights[..lights.len().min(crate::MAX_LIGHTS)];
        let problems: crate::Result<Vec<_>> =
            lights.iter().map(|&light| crate::ShadowProblem::new(self.camera, light, bounds, map)).collect();
        let options = crate::optimize::SampleOptions::default();
        match problems.and_then(|problems| crate::Samples::from_readback_all(&problems, &input, &options)) {
            Ok(all) => all.into_iter().map(Ok).collect(),
            // Some light's problem failed: light by light, so that each
            // keeps its own bit and its own error.
            Err(_) => (0..lights.len())
                .map(|i| Self::samples_from(&input, self.camera, lights[i], bounds, map, i as u32))
                .collect(),
        }
    }

    /// [`samples_all`](Self::samples_all) into kept buffers: `out` (the
    /// previous call's samples), `workspace` and `bits` (the shadow bits)
    /// are reused, so that an engine's analysis frames stop allocating per
    /// light ([`Samples::from_readback_all_into`](crate::Samples::from_readback_all_into)).
    /// On success `out[i]` equals `samples_all(..)[i]`.
    ///
    /// # Errors
    /// When some light's problem cannot be built or the extraction refuses;
    /// `out` is then left as it was, and [`samples_all`](Self::samples_all)
    /// gives each light its own samples or error.
    pub fn samples_all_into(
        &self,
        lights: &[crate::Light],
        bounds: crate::SceneBounds,
        map: crate::ShadowMapSize,
        out: &mut Vec<crate::Samples>,
        workspace: &mut crate::optimize::SampleWorkspace,
        bits: &mut Vec<u32>,
    ) -> crate::Result<()> {
        let lights = &lights[..lights.len().min(crate::MAX_LIGHTS)];
        let problems: Vec<_> = lights
            .iter()
            .map(|&light| crate::ShadowProblem::new(self.camera, light, bounds, map))
            .collect::<crate::Result<_>>()?;
        self.optimizer_bits_into(bits);
        let input = self.optimizer_input(bits);
        let options = crate::optimize::SampleOptions::default();
        crate::Samples::from_readback_all_into(&problems, &input, &options, out, workspace)
    }

    fn samples_from(
        input: &crate::optimize::Readback<'_>,
        camera: Camera,
        light: crate::Light,
        bounds: crate::SceneBounds,
        map: crate::ShadowMapSize,
        index: u32,
    ) -> crate::Result<crate::Samples> {
        let problem = crate::ShadowProblem::new(camera, light, bounds, map)?;
        crate::Samples::from_readback(&problem, input, index, &crate::optimize::SampleOptions::default())
    }

    /// The unit surface normal at pixel `(x, y)` (zero for background).
    #[must_use]
    pub fn normal(&self, x: u32, y: u32) -> Vec3 {
        Vec3::from_array(self.normals[(y * self.masks.width + x) as usize])
    }

    /// Full-resolution screen coordinates `(x1, x2, x3)` of the centre of
    /// analysis pixel `(x, y)`: pixels of the camera's viewport and the
    /// depth-buffer value, i.e. the point `y` of math.md §2 (`S [Xw; 1]`).
    #[must_use]
    pub fn screen_point(&self, x: u32, y: u32) -> DVec3 {
        let i = (y * self.masks.width + x) as usize;
        let scale =
            self.camera.viewport().as_dvec2() / glam::DVec2::new(self.masks.width.into(), self.masks.height.into());
        DVec3::new((f64::from(x) + 0.5) * scale.x, (f64::from(y) + 0.5) * scale.y, f64::from(self.masks.depth[i]))
    }

    /// World position of the surface at analysis pixel `(x, y)`; `None` for
    /// background.
    #[must_use]
    pub fn world_point(&self, x: u32, y: u32) -> Option<DVec3> {
        let i = (y * self.masks.width + x) as usize;
        self.masks.visible(i).then(|| {
            let world_from_screen = self.camera.screen_from_world().inverse();
            world_from_screen.project_point3(self.screen_point(x, y))
        })
    }
}

/// Inverse of `pack_normal` in `common.wgsl`.
#[must_use]
fn unpack_normal(packed: u32) -> Vec3 {
    let snorm = |bits: u32| (f32::from(bits as u16 as i16) / 32767.0).max(-1.0);
    let p = Vec2::new(snorm(packed & 0xffff), snorm(packed >> 16));
    let z = 1.0 - p.x.abs() - p.y.abs();
    let sign = Vec2::select(p.cmpge(Vec2::ZERO), Vec2::ONE, -Vec2::ONE);
    let xy = if z < 0.0 { (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs())) * sign } else { p };
    Vec3::new(xy.x, xy.y, z).normalize_or_zero()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// CPU copy of the shader's `pack_normal`, for the round trip.
    fn pack_normal(n: Vec3) -> u32 {
        let mut p = Vec2::new(n.x, n.y) / (n.x.abs() + n.y.abs() + n.z.abs());
        if n.z < 0.0 {
            p = (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs()))
                * Vec2::select(p.cmpge(Vec2::ZERO), Vec2::ONE, -Vec2::ONE);
        }
        let q = |v: f32| ((v.clamp(-1.0, 1.0) * 32767.0).round() as i16) as u16 as u32;
        q(p.x) | q(p.y) << 16
    }

    #[test]
    fn normals_round_trip() {
        for i in 0..200 {
            let a = i as f32 * 0.731;
            // Points spread over the sphere, both hemispheres (z < 0 folds).
            let n =
                Vec3::new(a.cos() * (a * 0.3).sin(), (a * 1.7).sin(), (a * 0.3).cos() * a.sin()).normalize_or_zero();
            if n == Vec3::ZERO {
                continue;
            }
            let back = unpack_normal(pack_normal(n));
            assert!((back - n).length() < 1e-3, "{n} -> {back}");
        }
    }

    #[test]
    fn rows_are_padded_to_256_bytes() {
        assert_eq!(padded_row_bytes(180), 3072);
        assert_eq!(padded_row_bytes(64), 1024);
    }
}
