//! The report's plots, drawn with `plotters` into a bitmap and written as
//! PNG: the sorted per-configuration errors of every method, and the
//! resolution-equivalence ladder. Text uses DejaVu Sans Mono, embedded in
//! the binary (licence in `fonts/LICENSE-DejaVu.txt`), so no system fonts
//! are needed.

use std::path::Path;
use std::sync::Once;

use image::RgbImage;
use plotters::prelude::*;

use super::method::{CascadeMethod, Search};
use super::report::Summary;
use super::rows::ConfigRow;
use super::{ExperimentConfig, ExperimentError, MethodSpec};
use crate::render::ShadowLookup;
use crate::Method;

const FONT: &[u8] = include_bytes!("fonts/DejaVuSansMono.ttf");

/// Plot size in pixels.
pub(super) const PLOT_SIZE: (u32, u32) = (960, 600);

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The embedded font is a valid TrueType file; should it not load,
        // plotters reports a font error when drawing text, which `draw`
        // turns into an `ExperimentError`.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Line colour of each method: a hue per matrix method and search, darker
/// for each lookup further along [`ShadowLookup::ALL`] (`+spsm`: half,
/// the next a third).
pub(super) fn color(method: MethodSpec) -> RGBColor {
    let RGBColor(r, g, b) = match (method.cascade(), method.matrix(), method.search()) {
        (Some(CascadeMethod::Csm), ..) => RGBColor(140, 86, 75),
        (Some(CascadeMethod::Sdsm), ..) => RGBColor(188, 189, 34),
        (Some(CascadeMethod::SdsmLispsm), ..) => RGBColor(127, 127, 30),
        (Some(CascadeMethod::Optimized), ..) => RGBColor(90, 0, 20),
        (_, Method::Normal, _) => RGBColor(120, 120, 120),
        (_, Method::Focused, _) => RGBColor(31, 119, 180),
        (_, Method::FocusedSnapped, _) => RGBColor(23, 190, 207),
        (_, Method::LiSpsm, _) => RGBColor(44, 160, 44),
        (_, Method::Psm, _) => RGBColor(148, 103, 189),
        (_, Method::PlaneOptimal, _) => RGBColor(255, 127, 14),
        (_, _, Search::Paper) => RGBColor(214, 39, 40),
        (_, _, Search::Argmin) => RGBColor(227, 119, 194),
    };
    let darker = ShadowLookup::ALL.iter().position(|l| l.name() == method.lookup().name()).unwrap_or(0);
    let shade = |c: u8| c / (1 + darker.min(7) as u8);
    RGBColor(shade(r), shade(g), shade(b))
}

/// Draws with `plot` on a white bitmap and writes it to `path` as PNG.
fn draw(
    path: &Path,
    plot: impl FnOnce(&DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>) -> Result<(), String>,
) -> Result<(), ExperimentError> {
    register_font();
    let (w, h) = PLOT_SIZE;
    let mut buffer = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (w, h)).into_drawing_area();
        let result = root.fill(&WHITE).map_err(|e| e.to_string()).and_then(|()| plot(&root));
        let result = result.and_then(|()| root.present().map_err(|e| e.to_string()));
        result.map_err(|e| ExperimentError::Io { path: path.to_path_buf(), source: std::io::Error::other(e) })?;
    }
    let image = RgbImage::from_raw(w, h, buffer).unwrap_or_default();
    let mut png = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| ExperimentError::Io { path: path.to_path_buf(), source: std::io::Error::other(e) })?;
    super::rundir::write_atomic(path, &png)
}

/// `sorted-errors.png`: per method, its misclassified pixels per
/// configuration sorted ascending; y logarithmic (of 1 + pixels).
pub(super) fn sorted_errors(path: &Path, config: &ExperimentConfig, rows: &[ConfigRow]) -> Result<(), ExperimentError> {
    let series: Vec<(MethodSpec, Vec<u64>)> = config
        .methods
        .iter()
        .map(|&m| {
            let mut v: Vec<u64> = rows.iter().filter(|r| r.method == m).filter_map(|r| r.misclassified).collect();
            v.sort_unstable();
            (m, v)
        })
        .collect();
    let longest = series.iter().map(|(_, v)| v.len()).max().unwrap_or(0).max(2);
    let all = || series.iter().flat_map(|(_, v)| v.iter().copied());
    let top = all().max().unwrap_or(1).max(1) as f64 + 1.0;
    let bottom = ((all().min().unwrap_or(0) as f64 + 1.0) / 1.5).max(1.0).min(top / 2.0);
    draw(path, |root| {
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        let mut chart = ChartBuilder::on(root)
            .caption("Misclassified pixels per configuration, sorted", ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d(1i32..i32::try_from(longest).unwrap_or(i32::MAX), (bottom..top * 1.5).log_scale())
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc("rank of the configuration by this method's error (1 = best)")
            .y_desc("1 + misclassified pixels")
            .x_labels(longest.min(12))
            .y_label_formatter(&|y| format!("{y:.0}"))
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .draw()
            .map_err(e)?;
        for (m, v) in &series {
            let c = color(*m);
            let points = v.iter().enumerate().map(|(i, &p)| (i32::try_from(i + 1).unwrap_or(i32::MAX), p as f64 + 1.0));
            chart
                .draw_series(LineSeries::new(points, c.stroke_width(2)))
                .map_err(e)?
                .label(m.name())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3)));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(e)
    })
}

/// `equivalence.png`: the focused ladder's mean error (logarithmic)
/// against its map size, and each scene-optimized measurement with the focused
/// size that reaches the same mean error.
pub(super) fn equivalence(path: &Path, summary: &Summary) -> Result<(), ExperimentError> {
    let sizes =
        summary.ladder.iter().map(|&(s, _)| f64::from(s)).chain(summary.equivalence.iter().map(|e| f64::from(e.0)));
    let errors = summary.ladder.iter().map(|&(_, e)| e).chain(summary.equivalence.iter().map(|e| e.1));
    let (x0, x1) = sizes.fold((f64::INFINITY, 0f64), |(lo, hi), s| (lo.min(s), hi.max(s)));
    let (y0, y1) =
        errors.filter(|e| e.is_finite() && *e > 0.0).fold((f64::INFINITY, 0f64), |(lo, hi), e| (lo.min(e), hi.max(e)));
    let (y0, y1) = if y0 <= y1 { (y0 / 1.5, y1 * 1.5) } else { (0.1, 10.0) };
    let (x0, x1) = if x0 < x1 { (0.0, x1 * 1.05) } else { (0.0, 5000.0) };
    draw(path, |root| {
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        let mut chart = ChartBuilder::on(root)
            .caption("Resolution equivalence", ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc("shadow-map size (pixels per side)")
            .y_desc("mean misclassified pixels")
            .x_labels(10)
            .x_label_formatter(&|x| format!("{x:.0}"))
            .y_label_formatter(&|y| format!("{y:.0}"))
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .draw()
            .map_err(e)?;
        let focused = color(MethodSpec::FOCUSED);
        let ladder: Vec<(f64, f64)> =
            summary.ladder.iter().filter(|(_, m)| *m > 0.0).map(|&(s, m)| (f64::from(s), m)).collect();
        chart
            .draw_series(LineSeries::new(ladder.iter().copied(), focused.stroke_width(2)))
            .map_err(e)?
            .label("focused, by map size")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], focused.stroke_width(3)));
        chart.draw_series(ladder.iter().map(|&p| Circle::new(p, 4, focused.filled()))).map_err(e)?;
        let optimized = color(MethodSpec::OPTIMIZED);
        let points: Vec<(f64, f64)> =
            summary.equivalence.iter().filter(|(_, m, _)| *m > 0.0).map(|&(s, m, _)| (f64::from(s), m)).collect();
        chart
            .draw_series(points.iter().map(|&p| TriangleMarker::new(p, 7, optimized.filled())))
            .map_err(e)?
            .label("scene-optimized")
            .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 6, optimized.filled()));
        // Each measurement's equivalent focused size, joined by a thin line.
        for &(size, mean, eq) in &summary.equivalence {
            if let Some(eq) = eq.filter(|_| mean > 0.0) {
                let line = vec![(f64::from(size), mean), (eq, mean)];
                chart.draw_series(LineSeries::new(line, optimized.mix(0.6).stroke_width(1))).map_err(e)?;
                chart.draw_series([Cross::new((eq, mean), 6, optimized.stroke_width(2))]).map_err(e)?;
            }
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(e)
    })
}

#[cfg(test)]
mod tests {
    use super::super::Preset;
    use super::*;

    fn row(config: usize, method: MethodSpec, misclassified: u64) -> ConfigRow {
        ConfigRow {
            config,
            method,
            light: [0.0; 3],
            counted: Some(10_000),
            misclassified: Some(misclassified),
            false_shadow: Some(misclassified),
            false_lit: Some(0),
            frames: 1,
            truth: None,
            visibility_error: None,
            note: String::new(),
        }
    }

    /// Pixels that are neither white nor grey (plot lines in colour).
    fn coloured(image: &image::RgbImage, c: RGBColor) -> usize {
        image.pixels().filter(|p| p.0 == [c.0, c.1, c.2]).count()
    }

    #[test]
    fn plots_are_pngs_of_the_stated_size_with_axes_lines_and_text() {
        let dir = std::env::temp_dir().join(format!("lixel-plots-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let config = ExperimentConfig {
            methods: vec![MethodSpec::FOCUSED, MethodSpec::OPTIMIZED],
            ..ExperimentConfig::preset(Preset::Quick)
        };
        let rows: Vec<ConfigRow> = (0..12)
            .flat_map(|c| {
                [row(c, MethodSpec::FOCUSED, 100 + 37 * c as u64), row(c, MethodSpec::OPTIMIZED, 20 + 5 * c as u64)]
            })
            .collect();
        let path = dir.join("sorted-errors.png");
        sorted_errors(&path, &config, &rows).unwrap();
        let image = image::open(&path).unwrap().to_rgb8();
        assert_eq!(image.dimensions(), PLOT_SIZE);
        assert!(coloured(&image, color(MethodSpec::FOCUSED)) > 200, "focused line missing");
        assert!(coloured(&image, color(MethodSpec::OPTIMIZED)) > 200, "optimized line missing");
        // Text and axes: a good share of dark pixels.
        let dark = image.pixels().filter(|p| p.0.iter().all(|&v| v < 80)).count();
        assert!(dark > 2_000, "only {dark} dark pixels: no axes or labels");

        let summary = Summary {
            methods: Vec::new(),
            worst: Vec::new(),
            truth_agreement: None,
            equivalence: vec![(400, 120.0, Some(900.0)), (1024, 40.0, Some(2100.0))],
            ladder: vec![(400, 400.0), (800, 180.0), (1600, 80.0), (3200, 30.0)],
            lookup_equivalence: Vec::new(),
            elapsed: std::time::Duration::ZERO,
            warnings: Vec::new(),
            missing: Vec::new(),
            adapter: String::new(),
            stages: super::super::RunStages::default(),
        };
        let path = dir.join("equivalence.png");
        equivalence(&path, &summary).unwrap();
        let image = image::open(&path).unwrap().to_rgb8();
        assert_eq!(image.dimensions(), PLOT_SIZE);
        assert!(coloured(&image, color(MethodSpec::FOCUSED)) > 200, "ladder missing");
        assert!(coloured(&image, color(MethodSpec::OPTIMIZED)) > 50, "optimized markers missing");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
