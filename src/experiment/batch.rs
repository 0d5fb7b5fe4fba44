//! Several methods' masks from one frame.
//!
//! Every method of a configuration looks at the same camera, so each
//! method's own frame repeats the camera pass (shading the captured view)
//! and the 16-byte-per-pixel mask read-back. The renderer draws up to
//! [`MAX_LIGHTS`] maps in one frame, each into its own layer, and the camera
//! pass writes light `i`'s shadow and facing bits to bit `i` of the mask
//! words; a light's lookup reads only its own layer. So one frame with the
//! methods' matrices as its lights gives each method, in its bit, the masks
//! its own frame gives in bit 0: the shadow passes are the same draws, the
//! camera pass evaluates the same lookup per light. One camera pass and one
//! read-back replace one per method.
//!
//! Only the standard depth compare shares a frame: the antialiased lookups
//! read per-frame words of their own after the frame (occlusion,
//! supersampling), and the cascade methods leave the renderer's cascades
//! marked for their own frame.

use std::time::Instant;

use crate::mesh::ShadowMasks;
use crate::render::{AnalysisReadback, AnalysisRequest, Frame, LoopView, ShadowLookup, MAX_LIGHTS};
use crate::{Light, LightMatrix};

use super::{Coverage, ExperimentError, MethodResult, MethodSpec, RunStage, Runner};

/// A solved method waiting for its shared frame.
pub(super) struct Pending {
    /// Its place in the configuration's results.
    pub(super) index: usize,
    pub(super) method: MethodSpec,
    pub(super) matrices: Vec<LightMatrix>,
    pub(super) frames: usize,
    pub(super) note: String,
}

/// Whether `method`'s masks may come from a frame shared with other methods.
pub(super) fn shares_frame(method: MethodSpec) -> bool {
    method.cascade().is_none() && matches!(method.lookup(), ShadowLookup::DepthCompare)
}

impl Runner<'_> {
    /// Renders the `pending` methods' masks in one frame, `first` (an index
    /// into `pending`) in its layer 0 and the others in order, and fills in
    /// their results. The layer order changes no bit (see the module doc);
    /// it lets a map already in layer 0 be kept
    /// ([`RendererOptions::reuse_maps`](crate::render::RendererOptions::reuse_maps)).
    /// Returns the end of the last stage lap.
    ///
    /// With `loop_light` (an optimized loop at this light and the standard
    /// lookup comes next) and the focused method among `pending`, the frame
    /// also draws an analysis pass, and light 0's part of its readback is
    /// kept as that loop's first frame ([`FirstFrame::keep_readback`](crate::render::FirstFrame::keep_readback)):
    /// the loop starts from the focused matrix, whose map, camera masks and
    /// analysis bits this frame already has in layer and bit 0.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn finish_shared(
        &mut self,
        mut pending: Vec<Pending>,
        first: Option<usize>,
        loop_light: Option<Light>,
        results: &mut [(MethodSpec, MethodResult)],
        truth: &ShadowMasks,
        coverage: Option<&Coverage>,
        lap: Instant,
    ) -> Result<Instant, ExperimentError> {
        if pending.is_empty() {
            return Ok(lap);
        }
        if let Some(first) = first.filter(|&f| f < pending.len()) {
            let p = pending.remove(first);
            pending.insert(0, p);
        }
        let matrices: Vec<LightMatrix> = pending.iter().filter_map(|p| p.matrices.first().copied()).collect();
        if matrices.len() != pending.len() {
            return Err(ExperimentError::Config("a method solved without a matrix".into()));
        }
        let focused_first = first.is_some_and(|_| pending[0].method.matrix() == crate::Method::Focused);
        let masks = match loop_light.filter(|_| focused_first) {
            Some(light) => self.masks_and_first_frame(&matrices, light)?,
            None => self.masks_of_many(&matrices)?,
        };
        let mut lap = self.stages.lap(RunStage::Lookups, lap);
        for (p, masks) in pending.into_iter().zip(&masks) {
            let result = self.method_result(p.method, p.matrices, p.frames, p.note, masks, truth, coverage)?;
            if let Some(slot) = results.get_mut(p.index) {
                slot.1 = result;
            }
        }
        lap = self.stages.lap(RunStage::Compare, lap);
        Ok(lap)
    }

    /// The standard lookup's masks of every matrix, as
    /// [`masks`](Runner::masks) of each would give them (light 0's bits),
    /// from one frame per [`MAX_LIGHTS`] matrices.
    ///
    /// # Errors
    /// Renderer failures.
    pub fn masks_of_many(&mut self, matrices: &[LightMatrix]) -> Result<Vec<ShadowMasks>, ExperimentError> {
        let mut out = Vec::with_capacity(matrices.len());
        for lights in matrices.chunks(MAX_LIGHTS) {
            self.renderer.set_cascades(0, None);
            let frame =
                Frame { camera: &self.camera, lights, masks: true, analysis: None, lookup: ShadowLookup::DepthCompare };
            let report = self.renderer.render(&frame)?;
            self.renderer.wait_for(&report.submission)?;
            let shared = self.renderer.read_masks()?;
            out.extend((0..lights.len()).map(|bit| light_masks(&shared, bit)));
        }
        Ok(out)
    }
}

impl Runner<'_> {
    /// [`masks_of_many`](Self::masks_of_many) whose first frame also draws
    /// an analysis pass; light 0's part of its readback (`matrices[0]` must
    /// be `light`'s focused matrix at the configuration's map size) becomes
    /// the next loop's first frame at `light`.
    fn masks_and_first_frame(
        &mut self,
        matrices: &[LightMatrix],
        light: Light,
    ) -> Result<Vec<ShadowMasks>, ExperimentError> {
        let lights = &matrices[..matrices.len().min(MAX_LIGHTS)];
        self.renderer.set_cascades(0, None);
        // Nothing older may be waiting: the loop takes the next readback.
        self.renderer.discard_analyses();
        const TAG: u32 = u32::MAX;
        let analysis = Some(AnalysisRequest { lights: None, tag: TAG });
        let frame = Frame { camera: &self.camera, lights, masks: true, analysis, lookup: ShadowLookup::DepthCompare };
        let report = self.renderer.render(&frame)?;
        self.renderer.wait_for(&report.submission)?;
        let shared = self.renderer.read_masks()?;
        let readback = loop {
            if let Some(r) = self.renderer.try_take_analysis() {
                break r;
            }
            self.renderer.wait_idle()?;
        };
        if readback.tag == TAG && readback.lights.as_slice() == lights {
            let problem = self.problem(light, self.config.single_map())?;
            let view = LoopView {
                camera: problem.camera(),
                lights: std::slice::from_ref(problem.light()),
                bounds: *problem.bounds(),
                map: problem.map_size(),
            };
            self.first_frame.keep_readback(&view, ShadowLookup::DepthCompare, light_zero(readback));
        }
        let mut out: Vec<ShadowMasks> = (0..lights.len()).map(|bit| light_masks(&shared, bit)).collect();
        if matrices.len() > lights.len() {
            out.extend(self.masks_of_many(&matrices[lights.len()..])?);
        }
        Ok(out)
    }
}

/// An analysis readback of several lights cut to light 0's: its matrix
/// and its bits (bit 0) alone.
fn light_zero(mut readback: AnalysisReadback) -> AnalysisReadback {
    readback.lights.truncate(1);
    for word in readback.masks.shadow.iter_mut().chain(readback.masks.facing.iter_mut()) {
        *word &= 1;
    }
    readback
}

/// Light `bit`'s masks moved to bit 0, the other bits clear: what a frame
/// with that light alone writes.
fn light_masks(shared: &ShadowMasks, bit: usize) -> ShadowMasks {
    ShadowMasks {
        width: shared.width,
        height: shared.height,
        depth: shared.depth.clone(),
        shadow: shared.shadow.iter().map(|s| s >> bit & 1).collect(),
        facing: shared.facing.iter().map(|f| f >> bit & 1).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_light_bit_moves_to_bit_zero_alone() {
        let shared = ShadowMasks {
            width: 2,
            height: 1,
            depth: vec![0.5, 1.0],
            shadow: vec![0b101, 0b010],
            facing: vec![0b111, 0b110],
        };
        let m = light_masks(&shared, 2);
        assert_eq!((m.shadow, m.facing, m.depth), (vec![1, 0], vec![1, 1], vec![0.5, 1.0]));
        let m = light_masks(&shared, 1);
        assert_eq!((m.shadow, m.facing), (vec![0, 1], vec![1, 1]));
    }

    #[test]
    fn only_single_map_depth_compare_methods_share_a_frame() {
        assert!(shares_frame(MethodSpec::FOCUSED));
        assert!(shares_frame(MethodSpec::LISPSM));
        for m in MethodSpec::CASCADED {
            assert!(!shares_frame(m), "{m}");
        }
        let aa = MethodSpec::parse("focused+aa8").expect("a method");
        assert!(!shares_frame(aa));
    }
}
