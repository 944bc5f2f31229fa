//! An 8-bit RGBA image in memory and its PNG encoding (to bytes: writing files is the
//! caller's business).

use crate::error::VizError;

/// An 8-bit sRGB image with alpha. Pixels are row-major, top row first, 4 bytes each:
/// the pixel at column `x`, row `y` starts at byte `4 * (y * width + x)`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RgbaImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<u8>,
}

impl RgbaImage {
    /// An image filled with `colour`.
    pub fn filled(width: u32, height: u32, colour: [u8; 4]) -> Self {
        let pixels = colour.iter().copied().cycle().take(4 * width as usize * height as usize).collect();
        Self { width, height, pixels }
    }

    /// The pixel at column `x`, row `y`.
    pub fn get(&self, x: u32, y: u32) -> [u8; 4] {
        let i = self.offset(x, y);
        [self.pixels[i], self.pixels[i + 1], self.pixels[i + 2], self.pixels[i + 3]]
    }

    /// Sets the pixel at column `x`, row `y`; coordinates outside the image are ignored
    /// (text and bars may be clipped at the border).
    pub fn put(&mut self, x: i64, y: i64, colour: [u8; 4]) {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return;
        }
        let i = self.offset(x as u32, y as u32);
        self.pixels[i..i + 4].copy_from_slice(&colour);
    }

    /// Fills the rectangle `[x0, x1) × [y0, y1)`, clipped to the image.
    pub fn fill_rect(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, colour: [u8; 4]) {
        for y in y0.max(0)..y1.min(self.height as i64) {
            for x in x0.max(0)..x1.min(self.width as i64) {
                self.put(x, y, colour);
            }
        }
    }

    /// The rectangle of `width × height` pixels whose top-left corner is `(x, y)`,
    /// clipped to the image (so the result may be smaller than asked).
    pub fn crop(&self, x: u32, y: u32, width: u32, height: u32) -> Self {
        let width = width.min(self.width.saturating_sub(x));
        let height = height.min(self.height.saturating_sub(y));
        let mut pixels = Vec::with_capacity(4 * width as usize * height as usize);
        for row in y..y + height {
            let start = self.offset(x, row);
            pixels.extend_from_slice(&self.pixels[start..start + 4 * width as usize]);
        }
        Self { width, height, pixels }
    }

    /// Copies `other` into this image with its top-left corner at `(x, y)`, clipped.
    pub fn paste(&mut self, other: &RgbaImage, x: i64, y: i64) {
        for row in 0..other.height {
            for col in 0..other.width {
                self.put(x + col as i64, y + row as i64, other.get(col, row));
            }
        }
    }

    /// `images` side by side, left to right, top-aligned, on `background` (an empty
    /// list gives a 0 × 0 image).
    pub fn hstack(images: &[RgbaImage], background: [u8; 4]) -> Self {
        let width = images.iter().map(|i| i.width).sum();
        let height = images.iter().map(|i| i.height).max().unwrap_or(0);
        let mut out = Self::filled(width, height, background);
        let mut x = 0;
        for image in images {
            out.paste(image, x, 0);
            x += image.width as i64;
        }
        out
    }

    /// `images` stacked top to bottom, left-aligned, on `background`.
    pub fn vstack(images: &[RgbaImage], background: [u8; 4]) -> Self {
        let width = images.iter().map(|i| i.width).max().unwrap_or(0);
        let height = images.iter().map(|i| i.height).sum();
        let mut out = Self::filled(width, height, background);
        let mut y = 0;
        for image in images {
            out.paste(image, 0, y);
            y += image.height as i64;
        }
        out
    }

    fn offset(&self, x: u32, y: u32) -> usize {
        4 * (y as usize * self.width as usize + x as usize)
    }
}

/// Encodes `image` as an 8-bit RGBA PNG file's bytes.
pub fn encode_png(image: &RgbaImage) -> Result<Vec<u8>, VizError> {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, image.width, image.height);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| VizError::Png(e.to_string()))?;
    writer.write_image_data(&image.pixels).map_err(|e| VizError::Png(e.to_string()))?;
    writer.finish().map_err(|e| VizError::Png(e.to_string()))?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 × 1 and a 1 × 2 image side by side: 3 × 2, the short one padded with the
    /// background; stacking puts the second below the first.
    #[test]
    fn stacking_and_cropping_keep_pixels_in_place() {
        let (red, blue, white) = ([255, 0, 0, 255], [0, 0, 255, 255], [255; 4]);
        let a = RgbaImage::filled(2, 1, red);
        let b = RgbaImage::filled(1, 2, blue);
        let row = RgbaImage::hstack(&[a.clone(), b.clone()], white);
        assert_eq!((row.width, row.height), (3, 2));
        assert_eq!([row.get(1, 0), row.get(2, 0), row.get(0, 1), row.get(2, 1)], [red, blue, white, blue]);
        let column = RgbaImage::vstack(&[a, b], white);
        assert_eq!((column.width, column.height), (2, 3));
        assert_eq!([column.get(1, 0), column.get(0, 2), column.get(1, 2)], [red, blue, white]);
        let corner = row.crop(1, 1, 5, 5);
        assert_eq!((corner.width, corner.height), (2, 1), "clipped to the image");
        assert_eq!([corner.get(0, 0), corner.get(1, 0)], [white, blue]);
    }

    #[test]
    fn png_round_trips_through_the_decoder() {
        let mut image = RgbaImage::filled(3, 2, [255, 255, 255, 255]);
        image.put(2, 1, [10, 20, 30, 255]);
        image.put(5, 5, [0, 0, 0, 255]); // outside: ignored
        let bytes = encode_png(&image).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (3, 2));
        assert_eq!(&buf[..info.buffer_size()], &image.pixels[..]);
    }
}
