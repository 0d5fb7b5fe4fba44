//! The error overlay: the frame's shadow masks against the experiment's
//! ray-cast truth ([`RayCaster::trace_masks`], exact and independent of
//! every method), counted as the experiment counts them (pixels visible and
//! facing the light in the truth; false shadow = lit in the truth but
//! shadowed, false light = the reverse), per light, summed.

use image::{Rgba, RgbaImage};

use crate::mesh::{RayCaster, ShadowMasks};

/// Misclassified pixels of one frame, all lights together.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ErrorCounts {
    /// Pixel-light pairs compared (visible and light-facing in the truth).
    pub counted: u64,
    /// Lit in the truth, shadowed in the frame.
    pub false_shadow: u64,
    /// Shadowed in the truth, lit in the frame.
    pub false_light: u64,
}

impl ErrorCounts {
    /// `false_shadow + false_light`.
    #[must_use]
    pub fn misclassified(&self) -> u64 {
        self.false_shadow + self.false_light
    }
}

/// Colour of a false-shadow pixel (sRGB).
pub(crate) const FALSE_SHADOW: [u8; 3] = [255, 40, 40];
/// Colour of a false-light pixel (sRGB).
pub(crate) const FALSE_LIGHT: [u8; 3] = [40, 220, 255];

/// Compares `frame` (the renderer's masks) with `truth` for `lights` lights
/// and paints the misclassified pixels (false shadow red, false light cyan;
/// both: the false shadow colour); everything else is transparent.
#[must_use]
pub(crate) fn compare(frame: &ShadowMasks, truth: &ShadowMasks, lights: usize) -> (RgbaImage, ErrorCounts) {
    let mut counts = ErrorCounts::default();
    let mut image = RgbaImage::new(truth.width, truth.height);
    let n = truth.depth.len().min(frame.depth.len());
    for i in 0..n {
        if !truth.visible(i) {
            continue;
        }
        let (mut false_shadow, mut false_light) = (false, false);
        for light in 0..lights.min(32) {
            let bit = 1u32 << light;
            if truth.facing[i] & bit == 0 {
                continue;
            }
            counts.counted += 1;
            match (truth.shadow[i] & bit != 0, frame.shadow[i] & bit != 0) {
                (false, true) => {
                    counts.false_shadow += 1;
                    false_shadow = true;
                }
                (true, false) => {
                    counts.false_light += 1;
                    false_light = true;
                }
                _ => {}
            }
        }
        let color = if false_shadow {
            Some(FALSE_SHADOW)
        } else if false_light {
            Some(FALSE_LIGHT)
        } else {
            None
        };
        if let Some([r, g, b]) = color {
            let (x, y) = (i as u32 % truth.width, i as u32 / truth.width);
            image.put_pixel(x, y, Rgba([r, g, b, 230]));
        }
    }
    (image, counts)
}

/// The ray-cast truth for `camera` and `lights` at the camera's viewport.
#[must_use]
pub(crate) fn truth(caster: &RayCaster, camera: &crate::Camera, lights: &[crate::Light]) -> ShadowMasks {
    let size = camera.viewport();
    caster.trace_masks(camera, lights, size.x, size.y)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn masks(shadow: Vec<u32>, facing: Vec<u32>) -> ShadowMasks {
        ShadowMasks { width: 2, height: 2, depth: vec![0.5, 0.5, 0.5, 1.0], shadow, facing }
    }

    #[test]
    fn counts_false_shadow_and_false_light_per_light() {
        let truth = masks(vec![0b00, 0b01, 0b10, 0], vec![0b11, 0b11, 0b01, 0b11]);
        let frame = masks(vec![0b01, 0b00, 0b11, 0b11], vec![0b11; 4]);
        let (image, c) = compare(&frame, &truth, 2);
        // Pixel 0: light 0 false shadow. Pixel 1: light 0 false light.
        // Pixel 2: light 0 false shadow (light 1 does not face). Pixel 3: background.
        assert_eq!(c, ErrorCounts { counted: 5, false_shadow: 2, false_light: 1 });
        assert_eq!(image.get_pixel(0, 0).0[..3], FALSE_SHADOW);
        assert_eq!(image.get_pixel(1, 0).0[..3], FALSE_LIGHT);
        assert_eq!(image.get_pixel(1, 1).0[3], 0);
    }
}
