//! Pixel primitives on one panel of the RGB24 output frame.
//!
//! Frames are drawn straight into the byte buffer that goes to ffmpeg (no
//! intermediate image), and every primitive writes whole row spans, so a
//! 1080p frame costs little more than its copy.

use image::RgbImage;

/// A rectangle of an RGB24 buffer; all drawing is clipped to it.
pub(crate) struct Canvas<'a> {
    buf: &'a mut [u8],
    /// Pixels per row of `buf`.
    stride: usize,
    x0: usize,
    y0: usize,
    w: usize,
    h: usize,
}

impl<'a> Canvas<'a> {
    /// The panel at (`x0`, `y0`) of size `w` x `h` in a buffer `stride`
    /// pixels wide. A panel reaching past the buffer is cut to it.
    pub(crate) fn new(
        buf: &'a mut [u8],
        stride: usize,
        x0: usize,
        y0: usize,
        w: usize,
        h: usize,
    ) -> Self {
        let rows = (buf.len() / 3).checked_div(stride).unwrap_or(0);
        let w = w.min(stride.saturating_sub(x0));
        // An empty panel has no rows either, so no row offset is ever taken.
        let h = if w == 0 {
            0
        } else {
            h.min(rows.saturating_sub(y0))
        };
        Self {
            buf,
            stride,
            x0,
            y0,
            w,
            h,
        }
    }

    pub(crate) fn height(&self) -> usize {
        self.h
    }

    /// Byte offset of panel pixel (`x`, `y`), which must be inside.
    fn at(&self, x: usize, y: usize) -> usize {
        ((self.y0 + y) * self.stride + self.x0 + x) * 3
    }

    /// Bytes of panel row `y` from column `x0` to `x1` (exclusive).
    fn row(&mut self, y: usize, x0: usize, x1: usize) -> &mut [u8] {
        let a = self.at(x0, y);
        let b = self.at(x1, y);
        &mut self.buf[a..b]
    }

    /// Panel pixel (`x`, `y`), if inside.
    #[cfg(test)]
    pub(crate) fn get(&self, x: usize, y: usize) -> Option<[u8; 3]> {
        (x < self.w && y < self.h).then(|| {
            let i = self.at(x, y);
            [self.buf[i], self.buf[i + 1], self.buf[i + 2]]
        })
    }

    /// Mixes `c` into pixel (`x`, `y`) with opacity `alpha` (255 = opaque).
    pub(crate) fn blend(&mut self, x: i32, y: i32, c: [u8; 3], alpha: u8) {
        if x < 0 || y < 0 || x as usize >= self.w || y as usize >= self.h {
            return;
        }
        let i = self.at(x as usize, y as usize);
        let a = u16::from(alpha);
        for (dst, &src) in self.buf[i..i + 3].iter_mut().zip(&c) {
            let old = u16::from(*dst);
            *dst = ((u16::from(src) * a + old * (255 - a) + 127) / 255) as u8;
        }
    }

    /// Paints row `y` from `x0` to `x1` (both inclusive, clipped) in `c`.
    pub(crate) fn hspan(&mut self, y: i32, x0: i32, x1: i32, c: [u8; 3]) {
        if y < 0 || y as usize >= self.h || x1 < 0 || x0 as i64 >= self.w as i64 || x1 < x0 {
            return;
        }
        let a = x0.max(0) as usize;
        let b = (x1 as usize + 1).min(self.w);
        for px in self.row(y as usize, a, b).chunks_exact_mut(3) {
            px.copy_from_slice(&c);
        }
    }

    /// Fills the `w` x `h` rectangle at (`x`, `y`) (clipped) with `c`.
    pub(crate) fn fill_rect(&mut self, x: i32, y: i32, w: i32, h: i32, c: [u8; 3]) {
        for yy in y..y.saturating_add(h) {
            self.hspan(yy, x, x.saturating_add(w) - 1, c);
        }
    }

    /// Fills the whole panel with `c`.
    pub(crate) fn fill(&mut self, c: [u8; 3]) {
        self.fill_rect(0, 0, self.w as i32, self.h as i32, c);
    }

    /// Multiplies every channel of the panel by `factor` (0..=1): the dimming
    /// of frames that do not count.
    pub(crate) fn dim(&mut self, factor: f32) {
        // Fixed point: a lookup table keeps this to one load per byte.
        let f = factor.clamp(0.0, 1.0);
        let lut: Vec<u8> = (0..=255u16)
            .map(|v| (f32::from(v) * f).round() as u8)
            .collect();
        for y in 0..self.h {
            for b in self.row(y, 0, self.w) {
                *b = lut[usize::from(*b)];
            }
        }
    }

    /// Copies `src` into the panel, resampled to fill it: a plain row copy at
    /// the same size, a 2x2 average at exactly half size, nearest neighbour
    /// otherwise (regenerated frames of another size).
    pub(crate) fn blit(&mut self, src: &RgbImage) {
        let (sw, sh) = (src.width() as usize, src.height() as usize);
        if sw == 0 || sh == 0 || self.w == 0 || self.h == 0 {
            return;
        }
        let s = src.as_raw();
        if sw == self.w && sh == self.h {
            for y in 0..self.h {
                let w = self.w;
                self.row(y, 0, w)
                    .copy_from_slice(&s[y * sw * 3..(y * sw + w) * 3]);
            }
        } else if sw / 2 == self.w && sh / 2 == self.h {
            for y in 0..self.h {
                let (r0, r1) = ((2 * y) * sw * 3, (2 * y + 1) * sw * 3);
                let w = self.w;
                let out = self.row(y, 0, w);
                for x in 0..w {
                    for k in 0..3 {
                        let i = 6 * x + k;
                        let sum = u16::from(s[r0 + i])
                            + u16::from(s[r0 + i + 3])
                            + u16::from(s[r1 + i])
                            + u16::from(s[r1 + i + 3]);
                        out[3 * x + k] = ((sum + 2) / 4) as u8;
                    }
                }
            }
        } else {
            let xs: Vec<usize> = (0..self.w).map(|x| x * sw / self.w).collect();
            for y in 0..self.h {
                let sy = y * sh / self.h;
                let w = self.w;
                let out = self.row(y, 0, w);
                for (x, &sx) in xs.iter().enumerate() {
                    let i = (sy * sw + sx) * 3;
                    out[3 * x..3 * x + 3].copy_from_slice(&s[i..i + 3]);
                }
            }
        }
    }

    /// A filled disc of radius `r` centred on (`cx`, `cy`).
    pub(crate) fn disc(&mut self, cx: f64, cy: f64, r: f64, c: [u8; 3]) {
        self.ring(cx, cy, 0.0, r, c);
    }

    /// The pixels between radius `r_in` and `r_out` around (`cx`, `cy`).
    pub(crate) fn ring(&mut self, cx: f64, cy: f64, r_in: f64, r_out: f64, c: [u8; 3]) {
        if !(cx.is_finite() && cy.is_finite() && r_out.is_finite()) || r_out <= 0.0 {
            return;
        }
        let (y0, y1) = ((cy - r_out).ceil() as i32, (cy + r_out).floor() as i32);
        for y in y0..=y1 {
            let dy = f64::from(y) - cy;
            let outer = (r_out * r_out - dy * dy).max(0.0).sqrt();
            let inner_sq = r_in * r_in - dy * dy;
            let (ol, or) = ((cx - outer).ceil() as i32, (cx + outer).floor() as i32);
            if r_in <= 0.0 || inner_sq <= 0.0 {
                self.hspan(y, ol, or, c);
            } else {
                // Two spans: left and right of the hole.
                let inner = inner_sq.sqrt();
                self.hspan(y, ol, (cx - inner).ceil() as i32 - 1, c);
                self.hspan(y, (cx + inner).floor() as i32 + 1, or, c);
            }
        }
    }

    /// A line of half-width `r` (round caps) from (`ax`, `ay`) to (`bx`, `by`).
    pub(crate) fn line(&mut self, ax: f64, ay: f64, bx: f64, by: f64, r: f64, c: [u8; 3]) {
        if ![ax, ay, bx, by, r].iter().all(|v| v.is_finite()) {
            return;
        }
        // Discs stamped every half radius overlap into a solid stroke; a
        // stroke far off the panel (a wild keypoint) is not walked at all.
        let len = (bx - ax).hypot(by - ay);
        let (w, h) = (self.w as f64, self.h as f64);
        if ax.min(bx) > w + r || ay.min(by) > h + r || ax.max(bx) < -r || ay.max(by) < -r {
            return;
        }
        let steps = (len / (r * 0.5).max(0.5)).ceil().min(1e5) as usize;
        for i in 0..=steps {
            let t = if steps == 0 {
                0.0
            } else {
                i as f64 / steps as f64
            };
            self.disc(ax + (bx - ax) * t, ay + (by - ay) * t, r, c);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn canvas(buf: &mut [u8], w: usize, h: usize) -> Canvas<'_> {
        Canvas::new(buf, w, 0, 0, w, h)
    }

    #[test]
    fn disc_and_ring_cover_the_right_pixels() {
        let mut buf = vec![0u8; 40 * 40 * 3];
        let mut c = canvas(&mut buf, 40, 40);
        c.disc(10.0, 10.0, 3.0, [255, 0, 0]);
        assert_eq!(c.get(10, 10), Some([255, 0, 0]));
        assert_eq!(c.get(13, 10), Some([255, 0, 0]));
        assert_eq!(c.get(14, 10), Some([0, 0, 0]));
        c.ring(30.0, 30.0, 4.0, 6.0, [0, 0, 255]);
        assert_eq!(c.get(30, 30), Some([0, 0, 0]), "the hole stays");
        assert_eq!(c.get(35, 30), Some([0, 0, 255]));
    }

    #[test]
    fn drawing_is_clipped_to_the_panel() {
        // A 10x10 panel at (5, 5) of a 20x20 buffer.
        let mut buf = vec![0u8; 20 * 20 * 3];
        let mut c = Canvas::new(&mut buf, 20, 5, 5, 10, 10);
        c.line(-50.0, 5.0, 80.0, 5.0, 2.0, [9, 9, 9]);
        c.disc(f64::NAN, 1.0, 3.0, [1, 1, 1]);
        c.fill_rect(-3, -3, 100, 1, [7, 7, 7]);
        let lit: Vec<(usize, usize)> = (0..20)
            .flat_map(|y| (0..20).map(move |x| (x, y)))
            .filter(|&(x, y)| buf[(y * 20 + x) * 3] != 0)
            .collect();
        assert!(!lit.is_empty());
        assert!(
            lit.iter()
                .all(|&(x, y)| (5..15).contains(&x) && (5..15).contains(&y))
        );
    }

    #[test]
    fn dim_scales_brightness() {
        let mut buf = vec![200u8; 4 * 4 * 3];
        canvas(&mut buf, 4, 4).dim(0.4);
        assert!(buf.iter().all(|&b| b == 80));
    }

    #[test]
    fn blit_copies_or_halves() {
        let src = RgbImage::from_fn(4, 2, |x, _| image::Rgb([x as u8 * 10, 0, 0]));
        let mut buf = vec![0u8; 4 * 2 * 3];
        canvas(&mut buf, 4, 2).blit(&src);
        assert_eq!(buf.as_slice(), src.as_raw().as_slice());
        let mut half = vec![0u8; 2 * 3];
        canvas(&mut half, 2, 1).blit(&src);
        assert_eq!(half[0], 5); // mean of 0 and 10
        assert_eq!(half[3], 25);
    }
}
