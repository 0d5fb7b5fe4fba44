//! The experiment's methods: a matrix method of the library (with the
//! optimizer's search) and the shadow lookup its pictures are made with.

use crate::render::{ShadowLookup, SpsmOptions};
use crate::Method;

/// A method of the experiment: one of the library's [`Method`]s, the
/// scene-optimized one with either search.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MethodKind {
    /// Uniform around all receivers.
    Normal,
    /// Uniform around the visible receivers.
    Focused,
    /// Focused with world-fixed axes and a texel-snapped grid.
    FocusedSnapped,
    /// Light-space perspective.
    #[serde(rename = "lispsm")]
    LiSpsm,
    /// Perspective shadow maps (near plane from the nearest visible depth).
    Psm,
    /// Perfect sampling on the floor plane.
    PlaneOptimal,
    /// Scene-optimized, the paper's search.
    Optimized,
    /// Scene-optimized with argmin's Nelder–Mead.
    OptimizedArgmin,
    /// `normal+spsm`: the normal matrix with the sub-pixel shadow-map lookup
    /// ([`ShadowLookup::Spsm`]).
    NormalSpsm,
    /// `focused+spsm`.
    FocusedSpsm,
    /// `focused-snapped+spsm`.
    FocusedSnappedSpsm,
    /// `lispsm+spsm`.
    LiSpsmSpsm,
    /// `psm+spsm`.
    PsmSpsm,
    /// `plane-optimal+spsm`.
    PlaneOptimalSpsm,
    /// `optimized+spsm` (its frame loop's analysis bits come from the SPSM
    /// lookup too).
    OptimizedSpsm,
    /// `optimized-argmin+spsm`.
    OptimizedArgminSpsm,
}

impl MethodKind {
    /// Every method, in report order.
    pub const ALL: [Self; 8] = [
        Self::Normal,
        Self::Focused,
        Self::FocusedSnapped,
        Self::LiSpsm,
        Self::Psm,
        Self::PlaneOptimal,
        Self::Optimized,
        Self::OptimizedArgmin,
    ];

    /// Every method with the SPSM lookup (`<method>+spsm`), in report order.
    pub const ALL_SPSM: [Self; 8] = [
        Self::NormalSpsm,
        Self::FocusedSpsm,
        Self::FocusedSnappedSpsm,
        Self::LiSpsmSpsm,
        Self::PsmSpsm,
        Self::PlaneOptimalSpsm,
        Self::OptimizedSpsm,
        Self::OptimizedArgminSpsm,
    ];

    /// The same matrix method with the standard lookup.
    #[must_use]
    pub fn base(self) -> Self {
        match Self::ALL_SPSM.iter().position(|&m| m == self) {
            Some(i) => Self::ALL[i],
            None => self,
        }
    }

    /// The same matrix method with the SPSM lookup (`<method>+spsm`).
    #[must_use]
    pub fn with_spsm(self) -> Self {
        let base = self.base();
        Self::ALL.iter().position(|&m| m == base).map_or(self, |i| Self::ALL_SPSM[i])
    }

    /// Whether it looks shadows up with sub-pixel shadow maps.
    #[must_use]
    pub fn spsm(self) -> bool {
        self.base() != self
    }

    /// The shadow lookup its camera pass and frame loop use.
    #[must_use]
    pub fn lookup(self) -> ShadowLookup {
        if self.spsm() {
            ShadowLookup::Spsm(SpsmOptions::default())
        } else {
            ShadowLookup::DepthCompare
        }
    }

    /// The library's method behind it.
    #[must_use]
    pub fn method(self) -> Method {
        match self.base() {
            Self::Normal => Method::Normal,
            Self::Focused => Method::Focused,
            Self::FocusedSnapped => Method::FocusedSnapped,
            Self::LiSpsm => Method::LiSpsm,
            Self::Psm => Method::Psm,
            Self::PlaneOptimal => Method::PlaneOptimal,
            _ => Method::Optimized,
        }
    }

    /// Name used on the command line and in reports: the library's
    /// [`Method::name`], with `-argmin` for the Nelder–Mead search and
    /// `+spsm` for the sub-pixel shadow-map lookup.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::OptimizedArgmin => "optimized-argmin",
            Self::NormalSpsm => "normal+spsm",
            Self::FocusedSpsm => "focused+spsm",
            Self::FocusedSnappedSpsm => "focused-snapped+spsm",
            Self::LiSpsmSpsm => "lispsm+spsm",
            Self::PsmSpsm => "psm+spsm",
            Self::PlaneOptimalSpsm => "plane-optimal+spsm",
            Self::OptimizedSpsm => "optimized+spsm",
            Self::OptimizedArgminSpsm => "optimized-argmin+spsm",
            other => other.method().name(),
        }
    }

    /// Parses [`name`](Self::name).
    #[must_use]
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().chain(Self::ALL_SPSM).find(|m| m.name() == name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_method_pairs_with_its_spsm_variant() {
        assert_eq!(MethodKind::ALL.len(), MethodKind::ALL_SPSM.len());
        for (&plain, &spsm) in MethodKind::ALL.iter().zip(&MethodKind::ALL_SPSM) {
            assert_eq!(plain.with_spsm(), spsm);
            assert_eq!(spsm.base(), plain);
            assert_eq!(spsm.method(), plain.method());
            assert!(spsm.spsm() && !plain.spsm());
            assert_eq!(spsm.name(), format!("{}+spsm", plain.name()));
            assert_eq!(MethodKind::parse(spsm.name()), Some(spsm));
            assert_eq!(MethodKind::parse(plain.name()), Some(plain));
        }
    }
}
