//! The half-plane bitmask table: for a line through a pixel, which of the
//! 32 sub-samples ([`SAMPLE_POSITIONS`]) lie on its inner side, precomputed
//! for quantized lines (after Eisemann & Décoret 2007, as Pan et al. use
//! it). A convex region's samples are the AND of its edges' masks; a union
//! of regions the OR. One 32-bit table serves 8, 16 and 32 samples (the
//! patterns are nested; [`AaSamples::mask`] picks the bits).
//!
//! A line is `(a, b, c)` over pixel-local coordinates (`x` right, `y` down,
//! the pixel is `[0, 1]²`); its inner side is `a x + b y + c >= 0`. The table
//! is indexed by the direction of `(a, b)` ([`ANGLES`] steps) and the signed
//! distance of the pixel centre from the line ([`OFFSETS`] steps over
//! `[-RADIUS, RADIUS]`; beyond that every sample is on one side). A lookup
//! rounds a line to the nearest entry, so a sample is misclassified only
//! when it lies within [`QUANTIZATION_ERROR`] of the line.

use glam::{DVec2, DVec3};

use super::{AaSamples, SAMPLE_POSITIONS};

/// Quantized directions of the line normal over the full turn.
pub const ANGLES: usize = 128;
/// Quantized signed distances of the pixel centre from the line.
pub const OFFSETS: usize = 64;
/// Distances are quantized over `[-RADIUS, RADIUS]`: just over the largest
/// distance of a sample from the pixel centre (`sqrt(2) * 3.5 / 8 = 0.619`).
pub const RADIUS: f64 = 0.625;
/// The most a sample's signed distance from a line can move by the table's
/// rounding: half an offset step plus half an angle step times the largest
/// sample radius.
pub const QUANTIZATION_ERROR: f64 = RADIUS / OFFSETS as f64 + 0.619 * std::f64::consts::PI / ANGLES as f64;

/// The table: `ANGLES x OFFSETS` masks, angle-major.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HalfPlaneTable {
    masks: Vec<u32>,
}

impl Default for HalfPlaneTable {
    fn default() -> Self {
        Self::new()
    }
}

/// Where a line falls in the table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TableIndex {
    /// Every sample is inside (the pixel lies well within the half-plane).
    All,
    /// No sample is inside.
    None,
    /// Entry `angle * OFFSETS + offset`.
    Entry {
        /// Angle step.
        angle: usize,
        /// Offset step.
        offset: usize,
    },
}

impl HalfPlaneTable {
    /// Builds the table.
    #[must_use]
    pub fn new() -> Self {
        let mut masks = Vec::with_capacity(ANGLES * OFFSETS);
        for angle in 0..ANGLES {
            for offset in 0..OFFSETS {
                let (normal, distance) = Self::representative(angle, offset);
                let mut mask = 0u32;
                for (s, p) in SAMPLE_POSITIONS.iter().enumerate() {
                    if normal.dot(*p - DVec2::splat(0.5)) + distance >= 0.0 {
                        mask |= 1 << s;
                    }
                }
                masks.push(mask);
            }
        }
        Self { masks }
    }

    /// The half-plane an entry stands for: unit normal `n` and signed
    /// distance `e` of the pixel centre, inside where `n·(p - centre) + e >= 0`.
    #[must_use]
    pub fn representative(angle: usize, offset: usize) -> (DVec2, f64) {
        let theta = std::f64::consts::TAU * angle as f64 / ANGLES as f64;
        let e = -RADIUS + (offset as f64 + 0.5) * 2.0 * RADIUS / OFFSETS as f64;
        (DVec2::new(theta.cos(), theta.sin()), e)
    }

    /// The mask of one entry.
    #[must_use]
    pub fn entry(&self, angle: usize, offset: usize) -> u32 {
        self.masks[angle * OFFSETS + offset]
    }

    /// Every entry, angle-major (for upload to the GPU).
    #[must_use]
    pub fn words(&self) -> &[u32] {
        &self.masks
    }

    /// Where the line `(a, b, c)` falls (inside: `a x + b y + c >= 0`).
    /// A degenerate line (`a = b = 0`, or not finite) is all or nothing by
    /// the sign of `c`.
    #[must_use]
    pub fn index(line: DVec3) -> TableIndex {
        let n = line.truncate();
        let len = n.length();
        if !(len > 0.0) || !len.is_finite() || !line.z.is_finite() {
            return if line.z >= 0.0 { TableIndex::All } else { TableIndex::None };
        }
        let e = (n.dot(DVec2::splat(0.5)) + line.z) / len;
        if e >= RADIUS {
            return TableIndex::All;
        }
        if e <= -RADIUS {
            return TableIndex::None;
        }
        let turns = n.y.atan2(n.x) / std::f64::consts::TAU;
        let angle = ((turns * ANGLES as f64).round() as i64).rem_euclid(ANGLES as i64) as usize;
        let offset = (((e + RADIUS) / (2.0 * RADIUS) * OFFSETS as f64).floor() as usize).min(OFFSETS - 1);
        TableIndex::Entry { angle, offset }
    }

    /// The samples inside the line's half-plane, from the table.
    #[must_use]
    pub fn lookup(&self, line: DVec3) -> u32 {
        match Self::index(line) {
            TableIndex::All => u32::MAX,
            TableIndex::None => 0,
            TableIndex::Entry { angle, offset } => self.entry(angle, offset),
        }
    }
}

/// The samples inside the line's half-plane, each tested directly (the
/// exact mask the table approximates).
#[must_use]
pub fn direct_mask(line: DVec3) -> u32 {
    let mut mask = 0u32;
    for (s, p) in SAMPLE_POSITIONS.iter().enumerate() {
        if line.dot(p.extend(1.0)) >= 0.0 {
            mask |= 1 << s;
        }
    }
    mask
}

/// The share of `samples`' sub-samples not in `occluded`.
#[must_use]
pub fn visibility(occluded: u32, samples: AaSamples) -> f64 {
    1.0 - f64::from((occluded & samples.mask()).count_ones()) / f64::from(samples.count())
}

/// The share of the pattern's *valid* samples (bits of `valid`) that are not
/// occluded (the paper's occlusion ratio with its validity mask); all of
/// the pattern's samples when none is valid.
#[must_use]
pub fn visibility_of_valid(occluded: u32, valid: u32, samples: AaSamples) -> f64 {
    let valid = valid & samples.mask();
    if valid == 0 {
        return visibility(occluded, samples);
    }
    1.0 - f64::from((occluded & valid).count_ones()) / f64::from(valid.count_ones())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Point-in-half-plane by orientation: the half-plane given by two points
    /// `p, q` on its boundary and one point `inside` strictly inside; a point
    /// is in it when it lies on the same side of `pq` as `inside` (or on the line).
    fn in_half_plane(p: DVec2, q: DVec2, inside: DVec2, x: DVec2) -> bool {
        let side = |r: DVec2| (q - p).perp_dot(r - p);
        let s = side(x);
        s == 0.0 || s.signum() == side(inside).signum()
    }

    #[test]
    fn every_entry_matches_direct_point_in_half_plane_tests() {
        let table = HalfPlaneTable::new();
        let centre = DVec2::splat(0.5);
        for angle in 0..ANGLES {
            for offset in 0..OFFSETS {
                let (n, e) = HalfPlaneTable::representative(angle, offset);
                // The boundary: the points centre + (t n⊥ - e n).
                let foot = centre - e * n;
                let (p, q) = (foot - n.perp(), foot + n.perp());
                let inside = foot + n;
                let mut want = 0u32;
                for (s, x) in SAMPLE_POSITIONS.iter().enumerate() {
                    if in_half_plane(p, q, inside, *x) {
                        want |= 1 << s;
                    }
                }
                assert_eq!(table.entry(angle, offset), want, "entry ({angle}, {offset})");
                // The entry's own line, scaled arbitrarily, finds the entry.
                let line = 3.7 * n.extend(e - n.dot(centre));
                assert_eq!(HalfPlaneTable::index(line), TableIndex::Entry { angle, offset });
            }
        }
    }

    #[test]
    fn lookups_err_only_within_the_quantization_error_of_the_line() {
        let table = HalfPlaneTable::new();
        // A deterministic spread of lines: every direction, offsets across
        // (and beyond) the pixel, scales from tiny to large.
        let mut wrong = 0;
        for k in 0..20_000u32 {
            let theta = f64::from(k) * 0.618_033_988_75 * std::f64::consts::TAU;
            let e = (f64::from(k % 97) / 96.0 - 0.5) * 1.6;
            let scale = 10f64.powi((k % 9) as i32 - 4);
            let n = DVec2::new(theta.cos(), theta.sin());
            let line = scale * n.extend(e - n.dot(DVec2::splat(0.5)));
            let (got, want) = (table.lookup(line), direct_mask(line));
            for (s, p) in SAMPLE_POSITIONS.iter().enumerate() {
                if (got ^ want) & (1 << s) != 0 {
                    wrong += 1;
                    let distance = line.dot(p.extend(1.0)).abs() / line.truncate().length();
                    assert!(distance <= QUANTIZATION_ERROR, "line {line}: sample {s} at {distance}");
                }
            }
        }
        // The rounding does bite sometimes (the test would notice a table
        // that silently matched nothing).
        assert!(wrong > 0);
    }

    #[test]
    fn degenerate_lines_are_all_or_nothing() {
        let table = HalfPlaneTable::new();
        assert_eq!(table.lookup(DVec3::new(0.0, 0.0, 1.0)), u32::MAX);
        assert_eq!(table.lookup(DVec3::new(0.0, 0.0, -1.0)), 0);
        assert_eq!(table.lookup(DVec3::new(f64::NAN, 0.0, -1.0)), 0);
        // Far from the pixel.
        assert_eq!(table.lookup(DVec3::new(1.0, 0.0, 5.0)), u32::MAX);
        assert_eq!(table.lookup(DVec3::new(1.0, 0.0, -5.0)), 0);
    }

    #[test]
    fn visibility_counts_the_pattern_bits_only() {
        // Bits beyond the 8-sample pattern do not count for it.
        assert_eq!(visibility(0xFFFF_FF00, AaSamples::X8), 1.0);
        assert_eq!(visibility(0x0000_000F, AaSamples::X8), 0.5);
        assert_eq!(visibility(u32::MAX, AaSamples::X32), 0.0);
        // Over the valid samples only; all of the pattern's when none is valid.
        assert_eq!(visibility_of_valid(0x0000_000F, 0x0000_00F0, AaSamples::X8), 1.0);
        assert_eq!(visibility_of_valid(0x0000_0013, 0x0000_000F, AaSamples::X8), 0.5);
        assert_eq!(visibility_of_valid(0x0000_000F, 0xFFFF_FF00, AaSamples::X8), 0.5);
        assert!((visibility_of_valid(0x0000_0003, 0x0000_0007, AaSamples::X32) - 1.0 / 3.0).abs() < 1e-12);
    }
}
