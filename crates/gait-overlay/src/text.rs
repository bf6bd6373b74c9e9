//! Text labels: DejaVu Sans glyphs rasterised once per size and blended
//! into the frame, so a label costs a few thousand pixel writes per frame.

use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};

use crate::canvas::Canvas;

/// DejaVu Sans 2.37 (Bitstream Vera licence), the file gait-eval's figures
/// embed (`crates/gait-eval/assets/`); shared rather than copied, so the
/// report and the overlay letter alike.
static DEJAVU_SANS: &[u8] = include_bytes!("../../gait-eval/assets/DejaVuSans.ttf");

/// First and last cached character: printable ASCII. Others draw as `?`
/// (every label this crate writes is ASCII).
const FIRST: u8 = b' ';
const LAST: u8 = b'~';

/// One glyph's coverage bitmap, placed relative to the pen on the baseline.
#[derive(Debug, Clone, Default)]
struct Glyph {
    /// Offset of the bitmap's top-left corner from the pen position.
    left: i32,
    top: i32,
    width: usize,
    height: usize,
    /// Coverage 0..=255, row by row.
    coverage: Vec<u8>,
    advance: f32,
}

/// Pre-rasterised printable ASCII at one pixel size.
#[derive(Debug, Clone)]
pub(crate) struct TextPainter {
    glyphs: Vec<Glyph>,
    ascent: f32,
    line_height: f32,
}

impl TextPainter {
    /// Rasterises the font at `px` pixels (the em height).
    pub(crate) fn new(px: f32) -> Self {
        // The font is embedded and known to be valid; an unreadable font
        // would be a build defect, which the tests show as missing text, so
        // fall back to an empty painter instead of failing a clinician's run.
        let Ok(font) = FontRef::try_from_slice(DEJAVU_SANS) else {
            return Self {
                glyphs: vec![Glyph::default(); usize::from(LAST - FIRST) + 1],
                ascent: px,
                line_height: px * 1.2,
            };
        };
        let scale = PxScale::from(px);
        let scaled = font.as_scaled(scale);
        let glyphs = (FIRST..=LAST)
            .map(|c| {
                let id = font.glyph_id(char::from(c));
                let advance = scaled.h_advance(id);
                let Some(outline) =
                    font.outline_glyph(id.with_scale_and_position(scale, point(0.0, 0.0)))
                else {
                    return Glyph {
                        advance,
                        ..Glyph::default()
                    };
                };
                let b = outline.px_bounds();
                let (width, height) = (b.width() as usize, b.height() as usize);
                let mut coverage = vec![0u8; width * height];
                outline.draw(|x, y, c| {
                    let i = y as usize * width + x as usize;
                    if let Some(px) = coverage.get_mut(i) {
                        *px = (c.clamp(0.0, 1.0) * 255.0).round() as u8;
                    }
                });
                Glyph {
                    left: b.min.x as i32,
                    top: b.min.y as i32,
                    width,
                    height,
                    coverage,
                    advance,
                }
            })
            .collect();
        Self {
            glyphs,
            ascent: scaled.ascent(),
            line_height: scaled.height() + scaled.line_gap(),
        }
    }

    fn glyph(&self, c: char) -> &Glyph {
        let code = u32::from(c);
        let i = if (u32::from(FIRST)..=u32::from(LAST)).contains(&code) {
            (code - u32::from(FIRST)) as usize
        } else {
            usize::from(b'?' - FIRST)
        };
        &self.glyphs[i]
    }

    /// Height of one line of text in pixels.
    pub(crate) fn line_height(&self) -> i32 {
        self.line_height.ceil() as i32
    }

    /// Width of `s` in pixels.
    pub(crate) fn width(&self, s: &str) -> i32 {
        s.chars().map(|c| self.glyph(c).advance).sum::<f32>().ceil() as i32
    }

    /// Draws `s` with its line box's top-left corner at (`x`, `y`).
    pub(crate) fn draw(&self, canvas: &mut Canvas, x: i32, y: i32, s: &str, colour: [u8; 3]) {
        let baseline = y + self.ascent.round() as i32;
        let mut pen = x as f32;
        for c in s.chars() {
            let g = self.glyph(c);
            let gx = pen.round() as i32 + g.left;
            let gy = baseline + g.top;
            for row in 0..g.height {
                let cov = &g.coverage[row * g.width..(row + 1) * g.width];
                for (col, &a) in cov.iter().enumerate() {
                    if a > 0 {
                        canvas.blend(gx + col as i32, gy + row as i32, colour, a);
                    }
                }
            }
            pen += g.advance;
        }
    }

    /// Draws `s` in `fg` on a filled box of `bg` (a padding of a quarter
    /// line around it) with the box's top-left corner at (`x`, `y`);
    /// returns the box's size, for stacking labels.
    pub(crate) fn label(
        &self,
        canvas: &mut Canvas,
        x: i32,
        y: i32,
        s: &str,
        fg: [u8; 3],
        bg: [u8; 3],
    ) -> (i32, i32) {
        let pad = (self.line_height() / 4).max(1);
        let (w, h) = (self.width(s) + 2 * pad, self.line_height() + pad);
        canvas.fill_rect(x, y, w, h, bg);
        self.draw(canvas, x + pad, y + pad / 2, s, fg);
        (w, h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_puts_ink_where_it_is_drawn() {
        let t = TextPainter::new(20.0);
        assert!(t.width("frame 12") > t.width("f"));
        assert!(t.line_height() >= 20);
        let (w, h) = (200usize, 40usize);
        let mut buf = vec![0u8; w * h * 3];
        let mut c = Canvas::new(&mut buf, w, 0, 0, w, h);
        t.draw(&mut c, 5, 5, "L heel strike", [255, 255, 255]);
        let ink = buf.chunks(3).filter(|p| p[0] > 128).count();
        assert!(ink > 100, "only {ink} lit pixels");
        // Nothing left of the start.
        assert!((0..h).all(|y| buf[(y * w + 2) * 3] == 0));
    }

    #[test]
    fn non_ascii_draws_as_question_mark() {
        let t = TextPainter::new(16.0);
        assert_eq!(t.width("é"), t.width("?"));
    }
}
