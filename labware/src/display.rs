//! Instrument displays drawn as textures: a bitmap font of our own (5x7 cells), a fixed layout of
//! glyph cells, and drawing into an RGB buffer. Pure pixels: the runtime uploads what a model
//! draws here to the GPU when the drawn state changes (retained mode), and a test reads the cells
//! back from rendered frames with the same glyphs.
//!
//! Fields have fixed cells (values are right-aligned, unused leading cells blank), so a reader can
//! find every digit without knowing the value.

/// One RGB colour.
pub type Rgb = [u8; 3];

/// Glyph grid size in font pixels.
pub const GLYPH_W: usize = 5;
pub const GLYPH_H: usize = 7;

/// The glyphs a display can show: rows top to bottom, bit 4 the leftmost pixel.
pub fn glyph(c: char) -> Option<[u8; GLYPH_H]> {
    Some(match c {
        '0' => [
            0b01110, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01110,
        ],
        '1' => [
            0b00100, 0b01100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110,
        ],
        '2' => [
            0b01110, 0b10001, 0b00001, 0b00110, 0b01000, 0b10000, 0b11111,
        ],
        '3' => [
            0b11110, 0b00001, 0b00001, 0b01110, 0b00001, 0b00001, 0b11110,
        ],
        '4' => [
            0b00010, 0b00110, 0b01010, 0b10010, 0b11111, 0b00010, 0b00010,
        ],
        '5' => [
            0b11111, 0b10000, 0b11110, 0b00001, 0b00001, 0b10001, 0b01110,
        ],
        '6' => [
            0b00110, 0b01000, 0b10000, 0b11110, 0b10001, 0b10001, 0b01110,
        ],
        '7' => [
            0b11111, 0b00001, 0b00010, 0b00100, 0b01000, 0b01000, 0b01000,
        ],
        '8' => [
            0b01110, 0b10001, 0b10001, 0b01110, 0b10001, 0b10001, 0b01110,
        ],
        '9' => [
            0b01110, 0b10001, 0b10001, 0b01111, 0b00001, 0b00010, 0b01100,
        ],
        ':' => [
            0b00000, 0b01100, 0b01100, 0b00000, 0b01100, 0b01100, 0b00000,
        ],
        '-' => [
            0b00000, 0b00000, 0b00000, 0b11111, 0b00000, 0b00000, 0b00000,
        ],
        '°' => [
            0b01100, 0b10010, 0b10010, 0b01100, 0b00000, 0b00000, 0b00000,
        ],
        'C' => [
            0b01110, 0b10001, 0b10000, 0b10000, 0b10000, 0b10001, 0b01110,
        ],
        'r' => [
            0b00000, 0b00000, 0b10110, 0b11001, 0b10000, 0b10000, 0b10000,
        ],
        'p' => [
            0b00000, 0b00000, 0b11110, 0b10001, 0b11110, 0b10000, 0b10000,
        ],
        'm' => [
            0b00000, 0b00000, 0b11010, 0b10101, 0b10101, 0b10101, 0b10101,
        ],
        'i' => [
            0b00100, 0b00000, 0b01100, 0b00100, 0b00100, 0b00100, 0b01110,
        ],
        'n' => [
            0b00000, 0b00000, 0b10110, 0b11001, 0b10001, 0b10001, 0b10001,
        ],
        's' => [
            0b00000, 0b00000, 0b01111, 0b10000, 0b01110, 0b00001, 0b11110,
        ],
        ' ' => [0; GLYPH_H],
        _ => return None,
    })
}

/// Whether font pixel (`col`, `row`) of `c` is set (blank for a character without a glyph).
pub fn ink(c: char, col: usize, row: usize) -> bool {
    glyph(c)
        .is_some_and(|g| col < GLYPH_W && row < GLYPH_H && g[row] >> (GLYPH_W - 1 - col) & 1 == 1)
}

/// A rectangle of texture pixels one glyph fills: top-left corner and font-pixel size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cell {
    pub x: usize,
    pub y: usize,
    pub scale: usize,
}

impl Cell {
    pub fn width(&self) -> usize {
        GLYPH_W * self.scale
    }

    pub fn height(&self) -> usize {
        GLYPH_H * self.scale
    }

    /// The character's ink at texture pixel (`x`, `y`), which must lie in the cell.
    pub fn ink_at(&self, c: char, x: usize, y: usize) -> bool {
        ink(c, (x - self.x) / self.scale, (y - self.y) / self.scale)
    }
}

/// A run of cells for one value: `len` cells from `first`, `advance` pixels apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Field {
    pub name: &'static str,
    pub first: Cell,
    pub len: usize,
    pub advance: usize,
}

impl Field {
    pub fn cell(&self, i: usize) -> Cell {
        Cell {
            x: self.first.x + i * self.advance,
            ..self.first
        }
    }

    /// `text` right-aligned in the field's cells (longer text keeps its last characters).
    pub fn cells(&self, text: &str) -> Vec<(Cell, char)> {
        let chars: Vec<char> = text.chars().collect();
        let skip = chars.len().saturating_sub(self.len);
        let pad = self.len.saturating_sub(chars.len());
        (0..self.len)
            .map(|i| {
                let c = if i < pad { ' ' } else { chars[skip + i - pad] };
                (self.cell(i), c)
            })
            .collect()
    }
}

/// An RGB canvas, row-major, top row first (MuJoCo's texture layout).
pub struct Canvas<'a> {
    pub width: usize,
    pub height: usize,
    pub rgb: &'a mut [u8],
}

impl Canvas<'_> {
    pub fn fill(&mut self, colour: Rgb) {
        for px in self.rgb.chunks_exact_mut(3) {
            px.copy_from_slice(&colour);
        }
    }

    pub fn rect(&mut self, x: usize, y: usize, w: usize, h: usize, colour: Rgb) {
        for row in y..(y + h).min(self.height) {
            for col in x..(x + w).min(self.width) {
                let at = 3 * (row * self.width + col);
                self.rgb[at..at + 3].copy_from_slice(&colour);
            }
        }
    }

    /// One character in a cell.
    pub fn glyph(&mut self, cell: Cell, c: char, colour: Rgb) {
        for row in 0..GLYPH_H {
            for col in 0..GLYPH_W {
                if ink(c, col, row) {
                    let (x, y) = (cell.x + col * cell.scale, cell.y + row * cell.scale);
                    self.rect(x, y, cell.scale, cell.scale, colour);
                }
            }
        }
    }

    /// Text from a cell onwards, `advance` pixels per character.
    pub fn text(&mut self, first: Cell, advance: usize, text: &str, colour: Rgb) {
        for (i, c) in text.chars().enumerate() {
            let cell = Cell {
                x: first.x + i * advance,
                ..first
            };
            self.glyph(cell, c, colour);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_digit_has_its_own_glyph() {
        let digits: Vec<[u8; GLYPH_H]> = ('0'..='9').map(|c| glyph(c).unwrap()).collect();
        for (i, a) in digits.iter().enumerate() {
            for b in &digits[i + 1..] {
                // At least two font pixels apart: a blurred pixel cannot turn one into another.
                let diff: u32 = a.iter().zip(b).map(|(x, y)| (x ^ y).count_ones()).sum();
                assert!(diff >= 2, "{a:?} {b:?}");
            }
        }
        assert!(glyph('x').is_none() && !ink('x', 0, 0));
    }

    #[test]
    fn values_are_right_aligned_in_fixed_cells() {
        let f = Field {
            name: "speed",
            first: Cell {
                x: 10,
                y: 4,
                scale: 2,
            },
            len: 4,
            advance: 12,
        };
        let cells = f.cells("900");
        assert_eq!(cells.len(), 4);
        assert_eq!(cells[0].1, ' ');
        assert_eq!((cells[1].0.x, cells[1].1), (22, '9'));
        let mut rgb = vec![0u8; 3 * 64 * 20];
        let mut canvas = Canvas {
            width: 64,
            height: 20,
            rgb: &mut rgb,
        };
        canvas.glyph(cells[3].0, '1', [255, 255, 255]);
        // '1' has ink at font pixel (2, 0): texture pixel (46 + 4, 4).
        let at = |x: usize, y: usize| rgb[3 * (y * 64 + x)];
        assert_eq!(at(50, 4), 255);
        assert_eq!(at(46, 4), 0);
        assert!(cells[3].0.ink_at('1', 50, 5));
    }
}
