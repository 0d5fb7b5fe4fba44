//! Per-pixel shadow data in one format for the GPU readback and the CPU ray
//! caster, and the comparison the experiments make between them.

/// Per-pixel depth, shadow and light-facing bits of one view.
///
/// Pixel `(x, y)` is at index `y * width + x`, row 0 at the top. Bit `i` of
/// the words belongs to light `i` (at most 32 lights).
///
/// * `depth`: the camera's depth-buffer value in `[0, 1]` (wgpu range);
///   exactly `1.0` where nothing was hit (background).
/// * `facing`: the surface faces light `i` (`interpolated normal · to-light > 0`)
///   and lies inside its cone for a spot light, i.e. it would receive light
///   `i` if unshadowed.
/// * `shadow`: light `i` is blocked; only ever set where `facing` is.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShadowMasks {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Depth-buffer value per pixel; `1.0` = background.
    pub depth: Vec<f32>,
    /// Shadow bits per pixel.
    pub shadow: Vec<u32>,
    /// Light-facing bits per pixel.
    pub facing: Vec<u32>,
}

/// How two sets of masks compare for one light.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MaskAgreement {
    /// Pixels compared (visible and light-facing in both, away from
    /// boundaries).
    pub compared: u64,
    /// Of those, pixels with the same shadow bit.
    pub agreeing: u64,
    /// Pixels lit in the reference but shadowed in the other.
    pub false_shadow: u64,
    /// Pixels shadowed in the reference but lit in the other.
    pub false_lit: u64,
}

impl MaskAgreement {
    /// `agreeing / compared` (1 when nothing was compared).
    #[must_use]
    pub fn fraction(&self) -> f64 {
        if self.compared == 0 {
            1.0
        } else {
            self.agreeing as f64 / self.compared as f64
        }
    }

    /// Sums two counts.
    #[must_use]
    pub fn merged(self, other: Self) -> Self {
        Self {
            compared: self.compared + other.compared,
            agreeing: self.agreeing + other.agreeing,
            false_shadow: self.false_shadow + other.false_shadow,
            false_lit: self.false_lit + other.false_lit,
        }
    }
}

impl ShadowMasks {
    /// Whether pixel `index` shows a surface.
    #[must_use]
    pub fn visible(&self, index: usize) -> bool {
        self.depth[index] < 1.0
    }

    /// Pixels that are visible, face `light` and show its shadow: the
    /// experiments' "shadowed receiver pixels".
    #[must_use]
    pub fn shadowed_count(&self, light: u32) -> usize {
        self.shadow.iter().filter(|&&s| s >> light & 1 == 1).count()
    }

    /// Compares `other`'s shadow bits for `light` with `self` as the
    /// reference, on pixels away from boundaries: a pixel counts when, in a
    /// `(2 radius + 1)²` window around it, every pixel is visible and facing
    /// the light in both masks and the reference's shadow bit is constant.
    ///
    /// Both masks must have the same size; otherwise nothing is compared.
    #[must_use]
    pub fn agreement_away_from_boundaries(&self, other: &Self, light: u32, radius: u32) -> MaskAgreement {
        let mut result = MaskAgreement::default();
        if self.width != other.width || self.height != other.height || light as usize >= crate::MAX_LIGHTS {
            return result;
        }
        let (w, h, r) = (self.width as i64, self.height as i64, i64::from(radius));
        let bit = |words: &[u32], i: usize| words[i] >> light & 1;
        for y in r..h - r {
            for x in r..w - r {
                let centre = (y * w + x) as usize;
                let reference = bit(&self.shadow, centre);
                let interior = (-r..=r).all(|dy| {
                    (-r..=r).all(|dx| {
                        let i = ((y + dy) * w + x + dx) as usize;
                        self.visible(i)
                            && other.visible(i)
                            && bit(&self.facing, i) == 1
                            && bit(&other.facing, i) == 1
                            && bit(&self.shadow, i) == reference
                    })
                });
                if !interior {
                    continue;
                }
                result.compared += 1;
                match (reference, bit(&other.shadow, centre)) {
                    (a, b) if a == b => result.agreeing += 1,
                    (0, _) => result.false_shadow += 1,
                    _ => result.false_lit += 1,
                }
            }
        }
        result
    }

    /// Misclassified pixels for `light` against a reference (the paper's
    /// measure): pixels visible and light-facing in the reference whose
    /// shadow bit differs. Sizes must match; otherwise `None`.
    #[must_use]
    pub fn misclassified(&self, reference: &Self, light: u32) -> Option<u64> {
        if self.width != reference.width || self.height != reference.height || light as usize >= crate::MAX_LIGHTS {
            return None;
        }
        let count = (0..self.shadow.len())
            .filter(|&i| reference.visible(i) && reference.facing[i] >> light & 1 == 1)
            .filter(|&i| (self.shadow[i] ^ reference.shadow[i]) >> light & 1 == 1)
            .count();
        Some(count as u64)
    }
}

/// Flicker of one light's shadow between two consecutive frames: the pixels
/// whose shadow bit changes while the truth's does not (a change the truth
/// also makes is real motion of the shadow, not flicker).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Flicker {
    /// Pixels visible and facing the light in both truths, with the same
    /// truth bit.
    pub stable: u64,
    /// Of those, pixels whose bit changed between the two frames.
    pub flipped: u64,
}

impl Flicker {
    /// Compares frames `a` and `b` for `light` with the truths of the same
    /// frames. Sizes must match (pixels past the shortest are ignored); a
    /// light past [`MAX_LIGHTS`](crate::MAX_LIGHTS) counts nothing.
    #[must_use]
    pub fn between(light: u32, a: &ShadowMasks, truth_a: &ShadowMasks, b: &ShadowMasks, truth_b: &ShadowMasks) -> Self {
        let mut out = Self::default();
        if light as usize >= crate::MAX_LIGHTS {
            return out;
        }
        let n = a.depth.len().min(b.depth.len()).min(truth_a.depth.len()).min(truth_b.depth.len());
        let bit = |words: &[u32], i: usize| words[i] >> light & 1;
        let counted = |t: &ShadowMasks, i: usize| t.visible(i) && bit(&t.facing, i) == 1;
        for i in 0..n {
            if !counted(truth_a, i) || !counted(truth_b, i) || bit(&truth_a.shadow, i) != bit(&truth_b.shadow, i) {
                continue;
            }
            out.stable += 1;
            out.flipped += u64::from(bit(&a.shadow, i) ^ bit(&b.shadow, i));
        }
        out
    }

    /// `flipped / stable` (0 when nothing was counted).
    #[must_use]
    pub fn share(&self) -> f64 {
        if self.stable == 0 {
            0.0
        } else {
            self.flipped as f64 / self.stable as f64
        }
    }

    /// Sums two counts (e.g. over frames or lights).
    #[must_use]
    pub fn merged(self, other: Self) -> Self {
        Self { stable: self.stable + other.stable, flipped: self.flipped + other.flipped }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn masks(shadow: &[u32], facing: &[u32]) -> ShadowMasks {
        ShadowMasks {
            width: shadow.len() as u32,
            height: 1,
            depth: vec![0.5; shadow.len()],
            shadow: shadow.to_vec(),
            facing: facing.to_vec(),
        }
    }

    #[test]
    fn truth_flips_are_excluded() {
        let facing = [1, 1, 1, 1, 0];
        let truth_a = masks(&[0, 1, 0, 1, 0], &facing);
        let truth_b = masks(&[0, 1, 1, 0, 0], &facing); // pixels 2 and 3 really change
        let a = masks(&[0, 1, 0, 1, 0], &facing);
        let b = masks(&[1, 0, 1, 0, 1], &facing); // flips 0, 1 (errors), 2, 3 (truth), 4 (not counted)
        let f = Flicker::between(0, &a, &truth_a, &b, &truth_b);
        assert_eq!(f, Flicker { stable: 2, flipped: 2 });
        assert_eq!(f.share(), 1.0);
        // Following the truth exactly is no flicker.
        assert_eq!(Flicker::between(0, &truth_a, &truth_a, &truth_b, &truth_b).flipped, 0);
    }

    #[test]
    fn identical_frames_do_not_flicker() {
        let facing = [1, 1, 1];
        let t = masks(&[1, 0, 1], &facing);
        let m = masks(&[0, 0, 1], &facing);
        assert_eq!(Flicker::between(0, &m, &t, &m, &t), Flicker { stable: 3, flipped: 0 });
    }

    #[test]
    fn each_light_is_its_own_bit() {
        // Light 1 (bit 1) flickers on pixel 0; light 0 does not.
        let facing = [0b11, 0b11];
        let t = masks(&[0b00, 0b10], &facing);
        let a = masks(&[0b00, 0b10], &facing);
        let b = masks(&[0b10, 0b10], &facing);
        assert_eq!(Flicker::between(0, &a, &t, &b, &t), Flicker { stable: 2, flipped: 0 });
        assert_eq!(Flicker::between(1, &a, &t, &b, &t), Flicker { stable: 2, flipped: 1 });
        assert_eq!(Flicker::between(32, &a, &t, &b, &t), Flicker::default());
    }
}
