//! SSD anchor centres of the pose detector (mediapipe's `SsdAnchorsCalculator`
//! with the pose-detection options; fixed anchor size, so only centres matter).

/// Input side of the detector.
pub const DETECTOR_SIZE: usize = 224;
const STRIDES: [usize; 5] = [8, 16, 32, 32, 32];
/// Anchors per layer and cell: one aspect ratio (1.0) plus the interpolated scale.
const PER_LAYER: usize = 2;

/// Normalised (x, y) centres, in the order of the detector's output rows.
pub fn anchors() -> Vec<(f32, f32)> {
    let mut out = Vec::with_capacity(2254);
    let mut layer = 0;
    while layer < STRIDES.len() {
        // Consecutive layers with the same stride share one feature map.
        let mut last = layer;
        while last + 1 < STRIDES.len() && STRIDES[last + 1] == STRIDES[layer] {
            last += 1;
        }
        let per_cell = PER_LAYER * (last - layer + 1);
        let fm = DETECTOR_SIZE.div_ceil(STRIDES[layer]);
        for y in 0..fm {
            for x in 0..fm {
                let c = ((x as f32 + 0.5) / fm as f32, (y as f32 + 0.5) / fm as f32);
                out.extend(std::iter::repeat_n(c, per_cell));
            }
        }
        layer = last + 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn count_and_layout() {
        let a = anchors();
        assert_eq!(a.len(), 28 * 28 * 2 + 14 * 14 * 2 + 7 * 7 * 6);
        assert_eq!(a[0], (0.5 / 28.0, 0.5 / 28.0));
        assert_eq!(a[1], a[0]);
        assert_eq!(a[2], (1.5 / 28.0, 0.5 / 28.0));
        assert_eq!(a[1568], (0.5 / 14.0, 0.5 / 14.0));
        let last = a[a.len() - 1];
        assert_eq!(last, (6.5 / 7.0, 6.5 / 7.0));
        assert_eq!(a[a.len() - 6], last);
    }
}
