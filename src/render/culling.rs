//! Per-object culling of the scene passes against a clip volume.
//!
//! The rasterizer clips every primitive to the half-spaces `-w <= x <= w`,
//! `-w <= y <= w` and (unless depth is unclipped) `0 <= z <= w` of clip
//! space. Each is linear in homogeneous world coordinates, so an object's
//! bounding box lies outside one exactly when its eight corners do: such an
//! object cannot produce a fragment and is left out of the draw. Nothing else
//! is culled, so the output is the same as drawing everything, whatever the
//! matrix (perspective, orthographic, PSM's inverted lights with `w < 0` for
//! part of the scene).

use std::ops::Range;

use glam::{DMat4, DVec3, DVec4};

use super::lookup::DepthClip;

/// One scene object: its index range and bounding-box corners.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ObjectBounds {
    pub(crate) indices: Range<u32>,
    corners: [DVec4; 8],
}

impl ObjectBounds {
    /// Bounds of `positions` drawn by `indices`; `None` when there is
    /// nothing to draw.
    pub(crate) fn new(indices: Range<u32>, positions: impl IntoIterator<Item = DVec3>) -> Option<Self> {
        let (lo, hi) =
            positions.into_iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
        if indices.is_empty() || !lo.is_finite() || !hi.is_finite() {
            return None;
        }
        let corner = |i: usize| {
            DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
            .extend(1.0)
        };
        Some(Self { indices, corners: std::array::from_fn(corner) })
    }
}

/// Whether no point of the box survives clipping by `clip_from_world`.
fn outside(corners: &[DVec4; 8], clip_from_world: &DMat4, depth: DepthClip) -> bool {
    let clip = corners.map(|c| *clip_from_world * c);
    // The six plane functions; a point is inside where all are >= 0.
    let planes: [fn(DVec4) -> f64; 6] =
        [|c| c.w + c.x, |c| c.w - c.x, |c| c.w + c.y, |c| c.w - c.y, |c| c.z, |c| c.w - c.z];
    let count = match depth {
        DepthClip::Clipped => 6,
        DepthClip::Unclipped => 4,
    };
    planes[..count].iter().any(|plane| {
        clip.iter().all(|&c| {
            // The GPU evaluates the matrix in f32: cull only what is
            // outside by more than its rounding.
            let tolerance = 1e-5 * (c.x.abs() + c.y.abs() + c.z.abs() + c.w.abs());
            plane(c) < -tolerance
        })
    })
}

/// Most draws one pass issues: a scene of many small objects would
/// otherwise cost more in draw calls than culling saves.
pub(crate) const MAX_DRAWS: usize = 256;

/// The index ranges of the objects that may reach the clip volume of
/// `clip_from_world`, consecutive ones merged into one draw, at most
/// [`MAX_DRAWS`] of them (see [`limit_draws`]). Under unclipped depth the
/// near and far planes do not cull.
pub(crate) fn visible_ranges(objects: &[ObjectBounds], clip_from_world: &DMat4, clip: DepthClip) -> Vec<Range<u32>> {
    let mut ranges: Vec<Range<u32>> = Vec::new();
    for object in objects.iter().filter(|o| !outside(&o.corners, clip_from_world, clip)) {
        match ranges.last_mut() {
            Some(last) if last.end == object.indices.start => last.end = object.indices.end,
            _ => ranges.push(object.indices.clone()),
        }
    }
    limit_draws(ranges, MAX_DRAWS)
}

/// Merges sorted, disjoint `ranges` across their smallest gaps until at
/// most `max` remain. What a merge adds back was culled, so it is drawn but
/// clipped: the output does not change.
fn limit_draws(ranges: Vec<Range<u32>>, max: usize) -> Vec<Range<u32>> {
    if ranges.len() <= max.max(1) {
        return ranges;
    }
    // Gap i lies between ranges i and i + 1; close the smallest ones.
    let mut gaps: Vec<(u32, usize)> = ranges.windows(2).enumerate().map(|(i, w)| (w[1].start - w[0].end, i)).collect();
    let close = ranges.len() - max.max(1);
    gaps.select_nth_unstable(close - 1);
    let mut closed = vec![false; ranges.len()];
    for &(_, i) in &gaps[..close] {
        closed[i] = true;
    }
    let mut merged: Vec<Range<u32>> = Vec::with_capacity(max);
    let mut joining = false;
    for (range, &join_next) in ranges.into_iter().zip(&closed) {
        match merged.last_mut() {
            Some(last) if joining => last.end = range.end,
            _ => merged.push(range),
        }
        joining = join_next;
    }
    merged
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box(at: DVec3, indices: Range<u32>) -> ObjectBounds {
        ObjectBounds::new(indices, [at - DVec3::splat(0.5), at + DVec3::splat(0.5)]).unwrap()
    }

    /// A perspective light at the origin looking down -z: 90° field of
    /// view, near 1, far 100, wgpu depth 0..1 (`w = -z`).
    fn perspective() -> DMat4 {
        let (near, far) = (1.0, 100.0);
        let a = far / (near - far);
        DMat4::from_cols(DVec4::X, DVec4::Y, DVec4::new(0.0, 0.0, a, -1.0), DVec4::new(0.0, 0.0, a * near, 0.0))
    }

    #[test]
    fn keeps_what_reaches_the_volume_and_merges_neighbours() {
        let objects = [
            unit_box(DVec3::new(0.0, 0.0, -10.0), 0..30),     // inside
            unit_box(DVec3::new(9.8, 0.0, -10.0), 30..60),    // straddles x = w
            unit_box(DVec3::new(30.0, 0.0, -10.0), 60..90),   // right of the volume
            unit_box(DVec3::new(0.0, 0.0, 10.0), 90..120),    // behind the light (w < 0)
            unit_box(DVec3::new(0.0, 0.0, -200.0), 120..150), // past far
            unit_box(DVec3::new(0.0, -3.0, -20.0), 150..153), // inside
        ];
        assert_eq!(visible_ranges(&objects, &perspective(), DepthClip::Clipped), vec![0..60, 150..153]);
        // Unclipped depth keeps what lies past far; the box behind the light
        // stays culled (w + x < 0 at all its corners).
        assert_eq!(visible_ranges(&objects, &perspective(), DepthClip::Unclipped), vec![0..60, 120..153]);
    }

    #[test]
    fn a_negated_matrix_clips_the_same_points() {
        // PSM's inverted lights: -M describes the same projective map, but
        // the rasterizer keeps only points with w > 0 in its clip space.
        let m = -perspective();
        let inside_for_m = unit_box(DVec3::new(0.0, 0.0, -10.0), 0..3);
        let behind = unit_box(DVec3::new(0.0, 0.0, 10.0), 3..6);
        let ranges = visible_ranges(&[inside_for_m, behind], &m, DepthClip::Unclipped);
        // Under -M the box in front of the light has w < 0 everywhere:
        // clipped. The one behind has w > 0 and small x, y: drawn (its z
        // lies past w, so only with unclipped depth).
        assert_eq!(ranges, vec![3..6]);
        assert!(visible_ranges(&[unit_box(DVec3::new(0.0, 0.0, 10.0), 3..6)], &m, DepthClip::Clipped).is_empty());
    }

    #[test]
    fn orthographic_boxes_on_the_boundary_are_kept() {
        // x, y in [-1, 1], depth 0..1 for z from 0 to -10.
        let m = DMat4::from_cols(DVec4::X, DVec4::Y, DVec4::new(0.0, 0.0, -0.1, 0.0), DVec4::W);
        // Touches x = 1 exactly.
        let touching = ObjectBounds::new(0..3, [DVec3::new(1.0, 0.0, -1.0), DVec3::new(2.0, 0.5, -2.0)]).unwrap();
        let beyond = ObjectBounds::new(3..6, [DVec3::new(1.01, 0.0, -1.0), DVec3::new(2.0, 0.5, -2.0)]).unwrap();
        assert_eq!(visible_ranges(&[touching, beyond], &m, DepthClip::Clipped), vec![0..3]);
    }

    #[test]
    fn many_ranges_merge_across_the_smallest_gaps() {
        // Ranges of 3 indices with gaps 3, 30, 6, 300.
        let ranges = vec![0..3, 6..9, 39..42, 48..51, 351..354];
        assert_eq!(limit_draws(ranges.clone(), 5), ranges);
        assert_eq!(limit_draws(ranges.clone(), 4), vec![0..9, 39..42, 48..51, 351..354]);
        assert_eq!(limit_draws(ranges.clone(), 3), vec![0..9, 39..51, 351..354]);
        assert_eq!(limit_draws(ranges.clone(), 2), vec![0..51, 351..354]);
        assert_eq!(limit_draws(ranges.clone(), 1), vec![0..354]);
        // Everything visible stays covered, whatever the limit.
        let many: Vec<_> = (0..10_000u32).map(|i| 9 * i..9 * i + 3 + 3 * (i % 2)).collect();
        let limited = limit_draws(many.clone(), MAX_DRAWS);
        assert_eq!(limited.len(), MAX_DRAWS);
        assert!(many.iter().all(|r| limited.iter().any(|l| l.start <= r.start && r.end <= l.end)));
        assert!(limited.windows(2).all(|w| w[0].end < w[1].start));
    }

    #[test]
    fn empty_objects_are_not_drawn() {
        assert!(ObjectBounds::new(0..0, [DVec3::ZERO]).is_none());
        assert!(ObjectBounds::new(0..3, std::iter::empty()).is_none());
    }
}
