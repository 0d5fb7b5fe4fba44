//! The HUD: lines of text and the density legend, rasterized on the CPU
//! with ab_glyph (the experiment's embedded DejaVu Sans Mono) into a small
//! picture that the composite pass lays over the top-left corner. A text
//! HUD of our own costs one small crate, where an immediate-mode UI
//! (egui) would have added several to every CI build.

use std::sync::OnceLock;

use ab_glyph::{Font, FontRef, PxScale, ScaleFont};
use image::{Rgba, RgbaImage};

const FONT: &[u8] = include_bytes!("../experiment/fonts/DejaVuSansMono.ttf");
const SCALE: f32 = 14.0;
const LINE: u32 = 17;
const PAD: u32 = 6;
const LEGEND_WIDTH: u32 = 288;

fn font() -> Option<&'static FontRef<'static>> {
    static FONT_REF: OnceLock<Option<FontRef<'static>>> = OnceLock::new();
    FONT_REF.get_or_init(|| FontRef::try_from_slice(FONT).ok()).as_ref()
}

/// The density colour ramp, the same as `density_color` in
/// `shaders/view_composite.wgsl`: log2(b) from -4 to 8; blue, green (b = 1),
/// yellow (b = 16), red (b = 256). Linear RGB in [0, 1].
#[must_use]
pub fn density_color(b: f64) -> [f64; 3] {
    let t = ((b.max(1e-12).log2() + 4.0) / 12.0).clamp(0.0, 1.0) * 3.0;
    let stops = [[0.15, 0.3, 1.0], [0.1, 0.85, 0.25], [1.0, 0.85, 0.1], [0.95, 0.1, 0.1]];
    let i = (t.floor() as usize).min(2);
    let f = t - i as f64;
    std::array::from_fn(|c| stops[i][c] * (1.0 - f) + stops[i + 1][c] * f)
}

/// Linear colour to sRGB bytes.
fn srgb_byte(linear: f64) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0).round() as u8
}

/// Draws `text` with its top-left corner at (x, y) in `color`.
fn draw_text(image: &mut RgbaImage, x: u32, y: u32, text: &str, color: [u8; 3]) {
    let Some(font) = font() else { return };
    let scaled = font.as_scaled(PxScale::from(SCALE));
    let mut caret = x as f32;
    let baseline = y as f32 + scaled.ascent();
    for c in text.chars() {
        let glyph = scaled.scaled_glyph(c);
        let advance = scaled.h_advance(glyph.id);
        let glyph = ab_glyph::Glyph { position: ab_glyph::point(caret, baseline), ..glyph };
        if let Some(outlined) = font.outline_glyph(glyph) {
            let bounds = outlined.px_bounds();
            outlined.draw(|gx, gy, coverage| {
                let (px, py) = (bounds.min.x as i64 + i64::from(gx), bounds.min.y as i64 + i64::from(gy));
                if px < 0 || py < 0 || px >= i64::from(image.width()) || py >= i64::from(image.height()) {
                    return;
                }
                let p = image.get_pixel_mut(px as u32, py as u32);
                let a = coverage.clamp(0.0, 1.0);
                for (channel, &c) in p.0.iter_mut().zip(&color) {
                    *channel = (f32::from(*channel) * (1.0 - a) + f32::from(c) * a).round() as u8;
                }
                p.0[3] = p.0[3].max((a * 255.0) as u8);
            });
        }
        caret += advance;
    }
}

/// The HUD picture: `lines` of text on a translucent dark panel and, with
/// `legend`, the density colour bar with its scale underneath.
#[must_use]
pub(crate) fn render(lines: &[String], legend: bool) -> RgbaImage {
    let advance = font().map_or(8.0, |f| f.as_scaled(PxScale::from(SCALE)).h_advance(f.glyph_id('M')));
    let text_width = lines.iter().map(|l| l.chars().count()).max().unwrap_or(0) as f32 * advance;
    let width = (text_width.ceil() as u32 + 2 * PAD).max(if legend { LEGEND_WIDTH + 2 * PAD } else { 0 });
    let legend_height = if legend { 2 * LINE + 14 } else { 0 };
    let height = lines.len() as u32 * LINE + 2 * PAD + legend_height;
    let mut image = RgbaImage::from_pixel(width, height, Rgba([10, 12, 16, 190]));
    for (i, line) in lines.iter().enumerate() {
        draw_text(&mut image, PAD, PAD + i as u32 * LINE, line, [235, 235, 235]);
    }
    if legend {
        let top = PAD + lines.len() as u32 * LINE + 4;
        draw_text(&mut image, PAD, top, "density b (px per texel)², grey: no map", [235, 235, 235]);
        let bar = top + LINE;
        for x in 0..LEGEND_WIDTH {
            // log2(b) from -4 to 8 across the bar.
            let b = 2f64.powf(-4.0 + 12.0 * (f64::from(x) + 0.5) / f64::from(LEGEND_WIDTH));
            let c = density_color(b).map(srgb_byte);
            for y in bar..bar + 10 {
                image.put_pixel(PAD + x, y, Rgba([c[0], c[1], c[2], 255]));
            }
        }
        for (label, log2) in [("1/16", -4.0), ("1", 0.0), ("16", 4.0), ("256", 8.0)] {
            let x =
                PAD as f64 + f64::from(LEGEND_WIDTH) * (log2 + 4.0) / 12.0 - advance as f64 * label.len() as f64 / 2.0;
            let x = x.clamp(0.0, f64::from(width) - advance as f64 * label.len() as f64);
            draw_text(&mut image, x as u32, bar + 11, label, [235, 235, 235]);
        }
    }
    image
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_hits_its_stops() {
        assert_eq!(density_color(1.0 / 16.0), [0.15, 0.3, 1.0]);
        let one = density_color(1.0);
        assert!((one[1] - 0.85).abs() < 1e-9, "{one:?}");
        assert_eq!(density_color(1e9), [0.95, 0.1, 0.1]);
    }

    #[test]
    fn text_is_drawn() {
        let blank = render(&[String::new()], false);
        let text = render(&["lixel 123".to_string()], false);
        let lit = |img: &RgbaImage| img.pixels().filter(|p| p.0[0] > 128).count();
        assert_eq!(lit(&blank), 0);
        assert!(lit(&text) > 20, "{} bright pixels", lit(&text));
    }
}
