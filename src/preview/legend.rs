//! Draws a colour legend into a rendered image: a panel in the top-right corner with a title,
//! a vertical colour bar and labelled ticks. Drawn on the CPU after the readback, in whole
//! pixels, so that it is sharp and identical on every adapter.

use super::colors::Legend;
use super::font::{draw_text, text_width, GLYPH_H};
use glam::Vec3;

/// Linear → sRGB-encoded byte (the render target is sRGB, so the bar matches the cloth).
pub fn srgb_byte(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (255.0 * s + 0.5) as u8
}

/// Where the legend was drawn, in pixels: the panel and the colour bar (x0, y0, x1, y1),
/// exclusive ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LegendBox {
    /// The whole panel.
    pub panel: (u32, u32, u32, u32),
    /// The colour bar inside it (t = 1 at the top row, 0 at the bottom row).
    pub bar: (u32, u32, u32, u32),
}

/// The text scale for an image `height` px tall: a 7-pixel glyph becomes about 2.2% of the
/// height (14 px at 600, 21 px at 960, 49 px at 2160), never less than one pixel per font
/// pixel.
pub fn text_scale(height: u32) -> u32 {
    ((height + 160) / 320).max(1)
}

/// Draws `legend` into the RGBA8 `pixels` of a `width × height` image and returns where. The
/// panel is white at 80% opacity, so labels stay legible over cloth or background.
pub fn draw_legend(pixels: &mut [u8], width: u32, height: u32, legend: &Legend) -> LegendBox {
    let s = text_scale(height);
    let pad = 3 * s;
    let bar_w = 8 * s;
    // Ticks set apart from the labels by `pad`, so that they do not read as minus signs.
    let tick = 2 * s;
    let label_w = (legend.ticks.iter())
        .map(|(_, l)| text_width(l, s))
        .max()
        .unwrap_or(0);
    let title_w = text_width(&legend.title, s);
    let glyph_h = GLYPH_H * s;
    let inner_w = title_w.max(bar_w + tick + pad + label_w);
    let panel_w = (inner_w + 2 * pad).min(width);
    let bar_h = (height * 2 / 5).max(4 * glyph_h);
    // Half a glyph above the top tick and below the bottom one, so their labels fit.
    let panel_h = (pad + glyph_h + pad + glyph_h / 2 + bar_h + glyph_h / 2 + pad).min(height);
    let margin = 4 * s;
    let x0 = width.saturating_sub(panel_w + margin);
    let y0 = margin.min(height - panel_h);
    let (x1, y1) = (x0 + panel_w, y0 + panel_h);
    let mut put = |x: i64, y: i64, c: [u8; 3], alpha: f32| {
        if x < 0 || y < 0 || x >= width as i64 || y >= height as i64 {
            return;
        }
        let k = 4 * (y as usize * width as usize + x as usize);
        for (i, v) in c.iter().enumerate() {
            let old = pixels[k + i] as f32;
            pixels[k + i] = (old + alpha * (*v as f32 - old)).round() as u8;
        }
        pixels[k + 3] = 255;
    };
    for y in y0..y1 {
        for x in x0..x1 {
            put(x as i64, y as i64, [255; 3], 0.8);
        }
    }
    let ink = [20u8, 20, 20];
    draw_text(
        &legend.title,
        (x0 + pad) as i64,
        (y0 + pad) as i64,
        s,
        |x, y| put(x, y, ink, 1.0),
    );
    let bx0 = x0 + pad;
    let by0 = y0 + pad + glyph_h + pad + glyph_h / 2;
    let (bx1, by1) = (bx0 + bar_w, (by0 + bar_h).min(height));
    for y in by0..by1 {
        let t = 1.0 - (y - by0) as f32 / (bar_h - 1).max(1) as f32;
        let c: Vec3 = (legend.color)(t);
        let rgb = c.to_array().map(srgb_byte);
        for x in bx0..bx1 {
            put(x as i64, y as i64, rgb, 1.0);
        }
    }
    // Labels in the given order; one that would overlap an earlier one is left out (its tick
    // stays), which happens only in small images.
    let mut taken: Vec<(i64, i64)> = Vec::new();
    for (t, label) in &legend.ticks {
        let y = by0 as i64 + ((1.0 - t) * (bar_h - 1) as f32).round() as i64;
        for dy in 0..s.div_ceil(2) as i64 {
            for x in bx1 as i64..(bx1 + tick) as i64 {
                put(x, y + dy, ink, 1.0);
            }
        }
        let top = y - (glyph_h / 2) as i64;
        let span = (top - s as i64, top + glyph_h as i64 + s as i64);
        if taken.iter().any(|&(a, b)| span.0 < b && a < span.1) {
            continue;
        }
        taken.push(span);
        draw_text(label, (bx1 + tick + pad) as i64, top, s, |x, y| {
            put(x, y, ink, 1.0)
        });
    }
    LegendBox {
        panel: (x0, y0, x1, y1),
        bar: (bx0, by0, bx1, by1),
    }
}
