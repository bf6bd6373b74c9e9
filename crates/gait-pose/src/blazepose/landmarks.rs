//! Decoding the landmark model: crop-pixel landmarks, heatmap refinement,
//! projection back to the image.

use super::roi::Roi;
use super::warp::square_padding;

/// Input side of the landmark model.
pub const LANDMARK_SIZE: usize = 256;
/// Landmarks in the model output: 33 body points + 6 auxiliary ones.
pub const ALL: usize = 39;
const HEATMAP: usize = 64;
/// mediapipe 0.10.14 refines over 9 x 9 heatmap cells (the graph's kernel_size 7 is not what runs).
const KERNEL: i64 = 9;
const MIN_REFINE: f32 = 0.5;

/// One landmark in normalised image coordinates with its visibility.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Landmark {
    pub x: f32,
    pub y: f32,
    pub visibility: f32,
}

fn sigmoid(v: f32) -> f32 {
    1.0 / (1.0 + (-v).exp())
}

/// `raw`: 39 x (x, y, z, visibility, presence) in crop pixels; `heatmap`:
/// 64 x 64 x 39 logits (HWC), for the crop `roi` of a `width` x `height`
/// image. Returns the 39 landmarks in image coordinates.
pub fn decode(raw: &[f32], heatmap: &[f32], roi: &Roi, width: u32, height: u32) -> Vec<Landmark> {
    let s = LANDMARK_SIZE as f32;
    // The ROI is square in pixels only up to rounding; mediapipe removes the
    // (last-bit) letterbox that leaves before projecting.
    let (px, py) = square_padding(roi.w * width as f32, roi.h * height as f32);
    (0..ALL)
        .map(|i| {
            let r = &raw[i * 5..i * 5 + 5];
            let (mut x, mut y) = (r[0] / s, r[1] / s);
            if let Some((rx, ry)) = refine(heatmap, i, x, y) {
                (x, y) = (rx, ry);
            }
            let (x, y) = ((x - px) / (1.0 - (px + px)), (y - py) / (1.0 - (py + py)));
            let (x, y) = roi.project(x, y);
            Landmark {
                x,
                y,
                visibility: sigmoid(r[3]),
            }
        })
        .collect()
}

/// Confidence-weighted mean cell of the heatmap window around (x, y), if the
/// window is confident enough.
fn refine(heatmap: &[f32], channel: usize, x: f32, y: f32) -> Option<(f32, f32)> {
    let n = HEATMAP as i64;
    let (col, row) = ((x * n as f32) as i64, (y * n as f32) as i64);
    // Rows past the heatmap are left alone too. Older mediapipe compared
    // center_col with the height here (so it refined rows 64..68); that was
    // fixed in July 2023 (9861b3c8a), before 0.10.14, which indeed leaves a
    // foot at row 65 unrefined where the old check would have refined it.
    if col < 0 || col >= n || row < 0 || row >= n {
        return None;
    }
    let off = (KERNEL - 1) / 2;
    let (mut sum, mut wc, mut wr, mut max) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for r in (row - off).max(0)..(row + off + 1).min(n) {
        for c in (col - off).max(0)..(col + off + 1).min(n) {
            let v = sigmoid(*heatmap.get(((r * n + c) as usize) * ALL + channel)?);
            sum += v;
            max = max.max(v);
            wc += c as f32 * v;
            wr += r as f32 * v;
        }
    }
    (max >= MIN_REFINE && sum > 0.0).then(|| (wc / n as f32 / sum, wr / n as f32 / sum))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refinement_moves_to_the_peak() {
        let mut hm = vec![-10.0f32; 64 * 64 * ALL];
        hm[(10 * 64 + 20) * ALL + 3] = 10.0;
        let (x, y) = refine(&hm, 3, 18.0 / 64.0, 11.0 / 64.0).unwrap();
        assert!((x - 20.0 / 64.0).abs() < 1e-3 && (y - 10.0 / 64.0).abs() < 1e-3);
        // Weak heatmap: left alone.
        assert!(refine(&vec![-10.0f32; 64 * 64 * ALL], 3, 0.3, 0.3).is_none());
    }
}
