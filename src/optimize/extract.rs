//! One pass over a readback for the samples of every light: the readback
//! brought to lixel's convention ([`Grid`]), each pixel's shadowed/lit
//! classes and their 3x3 neighbourhood, and the per-pixel world point and
//! surface derivatives shared by all lights.
//!
//! The buffers live in a [`SampleWorkspace`] so that an engine extracting
//! every analysis frame reuses them ([`Samples::from_readback_all_into`]).

use glam::{DMat4, DVec2, DVec3, DVec4};

use super::samples::{PixelRect, Readback, ReadbackDepth, RowOrder, SampleOptions, Samples};
use crate::error::{LixelError, Result};
use crate::light::Light;
use crate::optimize::objective::BoundarySample;

/// Reusable buffers for sample extraction ([`Samples::from_readback_into`],
/// [`Samples::from_readback_all_into`]): the readback in lixel's convention
/// and the per-pixel classes. Holds no result between calls.
#[derive(Clone, Debug, Default)]
pub struct SampleWorkspace {
    pub(super) grid: Grid,
    classes: Classes,
    pub(super) bits: Vec<u32>,
    /// Per pixel column: its screen x and that x's term of the unprojection.
    columns: Vec<(f64, DVec4)>,
    /// Several lights: the active pixels of each band of rows.
    bands: Vec<Band>,
}

impl SampleWorkspace {
    /// An empty workspace; its buffers grow on first use.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }
}

/// Where a readback lies on the screen and how to read it in lixel's
/// convention (top-down rows, lixel depth, non-finite where nothing was
/// drawn). The readback's buffers are read in place ([`Pixels`]); only a
/// depth in another convention is converted, into `converted`.
#[derive(Clone, Debug, Default)]
pub(super) struct Grid {
    width: usize,
    height: usize,
    /// Row 0 of the readback is the bottom of the screen.
    bottom_up: bool,
    /// The depth is lixel's already (read as it is).
    lixel_depth: bool,
    /// Lixel depth of a readback in another depth convention, in the
    /// readback's own order; empty for lixel depth.
    converted: Vec<f64>,
    /// Screen position of the readback's top-left corner, full-resolution pixels.
    origin: glam::DVec2,
    /// Full-resolution pixels per readback pixel.
    step: glam::DVec2,
}

impl Grid {
    /// Places `readback` (of `camera`'s view) on the screen and converts its
    /// depth if it is not lixel's, reusing the buffer.
    pub(super) fn fill(&mut self, camera: &crate::Camera, readback: &Readback<'_>) -> Result<()> {
        use crate::conventions::DepthDirection;
        let (w, h) = (readback.width as usize, readback.height as usize);
        let layout = readback.layout;
        let viewport = camera.viewport();
        let rect = layout.rect.unwrap_or(PixelRect { x: 0, y: 0, width: viewport.x, height: viewport.y });
        let inside = rect.width > 0
            && rect.height > 0
            && u64::from(rect.x) + u64::from(rect.width) <= u64::from(viewport.x)
            && u64::from(rect.y) + u64::from(rect.height) <= u64::from(viewport.y);
        if !inside {
            return Err(LixelError::UnusableSamples { reason: "readback rectangle is empty or outside the viewport" });
        }
        let reverse = camera.conventions().depth == DepthDirection::Reverse;
        match layout.depth {
            ReadbackDepth::WindowReversed if !reverse => {
                return Err(LixelError::UnusableSamples {
                    reason: "readback depth is reverse-Z but the camera's projection is forward-Z",
                })
            }
            ReadbackDepth::Window | ReadbackDepth::GlWindow if reverse => {
                return Err(LixelError::UnusableSamples {
                    reason: "readback depth is forward-Z but the camera's projection is reverse-Z",
                })
            }
            _ => {}
        }
        let top = match layout.rows {
            RowOrder::TopDown => rect.y,
            RowOrder::BottomUp => viewport.y - rect.y - rect.height,
        };
        let to_lixel = |v: f32| -> f64 {
            let v = f64::from(v);
            if !v.is_finite() {
                return f64::NAN;
            }
            let lixel = match layout.depth {
                ReadbackDepth::Lixel => v,
                ReadbackDepth::Window if v >= 1.0 => f64::NAN,
                ReadbackDepth::WindowReversed if v <= 0.0 => f64::NAN,
                ReadbackDepth::GlWindow if v >= 1.0 => f64::NAN,
                ReadbackDepth::Window | ReadbackDepth::WindowReversed => {
                    camera.depth_at_distance(camera.distance_at_source_depth(v))
                }
                ReadbackDepth::GlWindow => camera.depth_at_distance(camera.distance_at_source_depth(2.0 * v - 1.0)),
                ReadbackDepth::LinearView => camera.depth_at_distance(v),
            };
            if lixel.is_finite() && (0.0..1.0).contains(&lixel) {
                lixel
            } else {
                f64::NAN
            }
        };
        self.width = w;
        self.height = h;
        self.bottom_up = layout.rows == RowOrder::BottomUp;
        self.origin = glam::DVec2::new(f64::from(rect.x), f64::from(top));
        self.step = glam::DVec2::new(f64::from(rect.width) / w as f64, f64::from(rect.height) / h as f64);
        self.lixel_depth = layout.depth == ReadbackDepth::Lixel;
        self.converted.clear();
        if !self.lixel_depth {
            self.converted.reserve_exact(w * h);
            self.converted.extend(readback.depth.iter().map(|&v| to_lixel(v)));
        }
        Ok(())
    }

    /// `readback` (the one given to [`Self::fill`]) as lixel reads it.
    fn pixels<'a>(&'a self, readback: &Readback<'a>) -> Pixels<'a> {
        Pixels {
            width: self.width,
            height: self.height,
            bottom_up: self.bottom_up,
            depth: if self.lixel_depth { Depth::Lixel(readback.depth) } else { Depth::Converted(&self.converted) },
            bits: readback.shadow_bits,
            normals: readback.normals,
        }
    }
}

/// A readback's buffers as they are, read in lixel's convention: pixel
/// `(x, y)` counts rows from the top of the screen.
#[derive(Clone, Copy)]
struct Pixels<'a> {
    width: usize,
    height: usize,
    bottom_up: bool,
    depth: Depth<'a>,
    bits: &'a [u32],
    normals: Option<&'a [[f32; 3]]>,
}

/// A readback's depth: lixel's own (as read back; valid in `[0, 1)`) or
/// converted to it (non-finite where nothing was drawn).
#[derive(Clone, Copy)]
enum Depth<'a> {
    Lixel(&'a [f32]),
    Converted(&'a [f64]),
}

impl Pixels<'_> {
    /// The index in the readback's buffers of the first pixel of row `y`
    /// (from the top).
    #[inline]
    fn row_start(&self, y: usize) -> usize {
        (if self.bottom_up { self.height - 1 - y } else { y }) * self.width
    }

    /// Lixel depth at buffer index `i`, NaN where nothing was drawn (the
    /// same bits as converting the whole readback to `f64` first).
    #[inline]
    fn depth(&self, i: usize) -> f64 {
        match self.depth {
            Depth::Lixel(depth) => {
                let v = f64::from(depth[i]);
                if (0.0..1.0).contains(&v) {
                    v
                } else {
                    f64::NAN
                }
            }
            Depth::Converted(depth) => depth[i],
        }
    }

    /// Row `y`'s pixels (from the top) as bits: each run of 64 pixels as one
    /// word of covered pixels and one of those covered whose shadow bit `bit`
    /// (below 32) is set, pixel `64 k + j` at bit `j` of word `k`.
    fn row_words(&self, y: usize, bit: u32, push: impl FnMut(u64, u64)) {
        let start = self.row_start(y);
        let bits = &self.bits[start..][..self.width];
        match self.depth {
            // `(0.0..1.0).contains` on the `f32` is the same test as on its
            // exact `f64`.
            Depth::Lixel(depth) => pack_lixel_row(&depth[start..][..self.width], bits, bit, push),
            Depth::Converted(depth) => {
                pack_row(&depth[start..][..self.width], bits, 1 << (bit & 31), f64::is_finite, push);
            }
        }
    }

    /// Row `y`'s pixels (from the top): whether each is covered, and its shadow bits.
    fn row_pixels(&self, y: usize, mut each: impl FnMut(bool, u32)) {
        let start = self.row_start(y);
        let bits = &self.bits[start..][..self.width];
        match self.depth {
            Depth::Lixel(depth) => {
                for (&d, &b) in depth[start..][..self.width].iter().zip(bits) {
                    each((0.0..1.0).contains(&d), b);
                }
            }
            Depth::Converted(depth) => {
                for (&d, &b) in depth[start..][..self.width].iter().zip(bits) {
                    each(d.is_finite(), b);
                }
            }
        }
    }
}

/// [`Pixels::row_words`] over a row of lixel depth (valid in `[0, 1)`):
/// sixteen pixels a step with SSE2 on x86-64 ([`sse2::pack_row`]), the
/// portable [`pack_row`] elsewhere. Both give the same words (unit test
/// `sse2_pack_equals_the_portable_pack`).
#[inline(always)]
fn pack_lixel_row(depth: &[f32], bits: &[u32], bit: u32, push: impl FnMut(u64, u64)) {
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
    {
        #[allow(unsafe_code)]
        // SAFETY: `sse2::pack_row` requires SSE2 only, and this build has it
        // (`cfg(target_feature = "sse2")` above; every x86-64 CPU has it). It
        // takes no pointers: its memory accesses are safe Rust.
        unsafe {
            sse2::pack_row(depth, bits, bit, push);
        }
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "sse2")))]
    pack_row(depth, bits, 1 << (bit & 31), |d| (0.0..1.0).contains(&d), push);
}

/// The per-pixel pass of one light's extraction with SSE2: four pixels a
/// vector compare, sixteen pixels' bits by one `pmovmskb`. The intrinsics
/// used take no pointers (the loads are `_mm_setr_*` of array elements,
/// which LLVM merges into one unaligned load), so the only `unsafe` is the
/// call into the `#[target_feature]` function ([`pack_lixel_row`]).
#[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
mod sse2 {
    use std::arch::x86_64::{
        __m128i, _mm_and_ps, _mm_and_si128, _mm_castps_si128, _mm_cmple_ps, _mm_cmplt_ps, _mm_cvtsi32_si128,
        _mm_movemask_epi8, _mm_packs_epi16, _mm_packs_epi32, _mm_set1_ps, _mm_setr_epi32, _mm_setr_ps, _mm_setzero_ps,
        _mm_sll_epi32,
    };

    /// Sixteen pixels: bit `i` of the low half is pixel `i` covered (its
    /// depth in `[0, 1)`: `0 <= d` and `d < 1`, both false for NaN, as
    /// `(0.0..1.0).contains`), of the high half covered with the shadow bit
    /// that a left shift by `shift` (in its low 64 bits) moves to bit 31.
    #[target_feature(enable = "sse2")]
    #[inline]
    fn pack16(depth: &[f32; 16], bits: &[u32; 16], shift: __m128i) -> u32 {
        let (zero, one) = (_mm_setzero_ps(), _mm_set1_ps(1.0));
        let covered = |i: usize| {
            let d = _mm_setr_ps(depth[i], depth[i + 1], depth[i + 2], depth[i + 3]);
            _mm_castps_si128(_mm_and_ps(_mm_cmple_ps(zero, d), _mm_cmplt_ps(d, one)))
        };
        // The shadow bit moved to the sign (one shift instead of a mask
        // and a compare with zero).
        let shadow = |i: usize| {
            let b = _mm_setr_epi32(
                bits[i].cast_signed(),
                bits[i + 1].cast_signed(),
                bits[i + 2].cast_signed(),
                bits[i + 3].cast_signed(),
            );
            _mm_sll_epi32(b, shift)
        };
        // Narrowed to bytes with signed saturation, which keeps each lane's
        // sign (all-ones or zero lanes stay all-ones or zero), in pixel
        // order; `pmovmskb` reads the signs.
        let covered =
            _mm_packs_epi16(_mm_packs_epi32(covered(0), covered(4)), _mm_packs_epi32(covered(8), covered(12)));
        let shadow = _mm_packs_epi16(_mm_packs_epi32(shadow(0), shadow(4)), _mm_packs_epi32(shadow(8), shadow(12)));
        let shadowed = _mm_and_si128(shadow, covered);
        _mm_movemask_epi8(covered).cast_unsigned() | _mm_movemask_epi8(shadowed).cast_unsigned() << 16
    }

    /// [`super::pack_row`] for lixel depth: each run of 64 pixels as one word
    /// of covered pixels and one of those with shadow bit `bit` (below 32;
    /// `bit & 31` is read) set.
    #[target_feature(enable = "sse2")]
    pub(super) fn pack_row(depth: &[f32], bits: &[u32], bit: u32, mut push: impl FnMut(u64, u64)) {
        let shift = _mm_cvtsi32_si128((31 - (bit & 31)).cast_signed());
        let sixteen =
            |d: &[f32], b: &[u32]| pack16(d.try_into().expect("16 pixels"), b.try_into().expect("16 pixels"), shift);
        let (mut depth64, mut bits64) = (depth.chunks_exact(64), bits.chunks_exact(64));
        for (d, b) in (&mut depth64).zip(&mut bits64) {
            let (mut covered, mut shadowed) = (0u64, 0u64);
            for (k, (d, b)) in d.chunks_exact(16).zip(b.chunks_exact(16)).enumerate() {
                let both = sixteen(d, b);
                covered |= u64::from(both & 0xffff) << (16 * k);
                shadowed |= u64::from(both >> 16) << (16 * k);
            }
            push(covered, shadowed);
        }
        // The row's last word, when the row does not end on 64 pixels.
        let (d, b) = (depth64.remainder(), bits64.remainder());
        if d.is_empty() {
            return;
        }
        let (mut covered, mut shadowed, mut at) = (0u64, 0u64, 0);
        let (mut depth16, mut bits16) = (d.chunks_exact(16), b.chunks_exact(16));
        for (d, b) in (&mut depth16).zip(&mut bits16) {
            let both = sixteen(d, b);
            covered |= u64::from(both & 0xffff) << at;
            shadowed |= u64::from(both >> 16) << at;
            at += 16;
        }
        let rest = depth16.remainder().len();
        if rest > 0 {
            // The last `rest` pixels: the row's last sixteen (overlapping
            // pixels already packed) shifted down to them, or, in a row
            // narrower than sixteen, the row padded with uncovered pixels
            // (NaN depth, no shadow bits).
            let n = depth.len();
            let both = if n >= 16 {
                let both = sixteen(&depth[n - 16..], &bits[n - 16..]);
                (both & 0xffff) >> (16 - rest) | (both >> 16 >> (16 - rest)) << 16
            } else {
                let (mut d, mut b) = ([f32::NAN; 16], [0u32; 16]);
                d[..n].copy_from_slice(depth);
                b[..n].copy_from_slice(bits);
                sixteen(&d, &b)
            };
            covered |= u64::from(both & 0xffff) << at;
            shadowed |= u64::from(both >> 16) << at;
        }
        push(covered, shadowed);
    }
}

/// [`Pixels::row_words`] over one row's depth and shadow bits: a byte per
/// pixel first (a loop without dependences, so it vectorizes), then eight
/// bytes to eight bits by one multiply.
#[inline(always)]
fn pack_row<T: Copy>(depth: &[T], bits: &[u32], mask: u32, valid: impl Fn(T) -> bool, mut push: impl FnMut(u64, u64)) {
    for (depth, bits) in depth.chunks(64).zip(bits.chunks(64)) {
        let (mut covered, mut shadowed) = ([0u8; 64], [0u8; 64]);
        for ((c, s), (&d, &b)) in covered.iter_mut().zip(&mut shadowed).zip(depth.iter().zip(bits)) {
            let ok = u8::from(valid(d));
            *c = ok;
            *s = ok & u8::from(b & mask != 0);
        }
        push(pack_bytes(&covered), pack_bytes(&shadowed));
    }
}

/// Bit 0 of byte `i` of `bytes` (each 0 or 1) as bit `i` of a `u64`.
#[inline(always)]
fn pack_bytes(bytes: &[u8; 64]) -> u64 {
    bytes.chunks_exact(8).enumerate().fold(0, |word, (k, eight)| {
        let eight = u64::from_le_bytes(eight.try_into().expect("eight bytes"));
        // Byte `i`'s bit 0 (bit `8 i`) lands on bit `56 + i`, with no
        // carries when every byte is 0 or 1.
        word | (eight.wrapping_mul(0x0102_0408_1020_4080) >> 56) << (8 * k)
    })
}

/// The buffers match the readback's size.
pub(super) fn check_readback(readback: &Readback<'_>) -> Result<()> {
    let n = readback.width as usize * readback.height as usize;
    if readback.depth.len() != n
        || readback.shadow_bits.len() != n
        || readback.normals.is_some_and(|normals| normals.len() != n)
    {
        return Err(LixelError::UnusableSamples { reason: "readback buffers do not match its size" });
    }
    Ok(())
}

/// Each item of row `s` ORed with its left and right neighbours (clamped at
/// the edges), into `t`.
fn or_row<T: Copy + std::ops::BitOr<Output = T>>(s: &[T], t: &mut [T]) {
    let w = s.len();
    if w < 3 {
        for x in 0..w {
            t[x] = s[x.saturating_sub(1)] | s[x] | s[(x + 1).min(w - 1)];
        }
        return;
    }
    // The edges clamped, the interior as three shifted slices (no index
    // arithmetic per pixel, so it vectorizes).
    t[0] = s[0] | s[1];
    t[w - 1] = s[w - 2] | s[w - 1];
    for (((t, &l), &c), &r) in t[1..w - 1].iter_mut().zip(&s[..w - 2]).zip(&s[1..w - 1]).zip(&s[2..]) {
        *t = l | c | r;
    }
}

/// A row of bits with each bit ORed with its left and right neighbours:
/// `word` is pixels `64 k ..`, `prev` and `next` the words beside it (zero
/// past the row's ends, where the clamped neighbour is the pixel itself).
#[inline(always)]
fn spread(prev: u64, word: u64, next: u64) -> u64 {
    word | word << 1 | prev >> 63 | word >> 1 | next << 63
}

/// One light's boundary pixels into `mixed`: the covered pixels with a
/// shadowed and a lit pixel in their 3x3 neighbourhood (clamped at the
/// edges). `covered` and `shadowed` are bit images of `h` rows of `words`
/// words, `w` pixels a row (pixel `64 k + j` of a row at bit `j` of its
/// word `k`; the bits beyond the row's pixels zero). The 3x3 OR is the OR
/// across rows of the spread along the row (shifts distribute over OR), so
/// one pass spreads the shadowed and the lit bits along the rows together,
/// into `near`, and a second ORs three rows of both and masks them with
/// `covered`: the same bits as `covered & or_3x3(shadowed) & or_3x3(lit)`,
/// without their separate passes and buffers, and with no loop per row
/// where it can be avoided (a light's image at 180x180 has three words a
/// row, so the per-row work cost more than the words' own).
fn boundary_bits(
    covered: &[u64],
    shadowed: &[u64],
    w: usize,
    words: usize,
    h: usize,
    near: &mut Vec<[u64; 2]>,
    mixed: &mut Vec<u64>,
) {
    let n = covered.len().min(shadowed.len());
    near.clear();
    near.resize(n, [0; 2]);
    let both = |i: usize| match (covered.get(i), shadowed.get(i)) {
        (Some(&c), Some(&s)) => [s, c & !s],
        _ => [0; 2],
    };
    if !w.is_multiple_of(64) {
        // Every word spread with the words before and after it in the
        // buffer, across rows too: a row's pixels end before bit 63 of its
        // last word, so the row before carries in nothing (its bits beyond
        // its pixels are clear), and what the row after carries in lands
        // beyond this row's pixels, where `covered` clears it below.
        let (mut prev, mut here) = ([0; 2], both(0));
        for (i, out) in near.iter_mut().enumerate() {
            let next = both(i + 1);
            *out = [spread(prev[0], here[0], next[0]), spread(prev[1], here[1], next[1])];
            (prev, here) = (here, next);
        }
    } else {
        // Whole words a row: the words beyond a row's ends are none.
        for (y, out) in near.chunks_exact_mut(words).enumerate() {
            let (mut prev, mut here) = ([0; 2], both(y * words));
            for (k, out) in out.iter_mut().enumerate() {
                let next = if k + 1 < words { both(y * words + k + 1) } else { [0; 2] };
                *out = [spread(prev[0], here[0], next[0]), spread(prev[1], here[1], next[1])];
                (prev, here) = (here, next);
            }
        }
    }
    mixed.clear();
    mixed.resize(n, 0);
    if n == 0 || h == 0 {
        return;
    }
    let or3 = |c: u64, a: &[u64; 2], m: &[u64; 2], b: &[u64; 2]| c & (a[0] | m[0] | b[0]) & (a[1] | m[1] | b[1]);
    // The rows between the first and the last: the rows above and below
    // are the words `words` before and after, so the whole stretch is
    // three shifted slices (no loop per row).
    if h >= 3 {
        let inner = words..n - words;
        for ((((out, &c), a), m), b) in mixed[inner.clone()]
            .iter_mut()
            .zip(&covered[inner.clone()])
            .zip(&near[..n - 2 * words])
            .zip(&near[inner])
            .zip(&near[2 * words..])
        {
            *out = or3(c, a, m, b);
        }
    }
    // The first and the last row, their missing neighbour clamped to
    // themselves.
    for y in [0, h - 1] {
        let row = |y: usize| &near[y * words..][..words];
        let (above, here, below) = (row(y.saturating_sub(1)), row(y), row((y + 1).min(h - 1)));
        let rows = y * words..(y + 1) * words;
        for ((((out, &c), a), m), b) in
            mixed[rows.clone()].iter_mut().zip(&covered[rows]).zip(above).zip(here).zip(below)
        {
            *out = or3(c, a, m, b);
        }
    }
}

/// Per pixel and light slot `k` (the `k`-th light extracted): shadowed, and
/// lit, over covered pixels; and the OR of both over the 3x3 neighbourhood,
/// so a slot both shadowed and lit nearby marks a shadow boundary. One light
/// packs into bit images (a bit per pixel, 64 pixels a word); up to 32 into
/// a `u64` per pixel (shadowed slots in the low half, lit in the high half),
/// so one pass serves every light.
#[derive(Clone, Debug, Default)]
struct Classes {
    /// One light (bit images) or several (`u64`s).
    one: bool,
    /// One light: words per row.
    words: usize,
    /// One light: covered pixels.
    covered: Vec<u64>,
    /// One light: shadowed pixels.
    shadowed: Vec<u64>,
    /// One light: boundary pixels (covered, with shadowed and lit pixels in
    /// their 3x3 neighbourhood).
    mixed: Vec<u64>,
    /// One light: scratch (the shadowed and the lit bits spread along the
    /// rows, see [`boundary_bits`]).
    near: Vec<[u64; 2]>,
    /// Several lights: per pixel, shadowed slots (low half) and lit slots
    /// (high half).
    class64: Vec<u64>,
    /// Several lights: `class64` ORed along rows (see [`or_row`]); the 3x3
    /// OR is this row's and its neighbours' OR ([`Classes::row`]).
    hor64: Vec<u64>,
}

impl Classes {
    /// The classes of `pixels` for the light bits `bits` (slot `k` is
    /// `bits[k]`); several lights' are filled in bands of `band_rows` rows.
    fn fill(&mut self, pixels: &Pixels<'_>, bits: &[u32], band_rows: usize) {
        let (w, h) = (pixels.width, pixels.height);
        if let [bit] = *bits {
            self.one = true;
            let words = w.div_ceil(64);
            self.words = words;
            let (covered, shadowed) = (&mut self.covered, &mut self.shadowed);
            // Every word is written: a buffer of the right size is reused as
            // it is, and each row's words go in place (no capacity checks).
            covered.resize(words * h, 0);
            shadowed.resize(words * h, 0);
            for (y, (covered, shadowed)) in
                covered.chunks_exact_mut(words).zip(shadowed.chunks_exact_mut(words)).enumerate()
            {
                let mut words = covered.iter_mut().zip(shadowed.iter_mut());
                pixels.row_words(y, bit, |c, s| {
                    if let Some((covered, shadowed)) = words.next() {
                        (*covered, *shadowed) = (c, s);
                    }
                });
            }
            boundary_bits(covered, shadowed, w, words, h, &mut self.near, &mut self.mixed);
            return;
        }
        self.one = false;
        // `fill_classes` writes every cell: a buffer of the right size is
        // reused as it is (zeroing half a megabyte at 180x180 first cost
        // more than the rest of the class fill).
        for buffer in [&mut self.class64, &mut self.hor64] {
            buffer.resize(w * h, 0);
        }
        // In bands of `band_rows` rows (in parallel with rayon): a row's
        // classes and their OR along the row depend on that row only.
        let fill = |(band, (class, hor)): (usize, (&mut [u64], &mut [u64]))| {
            fill_classes(pixels, bits, band * band_rows, class, hor);
        };
        #[cfg(feature = "rayon")]
        {
            use rayon::prelude::*;
            self.class64
                .par_chunks_mut(band_rows * w)
                .zip(self.hor64.par_chunks_mut(band_rows * w))
                .enumerate()
                .for_each(fill);
        }
        #[cfg(not(feature = "rayon"))]
        self.class64.chunks_mut(band_rows * w).zip(self.hor64.chunks_mut(band_rows * w)).enumerate().for_each(fill);
    }

    /// Several lights: row `y`'s classes, and for each of its pixels the OR
    /// of the classes over its 3x3 neighbourhood (clamped at the edges).
    #[inline]
    fn row(&self, y: usize, w: usize, h: usize) -> (&[u64], impl Iterator<Item = u64> + '_) {
        let row = |y: usize| &self.hor64[y * w..][..w];
        let (above, here, below) = (row(y.saturating_sub(1)), row(y), row((y + 1).min(h - 1)));
        let near = above.iter().zip(here).zip(below).map(|((&a, &m), &b)| a | m | b);
        (&self.class64[y * w..][..w], near)
    }
}

/// Several lights' classes (see [`Classes`]) of the rows from `y0`, into
/// `class` (whole rows) and their OR along each row into `hor`.
fn fill_classes(pixels: &Pixels<'_>, bits: &[u32], y0: usize, class: &mut [u64], hor: &mut [u64]) {
    let w = pixels.width;
    // Slot `k` is bit `k` (what every caller passes): the classes are the
    // masked bits and their complement, without a loop.
    let identity = bits.iter().enumerate().all(|(k, &bit)| bit as usize == k);
    let mask = if bits.len() >= 32 { u32::MAX } else { (1u32 << bits.len()) - 1 };
    for (dy, (class, hor)) in class.chunks_exact_mut(w).zip(hor.chunks_exact_mut(w)).enumerate() {
        let mut cells = class.iter_mut();
        pixels.row_pixels(y0 + dy, |valid, b| {
            let cell = cells.next().expect("a cell per pixel");
            *cell = match (valid, identity) {
                (false, _) => 0,
                (true, true) => u64::from(b & mask) | u64::from(!b & mask) << 32,
                (true, false) => bits
                    .iter()
                    .enumerate()
                    .fold(0u64, |c, (k, &bit)| c | if b >> bit & 1 != 0 { 1 << k } else { 1 << (k + 32) }),
            };
        });
        or_row(class, hor);
    }
}

/// Fills `all[k]` (already reset to their bodies, no samples) from
/// `readback` (placed by `workspace.grid`) for light bit `workspace.bits[k]`
/// (at most 32 lights), in one pass over the pixels.
pub(super) fn extract(
    all: &mut [Samples],
    workspace: &mut SampleWorkspace,
    readback: &Readback<'_>,
    options: &SampleOptions,
) {
    let SampleWorkspace { grid, classes, bits, columns, bands } = workspace;
    let grid = &*grid;
    let pixels = grid.pixels(readback);
    let (w, h) = (grid.width, grid.height);
    let n = w * h;
    if n == 0 || all.is_empty() {
        return;
    }
    // Every light's problem shares the camera (the readback is its view).
    let camera = *all[0].problem.camera();
    let world_from_screen = camera.screen_from_world().inverse();
    let step = grid.step;
    let m = world_from_screen;
    columns.clear();
    columns.extend((0..w).map(|x| {
        let sx = grid.origin.x + (x as f64 + 0.5) * step.x;
        (sx, m.x_axis * sx)
    }));
    // Each light's `X~ = T [x; w]` rows, made once rather than per pixel
    // (`LightFrame::homogeneous4` rebuilds them on every call).
    let mut rows = [[DVec4::ZERO; 3]; 32];
    for (rows, samples) in rows.iter_mut().zip(all.iter()) {
        *rows = samples.frame.light_from_world_3x4_rows();
    }
    // Several lights are worked in bands of rows (one per thread with rayon,
    // twice as many for balance). One light does not touch rayon (its first
    // use starts the thread pool).
    let band_count = {
        #[cfg(feature = "rayon")]
        {
            if bits.len() > 1 {
                (2 * rayon::current_num_threads()).clamp(1, h)
            } else {
                1
            }
        }
        #[cfg(not(feature = "rayon"))]
        {
            1
        }
    };
    let band_rows = h.div_ceil(band_count);
    classes.fill(&pixels, bits, band_rows);
    let classes = &*classes;
    // The camera's side of every surface (`Camera::towards_viewer`, with
    // the eye made once rather than per boundary pixel: the same bits).
    let viewer =
        if camera.is_orthographic() { Viewer::Direction(-camera.view_direction()) } else { Viewer::Eye(camera.eye()) };
    let work = PixelWork { pixels, world_from_screen, viewer, options, step, rows };
    if classes.one {
        // One light: its classes as bit images, so that runs without an
        // active pixel cost a few instructions per 64 pixels; then only the
        // active pixels are visited, in pixel order.
        let words = classes.words;
        let (mut covered, mut shadowed, mut relevant, mut boundary) = (0usize, 0usize, 0usize, 0usize);
        for ((&c, &s), &b) in classes.covered.iter().zip(&classes.shadowed).zip(&classes.mixed) {
            covered += c.count_ones() as usize;
            shadowed += s.count_ones() as usize;
            relevant += (s | b).count_ones() as usize;
            boundary += b.count_ones() as usize;
        }
        // Exact capacities first (a fresh `Samples` would otherwise grow
        // each list a dozen times, copying it each time).
        let samples = &mut all[0];
        samples.relevant.reserve_exact(relevant);
        samples.relevant_world.reserve_exact(relevant);
        samples.boundary.reserve_exact(boundary);
        samples.boundary_world.reserve_exact(boundary);
        for y in 0..h {
            let sy = grid.origin.y + (y as f64 + 0.5) * step.y;
            let row = m.y_axis * sy;
            let start = pixels.row_start(y);
            let range = y * words..(y + 1) * words;
            for (k, (&shadow, &mixed)) in classes.shadowed[range.clone()].iter().zip(&classes.mixed[range]).enumerate()
            {
                let mut active = shadow | mixed;
                while active != 0 {
                    let j = active.trailing_zeros();
                    active &= active - 1;
                    let x = 64 * k + j as usize;
                    let (sx, column) = columns[x];
                    // Active: shadowed, or at a boundary (then also relevant).
                    let boundary = mixed >> j & 1 != 0;
                    let mut surface = None;
                    let point = work
                        .point_at::<true>((x, y, start + x), (sx, sy), row, column, boundary, |found| surface = found);
                    let samples = &mut all[0];
                    match point {
                        None => samples.counts.rejected_invalid += 1,
                        Some((here, world)) if boundary => work.boundary(samples, 0, here, world, surface.as_ref()),
                        Some((here, world)) => work.relevant(samples, 0, here, world),
                    }
                }
            }
        }
        all[0].counts.covered += covered;
        all[0].counts.shadowed += shadowed;
        return;
    }
    // Several lights: first the light-independent work of every pixel
    // active for some light (its world point and surface), in bands of
    // rows (one per thread with rayon), into `bands`; then each light's
    // samples from those pixels, in pixel order (with rayon, the lights
    // split between threads). So each pixel is unprojected once, whatever
    // the number of threads, and each light's lists are those of a single
    // pass.
    bands.resize_with(h.div_ceil(band_rows), Band::default);
    let collect = |(b, band): (usize, &mut Band)| {
        band.active.clear();
        band.surfaces.clear();
        band.covered = 0;
        let rows = b * band_rows..((b + 1) * band_rows).min(h);
        if band.active.capacity() == 0 {
            // A fresh workspace (every `from_readback_all`): a first guess
            // at the band's active pixels, an eighth of its pixels, so that
            // the lists do not start at a few entries and get copied a
            // dozen times as they grow (counting them exactly first cost
            // as much as the copies). A reused workspace has grown to fit.
            let pixels = rows.len() * w;
            band.active.reserve(pixels / 8);
            band.surfaces.reserve(pixels / 32);
        }
        for y in rows {
            let sy = grid.origin.y + (y as f64 + 0.5) * step.y;
            let row = m.y_axis * sy;
            let start = pixels.row_start(y);
            let (class, near) = classes.row(y, w, h);
            for ((x, &(sx, column)), (&class, near)) in columns.iter().enumerate().zip(class.iter().zip(near)) {
                // A covered pixel is shadowed or lit for every slot (there is
                // one at least).
                if class == 0 {
                    continue;
                }
                let (shadowed, mixed) = (class as u32, near as u32 & (near >> 32) as u32);
                band.covered += 1;
                if shadowed | mixed == 0 {
                    continue;
                }
                let surfaces = &mut band.surfaces;
                let point = work.point_at::<false>((x, y, start + x), (sx, sy), row, column, mixed != 0, |found| {
                    surfaces.push(found)
                });
                let (here, world) = point.unwrap_or((DVec4::NAN, DVec3::NAN));
                band.active.push(Active { shadowed, mixed, here, world });
            }
        }
    };
    // The slots `first..first + all.len()` (all of them, or one thread's
    // share) from the bands' active pixels.
    let scan = |all: &mut [Samples], first: usize, bands: &[Band]| {
        // Slots beyond `all` (none from the callers) are ignored.
        let slots = if all.len() >= 32 { u32::MAX } else { ((1u32 << all.len()) - 1) << first };
        let active = || bands.iter().flat_map(|band| &band.active);
        // A fresh `Samples` (no capacity yet) gets its lists' exact sizes
        // first (reused samples have grown to fit already, and counting
        // costs a loop over the set bits).
        let fresh = all
            .iter()
            .enumerate()
            .fold(0u32, |fresh, (k, samples)| fresh | u32::from(samples.relevant.capacity() == 0) << (first + k))
            & slots;
        if fresh != 0 {
            let (mut relevant, mut boundary) = ([0usize; 32], [0usize; 32]);
            for pixel in active().filter(|pixel| pixel.is_valid()) {
                for bit in set_bits((pixel.shadowed | pixel.mixed) & fresh) {
                    relevant[bit] += 1;
                }
                for bit in set_bits(pixel.mixed & fresh) {
                    boundary[bit] += 1;
                }
            }
            for bit in set_bits(fresh) {
                let samples = &mut all[bit - first];
                samples.relevant.reserve_exact(relevant[bit]);
                samples.relevant_world.reserve_exact(relevant[bit]);
                samples.boundary.reserve_exact(boundary[bit]);
                samples.boundary_world.reserve_exact(boundary[bit]);
            }
        }
        // Counted here and added at the end: the counts are the same, without
        // a loop over every light at every pixel.
        let mut shadowed = [0usize; 32];
        for band in bands {
            // The band's surfaces, one per valid pixel with a boundary slot
            // (of any share), in the same order.
            let mut surfaces = band.surfaces.iter();
            for pixel in &band.active {
                let valid = pixel.is_valid();
                let surface = if valid && pixel.mixed != 0 {
                    surfaces.next().expect("a surface per valid boundary pixel").as_ref()
                } else {
                    None
                };
                let (shadowed_bits, mixed_bits) = (pixel.shadowed & slots, pixel.mixed & slots);
                if shadowed_bits | mixed_bits == 0 {
                    continue;
                }
                for bit in set_bits(shadowed_bits) {
                    shadowed[bit] += 1;
                }
                work.emit(all, first, valid.then_some((pixel.here, pixel.world)), surface, shadowed_bits, mixed_bits);
            }
        }
        let covered: usize = bands.iter().map(|band| band.covered).sum();
        for (samples, &shadowed) in all.iter_mut().zip(&shadowed[first..]) {
            samples.counts.covered += covered;
            samples.counts.shadowed += shadowed;
        }
    };
    #[cfg(feature = "rayon")]
    {
        use rayon::prelude::*;
        bands.par_iter_mut().enumerate().for_each(collect);
        let bands = &*bands;
        let threads = rayon::current_num_threads().min(all.len());
        if threads > 1 {
            let chunk = all.len().div_ceil(threads);
            all.par_chunks_mut(chunk).enumerate().for_each(|(c, part)| scan(part, c * chunk, bands));
            return;
        }
        scan(all, 0, bands);
    }
    #[cfg(not(feature = "rayon"))]
    {
        bands.iter_mut().enumerate().for_each(collect);
        scan(all, 0, bands);
    }
}

/// What the work at a pixel needs: the readback, the unprojection, each
/// light's `X~ = T [x; w]` rows (made once rather than per pixel:
/// `LightFrame::homogeneous4` rebuilds them on every call).
struct PixelWork<'a> {
    pixels: Pixels<'a>,
    world_from_screen: DMat4,
    /// The camera's side of every surface.
    viewer: Viewer,
    options: &'a SampleOptions,
    /// Full-resolution pixels per readback pixel.
    step: DVec2,
    rows: [[DVec4; 3]; 32],
}

impl PixelWork<'_> {
    /// The light-independent work at one covered pixel with an active slot
    /// (shadowed or at a shadow boundary): its world point (homogeneous,
    /// `w > 0`, and dehomogenised), and its surface derivatives when some
    /// slot has a boundary there (`mixed`), given to `surface` (`None` at a
    /// depth discontinuity); `None` where the point is not finite or behind
    /// the eye (and `surface` is not called). `i` is pixel `(x, y)`'s index in
    /// the readback's buffers; `row` and `column` are its terms of the
    /// unprojection. (The surface goes to a callback
    /// rather than into the result: a result that large is moved with
    /// `memcpy` calls.) With `INLINE`, [`surface_at`] is inlined here (one
    /// light's scan: −3% of one light's extraction and optimization);
    /// otherwise it is called (several lights' bands, where inlining it cost
    /// +0.8% of the 32 lights' instructions).
    #[inline(always)]
    fn point_at<const INLINE: bool>(
        &self,
        (x, y, i): (usize, usize, usize),
        (sx, sy): (f64, f64),
        row: DVec4,
        column: DVec4,
        mixed: bool,
        surface: impl FnOnce(Option<Surface>),
    ) -> Option<(DVec4, DVec3)> {
        let pixels = &self.pixels;
        let d = pixels.depth(i);
        // Homogeneous world point of screen (x1, x2, depth), scaled to w > 0:
        // `world_from_screen * [sx, sy, d, 1]` summed in glam's order (x, y,
        // z, w columns), with the column's and the row's terms made once
        // each (the same products, so the same bits; `w_axis * 1.0` is
        // `w_axis`).
        let m = &self.world_from_screen;
        let here = column + row + m.z_axis * d + m.w_axis;
        let here = if here.w < 0.0 { -here } else { here };
        if !(here.w > 0.0) || !here.is_finite() {
            return None;
        }
        let world = here.truncate() / here.w;
        if mixed {
            let (viewer, options, step) = (self.viewer, self.options, self.step);
            surface(if INLINE {
                surface_at(pixels, m, viewer, options, (x, y), i, (sx, sy, d), here, world, step)
            } else {
                surface_at_called(pixels, m, viewer, options, (x, y), i, (sx, sy, d), here, world, step)
            });
        }
        Some((here, world))
    }

    /// The per-light work at that pixel, in pixel order: the relevant
    /// samples of the slots shadowed or at a boundary there, and the
    /// boundary samples of the slots in `mixed_bits` (`all` is the slots
    /// from `first`).
    #[inline(always)]
    fn emit(
        &self,
        all: &mut [Samples],
        first: usize,
        point: Option<(DVec4, DVec3)>,
        surface: Option<&Surface>,
        shadowed_bits: u32,
        mixed_bits: u32,
    ) {
        let Some((here, world)) = point else {
            for bit in set_bits(shadowed_bits | mixed_bits) {
                all[bit - first].counts.rejected_invalid += 1;
            }
            return;
        };
        // Each slot's lists are its own, so the slots without a boundary
        // here (only relevant samples) go first, in a loop of their own.
        for bit in set_bits(shadowed_bits & !mixed_bits) {
            self.relevant(&mut all[bit - first], bit, here, world);
        }
        for bit in set_bits(mixed_bits) {
            self.boundary(&mut all[bit - first], bit, here, world, surface);
        }
    }

    /// Slot `slot`'s relevant sample at a pixel where it has no boundary.
    #[inline(always)]
    fn relevant(&self, samples: &mut Samples, slot: usize, here: DVec4, world: DVec3) {
        samples.relevant.push(to_light(&self.rows[slot], here));
        samples.relevant_world.push(world);
    }

    /// Slot `slot`'s relevant sample and boundary candidate at a pixel where
    /// it has a boundary.
    #[inline(always)]
    fn boundary(&self, samples: &mut Samples, slot: usize, here: DVec4, world: DVec3, surface: Option<&Surface>) {
        let rows = &self.rows[slot];
        let x_light = to_light(rows, here);
        samples.relevant.push(x_light);
        samples.relevant_world.push(world);
        samples.counts.boundary_candidates += 1;
        let Some(&found) = surface else {
            samples.counts.rejected_discontinuity += 1;
            return;
        };
        let sample = match found {
            Surface::Given { tx, ty, .. } => {
                let along = |t: DVec3| to_light(rows, t.extend(0.0));
                BoundarySample { light: samples.frame.homogeneous(world), d_dx: along(tx), d_dy: along(ty) }
            }
            // Where the raw homogeneous point had `w < 0`, `x_light` is the
            // flipped point while `dx4`/`dy4` keep their raw sign: that turns
            // the sample's Jacobian into `−J`; the badness (`‖J‖²/det²`) is
            // even in `J` and its gradient through the derivatives unchanged,
            // so it is harmless (issue-15 note, session 14, coordinator).
            Surface::Depth { dx4, dy4, .. } => {
                BoundarySample { light: x_light, d_dx: to_light(rows, dx4), d_dy: to_light(rows, dy4) }
            }
        };
        if !faces_light(samples.problem.light(), world, found.normal(), self.options.min_light_cosine) {
            samples.counts.rejected_back_facing += 1;
            return;
        }
        samples.boundary.push(sample);
        samples.boundary_world.push(world);
    }
}

/// A light's `X~ = T [x; w]` from its rows.
#[inline(always)]
fn to_light(rows: &[DVec4; 3], x: DVec4) -> DVec3 {
    DVec3::new(rows[0].dot(x), rows[1].dot(x), rows[2].dot(x))
}

/// A pixel active for some light, with its world point (its surface, where
/// some slot has a boundary, is in [`Band::surfaces`]: kept apart, an active
/// pixel is 64 bytes instead of 160, and each share of the lights reads
/// every active pixel).
#[derive(Clone, Copy, Debug)]
struct Active {
    /// Slots shadowed there.
    shadowed: u32,
    /// Slots with a shadow boundary there.
    mixed: u32,
    /// The homogeneous world point (`w > 0`); NaN where the point is not finite or behind the eye
    /// (see [`Self::is_valid`]).
    here: DVec4,
    /// The world point.
    world: DVec3,
}

impl Active {
    /// The point is finite and in front of the eye (`here.w > 0`).
    #[inline]
    fn is_valid(&self) -> bool {
        self.here.w > 0.0
    }
}

/// A band of rows' active pixels, in pixel order, and its covered pixels.
#[derive(Clone, Debug, Default)]
pub(super) struct Band {
    active: Vec<Active>,
    /// The surface of each valid active pixel with a boundary slot, in
    /// pixel order.
    surfaces: Vec<Option<Surface>>,
    covered: usize,
}

/// Where the camera is seen from a surface point ([`crate::Camera::towards_viewer`]).
#[derive(Clone, Copy)]
enum Viewer {
    /// Orthographic: the same direction everywhere.
    Direction(DVec3),
    /// Perspective: the eye.
    Eye(DVec3),
}

impl Viewer {
    fn towards(self, world: DVec3) -> DVec3 {
        match self {
            Self::Direction(d) => d,
            Self::Eye(eye) => eye - world,
        }
    }
}

/// The indices of the bits set in `mask`, lowest first.
fn set_bits(mut mask: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let bit = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            bit
        })
    })
}

/// A boundary pixel's surface: world tangents from a read-back normal, or
/// homogeneous derivatives from depth differences.
#[derive(Clone, Copy, Debug)]
enum Surface {
    Given { tx: DVec3, ty: DVec3, normal: DVec3 },
    Depth { dx4: DVec4, dy4: DVec4, normal: DVec3 },
}

impl Surface {
    fn normal(self) -> DVec3 {
        match self {
            Self::Given { normal, .. } | Self::Depth { normal, .. } => normal,
        }
    }
}

/// The surface at boundary pixel `(x, y)` (index `i` in the readback's
/// buffers), whose homogeneous point `here` has `w > 0`; `None` at a depth
/// discontinuity or where the derivatives are not finite.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn surface_at(
    pixels: &Pixels<'_>,
    world_from_screen: &DMat4,
    viewer: Viewer,
    options: &SampleOptions,
    (x, y): (usize, usize),
    i: usize,
    (sx, sy, d): (f64, f64, f64),
    here: DVec4,
    world: DVec3,
    step: DVec2,
) -> Option<Surface> {
    let (w, h) = (pixels.width, pixels.height);
    // Depth slope from the neighbours' depths `d0` (before) and `d1`
    // (after) along a screen axis of `step` full-resolution pixels a pixel;
    // `None` where one is not drawn or across a discontinuity.
    let slope = |d0: f64, d1: f64, step: f64| -> Option<f64> {
        if !(d0.is_finite() && d1.is_finite()) {
            return None;
        }
        let first = 0.5 * (d1 - d0);
        let second = d1 - 2.0 * d + d0;
        (second.abs() <= options.curvature_ratio * first.abs() + options.depth_epsilon).then_some(first / step)
    };
    let normal_given = pixels.normals.map(|normals| {
        let [nx, ny, nz] = normals[i];
        DVec3::new(f64::from(nx), f64::from(ny), f64::from(nz))
    });
    match normal_given.and_then(DVec3::try_normalize) {
        Some(normal) => {
            // Derivatives of the surface point along the tangent plane.
            let (tx, ty) = plane_derivatives(world_from_screen, sx, sy, world, normal)?;
            Some(Surface::Given { tx, ty, normal })
        }
        None => {
            // A row's pixels are contiguous in the readback.
            if x == 0 || x + 1 >= w || y == 0 || y + 1 >= h {
                return None;
            }
            let zx = slope(pixels.depth(i - 1), pixels.depth(i + 1), step.x)?;
            // Rows `y - 1` and `y + 1` are a row's length before and after
            // `i` in the buffer, or after and before for bottom-up rows.
            let (above, below) = if pixels.bottom_up { (i + w, i - w) } else { (i - w, i + w) };
            let zy = slope(pixels.depth(above), pixels.depth(below), step.y)?;
            let dx4 = *world_from_screen * DVec4::new(1.0, 0.0, zx, 0.0);
            let dy4 = *world_from_screen * DVec4::new(0.0, 1.0, zy, 0.0);
            // World tangents (derivative of the dehomogenised point).
            let tx = (dx4.truncate() - world * dx4.w) / here.w;
            let ty = (dy4.truncate() - world * dy4.w) / here.w;
            let mut normal = tx.cross(ty).normalize_or_zero();
            if normal.dot(viewer.towards(world)) < 0.0 {
                normal = -normal;
            }
            // Homogeneous point and its homogeneous derivatives: one scale.
            Some(Surface::Depth { dx4, dy4, normal })
        }
    }
}

/// [`surface_at`], not inlined.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn surface_at_called(
    pixels: &Pixels<'_>,
    world_from_screen: &DMat4,
    viewer: Viewer,
    options: &SampleOptions,
    xy: (usize, usize),
    i: usize,
    screen: (f64, f64, f64),
    here: DVec4,
    world: DVec3,
    step: DVec2,
) -> Option<Surface> {
    surface_at(pixels, world_from_screen, viewer, options, xy, i, screen, here, world, step)
}

/// World-space derivatives, per full-resolution pixel along x and y, of the
/// point where the pixel's ray meets the plane through `world` with `normal`.
fn plane_derivatives(
    world_from_screen: &glam::DMat4,
    sx: f64,
    sy: f64,
    world: DVec3,
    normal: DVec3,
) -> Option<(DVec3, DVec3)> {
    // Move one pixel along x (or y) and intersect that pixel's ray with the plane.
    let hit = |px: f64, py: f64| -> Option<DVec3> {
        let a = world_from_screen.project_point3(DVec3::new(px, py, 0.0));
        // Depth 0.5, not 1: an infinite far plane's depth 1 is at infinity.
        let b = world_from_screen.project_point3(DVec3::new(px, py, 0.5));
        let denom = normal.dot(b - a);
        if denom.abs() <= f64::EPSILON * (b - a).length() {
            return None;
        }
        Some(a + (b - a) * (normal.dot(world - a) / denom))
    };
    let (xp, xm) = (hit(sx + 0.5, sy)?, hit(sx - 0.5, sy)?);
    let (yp, ym) = (hit(sx, sy + 0.5)?, hit(sx, sy - 0.5)?);
    Some((xp - xm, yp - ym)).filter(|(a, b)| a.is_finite() && b.is_finite())
}

/// Whether a receiver at `p` with unit normal `n` faces the light.
pub(super) fn faces_light(light: &Light, p: DVec3, n: DVec3, min_cosine: f64) -> bool {
    let to_light = match *light {
        Light::Directional { direction } => -direction,
        Light::Point { position } | Light::Spot { position, .. } => (position - p).normalize_or_zero(),
    };
    n.dot(to_light) > min_cosine
}

#[cfg(test)]
mod tests {
    use super::{boundary_bits, or_row, pack_bytes, pack_lixel_row, pack_row};

    /// Each row of `src` (`h` rows of `w` items) ORed with the rows above and
    /// below (clamped at the edges), into `dst`.
    fn or_rows<T: Copy + Default + std::ops::BitOr<Output = T>>(src: &[T], w: usize, h: usize, dst: &mut Vec<T>) {
        dst.clear();
        dst.resize(src.len(), T::default());
        for y in 0..h {
            let (above, here, below) =
                (&src[y.saturating_sub(1) * w..][..w], &src[y * w..][..w], &src[(y + 1).min(h - 1) * w..][..w]);
            for (((cell, &a), &m), &b) in dst[y * w..][..w].iter_mut().zip(above).zip(here).zip(below) {
                *cell = a | m | b;
            }
        }
    }

    /// [`or_3x3`] of a bit image, word by word (the one-light path's
    /// earlier two passes, the reference for [`boundary_bits`]): `h` rows of
    /// `words` `u64`s, pixel `64 k + j` of a row at bit `j` of its word `k`,
    /// `w` pixels a row (the bits beyond them zero, in `src` and in `dst`).
    fn or_3x3_bits(src: &[u64], w: usize, words: usize, h: usize, tmp: &mut Vec<u64>, dst: &mut Vec<u64>) {
        tmp.clear();
        // The last word's pixels (a whole word when `w` is a multiple of 64).
        let last = u64::MAX >> ((64 - w % 64) % 64);
        for row in src.chunks_exact(words) {
            for k in 0..words {
                let word = row[k];
                let from_left = if k > 0 { row[k - 1] >> 63 } else { 0 };
                let from_right = if k + 1 < words { row[k + 1] << 63 } else { 0 };
                let spread = word | word << 1 | from_left | word >> 1 | from_right;
                tmp.push(if k + 1 == words { spread & last } else { spread });
            }
        }
        or_rows(tmp, words, h, dst);
    }

    /// The 3x3 OR as the extraction makes it: along rows, then across.
    fn or_3x3<T: Copy + Default + std::ops::BitOr<Output = T>>(
        src: &[T],
        w: usize,
        h: usize,
        tmp: &mut Vec<T>,
        dst: &mut Vec<T>,
    ) {
        tmp.clear();
        tmp.resize(src.len(), T::default());
        for (s, t) in src.chunks_exact(w).zip(tmp.chunks_exact_mut(w)) {
            or_row(s, t);
        }
        or_rows(tmp, w, h, dst);
    }

    #[test]
    fn pack_bytes_puts_byte_i_on_bit_i() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..1000 {
            state = crate::test_rng::step(state);
            let bytes: [u8; 64] = std::array::from_fn(|i| u8::from(state >> i & 1 != 0));
            assert_eq!(pack_bytes(&bytes), state);
        }
        assert_eq!(pack_bytes(&[1; 64]), u64::MAX);
    }

    /// The SSE2 pack of a row of lixel depth (what `pack_lixel_row` runs on
    /// x86-64) gives the portable `pack_row`'s words, and both the
    /// pixel-by-pixel definition: rows of 1 to 200 pixels (every remainder
    /// modulo 16 and 64, rows narrower than sixteen), starting anywhere in a
    /// buffer, with depths at and around the interval's ends (both zeros,
    /// one, the float below one, subnormals, NaNs of both signs, infinities)
    /// and random ones, and every shadow bit (the pixels' shadow bits random:
    /// none, one, several or all set).
    #[test]
    fn sse2_pack_equals_the_portable_pack() {
        let special = [
            0.0f32,
            -0.0,
            1.0,
            1.0 - f32::EPSILON / 2.0,
            1.0 + f32::EPSILON,
            f32::MIN_POSITIVE,
            f32::from_bits(1),
            -f32::from_bits(1),
            f32::NAN,
            -f32::NAN,
            f32::from_bits(0x7fc0_0001),
            f32::INFINITY,
            f32::NEG_INFINITY,
            -0.5,
            0.5,
            2.0,
            f32::MAX,
        ];
        let mut state = 0x6a09_e667_f3bc_c908u64;
        let mut next = || {
            state = crate::test_rng::step(state);
            state
        };
        let (mut sse, mut portable) = (Vec::new(), Vec::new());
        let mut checked = [0usize; 2];
        for round in 0..3000 {
            let w = 1 + round % 200;
            let offset = (next() % 4) as usize;
            let depth: Vec<f32> = (0..w + offset)
                .map(|_| {
                    let r = next();
                    if r % 4 == 0 {
                        special[(r >> 8) as usize % special.len()]
                    } else {
                        (r >> 11) as f32 / (1u64 << 53) as f32 * 1.5 - 0.25
                    }
                })
                .collect();
            let bits: Vec<u32> = (0..w + offset)
                .map(|_| match next() % 8 {
                    0 => 0,
                    1 => u32::MAX,
                    2 => 1 << (next() % 32),
                    _ => next() as u32 & next() as u32,
                })
                .collect();
            let bit = (next() % 32) as u32;
            let mask = 1 << bit;
            let (depth, bits) = (&depth[offset..], &bits[offset..]);
            sse.clear();
            portable.clear();
            pack_lixel_row(depth, bits, bit, |c, s| sse.push((c, s)));
            pack_row(depth, bits, mask, |d| (0.0..1.0).contains(&d), |c, s| portable.push((c, s)));
            assert_eq!(sse, portable, "width {w}, offset {offset}, bit {bit}");
            assert_eq!(sse.len(), w.div_ceil(64));
            for x in 0..w {
                let covered = (0.0..1.0).contains(&depth[x]);
                let shadowed = covered && bits[x] & mask != 0;
                let (c, s) = sse[x / 64];
                assert_eq!(
                    (c >> (x % 64) & 1 != 0, s >> (x % 64) & 1 != 0),
                    (covered, shadowed),
                    "width {w}, pixel {x}"
                );
                checked[usize::from(shadowed)] += 1;
            }
            // The bits beyond the row's pixels are clear.
            let last = sse[sse.len() - 1];
            if w % 64 != 0 {
                assert_eq!((last.0 | last.1) >> (w % 64), 0, "width {w}");
            }
        }
        assert!(checked[0] > 10_000 && checked[1] > 10_000, "{checked:?}");
    }

    /// The 3x3 OR with clamped edges, pixel by pixel.
    fn reference(src: &[u64], w: usize, h: usize) -> Vec<u64> {
        let mut out = vec![0; src.len()];
        for y in 0..h {
            for x in 0..w {
                for dy in [-1isize, 0, 1] {
                    for dx in [-1isize, 0, 1] {
                        let yy = y.saturating_add_signed(dy).min(h - 1);
                        let xx = x.saturating_add_signed(dx).min(w - 1);
                        out[y * w + x] |= src[yy * w + xx];
                    }
                }
            }
        }
        out
    }

    #[test]
    fn or_3x3_equals_the_pixel_by_pixel_or() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let (mut tmp, mut dst) = (Vec::new(), Vec::new());
        for w in 1..=11 {
            for h in 1..=5 {
                // Sparse single bits, so that a missed neighbour shows.
                let src: Vec<u64> = (0..w * h)
                    .map(|_| {
                        state = crate::test_rng::step(state);
                        if state.is_multiple_of(4) {
                            1 << (state >> 58)
                        } else {
                            0
                        }
                    })
                    .collect();
                or_3x3(&src, w, h, &mut tmp, &mut dst);
                assert_eq!(dst, reference(&src, w, h), "{w}x{h}");
                let bytes: Vec<u8> = src.iter().map(|&v| (v | v >> 8 | v >> 16 | v >> 24) as u8).collect();
                let (mut tmp8, mut dst8) = (Vec::new(), Vec::new());
                or_3x3(&bytes, w, h, &mut tmp8, &mut dst8);
                let wide: Vec<u64> = bytes.iter().map(|&b| u64::from(b)).collect();
                let expected: Vec<u8> = reference(&wide, w, h).iter().map(|&v| v as u8).collect();
                assert_eq!(dst8, expected, "{w}x{h} bytes");
            }
        }
    }

    #[test]
    fn or_3x3_bits_equals_the_pixel_by_pixel_or() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let (mut tmp, mut dst) = (Vec::new(), Vec::new());
        for w in [1usize, 2, 3, 63, 64, 65, 127, 128, 129, 180] {
            let words = w.div_ceil(64);
            for h in 1..=4 {
                let pixels: Vec<u64> = (0..w * h)
                    .map(|_| {
                        state = crate::test_rng::step(state);
                        u64::from(state.is_multiple_of(5))
                    })
                    .collect();
                let mut packed = vec![0u64; words * h];
                for y in 0..h {
                    for x in 0..w {
                        packed[y * words + x / 64] |= pixels[y * w + x] << (x % 64);
                    }
                }
                or_3x3_bits(&packed, w, words, h, &mut tmp, &mut dst);
                let expected = reference(&pixels, w, h);
                for y in 0..h {
                    for x in 0..w {
                        assert_eq!(
                            dst[y * words + x / 64] >> (x % 64) & 1,
                            expected[y * w + x],
                            "{w}x{h} at ({x}, {y})"
                        );
                    }
                    // The bits beyond the row's pixels stay clear.
                    let tail = if w % 64 == 0 { 0 } else { dst[y * words + words - 1] >> (w % 64) };
                    assert_eq!(tail, 0, "{w}x{h} row {y}");
                }
            }
        }
    }

    /// The fused one-light pass gives the two 3x3 ORs' bits: covered pixels
    /// with shadowed and lit pixels nearby, none beyond a row's pixels.
    #[test]
    fn boundary_bits_equals_both_or_3x3() {
        let mut state = 0x51_7cc1_b727_220au64;
        let (mut tmp, mut near_shadowed, mut near_lit) = (Vec::new(), Vec::new(), Vec::new());
        let (mut near, mut mixed) = (Vec::new(), Vec::new());
        let mut nonzero = 0;
        for w in [1usize, 2, 3, 63, 64, 65, 127, 128, 129, 180, 200] {
            let words = w.div_ceil(64);
            let last = u64::MAX >> ((64 - w % 64) % 64);
            for h in 1..=5 {
                // Dense and sparse images: runs of covered and shadowed bits.
                for density in [1u64, 3, 7] {
                    let mut random = || {
                        state = crate::test_rng::step(state);
                        (0..64).fold(0u64, |word, _| {
                            state = crate::test_rng::step(state);
                            word << 1 | u64::from(state % 8 < density)
                        })
                    };
                    let mut covered: Vec<u64> = (0..words * h).map(|_| random() | random()).collect();
                    let mut shadowed: Vec<u64> = covered.iter().map(|&c| c & random()).collect();
                    for row in 0..h {
                        covered[row * words + words - 1] &= last;
                        shadowed[row * words + words - 1] &= last;
                    }
                    let lit: Vec<u64> = covered.iter().zip(&shadowed).map(|(&c, &s)| c & !s).collect();
                    or_3x3_bits(&shadowed, w, words, h, &mut tmp, &mut near_shadowed);
                    or_3x3_bits(&lit, w, words, h, &mut tmp, &mut near_lit);
                    let expected: Vec<u64> =
                        covered.iter().zip(&near_shadowed).zip(&near_lit).map(|((&c, &s), &l)| c & s & l).collect();
                    boundary_bits(&covered, &shadowed, w, words, h, &mut near, &mut mixed);
                    assert_eq!(mixed, expected, "{w}x{h} density {density}");
                    nonzero += usize::from(mixed.iter().any(|&m| m != 0));
                }
            }
        }
        // Most images have boundary pixels, so the comparison is not of zeros.
        assert!(nonzero > 100, "{nonzero}");
        // No rows: nothing.
        boundary_bits(&[], &[], 1, 1, 0, &mut near, &mut mixed);
        assert!(mixed.is_empty());
    }
}
