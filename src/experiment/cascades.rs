//! Cascaded suns in the experiment: the cascade methods' frame loop and the
//! folding of a sun's `K` map slots into one light (masks, `+aaN`
//! occlusion words, `+ssN` sub-sample words), the checks that refuse a
//! cascade method where it cannot run, and the large view's scene.

use super::{rows, CascadeMethod, ExperimentConfig, ExperimentError, LightKind, Runner};
use crate::mesh::ShadowMasks;
use crate::render::{LoopOptions, LoopPolicy, LoopView, ShadowLookup, ShadowLoop};
use crate::{Light, LightMatrix, ShadowMapSize};

/// The large view's scene ([`SceneSource::Large`](super::SceneSource::Large)): the procedural scene
/// spread over a 2000-unit floor, 40×40 objects, so that a view from 1.7
/// units above the floor reaches 1500 units deep through it.
#[must_use]
pub fn large_scene(triangles: usize) -> crate::mesh::ProceduralScene {
    crate::mesh::ProceduralScene { triangle_budget: triangles, objects_per_side: 40, floor_size: 2000.0, seed: 2026 }
}

/// Checks the cascade settings: cascade methods need directional lights
/// and `cascades` in `1..=`[`MAX_CASCADES`](crate::cascade::MAX_CASCADES)
/// (at most [`MAX_LIGHTS`](crate::MAX_LIGHTS) maps); `cascades` > 0 needs
/// directional lights. (Every lookup honours the per-pixel cascade choice:
/// SPSM and SGSM shade through `shade`, the antialiased passes compute a
/// cascade's words only where it owns the pixel.)
///
/// # Errors
/// [`ExperimentError::Cascades`] naming the method or flag.
pub fn check_cascades(config: &ExperimentConfig) -> Result<(), ExperimentError> {
    let refuse = |what: String, reason| Err(ExperimentError::Cascades { what, reason });
    let max = crate::cascade::MAX_CASCADES.min(crate::MAX_LIGHTS);
    if config.cascades > max {
        return refuse(format!("--cascades {}", config.cascades), "at most 8 cascades per sun");
    }
    if config.cascades > 0 && config.light != LightKind::Directional {
        return refuse(format!("--cascades {}", config.cascades), "cascades are for suns: add --light directional");
    }
    for m in config.methods.iter().filter(|m| m.cascade().is_some()) {
        if config.light != LightKind::Directional {
            return refuse(format!("--methods {m}"), "a cascade method needs --light directional");
        }
        if config.cascades == 0 {
            return refuse(format!("--methods {m}"), "a cascade method needs --cascades N (1 to 8)");
        }
    }
    Ok(())
}

/// A cascaded sun's masks with its cascades folded into one light: light
/// `i` of the result is map slots `slots[i]..slots[i + 1]` of `masks`,
/// shadowed where one of them is and facing where one of them is (the
/// renderer looks a cascade up only where it owns the pixel's depth, so at
/// most one of each sun's bits is set: the per-pixel cascade's).
#[must_use]
pub fn fold_cascade_masks(masks: &ShadowMasks, slots: &[usize]) -> ShadowMasks {
    let fold = |bits: u32| {
        slots.windows(2).enumerate().fold(0u32, |out, (i, w)| {
            let range = ((1u64 << w[1]) - (1u64 << w[0])) as u32;
            out | (u32::from(bits & range != 0) << i)
        })
    };
    ShadowMasks {
        shadow: masks.shadow.iter().map(|&b| fold(b)).collect(),
        facing: masks.facing.iter().map(|&b| fold(b)).collect(),
        ..masks.clone()
    }
}

impl Runner<'_> {
    /// A cascade method's frame loop at this configuration ([`ShadowLoop`]
    /// with [`LoopPolicy::Cascaded`], `config.cascades` maps of `config.map`²
    /// for the sun), settled at its view. Returns the cascades' matrices
    /// (the renderer's cascades left marked for them), the frames and a
    /// note.
    pub(super) fn settle_cascades(
        &mut self,
        cascade: CascadeMethod,
        light: Light,
        lookup: ShadowLookup,
    ) -> Result<(Vec<LightMatrix>, usize, String), ExperimentError> {
        let count = self.config.cascades;
        let options = LoopOptions { lookup, ..Default::default() };
        let mut shadows = ShadowLoop::new(LoopPolicy::Cascaded(cascade.policy(count)), 1, options)?;
        let lights = [light];
        let view = LoopView {
            camera: &self.camera,
            lights: &lights,
            bounds: self.shared.scene.bounds(),
            map: ShadowMapSize::square(self.config.map),
        };
        let settled = shadows.settle(&mut self.renderer, &view, self.config.max_optimize_frames)?;
        let note = settled.fallbacks[0].map(rows::fallback_note).unwrap_or_default();
        Ok((settled.matrices, settled.frames, note))
    }

    /// The antialiased passes' occlusion words of the sun drawn in map slots
    /// `0..slots` (one light, or a cascaded sun's cascades): each cascade
    /// computes words only where it owns the pixel (its facing bit), so
    /// their OR is the owning cascade's.
    pub(super) fn occlusion(&self, slots: usize) -> Result<Vec<u32>, ExperimentError> {
        let mut words = self.renderer.read_occlusion(0)?;
        for k in 1..slots {
            for (w, o) in words.iter_mut().zip(self.renderer.read_occlusion(k)?) {
                *w |= o;
            }
        }
        Ok(words)
    }

    /// The antialiased passes' validity words of the sun drawn in map slots
    /// `0..slots`: a cascade that does not own a pixel leaves every sample
    /// valid there, so their AND is the owning cascade's.
    pub(super) fn validity(&self, slots: usize) -> Result<Vec<u32>, ExperimentError> {
        let mut words = self.renderer.read_validity(0)?;
        for k in 1..slots {
            for (w, v) in words.iter_mut().zip(self.renderer.read_validity(k)?) {
                *w &= v;
            }
        }
        Ok(words)
    }

    /// The supersampled lookup's words of the sun drawn in map slots
    /// `0..slots`: each sub-sample's camera pass sets a cascade's facing and
    /// shadow bits only where it owns the sub-sample, so the OR of the
    /// slots' words is the owning cascade's.
    pub(super) fn supersampled(
        &self,
        slots: usize,
    ) -> Result<crate::render::subpixel::supersample::SupersampledWords, ExperimentError> {
        let mut words = self.renderer.read_supersampled(0)?;
        for k in 1..slots {
            let more = self.renderer.read_supersampled(k)?;
            for (w, o) in words.valid.iter_mut().zip(more.valid) {
                *w |= o;
            }
            for (w, o) in words.occluded.iter_mut().zip(more.occluded) {
                *w |= o;
            }
        }
        Ok(words)
    }

    /// The antialiased passes' counts of map slots `0..slots`, summed.
    pub(super) fn aa_stats(&self, slots: usize) -> Result<crate::render::subpixel::gpu::AaStats, ExperimentError> {
        let mut s = self.renderer.read_aa_stats(0)?;
        for k in 1..slots {
            let t = self.renderer.read_aa_stats(k)?;
            s.pairs = s.pairs.saturating_add(t.pairs);
            s.exact_pixels += t.exact_pixels;
            s.overflow_pixels += t.overflow_pixels;
            s.wide_pixels += t.wide_pixels;
            s.uncertain_pixels += t.uncertain_pixels;
            s.triangle_tests = s.triangle_tests.saturating_add(t.triangle_tests);
            s.entries_scanned = s.entries_scanned.saturating_add(t.entries_scanned);
            s.silhouette_texels = s.silhouette_texels.saturating_add(t.silhouette_texels);
        }
        Ok(s)
    }
}

#[cfg(test)]
mod tests {
    use super::super::Preset;
    use super::*;

    // The binary literals are grouped by light slot (second sun | point | first sun).
    #[allow(clippy::unusual_byte_groupings)]
    #[test]
    fn folding_cascades_gives_one_bit_per_sun() {
        // Slots: a sun in 0..2, a point light in 2, a sun in 3..6.
        let slots = [0, 2, 3, 6];
        let masks = ShadowMasks {
            width: 3,
            height: 1,
            depth: vec![0.5; 3],
            shadow: vec![0b000_0_10, 0b100_1_00, 0],
            facing: vec![0b010_0_10, 0b100_1_01, 0b001_0_00],
        };
        let folded = fold_cascade_masks(&masks, &slots);
        assert_eq!(folded.shadow, [0b001, 0b110, 0]);
        assert_eq!(folded.facing, [0b101, 0b111, 0b100]);
        assert_eq!((folded.width, folded.depth.len()), (3, 3));
        assert_eq!(
            ExperimentConfig { cascades: 3, map: 100, ..ExperimentConfig::preset(Preset::Quick) }.single_map(),
            173
        );
    }
}
