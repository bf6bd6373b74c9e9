//! How crisp the outline in a region of a frame is along the image's rows: the strong end of
//! the horizontal luma gradient. Motion blur smears a foot along its path (in a side view,
//! along the rows), so a foot's outline swinging loses this contrast against the same foot
//! standing, while defocus and encoding change both alike. The sample's feet swinging keep
//! 0.74-1.23 of their standing contrast per stride in every copy of the robustness matrix; with
//! a 1/30 s shutter 0.41-0.56 (BENCHMARKS.md, "Motion blur of a long exposure").

use image::RgbImage;

use crate::blur::{Region, grey};

/// The share of the region's pixels, those with the strongest gradient, whose weakest is read:
/// a foot's outline is a few per cent of a box drawn round it.
const STRONGEST: f64 = 0.02;
/// Fewer pixels than this inside the region: too small to say.
const MIN_PIXELS: usize = 64;

/// The 98th percentile of |dI/dx| (grey levels per pixel, central differences) over `region`
/// of `image`; `None` when the region, clipped to the image, is too small.
pub fn edge_contrast(image: &RgbImage, region: Region) -> Option<f64> {
    let r = Region {
        x0: region.x0.min(image.width()),
        y0: region.y0.min(image.height()),
        x1: region.x1.min(image.width()),
        y1: region.y1.min(image.height()),
    };
    let (w, h) = (
        r.x1.checked_sub(r.x0)? as usize,
        r.y1.checked_sub(r.y0)? as usize,
    );
    if w < 3 || (w - 2) * h < MIN_PIXELS {
        return None;
    }
    let grey = grey(image, r);
    let mut gradient: Vec<f32> = grey
        .chunks_exact(w)
        .flat_map(|row| row.windows(3).map(|p| 0.5 * (p[2] - p[0]).abs()))
        .collect();
    let keep = ((gradient.len() as f64 * STRONGEST).ceil() as usize).max(1);
    let cut = gradient.len() - keep;
    let (_, at, _) = gradient.select_nth_unstable_by(cut, f32::total_cmp);
    Some(f64::from(*at))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dark bar on a light ground whose vertical edges ramp over `ramp` pixels, as a bar
    /// moving sideways `ramp` pixels during the exposure is drawn.
    fn bar(ramp: u32) -> RgbImage {
        RgbImage::from_fn(120, 60, |x, _| {
            let inside = |x: f64| {
                ((x - 40.0) / f64::from(ramp.max(1))).clamp(0.0, 1.0)
                    - ((x - 80.0) / f64::from(ramp.max(1))).clamp(0.0, 1.0)
            };
            let v = (200.0 - 160.0 * inside(f64::from(x))) as u8;
            image::Rgb([v, v, v])
        })
    }

    const WHOLE: Region = Region {
        x0: 0,
        y0: 0,
        x1: 120,
        y1: 60,
    };

    #[test]
    fn a_smeared_outline_reads_weaker_in_proportion() {
        let sharp = edge_contrast(&bar(1), WHOLE).unwrap();
        let smeared = edge_contrast(&bar(10), WHOLE).unwrap();
        // A step of 160 grey levels: 80 per pixel by central differences; over 10 pixels, 16.
        assert!((sharp - 80.0).abs() < 1.0, "{sharp}");
        assert!((smeared - 16.0).abs() < 1.0, "{smeared}");
    }

    #[test]
    fn rows_without_an_edge_read_zero_and_tiny_regions_nothing() {
        let flat = RgbImage::from_pixel(40, 40, image::Rgb([90, 90, 90]));
        assert_eq!(edge_contrast(&flat, WHOLE), Some(0.0));
        let tiny = Region {
            x0: 10,
            y0: 10,
            x1: 14,
            y1: 14,
        };
        assert_eq!(edge_contrast(&bar(1), tiny), None);
    }
}
