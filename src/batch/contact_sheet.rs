//! Wedge contact sheets: previews tiled into one PNG grid with each tile's parameter values
//! printed under it, because people compare wedges by looking at them side by side.
use std::path::{Path, PathBuf};

use font8x8::UnicodeFonts;

use crate::error::{Error, Result};
use crate::render::image::{read_png, Rgb8};

const PAD: usize = 8;
const GLYPH: usize = 8;
const LINE: usize = GLYPH + 3;
const BACKGROUND: [u8; 3] = [24, 24, 28];
const INK: [u8; 3] = [230, 230, 230];

/// Drawing on an RGB8 canvas.
trait Canvas {
    fn filled(width: usize, height: usize, color: [u8; 3]) -> Self;
    fn put(&mut self, x: usize, y: usize, color: [u8; 3]);
    fn blit(&mut self, tile: &Rgb8, x0: usize, y0: usize);
    fn text(&mut self, text: &str, x0: usize, y0: usize, max_width: usize);
}

impl Canvas for Rgb8 {
    fn filled(width: usize, height: usize, color: [u8; 3]) -> Rgb8 {
        Rgb8 { width: width as u32, height: height as u32, data: color.repeat(width * height) }
    }

    fn put(&mut self, x: usize, y: usize, color: [u8; 3]) {
        let (w, h) = (self.width as usize, self.height as usize);
        if x < w && y < h {
            let i = 3 * (y * w + x);
            self.data[i..i + 3].copy_from_slice(&color);
        }
    }

    fn blit(&mut self, tile: &Rgb8, x0: usize, y0: usize) {
        let tw = tile.width as usize;
        for y in 0..tile.height as usize {
            for x in 0..tw {
                let i = 3 * (y * tw + x);
                self.put(x0 + x, y0 + y, [tile.data[i], tile.data[i + 1], tile.data[i + 2]]);
            }
        }
    }

    /// Prints ASCII text with the 8×8 public-domain font; characters it lacks print as '?'.
    fn text(&mut self, text: &str, x0: usize, y0: usize, max_width: usize) {
        for (k, c) in text.chars().take(max_width / GLYPH).enumerate() {
            let glyph =
                font8x8::BASIC_FONTS.get(c).or_else(|| font8x8::BASIC_FONTS.get('?')).unwrap_or([0; 8]);
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..8 {
                    if bits >> col & 1 == 1 {
                        self.put(x0 + k * GLYPH + col, y0 + row, INK);
                    }
                }
            }
        }
    }
}

/// Tiles `(preview, labels)` pairs into a grid, labels under each tile, and writes `out`.
pub fn assemble(tiles: &[(PathBuf, Vec<String>)], out: &Path) -> Result<Rgb8> {
    if tiles.is_empty() {
        return Err(Error::Usage("a contact sheet needs at least one preview".into()));
    }
    let images: Vec<Rgb8> = tiles.iter().map(|(path, _)| read_png(path)).collect::<Result<_>>()?;
    let tile_w = images.iter().map(|i| i.width as usize).max().unwrap().max(16 * GLYPH);
    let tile_h = images.iter().map(|i| i.height as usize).max().unwrap();
    let label_lines = tiles.iter().map(|(_, l)| l.len()).max().unwrap_or(0);
    let cell_w = tile_w + PAD;
    let cell_h = tile_h + PAD + label_lines * LINE;
    let columns = (tiles.len() as f64).sqrt().ceil() as usize;
    let rows = tiles.len().div_ceil(columns);
    let mut sheet = Rgb8::filled(PAD + columns * cell_w, PAD + rows * cell_h, BACKGROUND);
    for (k, (image, (_, labels))) in images.iter().zip(tiles).enumerate() {
        let (x0, y0) = (PAD + (k % columns) * cell_w, PAD + (k / columns) * cell_h);
        sheet.blit(image, x0, y0);
        for (line, label) in labels.iter().enumerate() {
            sheet.text(label, x0, y0 + tile_h + 2 + line * LINE, tile_w);
        }
    }
    sheet.write_png(out)?;
    Ok(sheet)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_land_in_a_grid_with_labels_under_them() {
        let dir = tempfile::tempdir().unwrap();
        let colors = [[255, 0, 0], [0, 255, 0], [0, 0, 255]];
        let tiles: Vec<(PathBuf, Vec<String>)> = colors
            .iter()
            .enumerate()
            .map(|(k, &c)| {
                let path = dir.path().join(format!("{k}.png"));
                Rgb8::filled(160, 120, c).write_png(&path).unwrap();
                (path, vec![format!("radius = {k}")])
            })
            .collect();
        let out = dir.path().join("sheet.png");
        let sheet = assemble(&tiles, &out).unwrap();
        assert_eq!(read_png(&out).unwrap(), sheet);
        // Three tiles: a 2 × 2 grid.
        let cell_w = 160 + PAD;
        let cell_h = 120 + PAD + LINE;
        assert_eq!((sheet.width as usize, sheet.height as usize), (PAD + 2 * cell_w, PAD + 2 * cell_h));
        let w = sheet.width as usize;
        let at = |x: usize, y: usize| &sheet.data[3 * (y * w + x)..3 * (y * w + x) + 3];
        assert_eq!(at(PAD + 80, PAD + 60), [255, 0, 0]);
        assert_eq!(at(PAD + cell_w + 80, PAD + 60), [0, 255, 0]);
        assert_eq!(at(PAD + 80, PAD + cell_h + 60), [0, 0, 255]);
        // Some ink under the first tile, none under the empty fourth cell.
        let ink_in = |x0: usize, y0: usize| (y0..y0 + GLYPH).any(|y| (x0..x0 + 80).any(|x| at(x, y) == INK));
        assert!(ink_in(PAD, PAD + 122));
        assert!(!ink_in(PAD + cell_w, PAD + cell_h + 122));
    }
}
