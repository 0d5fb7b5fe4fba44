//! The experiment's pictures: sorted per-configuration error curves, and the
//! best, median and worst configuration of each method with its errors
//! overlaid.

use std::path::{Path, PathBuf};

use image::{Rgba, RgbaImage};

use super::report::ConfigRow;
use super::{light_for, Counts, ExperimentConfig, ExperimentError, MethodKind, Runner};
use crate::mesh::ShadowMasks;

/// Line colour of each method in the plots.
pub(super) fn method_color(method: MethodKind) -> Rgba<u8> {
    match method {
        MethodKind::Normal => Rgba([120, 120, 120, 255]),
        MethodKind::Focused => Rgba([31, 119, 180, 255]),
        MethodKind::FocusedSnapped => Rgba([23, 190, 207, 255]),
        MethodKind::LiSpsm => Rgba([44, 160, 44, 255]),
        MethodKind::Psm => Rgba([148, 103, 189, 255]),
        MethodKind::PlaneOptimal => Rgba([255, 127, 14, 255]),
        MethodKind::Optimized => Rgba([214, 39, 40, 255]),
        MethodKind::OptimizedArgmin => Rgba([227, 119, 194, 255]),
    }
}

/// Which colour is which method (the plot has no text).
#[must_use]
pub(super) fn legend(config: &ExperimentConfig) -> String {
    let items: Vec<String> = config
        .methods
        .iter()
        .map(|&m| {
            let [r, g, b, _] = method_color(m).0;
            format!("{} = rgb({r}, {g}, {b})", m.name())
        })
        .collect();
    format!(
        "Each line is one method's misclassified pixels per configuration, sorted ascending (x: rank; y: ln(1 + pixels), from 0 to the largest count). Colours: {}.",
        items.join(", ")
    )
}

fn save(image: &RgbaImage, path: &Path) -> Result<(), ExperimentError> {
    image.save(path).map_err(|e| ExperimentError::Io { path: path.to_path_buf(), source: std::io::Error::other(e) })
}

fn line(img: &mut RgbaImage, (x0, y0): (i64, i64), (x1, y1): (i64, i64), c: Rgba<u8>) {
    // Bresenham, two pixels thick.
    let (dx, dy) = ((x1 - x0).abs(), -(y1 - y0).abs());
    let (sx, sy) = (if x0 < x1 { 1 } else { -1 }, if y0 < y1 { 1 } else { -1 });
    let (mut x, mut y, mut err) = (x0, y0, dx + dy);
    loop {
        for (ox, oy) in [(0, 0), (0, 1)] {
            let (px, py) = (x + ox, y + oy);
            if px >= 0 && py >= 0 && (px as u32) < img.width() && (py as u32) < img.height() {
                img.put_pixel(px as u32, py as u32, c);
            }
        }
        if x == x1 && y == y1 {
            break;
        }
        let e2 = 2 * err;
        if e2 >= dy {
            err += dy;
            x += sx;
        }
        if e2 <= dx {
            err += dx;
            y += sy;
        }
    }
}

/// `sorted-errors.png`: per method, the misclassified counts sorted ascending.
pub(super) fn sorted_curves(path: &Path, config: &ExperimentConfig, rows: &[ConfigRow]) -> Result<(), ExperimentError> {
    let (w, h, margin) = (900i64, 540i64, 40i64);
    let mut img = RgbaImage::from_pixel(w as u32, h as u32, Rgba([255, 255, 255, 255]));
    let series: Vec<(MethodKind, Vec<u64>)> = config
        .methods
        .iter()
        .map(|&m| {
            let mut v: Vec<u64> = rows.iter().filter(|r| r.method == m).filter_map(|r| r.misclassified).collect();
            v.sort_unstable();
            (m, v)
        })
        .collect();
    // Logarithmic y (of 1 + pixels): the worst configurations are orders of
    // magnitude above the typical ones.
    let max = (series.iter().flat_map(|(_, v)| v.iter().copied()).max().unwrap_or(1).max(1) as f64).ln_1p();
    let axis = Rgba([0, 0, 0, 255]);
    line(&mut img, (margin, h - margin), (w - margin, h - margin), axis);
    line(&mut img, (margin, margin), (margin, h - margin), axis);
    for (m, v) in &series {
        if v.is_empty() {
            continue;
        }
        let point = |i: usize, e: u64| {
            let x = margin + ((w - 2 * margin) as f64 * i as f64 / (v.len() - 1).max(1) as f64) as i64;
            let y = h - margin - ((h - 2 * margin) as f64 * (e as f64).ln_1p() / max) as i64;
            (x, y)
        };
        for i in 1..v.len() {
            line(&mut img, point(i - 1, v[i - 1]), point(i, v[i]), method_color(*m));
        }
        if v.len() == 1 {
            line(&mut img, point(0, v[0]), point(0, v[0]), method_color(*m));
        }
    }
    // A colour key in the top-left corner, in method order.
    for (k, (m, _)) in series.iter().enumerate() {
        let x = margin + 10 + 30 * k as i64;
        for dy in 0..12 {
            line(&mut img, (x, margin + dy), (x + 20, margin + dy), method_color(*m));
        }
    }
    save(&img, path)
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

/// For every method: its best, median and worst configuration re-run, with
/// the errors overlaid, in `images/`. Returns (method, which, path).
pub(super) fn extremes(
    runner: &mut Runner<'_>,
    config: &ExperimentConfig,
    rows: &[ConfigRow],
) -> Result<Vec<(MethodKind, String, PathBuf)>, ExperimentError> {
    let dir = config.out.join("images");
    std::fs::create_dir_all(&dir).map_err(|source| ExperimentError::Io { path: dir.clone(), source })?;
    let mut written = Vec::new();
    for &m in &config.methods {
        let mut by_error: Vec<(u64, usize)> =
            rows.iter().filter(|r| r.method == m).filter_map(|r| Some((r.misclassified?, r.config))).collect();
        if by_error.is_empty() {
            continue;
        }
        by_error.sort_unstable();
        let picks = [
            ("best", by_error[0].1),
            ("median", by_error[by_error.len() / 2].1),
            ("worst", by_error[by_error.len() - 1].1),
        ];
        for (which, index) in picks {
            let light = light_for(config, runner.scene(), index);
            let (ray, focused) = runner.truths(light)?;
            let Some(truth) = ray.or(focused) else { continue };
            let problem = runner.problem(light, config.map)?;
            let nearest = super::nearest_view_depth(runner.camera(), &truth);
            let Ok((matrix, _, _)) = runner.matrix(m, &problem, nearest) else { continue };
            let masks = runner.masks(&matrix)?;
            let counts = Counts::compare(&masks, &truth);
            let path = dir.join(format!("{}-{which}-config{index}-{}px.png", m.name(), counts.misclassified()));
            save(&error_overlay(&masks, &truth), &path)?;
            written.push((m, which.to_string(), path));
        }
    }
    Ok(written)
}
