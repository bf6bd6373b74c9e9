//! Canny edge detection that reproduces OpenCV's `cv::Canny` (aperture 3)
//! bit for bit: 3x3 Sobel with replicated borders, per pixel the channel with
//! the largest gradient magnitude (first channel on ties), L1 or L2 magnitude,
//! OpenCV's fixed-point sector test for non-maximum suppression with its
//! asymmetric tie rules, and 8-connected hysteresis.
//!
//! No blur is applied (ControlNet's canny annotator calls `cv2.Canny` on the
//! raw frame). Work is row by row over ring buffers, in integers.

use image::{GrayImage, RgbImage};
use serde::{Deserialize, Serialize};

/// tan(22.5 deg) in Q15, rounded as OpenCV does.
const TG22: i32 = 13573;
const SHIFT: u32 = 15;

/// Map states during suppression and hysteresis.
const MAYBE: u8 = 0;
const NEVER: u8 = 1;
const EDGE: u8 = 2;

/// Thresholds and gradient norm of [`Canny`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CannyParams {
    /// Weak-edge threshold (pixels above it survive when connected to a strong one).
    pub low: f64,
    /// Strong-edge threshold.
    pub high: f64,
    /// Use sqrt(dx^2 + dy^2) instead of |dx| + |dy| (OpenCV's `L2gradient`).
    pub l2_gradient: bool,
}

impl Default for CannyParams {
    /// ControlNet's canny annotator: `cv2.Canny(img, 100, 200)`.
    fn default() -> Self {
        Self {
            low: 100.0,
            high: 200.0,
            l2_gradient: false,
        }
    }
}

impl CannyParams {
    /// Integer thresholds on the magnitude as OpenCV derives them (swapped if
    /// reversed, squared for L2, then floored).
    fn integer_thresholds(&self) -> (i32, i32) {
        let (mut low, mut high) = if self.low > self.high {
            (self.high, self.low)
        } else {
            (self.low, self.high)
        };
        if self.l2_gradient {
            low = low.min(32767.0);
            high = high.min(32767.0);
            if low > 0.0 {
                low *= low;
            }
            if high > 0.0 {
                high *= high;
            }
        }
        // Saturating casts: NaN becomes 0, huge values the i32 range.
        (low.floor() as i32, high.floor() as i32)
    }
}

/// A reusable Canny detector; keeps its scratch buffers between calls so a
/// video is processed without per-frame allocation beyond the output.
#[derive(Debug, Default)]
pub struct Canny {
    params: CannyParams,
    /// Per-channel vertical smoothing `r0 + 2 r1 + r2` and difference `r2 - r0`.
    vsmooth: Vec<i16>,
    vdiff: Vec<i16>,
    /// Per-channel gradients and magnitudes of the newest row (`cmag` padded
    /// by one on each side, so a gray row can be swapped into the ring as is).
    cdx: Vec<i16>,
    cdy: Vec<i16>,
    cmag: Vec<i32>,
    /// Ring of three rows (previous, current, next): selected gradient and
    /// magnitude, the latter padded with one zero on each side.
    dx: [Vec<i16>; 3],
    dy: [Vec<i16>; 3],
    mag: [Vec<i32>; 3],
    /// (h + 2) x (w + 2) states; the frame of NEVER stops hysteresis at the border.
    map: Vec<u8>,
    stack: Vec<usize>,
}

impl Canny {
    pub fn new(params: CannyParams) -> Self {
        Self {
            params,
            ..Self::default()
        }
    }

    pub fn params(&self) -> &CannyParams {
        &self.params
    }

    /// Edges of an RGB image, as `cv2.Canny` on the HxWx3 array.
    pub fn rgb(&mut self, image: &RgbImage) -> GrayImage {
        let (w, h) = image.dimensions();
        self.run(image.as_raw(), w as usize, h as usize, 3)
    }

    /// Edges of a gray image, as `cv2.Canny` on the HxW array.
    pub fn gray(&mut self, image: &GrayImage) -> GrayImage {
        let (w, h) = image.dimensions();
        self.run(image.as_raw(), w as usize, h as usize, 1)
    }

    fn run(&mut self, data: &[u8], w: usize, h: usize, cn: usize) -> GrayImage {
        let mut out = GrayImage::new(w as u32, h as u32);
        if w == 0 || h == 0 {
            return out;
        }
        debug_assert_eq!(data.len(), w * h * cn);
        let (low, high) = self.params.integer_thresholds();
        let l2 = self.params.l2_gradient;
        let stride = w + 2;

        self.prepare(w, h, cn);
        let row = |y: usize| &data[y * w * cn..(y + 1) * w * cn];

        // Slot k % 3 holds row k; row -1 and row h are all-zero magnitudes.
        self.mag[2].fill(0);
        self.gradient_row(row(0), row(0), row(1.min(h - 1)), cn, l2, 0);
        for y in 0..h {
            let next = (y + 1) % 3;
            if y + 1 < h {
                let below = row((y + 2).min(h - 1));
                self.gradient_row(row(y), row(y + 1), below, cn, l2, next);
            } else {
                self.mag[next].fill(0);
            }
            self.suppress_row(y, w, stride, low, high);
        }
        self.hysteresis(stride);

        for (dst, src) in out
            .as_mut()
            .chunks_exact_mut(w)
            .zip(self.map.chunks_exact(stride).skip(1))
        {
            for (d, &s) in dst.iter_mut().zip(&src[1..=w]) {
                // EDGE (2) -> 255, MAYBE/NEVER (0/1) -> 0.
                *d = 0u8.wrapping_sub(s >> 1);
            }
        }
        out
    }

    fn prepare(&mut self, w: usize, h: usize, cn: usize) {
        let n = w * cn;
        for v in [
            &mut self.vsmooth,
            &mut self.vdiff,
            &mut self.cdx,
            &mut self.cdy,
        ] {
            v.clear();
            v.resize(n, 0);
        }
        self.cmag.clear();
        self.cmag.resize(n + 2, 0);
        for k in 0..3 {
            self.dx[k].clear();
            self.dx[k].resize(w, 0);
            self.dy[k].clear();
            self.dy[k].resize(w, 0);
            self.mag[k].clear();
            self.mag[k].resize(w + 2, 0);
        }
        self.map.clear();
        self.map.resize((w + 2) * (h + 2), NEVER);
        self.stack.clear();
    }

    /// Sobel gradients of the row `mid` (with its replicated neighbours
    /// `above`/`below`) into ring slot `slot`, keeping per pixel the channel
    /// of largest magnitude.
    fn gradient_row(
        &mut self,
        above: &[u8],
        mid: &[u8],
        below: &[u8],
        cn: usize,
        l2: bool,
        slot: usize,
    ) {
        let n = mid.len();
        for (((s, d), (&a, &m)), &b) in self
            .vsmooth
            .iter_mut()
            .zip(self.vdiff.iter_mut())
            .zip(above.iter().zip(mid))
            .zip(below)
        {
            *s = i16::from(a) + 2 * i16::from(m) + i16::from(b);
            *d = i16::from(b) - i16::from(a);
        }

        // Horizontal pass: dx = s[x+1] - s[x-1], dy = d[x-1] + 2 d[x] + d[x+1],
        // neighbours `cn` apart, replicated at the ends.
        let (vs, vd) = (&self.vsmooth, &self.vdiff);
        let (cdx, cdy) = (&mut self.cdx, &mut self.cdy);
        if n > 2 * cn {
            let inner = n - 2 * cn;
            let (l, c, r) = (&vs[..inner], &vs[2 * cn..], &mut cdx[cn..n - cn]);
            for ((o, &a), &b) in r.iter_mut().zip(l).zip(c) {
                *o = b - a;
            }
            let (l, c, rr) = (&vd[..inner], &vd[cn..n - cn], &vd[2 * cn..]);
            for (((o, &a), &b), &e) in cdy[cn..n - cn].iter_mut().zip(l).zip(c).zip(rr) {
                *o = a + 2 * b + e;
            }
        }
        // The first and last pixel (all channels) with replicated neighbours.
        let w = n / cn;
        for x in [0, w - 1] {
            let xl = x.saturating_sub(1);
            let xr = (x + 1).min(w - 1);
            for k in 0..cn {
                let (il, i, ir) = (xl * cn + k, x * cn + k, xr * cn + k);
                cdx[i] = vs[ir] - vs[il];
                cdy[i] = vd[il] + 2 * vd[i] + vd[ir];
            }
        }

        let cmag = &mut self.cmag[1..=n];
        if l2 {
            for ((m, &x), &y) in cmag.iter_mut().zip(cdx.iter()).zip(cdy.iter()) {
                *m = i32::from(x) * i32::from(x) + i32::from(y) * i32::from(y);
            }
        } else {
            for ((m, &x), &y) in cmag.iter_mut().zip(cdx.iter()).zip(cdy.iter()) {
                *m = i32::from(x).abs() + i32::from(y).abs();
            }
        }

        if cn == 1 {
            // The row is final: trade buffers with the ring instead of copying.
            std::mem::swap(&mut self.dx[slot], &mut self.cdx);
            std::mem::swap(&mut self.dy[slot], &mut self.cdy);
            std::mem::swap(&mut self.mag[slot], &mut self.cmag);
            let mag = &mut self.mag[slot];
            mag[0] = 0;
            mag[w + 1] = 0;
        } else {
            let (dx, dy, mag) = (
                &mut self.dx[slot],
                &mut self.dy[slot],
                &mut self.mag[slot][1..=w],
            );
            debug_assert_eq!(cn, 3, "only gray and RGB rows reach here");
            let picks = mag
                .iter_mut()
                .zip(dx.iter_mut())
                .zip(dy.iter_mut())
                .zip(cmag.chunks_exact(3))
                .zip(cdx.chunks_exact(3).zip(cdy.chunks_exact(3)));
            for ((((m, gx), gy), cm), (cx, cy)) in picks {
                // Strictly greater: ties keep the earlier channel, as OpenCV.
                let take1 = cm[1] > cm[0];
                let (m01, x01, y01) = if take1 {
                    (cm[1], cx[1], cy[1])
                } else {
                    (cm[0], cx[0], cy[0])
                };
                let take2 = cm[2] > m01;
                *m = if take2 { cm[2] } else { m01 };
                *gx = if take2 { cx[2] } else { x01 };
                *gy = if take2 { cy[2] } else { y01 };
            }
        }
    }

    /// Non-maximum suppression and double threshold of row `y` (ring slot
    /// `y % 3`): writes NEVER/MAYBE/EDGE into the map row and queues EDGE
    /// pixels for hysteresis.
    ///
    /// The per-pixel decision is branch-free over contiguous slices so the
    /// compiler vectorises it; textured photographs put too many pixels above
    /// `low` for a branchy scan to predict.
    fn suppress_row(&mut self, y: usize, w: usize, stride: usize, low: i32, high: i32) {
        let cur = y % 3;
        let (prev, mag, next) = (
            &self.mag[(y + 2) % 3],
            &self.mag[cur],
            &self.mag[(y + 1) % 3],
        );
        let map_row = (y + 1) * stride + 1;
        let out = &mut self.map[map_row..map_row + w];
        let (dx, dy) = (&self.dx[cur][..w], &self.dy[cur][..w]);
        // Views shifted by one pixel: left (x - 1), centre (x), right (x + 1).
        let (pl, pc, pr) = (&prev[..w], &prev[1..=w], &prev[2..w + 2]);
        let (cl, cc, cr) = (&mag[..w], &mag[1..=w], &mag[2..w + 2]);
        let (nl, nc, nr) = (&next[..w], &next[1..=w], &next[2..w + 2]);
        for x in 0..w {
            out[x] = classify(
                cc[x],
                dx[x],
                dy[x],
                [pl[x], pc[x], pr[x]],
                [cl[x], cr[x]],
                [nl[x], nc[x], nr[x]],
                low,
                high,
            );
        }

        const BLOCK: usize = 32;
        for (b, chunk) in out.chunks(BLOCK).enumerate() {
            if chunk.iter().fold(false, |any, &v| any | (v == EDGE)) {
                for (k, &v) in chunk.iter().enumerate() {
                    if v == EDGE {
                        self.stack.push(map_row + b * BLOCK + k);
                    }
                }
            }
        }
    }

    /// Grows strong edges through 8-connected weak candidates.
    fn hysteresis(&mut self, stride: usize) {
        let map = &mut self.map;
        let offsets = [1, stride - 1, stride, stride + 1];
        while let Some(at) = self.stack.pop() {
            for off in offsets {
                for n in [at + off, at - off] {
                    if map[n] == MAYBE {
                        map[n] = EDGE;
                        self.stack.push(n);
                    }
                }
            }
        }
    }
}

/// Map state of one pixel with magnitude `m` and gradient (`dx`, `dy`) given
/// its neighbours' magnitudes (`prev`/`next`: left, centre, right of the rows
/// above/below; `side`: left, right). This is OpenCV's test: the gradient
/// direction picks the neighbour pair by the Q15 tangent comparison, and ties
/// are broken asymmetrically (`>` towards left/up, `>=` towards right/down,
/// `>` on both diagonals).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn classify(
    m: i32,
    dx: i16,
    dy: i16,
    prev: [i32; 3],
    side: [i32; 2],
    next: [i32; 3],
    low: i32,
    high: i32,
) -> u8 {
    let xs = i32::from(dx);
    let ys = i32::from(dy);
    let ax = xs.abs();
    let ay = ys.abs() << SHIFT;
    let tg22x = ax * TG22;
    let horizontal = ay < tg22x;
    // Beyond tan 67.5 deg; never true together with `horizontal`.
    let vertical = ay > tg22x + (ax << (SHIFT + 1));
    // Same signs: the gradient points down-right, so compare up-left/down-right.
    let same_sign = (xs ^ ys) >= 0;
    let (diag_a, diag_b) = if same_sign {
        (prev[0], next[2])
    } else {
        (prev[2], next[0])
    };
    let a = if horizontal {
        side[0]
    } else if vertical {
        prev[1]
    } else {
        diag_a
    };
    let b = if horizontal {
        side[1]
    } else if vertical {
        next[1]
    } else {
        diag_b
    };
    // `m >= b` off the diagonals, `m > b` on them.
    let b_limit = b - i32::from(horizontal | vertical);
    let is_max = (m > low) & (m > a) & (m > b_limit);
    let strong = m > high;
    // NEVER = 1, MAYBE = 0, EDGE = 2.
    let state = if strong { EDGE } else { MAYBE };
    if is_max { state } else { NEVER }
}

/// F1 agreement of two binary edge maps (non-zero = edge): harmonic mean of
/// precision and recall of `ours` against `reference`; 1 when both are empty.
pub fn edge_f1(ours: &GrayImage, reference: &GrayImage) -> f64 {
    let (mut tp, mut n_ours, mut n_ref) = (0u64, 0u64, 0u64);
    for (&a, &b) in ours.as_raw().iter().zip(reference.as_raw()) {
        let (a, b) = (a != 0, b != 0);
        tp += u64::from(a && b);
        n_ours += u64::from(a);
        n_ref += u64::from(b);
    }
    if n_ours + n_ref == 0 {
        return 1.0;
    }
    2.0 * tp as f64 / (n_ours + n_ref) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gray_from(rows: &[&[u8]]) -> GrayImage {
        let w = rows[0].len() as u32;
        let data: Vec<u8> = rows.iter().flat_map(|r| r.iter().copied()).collect();
        GrayImage::from_raw(w, rows.len() as u32, data).unwrap()
    }

    #[test]
    fn vertical_step_gives_one_pixel_wide_line() {
        // A step between columns 3 and 4: |dx| = 4 * 200 at both columns;
        // the tie goes to the left one (m > left, m >= right).
        let row: &[u8] = &[0, 0, 0, 0, 200, 200, 200, 200];
        let img = gray_from(&[row; 6]);
        let edges = Canny::new(CannyParams::default()).gray(&img);
        for y in 0..6 {
            let line: Vec<u8> = (0..8).map(|x| edges.get_pixel(x, y)[0]).collect();
            assert_eq!(line, [0, 0, 0, 255, 0, 0, 0, 0], "row {y}");
        }
    }

    #[test]
    fn flat_image_has_no_edges_and_weak_edges_need_a_strong_neighbour() {
        let flat = GrayImage::from_pixel(9, 5, image::Luma([77]));
        let mut canny = Canny::new(CannyParams::default());
        assert!(canny.gray(&flat).pixels().all(|p| p[0] == 0));
        // Step of 30: |dx| = 120, between low 100 and high 200: no strong seed.
        let row: &[u8] = &[10, 10, 10, 40, 40, 40];
        assert!(
            canny
                .gray(&gray_from(&[row; 4]))
                .pixels()
                .all(|p| p[0] == 0)
        );
    }

    #[test]
    fn thresholds_follow_opencv() {
        let p = CannyParams {
            low: 200.0,
            high: 100.5,
            l2_gradient: true,
        };
        assert_eq!(p.integer_thresholds(), (10100, 40000));
        assert_eq!(CannyParams::default().integer_thresholds(), (100, 200));
    }

    #[test]
    fn f1_counts_overlap() {
        let a = gray_from(&[&[255, 255, 0, 0]]);
        let b = gray_from(&[&[255, 0, 255, 0]]);
        assert!((edge_f1(&a, &b) - 0.5).abs() < 1e-12);
        assert_eq!(edge_f1(&a, &a), 1.0);
    }

    #[test]
    fn tiny_images_do_not_panic() {
        let mut canny = Canny::new(CannyParams::default());
        for (w, h) in [(1, 1), (1, 5), (5, 1), (2, 2)] {
            let img =
                RgbImage::from_fn(w, h, |x, y| image::Rgb([(x * 90) as u8, (y * 70) as u8, 3]));
            assert_eq!(canny.rgb(&img).dimensions(), (w, h));
        }
        assert_eq!(canny.gray(&GrayImage::new(0, 0)).dimensions(), (0, 0));
    }
}
