//! A tiny built-in 5×7 bitmap font for colour-bar labels and captions: digits, upper-case
//! letters (lower case is drawn as upper case) and the punctuation numbers and units
//! need. Built in so that the renderer needs no font file and no font library.

use crate::image::RgbaImage;

/// Glyph width and height in font pixels; one column of spacing follows each glyph.
pub const GLYPH_WIDTH: i64 = 5;
pub const GLYPH_HEIGHT: i64 = 7;

/// Each glyph is 7 rows, top first; bit 4 of a row is its leftmost pixel.
const GLYPHS: [(char, [u8; 7]); 50] = [
    ('0', [0b01110, 0b10001, 0b10011, 0b10101, 0b11001, 0b10001, 0b01110]),
    ('1', [0b00100, 0b01100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110]),
    ('2', [0b01110, 0b10001, 0b00001, 0b00010, 0b00100, 0b01000, 0b11111]),
    ('3', [0b11111, 0b00010, 0b00100, 0b00010, 0b00001, 0b10001, 0b01110]),
    ('4', [0b00010, 0b00110, 0b01010, 0b10010, 0b11111, 0b00010, 0b00010]),
    ('5', [0b11111, 0b10000, 0b11110, 0b00001, 0b00001, 0b10001, 0b01110]),
    ('6', [0b00110, 0b01000, 0b10000, 0b11110, 0b10001, 0b10001, 0b01110]),
    ('7', [0b11111, 0b00001, 0b00010, 0b00100, 0b01000, 0b01000, 0b01000]),
    ('8', [0b01110, 0b10001, 0b10001, 0b01110, 0b10001, 0b10001, 0b01110]),
    ('9', [0b01110, 0b10001, 0b10001, 0b01111, 0b00001, 0b00010, 0b01100]),
    ('A', [0b01110, 0b10001, 0b10001, 0b11111, 0b10001, 0b10001, 0b10001]),
    ('B', [0b11110, 0b10001, 0b10001, 0b11110, 0b10001, 0b10001, 0b11110]),
    ('C', [0b01110, 0b10001, 0b10000, 0b10000, 0b10000, 0b10001, 0b01110]),
    ('D', [0b11100, 0b10010, 0b10001, 0b10001, 0b10001, 0b10010, 0b11100]),
    ('E', [0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b11111]),
    ('F', [0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b10000]),
    ('G', [0b01110, 0b10001, 0b10000, 0b10111, 0b10001, 0b10001, 0b01111]),
    ('H', [0b10001, 0b10001, 0b10001, 0b11111, 0b10001, 0b10001, 0b10001]),
    ('I', [0b01110, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110]),
    ('J', [0b00111, 0b00010, 0b00010, 0b00010, 0b00010, 0b10010, 0b01100]),
    ('K', [0b10001, 0b10010, 0b10100, 0b11000, 0b10100, 0b10010, 0b10001]),
    ('L', [0b10000, 0b10000, 0b10000, 0b10000, 0b10000, 0b10000, 0b11111]),
    ('M', [0b10001, 0b11011, 0b10101, 0b10101, 0b10001, 0b10001, 0b10001]),
    ('N', [0b10001, 0b10001, 0b11001, 0b10101, 0b10011, 0b10001, 0b10001]),
    ('O', [0b01110, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01110]),
    ('P', [0b11110, 0b10001, 0b10001, 0b11110, 0b10000, 0b10000, 0b10000]),
    ('Q', [0b01110, 0b10001, 0b10001, 0b10001, 0b10101, 0b10010, 0b01101]),
    ('R', [0b11110, 0b10001, 0b10001, 0b11110, 0b10100, 0b10010, 0b10001]),
    ('S', [0b01111, 0b10000, 0b10000, 0b01110, 0b00001, 0b00001, 0b11110]),
    ('T', [0b11111, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100]),
    ('U', [0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01110]),
    ('V', [0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01010, 0b00100]),
    ('W', [0b10001, 0b10001, 0b10001, 0b10101, 0b10101, 0b10101, 0b01010]),
    ('X', [0b10001, 0b10001, 0b01010, 0b00100, 0b01010, 0b10001, 0b10001]),
    ('Y', [0b10001, 0b10001, 0b10001, 0b01010, 0b00100, 0b00100, 0b00100]),
    ('Z', [0b11111, 0b00001, 0b00010, 0b00100, 0b01000, 0b10000, 0b11111]),
    ('.', [0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b01100, 0b01100]),
    (',', [0b00000, 0b00000, 0b00000, 0b00000, 0b01100, 0b00100, 0b01000]),
    ('-', [0b00000, 0b00000, 0b00000, 0b11111, 0b00000, 0b00000, 0b00000]),
    ('+', [0b00000, 0b00100, 0b00100, 0b11111, 0b00100, 0b00100, 0b00000]),
    ('=', [0b00000, 0b00000, 0b11111, 0b00000, 0b11111, 0b00000, 0b00000]),
    (':', [0b00000, 0b01100, 0b01100, 0b00000, 0b01100, 0b01100, 0b00000]),
    ('(', [0b00010, 0b00100, 0b01000, 0b01000, 0b01000, 0b00100, 0b00010]),
    (')', [0b01000, 0b00100, 0b00010, 0b00010, 0b00010, 0b00100, 0b01000]),
    ('/', [0b00000, 0b00001, 0b00010, 0b00100, 0b01000, 0b10000, 0b00000]),
    ('%', [0b11000, 0b11001, 0b00010, 0b00100, 0b01000, 0b10011, 0b00011]),
    ('^', [0b00100, 0b01010, 0b10001, 0b00000, 0b00000, 0b00000, 0b00000]),
    ('_', [0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b11111]),
    (' ', [0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000]),
    ('?', [0b01110, 0b10001, 0b00001, 0b00010, 0b00100, 0b00000, 0b00100]),
];

/// The rows of `c`'s glyph; characters without a glyph are drawn as `?`.
fn glyph(c: char) -> [u8; 7] {
    let c = c.to_ascii_uppercase();
    GLYPHS
        .iter()
        .find(|(g, _)| *g == c)
        .or_else(|| GLYPHS.iter().find(|(g, _)| *g == '?'))
        .map(|(_, rows)| *rows)
        .unwrap_or_default()
}

/// Width in image pixels of `text` drawn at `scale`.
pub fn text_width(text: &str, scale: i64) -> i64 {
    text.chars().count() as i64 * (GLYPH_WIDTH + 1) * scale
}

/// Draws `text` with its top-left corner at `(x, y)`, each font pixel a `scale × scale`
/// block, clipped to the image.
pub fn draw_text(image: &mut RgbaImage, x: i64, y: i64, text: &str, scale: i64, colour: [u8; 4]) {
    for (k, c) in text.chars().enumerate() {
        let left = x + k as i64 * (GLYPH_WIDTH + 1) * scale;
        for (row, bits) in glyph(c).iter().enumerate() {
            for col in 0..GLYPH_WIDTH {
                if bits & (1 << (GLYPH_WIDTH - 1 - col)) != 0 {
                    let (px, py) = (left + col * scale, y + row as i64 * scale);
                    image.fill_rect(px, py, px + scale, py + scale, colour);
                }
            }
        }
    }
}

/// A short label for a colour-bar tick: three significant digits, trailing zeros
/// dropped; plain decimals between 0.01 and 10000, scientific notation (`1.5e-4`)
/// outside.
pub fn format_tick(value: f64) -> String {
    format_significant(value, 3)
}

/// Labels for a row of axis ticks: [`format_tick`]'s, with more significant digits
/// (up to 6) when three would print two different ticks alike (`1.45e-4`, `1.5e-4`,
/// `1.55e-4` rather than `1.5e-4` twice).
pub fn format_ticks(values: &[f64]) -> Vec<String> {
    let mut labels = Vec::new();
    for digits in 3..=6 {
        labels = values.iter().map(|&v| format_significant(v, digits)).collect();
        let mut sorted = labels.clone();
        sorted.sort();
        sorted.dedup();
        if sorted.len() == labels.len() {
            break;
        }
    }
    labels
}

/// `value` with `digits` significant digits, trailing zeros (and a bare point) dropped.
fn format_significant(value: f64, digits: usize) -> String {
    let magnitude = value.abs();
    if value == 0.0 {
        return "0".into();
    }
    let trim = |text: &str| -> String {
        if text.contains('.') {
            text.trim_end_matches('0').trim_end_matches('.').to_owned()
        } else {
            text.into()
        }
    };
    if !(1e-2..1e4).contains(&magnitude) {
        let text = format!("{value:.prec$e}", prec = digits - 1);
        let (mantissa, exponent) = text.split_once('e').expect("`e` formatting has an exponent");
        return format!("{}e{exponent}", trim(mantissa));
    }
    let decimals = (digits as i64 - 1 - magnitude.log10().floor() as i64).max(0) as usize;
    trim(&format!("{value:.decimals$}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_short_and_exact_enough() {
        assert_eq!(format_tick(0.0), "0");
        assert_eq!(format_tick(1.0), "1");
        assert_eq!(format_tick(0.5), "0.5");
        assert_eq!(format_tick(0.25), "0.25");
        assert_eq!(format_tick(5.556), "5.56");
        assert_eq!(format_tick(123.4), "123");
        assert_eq!(format_tick(-0.0123), "-0.0123");
        assert_eq!(format_tick(1.5e-4), "1.5e-4");
        assert_eq!(format_tick(3.08e-2), "0.0308");
        assert_eq!(format_tick(1.53e-4), "1.53e-4");
    }

    #[test]
    fn axis_ticks_get_the_digits_that_tell_them_apart() {
        assert_eq!(format_ticks(&[1.45e-4, 1.5e-4, 1.55e-4]), ["1.45e-4", "1.5e-4", "1.55e-4"]);
        assert_eq!(format_ticks(&[1.0e-4, 1.0001e-4]), ["1e-4", "1.0001e-4"]);
        assert_eq!(format_ticks(&[0.5, 1.0]), ["0.5", "1"]);
    }

    #[test]
    fn every_character_of_a_tick_or_unit_has_a_glyph() {
        let question = glyph('?');
        for c in "0123456789.-+e()/%^ms".chars() {
            assert!(c == '?' || glyph(c) != question, "{c}");
        }
        assert_eq!(glyph('é'), question);
    }

    #[test]
    fn text_is_drawn_where_asked() {
        let mut image = RgbaImage::filled(40, 20, [255; 4]);
        draw_text(&mut image, 2, 3, "1", 2, [0, 0, 0, 255]);
        // '1' has its stem in column 2 of the glyph: image x = 2 + 2*2 = 6, rows 3..17.
        assert_eq!(image.get(6, 5), [0, 0, 0, 255]);
        assert_eq!(image.get(0, 0), [255; 4]);
        assert_eq!(text_width("abc", 2), 36);
    }
}
