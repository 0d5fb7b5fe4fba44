//! The experiment's pictures: the best, median and worst configuration of
//! each method with its errors overlaid. The run renders them (see
//! `finish`); this module only colours masks and writes files.

use std::path::{Path, PathBuf};

use image::{Rgba, RgbaImage};

use super::{ExperimentError, MethodSpec};
use crate::mesh::ShadowMasks;

/// One picture collected by the run.
#[derive(Clone, Debug)]
pub(super) struct Picture {
    /// The method.
    pub method: MethodSpec,
    /// "best", "median" or "worst".
    pub which: &'static str,
    /// The configuration.
    pub config: usize,
    /// Its misclassified pixels.
    pub misclassified: u64,
    /// The overlay ([`error_overlay`]).
    pub image: RgbaImage,
}

pub(super) fn save(image: &RgbaImage, path: &Path) -> Result<(), ExperimentError> {
    let mut png = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| ExperimentError::Io { path: path.to_path_buf(), source: std::io::Error::other(e) })?;
    super::rundir::write_atomic(path, &png)
}

/// The truth's shading with the method's errors on top.
#[must_use]
pub fn error_overlay(masks: &ShadowMasks, truth: &ShadowMasks) -> RgbaImage {
    RgbaImage::from_fn(truth.width, truth.height, |x, y| {
        let i = (y * truth.width + x) as usize;
        if !truth.visible(i) {
            return Rgba([0, 0, 0, 255]);
        }
        if truth.facing[i] & 1 == 0 {
            return Rgba([40, 40, 40, 255]);
        }
        match (truth.shadow[i] & 1, masks.shadow.get(i).map_or(0, |s| s & 1)) {
            (0, 1) => Rgba([230, 30, 30, 255]),
            (1, 0) => Rgba([40, 90, 255, 255]),
            (0, _) => Rgba([200, 200, 200, 255]),
            _ => Rgba([90, 90, 90, 255]),
        }
    })
}

/// Writes `pictures` into `dir/images/`. Returns (method, which, path).
pub(super) fn write_pictures(
    dir: &Path,
    pictures: &[Picture],
) -> Result<Vec<(MethodSpec, String, PathBuf)>, ExperimentError> {
    let images = dir.join("images");
    std::fs::create_dir_all(&images).map_err(|source| ExperimentError::Io { path: images.clone(), source })?;
    let mut written = Vec::new();
    for p in pictures {
        let path = images.join(format!("{}-{}-config{}-{}px.png", p.method.name(), p.which, p.config, p.misclassified));
        save(&p.image, &path)?;
        written.push((p.method, p.which.to_string(), path));
    }
    Ok(written)
}
