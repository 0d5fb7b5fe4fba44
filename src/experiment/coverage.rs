//! Coverage truth: the share of each pixel the light reaches, by ray casting
//! stratified sub-samples (the positions of [`AaSamples`], the same the
//! antialiased lookup uses), and the metric built on it, the mean absolute
//! visibility error per counted pixel (`mean_visibility_error` in
//! `summary.csv`).
//!
//! A pixel is counted as in [`Counts`](super::Counts): its centre is visible
//! and faces the light in the (centre-sample) truth. Its sub-samples are
//! traced like the centre: a primary ray from the camera through the
//! sub-sample position; a sub-sample is *valid* when that ray hits a surface
//! facing the light (and inside a spot light's cone), and *lit* when the
//! light also reaches that surface point. The truth's visibility is
//! `lit / valid` over the pattern's sub-samples (sub-samples on the
//! background or on a surface turned away say nothing about the shadow);
//! a pixel with no valid sub-sample keeps its centre's value. A standard
//! lookup's visibility is its shadow bit: 0 or 1.
//!
//! Every counted pixel is traced with all 32 sub-samples (the patterns are
//! nested, so this one trace is the truth for 8, 16 and 32). No cheap test
//! proves a pixel's sub-samples uniform — a caster thinner than a pixel can
//! shadow sub-samples between lit centres — so none is skipped; the cost is
//! measured in the note of issue 18.

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use crate::mesh::raycast::Ray;
use crate::mesh::{RayCaster, ShadowMasks};
use crate::render::subpixel::facet::Facet;
use crate::render::subpixel::{bitmask, AaSamples, SAMPLE_POSITIONS};
use crate::{Camera, Light};

/// Per-pixel sub-sample truth of one view and one light.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Coverage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Bit `s`: sub-sample `s` sees a surface facing the light (0 for pixels not counted).
    pub valid: Vec<u32>,
    /// Bit `s`: sub-sample `s` is valid and the light reaches its surface point.
    pub lit: Vec<u32>,
    /// Pixels traced (the counted ones).
    pub traced: u64,
}

/// Whether pixel `i` of `truth` is counted: visible and facing light 0.
fn counted(truth: &ShadowMasks, i: usize) -> bool {
    truth.visible(i) && truth.facing[i] & 1 != 0
}

impl Coverage {
    /// Traces the 32 sub-samples of every counted pixel of `truth` (the
    /// centre-sample truth of the same camera and light, at the camera's
    /// viewport scaled to `truth`'s size).
    #[must_use]
    pub fn trace(caster: &RayCaster, camera: &Camera, light: &Light, truth: &ShadowMasks) -> Self {
        let (width, height) = (truth.width, truth.height);
        let world_from_clip = camera.clip_from_world().inverse();
        let words: Vec<(u32, u32)> = (0..truth.depth.len())
            .into_par_iter()
            .map(|i| {
                if !counted(truth, i) {
                    return (0, 0);
                }
                let pixel = DVec2::new(f64::from(i as u32 % width), f64::from(i as u32 / width));
                let (mut valid, mut lit) = (0u32, 0u32);
                for (s, offset) in SAMPLE_POSITIONS.iter().enumerate() {
                    let p = pixel + *offset;
                    let ndc = DVec2::new(p.x / f64::from(width) * 2.0 - 1.0, 1.0 - p.y / f64::from(height) * 2.0);
                    let near = world_from_clip.project_point3(ndc.extend(0.0));
                    let far = world_from_clip.project_point3(ndc.extend(1.0));
                    let ray = Ray { origin: near.as_vec3(), direction: (far - near).as_vec3() };
                    let Some(hit) = caster.bvh().closest_hit(&ray, 1.0) else { continue };
                    let point: DVec3 = near + (far - near) * f64::from(hit.t);
                    let (shading, geometric) = caster.normals_at(&hit);
                    let to_light = match *light {
                        Light::Directional { direction } => -direction,
                        Light::Point { position } | Light::Spot { position, .. } => position - point,
                    };
                    if !(shading.as_dvec3().dot(to_light) > 0.0) || !light.reaches(point) {
                        continue;
                    }
                    valid |= 1 << s;
                    if !caster.in_shadow(point.as_vec3(), geometric, light) {
                        lit |= 1 << s;
                    }
                }
                (valid, lit)
            })
            .collect();
        let traced = (0..truth.depth.len()).filter(|&i| counted(truth, i)).count() as u64;
        Self {
            width,
            height,
            valid: words.iter().map(|w| w.0).collect(),
            lit: words.iter().map(|w| w.1).collect(),
            traced,
        }
    }

    /// The true visibility of pixel `i` with `samples` sub-samples: the
    /// share of its valid sub-samples that are lit; `None` when none is valid.
    #[must_use]
    pub fn visibility(&self, i: usize, samples: AaSamples) -> Option<f64> {
        let valid = self.valid.get(i)? & samples.mask();
        (valid != 0).then(|| f64::from((self.lit[i] & valid).count_ones()) / f64::from(valid.count_ones()))
    }
}

/// The occluded sub-samples of each counted pixel's *facet* (Pan et al.
/// 2009): the plane through the surface point its centre sees, with that
/// triangle's geometric normal, cut by the view rays of the 32 sub-samples,
/// each facet point tested with a shadow ray. This is what the antialiased
/// lookup computes when it finds every blocker (exact pairs, no table
/// rounding) and counts every sample as valid: its error against
/// [`Coverage`] is the facet approximation's own without the validity mask
/// (the GPU lookup's mask, [`Renderer::read_validity`](crate::render::Renderer::read_validity),
/// leaves out samples whose facet point another surface hides from the
/// camera, and may end below it). Bit `s` set: occluded;
/// pixels not counted, or whose plane is seen edge-on (no facet), hold the
/// centre's shadow bit in every bit. For a spot light, samples whose facet
/// point lies outside the cone are not lit, not shadowed: use
/// [`facet_reference_words`], whose validity words leave them out as the
/// truth does.
#[must_use]
pub fn facet_reference(caster: &RayCaster, camera: &Camera, light: &Light, truth: &ShadowMasks) -> Vec<u32> {
    facet_reference_words(caster, camera, light, truth).0
}

/// [`facet_reference`]'s occlusion words and validity words: bit `s` of a
/// validity word set when the light reaches facet point `s` apart from
/// occluders, i.e. it lies inside a spot light's cone (as in [`Coverage`]
/// and the antialiased lookup's validity words); every bit for other
/// lights, for pixels without a facet, and for a facet with no sample
/// inside. Score them with [`VisibilityError::of_valid_occlusion`].
#[must_use]
pub fn facet_reference_words(
    caster: &RayCaster,
    camera: &Camera,
    light: &Light,
    truth: &ShadowMasks,
) -> (Vec<u32>, Vec<u32>) {
    let (width, height) = (truth.width, truth.height);
    let clip_from_world = camera.clip_from_world();
    let world_from_clip = clip_from_world.inverse();
    let viewport = glam::UVec2::new(width, height);
    (0..truth.depth.len())
        .into_par_iter()
        .map(|i| {
            let centre_bit = if truth.shadow[i] & 1 != 0 { u32::MAX } else { 0 };
            if !counted(truth, i) {
                return (centre_bit, u32::MAX);
            }
            let pixel = glam::UVec2::new(i as u32 % width, i as u32 / width);
            let p = pixel.as_dvec2() + DVec2::splat(0.5);
            let ndc = DVec2::new(p.x / f64::from(width) * 2.0 - 1.0, 1.0 - p.y / f64::from(height) * 2.0);
            let near = world_from_clip.project_point3(ndc.extend(0.0));
            let far = world_from_clip.project_point3(ndc.extend(1.0));
            let ray = Ray { origin: near.as_vec3(), direction: (far - near).as_vec3() };
            let Some(hit) = caster.bvh().closest_hit(&ray, 1.0) else { return (centre_bit, u32::MAX) };
            let point = near + (far - near) * f64::from(hit.t);
            let (_, geometric) = caster.normals_at(&hit);
            let Some(facet) = Facet::new(&clip_from_world, viewport, pixel, point, geometric.as_dvec3()) else {
                return (centre_bit, u32::MAX);
            };
            let (mut occluded, mut valid) = (0u32, 0u32);
            for (s, offset) in SAMPLE_POSITIONS.iter().enumerate() {
                let world = facet.world_at(*offset);
                if caster.in_shadow(world.as_vec3(), geometric, light) {
                    occluded |= 1 << s;
                }
                if light.reaches(world) {
                    valid |= 1 << s;
                }
            }
            (occluded, if valid == 0 { u32::MAX } else { valid })
        })
        .unzip()
}

/// The summed absolute visibility error of a method over the counted pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VisibilityError {
    /// `sum |v_method - v_truth|` over the counted pixels.
    pub sum: f64,
    /// Pixels counted.
    pub pixels: u64,
}

impl VisibilityError {
    /// The mean per counted pixel (`None` without pixels).
    #[must_use]
    pub fn mean(&self) -> Option<f64> {
        (self.pixels > 0).then(|| self.sum / self.pixels as f64)
    }

    /// The error of per-pixel visibilities `method(i)` against `coverage`
    /// with `samples` sub-samples, over the pixels `truth` counts (a pixel
    /// without a valid sub-sample is compared with its centre's truth).
    #[must_use]
    pub fn of(method: impl Fn(usize) -> f64, truth: &ShadowMasks, coverage: &Coverage, samples: AaSamples) -> Self {
        let mut e = Self::default();
        for i in 0..truth.depth.len() {
            if !counted(truth, i) {
                continue;
            }
            let want = coverage.visibility(i, samples).unwrap_or(if truth.shadow[i] & 1 != 0 { 0.0 } else { 1.0 });
            e.sum += (method(i) - want).abs();
            e.pixels += 1;
        }
        e
    }

    /// The error of per-pixel occlusion masks (bit `s`: sub-sample `s` is
    /// shadowed), such as [`facet_reference`]'s.
    #[must_use]
    pub fn of_occlusion(occluded: &[u32], truth: &ShadowMasks, coverage: &Coverage, samples: AaSamples) -> Self {
        Self::of(|i| bitmask::visibility(occluded[i], samples), truth, coverage, samples)
    }

    /// The error of the antialiased lookup's occlusion and validity words
    /// ([`Renderer::read_validity`](crate::render::Renderer::read_validity)):
    /// the share of valid samples not occluded.
    #[must_use]
    pub fn of_valid_occlusion(
        occluded: &[u32],
        valid: &[u32],
        truth: &ShadowMasks,
        coverage: &Coverage,
        samples: AaSamples,
    ) -> Self {
        Self::of(|i| bitmask::visibility_of_valid(occluded[i], valid[i], samples), truth, coverage, samples)
    }

    /// The error of a supersampled standard lookup
    /// ([`ShadowLookup::Supersampled`](crate::render::ShadowLookup::Supersampled)):
    /// its share of lit sub-samples among those facing the light, the
    /// truth's own estimator with the depth compare for the shadow ray; a
    /// pixel none of whose sub-samples faces the light takes the centre
    /// pass's bit (`masks`), as the truth takes its centre's.
    #[must_use]
    pub fn of_supersampled(
        words: &crate::render::subpixel::supersample::SupersampledWords,
        masks: &ShadowMasks,
        truth: &ShadowMasks,
        coverage: &Coverage,
        samples: AaSamples,
    ) -> Self {
        let centre = |i: usize| if masks.shadow.get(i).is_some_and(|s| s & 1 != 0) { 0.0 } else { 1.0 };
        Self::of(|i| words.visibility(i).unwrap_or_else(|| centre(i)), truth, coverage, samples)
    }

    /// The error of a standard lookup's masks: visibility 0 where its
    /// shadow bit is set, 1 elsewhere.
    #[must_use]
    pub fn of_masks(masks: &ShadowMasks, truth: &ShadowMasks, coverage: &Coverage, samples: AaSamples) -> Self {
        Self::of(|i| if masks.shadow.get(i).is_some_and(|s| s & 1 != 0) { 0.0 } else { 1.0 }, truth, coverage, samples)
    }
}

#[cfg(test)]
mod tests {
    use glam::{UVec2, Vec3};

    use super::*;
    use crate::mesh::{Mesh, Role, Scene, SceneObject};

    /// A floor quad at y = 0 and, above it, a blocker quad covering x < edge
    /// (the whole z range), lit straight from above by a directional light:
    /// the shadow on the floor is the half-plane x < edge.
    fn half_plane_scene(edge: f32) -> Scene {
        let quad = |x0: f32, x1: f32, y: f32| Mesh {
            positions: vec![
                Vec3::new(x0, y, -10.0),
                Vec3::new(x1, y, -10.0),
                Vec3::new(x1, y, 10.0),
                Vec3::new(x0, y, 10.0),
            ],
            normals: vec![Vec3::Y; 4],
            indices: vec![0, 2, 1, 0, 3, 2],
        };
        let mut scene = Scene::default();
        let object = |name: &str, mesh| SceneObject {
            name: name.into(),
            mesh,
            role: Role::CasterAndReceiver,
            albedo: Vec3::ONE,
        };
        scene.objects.push(object("floor", quad(-10.0, 10.0, 0.0)));
        scene.objects.push(object("blocker", quad(-10.0, edge, 1.0)));
        scene
    }

    /// A camera straight above the floor, looking down, seeing x in [-1, 1]
    /// over `size` pixels (orthographic-like: a narrow perspective far away).
    fn top_camera(size: u32) -> Camera {
        let height = 400.0;
        let half = 1.0f64;
        Camera::look_at(
            DVec3::new(0.0, height, 0.0),
            DVec3::ZERO,
            DVec3::NEG_Z,
            2.0 * (half / height).atan(),
            UVec2::splat(size),
            // The blocker at y = 1 lies before the near plane: the camera
            // sees only the floor (and its shadow).
            height - 0.5,
            height + 1.0,
        )
        .expect("valid camera")
    }

    #[test]
    fn a_half_plane_edge_covers_its_analytic_area() {
        // The edge at x = 0.013 (not on a sample column) crosses pixel column
        // 16 of 32 (x in [0, 1/16)): its pixels are partly shadowed.
        let size = 32u32;
        let edge = 0.013f32;
        let scene = half_plane_scene(edge);
        let caster = RayCaster::new(&scene);
        let camera = top_camera(size);
        let light = Light::directional(DVec3::new(0.0, -1.0, 0.0));
        let truth = caster.trace_masks(&camera, &[light], size, size);
        let coverage = Coverage::trace(&caster, &camera, &light, &truth);
        assert_eq!(coverage.traced, u64::from(size * size), "the floor fills the view");
        let pixel_width = 2.0 / f64::from(size);
        for samples in AaSamples::ALL {
            let mut worst: f64 = 0.0;
            for row in 2..size - 2 {
                for col in 0..size {
                    let i = (row * size + col) as usize;
                    let x0 = -1.0 + f64::from(col) * pixel_width;
                    // Analytic lit share of the pixel: the part with x >= edge.
                    let lit = ((x0 + pixel_width - f64::from(edge)) / pixel_width).clamp(0.0, 1.0);
                    let got = coverage.visibility(i, samples).expect("valid");
                    // Stratified in x with n/8 samples per column of the 8x8
                    // grid: within one grid column (1/8) of the area.
                    assert!((got - lit).abs() <= 1.0 / 8.0 + 1e-9, "{samples:?} pixel ({col}, {row}): {got} vs {lit}");
                    worst = worst.max((got - lit).abs());
                }
            }
            // The edge pixels are fractional, not 0 or 1.
            let i = (size / 2 * size + size / 2) as usize;
            let v = coverage.visibility(i, samples).expect("valid");
            assert!(v > 0.0 && v < 1.0, "{samples:?}: {v}");
            assert!(worst > 0.0);
        }
        // A binary lookup that agrees with the centre truth everywhere still
        // errs by the edge pixels' fractions.
        let e = VisibilityError::of_masks(&truth, &truth, &coverage, AaSamples::X32);
        assert_eq!(e.pixels, u64::from(size * size));
        let edge_column = (size / 2) as usize;
        let lit_share = 1.0 - f64::from(edge) / pixel_width;
        let centre_lit = f64::from(edge) < pixel_width / 2.0;
        let per_pixel = if centre_lit { 1.0 - lit_share } else { lit_share };
        let want = per_pixel * f64::from(size);
        assert!((e.sum - want).abs() <= f64::from(size) / 8.0, "{} vs {want} (column {edge_column})", e.sum);
        // The truth against itself has no error.
        let exact = VisibilityError::of(
            |i| coverage.visibility(i, AaSamples::X32).unwrap_or(0.0),
            &truth,
            &coverage,
            AaSamples::X32,
        );
        assert_eq!(exact.sum, 0.0);
    }

    #[test]
    fn facets_on_a_plane_reproduce_the_coverage_truth() {
        // On a flat receiver the facet is the receiver itself: the facet
        // reference equals the ray-cast sub-samples.
        let size = 32u32;
        let scene = half_plane_scene(0.013);
        let caster = RayCaster::new(&scene);
        let camera = top_camera(size);
        let light = Light::directional(DVec3::new(0.2, -1.0, 0.1));
        let truth = caster.trace_masks(&camera, &[light], size, size);
        let coverage = Coverage::trace(&caster, &camera, &light, &truth);
        let facets = facet_reference(&caster, &camera, &light, &truth);
        for samples in AaSamples::ALL {
            let e = VisibilityError::of_occlusion(&facets, &truth, &coverage, samples);
            let binary = VisibilityError::of_masks(&truth, &truth, &coverage, samples);
            assert_eq!(e.pixels, u64::from(size * size));
            assert!(binary.sum > 1.0, "the edge is fractional: {binary:?}");
            assert!(e.sum <= 1e-9, "{samples:?}: {e:?}");
        }
    }

    #[test]
    fn facets_leave_samples_outside_a_spots_cone_out() {
        // A spot above the floor at x = -4 whose cone's edge on the floor
        // (a circle) runs within a pixel of the shadow's edge (x = 0.459,
        // the blocker's edge 0.013 seen from the spot) for |z| < 0.3, just
        // outside it: the samples of the pixels there beyond the circle are
        // lit but outside the cone, where the truth counts them neither lit
        // nor shadowed. The facet reference's
        // validity words leave out the same samples (on a flat receiver the
        // facet is the receiver), so its error is 0; with every sample
        // valid it is not.
        let size = 64u32;
        let scene = half_plane_scene(0.013);
        let caster = RayCaster::new(&scene);
        let camera = top_camera(size);
        let radius: f64 = (0.013 + 4.0) * 10.0 / 9.0 + 0.01;
        let light = Light::spot(DVec3::new(-4.0, 10.0, 0.0), DVec3::NEG_Y, (radius / 10.0).atan());
        let truth = caster.trace_masks(&camera, &[light], size, size);
        let coverage = Coverage::trace(&caster, &camera, &light, &truth);
        let (occluded, valid) = facet_reference_words(&caster, &camera, &light, &truth);
        assert_eq!(occluded, facet_reference(&caster, &camera, &light, &truth));
        let mut edge = 0;
        for (i, (&v, &want)) in valid.iter().zip(&coverage.valid).enumerate() {
            if want != 0 {
                assert_eq!(v, want, "pixel {i}");
                edge += usize::from(v != u32::MAX);
            }
        }
        assert!(edge > 20, "{edge} pixels on the cone's edge");
        for samples in AaSamples::ALL {
            let e = VisibilityError::of_valid_occlusion(&occluded, &valid, &truth, &coverage, samples);
            let all_valid = VisibilityError::of_occlusion(&occluded, &truth, &coverage, samples);
            assert!(e.sum <= 1e-9, "{samples:?}: {e:?}");
            assert!(all_valid.sum > 1.0, "{samples:?}: {all_valid:?}");
        }
    }

    #[test]
    fn uncounted_pixels_are_not_traced() {
        let size = 16u32;
        let scene = half_plane_scene(0.0);
        let caster = RayCaster::new(&scene);
        let camera = top_camera(size);
        // A light from below: nothing faces it.
        let light = Light::directional(DVec3::new(0.0, 1.0, 0.0));
        let truth = caster.trace_masks(&camera, &[light], size, size);
        let coverage = Coverage::trace(&caster, &camera, &light, &truth);
        assert_eq!(coverage.traced, 0);
        assert!(coverage.valid.iter().all(|&v| v == 0));
        assert_eq!(VisibilityError::of_masks(&truth, &truth, &coverage, AaSamples::X8).mean(), None);
    }
}
