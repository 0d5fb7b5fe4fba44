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
use crate::render::{Frame, ShadowLookup, MAX_LIGHTS};
use crate::LightMatrix;

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
    pub(super) fn finish_shared(
        &mut self,
        mut pending: Vec<Pending>,
        first: Option<usize>,
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
        let masks = self.masks_of_many(&matrices)?;
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
