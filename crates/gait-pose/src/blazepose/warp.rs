//! Rotated crops resampled exactly as mediapipe's CPU image-to-tensor step:
//! OpenCV `boxPoints` + `getPerspectiveTransform` + `warpPerspective`
//! (INTER_LINEAR, fixed point, 1/32-pixel grid) on the 8-bit image, byte for
//! byte (tests/blazepose_imagetotensor.rs).

use image::RgbImage;

use super::perspective::{box_points, degrees, invert, perspective_transform};
use super::roi::Roi;

/// What lies outside the image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Border {
    Zero,
    Replicate,
}

/// A rectangle in pixels: centre, size, rotation in radians.
#[derive(Debug, Clone, Copy)]
pub struct PixelRect {
    pub cx: f32,
    pub cy: f32,
    pub w: f32,
    pub h: f32,
    pub rotation: f32,
}

/// The pixel rectangle mediapipe crops for `roi` of a `width` x `height`
/// image into a square tensor: `GetRoi` (normalised -> pixels, f32), then
/// `PadRoi` with keep_aspect_ratio (the short side grows to the long one).
pub fn roi_rect(roi: &Roi, width: u32, height: u32) -> PixelRect {
    let (w, h) = (width as f32, height as f32);
    let (mut rw, mut rh) = (roi.w * w, roi.h * h);
    if 1.0 > rh / rw {
        rh = rw;
    } else {
        rw = rh;
    }
    PixelRect {
        cx: roi.cx * w,
        cy: roi.cy * h,
        w: rw,
        h: rh,
        rotation: roi.rotation,
    }
}

/// `PadRoi`'s letterbox padding for a `w` x `h` rectangle in a square
/// tensor: (left = right, top = bottom), fractions of the padded side, in
/// mediapipe's f32 operation order.
pub fn square_padding(w: f32, h: f32) -> (f32, f32) {
    let aspect = h / w;
    if 1.0 > aspect {
        (0.0, (1.0 - aspect / 1.0) / 2.0)
    } else {
        ((1.0 - 1.0 / aspect) / 2.0, 0.0)
    }
}

/// [`crop`] of [`roi_rect`]: mediapipe's `ImageToTensorCalculator` on the CPU
/// for a square `size` x `size` tensor, before the float conversion.
pub fn crop_roi(img: &RgbImage, roi: &Roi, size: usize, border: Border) -> Option<Vec<u8>> {
    crop(img, roi_rect(roi, img.width(), img.height()), size, border)
}

/// The 1/32-pixel sampling grid: OpenCV's INTER_BITS.
const PHASES: i64 = 32;
/// `warpPerspective` computes its map in blocks this many columns wide
/// (BLOCK_SZ^2 / 16 rows); each block restarts the row sum at its first
/// column, which changes the last bit of some coordinates.
const BLOCK_COLS: usize = 64;

/// Resamples `rect` of `img` into a `size` x `size` RGB u8 buffer (row-major,
/// HWC), as mediapipe's `ImageToTensorOpenCvConverter`: `boxPoints`,
/// `getPerspectiveTransform` onto the output corners, then `warpPerspective`
/// with INTER_LINEAR and `border`. `None` for a degenerate rectangle (zero
/// or non-finite size), where mediapipe fails too.
pub fn crop(img: &RgbImage, rect: PixelRect, size: usize, border: Border) -> Option<Vec<u8>> {
    let inverse = inverse_map(rect, size)?;
    let (w, h) = (img.width() as i64, img.height() as i64);
    if w == 0 || h == 0 {
        return None;
    }
    let mut out = vec![0u8; size * size * 3];
    let src = img.as_raw();
    let mut grid = vec![(0i64, 0i64); size];
    for (y, row) in out.chunks_exact_mut(size * 3).enumerate() {
        // The row's grid points first: a loop of arithmetic alone, which the compiler
        // vectorises, then the memory-bound sampling.
        grid_row(&inverse, y, &mut grid);
        for (px, &(gx, gy)) in row.chunks_exact_mut(3).zip(&grid) {
            match inside(src, w, h, gx, gy) {
                Some(v) => px.copy_from_slice(&v),
                None => px.copy_from_slice(&sample(img, gx, gy, border)),
            }
        }
    }
    Some(out)
}

/// The matrix taking output pixels to image points (OpenCV inverts the
/// forward one, as `warpPerspective` without WARP_INVERSE_MAP does).
fn inverse_map(rect: PixelRect, size: usize) -> Option<[f64; 9]> {
    let sane = [rect.cx, rect.cy, rect.w, rect.h, rect.rotation]
        .iter()
        .all(|v| v.is_finite());
    if !sane || rect.w <= 0.0 || rect.h <= 0.0 || size == 0 {
        return None;
    }
    let src = box_points(rect.cx, rect.cy, rect.w, rect.h, degrees(rect.rotation));
    let n = size as f32;
    let dst = [(0.0, n), (0.0, 0.0), (n, 0.0), (n, n)];
    invert(&perspective_transform(&src, &dst)?)
}

/// [`grid_point`] for every pixel of output row `y`, in the widest registers the CPU has (the
/// same operations on each lane: the same bits).
fn grid_row(m: &[f64; 9], y: usize, out: &mut [(i64, i64)]) {
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512dq") {
        // SAFETY: the CPU has the features the function is compiled for.
        return unsafe { grid_row_avx512(m, y, out) };
    }
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx2") {
        // SAFETY: as above.
        return unsafe { grid_row_avx2(m, y, out) };
    }
    grid_row_plain(m, y, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq")]
unsafe fn grid_row_avx512(m: &[f64; 9], y: usize, out: &mut [(i64, i64)]) {
    grid_row_plain(m, y, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn grid_row_avx2(m: &[f64; 9], y: usize, out: &mut [(i64, i64)]) {
    grid_row_plain(m, y, out)
}

#[inline(always)]
fn grid_row_plain(m: &[f64; 9], y: usize, out: &mut [(i64, i64)]) {
    for (x, g) in out.iter_mut().enumerate() {
        *g = grid_point(m, x, y);
    }
}

/// Output pixel (x, y) -> image point in 1/32 pixels, with
/// `WarpPerspectiveInvoker`'s operation order and rounding (cvRound: half to
/// even; coordinates clamped to the i32 range first).
#[inline(always)]
fn grid_point(m: &[f64; 9], x: usize, y: usize) -> (i64, i64) {
    let (bx, x1) = (
        (x / BLOCK_COLS * BLOCK_COLS) as f64,
        (x % BLOCK_COLS) as f64,
    );
    let y = y as f64;
    let x0 = m[0] * bx + m[1] * y + m[2];
    let y0 = m[3] * bx + m[4] * y + m[5];
    let w0 = m[6] * bx + m[7] * y + m[8];
    let w = w0 + m[6] * x1;
    let w = if w != 0.0 { PHASES as f64 / w } else { 0.0 };
    let round = |v: f64| {
        // std::max(INT_MIN, std::min(INT_MAX, v)): NaN ends up as INT_MAX.
        let v = if v < i32::MAX as f64 {
            v
        } else {
            i32::MAX as f64
        };
        let v = if i32::MIN as f64 > v {
            i32::MIN as f64
        } else {
            v
        };
        // Half to even by the 1.5 * 2^52 trick, exact for |v| < 2^51 (v is
        // within the i32 range here): `round_ties_even` is a libm call on the
        // baseline x86-64 target, twice per output pixel.
        const MAGIC: f64 = 6_755_399_441_055_744.0;
        ((v + MAGIC) - MAGIC) as i64
    };
    (round((x0 + m[0] * x1) * w), round((y0 + m[3] * x1) * w))
}

/// [`sample`] where all four taps lie inside the image (nearly every pixel of a crop), in i32:
/// the weights sum to 2^15 and the pixels are 8-bit, so no sum exceeds 2^23.
#[inline(always)]
fn inside(src: &[u8], w: i64, h: i64, gx: i64, gy: i64) -> Option<[u8; 3]> {
    let (ix, iy) = (gx >> 5, gy >> 5);
    if !(ix >= 0 && iy >= 0 && ix + 1 < w && iy + 1 < h) {
        return None;
    }
    let (fx, fy) = ((gx & (PHASES - 1)) as i32, (gy & (PHASES - 1)) as i32);
    let (w00, w01) = ((32 - fx) * (32 - fy) * 32, fx * (32 - fy) * 32);
    let (w10, w11) = ((32 - fx) * fy * 32, fx * fy * 32);
    let i = ((iy * w + ix) * 3) as usize;
    let j = i + (w * 3) as usize;
    let (a, b) = (&src[i..i + 6], &src[j..j + 6]);
    let mut v = [0u8; 3];
    for c in 0..3 {
        let s =
            w00 * a[c] as i32 + w01 * a[3 + c] as i32 + w10 * b[c] as i32 + w11 * b[3 + c] as i32;
        v[c] = ((s + (1 << 14)) >> 15).clamp(0, 255) as u8;
    }
    Some(v)
}

/// Bilinear sample at a 1/32-pixel grid point with taps outside the image, fixed point as
/// OpenCV's `remapBilinear` on 8-bit images (weights sum to 2^15), `border` deciding what lies
/// outside; [`inside`] takes the pixels whose taps all fall inside.
fn sample(img: &RgbImage, gx: i64, gy: i64, border: Border) -> [u8; 3] {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let (ix, iy) = (gx >> 5, gy >> 5);
    let (fx, fy) = (gx & (PHASES - 1), gy & (PHASES - 1));
    let wts = [
        (32 - fx) * (32 - fy) * 32,
        fx * (32 - fy) * 32,
        (32 - fx) * fy * 32,
        fx * fy * 32,
    ];
    let taps = [(ix, iy), (ix + 1, iy), (ix, iy + 1), (ix + 1, iy + 1)];
    let src = img.as_raw();
    let mut acc = [0i64; 3];
    for (&(tx, ty), &wt) in taps.iter().zip(&wts) {
        let inside = tx >= 0 && ty >= 0 && tx < w && ty < h;
        let (tx, ty) = match (inside, border) {
            (true, _) => (tx, ty),
            (false, Border::Zero) => continue,
            (false, Border::Replicate) => (tx.clamp(0, w - 1), ty.clamp(0, h - 1)),
        };
        let i = ((ty * w + tx) * 3) as usize;
        for c in 0..3 {
            acc[c] += wt * src[i + c] as i64;
        }
    }
    acc.map(|v| ((v + (1 << 14)) >> 15).clamp(0, 255) as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_crop_copies_pixels() {
        let img = RgbImage::from_fn(4, 4, |x, y| image::Rgb([(x * 10 + y) as u8, 0, 255]));
        let rect = PixelRect {
            cx: 2.0,
            cy: 2.0,
            w: 4.0,
            h: 4.0,
            rotation: 0.0,
        };
        let out = crop(&img, rect, 4, Border::Zero).unwrap();
        for y in 0..4 {
            for x in 0..4 {
                assert_eq!(out[(y * 4 + x) * 3], (x * 10 + y) as u8);
            }
        }
    }

    #[test]
    fn grid_rows_in_wide_registers_match_the_scalar_points() {
        for (k, rotation) in [0.0f32, 0.3, -1.2, 2.9, 1e-7].into_iter().enumerate() {
            let rect = PixelRect {
                cx: 900.5 + k as f32 * 13.3,
                cy: 480.25,
                w: 417.0 + k as f32,
                h: 417.0 + k as f32,
                rotation,
            };
            let m = inverse_map(rect, 256).unwrap();
            let mut row = vec![(0, 0); 256];
            for y in [0, 1, 63, 64, 200, 255] {
                let want: Vec<_> = (0..256).map(|x| grid_point(&m, x, y)).collect();
                grid_row(&m, y, &mut row);
                assert_eq!(row, want, "rotation {rotation}, row {y}");
                // Each variant this CPU can run, not only the one it dispatches to.
                #[cfg(target_arch = "x86_64")]
                if is_x86_feature_detected!("avx2") {
                    // SAFETY: the CPU has AVX2, checked just above.
                    unsafe { grid_row_avx2(&m, y, &mut row) };
                    assert_eq!(row, want, "AVX2, rotation {rotation}, row {y}");
                }
                grid_row_plain(&m, y, &mut row);
                assert_eq!(row, want, "plain, rotation {rotation}, row {y}");
            }
        }
    }

    #[test]
    fn borders() {
        let img = RgbImage::from_pixel(2, 2, image::Rgb([100, 100, 100]));
        let rect = PixelRect {
            cx: 1.0,
            cy: 1.0,
            w: 8.0,
            h: 8.0,
            rotation: 0.5,
        };
        assert_eq!(crop(&img, rect, 8, Border::Zero).unwrap()[0], 0);
        assert!(
            crop(&img, rect, 8, Border::Replicate)
                .unwrap()
                .iter()
                .all(|&v| v == 100)
        );
    }
}
