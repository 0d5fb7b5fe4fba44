//! Shadow maps kept from one frame to the next.
//!
//! A shadow pass is a pure function of the scene, its pipeline, its
//! uniforms and the map's size: drawing it again into a layer that already
//! holds its output writes the same texels. The experiment draws such passes
//! often: the scene-optimized loop's first frame uses the focused matrix the
//! focused method just drew, and a loop's last frame the matrix its method's
//! masks are then rendered with. [`MapRecords`] remembers, per layer of one
//! lookup mode's maps, what the last pass drew there, so a frame can skip a
//! pass whose record matches ([`RendererOptions::reuse_maps`](super::RendererOptions::reuse_maps)).
//! The records live with the maps: new maps start with none. A frame whose
//! submission fails forgets them all.

use super::uniforms::ShadowPassRaw;
use crate::LightMatrix;

/// What the last pass into a layer drew.
#[derive(Clone, Copy, Debug)]
struct Drawn {
    matrix: LightMatrix,
    raw: ShadowPassRaw,
}

impl Drawn {
    /// Bit for bit the same pass (a `NaN` anywhere never matches).
    fn same(&self, matrix: &LightMatrix, raw: &ShadowPassRaw) -> bool {
        self.matrix == *matrix && bytemuck::bytes_of(&self.raw) == bytemuck::bytes_of(raw)
    }
}

/// Per layer, the pass that drew it last, if known.
#[derive(Clone, Debug, Default)]
pub(crate) struct MapRecords {
    layers: Vec<Option<Drawn>>,
}

impl MapRecords {
    /// For each slot, whether its layer already holds the pass it would draw.
    pub(crate) fn reusable(&self, maps: &[&LightMatrix], raws: &[ShadowPassRaw]) -> Vec<bool> {
        maps.iter()
            .zip(raws)
            .enumerate()
            .map(|(i, (m, raw))| self.layers.get(i).copied().flatten().is_some_and(|d| d.same(m, raw)))
            .collect()
    }

    /// Records the passes of a submitted frame (drawn or reused alike).
    pub(crate) fn record(&mut self, maps: &[&LightMatrix], raws: &[ShadowPassRaw]) {
        if self.layers.len() < maps.len() {
            self.layers.resize(maps.len(), None);
        }
        for (i, (m, raw)) in maps.iter().zip(raws).enumerate() {
            self.layers[i] = Some(Drawn { matrix: **m, raw: *raw });
        }
    }

    /// Forgets every layer (after a failed frame, the maps are unknown).
    pub(crate) fn forget(&mut self) {
        self.layers.clear();
    }
}
