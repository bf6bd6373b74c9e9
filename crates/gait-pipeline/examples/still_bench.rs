//! Decode time of a still image, for tools/jpeg/bench.py (which times `cv2.imread` on the same
//! file in the same run): `cargo run --release -p gait-pipeline --example still_bench -- FILE N`.
//! Prints the median milliseconds of N reads through `gait_pipeline::still::read` (the JPEG
//! reader of image inputs) and through the `image` crate (what it replaced), file read included.

use std::path::PathBuf;
use std::time::Instant;

fn median_ms(n: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..n)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[n / 2]
}

fn main() {
    let mut args = std::env::args().skip(1);
    let file = PathBuf::from(args.next().expect("usage: still_bench FILE N"));
    let n: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(30);
    let ours = median_ms(n, || {
        std::hint::black_box(gait_pipeline::still::read(&file).unwrap());
    });
    let image_crate = median_ms(n, || {
        std::hint::black_box(image::open(&file).unwrap().to_rgb8());
    });
    println!("{{\"gait_ms\": {ours:.3}, \"image_crate_ms\": {image_crate:.3}}}");
}
