//! Planar convex hull: Andrew's monotone chain with exact orientation tests.

use core::cmp::Ordering;

use glam::DVec2;
use robust::{orient2d, Coord};

/// Exact orientation of the triangle `(a, b, c)`.
///
/// Positive when `c` lies strictly left of the directed line `a → b` (the turn
/// `a → b → c` is counter-clockwise), negative when it lies strictly right and
/// exactly zero when the three points are collinear. The sign is exact for all
/// finite inputs (Shewchuk's adaptive predicate, via the `robust` crate).
#[inline]
#[must_use]
pub(crate) fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    orient2d(Coord { x: a.x, y: a.y }, Coord { x: b.x, y: b.y }, Coord { x: c.x, y: c.y })
}

/// Lexicographic order on `(x, y)`.
///
/// Only ever applied to finite points, where the order is total; `-0.0` and
/// `0.0` compare equal, so equal points end up adjacent for deduplication.
///
/// Plain comparisons rather than `partial_cmp(..).then_with(..)`: the same
/// answer for every pair of finite points (so the sort permutes exactly as
/// before), in fewer instructions.
#[inline]
fn lexicographic(a: &DVec2, b: &DVec2) -> Ordering {
    if a.x < b.x {
        Ordering::Less
    } else if a.x > b.x {
        Ordering::Greater
    } else if a.y < b.y {
        Ordering::Less
    } else if a.y > b.y {
        Ordering::Greater
    } else {
        Ordering::Equal
    }
}

/// Convex hull of a planar point set.
///
/// Returns the hull's vertices in counter-clockwise order, starting at the
/// lexicographically smallest point (least `x`, then least `y`), without
/// repeating the first vertex at the end. The hull is *strictly* convex: points
/// on the interior of a hull edge are not vertices, and every vertex is one of
/// the input points, bit for bit.
///
/// Degenerate inputs give short hulls: no points give an empty hull, a single
/// distinct point (possibly repeated) gives that point, and collinear points
/// give the two extreme points of the line they span.
///
/// Non-finite points have no place in a hull: the caller is expected to filter
/// or reject them (as [`fit_affine`](super::fit_affine) does). Here they are
/// skipped, so that the function never panics.
///
/// This allocates its result and a sorting buffer; repeated callers should use
/// [`convex_hull_2d_into`].
///
/// # Algorithm
///
/// Andrew's monotone chain: sort the points, then build the lower and upper
/// chains in one sweep each, popping a vertex whenever it does not make a
/// strict left turn. The turn test is Shewchuk's adaptive exact `orient2d`, so
/// the result is the exact hull of the (finite) input points, with no
/// tolerance involved. `O(n log n)` time for `n` points, `O(n)` memory.
#[must_use]
pub fn convex_hull_2d(points: &[DVec2]) -> Vec<DVec2> {
    let mut sorted = Vec::with_capacity(points.len());
    let mut hull = Vec::new();
    convex_hull_2d_into(points, &mut sorted, &mut hull);
    hull
}

/// Inputs larger than this are first thinned by the Akl–Toussaint heuristic.
const AKL_TOUSSAINT_MIN_POINTS: usize = 64;

/// Points per block of the thinning: a block whose bounding box lies inside
/// the octagon is dropped whole. Input points that are neighbours in order
/// (a readback's samples, row by row) tend to be neighbours in the plane, so
/// many blocks are small and far inside.
const BLOCK: usize = 16;

/// `(min, max)` of `x` and of `y` over `points` (their bounding box) and the
/// sum of the `x + y`: not finite when a point is not (or, harmlessly, when
/// the sum overflows).
#[inline]
fn block_box(points: &[DVec2]) -> (DVec2, DVec2, f64) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    let mut sum = [0.0; 2];
    for p in points {
        let keys = [p.x, p.y];
        for k in 0..2 {
            sum[k] += keys[k];
            // Selects, not `f64::min`: one `minpd` for both keys.
            lo[k] = if keys[k] < lo[k] { keys[k] } else { lo[k] };
            hi[k] = if keys[k] > hi[k] { keys[k] } else { hi[k] };
        }
    }
    (DVec2::from(lo), DVec2::from(hi), sum[0] + sum[1])
}

/// The greatest `key` over `points` and the first block of [`BLOCK`] points
/// that holds it, reading only the blocks whose `bound` (of the block's box
/// in `boxes`, at least `key` of every point in the box) reaches the
/// greatest `key` of the block with the greatest bound: no other block can
/// hold the greatest. The same value and block as reading every block in
/// order; `None` when no point's key is above `-∞` (or a key is NaN).
fn first_greatest(
    points: &[DVec2],
    boxes: &[DVec2],
    key: impl Fn(DVec2) -> f64,
    bound: impl Fn(DVec2, DVec2) -> f64,
) -> Option<(f64, usize)> {
    let block_max = |b: usize| {
        let block = &points[b * BLOCK..((b + 1) * BLOCK).min(points.len())];
        block.iter().fold(f64::NEG_INFINITY, |m, &p| if key(p) > m { key(p) } else { m })
    };
    let (mut top, mut top_block) = (f64::NEG_INFINITY, 0);
    for (b, bounds) in boxes.chunks_exact(2).enumerate() {
        let u = bound(bounds[0], bounds[1]);
        if u > top {
            (top, top_block) = (u, b);
        }
    }
    let floor = block_max(top_block);
    let (mut best, mut best_block) = (f64::NEG_INFINITY, None);
    for (b, bounds) in boxes.chunks_exact(2).enumerate() {
        if bound(bounds[0], bounds[1]) >= floor {
            let m = block_max(b);
            if m > best {
                (best, best_block) = (m, Some(b));
            }
        }
    }
    best_block.map(|b| (best, b))
}

/// Akl–Toussaint, then quickhull's first steps: appends to `kept` (in no
/// particular order) the points of `points` that may be hull vertices and
/// returns `true`; or returns `false`, appending nothing, when a point may
/// not be finite. A point is dropped only when plain floating-point
/// orientation tests put it inside every edge of a polygon or triangle whose
/// corners are input points by a margin far above their rounding error (it
/// is then strictly inside the hull), so hull vertices are never dropped.
///
/// First the octagon spanned by the extreme points in x, y, x + y and x − y,
/// in two linear passes. Its inside test runs per block of [`BLOCK`] points
/// first: the corner of the block's bounding box lowest on each edge's
/// inside function decides for the whole block (the box is convex and the
/// test affine), and only the edges that corner fails are tested per point.
/// The first pass leaves the blocks' boxes in `boxes` (`min`, `max` per
/// block). Then the octagon's survivors, in the caps outside its edges,
/// go through [`refine_caps`]: on a readback's samples the octagon leaves
/// a few to a few dozen percent, the caps' triangles a few dozen points.
fn keep_possible_vertices(points: &[DVec2], boxes: &mut Vec<DVec2>, kept: &mut Vec<DVec2>) -> bool {
    // The extremes of the four keys and the first block that reaches each:
    // `x` and `y` from every block's box, `x ± y` from the few blocks whose
    // box may hold them (the bounds are the keys of the box's corners:
    // rounding is monotone, so no point's key passes its box's).
    let mut lo = [f64::INFINITY; 4];
    let mut hi = [f64::NEG_INFINITY; 4];
    let (mut lo_block, mut hi_block) = ([0; 4], [0; 4]);
    let mut sum = 0.0;
    boxes.clear();
    boxes.reserve(2 * points.len().div_ceil(BLOCK));
    for (b, block) in points.chunks(BLOCK).enumerate() {
        let (block_lo, block_hi, block_sum) = block_box(block);
        sum += block_sum;
        boxes.push(block_lo);
        boxes.push(block_hi);
        for k in 0..2 {
            if block_lo[k] < lo[k] {
                lo[k] = block_lo[k];
                lo_block[k] = b;
            }
            if block_hi[k] > hi[k] {
                hi[k] = block_hi[k];
                hi_block[k] = b;
            }
        }
    }
    if !sum.is_finite() {
        return false;
    }
    // The least `x ± y` as the greatest `−(x ± y)`: negation is exact.
    let diagonals = [
        first_greatest(points, boxes, |p| p.x + p.y, |_, h| h.x + h.y).map(|(v, b)| (2, false, v, b)),
        first_greatest(points, boxes, |p| -(p.x + p.y), |l, _| -(l.x + l.y)).map(|(v, b)| (2, true, -v, b)),
        first_greatest(points, boxes, |p| p.x - p.y, |l, h| h.x - l.y).map(|(v, b)| (3, false, v, b)),
        first_greatest(points, boxes, |p| -(p.x - p.y), |l, h| -(l.x - h.y)).map(|(v, b)| (3, true, -v, b)),
    ];
    for diagonal in diagonals {
        // Finite points have finite keys unless a sum overflows: then
        // thin nothing.
        let Some((k, least, value, block)) = diagonal else {
            return false;
        };
        if least {
            (lo[k], lo_block[k]) = (value, block);
        } else {
            (hi[k], hi_block[k]) = (value, block);
        }
    }
    // The first point of that block with the extreme value (the same
    // expressions as `block_box` and `first_greatest`, so the same bits).
    let key = |p: &DVec2, k: usize| [p.x, p.y, p.x + p.y, p.x - p.y][k];
    let corner = |block: usize, k: usize, value: f64| {
        let block = &points[block * BLOCK..((block + 1) * BLOCK).min(points.len())];
        block.iter().copied().find(|p| key(p, k) == value).unwrap_or(block[0])
    };
    // Counter-clockwise: bottom (min y), bottom-right (max x − y), right
    // (max x), top-right (max x + y), top (max y), top-left (min x − y),
    // left (min x), bottom-left (min x + y).
    let octagon = [
        corner(lo_block[1], 1, lo[1]),
        corner(hi_block[3], 3, hi[3]),
        corner(hi_block[0], 0, hi[0]),
        corner(hi_block[2], 2, hi[2]),
        corner(hi_block[1], 1, hi[1]),
        corner(lo_block[3], 3, lo[3]),
        corner(lo_block[0], 0, lo[0]),
        corner(lo_block[2], 2, lo[2]),
    ];
    // At most eight corners: kept in an array, so the pass allocates nothing.
    let mut corners = [DVec2::ZERO; 8];
    let mut n = 0;
    for p in octagon {
        if n == 0 || (corners[n - 1] != p && corners[0] != p) {
            corners[n] = p;
            n += 1;
        }
    }
    if n < 3 {
        kept.extend_from_slice(points);
        return true;
    }
    // Each edge `a → b` as the line `dx·y − dy·x − c` (positive inside),
    // with a margin above its rounding error ([`Edge`]). Points are far
    // from the origin compared with their spread only when the spread is
    // tiny; then fewer are dropped, never a vertex. The blocks' box corners
    // are made of the points' coordinates, so the same bound holds for them.
    let scale = lo[0].abs().max(hi[0].abs()).max(lo[1].abs()).max(hi[1].abs());
    let mut lines = [Edge::default(); 8];
    for (i, line) in lines[..n].iter_mut().enumerate() {
        *line = Edge::new(corners[i], corners[(i + 1) % n], scale);
    }
    let lines = &lines[..n];
    let start = kept.len();
    // The open edges of a block, with their indices; the survivors per
    // edge they first fail (the caps' sizes, for their order below).
    let mut open = [(Edge::default(), 0); 8];
    let mut sizes = [0usize; 8];
    for (block, bounds) in points.chunks(BLOCK).zip(boxes.chunks_exact(2)) {
        let (block_lo, block_hi) = (bounds[0], bounds[1]);
        // The edges whose inside the block's box is not in: the box's corner
        // lowest on the edge's inside function decides.
        let mut m = 0;
        for (i, line) in lines.iter().enumerate() {
            let x = if line.dy >= 0.0 { block_hi.x } else { block_lo.x };
            let y = if line.dx >= 0.0 { block_lo.y } else { block_hi.y };
            if !line.inside(DVec2::new(x, y)) {
                open[m] = (*line, i);
                m += 1;
            }
        }
        if m == 0 {
            continue;
        }
        let open = &open[..m];
        for &p in block {
            if let Some(&(_, i)) = open.iter().find(|(line, _)| !line.inside(p)) {
                kept.push(p);
                sizes[i] += 1;
            }
        }
    }
    // The largest caps first: each cap's partition reads the points no
    // earlier cap took.
    let mut order = [0, 1, 2, 3, 4, 5, 6, 7];
    let order = &mut order[..n];
    order.sort_unstable_by_key(|&i| core::cmp::Reverse(sizes[i]));
    let survivors = refine_caps(&corners[..n], lines, order, &mut kept[start..], scale);
    kept.truncate(start + survivors);
    true
}

/// The line through two input points `a → b` as `dx·y − dy·x − c`
/// (positive left of it), with a margin above the rounding error of that
/// expression: every term is at most `(|dx| + |dy|)·scale` when `scale`
/// bounds the absolute coordinates of `a`, `b` and the point tested, and
/// the few roundings of the test, of `c` and of `b − a` each err by an
/// `f64::EPSILON` of that, so `1e-12` of it is thousands of times the
/// error; `f64::MIN_POSITIVE` more covers products that underflow (their
/// error is absolute, at most a subnormal's ulp each). A value above the
/// margin means the point is strictly left of the exact line; an overflow
/// makes the value or the margin infinite or NaN, and then the test fails
/// (the point is kept).
#[derive(Clone, Copy, Default)]
struct Edge {
    dx: f64,
    dy: f64,
    c: f64,
    margin: f64,
}

impl Edge {
    #[inline]
    fn new(a: DVec2, b: DVec2, scale: f64) -> Self {
        let d = b - a;
        let margin = 1e-12 * (d.x.abs() + d.y.abs()) * scale + f64::MIN_POSITIVE;
        Self { dx: d.x, dy: d.y, c: d.x * a.y - d.y * a.x, margin }
    }

    #[inline]
    fn value(&self, p: DVec2) -> f64 {
        self.dx * p.y - self.dy * p.x - self.c
    }

    /// `p` strictly left of the line, by more than the margin.
    #[inline]
    fn inside(&self, p: DVec2) -> bool {
        self.value(p) > self.margin
    }

    /// `p` strictly right of the line, by more than the margin.
    #[inline]
    fn outside(&self, p: DVec2) -> bool {
        self.value(p) < -self.margin
    }
}

/// Levels of [`refine_cap`]'s recursion at most: past it a cap's points are
/// all kept. Each level splits a cap in two; 24 is far more than the
/// survivors of real inputs need (a few), and bounds the stack.
const CAP_DEPTH: u32 = 24;

/// The octagon's survivors thinned again: each goes to the cap of the first
/// edge of `corners` (a convex polygon of input points, counter-clockwise,
/// `lines` its edges), in the edges' `order`, that it is not strictly
/// inside, and [`refine_cap`] drops what it can there. Moves the points that
/// may be hull vertices to the front of `points` and returns their count; a
/// point inside every edge (none: each survivor failed one) is kept.
fn refine_caps(corners: &[DVec2], lines: &[Edge], order: &[usize], points: &mut [DVec2], scale: f64) -> usize {
    let (mut out, mut start) = (0, 0);
    for &i in order {
        // This edge's cap: the points not strictly inside it, to the front
        // of the points no cap has taken yet.
        let line = lines[i];
        let mut end = start;
        for j in start..points.len() {
            if !line.inside(points[j]) {
                points.swap(j, end);
                end += 1;
            }
        }
        let kept = refine_cap(corners[i], corners[(i + 1) % corners.len()], &mut points[start..end], scale, CAP_DEPTH);
        points.copy_within(start..start + kept, out);
        out += kept;
        start = end;
    }
    let rest = points.len() - start;
    points.copy_within(start.., out);
    out + rest
}

/// One step of quickhull on `points`, input points none of which is
/// strictly inside the edge `a → b` (`a`, `b` input points too): the point
/// `c` farthest outside the edge (the least value of [`Edge::value`])
/// makes the triangle `a, c, b` of input points; a point strictly inside
/// it by the margin on all three edges is strictly inside the hull, so not
/// a vertex, and is dropped. The points not strictly inside `a → c` and
/// those not strictly inside `c → b` are thinned the same way against those
/// edges (`depth` levels more at most). Moves the points that may be hull
/// vertices to the front and returns their count; keeps them all when no
/// point is outside `a → b` by more than the margin.
///
/// Only ever drops points strictly inside a triangle of input points,
/// whatever `c` rounding picked: correct for any input, effective when the
/// caps are thin.
fn refine_cap(a: DVec2, b: DVec2, points: &mut [DVec2], scale: f64, depth: u32) -> usize {
    let n = points.len();
    if n <= 1 || depth == 0 {
        return n;
    }
    let ab = Edge::new(a, b, scale);
    let (mut far, mut least) = (0, ab.value(points[0]));
    for (i, &p) in points.iter().enumerate().skip(1) {
        let v = ab.value(p);
        if v < least {
            (far, least) = (i, v);
        }
    }
    if !(least < -ab.margin) {
        return n;
    }
    let c = points[far];
    let (ac, cb) = (Edge::new(a, c, scale), Edge::new(c, b, scale));
    // [not inside a → c | not inside c → b | the rest kept], the points
    // strictly inside the triangle after them.
    let mut left = 0;
    for i in 0..n {
        if !ac.inside(points[i]) {
            points.swap(i, left);
            left += 1;
        }
    }
    let mut right = left;
    for i in left..n {
        if !cb.inside(points[i]) {
            points.swap(i, right);
            right += 1;
        }
    }
    let mut kept = right;
    for i in right..n {
        if !ab.outside(points[i]) {
            points.swap(i, kept);
            kept += 1;
        }
    }
    let l = refine_cap(a, c, &mut points[..left], scale, depth - 1);
    let r = refine_cap(c, b, &mut points[left..right], scale, depth - 1);
    points.copy_within(left..left + r, l);
    points.copy_within(right..kept, l + r);
    l + r + (kept - right)
}

/// Allocation-free form of [`convex_hull_2d`].
///
/// Writes the hull of `points` to `hull`, replacing its contents. `scratch` is
/// a working buffer whose contents on entry are ignored and on return are
/// unspecified (currently the sorted, deduplicated finite points that may be
/// vertices). Once both buffers have grown to fit the largest input, repeated
/// calls do not allocate.
///
/// Output order, degenerate cases and the handling of non-finite points are
/// those of [`convex_hull_2d`].
///
/// # Algorithm
///
/// Andrew's monotone chain with exact orientation tests; `O(n log n)` time for
/// `n` points. Finite inputs of more than 64 points are first thinned in
/// `O(n)` by the Akl–Toussaint heuristic, block by block (on pixel-grid
/// samples it leaves a few percent). See [`convex_hull_2d`].
pub fn convex_hull_2d_into(points: &[DVec2], scratch: &mut Vec<DVec2>, hull: &mut Vec<DVec2>) {
    hull_into(points, false, scratch, hull);
}

/// [`convex_hull_2d_into`] of points the caller has found all finite (the
/// affine fit rejects any other input first): they are copied as they are,
/// with no test each. The same hull.
pub(crate) fn convex_hull_of_finite_into(points: &[DVec2], scratch: &mut Vec<DVec2>, hull: &mut Vec<DVec2>) {
    debug_assert!(points.iter().all(|p| p.is_finite()));
    hull_into(points, true, scratch, hull);
}

fn hull_into(points: &[DVec2], all_finite: bool, scratch: &mut Vec<DVec2>, hull: &mut Vec<DVec2>) {
    scratch.clear();
    // `hull` holds the thinning's block boxes until the chain overwrites it.
    if points.len() <= AKL_TOUSSAINT_MIN_POINTS || !keep_possible_vertices(points, hull, scratch) {
        if all_finite {
            scratch.extend_from_slice(points);
        } else {
            scratch.extend(points.iter().copied().filter(|p| p.is_finite()));
        }
    }
    scratch.sort_unstable_by(lexicographic);
    scratch.dedup();
    chain(scratch, hull);
}

/// [`convex_hull_2d_into`] of points expected to be the vertices of a
/// strictly convex polygon in order (either orientation, any first vertex),
/// such as the vertices of an earlier hull seen through a projective map
/// that keeps them all on one side of its vanishing line: when they are,
/// writes them counter-clockwise from the lexicographically smallest, with
/// no sort; when they only rise once and fall once in lexicographic order
/// (rounding made a few nearly collinear vertices turn the wrong way),
/// merges the two runs into the sorted order and runs the monotone chain
/// on it, again with no sort; otherwise runs [`convex_hull_2d_into`]. The
/// same hull, bit for bit, in every case.
///
/// The check is exact: every consecutive triple turns strictly the same
/// way (the chain's exact `orient`), and the points rise strictly in
/// lexicographic order from the smallest to the largest and fall back,
/// once around. A closed polygon whose turns are all strictly left winds
/// around as many times as its `x` (then `y`) rises and falls, so once
/// means a strictly convex polygon: all its vertices, and nothing else, are
/// the hull's, which the monotone chain lists counter-clockwise from the
/// smallest (its lower chain is the rising run, its upper one the falling
/// run). Collinear vertices take the merged runs; non-finite points and
/// neighbours or two points that compare equal take the general path.
pub(crate) fn convex_hull_of_polygon_into(points: &[DVec2], scratch: &mut Vec<DVec2>, hull: &mut Vec<DVec2>) {
    let Some((first, turns)) = polygon_order(points) else {
        convex_hull_2d_into(points, scratch, hull);
        return;
    };
    hull.clear();
    match turns {
        Some(true) => {
            hull.extend_from_slice(&points[first..]);
            hull.extend_from_slice(&points[..first]);
        }
        Some(false) => {
            hull.extend(points[..=first].iter().rev());
            hull.extend(points[first + 1..].iter().rev());
        }
        None => {
            // Not strictly convex, but rising once and falling once: the
            // two runs merged are the sorted order (no two points compare
            // equal), so the chain needs no sort.
            if merge_runs(points, first, scratch) {
                chain(scratch, hull);
            } else {
                convex_hull_2d_into(points, scratch, hull);
            }
        }
    }
}

/// When `points` (at least three, finite, no two neighbours equal) rise
/// strictly in lexicographic order from their smallest point to their
/// largest and fall back, once around: the index of the smallest, and
/// `Some(counter_clockwise)` when every consecutive triple also turns
/// strictly the same way (a strictly convex polygon, see
/// [`convex_hull_of_polygon_into`]), else `None`.
fn polygon_order(points: &[DVec2]) -> Option<(usize, Option<bool>)> {
    let n = points.len();
    if n < 3 || !points.iter().all(|p| p.is_finite()) {
        return None;
    }
    let (mut a, mut b) = (points[n - 1], points[0]);
    let left = orient(a, b, points[1]) > 0.0;
    let mut convex = true;
    let mut first = None;
    let mut before = lexicographic(&a, &b);
    for i in 0..n {
        let c = points[if i + 1 == n { 0 } else { i + 1 }];
        let after = lexicographic(&b, &c);
        // The one vertex where the falling run turns into the rising one
        // is the smallest.
        match (before, after) {
            (Ordering::Equal, _) | (_, Ordering::Equal) => return None,
            (Ordering::Greater, Ordering::Less) if first.is_none() => first = Some(i),
            (Ordering::Greater, Ordering::Less) => return None,
            _ => {}
        }
        if convex {
            let turn = orient(a, b, c);
            convex = if left { turn > 0.0 } else { turn < 0.0 };
        }
        (a, b, before) = (b, c, after);
    }
    Some((first?, convex.then_some(left)))
}

/// Writes to `sorted` the points in lexicographic order by merging the run
/// rising from `first` with the falling one read backwards; `false` when
/// two points compare equal (their order after a sort is unspecified).
fn merge_runs(points: &[DVec2], first: usize, sorted: &mut Vec<DVec2>) -> bool {
    let n = points.len();
    let at = |k: usize| points[(first + k) % n];
    // Rising: at(0), at(1), …, at(last); falling read backwards: at(n − 1), …, at(last + 1).
    let mut last = 0;
    while last + 1 < n && lexicographic(&at(last), &at(last + 1)) == Ordering::Less {
        last += 1;
    }
    sorted.clear();
    let (mut i, mut j) = (0, n);
    while i <= last || j > last + 1 {
        let take_rising = if i > last {
            false
        } else if j == last + 1 {
            true
        } else {
            match lexicographic(&at(i), &at(j - 1)) {
                Ordering::Less => true,
                Ordering::Greater => false,
                Ordering::Equal => return false,
            }
        };
        if take_rising {
            sorted.push(at(i));
            i += 1;
        } else {
            sorted.push(at(j - 1));
            j -= 1;
        }
    }
    true
}

/// Andrew's monotone chain over points sorted lexicographically and deduplicated.
fn chain(scratch: &[DVec2], hull: &mut Vec<DVec2>) {
    hull.clear();
    if scratch.len() <= 2 {
        // Zero, one or two distinct points: already their own hull, and two
        // points in lexicographic order are a valid (degenerate) CCW polygon.
        hull.extend_from_slice(scratch);
        return;
    }

    // A hull vertex must make a strict left turn with its neighbours; anything
    // that turns right or goes straight on is popped.
    let turns_left = |hull: &[DVec2], p: DVec2| orient(hull[hull.len() - 2], hull[hull.len() - 1], p) > 0.0;

    // Lower chain, left to right.
    for &p in scratch.iter() {
        while hull.len() >= 2 && !turns_left(hull, p) {
            hull.pop();
        }
        hull.push(p);
    }

    // Upper chain, right to left. The last point of the lower chain (the
    // rightmost point) stays; the upper chain may pop only its own vertices.
    let lower_len = hull.len();
    for &p in scratch.iter().rev().skip(1) {
        while hull.len() > lower_len && !turns_left(hull, p) {
            hull.pop();
        }
        hull.push(p);
    }

    // The upper chain ends at the first (leftmost) point, which is already the
    // hull's first vertex.
    hull.pop();
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Akl–Toussaint thinning never changes the hull: compare with the
    /// plain monotone chain on large inputs of several shapes.
    #[test]
    fn thinning_keeps_the_hull() {
        let mut next = crate::test_rng::unit(0x9E37_79B9_7F4A_7C15_u64);
        for case in 0..300 {
            let n = 65 + case * 23;
            let points: Vec<DVec2> = (0..n)
                .map(|k| match case % 10 {
                    0 => v(next(), next()),
                    1 => {
                        let a = next() * std::f64::consts::TAU;
                        v(a.cos(), a.sin()) * if k % 3 == 0 { 1.0 } else { next() }
                    }
                    2 => v((next() * 20.0).floor(), (next() * 20.0).floor()),
                    3 => v(next() * 1e6, next() * 1e-6),
                    // Far from the origin for their spread: the margin
                    // scales with the coordinates.
                    4 => v(1e7 + next(), -3e6 + next() * 1e-3),
                    // On the circle and an ulp or two inside it.
                    5 => {
                        let a = next() * std::f64::consts::TAU;
                        v(a.cos(), a.sin()) * (1.0 - f64::EPSILON * (k % 3) as f64)
                    }
                    // A readback's pixels in row order through a perspective
                    // map (the thinning's blocks are runs of a row), the
                    // last row cut short.
                    7 => {
                        let (px, py) = ((k % 37) as f64, (k / 37) as f64);
                        let w = 1.0 + 0.01 * px + 0.03 * py;
                        v((px + 0.2 * py) / w, (py - 0.1 * px) / w)
                    }
                    // Non-finite points among finite ones: skipped.
                    8 => match k % 11 {
                        3 => v(f64::NAN, next()),
                        7 => v(next(), f64::INFINITY),
                        _ => v(next(), next() * 3.0),
                    },
                    // Along a square's edges, a hair outside or inside
                    // (near-hull points right at the thinning octagon's edges).
                    _ => {
                        let (t, hair) = (next(), (next() - 0.5) * 1e-13);
                        match k % 4 {
                            0 => v(t, -hair),
                            1 => v(1.0 + hair, t),
                            2 => v(t, 1.0 + hair),
                            _ => v(-hair, t),
                        }
                    }
                })
                .collect();
            let mut plain: Vec<DVec2> = points.iter().copied().filter(|p| p.is_finite()).collect();
            plain.sort_unstable_by(lexicographic);
            plain.dedup();
            let mut expected = Vec::new();
            // Monotone chain without thinning.
            chain(&plain, &mut expected);
            assert_eq!(convex_hull_2d(&points), expected, "case {case}");
        }
    }

    /// Point sets of many shapes, at many scales: the thinning (octagon and
    /// caps) keeps every hull vertex and drops only points strictly inside
    /// the hull (checked with the exact `orient` against the unthinned
    /// chain's hull), and the hull is the unthinned one bit for bit.
    #[test]
    fn thinning_drops_only_interior_points() {
        let mut next = crate::test_rng::unit(0x2545_F491_4F6C_DD1D_u64);
        let mut dropped_total = 0;
        for case in 0..700 {
            let n = 65 + (next() * 2500.0) as usize;
            let shape = case % 10;
            let w = 8 + case % 41;
            let tilt = next() * 0.05;
            let mut points: Vec<DVec2> = (0..n)
                .map(|k| match shape {
                    // Integer grid: long collinear runs on the octagon's edges.
                    0 => v((k % w) as f64, (k / w) as f64),
                    // A grid's points with x + y and x − y bounded: an
                    // octagon of integer corners, its edges full of points.
                    1 => {
                        let (x, y) = ((k % 31) as f64 - 15.0, ((k / 31) % 31) as f64 - 15.0);
                        if x.abs() + y.abs() <= 21.0 {
                            v(x, y)
                        } else {
                            v(x * 0.5, y * 0.5)
                        }
                    }
                    // A readback's pixels through a perspective map, rows
                    // of `w`.
                    2 => {
                        let (px, py) = ((k % w) as f64, (k / w) as f64);
                        let q = 1.0 + tilt * px + 0.02 * py;
                        v((px + 0.3 * py) / q, (py - 0.1 * px) / q)
                    }
                    // On a circle (all vertices) and just inside.
                    3 => {
                        let a = next() * std::f64::consts::TAU;
                        v(a.cos(), a.sin()) * if k % 2 == 0 { 1.0 } else { 1.0 - f64::EPSILON * (k % 5) as f64 }
                    }
                    // Random in a thin rotated ellipse.
                    4 => {
                        let (a, r) = (next() * std::f64::consts::TAU, next().sqrt());
                        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
                        let (x, y) = (r * a.cos() * 100.0, r * a.sin() * 0.01);
                        v(c * x - s * y, s * x + c * y)
                    }
                    // Each point two or three times, from a small set.
                    5 => {
                        let j = (k / 3) % 40;
                        v((j % 7) as f64 * 0.25, (j / 7) as f64 * 0.5)
                    }
                    // Collinear: every point on one line.
                    6 => v(k as f64 * 3.0, k as f64 * -2.0),
                    // A square's edges, a hair inside or outside.
                    7 => {
                        let (t, hair) = (next(), (next() - 0.5) * 1e-13);
                        match k % 4 {
                            0 => v(t, -hair),
                            1 => v(1.0 + hair, t),
                            2 => v(t, 1.0 + hair),
                            _ => v(-hair, t),
                        }
                    }
                    // A polygon's vertices with points on its edges
                    // (exactly: dyadic steps) and inside.
                    8 => {
                        let corners =
                            [v(0.0, 0.0), v(8.0, 0.0), v(12.0, 4.0), v(12.0, 8.0), v(4.0, 12.0), v(-4.0, 4.0)];
                        let (i, t) = (k % 6, ((k / 6) % 16) as f64 / 16.0);
                        let (a, b) = (corners[i], corners[(i + 1) % 6]);
                        if k % 3 == 0 {
                            v(4.0, 5.0) + (a - v(4.0, 5.0)) * t
                        } else {
                            a + (b - a) * t
                        }
                    }
                    // Random in a square.
                    _ => v(next(), next()),
                })
                .collect();
            // Scales from tiny (products subnormal or zero) to huge
            // (products overflow), and far from the origin.
            let scale = [1.0, 1e-160, 1e-300, 1e150, 1e300, 3.0][case % 6];
            let offset = if case % 7 == 3 { v(1e9, -2e9) } else { v(0.0, 0.0) };
            for p in &mut points {
                // `+ 0.0`: no −0.0 (it ties with 0.0 in the sort).
                *p = *p * scale + offset + v(0.0, 0.0);
            }
            if case % 4 == 1 {
                // Not in the readback's order.
                for i in (1..points.len()).rev() {
                    points.swap(i, (next() * (i + 1) as f64) as usize % (i + 1));
                }
            }
            let mut plain: Vec<DVec2> = points.clone();
            plain.sort_unstable_by(lexicographic);
            plain.dedup();
            let mut expected = Vec::new();
            chain(&plain, &mut expected);
            let (mut boxes, mut kept) = (Vec::new(), Vec::new());
            let thinned = keep_possible_vertices(&points, &mut boxes, &mut kept);
            let context = format!("case {case}, shape {shape}, scale {scale:e}, {n} points");
            if thinned {
                for q in &expected {
                    assert!(
                        kept.iter().any(|k| k.x.to_bits() == q.x.to_bits() && k.y.to_bits() == q.y.to_bits()),
                        "{context}: vertex {q} dropped"
                    );
                }
                let m = expected.len();
                for p in &points {
                    if !kept.contains(p) {
                        dropped_total += 1;
                        assert!(m >= 3, "{context}: {p} dropped from a degenerate hull");
                        for i in 0..m {
                            assert!(
                                orient(expected[i], expected[(i + 1) % m], *p) > 0.0,
                                "{context}: dropped {p} not strictly inside"
                            );
                        }
                    }
                }
            }
            let hull = convex_hull_2d(&points);
            assert_eq!(hull.len(), expected.len(), "{context}");
            for (a, b) in hull.iter().zip(&expected) {
                assert_eq!((a.x.to_bits(), a.y.to_bits()), (b.x.to_bits(), b.y.to_bits()), "{context}");
            }
        }
        // The thinning did drop points (else the checks above check nothing).
        assert!(dropped_total > 100_000, "{dropped_total}");
    }

    /// The caps thin a readback-like grid and a random disk to a few dozen
    /// points, where the octagon alone leaves far more.
    #[test]
    fn caps_leave_few_points() {
        let mut next = crate::test_rng::unit(0x1234_5678_9ABC_DEF1_u64);
        // A disk of pixels through a perspective map (its edge pixels are
        // not collinear, unlike a rectangle's rows).
        let grid: Vec<DVec2> = (0..200 * 200)
            .filter_map(|k| {
                let (px, py) = ((k % 200) as f64 - 100.0, (k / 200) as f64 - 100.0);
                let q = 3.0 + 0.004 * px + 0.01 * py;
                (px * px + py * py < 95.0 * 95.0).then(|| v((px + 0.3 * py) / q, (py - 0.1 * px) / q))
            })
            .collect();
        let disk: Vec<DVec2> = (0..20_000)
            .map(|_| {
                let (a, r) = (next() * std::f64::consts::TAU, next().sqrt());
                v(a.cos(), a.sin()) * r
            })
            .collect();
        for (name, points, at_most) in [("grid", &grid, 600), ("disk", &disk, 400)] {
            let (mut boxes, mut kept) = (Vec::new(), Vec::new());
            assert!(keep_possible_vertices(points, &mut boxes, &mut kept));
            eprintln!("{name}: {} of {} kept", kept.len(), points.len());
            assert!(kept.len() <= at_most, "{name}: {} kept", kept.len());
        }
    }

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    /// Points in polygon order give `convex_hull_2d`'s hull bit for bit:
    /// convex polygons in either orientation from any vertex (the path
    /// without a sort), with collinear, near-collinear or dented vertices
    /// (the merged runs), and orders that wind twice, repeat a point or are
    /// not finite (the general path).
    #[test]
    fn polygon_order_gives_the_hull() {
        let mut next = crate::test_rng::unit(0x5851_F42D_4C95_7F2D_u64);
        let mut paths = [0; 3];
        for case in 0..3000 {
            let n = 3 + case % 40;
            let mut angles: Vec<f64> = (0..n).map(|_| next() * std::f64::consts::TAU).collect();
            angles.sort_by(f64::total_cmp);
            let (cx, cy, r) = (next() * 10.0 - 5.0, next() * 10.0 - 5.0, 0.1 + next() * 1e3);
            let mut points: Vec<DVec2> = angles.iter().map(|a| v(cx + r * a.cos(), cy + r * a.sin())).collect();
            match case % 9 {
                // A midpoint of an edge (collinear, or a rounding off it).
                1 if n > 3 => {
                    let m = (points[1] + points[2]) * 0.5;
                    points.insert(2, m);
                }
                // A vertex pulled inside (a dent).
                2 => points[n / 2] = v(cx, cy) + (points[n / 2] - v(cx, cy)) * 0.5,
                // Twice around.
                3 => points = points.iter().chain(points.iter()).map(|p| *p + v(next() * 1e-3, 0.0)).collect(),
                // A repeated point.
                4 => points.push(points[0]),
                // Not finite.
                5 => points[n / 3] = v(f64::NAN, 0.0),
                // A pixel-grid line: exactly collinear runs.
                6 => {
                    points = (0..n).map(|k| v(k as f64, 0.0)).chain((1..n).map(|k| v((n - k) as f64, 1.0))).collect();
                }
                _ => {}
            }
            if case % 2 == 1 {
                points.reverse();
            }
            let start = case % points.len();
            points.rotate_left(start);
            let expected = convex_hull_2d(&points);
            let (mut scratch, mut hull) = (Vec::new(), vec![v(7.0, 7.0)]);
            convex_hull_of_polygon_into(&points, &mut scratch, &mut hull);
            assert_eq!(hull.len(), expected.len(), "case {case}");
            for (a, b) in hull.iter().zip(&expected) {
                assert_eq!((a.x.to_bits(), a.y.to_bits()), (b.x.to_bits(), b.y.to_bits()), "case {case}");
            }
            paths[match polygon_order(&points) {
                Some((_, Some(_))) => 0,
                Some((_, None)) => 1,
                None => 2,
            }] += 1;
        }
        // Every path is taken often.
        assert!(paths.iter().all(|&count| count > 200), "{paths:?}");
    }

    #[test]
    fn empty_single_and_pair() {
        assert!(convex_hull_2d(&[]).is_empty());
        assert_eq!(convex_hull_2d(&[v(1.0, 2.0)]), vec![v(1.0, 2.0)]);
        assert_eq!(convex_hull_2d(&[v(1.0, 2.0), v(1.0, 2.0), v(1.0, 2.0)]), vec![v(1.0, 2.0)]);
        assert_eq!(convex_hull_2d(&[v(3.0, 0.0), v(1.0, 2.0)]), vec![v(1.0, 2.0), v(3.0, 0.0)]);
    }

    #[test]
    fn square_with_interior_edge_and_duplicate_points() {
        let points = [
            v(1.0, 1.0),
            v(0.0, 0.0),
            v(0.5, 0.0),
            v(1.0, 0.0),
            v(0.5, 0.5),
            v(0.0, 1.0),
            v(1.0, 0.5),
            v(0.0, 0.0),
            v(1.0, 1.0),
        ];
        assert_eq!(convex_hull_2d(&points), vec![v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)]);
    }

    #[test]
    fn collinear_points_give_the_extremes() {
        let points: Vec<_> = (0..10).map(|i| v(f64::from(i), 2.0 * f64::from(i))).collect();
        assert_eq!(convex_hull_2d(&points), vec![v(0.0, 0.0), v(9.0, 18.0)]);
        let vertical = [v(0.0, 3.0), v(0.0, -1.0), v(-0.0, 2.0), v(0.0, 0.0)];
        assert_eq!(convex_hull_2d(&vertical), vec![v(0.0, -1.0), v(0.0, 3.0)]);
    }

    #[test]
    fn nearly_collinear_points_are_decided_exactly() {
        // The middle point lies below the chord by far less than the rounding
        // error of a naive cross product at this magnitude.
        let a = v(1.0e6, 1.0e6);
        let b = v(1.0e6 + 3.0, 1.0e6 + 3.0);
        let below = v(1.0e6 + 1.0, 1.0e6 + 1.0 - 1.0e-10);
        let hull = convex_hull_2d(&[a, b, below]);
        assert_eq!(hull, vec![a, below, b]);
        let on = v(1.0e6 + 1.0, 1.0e6 + 1.0);
        assert_eq!(convex_hull_2d(&[a, b, on]), vec![a, b]);
    }

    #[test]
    fn non_finite_points_are_skipped() {
        let points =
            [v(f64::NAN, 0.0), v(0.0, 0.0), v(f64::INFINITY, 1.0), v(1.0, 0.0), v(0.0, f64::NEG_INFINITY), v(0.0, 1.0)];
        assert_eq!(convex_hull_2d(&points), vec![v(0.0, 0.0), v(1.0, 0.0), v(0.0, 1.0)]);
        assert!(convex_hull_2d(&[v(f64::NAN, f64::NAN)]).is_empty());
    }

    #[test]
    fn buffers_are_reused_and_overwritten() {
        let mut scratch = vec![v(9.0, 9.0); 3];
        let mut hull = vec![v(7.0, 7.0); 5];
        let triangle = [v(0.0, 0.0), v(2.0, 0.0), v(0.0, 2.0), v(0.5, 0.5)];
        convex_hull_2d_into(&triangle, &mut scratch, &mut hull);
        assert_eq!(hull, vec![v(0.0, 0.0), v(2.0, 0.0), v(0.0, 2.0)]);
        convex_hull_2d_into(&[v(1.0, 1.0)], &mut scratch, &mut hull);
        assert_eq!(hull, vec![v(1.0, 1.0)]);
    }
}
