use super::*;

/// The error function (Abramowitz and Stegun 7.1.26, error under 1.5e-7).
fn erf(x: f64) -> f64 {
    let t = 1.0 / (1.0 + 0.327_591_1 * x.abs());
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    (1.0 - poly * (-x * x).exp()).copysign(x)
}

/// A dark disc of radius 60 on a light ground, its rim blurred by a Gaussian of `sigma` px
/// (the exact profile of a blurred straight edge, which a rim this wide follows closely).
fn disc(sigma: f64) -> RgbImage {
    RgbImage::from_fn(200, 200, |x, y| {
        let d = ((f64::from(x) - 100.0).hypot(f64::from(y) - 100.0)) - 60.0;
        let t = if sigma == 0.0 {
            f64::from(u8::from(d > 0.0))
        } else {
            0.5 * (1.0 + erf(d / (sigma * std::f64::consts::SQRT_2)))
        };
        let v = (40.0 + 170.0 * t).round() as u8;
        image::Rgb([v, v, v])
    })
}

const WHOLE: Region = Region {
    x0: 20,
    y0: 20,
    x1: 180,
    y1: 180,
};

#[test]
fn reads_the_blur_of_a_blurred_edge() {
    for sigma in [1.0, 2.0, 3.0, 4.0] {
        let read = blur_px(&disc(sigma), WHOLE).unwrap();
        // What the ratio sees: the edge's blur with the pre-blur on top.
        let expected = (sigma * sigma + 0.25f64).sqrt();
        assert!(
            (read - expected).abs() < 0.15 * expected,
            "sigma {sigma}: read {read:.2}, expected about {expected:.2}"
        );
    }
}

#[test]
fn more_blur_reads_more() {
    let reads: Vec<f64> = [0.0, 1.0, 2.0, 4.0, 8.0]
        .iter()
        .map(|&s| blur_px(&disc(s), WHOLE).unwrap())
        .collect();
    assert!(reads.windows(2).all(|w| w[0] < w[1]), "{reads:?}");
}

#[test]
fn flat_or_empty_regions_read_nothing() {
    let flat = RgbImage::from_pixel(100, 100, image::Rgb([90, 90, 90]));
    assert_eq!(blur_px(&flat, WHOLE), None);
    let outside = Region {
        x0: 300,
        y0: 300,
        x1: 400,
        y1: 400,
    };
    assert_eq!(blur_px(&disc(1.0), outside), None);
}

#[test]
fn a_region_at_the_image_border_is_clipped() {
    let corner = Region {
        x0: 0,
        y0: 0,
        x1: 120,
        y1: 120,
    };
    let read = blur_px(&disc(2.0), corner).unwrap();
    assert!((read - 2.06).abs() < 0.3, "{read}");
}
