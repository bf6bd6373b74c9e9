//! Sobel gradient magnitude with OpenCV's default border (reflect-101).

use image::{GrayImage, RgbImage};

/// Gray levels as `0.299 R + 0.587 G + 0.114 B` (ITU-R BT.601), unrounded.
fn gray(image: &RgbImage) -> Vec<f32> {
    image
        .pixels()
        .map(|p| 0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2]))
        .collect()
}

/// Index `i` (possibly -1 or n) mirrored into 0..n without repeating the edge
/// pixel (`gfedcb|abcdefgh|gfedcba`).
fn reflect101(i: isize, n: usize) -> usize {
    let n = n as isize;
    if n == 1 {
        return 0;
    }
    let r = if i < 0 {
        -i
    } else if i >= n {
        2 * n - 2 - i
    } else {
        i
    };
    r as usize
}

/// 255 where `sqrt(gx^2 + gy^2) > threshold`, else 0, with the 3x3 Sobel
/// kernels `gx = [1 2 1]^T [-1 0 1]` and `gy` its transpose.
pub fn edges(image: &RgbImage, threshold: f32) -> GrayImage {
    let (w, h) = (image.width() as usize, image.height() as usize);
    let g = gray(image);
    let cols: Vec<[usize; 3]> = (0..w as isize)
        .map(|x| [reflect101(x - 1, w), x as usize, reflect101(x + 1, w)])
        .collect();
    let mut out = vec![0u8; w * h];
    for y in 0..h {
        let rows = [
            reflect101(y as isize - 1, h) * w,
            y * w,
            reflect101(y as isize + 1, h) * w,
        ];
        for (x, [l, c, r]) in cols.iter().enumerate() {
            let at = |row: usize, col: usize| g[row + col];
            // Separable: smooth [1 2 1] across, difference [-1 0 1] along.
            let gx = (at(rows[0], *r) - at(rows[0], *l))
                + 2.0 * (at(rows[1], *r) - at(rows[1], *l))
                + (at(rows[2], *r) - at(rows[2], *l));
            let gy = (at(rows[2], *l) - at(rows[0], *l))
                + 2.0 * (at(rows[2], *c) - at(rows[0], *c))
                + (at(rows[2], *r) - at(rows[0], *r));
            if (gx * gx + gy * gy).sqrt() > threshold {
                out[y * w + x] = 255;
            }
        }
    }
    GrayImage::from_raw(image.width(), image.height(), out).expect("buffer of width * height bytes")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflect_101_border() {
        assert_eq!(reflect101(-1, 5), 1);
        assert_eq!(reflect101(5, 5), 3);
        assert_eq!(reflect101(2, 5), 2);
        assert_eq!(reflect101(-1, 1), 0);
    }

    #[test]
    fn vertical_step_gives_a_two_pixel_edge() {
        // Columns 0..3 black, 3..6 white: gx = 4 * 255 at columns 2 and 3.
        let img = RgbImage::from_fn(6, 4, |x, _| {
            if x < 3 {
                [0, 0, 0].into()
            } else {
                [255, 255, 255].into()
            }
        });
        let e = edges(&img, 500.0);
        for y in 0..4 {
            let row: Vec<u8> = (0..6).map(|x| e.get_pixel(x, y)[0]).collect();
            assert_eq!(row, [0, 0, 255, 255, 0, 0], "row {y}");
        }
        assert!(edges(&img, 1100.0).pixels().all(|p| p[0] == 0));
    }
}
