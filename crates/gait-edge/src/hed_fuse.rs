//! The HED annotator's post-processing (controlnet_aux `HEDdetector`): each
//! side output is upsampled to the working size with OpenCV's bilinear rule,
//! the five are averaged, passed through a sigmoid, optionally quantised by
//! the "safe" step, and scaled to 0..255 (truncating, as `astype(uint8)`).

use image::GrayImage;

/// One raw (pre-sigmoid) side output of the network, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct SideOutput {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

/// Fuses side outputs into the soft edge map at `width` x `height`.
/// `safe_steps = Some(n)` applies controlnet_aux's `safe_step(x, n)`.
pub fn fuse(
    sides: &[SideOutput],
    width: usize,
    height: usize,
    safe_steps: Option<u32>,
) -> GrayImage {
    let ups: Vec<Vec<f32>> = sides.iter().map(|s| upsample(s, width, height)).collect();
    let n = ups.len().max(1) as f32;
    let mut out = GrayImage::new(width as u32, height as u32);
    for (i, px) in out.as_mut().iter_mut().enumerate() {
        // numpy sums the float32 stack in float32, then the sigmoid runs in float64.
        let mean = ups.iter().map(|u| u[i]).sum::<f32>() / n;
        let mut edge = 1.0 / (1.0 + (-f64::from(mean)).exp());
        if let Some(steps) = safe_steps {
            let steps = steps.max(1) as f32;
            edge = f64::from(((edge as f32) * (steps + 1.0)).trunc() / steps);
        }
        *px = (edge * 255.0).clamp(0.0, 255.0) as u8;
    }
    out
}

/// `cv2.resize(.., INTER_LINEAR)` of a float map: half-pixel centres,
/// neighbours clamped at the border.
fn upsample(side: &SideOutput, width: usize, height: usize) -> Vec<f32> {
    if (side.width, side.height) == (width, height) {
        return side.data.clone();
    }
    let taps = |src: usize, dst: usize| -> Vec<(usize, usize, f32)> {
        let scale = src as f64 / dst as f64;
        (0..dst)
            .map(|d| {
                let f = ((d as f64 + 0.5) * scale - 0.5) as f32;
                let i = f.floor();
                let frac = f - i;
                let i = i as isize;
                if i < 0 {
                    (0, 0, 0.0)
                } else if i as usize >= src - 1 {
                    (src - 1, src - 1, 0.0)
                } else {
                    (i as usize, i as usize + 1, frac)
                }
            })
            .collect()
    };
    let xt = taps(side.width, width);
    let yt = taps(side.height, height);
    let row = |y: usize| &side.data[y * side.width..(y + 1) * side.width];
    let mut out = Vec::with_capacity(width * height);
    for &(y0, y1, fy) in &yt {
        let (r0, r1) = (row(y0), row(y1));
        for &(x0, x1, fx) in &xt {
            let top = r0[x0] * (1.0 - fx) + r0[x1] * fx;
            let bottom = r1[x0] * (1.0 - fx) + r1[x1] * fx;
            out.push(top * (1.0 - fy) + bottom * fy);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn side(width: usize, height: usize, data: Vec<f32>) -> SideOutput {
        SideOutput {
            width,
            height,
            data,
        }
    }

    #[test]
    fn upsampling_doubles_with_half_pixel_centres() {
        let s = side(2, 1, vec![0.0, 4.0]);
        // Targets at source x = -0.25, 0.25, 0.75, 1.25 -> clamp, 1, 3, clamp.
        assert_eq!(upsample(&s, 4, 1), vec![0.0, 1.0, 3.0, 4.0]);
    }

    #[test]
    fn sigmoid_mean_and_safe_step() {
        let zero = side(1, 1, vec![0.0]);
        // sigmoid(0) = 0.5 -> 127 (truncated); safe: trunc(1.5) / 2 = 0.5 -> 127.
        assert_eq!(
            fuse(std::slice::from_ref(&zero), 1, 1, None).get_pixel(0, 0)[0],
            127
        );
        let big = side(1, 1, vec![20.0]);
        assert_eq!(
            fuse(&[big.clone(), big], 1, 1, Some(2)).get_pixel(0, 0)[0],
            255
        );
        let low = side(1, 1, vec![-1.0]);
        // sigmoid(-1) = 0.269 -> 68; safe: trunc(0.807) = 0 -> 0.
        assert_eq!(
            fuse(std::slice::from_ref(&low), 1, 1, None).get_pixel(0, 0)[0],
            68
        );
        assert_eq!(fuse(&[low], 1, 1, Some(2)).get_pixel(0, 0)[0], 0);
    }
}
