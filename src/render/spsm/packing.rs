//! The SPSM texel format on the CPU: the same encoding as
//! `shaders/spsm_common.wgsl` (for tests, readback and error reports), the
//! lookup's 3x3 silhouette estimate, and a reference for conservative
//! coverage.
//!
//! Texel words: `x, y, z` = the three vertices relative to the texel centre
//! in texels, two IEEE half floats each (low half = x); `w` = 16-bit depth
//! code (bits 31..16), then the 16-bit code of the depth gradient
//! ([`GradientCode`]), never zero. `w & 0xffff == 0`: no triangle (all
//! zero: empty; `x == 1`: depth only).

use glam::{DVec2, Vec2};

const DEPTH_LO: f64 = -0.0625;
const DEPTH_SPAN: f64 = 1.125;
const MAX_ANGLE: f64 = 0.999_999;

/// 16-bit code of a post-projective depth (unorm over `[-1/16, 17/16]`).
#[must_use]
pub fn encode_depth(z: f64) -> u32 {
    (((z - DEPTH_LO) / DEPTH_SPAN).clamp(0.0, 1.0) * 65535.0).round() as u32
}

/// Inverse of [`encode_depth`].
#[must_use]
pub fn decode_depth(code: u32) -> f64 {
    f64::from(code) / 65535.0 * DEPTH_SPAN + DEPTH_LO
}

/// How the 16 low bits of a texel's `w` word hold the plane's depth
/// gradient (`dzeta/dx`, `dzeta/dy`).
///
/// Why two (issue 16, session 6): the paper's power code (eq. 3) spends its
/// 254 levels per axis on steep slopes and has a dead zone around zero:
/// with exponent 5 every slope below ~0.55 of the depth range per map
/// extent (1.4e-3 per texel on a 400² map) decodes to 0, and the packing
/// tolerance grows accordingly. The scene-optimized matrices squeeze the
/// receivers' depths into a narrow band (default preset, configuration 5:
/// `zeta` in [0.91, 0.96], slopes ~4.5e-4 per texel), so every stored plane
/// there was flat to the lookup and its tolerance (1.4e-3 per texel) was
/// larger than the caster-receiver gaps (~1e-3): whole shadow interiors
/// came out lit. [`Self::LogPolar`] keeps the same relative precision at
/// every slope instead.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[non_exhaustive]
pub enum GradientCode {
    /// The paper's eq. (3) per axis: `Q(d) = 127 (1 + a^n)`,
    /// `a = 2 atan(d) / π`, `d` the slope per map extent (texel slope times
    /// the map size), 8 bits each (stored `+ 1`).
    Power {
        /// The exponent `n` (the paper: 5; 1 is linear in the angle).
        exponent: f32,
    },
    /// The gradient as one vector: 8 bits of log magnitude per texel (code
    /// 1: zero; code `c >= 2`: `LOG_MIN · e^{Δ (c - 2)}` over
    /// `[1e-7, 10]` per texel) and 8 bits of direction (`2π k / 256`). Error
    /// bound: 4.9% of the decoded magnitude (half a magnitude step plus half a
    /// direction step; [`gradient_error`]), 1e-7 per texel below the range.
    /// The default.
    #[default]
    LogPolar,
}

/// Smallest nonzero gradient magnitude of [`GradientCode::LogPolar`], zeta per texel.
pub const LOG_MIN: f64 = 1e-7;
/// Largest gradient magnitude of [`GradientCode::LogPolar`] (codes saturate above).
pub const LOG_MAX: f64 = 10.0;

/// The log step of [`GradientCode::LogPolar`]'s magnitude.
fn log_step() -> f64 {
    (LOG_MAX / LOG_MIN).ln() / 253.0
}

/// The 16-bit code of `gradient` (zeta per texel) on a `map`-sized map.
#[must_use]
pub fn encode_gradient(gradient: DVec2, map: [u32; 2], code: GradientCode) -> u32 {
    match code {
        GradientCode::Power { exponent } => {
            let e = f64::from(exponent);
            let sx = encode_slope(gradient.x * f64::from(map[0]), e);
            let sy = encode_slope(gradient.y * f64::from(map[1]), e);
            (sx + 1) << 8 | (sy + 1)
        }
        GradientCode::LogPolar => {
            let m = gradient.length();
            let step = log_step();
            if !(m >= LOG_MIN * (-0.5 * step).exp()) {
                return 1 << 8;
            }
            let c = 2 + ((m / LOG_MIN).ln() / step).round().clamp(0.0, 253.0) as u32;
            let turn = gradient.y.atan2(gradient.x) / std::f64::consts::TAU;
            let k = ((turn * 256.0).round() as i64).rem_euclid(256) as u32;
            c << 8 | k
        }
    }
}

/// Inverse of [`encode_gradient`]: zeta per texel.
#[must_use]
pub fn decode_gradient(bits: u32, map: [u32; 2], code: GradientCode) -> DVec2 {
    match code {
        GradientCode::Power { exponent } => {
            let e = f64::from(exponent);
            let slope = |q: u32, size: u32| decode_slope(f64::from(q.max(1) - 1), e) / f64::from(size);
            DVec2::new(slope(bits >> 8 & 0xff, map[0]), slope(bits & 0xff, map[1]))
        }
        GradientCode::LogPolar => {
            let c = bits >> 8 & 0xff;
            if c < 2 {
                return DVec2::ZERO;
            }
            let m = LOG_MIN * (log_step() * f64::from(c - 2)).exp();
            let angle = f64::from(bits & 0xff) / 256.0 * std::f64::consts::TAU;
            m * DVec2::new(angle.cos(), angle.sin())
        }
    }
}

/// A bound on the error of [`decode_gradient`] per axis (zeta per texel),
/// as the lookup's packing tolerance uses it (`shaders/spsm_common.wgsl`).
/// For [`GradientCode::LogPolar`] the same bound on both axes: the
/// magnitude lies within half a log step of the decoded one and the angle
/// within half a direction step, so `|g - g'| <= m' (e^{Δ/2} - 1) +
/// m' e^{Δ/2} π / 256` (the saturated top code excepted).
#[must_use]
pub fn gradient_error(bits: u32, map: [u32; 2], code: GradientCode) -> DVec2 {
    match code {
        GradientCode::Power { exponent } => {
            let e = f64::from(exponent);
            let err = |q: u32, size: u32| {
                let q = f64::from(q.max(1) - 1);
                let d = decode_slope(q, e);
                let lo = decode_slope((q - 0.5).max(0.0), e);
                let hi = decode_slope((q + 0.5).min(254.0), e);
                (d - lo).abs().max((hi - d).abs()) / f64::from(size)
            };
            DVec2::new(err(bits >> 8 & 0xff, map[0]), err(bits & 0xff, map[1]))
        }
        GradientCode::LogPolar => {
            let c = bits >> 8 & 0xff;
            let step = log_step();
            if c < 2 {
                return DVec2::splat(LOG_MIN);
            }
            let m = LOG_MIN * (step * f64::from(c - 2)).exp();
            let half = (0.5 * step).exp();
            DVec2::splat(m * (half - 1.0) + m * half * std::f64::consts::PI / 256.0)
        }
    }
}

/// The paper's eq. (3): `Q(d) = 127 (1 + a^n)`, `a = 2 atan(d) / π`
/// (signed power), rounded to `0..=254` ([`GradientCode::Power`]).
#[must_use]
pub fn encode_slope(d: f64, exponent: f64) -> u32 {
    let a = (d.atan() / std::f64::consts::FRAC_PI_2).clamp(-MAX_ANGLE, MAX_ANGLE);
    (127.0 * (1.0 + a.signum() * a.abs().powf(exponent))).round().clamp(0.0, 254.0) as u32
}

/// The paper's eq. (4) (also for fractional codes).
#[must_use]
pub fn decode_slope(q: f64, exponent: f64) -> f64 {
    let s = (q / 127.0 - 1.0).clamp(-1.0, 1.0);
    if s == 0.0 {
        return 0.0;
    }
    let a = (s.signum() * s.abs().powf(1.0 / exponent)).clamp(-MAX_ANGLE, MAX_ANGLE);
    (a * std::f64::consts::FRAC_PI_2).tan()
}

/// A texel's triangle as the lookup sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DecodedTexel {
    /// Vertices in absolute texel coordinates.
    pub vertices: [DVec2; 3],
    /// Post-projective depth at the texel centre.
    pub depth: f64,
    /// Depth per texel along x and y.
    pub gradient: DVec2,
}

/// Packs a triangle (absolute texel coordinates) stored at texel `texel` of
/// a `map`-sized SPSM whose plane has depth `depth` at the texel centre and
/// `gradient` per texel.
#[must_use]
pub fn pack(
    vertices: [DVec2; 3],
    texel: [u32; 2],
    depth: f64,
    gradient: DVec2,
    map: [u32; 2],
    code: GradientCode,
) -> [u32; 4] {
    let centre = DVec2::new(f64::from(texel[0]), f64::from(texel[1])) + 0.5;
    let half = |v: DVec2| {
        let d = (v - centre).clamp(DVec2::splat(-60000.0), DVec2::splat(60000.0));
        u32::from(half::f16::from_f64(d.x).to_bits()) | u32::from(half::f16::from_f64(d.y).to_bits()) << 16
    };
    [
        half(vertices[0]),
        half(vertices[1]),
        half(vertices[2]),
        encode_depth(depth) << 16 | encode_gradient(gradient, map, code),
    ]
}

/// Bits 30..26 of word x of a compact texel (`shaders/spsm_common.wgsl`,
/// [`SpsmOptions::inner_edges`](super::SpsmOptions::inner_edges)): v0.y's
/// f16 exponent all ones, which plain offsets never have.
pub const COMPACT_MARK: u32 = 0x7c00_0000;

/// Logical bits `[l, l + n)` of a compact texel's payload: the 96 bits of
/// words x, y, z without the marker's bits 26..30 (`spsm_field_get`).
fn compact_field(words: [u32; 3], l: u32, n: u32) -> u32 {
    let bit = |b: u32| (words[(b / 32) as usize] >> (b % 32)) & 1;
    (0..n).fold(0, |v, i| {
        let logical = l + i;
        let physical = if logical >= 26 { logical + 5 } else { logical };
        v | bit(physical) << i
    })
}

/// The three vertex offsets of a compact texel (11-bit fixed point over
/// `[-4, 4)`, from logical bit 24).
#[must_use]
pub fn compact_offsets(words: [u32; 3]) -> [DVec2; 3] {
    let coordinate = |l: u32| f64::from(compact_field(words, l, 11)) / 256.0 - 4.0;
    [24, 46, 68].map(|l| DVec2::new(coordinate(l), coordinate(l + 11)))
}

/// The 8-bit inner-edge codes of a compact texel (edge k in bits
/// 8k..8k+7; `spsm_edge_code`).
#[must_use]
pub fn compact_codes(words: [u32; 3]) -> u32 {
    compact_field(words, 0, 24)
}

/// Decodes a texel at `texel`; `None` without a triangle.
#[must_use]
pub fn unpack(words: [u32; 4], texel: [u32; 2], map: [u32; 2], code: GradientCode) -> Option<DecodedTexel> {
    if words[3] & 0xffff == 0 {
        return None;
    }
    let centre = DVec2::new(f64::from(texel[0]), f64::from(texel[1])) + 0.5;
    let vertex = |w: u32| {
        let x = half::f16::from_bits(w as u16).to_f64();
        let y = half::f16::from_bits((w >> 16) as u16).to_f64();
        centre + DVec2::new(x, y)
    };
    let vertices = if words[0] & COMPACT_MARK == COMPACT_MARK {
        let offsets = compact_offsets([words[0], words[1], words[2]]);
        offsets.map(|o| centre + o)
    } else {
        [vertex(words[0]), vertex(words[1]), vertex(words[2])]
    };
    Some(DecodedTexel {
        vertices,
        depth: decode_depth(words[3] >> 16),
        gradient: decode_gradient(words[3] & 0xffff, map, code),
    })
}

/// Whether the texel texel box `[x, x + 1] x [y, y + 1]`, grown by `margin`
/// on every side (negative: shrunk), meets the triangle (closed sets;
/// separating axes x, y and the edge normals). The reference for the
/// conservative rasterization tests.
#[must_use]
pub fn texel_touches(triangle: [DVec2; 3], texel: [i64; 2], margin: f64) -> bool {
    let c = DVec2::new(texel[0] as f64, texel[1] as f64) + 0.5;
    let h = 0.5 + margin;
    let lo = triangle[0].min(triangle[1]).min(triangle[2]);
    let hi = triangle[0].max(triangle[1]).max(triangle[2]);
    if lo.x > c.x + h || lo.y > c.y + h || hi.x < c.x - h || hi.y < c.y - h {
        return false;
    }
    let orient = (triangle[1] - triangle[0]).perp_dot(triangle[2] - triangle[0]).signum();
    if orient == 0.0 {
        let d = triangle[1] - triangle[0];
        let n = DVec2::new(-d.y, d.x);
        return n.dot(c - triangle[0]).abs() <= h * (n.x.abs() + n.y.abs());
    }
    (0..3).all(|k| {
        let (a, b) = (triangle[k], triangle[(k + 1) % 3]);
        let n = orient * DVec2::new(b.y - a.y, a.x - b.x);
        n.dot(c - a) - h * (n.x.abs() + n.y.abs()) <= 0.0
    })
}

/// What the lookup's silhouette recovery makes of a 3x3 depth-test pattern
/// (bit `3 (dy + 1) + dx + 1` set where that neighbour's texel blocks the
/// receiver); the CPU mirror of `spsm_silhouette` in
/// `shaders/spsm_lookup.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Silhouette {
    /// No bit or every bit: nothing to recover.
    None,
    /// One edge: its unit normal from the blocked to the free side.
    OneSided(Vec2),
    /// A thin blocked band, free on both sides: the unit normal of its axis
    /// (both signs are tested).
    TwoSided(Vec2),
    /// A blocked blob without a direction: the four axis directions are
    /// tested.
    Blob,
}

/// The silhouette estimate of `pattern` (see [`Silhouette`]).
///
/// As in the paper (section 4.2), blocked texels without a 4-connected
/// blocked neighbour are left out of the estimate (conservative
/// rasterization means an edge cannot pass between them unnoticed), unless
/// that leaves none. The normal runs from the kept blocked texels' centroid
/// to the free ones'; where the two coincide the kept texels' principal
/// axis is the tangent (two-sided), or there is none (a blob).
#[must_use]
pub fn silhouette_estimate(pattern: u32) -> Silhouette {
    let offset = |i: usize| DVec2::new((i % 3) as f64 - 1.0, (i / 3) as f64 - 1.0);
    let blocked: Vec<usize> = (0..9).filter(|&i| pattern >> i & 1 == 1).collect();
    if blocked.is_empty() || blocked.len() == 9 {
        return Silhouette::None;
    }
    let connected: Vec<usize> = blocked
        .iter()
        .copied()
        .filter(|&i| blocked.iter().any(|&j| (offset(i) - offset(j)).abs().element_sum() == 1.0))
        .collect();
    let kept = if connected.is_empty() { blocked } else { connected };
    let free: Vec<usize> = (0..9).filter(|&i| pattern >> i & 1 == 0).collect();
    let centroid = |set: &[usize]| set.iter().map(|&i| offset(i)).sum::<DVec2>() / set.len() as f64;
    let c = centroid(&kept);
    let n = centroid(&free) - c;
    if n.length() > 1e-3 {
        return Silhouette::OneSided(n.normalize().as_vec2());
    }
    let moment = |f: &dyn Fn(DVec2) -> f64| kept.iter().map(|&i| f(offset(i) - c)).sum::<f64>() / kept.len() as f64;
    let (sxx, syy, sxy) = (moment(&|o| o.x * o.x), moment(&|o| o.y * o.y), moment(&|o| o.x * o.y));
    if (sxx - syy).abs() + sxy.abs() < 1e-3 {
        return Silhouette::Blob;
    }
    let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    Silhouette::TwoSided(DVec2::new(-theta.sin(), theta.cos()).as_vec2())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_codes_round_trip_within_half_a_step() {
        for k in 0..=1000 {
            let z = -0.05 + 1.1 * f64::from(k) / 1000.0;
            let err = (decode_depth(encode_depth(z)) - z).abs();
            assert!(err <= 0.5 * DEPTH_SPAN / 65535.0 + 1e-12, "z {z}: {err}");
        }
    }

    #[test]
    fn slope_codes_are_odd_monotone_and_exact_at_zero() {
        let mut last = 0;
        for k in -400..=400 {
            let d = (f64::from(k) / 100.0).powi(3);
            let q = encode_slope(d, 5.0);
            assert!(q >= last, "monotone");
            last = q;
            assert_eq!(encode_slope(-d, 5.0), 254 - q, "odd");
        }
        assert_eq!(decode_slope(f64::from(encode_slope(0.0, 5.0)), 5.0), 0.0);
    }

    #[test]
    fn pack_round_trips() {
        let tri = [DVec2::new(10.25, 3.5), DVec2::new(12.0, 9.75), DVec2::new(7.125, 6.0)];
        for code in [GradientCode::Power { exponent: 5.0 }, GradientCode::LogPolar] {
            let g = DVec2::new(0.01, -0.003);
            let words = pack(tri, [10, 5], 0.4321, g, [64, 64], code);
            let back = unpack(words, [10, 5], [64, 64], code).unwrap();
            let bound = gradient_error(words[3] & 0xffff, [64, 64], code);
            assert!((back.gradient - g).abs().cmple(bound).all(), "{code:?}: {} vs {g}, bound {bound}", back.gradient);
        }
        let code = GradientCode::LogPolar;
        let words = pack(tri, [10, 5], 0.4321, DVec2::new(0.01, -0.003), [64, 64], code);
        let back = unpack(words, [10, 5], [64, 64], code).unwrap();
        for (a, b) in tri.iter().zip(back.vertices) {
            assert!((*a - b).length() < 1e-3, "{a} {b}");
        }
        assert!((back.depth - 0.4321).abs() < 1e-5);
        assert!(unpack([0, 0, 0, 0], [0, 0], [4, 4], code).is_none());
        assert!(unpack([1, 0, 0, 0x1234_0000], [0, 0], [4, 4], code).is_none());
    }

    /// Every log-polar code decodes within its bound of what it encodes,
    /// never to the "no triangle" word, and the bound holds for gradients
    /// of every size and direction in the range (4.9% of the decoded
    /// magnitude).
    #[test]
    fn log_polar_codes_hold_their_bound() {
        let code = GradientCode::LogPolar;
        for k in 0..=4000 {
            let m = LOG_MIN * 0.5 * (2.0 * LOG_MAX / LOG_MIN).powf(f64::from(k) / 4000.0);
            let angle = f64::from(k) * 2.399;
            let g = m.min(LOG_MAX) * DVec2::new(angle.cos(), angle.sin());
            let bits = encode_gradient(g, [400, 400], code);
            assert!(bits != 0 && bits <= 0xffff, "{bits:#x}");
            let err = (decode_gradient(bits, [400, 400], code) - g).abs();
            let bound = gradient_error(bits, [400, 400], code);
            assert!(err.cmple(bound * 1.000_001).all(), "{g}: error {err}, bound {bound}");
            if (LOG_MIN..=LOG_MAX).contains(&m) {
                // 4.9% of the decoded magnitude (up to 5.2% of the true one).
                let decoded = decode_gradient(bits, [400, 400], code).length();
                assert!(bound.x <= 0.05 * decoded, "relative bound {}", bound.x / decoded);
            }
        }
        assert_eq!(decode_gradient(encode_gradient(DVec2::ZERO, [4, 4], code), [4, 4], code), DVec2::ZERO);
    }

    #[test]
    fn estimates_point_from_blocked_to_free() {
        let one_sided = |pattern: u32| match silhouette_estimate(pattern) {
            Silhouette::OneSided(n) => n,
            other => panic!("{pattern:#b}: {other:?}"),
        };
        // Left column blocked: free side to the right.
        assert!(one_sided(1 | 1 << 3 | 1 << 6).x > 0.99);
        // Top row plus centre blocked: free side down.
        assert!(one_sided(1 | 2 | 4 | 16).y > 0.9);
        assert_eq!(silhouette_estimate(0), Silhouette::None);
        assert_eq!(silhouette_estimate(511), Silhouette::None);
        // A thin band through the middle row: free above and below.
        match silhouette_estimate(1 << 3 | 1 << 4 | 1 << 5) {
            Silhouette::TwoSided(n) => assert!(n.y.abs() > 0.99, "{n}"),
            other => panic!("{other:?}"),
        }
        // A diagonal band.
        match silhouette_estimate(1 | 1 << 4 | 1 << 8) {
            Silhouette::TwoSided(n) => assert!((n.x + n.y).abs() < 1e-6 && n.x.abs() > 0.7, "{n}"),
            other => panic!("{other:?}"),
        }
        // The centre alone, or a plus: no direction.
        assert_eq!(silhouette_estimate(1 << 4), Silhouette::Blob);
        assert_eq!(silhouette_estimate(1 << 1 | 1 << 3 | 1 << 4 | 1 << 5 | 1 << 7), Silhouette::Blob);
    }

    #[test]
    fn touches_is_exact_on_a_sliver() {
        let tri = [DVec2::new(0.5, 0.5), DVec2::new(9.5, 0.6), DVec2::new(9.5, 0.61)];
        assert!(texel_touches(tri, [5, 0], 0.0));
        assert!(!texel_touches(tri, [5, 1], 0.0));
        assert!(!texel_touches(tri, [5, 1], -0.01));
    }

    /// The compact texel's layout as `spsm_field_put` / `spsm_pack_compact`
    /// write it: codes from logical bit 0, offsets from 24, the marker's
    /// bits 26..30 of word x skipped.
    #[test]
    fn compact_texel_round_trips() {
        let put = |words: &mut [u32; 3], l: u32, n: u32, value: u32| {
            for i in 0..n {
                let logical = l + i;
                let physical = if logical >= 26 { logical + 5 } else { logical };
                words[(physical / 32) as usize] |= ((value >> i) & 1) << (physical % 32);
            }
        };
        let offsets = [DVec2::new(-3.99, 0.5), DVec2::new(1.25, -2.0), DVec2::new(3.98, 3.5)];
        let mut words = [COMPACT_MARK, 0, 0];
        put(&mut words, 0, 24, 0x00a5_1f3c);
        for (k, o) in offsets.iter().enumerate() {
            let fixed = |v: f64| ((v + 4.0) * 256.0).round().clamp(0.0, 2047.0) as u32;
            put(&mut words, 24 + 22 * k as u32, 11, fixed(o.x));
            put(&mut words, 35 + 22 * k as u32, 11, fixed(o.y));
        }
        assert_eq!(words[0] & COMPACT_MARK, COMPACT_MARK);
        assert_eq!(compact_codes(words), 0x00a5_1f3c);
        for (a, b) in offsets.iter().zip(compact_offsets(words)) {
            assert!((*a - b).abs().max_element() <= 0.5 / 256.0 + 1e-12, "{a} vs {b}");
        }
        let decoded =
            unpack([words[0], words[1], words[2], 0x8000_0101], [3, 4], [8, 8], GradientCode::LogPolar).unwrap();
        assert!((decoded.vertices[1] - DVec2::new(4.75, 2.5)).length() < 1e-9);
    }
}
