//! The SGSM pattern table and the per-texel mask word, on the CPU: the
//! mirror of the tables the sweep and the lookup shaders use
//! (`shaders/sgsm_common.wgsl` gets them from [`wgsl_tables`]).
//!
//! Why a table: the paper recognises the triangles sharing a texel by the
//! surface normals at its four corners and a set of *predetermined
//! patterns* (its figure 4: which corners share a triangle, up to four
//! triangles). A pattern here is a partition of the corners into groups
//! that lie on one plane, written as a restricted growth string (corner 0
//! gets label 0, every later corner an earlier label or the next new one):
//! `0000` one plane over the whole texel, `0011` a horizontal crease,
//! `0001` one corner cut off, `0123` four planes, and so on; the 15 set
//! partitions of four corners. Corners are numbered top-left, top-right,
//! bottom-left, bottom-right (x right, y down, as the map's texels).

/// The 15 partitions of the four corners, as restricted growth strings.
pub const PATTERNS: [[u8; 4]; 15] = [
    [0, 0, 0, 0],
    [0, 0, 0, 1],
    [0, 0, 1, 0],
    [0, 0, 1, 1],
    [0, 0, 1, 2],
    [0, 1, 0, 0],
    [0, 1, 0, 1],
    [0, 1, 0, 2],
    [0, 1, 1, 0],
    [0, 1, 1, 1],
    [0, 1, 1, 2],
    [0, 1, 2, 0],
    [0, 1, 2, 1],
    [0, 1, 2, 2],
    [0, 1, 2, 3],
];

/// Corner offsets from the texel's top-left corner, in corner order.
pub const CORNERS: [[i32; 2]; 4] = [[0, 0], [1, 0], [0, 1], [1, 1]];

/// Canonical form of arbitrary corner labels (equal labels: one group).
#[must_use]
pub fn canonical(labels: [u32; 4]) -> [u8; 4] {
    let mut out = [0u8; 4];
    let mut seen: Vec<u32> = Vec::with_capacity(4);
    for (q, label) in labels.iter().enumerate() {
        let k = seen.iter().position(|s| s == label).unwrap_or_else(|| {
            seen.push(*label);
            seen.len() - 1
        });
        out[q] = k as u8;
    }
    out
}

/// The pattern index of corner labels (equal labels: one group); every
/// labelling has one.
#[must_use]
pub fn pattern_index(labels: [u32; 4]) -> u8 {
    let c = canonical(labels);
    PATTERNS.iter().position(|p| *p == c).expect("every restricted growth string of length 4 is listed") as u8
}

/// The groups of a pattern as corner bit masks (bit `q`: corner `q`), in
/// label order; `None` past the table.
#[must_use]
pub fn groups(pattern: u8) -> Option<Vec<u8>> {
    let rgs = PATTERNS.get(usize::from(pattern))?;
    let count = rgs.iter().max().map_or(0, |m| m + 1);
    Some(
        (0..count)
            .map(|g| rgs.iter().enumerate().filter(|(_, l)| **l == g).fold(0u8, |m, (q, _)| m | 1 << q))
            .collect(),
    )
}

/// A pattern's groups packed as the shaders hold them: group `g`'s corner
/// mask in bits `4g..4g + 4` (zero: no such group).
#[must_use]
pub fn table_word(pattern: u8) -> u32 {
    groups(pattern).unwrap_or_default().iter().enumerate().fold(0, |w, (g, m)| w | u32::from(*m) << (4 * g))
}

/// A texel's sweep status.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Status {
    /// Nothing drawn in the texel (or not swept).
    Empty = 0,
    /// All four corners on one plane.
    Full = 1,
    /// Two to four planes (or uncovered corners) in a listed pattern.
    Pattern = 2,
    /// A corner whose triangle is not among the stored ones (more than the
    /// stored triangles overlap, or a depth-only neighbour): the lookup
    /// falls back to SPSM.
    Unrecognised = 3,
}

/// Corner code: the corner lies on no triangle (a neighbour is empty).
pub const CORNER_EMPTY: u8 = 9;
/// Corner code: no stored triangle contains the corner.
pub const CORNER_UNKNOWN: u8 = 10;

/// The sweep's per-texel word: bits 0..9 the 3x3 slots (`3 (dy + 1) + dx +
/// 1`) whose stored triangles reach into the texel (take part), bits 9..11 the [`Status`], bits
/// 11..15 the pattern index, bits `15 + 4q..19 + 4q` corner `q`'s slot
/// (0..=8, [`CORNER_EMPTY`], [`CORNER_UNKNOWN`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MaskWord(pub u32);

impl MaskWord {
    /// Assembles a word from the participating slots (bits 0..9), the
    /// status, the pattern and the corners' slots.
    #[must_use]
    pub fn new(slots: u32, status: Status, pattern: u8, corners: [u8; 4]) -> Self {
        let corner_bits = corners.iter().enumerate().fold(0u32, |w, (q, &c)| w | u32::from(c & 0xf) << (15 + 4 * q));
        Self(slots & 0x1ff | (status as u32) << 9 | u32::from(pattern & 0xf) << 11 | corner_bits)
    }

    /// The 3x3 slots taking part.
    #[must_use]
    pub fn slots(self) -> u32 {
        self.0 & 0x1ff
    }

    /// The status.
    #[must_use]
    pub fn status(self) -> Status {
        match self.0 >> 9 & 3 {
            0 => Status::Empty,
            1 => Status::Full,
            2 => Status::Pattern,
            _ => Status::Unrecognised,
        }
    }

    /// The pattern index.
    #[must_use]
    pub fn pattern(self) -> u8 {
        (self.0 >> 11 & 0xf) as u8
    }

    /// Corner `q`'s slot code.
    #[must_use]
    pub fn corner(self, q: usize) -> u8 {
        (self.0 >> (15 + 4 * q) & 0xf) as u8
    }
}

/// The tables as WGSL constants (`SGSM_PATTERNS`: the restricted growth
/// strings, two bits per corner; `SGSM_GROUPS`: [`table_word`]).
#[must_use]
pub fn wgsl_tables() -> String {
    let rgs: Vec<String> = PATTERNS
        .iter()
        .map(|p| format!("{}u", p.iter().enumerate().fold(0u32, |w, (q, l)| w | u32::from(*l) << (2 * q))))
        .collect();
    let groups: Vec<String> = (0..PATTERNS.len() as u8).map(|i| format!("{}u", table_word(i))).collect();
    format!(
        "const SGSM_PATTERNS = array<u32, 15>({});\nconst SGSM_GROUPS = array<u32, 15>({});\n",
        rgs.join(", "),
        groups.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_lists_every_partition_once() {
        // Bell(4) = 15 partitions; each canonical labelling of 4^4 inputs is listed.
        let mut hit = [false; 15];
        for code in 0..256u32 {
            let labels = [code & 3, code >> 2 & 3, code >> 4 & 3, code >> 6 & 3];
            let i = usize::from(pattern_index(labels));
            hit[i] = true;
            // Same groups as the labels.
            for a in 0..4 {
                for b in 0..4 {
                    assert_eq!(labels[a] == labels[b], PATTERNS[i][a] == PATTERNS[i][b], "{labels:?}");
                }
            }
        }
        assert!(hit.iter().all(|&h| h));
        for i in 0..15u8 {
            let g = groups(i).unwrap();
            assert_eq!(g.iter().fold(0, |m, x| m | x), 0xf, "pattern {i} covers all corners");
            assert_eq!(g.iter().map(|x| x.count_ones()).sum::<u32>(), 4, "disjoint");
        }
    }

    #[test]
    fn mask_words_round_trip() {
        for status in [Status::Empty, Status::Full, Status::Pattern, Status::Unrecognised] {
            for pattern in 0..15u8 {
                let corners = [pattern % 9, CORNER_EMPTY, CORNER_UNKNOWN, 8 - pattern % 9];
                let slots = 1 << (pattern % 9) | 1 << (8 - pattern % 9);
                let w = MaskWord::new(slots, status, pattern, corners);
                assert_eq!(w.status(), status);
                assert_eq!(w.pattern(), pattern);
                assert_eq!((0..4).map(|q| w.corner(q)).collect::<Vec<_>>(), corners);
                assert_eq!(w.slots(), 1 << (pattern % 9) | 1 << (8 - pattern % 9));
            }
        }
    }
}
