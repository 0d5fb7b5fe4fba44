//! Sub-pixel antialiased shadows after Pan et al. 2009 ("Fast, Sub-pixel
//! Antialiased Shadow Maps"): the parts that do not need a GPU.
//!
//! A pixel's shadow becomes a fraction: the share of its sub-samples the
//! light reaches. The paper gets that share without tracing a ray per
//! sub-sample: the pixel is approximated by a *facet* on its tangent plane
//! ([`facet`]), every blocker triangle's shadow volume cuts that plane in a
//! convex region bounded by at most four lines, and those lines, projected
//! back onto the screen, pick the occluded sub-samples from a precomputed
//! table of half-plane bitmasks ([`bitmask`]), ANDed per triangle and ORed
//! over triangles.
//!
//! This module fixes the one thing every consumer must agree on — where the
//! sub-samples lie ([`AaSamples`]) — so the experiment's ray-cast coverage
//! truth (`experiment::coverage`) and the lookup use the same positions.

pub mod bitmask;
pub mod facet;
pub mod gpu;
pub mod reference;
pub mod supersample;

use glam::DVec2;

/// Sub-samples per pixel of the antialiased lookup and of its coverage truth.
///
/// The three patterns are nested: the first 8 positions of
/// [`positions`](Self::positions) are the 8-sample pattern, the first 16
/// the 16-sample one, all 32 the 32-sample one. So one 32-bit mask per pixel
/// serves every count ([`mask`](Self::mask) selects the bits), and one
/// ray-cast truth of 32 sub-samples gives all three truths.
///
/// The positions are cells of an 8x8 grid over the pixel (cell centres
/// `((i + 0.5) / 8, (j + 0.5) / 8)`, `i` across, `j` down): 32 samples on the
/// cells with `i + j` odd, 16 on `i + j = 3 (mod 4)`, 8 on `i + j = 3 (mod 8)`.
/// Each is stratified (every row and every column of the grid holds 4, 2 or
/// 1 of them) and symmetric about the pixel centre (`(i, j) -> (7 - i, 7 - j)`
/// keeps each set), so its centroid is the pixel centre. None lies on the
/// centre itself (the paper's validity mask needs one there; see the note of
/// issue 18 for why it is left out).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum AaSamples {
    /// 8 sub-samples.
    X8,
    /// 16 sub-samples.
    X16,
    /// 32 sub-samples.
    X32,
}

/// Every sub-sample position, in the nested order of [`AaSamples`]: pixel
/// coordinates relative to the pixel's top-left corner, `x` right, `y` down
/// (framebuffer rows), both in `(0, 1)`.
pub const SAMPLE_POSITIONS: [DVec2; 32] = sample_positions();

const fn sample_positions() -> [DVec2; 32] {
    let mut out = [DVec2::ZERO; 32];
    let mut n = 0;
    // Three passes: i + j = 3 (mod 8), then the rest of 3 (mod 4), then the rest of odd.
    let mut pass = 0;
    while pass < 3 {
        let mut j = 0;
        while j < 8 {
            let mut i = 0;
            while i < 8 {
                let s = i + j;
                let take = match pass {
                    0 => s % 8 == 3,
                    1 => s % 4 == 3 && s % 8 != 3,
                    _ => s % 2 == 1 && s % 4 != 3,
                };
                if take {
                    out[n] = DVec2::new((i as f64 + 0.5) / 8.0, (j as f64 + 0.5) / 8.0);
                    n += 1;
                }
                i += 1;
            }
            j += 1;
        }
        pass += 1;
    }
    out
}

impl AaSamples {
    /// Every count, smallest first.
    pub const ALL: [AaSamples; 3] = [AaSamples::X8, AaSamples::X16, AaSamples::X32];

    /// The number of sub-samples.
    #[must_use]
    pub fn count(self) -> u32 {
        match self {
            Self::X8 => 8,
            Self::X16 => 16,
            Self::X32 => 32,
        }
    }

    /// The count for `n` (8, 16 or 32).
    #[must_use]
    pub fn from_count(n: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.count() == n)
    }

    /// The positions of this pattern (a prefix of [`SAMPLE_POSITIONS`]).
    #[must_use]
    pub fn positions(self) -> &'static [DVec2] {
        &SAMPLE_POSITIONS[..self.count() as usize]
    }

    /// The bits of a 32-sample mask that belong to this pattern.
    #[must_use]
    pub fn mask(self) -> u32 {
        match self {
            Self::X32 => u32::MAX,
            other => (1u32 << other.count()) - 1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_are_nested_stratified_and_centred() {
        for samples in AaSamples::ALL {
            let p = samples.positions();
            let n = p.len();
            assert_eq!(n as u32, samples.count());
            assert_eq!(samples.mask().count_ones(), samples.count());
            // Distinct, inside the pixel.
            for (a, pa) in p.iter().enumerate() {
                assert!(pa.x > 0.0 && pa.x < 1.0 && pa.y > 0.0 && pa.y < 1.0);
                for pb in &p[a + 1..] {
                    assert!(pa.distance(*pb) > 0.1, "{pa} {pb}");
                }
            }
            // Every row and column of the 8x8 grid holds n / 8 samples.
            for k in 0..8 {
                let in_row = p.iter().filter(|q| (q.y * 8.0).floor() as usize == k).count();
                let in_col = p.iter().filter(|q| (q.x * 8.0).floor() as usize == k).count();
                assert_eq!((in_row, in_col), (n / 8, n / 8), "{samples:?} row/column {k}");
            }
            let centroid = p.iter().copied().sum::<DVec2>() / n as f64;
            assert!(centroid.distance(DVec2::splat(0.5)) < 1e-12, "{samples:?}: {centroid}");
        }
    }
}
