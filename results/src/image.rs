//! One camera frame: 8-bit RGB, row-major, top row first, and its lossless PNG form (what
//! recordings store). Rendering is the runtime's; this is only the frame.

/// One rendered frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub camera: String,
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<u8>,
}

impl Image {
    /// The frame as PNG (fast compression; the same pixels always give the same bytes).
    pub fn to_png(&self) -> std::io::Result<Vec<u8>> {
        let mut out = Vec::with_capacity(self.rgb.len() / 2);
        let mut enc = png::Encoder::new(&mut out, self.width as u32, self.height as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Fast);
        let mut w = enc.write_header().map_err(std::io::Error::other)?;
        w.write_image_data(&self.rgb)
            .map_err(std::io::Error::other)?;
        w.finish().map_err(std::io::Error::other)?;
        Ok(out)
    }

    /// An 8-bit RGB PNG as a frame of `camera`.
    pub fn from_png(camera: &str, png_bytes: &[u8]) -> std::io::Result<Image> {
        let mut dec = png::Decoder::new(std::io::Cursor::new(png_bytes))
            .read_info()
            .map_err(std::io::Error::other)?;
        let info = dec.info();
        let (width, height) = (info.width as usize, info.height as usize);
        if (info.color_type, info.bit_depth) != (png::ColorType::Rgb, png::BitDepth::Eight) {
            return Err(std::io::Error::other("not an 8-bit RGB PNG"));
        }
        let mut rgb = vec![0; width * height * 3];
        dec.next_frame(&mut rgb).map_err(std::io::Error::other)?;
        Ok(Image {
            camera: camera.to_string(),
            width,
            height,
            rgb,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trips_the_pixels() {
        let rgb: Vec<u8> = (0..4 * 3 * 3).map(|i| (i * 7) as u8).collect();
        let img = Image {
            camera: "top".into(),
            width: 4,
            height: 3,
            rgb,
        };
        let back = Image::from_png("top", &img.to_png().unwrap()).unwrap();
        assert_eq!(back, img);
        assert!(Image::from_png("top", b"not a png").is_err());
    }
}
