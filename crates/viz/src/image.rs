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
