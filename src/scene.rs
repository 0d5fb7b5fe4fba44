//! Scene bounds and shadow-map sizes.

use glam::DVec3;

use crate::error::{check_finite, LixelError, Result};

/// An axis-aligned box in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: DVec3,
    /// Largest corner.
    pub max: DVec3,
}

impl Aabb {
    /// A box from two opposite corners (in any order).
    #[must_use]
    pub fn from_corners(a: DVec3, b: DVec3) -> Self {
        Self { min: a.min(b), max: a.max(b) }
    }

    /// The smallest box holding every point; `None` for no points.
    #[must_use]
    pub fn from_points(points: impl IntoIterator<Item = DVec3>) -> Option<Self> {
        let mut it = points.into_iter();
        let first = it.next()?;
        Some(it.fold(Self { min: first, max: first }, |b, p| Self { min: b.min.min(p), max: b.max.max(p) }))
    }

    /// The smallest box holding both.
    #[must_use]
    pub fn union(&self, other: &Self) -> Self {
        Self { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    /// Centre point.
    #[must_use]
    pub fn center(&self) -> DVec3 {
        0.5 * (self.min + self.max)
    }

    /// Length of the diagonal.
    #[must_use]
    pub fn diagonal(&self) -> f64 {
        (self.max - self.min).length()
    }

    /// The eight corners (bit 0: x = max, bit 1: y = max, bit 2: z = max).
    #[must_use]
    pub fn corners(&self) -> [DVec3; 8] {
        std::array::from_fn(|i| {
            DVec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            )
        })
    }

    /// Whether `p` lies inside (boundary included).
    #[must_use]
    pub fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    fn validate(&self, what: &'static str) -> Result<()> {
        check_finite(&[self.min.to_array(), self.max.to_array()].concat(), what)?;
        if self.min.cmpgt(self.max).any() {
            return Err(LixelError::InvalidBounds { reason: "min > max" });
        }
        Ok(())
    }
}

/// Where the shadow casters and receivers are. Flat boxes (a floor) are fine.
///
/// Receivers are the surfaces that show shadows (their visible part must be
/// in the map); casters are what throws them (they must lie inside the depth
/// range wherever they sit between a receiver and the light).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneBounds {
    /// Bounds of the shadow casters.
    pub casters: Aabb,
    /// Bounds of the shadow receivers.
    pub receivers: Aabb,
}

impl SceneBounds {
    /// Casters and receivers in the same box.
    #[must_use]
    pub fn uniform(bounds: Aabb) -> Self {
        Self { casters: bounds, receivers: bounds }
    }

    /// The box holding casters and receivers: `S` in the PSM papers.
    #[must_use]
    pub fn scene(&self) -> Aabb {
        self.casters.union(&self.receivers)
    }

    /// Checks both boxes.
    ///
    /// # Errors
    /// [`LixelError::NonFinite`] or [`LixelError::InvalidBounds`].
    pub fn validate(&self) -> Result<()> {
        self.casters.validate("caster bounds")?;
        self.receivers.validate("receiver bounds")
    }
}

/// Shadow-map size in texels; non-square maps are allowed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ShadowMapSize {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
}

impl ShadowMapSize {
    /// A `width x height` map.
    #[must_use]
    pub const fn new(width: u32, height: u32) -> Self {
        Self { width, height }
    }

    /// A square map.
    #[must_use]
    pub const fn square(size: u32) -> Self {
        Self { width: size, height: size }
    }

    /// Checks for zero sizes.
    ///
    /// # Errors
    /// [`LixelError::ZeroMapSize`].
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(LixelError::ZeroMapSize { width: self.width, height: self.height });
        }
        Ok(())
    }
}
