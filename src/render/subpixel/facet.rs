//! Pixel facets (Pan et al. 2009, section 3.4) as CPU reference code: the
//! pixel's tangent plane seen through the pixel, blocker triangles' shadow
//! volumes cut with it and projected back onto the screen as half-planes,
//! and the facet's footprint in a light's map.
//!
//! Everything is homogeneous, so point and directional lights (and
//! perspective or orthographic cameras) share one code path:
//!
//! * [`Facet::plane_from_pixel`] is a 4x3 matrix `H` taking pixel-local
//!   coordinates `(u, v, 1)` (`[0, 1]²` over the pixel, `v` down) to the
//!   homogeneous world point where that pixel position's view ray meets the
//!   tangent plane: with `C` the camera centre and `D(s)` any other point of
//!   the ray, `X(s) = (π·C) D(s) − (π·D(s)) C` lies on both, linear in `s`.
//! * A world half-space `{X : h·X >= 0}` then becomes the screen half-plane
//!   `Hᵀh`: the paper's two-step projection (blocker onto the tangent plane,
//!   then onto the screen) in one matrix product.
//! * A triangle's shadow volume is four half-spaces (three planes through an
//!   edge and the light, one beyond the triangle's own plane), so its shadow
//!   on the facet is the AND of four half-plane masks ([`occluded_mask`]).

use glam::{DMat4, DVec2, DVec3, DVec4, UVec2};

use super::bitmask::HalfPlaneTable;

/// One pixel's facet: its tangent plane as seen through the pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Facet {
    /// Columns: the images of `u`, `v` and `1` (see the module docs);
    /// oriented so that `w > 0` over the whole pixel.
    pub plane_from_pixel: [DVec4; 3],
}

/// The plane through three homogeneous points (the 4D cross product):
/// `π·p = π·q = π·r = 0`.
#[must_use]
pub fn plane_through(p: DVec4, q: DVec4, r: DVec4) -> DVec4 {
    let det3 = |a: DVec3, b: DVec3, c: DVec3| a.dot(b.cross(c));
    let drop = |v: DVec4, k: usize| {
        let a = v.to_array();
        let mut out = [0.0; 3];
        let mut n = 0;
        for (i, x) in a.into_iter().enumerate() {
            if i != k {
                out[n] = x;
                n += 1;
            }
        }
        DVec3::from_array(out)
    };
    let minor = |k: usize| det3(drop(p, k), drop(q, k), drop(r, k));
    DVec4::new(minor(0), -minor(1), minor(2), -minor(3))
}

impl Facet {
    /// The facet of pixel `pixel` (column, row; row 0 at the top) of a
    /// `viewport` rendered with `clip_from_world` (wgpu conventions), on the
    /// plane through `point` with normal `normal`.
    ///
    /// `None` when the plane is seen edge-on somewhere in the pixel (a
    /// corner's view ray misses it, or meets it behind the camera): such a
    /// pixel keeps the point test at its centre.
    #[must_use]
    pub fn new(clip_from_world: &DMat4, viewport: UVec2, pixel: UVec2, point: DVec3, normal: DVec3) -> Option<Self> {
        let world_from_clip = clip_from_world.inverse();
        let plane = normal.extend(-normal.dot(point));
        let centre = world_from_clip * DVec4::new(0.0, 0.0, 1.0, 0.0);
        let (w, h) = (f64::from(viewport.x), f64::from(viewport.y));
        // Pixel-local (u, v, 1) to the clip point (x_ndc, y_ndc, 0, 1).
        let ndc = [
            DVec4::new(2.0 / w, 0.0, 0.0, 0.0),
            DVec4::new(0.0, -2.0 / h, 0.0, 0.0),
            DVec4::new(2.0 * f64::from(pixel.x) / w - 1.0, 1.0 - 2.0 * f64::from(pixel.y) / h, 0.0, 1.0),
        ];
        let d = ndc.map(|c| world_from_clip * c);
        let pc = plane.dot(centre);
        let mut columns = d.map(|dk| pc * dk - plane.dot(dk) * centre);
        let at = |cols: &[DVec4; 3], s: DVec2| cols[0] * s.x + cols[1] * s.y + cols[2];
        let mid = at(&columns, DVec2::splat(0.5));
        if !(mid.w.abs() > 0.0) || !mid.is_finite() {
            return None;
        }
        if mid.w < 0.0 {
            columns = columns.map(|c| -c);
        }
        for corner in [DVec2::ZERO, DVec2::X, DVec2::Y, DVec2::ONE] {
            let x = at(&columns, corner);
            if !(x.w > 0.0) {
                return None;
            }
            // In front of the camera.
            if !((*clip_from_world * (x / x.w)).w > 0.0) {
                return None;
            }
        }
        Some(Self { plane_from_pixel: columns })
    }

    /// The homogeneous world point at pixel-local `s` (`w > 0` inside the pixel).
    #[must_use]
    pub fn homogeneous_at(&self, s: DVec2) -> DVec4 {
        let [a, b, c] = self.plane_from_pixel;
        a * s.x + b * s.y + c
    }

    /// The world point at pixel-local `s`.
    #[must_use]
    pub fn world_at(&self, s: DVec2) -> DVec3 {
        let x = self.homogeneous_at(s);
        x.truncate() / x.w
    }

    /// The screen half-plane `(a, b, c)` (inside: `a u + b v + c >= 0`) of
    /// the world half-space `{X : h·(X, 1) >= 0}` on this facet.
    #[must_use]
    pub fn half_plane(&self, h: DVec4) -> DVec3 {
        let [a, b, c] = self.plane_from_pixel;
        DVec3::new(a.dot(h), b.dot(h), c.dot(h))
    }

    /// The facet's footprint in a light's map: the texel rectangle
    /// `[min, max]` (in texel units, `x` across, `y` down; texel `k` covers
    /// `[k, k + 1)`) bounding the pixel's four corners projected with the
    /// light's `clip_from_world` into a `map`-sized map. `None` when a corner
    /// is behind the light's image plane.
    #[must_use]
    pub fn light_footprint(&self, light_clip_from_world: &DMat4, map: UVec2) -> Option<(DVec2, DVec2)> {
        let size = map.as_dvec2();
        let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
        for corner in [DVec2::ZERO, DVec2::X, DVec2::Y, DVec2::ONE] {
            let clip = *light_clip_from_world * self.homogeneous_at(corner);
            if !(clip.w > 0.0) {
                return None;
            }
            let ndc = clip.truncate().truncate() / clip.w;
            let texel = DVec2::new(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * size;
            lo = lo.min(texel);
            hi = hi.max(texel);
        }
        Some((lo, hi))
    }
}

/// The four half-spaces whose intersection is the part of space a triangle
/// `a, b, c` shadows from `light` (homogeneous: `(p, 1)` or `(-d, 0)`):
/// the three planes through an edge and the light, facing the third vertex,
/// and the triangle's plane moved `bias` world units away from the light,
/// facing away from it (so a receiver on the triangle's own plane is not
/// shadowed by it). `None` when the light lies in the triangle's plane (it
/// shadows no area) or the triangle is degenerate.
#[must_use]
pub fn shadow_half_spaces(a: DVec3, b: DVec3, c: DVec3, light: DVec4, bias: f64) -> Option<[DVec4; 4]> {
    let [ah, bh, ch] = [a, b, c].map(|v| v.extend(1.0));
    let normal = (b - a).cross(c - a);
    let scale = normal.length();
    if !(scale > 0.0) || !scale.is_finite() {
        return None;
    }
    let mut out = [DVec4::ZERO; 4];
    for (k, (p, q, r)) in [(ah, bh, ch), (bh, ch, ah), (ch, ah, bh)].into_iter().enumerate() {
        let plane = plane_through(p, q, light);
        let side = plane.dot(r);
        // The light in the triangle's plane makes every edge plane contain
        // the third vertex.
        if !(side.abs() > 1e-12 * plane.truncate().length() * (r.truncate() - p.truncate()).length()) {
            return None;
        }
        out[k] = plane * side.signum();
    }
    let plane = normal.extend(-normal.dot(a));
    let towards_light = plane.dot(light);
    if !(towards_light.abs() > 0.0) {
        return None;
    }
    // Beyond the triangle: the opposite side from the light, by `bias`.
    let beyond = plane * -towards_light.signum();
    out[3] = beyond - DVec4::new(0.0, 0.0, 0.0, bias * scale);
    Some(out)
}

/// The sub-samples of `facet` that any of `triangles` shadows from `light`,
/// from the table: per triangle the AND of its four half-plane masks, ORed
/// over the triangles.
#[must_use]
pub fn occluded_mask(
    facet: &Facet,
    triangles: impl IntoIterator<Item = [DVec3; 3]>,
    light: DVec4,
    bias: f64,
    table: &HalfPlaneTable,
) -> u32 {
    let mut mask = 0u32;
    for [a, b, c] in triangles {
        let Some(spaces) = shadow_half_spaces(a, b, c, light, bias) else { continue };
        let mut tri = u32::MAX;
        for h in spaces {
            tri &= table.lookup(facet.half_plane(h));
            if tri == 0 {
                break;
            }
        }
        mask |= tri;
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::super::bitmask::{direct_mask, QUANTIZATION_ERROR};
    use super::super::SAMPLE_POSITIONS;
    use super::*;
    use crate::mesh::raycast::{Bvh, Ray};
    use crate::mesh::Mesh;

    fn camera() -> (DMat4, UVec2) {
        let camera = crate::Camera::look_at(
            DVec3::new(0.3, 2.0, 4.0),
            DVec3::ZERO,
            DVec3::Y,
            50f64.to_radians(),
            UVec2::new(64, 64),
            0.1,
            50.0,
        )
        .expect("valid camera");
        (camera.clip_from_world(), camera.viewport())
    }

    /// A deterministic pseudo-random number in [0, 1).
    fn rand(state: &mut u64) -> f64 {
        *state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn plane_through_holds_its_points() {
        let p = DVec4::new(1.0, 2.0, 3.0, 1.0);
        let q = DVec4::new(-1.0, 0.5, 2.0, 1.0);
        let r = DVec4::new(0.3, -0.7, 0.0, 0.0);
        let pi = plane_through(p, q, r);
        for x in [p, q, r] {
            assert!(pi.dot(x).abs() < 1e-12, "{}", pi.dot(x));
        }
        assert!(pi.length() > 0.1);
    }

    #[test]
    fn facet_points_lie_on_the_plane_and_on_their_view_rays() {
        let (clip_from_world, viewport) = camera();
        let point = DVec3::new(0.2, 0.0, -0.1);
        let normal = DVec3::new(0.1, 1.0, 0.2).normalize();
        // The pixel whose centre sees `point`.
        let ndc = clip_from_world.project_point3(point);
        let pixel = UVec2::new(((ndc.x + 1.0) * 32.0) as u32, ((1.0 - ndc.y) * 32.0) as u32);
        let facet = Facet::new(&clip_from_world, viewport, pixel, point, normal).expect("facing the camera");
        for s in SAMPLE_POSITIONS.iter().chain(&[DVec2::ZERO, DVec2::ONE]) {
            let x = facet.world_at(*s);
            assert!(normal.dot(x - point).abs() < 1e-9, "off the plane");
            let back = clip_from_world.project_point3(x);
            let want = DVec2::new(
                2.0 * (f64::from(pixel.x) + s.x) / 64.0 - 1.0,
                1.0 - 2.0 * (f64::from(pixel.y) + s.y) / 64.0,
            );
            assert!(back.truncate().distance(want) < 1e-9, "{back} vs {want}");
            assert!(back.z > 0.0 && back.z < 1.0);
        }
        // Its footprint in a light's map holds the projected centre.
        // Any projective map serves as a light's: a camera at the light.
        let light = crate::Camera::look_at(
            DVec3::new(1.0, 5.0, 1.0),
            DVec3::ZERO,
            DVec3::Z,
            40f64.to_radians(),
            UVec2::new(256, 256),
            0.1,
            20.0,
        )
        .expect("valid light camera")
        .clip_from_world();
        let (lo, hi) = facet.light_footprint(&light, UVec2::new(256, 256)).expect("in front");
        let c = light.project_point3(facet.world_at(DVec2::splat(0.5)));
        let texel = DVec2::new(c.x * 0.5 + 0.5, 0.5 - c.y * 0.5) * 256.0;
        assert!(texel.cmpge(lo).all() && texel.cmple(hi).all());
        // A pixel (about 0.06 units here) spans a few texels (about 0.014).
        let extent = (hi - lo).max_element();
        assert!(extent > 1.0 && extent < 16.0, "{extent}");
    }

    #[test]
    fn an_edge_on_plane_has_no_facet() {
        let (clip_from_world, viewport) = camera();
        let eye = DVec3::new(0.3, 2.0, 4.0);
        let point = DVec3::new(0.0, 0.0, 0.0);
        // The plane contains the view ray through `point`.
        let normal = (point - eye).cross(DVec3::X).normalize();
        let ndc = clip_from_world.project_point3(point);
        let pixel = UVec2::new(((ndc.x + 1.0) * 32.0) as u32, ((1.0 - ndc.y) * 32.0) as u32);
        assert_eq!(Facet::new(&clip_from_world, viewport, pixel, point, normal), None);
    }

    /// The half-plane masks agree with tracing a ray from each sub-sample's
    /// facet point to the light against the triangle; the table's rounding
    /// only flips samples close to one of the four lines.
    #[test]
    fn facet_shadow_masks_match_rays_to_the_light() {
        let (clip_from_world, viewport) = camera();
        let table = HalfPlaneTable::new();
        let mut state = 7u64;
        let (mut shadowed, mut partial, mut exact_checked) = (0, 0, 0);
        for case in 0..400 {
            let point = DVec3::new(rand(&mut state) - 0.5, 0.0, rand(&mut state) - 0.5);
            let normal = DVec3::new(0.3 * (rand(&mut state) - 0.5), 1.0, 0.3 * (rand(&mut state) - 0.5)).normalize();
            let ndc = clip_from_world.project_point3(point);
            let pixel = UVec2::new(((ndc.x + 1.0) * 32.0) as u32, ((1.0 - ndc.y) * 32.0) as u32);
            let Some(facet) = Facet::new(&clip_from_world, viewport, pixel, point, normal) else { continue };
            let light = if case % 2 == 0 {
                DVec4::new(rand(&mut state) - 0.5, 3.0 + rand(&mut state), rand(&mut state) - 0.5, 1.0)
            } else {
                DVec3::new(rand(&mut state) - 0.5, 1.0, rand(&mut state) - 0.5).normalize().extend(0.0)
            };
            // A blocker with an edge through the pixel's shadow: a small
            // triangle above the facet, placed around the pixel's centre
            // point's light ray.
            let centre = facet.world_at(DVec2::splat(0.5));
            let toward = if light.w > 0.0 { light.truncate() - centre } else { light.truncate() };
            let base = centre + toward.normalize() * (0.2 + 0.5 * rand(&mut state));
            let jitter = |state: &mut u64| DVec3::new(rand(state) - 0.5, 0.0, rand(state) - 0.5) * 0.12;
            let [a, b, c] = [base + jitter(&mut state), base + jitter(&mut state), base + jitter(&mut state)];
            let Some(spaces) = shadow_half_spaces(a, b, c, light, 1e-6) else { continue };
            let mesh = Mesh {
                positions: vec![a.as_vec3(), b.as_vec3(), c.as_vec3()],
                normals: vec![glam::Vec3::Y; 3],
                indices: vec![0, 1, 2],
            };
            let bvh = Bvh::new(&mesh);
            let lines = spaces.map(|h| facet.half_plane(h));
            let exact = lines.iter().fold(u32::MAX, |m, l| m & direct_mask(*l));
            let looked_up = occluded_mask(&facet, [[a, b, c]], light, 1e-6, &table);
            for (s, p) in SAMPLE_POSITIONS.iter().enumerate() {
                let x = facet.world_at(*p);
                let (direction, t_max) =
                    if light.w > 0.0 { (light.truncate() - x, 1.0) } else { (light.truncate(), 1e6) };
                let hit = bvh.occluded(&Ray { origin: x.as_vec3(), direction: direction.as_vec3() }, t_max);
                // Distance of the sample from the nearest of the four lines, in pixels.
                let near = lines
                    .iter()
                    .map(|l| l.dot(p.extend(1.0)).abs() / l.truncate().length())
                    .fold(f64::INFINITY, f64::min);
                if near > 1e-3 {
                    exact_checked += 1;
                    assert_eq!(exact & (1 << s) != 0, hit, "case {case} sample {s}: exact half-planes vs ray");
                }
                if near > QUANTIZATION_ERROR {
                    assert_eq!(looked_up & (1 << s) != 0, hit, "case {case} sample {s}: table vs ray");
                }
            }
            if exact != 0 {
                shadowed += 1;
            }
            if exact != 0 && exact != u32::MAX {
                partial += 1;
            }
        }
        // The cases do exercise shadow edges inside pixels.
        assert!(shadowed > 50 && partial > 20 && exact_checked > 5000, "{shadowed} {partial} {exact_checked}");
    }
}
