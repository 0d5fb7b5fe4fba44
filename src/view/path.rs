//! Scripted camera paths (`lixel view --path FILE`) for reproducible
//! figures and timings: key frames of eye and target, linearly
//! interpolated by frame number.
//!
//! The file is plain text, one key per line, `#` starts a comment:
//!
//! ```text
//! # frame  eye x y z        target x y z
//! 0        0 2 30           0 1 0
//! 60       20 2 20          0 1 0
//! ```
//!
//! Frame numbers must increase; before the first key the camera stands at
//! it, after the last at the last.

use std::path::Path;

use glam::DVec3;

use super::ViewError;

/// One key frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraKey {
    /// Frame number.
    pub frame: u64,
    /// Eye position.
    pub eye: DVec3,
    /// Look-at point.
    pub target: DVec3,
}

/// A camera path: key frames in increasing frame order (at least one).
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPath {
    keys: Vec<CameraKey>,
}

impl CameraPath {
    /// Reads a path file.
    ///
    /// # Errors
    /// [`ViewError::Path`] for an unreadable file or a malformed line.
    pub fn load(path: &Path) -> Result<Self, ViewError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| ViewError::Path { path: path.to_path_buf(), reason: e.to_string() })?;
        Self::parse(&text).map_err(|reason| ViewError::Path { path: path.to_path_buf(), reason })
    }

    /// Parses the text of a path file.
    ///
    /// # Errors
    /// The reason, with the line number, for a malformed line, frames out of
    /// order, a non-finite coordinate, an eye on its target, or no key.
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut keys: Vec<CameraKey> = Vec::new();
        for (n, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let fields: Vec<&str> = line.split_whitespace().collect();
            if fields.len() != 7 {
                return Err(format!(
                    "line {}: expected 7 fields (frame, eye x y z, target x y z), got {}",
                    n + 1,
                    fields.len()
                ));
            }
            let frame: u64 = fields[0]
                .parse()
                .map_err(|_| format!("line {}: frame {:?} is not a whole number", n + 1, fields[0]))?;
            let mut v = [0.0; 6];
            for (slot, text) in v.iter_mut().zip(&fields[1..]) {
                *slot = text
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| format!("line {}: {text:?} is not a finite number", n + 1))?;
            }
            let (eye, target) = (DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5]));
            if eye == target {
                return Err(format!("line {}: the eye is on its target", n + 1));
            }
            if keys.last().is_some_and(|k| k.frame >= frame) {
                return Err(format!("line {}: frame {frame} does not follow the previous key's", n + 1));
            }
            keys.push(CameraKey { frame, eye, target });
        }
        if keys.is_empty() {
            return Err("no key frames".into());
        }
        Ok(Self { keys })
    }

    /// The key frames.
    #[must_use]
    pub fn keys(&self) -> &[CameraKey] {
        &self.keys
    }

    /// Eye and target at `frame`.
    #[must_use]
    pub fn at(&self, frame: u64) -> (DVec3, DVec3) {
        let after = self.keys.partition_point(|k| k.frame <= frame);
        match (after.checked_sub(1).map(|i| self.keys[i]), self.keys.get(after)) {
            (Some(a), Some(b)) => {
                let t = (frame - a.frame) as f64 / (b.frame - a.frame) as f64;
                (a.eye.lerp(b.eye, t), a.target.lerp(b.target, t))
            }
            (Some(a), None) => (a.eye, a.target),
            (None, Some(b)) => (b.eye, b.target),
            (None, None) => unreachable!("a path has at least one key"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_between_keys_and_holds_at_the_ends() {
        let p = CameraPath::parse("# comment\n10 0 0 10  0 0 0\n20 10 0 10 0 0 0 # end\n").unwrap();
        assert_eq!(p.at(0).0, DVec3::new(0.0, 0.0, 10.0));
        assert_eq!(p.at(15).0, DVec3::new(5.0, 0.0, 10.0));
        assert_eq!(p.at(99).0, DVec3::new(10.0, 0.0, 10.0));
    }

    #[test]
    fn malformed_lines_are_named() {
        for (text, want) in [
            ("0 1 2 3 4 5", "line 1: expected 7"),
            ("0 0 0 1 0 0 0\n0 0 0 2 0 0 0", "line 2: frame 0 does not follow"),
            ("x 0 0 1 0 0 0", "not a whole number"),
            ("0 0 0 nan 0 0 0", "not a finite number"),
            ("0 1 1 1 1 1 1", "eye is on its target"),
            ("# nothing", "no key frames"),
        ] {
            let e = CameraPath::parse(text).unwrap_err();
            assert!(e.contains(want), "{text:?}: {e}");
        }
    }
}
