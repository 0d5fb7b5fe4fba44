//! The scene-optimized objective (math.md §3) and its analytic gradient with
//! respect to the optical axis `j`.
//!
//! A boundary sample carries its light coordinates `P = X~` (homogeneous, any
//! positive scale) and their derivatives `D₁, D₂` along the visible surface
//! with respect to full-resolution screen pixels. For `G = [g₁; g₂; j]` in
//! texel units, with `w = j·P`, `aᵢ = gᵢ·P`, `cᵢⱼ = gᵢ·Dⱼ` and `eⱼ = j·Dⱼ`,
//! the screen-to-texel Jacobian is
//!
//! ```text
//! Jᵢⱼ = cᵢⱼ / w − aᵢ eⱼ / w²
//! ```
//!
//! and the badness `b = ‖J⁻¹‖²_F = ‖J‖²_F / det(J)²`.

use glam::{DMat2, DMat3, DVec2, DVec3};

use crate::scene::ShadowMapSize;

/// One boundary sample in light coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundarySample {
    /// `X~` of the surface point (homogeneous; positive scale).
    pub light: DVec3,
    /// `∂X~/∂x₁` along the surface (full-resolution pixels).
    pub d_dx: DVec3,
    /// `∂X~/∂x₂` along the surface.
    pub d_dy: DVec3,
}

/// `G` rescaled from NDC to texels (the translation does not affect `J`).
#[must_use]
pub(crate) fn texel_homography(g_ndc: &DMat3, map: ShadowMapSize) -> DMat3 {
    let sx = 0.5 * f64::from(map.width);
    let sy = 0.5 * f64::from(map.height);
    DMat3::from_cols(g_ndc.row(0) * sx, g_ndc.row(1) * sy, g_ndc.row(2)).transpose()
}

struct Parts {
    w: f64,
    a: DVec2,
    c: DMat2,
    e: DVec2,
    jac: DMat2,
}

// Always inlined: a call per sample and candidate was a tenth of the sum.
#[inline(always)]
fn parts(g: &DMat3, s: &BoundarySample) -> Option<Parts> {
    let (g1, g2, j) = (g.row(0), g.row(1), g.row(2));
    let w = j.dot(s.light);
    if !(w > 0.0) {
        return None;
    }
    let a = DVec2::new(g1.dot(s.light), g2.dot(s.light));
    // Column k of c and e: derivatives along screen axis k.
    let c = DMat2::from_cols(DVec2::new(g1.dot(s.d_dx), g2.dot(s.d_dx)), DVec2::new(g1.dot(s.d_dy), g2.dot(s.d_dy)));
    let e = DVec2::new(j.dot(s.d_dx), j.dot(s.d_dy));
    let inv_w = 1.0 / w;
    let jac =
        DMat2::from_cols(c.x_axis * inv_w - a * (e.x * inv_w * inv_w), c.y_axis * inv_w - a * (e.y * inv_w * inv_w));
    Some(Parts { w, a, c, e, jac })
}

/// Badness of one sample under `g` (texel units); `+∞` behind the light or
/// where the light sees the surface edge-on.
#[must_use]
#[inline]
pub fn sample_badness(g: &DMat3, s: &BoundarySample) -> f64 {
    parts(g, s).map_or(f64::INFINITY, |p| crate::score::badness_of_jacobian(&p.jac))
}

/// Samples scored together by [`badness_group`].
const LANES: usize = 4;

/// `LANES` boundary samples component by component (a structure of arrays
/// per group): the lanes of [`badness_group`] load each component of four
/// samples at once instead of gathering it from four samples.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct SampleGroup {
    /// `light.x`, `light.y`, `light.z` of each lane.
    light: [[f64; LANES]; 3],
    d_dx: [[f64; LANES]; 3],
    d_dy: [[f64; LANES]; 3],
}

impl SampleGroup {
    #[inline]
    fn new(s: &[BoundarySample; LANES]) -> Self {
        let column = |v: [DVec3; LANES]| {
            [[v[0].x, v[1].x, v[2].x, v[3].x], [v[0].y, v[1].y, v[2].y, v[3].y], [v[0].z, v[1].z, v[2].z, v[3].z]]
        };
        Self { light: column(s.map(|s| s.light)), d_dx: column(s.map(|s| s.d_dx)), d_dy: column(s.map(|s| s.d_dy)) }
    }
}

/// The boundary samples as [`SampleGroup`]s, built once per optimization
/// (in the optimizer's workspace) for the candidates' objectives and
/// medians: every whole group of `LANES` samples, in order; the remainder
/// (`len % LANES` samples) stays in the samples' slice.
#[derive(Clone, Debug, Default)]
pub(crate) struct BoundaryGroups {
    groups: Vec<SampleGroup>,
}

impl BoundaryGroups {
    /// Rebuilds the groups for `samples`, reusing the buffer.
    pub(crate) fn fill(&mut self, samples: &[BoundarySample]) {
        self.groups.clear();
        self.groups.extend(samples.chunks_exact(LANES).map(|c| SampleGroup::new(c.try_into().expect("chunks_exact"))));
    }

    /// The groups and the remainder of `samples` (the slice they were
    /// filled from).
    fn split<'a>(&'a self, samples: &'a [BoundarySample]) -> (&'a [SampleGroup], &'a [BoundarySample]) {
        assert_eq!(self.groups.len(), samples.len() / LANES, "groups filled from other samples");
        (&self.groups, &samples[self.groups.len() * LANES..])
    }
}

/// [`sample_badness`] of `LANES` samples at once: every lane does the same
/// operations in the same order as `sample_badness` (glam's dot products
/// `(x·x' + y·y') + z·z'`, its determinant and squared lengths), so each
/// lane's value is `sample_badness`'s bit for bit; written lane by lane the
/// compiler packs them into vector instructions.
#[inline(always)]
fn badness_group(g: &DMat3, s: &SampleGroup) -> [f64; LANES] {
    let (g1, g2, j) = (g.row(0), g.row(1), g.row(2));
    let dot = |r: DVec3, v: &[[f64; LANES]; 3], k: usize| (r.x * v[0][k]) + (r.y * v[1][k]) + (r.z * v[2][k]);
    let mut out = [0.0; LANES];
    for (k, out) in out.iter_mut().enumerate() {
        let (p, dx, dy) = (&s.light, &s.d_dx, &s.d_dy);
        let w = dot(j, p, k);
        let (a0, a1) = (dot(g1, p, k), dot(g2, p, k));
        let (c00, c10, c01, c11) = (dot(g1, dx, k), dot(g2, dx, k), dot(g1, dy, k), dot(g2, dy, k));
        let (e0, e1) = (dot(j, dx, k), dot(j, dy, k));
        let inv_w = 1.0 / w;
        let (t0, t1) = (e0 * inv_w * inv_w, e1 * inv_w * inv_w);
        let (j00, j10) = (c00 * inv_w - a0 * t0, c10 * inv_w - a1 * t0);
        let (j01, j11) = (c01 * inv_w - a0 * t1, c11 * inv_w - a1 * t1);
        let det = j00 * j11 - j10 * j01;
        let frob = (j00 * j00 + j10 * j10) + (j01 * j01 + j11 * j11);
        let b = frob / (det * det);
        *out = if !(w > 0.0) || det == 0.0 { f64::INFINITY } else { b };
    }
    out
}

/// Badness of one sample and its gradient with respect to the rows of `g`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct SampleGradient {
    /// The badness `b`.
    pub badness: f64,
    /// `∂b/∂g₁`.
    pub d_g1: DVec3,
    /// `∂b/∂g₂`.
    pub d_g2: DVec3,
    /// `∂b/∂j` (affine rows fixed).
    pub d_j: DVec3,
}

/// Badness of one sample and its gradient with respect to the three rows of
/// `g` (texel units). `None` behind the light or edge-on.
#[must_use]
pub(crate) fn sample_badness_gradient(g: &DMat3, s: &BoundarySample) -> Option<SampleGradient> {
    let p = parts(g, s)?;
    let jac = p.jac;
    let det = jac.determinant();
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let frob = jac.x_axis.length_squared() + jac.y_axis.length_squared();
    let b = frob / (det * det);
    // ∂b/∂J = 2J/Δ² − 2F cof(J)/Δ³, cof(J) = ∂Δ/∂J = [[J₂₂, −J₂₁], [−J₁₂, J₁₁]].
    let cof = DMat2::from_cols(DVec2::new(jac.y_axis.y, -jac.y_axis.x), DVec2::new(-jac.x_axis.y, jac.x_axis.x));
    let db_dj = jac * (2.0 / (det * det)) - cof * (2.0 * frob / (det * det * det));
    let (w, a, c, e) = (p.w, p.a, p.c, p.e);
    let (w2, w3) = (w * w, w * w * w);
    let d = [s.d_dx, s.d_dy];
    // ∂Jᵢⱼ/∂w = −cᵢⱼ/w² + 2 aᵢ eⱼ / w³ ;  ∂Jᵢⱼ/∂eₖ = −aᵢ δⱼₖ / w²;
    // ∂Jᵢⱼ/∂gᵢ = Dⱼ / w − P eⱼ / w².
    let mut db_dw = 0.0;
    let mut db_de = DVec2::ZERO;
    let mut d_g = [DVec3::ZERO; 2];
    for k in 0..2 {
        let col_db = db_dj.col(k);
        let col_c = c.col(k);
        for i in 0..2 {
            db_dw += col_db[i] * (-col_c[i] / w2 + 2.0 * a[i] * e[k] / w3);
            db_de[k] += col_db[i] * (-a[i] / w2);
            d_g[i] += (d[k] / w - s.light * (e[k] / w2)) * col_db[i];
        }
    }
    let d_j = s.light * db_dw + s.d_dx * db_de.x + s.d_dy * db_de.y;
    Some(SampleGradient { badness: b, d_g1: d_g[0], d_g2: d_g[1], d_j })
}

/// `h(G) = Σ b` over the samples (`+∞` when any sample is behind the light).
#[must_use]
pub fn objective(g: &DMat3, samples: &[BoundarySample]) -> f64 {
    samples.iter().map(|s| sample_badness(g, s)).sum()
}

/// [`objective`] when it is below `bound`, else `None`, stopping as soon as
/// the partial sum reaches `bound`: every term is `≥ 0` (or `+∞`, or NaN
/// from non-finite input), and adding a non-negative float never lowers a
/// sum, so a partial sum at or above `bound` means the whole one is too.
/// When it returns a value, that value is [`objective`]'s bit for bit (the
/// same terms added in the same order; for non-negative terms the start
/// value's sign does not matter). `groups` holds `samples` as filled by
/// [`BoundaryGroups::fill`].
///
/// On x86-64 CPUs with AVX the same loop runs compiled for AVX ([`avx`]):
/// four lanes a vector instruction instead of two, the same operations on
/// each lane, so the same bits (IEEE-754 operations round the same whatever
/// the vector width, and Rust never fuses a product into a sum).
#[must_use]
pub(crate) fn objective_below(
    g: &DMat3,
    groups: &BoundaryGroups,
    samples: &[BoundarySample],
    bound: f64,
) -> Option<f64> {
    avx_or_portable!(avx::objective_below(g, groups, samples, bound), objective_below_lanes(g, groups, samples, bound),)
}

/// The body of [`objective_below`], for any target features.
#[inline(always)]
fn objective_below_lanes(g: &DMat3, groups: &BoundaryGroups, samples: &[BoundarySample], bound: f64) -> Option<f64> {
    let (groups, rest) = groups.split(samples);
    let mut total = 0.0;
    for group in groups {
        // Added one by one, in order: the same sum and the same stop.
        for b in badness_group(g, group) {
            total += b;
            if total >= bound {
                return None;
            }
        }
    }
    for s in rest {
        total += sample_badness(g, s);
        if total >= bound {
            return None;
        }
    }
    (total < bound).then_some(total)
}

/// `h` and `∇_j h` with the affine rows `g₁, g₂` fixed; `None` when any
/// sample is unusable.
#[must_use]
pub fn objective_gradient(g: &DMat3, samples: &[BoundarySample]) -> Option<(f64, DVec3)> {
    let (h, _, _, d_j) = gradient_sums(g, samples)?;
    Some((h, d_j))
}

fn gradient_sums(g: &DMat3, samples: &[BoundarySample]) -> Option<(f64, DVec3, DVec3, DVec3)> {
    samples.iter().try_fold((0.0, DVec3::ZERO, DVec3::ZERO, DVec3::ZERO), |(h, g1, g2, j), s| {
        let d = sample_badness_gradient(g, s)?;
        Some((h + d.badness, g1 + d.d_g1, g2 + d.d_g2, j + d.d_j))
    })
}

/// `h` and its gradient with respect to `j` when the affine part is held
/// fixed *on the image plane*: `G = A [e₁; e₂; j]` with the plane's frame
/// `e₁, e₂` carried along as `j` turns (parallel transport), so that turning
/// `j` does not also translate and rescale the map the way a fixed `g₁, g₂`
/// would. Only the part orthogonal to `j` is returned.
///
/// With `gᵢ = Aᵢ₁e₁ + Aᵢ₂e₂ + tᵢ j` and `deₖ = −(eₖ·dj) j`:
/// `∇ = ∂h/∂j + Σᵢ [(gᵢ·j) ∂h/∂gᵢ − (∂h/∂gᵢ·j) gᵢ⊥]`, projected onto `j⊥`.
#[must_use]
pub fn plane_frame_gradient(g: &DMat3, samples: &[BoundarySample]) -> Option<(f64, DVec3)> {
    let (h, d_g1, d_g2, d_j) = gradient_sums(g, samples)?;
    let j = g.row(2).normalize();
    let perp = |v: DVec3| v - j * v.dot(j);
    let mut grad = d_j;
    for (gi, d_gi) in [(g.row(0), d_g1), (g.row(1), d_g2)] {
        grad += d_gi * gi.dot(j) - perp(gi) * d_gi.dot(j);
    }
    Some((h, perp(grad)))
}

/// Median badness over the samples (`+∞` for none), using `scratch`;
/// `groups` as in [`objective_below`] (and, like it, the badness with AVX
/// where the CPU has it).
#[must_use]
pub(crate) fn median_badness(
    g: &DMat3,
    groups: &BoundaryGroups,
    samples: &[BoundarySample],
    scratch: &mut Vec<f64>,
) -> f64 {
    scratch.clear();
    avx_or_portable!(avx::badness_into(g, groups, samples, scratch), badness_into_lanes(g, groups, samples, scratch),);
    if scratch.is_empty() {
        return f64::INFINITY;
    }
    let mid = scratch.len() / 2;
    let (_, &mut upper, _) = scratch.select_nth_unstable_by(mid, f64::total_cmp);
    if scratch.len() % 2 == 1 {
        upper
    } else {
        let lower = scratch[..mid].iter().copied().fold(f64::NEG_INFINITY, f64::max);
        0.5 * (lower + upper)
    }
}

/// Every sample's badness, in order, appended to `scratch`.
#[inline(always)]
fn badness_into_lanes(g: &DMat3, groups: &BoundaryGroups, samples: &[BoundarySample], scratch: &mut Vec<f64>) {
    let (groups, rest) = groups.split(samples);
    for group in groups {
        scratch.extend(badness_group(g, group));
    }
    scratch.extend(rest.iter().map(|s| sample_badness(g, s)));
}

/// [`objective_below`] and [`median_badness`]'s loops compiled for AVX
/// (called only where the CPU has it): the same Rust, so the same
/// operations per lane and the same bits; LLVM packs four lanes of
/// [`badness_group`] into each 256-bit instruction.
#[cfg(target_arch = "x86_64")]
mod avx {
    use glam::DMat3;

    use super::{BoundaryGroups, BoundarySample};

    #[target_feature(enable = "avx")]
    pub(super) fn objective_below(
        g: &DMat3,
        groups: &BoundaryGroups,
        samples: &[BoundarySample],
        bound: f64,
    ) -> Option<f64> {
        super::objective_below_lanes(g, groups, samples, bound)
    }

    #[target_feature(enable = "avx")]
    pub(super) fn badness_into(g: &DMat3, groups: &BoundaryGroups, samples: &[BoundarySample], scratch: &mut Vec<f64>) {
        super::badness_into_lanes(g, groups, samples, scratch);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lanes are `sample_badness` bit for bit, including samples behind
    /// the light (`w ≤ 0`), edge-on ones (`det = 0`) and NaN.
    #[test]
    fn lanes_equal_one_sample_at_a_time() {
        let mut unit = crate::test_rng::unit(0x2545_F491_4F6C_DD1D_u64);
        let mut next = move || unit() * 2.0 - 1.0;
        let g = DMat3::from_cols_array(&[300.0, 20.0, 0.1, -15.0, 280.0, 0.2, 40.0, -30.0, 1.0]).transpose();
        let mut v = || DVec3::new(next(), next(), next());
        let mut samples: Vec<BoundarySample> = (0..4000)
            .map(|k| {
                let light = v() + DVec3::Z * if k % 7 == 0 { 0.0 } else { 1.5 };
                let d_dx = v() * 1e-3;
                // Edge-on: the two derivatives parallel.
                let d_dy = if k % 11 == 0 { d_dx * 2.0 } else { v() * 1e-3 };
                BoundarySample { light, d_dx, d_dy }
            })
            .collect();
        samples[5].light.x = f64::NAN;
        samples[9].light = DVec3::new(0.0, 0.0, -1.0);
        let mut behind_or_edge_on = 0;
        for chunk in samples.chunks_exact(LANES) {
            let lanes = badness_group(&g, &SampleGroup::new(chunk.try_into().unwrap()));
            for (s, b) in chunk.iter().zip(lanes) {
                let one = sample_badness(&g, s);
                assert_eq!(b.to_bits(), one.to_bits(), "{s:?}");
                behind_or_edge_on += usize::from(one == f64::INFINITY);
            }
        }
        assert!(behind_or_edge_on > 100, "{behind_or_edge_on}");
        // Over the finite ones (an odd count: lanes and remainder), the
        // lanes' sum is `objective`'s, and it stops below a smaller bound.
        let finite: Vec<_> = samples.iter().copied().filter(|s| sample_badness(&g, s).is_finite()).take(3001).collect();
        let total = objective(&g, &finite);
        let mut groups = BoundaryGroups::default();
        groups.fill(&finite);
        assert_eq!(objective_below(&g, &groups, &finite, f64::INFINITY).map(f64::to_bits), Some(total.to_bits()));
        assert_eq!(objective_below(&g, &groups, &finite, total), None);
    }
    /// The dispatched loops (AVX where this CPU has it, as on x86-64 CI
    /// machines) give the scalar definitions' bits: `objective_below`
    /// against [`objective`] for bounds above, at and below the total and
    /// mid-way, and `median_badness` against a sort of the scalar values;
    /// sample counts 1–40 (every remainder), samples behind the light,
    /// edge-on and NaN included.
    #[test]
    fn dispatched_loops_equal_the_scalar_ones() {
        let mut unit = crate::test_rng::unit(0x9E37_79B9_7F4A_7C15_u64);
        let mut next = move || unit() * 2.0 - 1.0;
        let mut groups = BoundaryGroups::default();
        let mut scratch = Vec::new();
        let (mut finite, mut stopped) = (0, 0);
        for case in 0..3000 {
            let g = DMat3::from_cols_array(&std::array::from_fn(|k| {
                let diagonal = [300.0, 0.0, 0.0, 0.0, 280.0, 0.0, 0.0, 0.0, 1.0][k];
                // (from_cols_array then transpose: k = 6..9 is the row `j`.)
                diagonal + if k < 6 { 40.0 } else { 0.1 } * next()
            }))
            .transpose();
            let mut v = || DVec3::new(next(), next(), next());
            // (1 to 40: `objective` of no samples is `Sum`'s `-0.0`, which
            // the optimizer never asks for.)
            let samples: Vec<BoundarySample> = (0..1 + case % 40)
                .map(|k| {
                    let light = v() + DVec3::Z * if (k + case) % 97 == 0 { 0.0 } else { 2.5 };
                    let d_dx = v() * 1e-3;
                    let d_dy = if (k + case) % 89 == 0 { d_dx * 2.0 } else { v() * 1e-3 };
                    let mut s = BoundarySample { light, d_dx, d_dy };
                    if (k + case) % 211 == 0 {
                        s.d_dy.y = f64::NAN;
                    }
                    s
                })
                .collect();
            groups.fill(&samples);
            let total = objective(&g, &samples);
            let below = |bound: f64| objective_below(&g, &groups, &samples, bound).map(f64::to_bits);
            let expect = |bound: f64| (total < bound).then_some(total.to_bits());
            for bound in [f64::INFINITY, total, total * 0.5, total * (1.0 + 1e-15), 0.0] {
                assert_eq!(below(bound), expect(bound), "case {case} bound {bound}");
            }
            finite += usize::from(total.is_finite());
            stopped += usize::from(below(total * 0.5).is_none() && total > 0.0);
            let mut values: Vec<f64> = samples.iter().map(|s| sample_badness(&g, s)).collect();
            values.sort_by(f64::total_cmp);
            let mid = values.len() / 2;
            let median = match values.len() {
                0 => f64::INFINITY,
                n if n % 2 == 1 => values[mid],
                _ => 0.5 * (values[mid - 1] + values[mid]),
            };
            let got = median_badness(&g, &groups, &samples, &mut scratch);
            assert_eq!(got.to_bits(), median.to_bits(), "case {case}");
        }
        assert!(finite > 1000 && stopped > 1000, "{finite} {stopped}");
    }
}
