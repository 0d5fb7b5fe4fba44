//! The renderer's side of the optimizer cadence: when to render an analysis
//! pass, and per-light matrices that change only when analysis data arrives.
//!
//! The paper (section 2.4) optimizes every three frames from data read back
//! asynchronously, and every couple of optimizations renders the analysis
//! pass with standard (focused) maps instead of the optimized ones, so that
//! shadows that moved into view are not missed. When data is late, the
//! previous matrices stay in use.

use super::AnalysisReadback;
use crate::LightMatrix;

/// Which maps an analysis pass looks its shadow bits up in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AnalysisKind {
    /// The frame's own (optimized) maps.
    Current,
    /// Standard maps (e.g. focused), to catch shadows the optimized maps
    /// do not cover.
    Standard,
}

impl AnalysisKind {
    /// The tag carried through the readback ([`super::AnalysisRequest::tag`]).
    #[must_use]
    pub fn tag(self) -> u32 {
        match self {
            Self::Current => 0,
            Self::Standard => 1,
        }
    }

    /// Inverse of [`tag`](Self::tag); unknown tags read as `Current`.
    #[must_use]
    pub fn from_tag(tag: u32) -> Self {
        if tag == 1 {
            Self::Standard
        } else {
            Self::Current
        }
    }
}

/// When to render analysis passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cadence {
    /// An analysis pass every this many frames (the paper: 3). 0 disables.
    pub analysis_every: u64,
    /// Every this many analysis passes, one uses standard maps (0: never).
    pub standard_every: u64,
}

impl Default for Cadence {
    fn default() -> Self {
        Self { analysis_every: 3, standard_every: 4 }
    }
}

impl Cadence {
    /// The analysis pass frame `frame` should render, if any.
    #[must_use]
    pub fn analysis_for(&self, frame: u64) -> Option<AnalysisKind> {
        if self.analysis_every == 0 || frame % self.analysis_every != 0 {
            return None;
        }
        let n = frame / self.analysis_every;
        Some(if self.standard_every != 0 && n % self.standard_every == 0 {
            AnalysisKind::Standard
        } else {
            AnalysisKind::Current
        })
    }
}

/// Per-light matrices that are replaced only from analysis data.
#[derive(Clone, Debug)]
pub struct AdaptiveLights {
    current: Vec<LightMatrix>,
    updated_in: Vec<Option<u64>>,
}

impl AdaptiveLights {
    /// Starts from `initial` (e.g. focused matrices).
    #[must_use]
    pub fn new(initial: Vec<LightMatrix>) -> Self {
        let updated_in = vec![None; initial.len()];
        Self { current: initial, updated_in }
    }

    /// The matrices to render with.
    #[must_use]
    pub fn matrices(&self) -> &[LightMatrix] {
        &self.current
    }

    /// Frame of the readback each light's matrix was last computed from.
    #[must_use]
    pub fn updated_in(&self) -> &[Option<u64>] {
        &self.updated_in
    }

    /// Replaces a light's matrix outright (a light was added or moved so
    /// far that its old matrix is useless).
    pub fn set(&mut self, light: usize, matrix: LightMatrix) {
        if let Some(m) = self.current.get_mut(light) {
            *m = matrix;
        }
    }

    /// Offers this frame's readback. Without one (late or never arriving),
    /// nothing changes. With one, `optimize(light, readback, previous)` is
    /// asked for each light; `None` keeps the previous matrix. Returns how
    /// many lights changed.
    pub fn update(
        &mut self,
        readback: Option<&AnalysisReadback>,
        mut optimize: impl FnMut(usize, &AnalysisReadback, &LightMatrix) -> Option<LightMatrix>,
    ) -> usize {
        let Some(readback) = readback else { return 0 };
        let mut changed = 0;
        for (light, matrix) in self.current.iter_mut().enumerate() {
            if let Some(new) = optimize(light, readback, matrix) {
                *matrix = new;
                self.updated_in[light] = Some(readback.frame);
                changed += 1;
            }
        }
        changed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cadence_follows_the_paper() {
        let cadence = Cadence::default();
        let kinds: Vec<_> = (0..13).map(|f| cadence.analysis_for(f)).collect();
        assert_eq!(kinds[0], Some(AnalysisKind::Standard));
        assert_eq!(kinds[1], None);
        assert_eq!(kinds[3], Some(AnalysisKind::Current));
        assert_eq!(kinds[12], Some(AnalysisKind::Standard));
        assert_eq!(Cadence { analysis_every: 0, standard_every: 4 }.analysis_for(0), None);
        for kind in [AnalysisKind::Current, AnalysisKind::Standard] {
            assert_eq!(AnalysisKind::from_tag(kind.tag()), kind);
        }
    }
}
