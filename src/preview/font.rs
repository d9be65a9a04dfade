//! A 5×7 pixel bitmap font of the characters the legends use (digits, `% . - + ,`, a few
//! capitals and the `m` of mm), so that labels need no font file or font crate. Glyphs are drawn scaled by whole
//! pixels, which keeps them sharp at any image size.

/// Glyph width and height in font pixels; a character cell adds one column of spacing.
pub const GLYPH_W: u32 = 5;
/// Glyph height in font pixels.
pub const GLYPH_H: u32 = 7;

/// Each row of a glyph, top first, as five bits (the high bit is the left pixel).
fn glyph(c: char) -> Option<[u8; 7]> {
    let rows: [&str; 7] = match c {
        '0' => [
            "01110", "10001", "10011", "10101", "11001", "10001", "01110",
        ],
        '1' => [
            "00100", "01100", "00100", "00100", "00100", "00100", "01110",
        ],
        '2' => [
            "01110", "10001", "00001", "00010", "00100", "01000", "11111",
        ],
        '3' => [
            "11111", "00010", "00100", "00010", "00001", "10001", "01110",
        ],
        '4' => [
            "00010", "00110", "01010", "10010", "11111", "00010", "00010",
        ],
        '5' => [
            "11111", "10000", "11110", "00001", "00001", "10001", "01110",
        ],
        '6' => [
            "00110", "01000", "10000", "11110", "10001", "10001", "01110",
        ],
        '7' => [
            "11111", "00001", "00010", "00100", "01000", "01000", "01000",
        ],
        '8' => [
            "01110", "10001", "10001", "01110", "10001", "10001", "01110",
        ],
        '9' => [
            "01110", "10001", "10001", "01111", "00001", "00010", "01100",
        ],
        '%' => [
            "11000", "11001", "00010", "00100", "01000", "10011", "00011",
        ],
        '.' => [
            "00000", "00000", "00000", "00000", "00000", "01100", "01100",
        ],
        ',' => [
            "00000", "00000", "00000", "00000", "01100", "00100", "01000",
        ],
        '-' => [
            "00000", "00000", "00000", "11111", "00000", "00000", "00000",
        ],
        '+' => [
            "00000", "00100", "00100", "11111", "00100", "00100", "00000",
        ],
        ' ' => ["00000"; 7],
        'A' => [
            "01110", "10001", "10001", "11111", "10001", "10001", "10001",
        ],
        'B' => [
            "11110", "10001", "10001", "11110", "10001", "10001", "11110",
        ],
        'C' => [
            "01110", "10001", "10000", "10000", "10000", "10001", "01110",
        ],
        'D' => [
            "11100", "10010", "10001", "10001", "10001", "10010", "11100",
        ],
        'E' => [
            "11111", "10000", "10000", "11110", "10000", "10000", "11111",
        ],
        'G' => [
            "01110", "10001", "10000", "10111", "10001", "10001", "01111",
        ],
        'I' => [
            "01110", "00100", "00100", "00100", "00100", "00100", "01110",
        ],
        'M' => [
            "10001", "11011", "10101", "10101", "10001", "10001", "10001",
        ],
        'N' => [
            "10001", "10001", "11001", "10101", "10011", "10001", "10001",
        ],
        'O' => [
            "01110", "10001", "10001", "10001", "10001", "10001", "01110",
        ],
        'P' => [
            "11110", "10001", "10001", "11110", "10000", "10000", "10000",
        ],
        'R' => [
            "11110", "10001", "10001", "11110", "10100", "10010", "10001",
        ],
        'S' => [
            "01111", "10000", "10000", "01110", "00001", "00001", "11110",
        ],
        'T' => [
            "11111", "00100", "00100", "00100", "00100", "00100", "00100",
        ],
        'Y' => [
            "10001", "10001", "01010", "00100", "00100", "00100", "00100",
        ],
        // Lower case for units (mm), on the capitals' baseline with an x-height of 5 rows.
        'm' => [
            "00000", "00000", "11010", "10101", "10101", "10101", "10101",
        ],
        _ => return None,
    };
    Some(rows.map(|r| u8::from_str_radix(r, 2).expect("five binary digits")))
}

/// Whether every character of `text` has a glyph.
#[cfg(test)]
pub fn covers(text: &str) -> bool {
    text.chars().all(|c| glyph(c).is_some())
}

/// Width in image pixels of `text` at `scale` (cells of 6 font pixels, the last without its
/// spacing column).
pub fn text_width(text: &str, scale: u32) -> u32 {
    let n = text.chars().count() as u32;
    (n * (GLYPH_W + 1)).saturating_sub(1) * scale
}

/// Calls `plot(x, y)` for every image pixel of `text` drawn with its top-left corner at
/// (`x0`, `y0`), each font pixel a `scale × scale` square. Characters without a glyph are blank.
pub fn draw_text(text: &str, x0: i64, y0: i64, scale: u32, mut plot: impl FnMut(i64, i64)) {
    let s = scale as i64;
    for (k, c) in text.chars().enumerate() {
        let Some(rows) = glyph(c) else { continue };
        let cx = x0 + k as i64 * (GLYPH_W as i64 + 1) * s;
        for (r, bits) in rows.iter().enumerate() {
            for col in 0..GLYPH_W as i64 {
                if bits & (1 << (GLYPH_W as i64 - 1 - col)) != 0 {
                    for dy in 0..s {
                        for dx in 0..s {
                            plot(cx + col * s + dx, y0 + r as i64 * s + dy);
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glyphs_are_distinct_and_five_wide() {
        let chars = "0123456789%.,-+ABCDEGIMNOPRSTYm";
        let all: Vec<[u8; 7]> = chars.chars().map(|c| glyph(c).unwrap()).collect();
        for (i, a) in all.iter().enumerate() {
            assert!(a.iter().all(|r| *r < 32));
            for b in &all[i + 1..] {
                assert_ne!(a, b, "two glyphs look the same");
            }
        }
        assert_eq!(text_width("20%", 3), (3 * 6 - 1) * 3);
    }
}
