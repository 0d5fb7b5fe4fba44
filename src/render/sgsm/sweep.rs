//! The SGSM normal detection on the CPU: the reference of the sweep
//! (`shaders/sgsm_sweep.wgsl`) and of the lookup's triangle choice, used by
//! the tests and the detection-rate example.
//!
//! Per texel corner (an integer point of the map) the *corner triangle* is
//! the stored triangle, among the four texels sharing the corner, that
//! contains it and is nearest the light there; the corner is *empty* when
//! one of those texels holds nothing (a triangle through the corner would
//! touch all four) and *unknown* when none of the stored triangles contains
//! it (the surface there was not kept: more triangles overlap than the
//! texels could store) or a texel is depth-only. The four corners of a
//! texel are grouped by plane, the paper's comparison of corner normals:
//! two corner triangles are on one plane when they are the same texel's or
//! their normals (the conservative pass's f16 slopes) and their depths at
//! the texel centre agree within the packing's precision. The grouping,
//! the [`super::pattern`] index and the corners' slots make the
//! texel's [`MaskWord`]. A texel into which a stored triangle of its 3x3
//! reaches that lies on none of the corner planes is unrecognised: that
//! geometry touches no corner, and the corners do not explain the texel.

use glam::DVec2;

use super::pattern::{self, MaskWord, Status, CORNERS, CORNER_EMPTY, CORNER_UNKNOWN};
use crate::render::spsm::packing::{self, DecodedTexel};

/// Corner-containment tolerance, in texels (f16 vertex offsets).
pub const CONTAINS_EPS: f64 = 2e-3;
/// Relative tolerance of "same normal" on the f16 slopes.
pub const SLOPE_REL: f64 = 4e-3;
/// Absolute tolerance of "same normal", in depth per map extent.
pub const SLOPE_ABS: f64 = 1e-3;
/// How far (texels) a stored triangle must reach into a texel to count as
/// part of it.
pub const POKE_MARGIN: f64 = 1e-3;
/// Depth tolerance of "same plane" at the texel centre (two 16-bit centre
/// depth codes' rounding and more).
pub const DEPTH_EPS: f64 = 4e-5;

/// One texel of a map as the sweep reads it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SweepTexel {
    /// Nothing drawn.
    Empty,
    /// A triangle crossing the light's `w = 0` plane (depth only).
    DepthOnly,
    /// A stored triangle.
    Triangle(Stored),
}

/// A stored triangle as the sweep and the lookup use it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stored {
    /// The SPSM texel's triangle and centre-depth plane.
    pub spsm: DecodedTexel,
    /// The centre of the texel it is stored at.
    pub centre: DVec2,
    /// Depth per texel along x and y from the f16 normal word.
    pub slopes: DVec2,
}

/// A whole map: SPSM words, the conservative pass's normal words, size.
#[derive(Clone, Debug)]
pub struct SweepMap {
    /// Row-major texels.
    pub texels: Vec<SweepTexel>,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
}

/// Decodes an SGSM normal word (two f16 slopes per map extent) into
/// slopes per texel.
#[must_use]
pub fn decode_normal(word: u32, map: [u32; 2]) -> DVec2 {
    let x = half::f16::from_bits(word as u16).to_f64();
    let y = half::f16::from_bits((word >> 16) as u16).to_f64();
    DVec2::new(x / f64::from(map[0]), y / f64::from(map[1]))
}

impl SweepMap {
    /// From the readbacks of one light: SPSM words and normal words.
    #[must_use]
    pub fn new(words: &[[u32; 4]], normals: &[u32], width: u32, height: u32, code: packing::GradientCode) -> Self {
        let texels = words
            .iter()
            .zip(normals)
            .enumerate()
            .map(|(i, (w, n))| {
                let texel = [i as u32 % width, i as u32 / width];
                match packing::unpack(*w, texel, [width, height], code) {
                    Some(spsm) => SweepTexel::Triangle(Stored {
                        spsm,
                        centre: DVec2::new(f64::from(texel[0]) + 0.5, f64::from(texel[1]) + 0.5),
                        slopes: decode_normal(*n, [width, height]),
                    }),
                    None if w[0] == 1 => SweepTexel::DepthOnly,
                    None => SweepTexel::Empty,
                }
            })
            .collect();
        Self { texels, width, height }
    }

    /// The texel at `k` (outside the map: empty).
    #[must_use]
    pub fn get(&self, k: [i64; 2]) -> SweepTexel {
        if k[0] < 0 || k[1] < 0 || k[0] >= i64::from(self.width) || k[1] >= i64::from(self.height) {
            return SweepTexel::Empty;
        }
        self.texels[(k[1] * i64::from(self.width) + k[0]) as usize]
    }

    /// Every texel's mask word, row-major (the sweep's output).
    #[must_use]
    pub fn sweep(&self) -> Vec<MaskWord> {
        let mut out = Vec::with_capacity(self.texels.len());
        for y in 0..i64::from(self.height) {
            for x in 0..i64::from(self.width) {
                let corners = CORNERS.map(|o| self.corner([x + i64::from(o[0]), y + i64::from(o[1])]));
                out.push(self.classify([x, y], corners));
            }
        }
        out
    }

    /// The corner triangle at integer point `c`.
    #[must_use]
    pub fn corner(&self, c: [i64; 2]) -> Corner {
        let point = DVec2::new(c[0] as f64, c[1] as f64);
        let mut best: Option<([i64; 2], f64)> = None;
        let mut unknown = false;
        for k in [[c[0] - 1, c[1] - 1], [c[0], c[1] - 1], [c[0] - 1, c[1]], [c[0], c[1]]] {
            match self.get(k) {
                SweepTexel::Empty => return Corner::Empty,
                SweepTexel::DepthOnly => unknown = true,
                SweepTexel::Triangle(t) => {
                    if contains(&t, point, CONTAINS_EPS) {
                        let depth = plane_at(&t, point);
                        if best.is_none_or(|(_, d)| depth < d) {
                            best = Some((k, depth));
                        }
                    }
                }
            }
        }
        match best {
            Some((k, _)) if !unknown => Corner::Triangle(k),
            _ => Corner::Unknown,
        }
    }

    /// Whether the stored triangles of texels `a` and `b` lie on one plane,
    /// judged at point `at`.
    #[must_use]
    pub fn same_plane(&self, a: [i64; 2], b: [i64; 2], at: DVec2) -> bool {
        if a == b {
            return true;
        }
        let (SweepTexel::Triangle(ta), SweepTexel::Triangle(tb)) = (self.get(a), self.get(b)) else {
            return false;
        };
        let (sa, sb) = (ta.slopes, tb.slopes);
        let size = DVec2::new(f64::from(self.width), f64::from(self.height));
        let (ea, eb) = (sa * size, sb * size);
        let slope_tol = ea.abs().max(eb.abs()) * SLOPE_REL + SLOPE_ABS;
        if (ea - eb).abs().cmpgt(slope_tol).any() {
            return false;
        }
        let depth_tol = DEPTH_EPS + 1e-3 * (sa.abs() + sb.abs()).dot(DVec2::splat(1.5));
        (plane_at(&ta, at) - plane_at(&tb, at)).abs() <= depth_tol
    }

    /// The mask word of texel `k` from its four corners.
    #[must_use]
    pub fn classify(&self, k: [i64; 2], corners: [Corner; 4]) -> MaskWord {
        match self.get(k) {
            SweepTexel::Empty => return MaskWord(0),
            SweepTexel::DepthOnly => return MaskWord::new(0, Status::Unrecognised, 0, [CORNER_UNKNOWN; 4]),
            SweepTexel::Triangle(..) => {}
        }
        let codes = corners.map(|c| match c {
            Corner::Empty => CORNER_EMPTY,
            Corner::Unknown => CORNER_UNKNOWN,
            Corner::Triangle(t) => ((t[1] - k[1] + 1) * 3 + (t[0] - k[0] + 1)) as u8,
        });
        // The 3x3 slots whose stored triangles reach into the texel.
        let slots = (0..9i64).fold(0u32, |m, slot| match self.get([k[0] + slot % 3 - 1, k[1] + slot / 3 - 1]) {
            SweepTexel::Triangle(s) if packing::texel_touches(s.spsm.vertices, k, -POKE_MARGIN) => m | 1 << slot,
            _ => m,
        });
        if codes.contains(&CORNER_UNKNOWN) {
            return MaskWord::new(slots, Status::Unrecognised, 0, codes);
        }
        let centre = DVec2::new(k[0] as f64 + 0.5, k[1] as f64 + 0.5);
        // Labels: empty corners share label 4; a triangle corner takes the
        // label of the first earlier corner on its plane, else its own index.
        let mut labels = [0u32; 4];
        for q in 0..4 {
            labels[q] = match corners[q] {
                Corner::Triangle(t) => (0..q)
                    .find(|&r| matches!(corners[r], Corner::Triangle(u) if self.same_plane(u, t, centre)))
                    .map_or(q as u32, |r| labels[r]),
                _ => 4,
            };
        }
        let mut planes: Vec<u32> = labels.iter().copied().filter(|&l| l != 4).collect();
        planes.sort_unstable();
        planes.dedup();
        // Every stored triangle of the 3x3 that reaches into the texel must
        // lie on a corner plane; otherwise geometry reaching no corner pokes
        // into the texel.
        let explained = (0..9i64).filter(|slot| slots & 1 << slot != 0).all(|slot| {
            let t = [k[0] + slot % 3 - 1, k[1] + slot / 3 - 1];
            corners.iter().any(|c| matches!(c, Corner::Triangle(u) if self.same_plane(*u, t, centre)))
        });
        let status = match (planes.len(), labels.contains(&4)) {
            _ if !explained => Status::Unrecognised,
            (0, _) => Status::Unrecognised,
            (1, false) => Status::Full,
            _ => Status::Pattern,
        };
        MaskWord::new(slots, status, pattern::pattern_index(labels), codes)
    }
}

/// A corner's triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Corner {
    /// On no triangle.
    Empty,
    /// Not on a stored triangle.
    Unknown,
    /// On the triangle stored at this texel.
    Triangle([i64; 2]),
}

/// Whether `p` is inside the triangle or within `eps` texels of it.
#[must_use]
pub fn contains(t: &Stored, p: DVec2, eps: f64) -> bool {
    let v = t.spsm.vertices;
    let area = (v[1] - v[0]).perp_dot(v[2] - v[0]);
    if area.abs() < 1e-6 {
        return false;
    }
    (0..3).all(|k| {
        let (a, b) = (v[k], v[(k + 1) % 3]);
        let edge = b - a;
        area.signum() * edge.perp_dot(p - a) / edge.length() >= -eps
    })
}

/// The plane of a stored triangle at `p` (centre depth and f16 slopes).
#[must_use]
pub fn plane_at(t: &Stored, p: DVec2) -> f64 {
    t.spsm.depth + t.slopes.dot(p - t.centre)
}

/// The lookup's triangle choice for a point `p` of texel `k` whose own
/// stored triangle does not contain `p`: for a full texel its corner 0's
/// slot (the texel's one plane); for a pattern the slot of the nearest of
/// the word's participating triangles that contains `p` (`None`: the
/// lookup falls back to SPSM).
#[must_use]
pub fn choose(map: &SweepMap, word: MaskWord, k: [i64; 2], p: DVec2) -> Option<u8> {
    match word.status() {
        Status::Full => Some(word.corner(0)),
        Status::Pattern => {
            let mut best: Option<(u8, f64)> = None;
            for slot in (0..9u8).filter(|s| word.slots() & 1 << s != 0) {
                let t = [k[0] + i64::from(slot % 3) - 1, k[1] + i64::from(slot / 3) - 1];
                if let SweepTexel::Triangle(d) = map.get(t) {
                    if contains(&d, p, 0.0) {
                        let depth = plane_at(&d, p);
                        if best.is_none_or(|(_, b)| depth < b) {
                            best = Some((slot, depth));
                        }
                    }
                }
            }
            best.map(|(s, _)| s)
        }
        Status::Empty | Status::Unrecognised => None,
    }
}
