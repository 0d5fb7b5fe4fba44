//! Exact ray casting against triangle meshes: a bounding volume hierarchy,
//! closest-hit and any-hit queries, and per-pixel shadow masks traced like
//! the renderer draws them (the ground truth of the shadow experiments).
//!
//! # Algorithm
//! The BVH splits each node's triangles where the surface-area heuristic
//! over 16 centroid bins per axis is least (below depth 32 it splits at the
//! centroid median of the longest axis, which bounds the depth; build
//! `O(n log n)`, leaves of at most [`LEAF_SIZE`] triangles); queries use
//! slab tests against node boxes and Möller–Trumbore against triangles
//! (`O(log n)` typical). Rays are traced in parallel with
//! rayon.

use glam::{DMat4, DVec3, Vec2, Vec3};
use rayon::prelude::*;

use super::masks::ShadowMasks;
use super::{Mesh, Scene};
use crate::{Camera, Light};

/// Most triangles per BVH leaf.
pub const LEAF_SIZE: usize = 4;

/// Centroid bins per axis of the surface-area split.
const SAH_BINS: usize = 16;

/// Nodes at this depth or deeper (the root is at 0) split at the centroid
/// median instead of by surface area, which bounds the tree's depth: a
/// median split of `n <= 2^32` triangles reaches leaves of [`LEAF_SIZE`]
/// within 30 levels, so no leaf is deeper than `SAH_DEPTH + 30 = 62` and the
/// traversal's stack (one entry per level plus one) never holds more than 63
/// of its 64 entries.
const SAH_DEPTH: usize = 32;

/// A triangle while the BVH is built.
#[derive(Clone, Copy, Debug)]
struct Item {
    /// Index of the triangle in the mesh.
    index: u32,
    triangle: Triangle,
    centroid: Vec3,
    /// The triangle's box.
    min: Vec3,
    max: Vec3,
}

/// A ray `origin + t direction`, `t >= 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: Vec3,
    /// Direction (any non-zero length; `t` is measured in its units).
    pub direction: Vec3,
}

/// The nearest intersection of a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Index of the triangle in the mesh the BVH was built from.
    pub triangle: u32,
    /// Barycentric coordinates `(u, v)` of the hit: weights of the second and
    /// third vertex.
    pub barycentric: Vec2,
}

#[derive(Clone, Copy, Debug)]
struct Node {
    min: Vec3,
    max: Vec3,
    /// Leaf: first triangle in `order`; inner node: index of the left child
    /// (the right child follows it).
    first: u32,
    /// Triangles in a leaf; 0 for an inner node.
    count: u32,
}

/// A triangle as Möller–Trumbore wants it.
#[derive(Clone, Copy, Debug)]
struct Triangle {
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
}

/// A bounding volume hierarchy over a mesh's triangles.
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// Triangles in leaf order.
    triangles: Vec<Triangle>,
    /// Original triangle index of each entry of `triangles`.
    order: Vec<u32>,
}

impl Bvh {
    /// Builds the hierarchy over `mesh`'s triangles. The mesh should be valid
    /// ([`Mesh::validate`]); out-of-range indices are skipped.
    #[must_use]
    pub fn new(mesh: &Mesh) -> Self {
        Self::build(mesh, SAH_DEPTH)
    }

    /// [`new`](Self::new) with the surface-area split above depth
    /// `sah_depth` and the median split from there on (no leaf deeper than
    /// `sah_depth + 30`).
    fn build(mesh: &Mesh, sah_depth: usize) -> Self {
        let mut items: Vec<Item> = mesh
            .indices
            .chunks_exact(3)
            .enumerate()
            .filter_map(|(k, tri)| {
                let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| mesh.positions.get(i as usize).copied());
                let (a, b, c) = (a?, b?, c?);
                let triangle = Triangle { v0: a, e1: b - a, e2: c - a };
                // The box of the corners as the traversal's triangle test
                // sees them (`v0 + e1`, `v0 + e2`).
                let corners = [triangle.v0, triangle.v0 + triangle.e1, triangle.v0 + triangle.e2];
                let min = corners[0].min(corners[1]).min(corners[2]);
                let max = corners[0].max(corners[1]).max(corners[2]);
                Some(Item { index: k as u32, triangle, centroid: (a + b + c) / 3.0, min, max })
            })
            .collect();
        let mut nodes = Vec::with_capacity(2 * items.len() / LEAF_SIZE + 1);
        nodes.push(Node { min: Vec3::ZERO, max: Vec3::ZERO, first: 0, count: 0 });
        // Explicit stack of (node, range, depth) to build without recursion.
        let mut stack = vec![(0usize, 0usize, items.len(), 0usize)];
        while let Some((node, start, end, depth)) = stack.pop() {
            let slice = &mut items[start..end];
            let (mut min, mut max) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
            let (mut cmin, mut cmax) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
            for item in slice.iter() {
                min = min.min(item.min);
                max = max.max(item.max);
                cmin = cmin.min(item.centroid);
                cmax = cmax.max(item.centroid);
            }
            let extent = cmax - cmin;
            if slice.len() <= LEAF_SIZE || extent.max_element() <= 0.0 {
                nodes[node] = Node { min, max, first: start as u32, count: slice.len() as u32 };
                continue;
            }
            let mid = if depth < sah_depth {
                sah_partition(slice, cmin, extent)
            } else {
                let axis = extent.max_position();
                let mid = slice.len() / 2;
                slice.select_nth_unstable_by(mid, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
                mid
            };
            let left = nodes.len();
            nodes.push(Node { min: Vec3::ZERO, max: Vec3::ZERO, first: 0, count: 0 });
            nodes.push(Node { min: Vec3::ZERO, max: Vec3::ZERO, first: 0, count: 0 });
            nodes[node] = Node { min, max, first: left as u32, count: 0 };
            stack.push((left, start, start + mid, depth + 1));
            stack.push((left + 1, start + mid, end, depth + 1));
        }
        if items.is_empty() {
            nodes[0] = Node { min: Vec3::INFINITY, max: Vec3::NEG_INFINITY, first: 0, count: 0 };
        }
        Self {
            nodes,
            order: items.iter().map(|item| item.index).collect(),
            triangles: items.into_iter().map(|item| item.triangle).collect(),
        }
    }

    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The nearest hit with `0 <= t < t_max`.
    #[must_use]
    pub fn closest_hit(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        // Shared by the traversal (which prunes with it) and the triangle test.
        let t_best = std::cell::Cell::new(t_max);
        self.traverse(
            ray,
            |t_lim| t_lim.min(t_best.get()),
            |k, tri| {
                if let Some((t, uv)) = intersect(ray, tri, t_best.get()) {
                    t_best.set(t);
                    best = Some(Hit { t, triangle: self.order[k], barycentric: uv });
                }
                false
            },
        );
        best
    }

    /// Whether anything blocks the ray for `0 <= t < t_max`.
    #[must_use]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let mut hit = false;
        self.traverse(
            ray,
            |t| t.min(t_max),
            |_, tri| {
                hit = intersect(ray, tri, t_max).is_some();
                hit
            },
        );
        hit
    }

    /// Depth-first traversal, nearer child first. `limit` gives the current
    /// search distance; `visit` tests one triangle and returns `true` to stop.
    /// A node is tested against the limit when its parent is opened and
    /// tested again when popped only if the limit shrank since (the same
    /// test would give the same answer): an occlusion ray's limit never
    /// shrinks, so each node costs one box test, not two.
    fn traverse(&self, ray: &Ray, mut limit: impl FnMut(f32) -> f32, mut visit: impl FnMut(usize, &Triangle) -> bool) {
        let Some(root) = self.nodes.first() else { return };
        if self.triangles.is_empty() {
            return;
        }
        // Division by a zero component gives ±inf, which the slab test handles.
        let inv = ray.direction.recip();
        let mut t_max = limit(f32::INFINITY);
        if slab(ray.origin, inv, root.min, root.max, t_max).is_none() {
            return;
        }
        // Each entry: a node and the limit it passed its box test with. The
        // build's depth bound (see `SAH_DEPTH`: no leaf deeper than 62) and
        // a depth-first walk's one entry per level plus one keep this at
        // most 63 full; an overflow would panic at the index, never drop
        // a node.
        let mut stack = [(0u32, t_max); 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (index, tested) = stack[top];
            let node = &self.nodes[index as usize];
            t_max = limit(f32::INFINITY);
            if t_max < tested && slab(ray.origin, inv, node.min, node.max, t_max).is_none() {
                continue;
            }
            if node.count > 0 {
                let first = node.first as usize;
                for k in first..first + node.count as usize {
                    if visit(k, &self.triangles[k]) {
                        return;
                    }
                }
                continue;
            }
            let (l, r) = (node.first as usize, node.first as usize + 1);
            let dl = slab(ray.origin, inv, self.nodes[l].min, self.nodes[l].max, t_max);
            let dr = slab(ray.origin, inv, self.nodes[r].min, self.nodes[r].max, t_max);
            // Push the farther child first so the nearer one is visited next.
            let mut push = |i: usize| {
                stack[top] = (i as u32, t_max);
                top += 1;
            };
            match (dl, dr) {
                (Some(a), Some(b)) if a <= b => {
                    push(r);
                    push(l);
                }
                (Some(_), Some(_)) => {
                    push(l);
                    push(r);
                }
                (Some(_), None) => push(l),
                (None, Some(_)) => push(r),
                (None, None) => {}
            }
        }
    }
}

/// Half the surface area of a box.
fn half_area(min: Vec3, max: Vec3) -> f32 {
    let d = (max - min).max(Vec3::ZERO);
    d.x * d.y + d.y * d.z + d.z * d.x
}

/// Splits `items` (at least two, centroids spanning `extent > 0` from
/// `cmin` on some axis) where the surface-area heuristic is least: the
/// centroids are binned into [`SAH_BINS`] equal slabs per axis and every
/// boundary between bins is costed as `area(left) * count(left) +
/// area(right) * count(right)`; the first least cost (axes x, y, z, then
/// boundaries in order) wins, so the build is deterministic. Moves the left
/// side to the front and returns its length, which is never 0 or
/// `items.len()` (the extreme centroids of an axis with extent fall in its
/// first and last bins).
fn sah_partition(items: &mut [Item], cmin: Vec3, extent: Vec3) -> usize {
    let scale = Vec3::splat(SAH_BINS as f32) / extent;
    let bin_of = |c: f32, axis: usize| -> usize { (((c - cmin[axis]) * scale[axis]) as usize).min(SAH_BINS - 1) };
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let mut counts = [0usize; SAH_BINS];
        let mut bmin = [Vec3::INFINITY; SAH_BINS];
        let mut bmax = [Vec3::NEG_INFINITY; SAH_BINS];
        for item in items.iter() {
            let b = bin_of(item.centroid[axis], axis);
            counts[b] += 1;
            bmin[b] = bmin[b].min(item.min);
            bmax[b] = bmax[b].max(item.max);
        }
        // Sweep from the right: cost of the right side of each boundary.
        let mut right_cost = [0.0f32; SAH_BINS];
        let (mut rmin, mut rmax, mut rcount) = (Vec3::INFINITY, Vec3::NEG_INFINITY, 0usize);
        for b in (1..SAH_BINS).rev() {
            rmin = rmin.min(bmin[b]);
            rmax = rmax.max(bmax[b]);
            rcount += counts[b];
            right_cost[b] = if rcount == 0 { 0.0 } else { half_area(rmin, rmax) * rcount as f32 };
        }
        let (mut lmin, mut lmax, mut lcount) = (Vec3::INFINITY, Vec3::NEG_INFINITY, 0usize);
        for b in 1..SAH_BINS {
            lmin = lmin.min(bmin[b - 1]);
            lmax = lmax.max(bmax[b - 1]);
            lcount += counts[b - 1];
            if lcount == 0 || lcount == items.len() {
                continue;
            }
            let cost = half_area(lmin, lmax) * lcount as f32 + right_cost[b];
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b));
            }
        }
    }
    let Some((_, axis, boundary)) = best else {
        // Unreachable for a valid extent; split in half rather than fail.
        return items.len() / 2;
    };
    // In-place partition: bins below `boundary` to the front.
    let (mut i, mut j) = (0, items.len());
    while i < j {
        if bin_of(items[i].centroid[axis], axis) < boundary {
            i += 1;
        } else {
            j -= 1;
            items.swap(i, j);
        }
    }
    i
}

/// Entry distance of the ray into a box, if it enters before `t_max`.
fn slab(origin: Vec3, inv_dir: Vec3, min: Vec3, max: Vec3, t_max: f32) -> Option<f32> {
    let t0 = (min - origin) * inv_dir;
    let t1 = (max - origin) * inv_dir;
    // NaN (0 * inf on a slab boundary) is dropped by min/max.
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element().min(t_max);
    (near <= far).then_some(near)
}

/// Möller–Trumbore: `(t, (u, v))` for a hit with `0 <= t < t_max`.
fn intersect(ray: &Ray, tri: &Triangle, t_max: f32) -> Option<(f32, Vec2)> {
    let p = ray.direction.cross(tri.e2);
    let det = tri.e1.dot(p);
    if det.abs() < f32::MIN_POSITIVE {
        return None;
    }
    let inv_det = det.recip();
    let s = ray.origin - tri.v0;
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(tri.e1);
    let v = ray.direction.dot(q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = tri.e2.dot(q) * inv_det;
    (t >= 0.0 && t < t_max).then_some((t, Vec2::new(u, v)))
}

/// A scene ready for ray casting: its triangles merged into one BVH, with
/// the vertex normals for shading decisions.
#[derive(Clone, Debug)]
pub struct RayCaster {
    mesh: Mesh,
    bvh: Bvh,
    /// Offset of shadow-ray origins along the surface normal, in world units.
    pub shadow_ray_offset: f32,
}

impl RayCaster {
    /// Builds the BVH over every object of `scene`. The shadow-ray offset
    /// defaults to `1e-4` of the scene's diagonal.
    #[must_use]
    pub fn new(scene: &Scene) -> Self {
        let (mesh, _) = scene.merged();
        let bvh = Bvh::new(&mesh);
        let diagonal = mesh.bounds().map_or(1.0, |b| b.diagonal()) as f32;
        Self { mesh, bvh, shadow_ray_offset: 1e-4 * diagonal }
    }

    /// The BVH.
    #[must_use]
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// The interpolated unit vertex normal and geometric normal at a hit.
    #[must_use]
    pub fn normals_at(&self, hit: &Hit) -> (Vec3, Vec3) {
        let k = 3 * hit.triangle as usize;
        let [a, b, c] = [0, 1, 2].map(|i| self.mesh.indices[k + i] as usize);
        let (u, v) = (hit.barycentric.x, hit.barycentric.y);
        let shading = (self.mesh.normals[a] * (1.0 - u - v) + self.mesh.normals[b] * u + self.mesh.normals[c] * v)
            .normalize_or_zero();
        let [pa, pb, pc] = [a, b, c].map(|i| self.mesh.positions[i]);
        let geometric = (pb - pa).cross(pc - pa).normalize_or_zero();
        (shading, geometric)
    }

    /// Whether `light` is blocked from the surface point `point` with
    /// geometric normal `geometric_normal` (facing the light is not checked).
    #[must_use]
    pub fn in_shadow(&self, point: Vec3, geometric_normal: Vec3, light: &Light) -> bool {
        let (to_light, t_max) = match *light {
            Light::Directional { direction } => (-direction.as_vec3(), f32::INFINITY),
            Light::Point { position } | Light::Spot { position, .. } => (position.as_vec3() - point, 1.0),
        };
        // Offset towards the light's side of the surface so that the ray
        // never re-hits the triangle it starts on.
        let side = if geometric_normal.dot(to_light) >= 0.0 { 1.0 } else { -1.0 };
        let origin = point + geometric_normal * (side * self.shadow_ray_offset);
        let t_max = if t_max.is_finite() { t_max * (1.0 - 1e-5) } else { t_max };
        self.bvh.occluded(&Ray { origin, direction: to_light }, t_max)
    }

    /// Traces one primary ray through every pixel centre of the camera's
    /// viewport scaled to `width x height`, and for every light tests facing
    /// (`interpolated normal · to-light > 0`) and occlusion, exactly as the
    /// renderer's mask output defines them (see [`ShadowMasks`]). At most 32
    /// lights; the rest are ignored.
    ///
    /// The same as [`primary_view`](Self::primary_view) followed by
    /// [`trace_masks_from`](Self::trace_masks_from); callers that trace many
    /// lights from one camera should keep the view.
    #[must_use]
    pub fn trace_masks(&self, camera: &Camera, lights: &[Light], width: u32, height: u32) -> ShadowMasks {
        self.trace_masks_from(&self.primary_view(camera, width, height), lights)
    }

    /// The light-independent half of [`trace_masks`](Self::trace_masks):
    /// the primary ray of every pixel centre, its hit point, depth-buffer
    /// value and normals. About two thirds of a one-light trace on the
    /// paper's scene; an experiment's camera is fixed, so it is traced once
    /// per run instead of once per light.
    #[must_use]
    pub fn primary_view(&self, camera: &Camera, width: u32, height: u32) -> PrimaryView {
        let clip_from_world = camera.clip_from_world();
        let world_from_clip = clip_from_world.inverse();
        let pixels = (0..width * height)
            .into_par_iter()
            .map(|i| self.primary_pixel(i % width, i / width, width, height, &clip_from_world, &world_from_clip))
            .collect();
        PrimaryView { width, height, pixels }
    }

    /// Shadow masks of `lights` over a [`primary_view`](Self::primary_view):
    /// the same words as [`trace_masks`](Self::trace_masks) with that view's
    /// camera and size. At most 32 lights; the rest are ignored.
    #[must_use]
    pub fn trace_masks_from(&self, view: &PrimaryView, lights: &[Light]) -> ShadowMasks {
        let lights = &lights[..lights.len().min(32)];
        let bits: Vec<(u32, u32)> = view.pixels.par_iter().map(|p| self.light_bits(p, lights)).collect();
        ShadowMasks {
            width: view.width,
            height: view.height,
            depth: view.pixels.iter().map(|p| p.depth).collect(),
            shadow: bits.iter().map(|b| b.0).collect(),
            facing: bits.iter().map(|b| b.1).collect(),
        }
    }

    fn primary_pixel(
        &self,
        x: u32,
        y: u32,
        width: u32,
        height: u32,
        clip_from_world: &DMat4,
        world_from_clip: &DMat4,
    ) -> PrimaryPixel {
        // Pixel centre to NDC: x right; row 0 at the top, NDC y up (flip).
        let ndc_x = (f64::from(x) + 0.5) / f64::from(width) * 2.0 - 1.0;
        let ndc_y = 1.0 - (f64::from(y) + 0.5) / f64::from(height) * 2.0;
        // Depth 0 is the near plane, 1 the far plane (wgpu's range).
        let near = world_from_clip.project_point3(DVec3::new(ndc_x, ndc_y, 0.0));
        let far = world_from_clip.project_point3(DVec3::new(ndc_x, ndc_y, 1.0));
        let ray = Ray { origin: near.as_vec3(), direction: (far - near).as_vec3() };
        let Some(hit) = self.bvh.closest_hit(&ray, 1.0) else {
            return PrimaryPixel::MISS;
        };
        let point = near + (far - near) * f64::from(hit.t);
        let depth = clip_from_world.project_point3(point).z as f32;
        let (shading, geometric) = self.normals_at(&hit);
        PrimaryPixel { hit: true, depth, point: point.as_vec3(), shading, geometric }
    }

    /// Shadow and facing bits of one pixel for every light.
    fn light_bits(&self, pixel: &PrimaryPixel, lights: &[Light]) -> (u32, u32) {
        if !pixel.hit {
            return (0, 0);
        }
        let (point, shading, geometric) = (pixel.point, pixel.shading, pixel.geometric);
        let (mut shadow, mut facing) = (0u32, 0u32);
        for (i, light) in lights.iter().enumerate() {
            let to_light = match *light {
                Light::Directional { direction } => -direction.as_vec3(),
                Light::Point { position } | Light::Spot { position, .. } => position.as_vec3() - point,
            };
            if shading.dot(to_light) > 0.0 && light.reaches(point.as_dvec3()) {
                facing |= 1 << i;
                if self.in_shadow(point, geometric, light) {
                    shadow |= 1 << i;
                }
            }
        }
        (shadow, facing)
    }
}

/// The camera's primary rays over a `width x height` grid of pixel centres
/// ([`RayCaster::primary_view`]): what the shadow rays of every light start
/// from. 44 bytes per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct PrimaryView {
    width: u32,
    height: u32,
    pixels: Vec<PrimaryPixel>,
}

impl PrimaryView {
    /// Width in pixels.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.height
    }
}

/// One pixel's primary hit.
#[derive(Clone, Copy, Debug, PartialEq)]
struct PrimaryPixel {
    /// The ray hit a triangle.
    hit: bool,
    /// Depth-buffer value; `1.0` where the ray hit nothing.
    depth: f32,
    point: Vec3,
    shading: Vec3,
    geometric: Vec3,
}

impl PrimaryPixel {
    const MISS: Self = Self { hit: false, depth: 1.0, point: Vec3::ZERO, shading: Vec3::ZERO, geometric: Vec3::ZERO };
}

#[cfg(test)]
mod tests {
    use super::super::primitives;
    use super::*;

    /// Brute force over all triangles, for comparison.
    fn brute_closest(mesh: &Mesh, ray: &Ray) -> Option<f32> {
        mesh.indices
            .chunks_exact(3)
            .filter_map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
                intersect(ray, &Triangle { v0: a, e1: b - a, e2: c - a }, f32::INFINITY).map(|h| h.0)
            })
            .reduce(f32::min)
    }

    #[test]
    fn bvh_matches_brute_force() {
        let mut mesh = primitives::sphere(1.0, 2000);
        mesh.append(&primitives::torus(2.0, 0.4, 2000));
        let bvh = Bvh::new(&mesh);
        let mut hits = 0;
        for i in 0..400 {
            let a = i as f32 * 0.37;
            let origin = Vec3::new(5.0 * a.cos(), 0.3 * (a * 1.7).sin(), 5.0 * a.sin());
            let target = Vec3::new((a * 2.3).sin() * 1.5, (a * 0.9).cos() * 0.5, (a * 1.1).cos() * 1.5);
            let ray = Ray { origin, direction: target - origin };
            let got = bvh.closest_hit(&ray, f32::INFINITY).map(|h| h.t);
            let want = brute_closest(&mesh, &ray);
            assert_eq!(got.is_some(), want.is_some(), "ray {i}");
            if let (Some(g), Some(w)) = (got, want) {
                assert!((g - w).abs() < 1e-5, "ray {i}: {g} vs {w}");
                hits += 1;
                assert!(bvh.occluded(&ray, g + 1e-3));
                assert!(!bvh.occluded(&ray, g * 0.999));
            }
        }
        assert!(hits > 100);
    }

    /// Depth of the deepest leaf (the root at 0) and the triangles in leaves.
    fn depth_and_count(bvh: &Bvh) -> (usize, usize) {
        let (mut deepest, mut count) = (0, 0);
        let mut stack = vec![(0usize, 0usize)];
        while let Some((i, d)) = stack.pop() {
            let node = &bvh.nodes[i];
            if node.count > 0 {
                deepest = deepest.max(d);
                count += node.count as usize;
            } else {
                stack.push((node.first as usize, d + 1));
                stack.push((node.first as usize + 1, d + 1));
            }
        }
        (deepest, count)
    }

    /// Triangles at geometrically growing distances make the surface-area
    /// split peel a few off per level (28 levels for these 120 with the
    /// default switch depth); the median fallback caps the depth within what
    /// the traversal's stack holds (checked with an early switch too), and
    /// every triangle is still found.
    #[test]
    fn a_skewed_mesh_stays_within_the_stack() {
        let mut mesh = Mesh::default();
        for i in 0..120u32 {
            let x = 2.0f32.powi(i as i32);
            let base = mesh.positions.len() as u32;
            mesh.positions.extend([Vec3::new(x, 0.0, 0.0), Vec3::new(x, 1.0, 0.0), Vec3::new(x, 0.0, 1.0)]);
            mesh.normals.extend([Vec3::X; 3]);
            mesh.indices.extend([base, base + 1, base + 2]);
        }
        for sah_depth in [SAH_DEPTH, 8] {
            let bvh = Bvh::build(&mesh, sah_depth);
            let (deepest, count) = depth_and_count(&bvh);
            assert_eq!(count, 120);
            assert!(deepest <= sah_depth + 30, "{deepest}");
            // The surface-area split peels a few triangles off per level.
            assert!(deepest > 8, "{deepest}");
            assert_hits_each(&bvh);
        }
    }

    fn assert_hits_each(bvh: &Bvh) {
        for i in 0..120u32 {
            let x = 2.0f32.powi(i as i32);
            // Between the previous triangle (at x / 2) and this one.
            let ray = Ray { origin: Vec3::new(0.99 * x, 0.25, 0.25), direction: Vec3::X };
            let hit = bvh.closest_hit(&ray, f32::INFINITY).expect("every triangle is hit");
            assert_eq!(hit.triangle, i);
            assert!(bvh.occluded(&ray, 0.02 * x));
            assert!(!bvh.occluded(&ray, 0.005 * x));
        }
    }
}
