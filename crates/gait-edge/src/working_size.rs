//! The size an edge detector works at: ControlNet's annotators resize the
//! frame so the short side is `resolution` and both sides are multiples of 64,
//! then detect edges on the resized frame.

use gait_core::{Frame, Resize};
use image::RgbImage;

use crate::resample::resize_for_annotator;

/// ControlNet 1.x (SD 1.5) conditioning resolution.
pub const DEFAULT_RESOLUTION: u32 = 512;

/// Side lengths of the working image are rounded to this multiple.
const MULTIPLE: u32 = 64;

/// The frame -> working-image transform for `resolution` (0 = keep the
/// frame's own size).
pub fn working_resize(width: u32, height: u32, resolution: u32) -> Resize {
    if resolution == 0 {
        Resize::identity(width, height)
    } else {
        Resize::short_side(width, height, resolution, MULTIPLE)
    }
}

/// The frame resampled to the working size, with the transform that maps
/// frame coordinates onto it.
pub fn to_working_size(frame: &Frame, resolution: u32) -> (RgbImage, Resize) {
    let resize = working_resize(frame.width(), frame.height(), resolution);
    let image = resize_for_annotator(&frame.image, resize.dst_width, resize.dst_height);
    (image, resize)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_keeps_native_size() {
        let r = working_resize(1768, 994, 0);
        assert_eq!((r.dst_width, r.dst_height), (1768, 994));
        let r = working_resize(1768, 994, 512);
        assert_eq!((r.dst_width, r.dst_height), (896, 512));
    }
}
