//! Times [`gait_edge::Canny`] on one image (run by `tools/edge/bench_canny.sh`,
//! which times `cv2.Canny` on the same file in the same run).
//!
//! Usage: `canny_bench RGB.png GRAY.png ITERATIONS CV_RGB_EDGES.png CV_GRAY_EDGES.png`;
//! prints the median times and the F1 agreement with OpenCV's maps.

use std::time::Instant;

use gait_edge::{Canny, CannyParams, edge_f1};

fn median_ms(iterations: usize, mut f: impl FnMut()) -> f64 {
    f(); // warm-up: buffers allocated, caches filled
    let mut times: Vec<f64> = (0..iterations)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, rgb, gray, iterations, cv_rgb, cv_gray] = args.as_slice() else {
        return Err(
            "usage: canny_bench RGB.png GRAY.png ITERATIONS CV_RGB_EDGES.png CV_GRAY_EDGES.png"
                .into(),
        );
    };
    let rgb = image::open(rgb)?.to_rgb8();
    let gray = image::open(gray)?.to_luma8();
    let iterations: usize = iterations.parse()?;
    let mut canny = Canny::new(CannyParams::default());
    let rgb_ms = median_ms(iterations.max(1), || {
        std::hint::black_box(canny.rgb(std::hint::black_box(&rgb)));
    });
    let gray_ms = median_ms(iterations.max(1), || {
        std::hint::black_box(canny.gray(std::hint::black_box(&gray)));
    });
    let f1_rgb = edge_f1(&canny.rgb(&rgb), &image::open(cv_rgb)?.to_luma8());
    let f1_gray = edge_f1(&canny.gray(&gray), &image::open(cv_gray)?.to_luma8());
    println!("rgb_ms={rgb_ms:.3} gray_ms={gray_ms:.3} f1_rgb={f1_rgb:.6} f1_gray={f1_gray:.6}");
    Ok(())
}
