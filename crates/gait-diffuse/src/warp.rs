//! Resampling between frame, edge-map and generation-canvas pixels through
//! [`gait_core::Resize`] maps (bilinear, pixel centres at integer coordinates).

use gait_core::Resize;

/// Bilinear sample of a `w` x `h` image with `c` interleaved channels at
/// (x, y); coordinates outside are clamped to the border.
fn sample(data: &[u8], w: u32, h: u32, c: usize, x: f64, y: f64, out: &mut [f32]) {
    let x = x.clamp(0.0, f64::from(w - 1));
    let y = y.clamp(0.0, f64::from(h - 1));
    let (x0, y0) = (x.floor() as u32, y.floor() as u32);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = ((x - f64::from(x0)) as f32, (y - f64::from(y0)) as f32);
    let at = |xx: u32, yy: u32, k: usize| {
        f32::from(data[(yy as usize * w as usize + xx as usize) * c + k])
    };
    for (k, o) in out.iter_mut().enumerate().take(c) {
        let top = at(x0, y0, k) * (1.0 - fx) + at(x1, y0, k) * fx;
        let bottom = at(x0, y1, k) * (1.0 - fx) + at(x1, y1, k) * fx;
        *o = top * (1.0 - fy) + bottom * fy;
    }
}

/// Renders an edge map onto the canvas that `canvas` maps the frame to;
/// returns `(height * width)` values in [0, 1].
pub fn edge_to_canvas(edge: &image::GrayImage, edge_map: &Resize, canvas: &Resize) -> Vec<f32> {
    let (w, h) = (canvas.dst_width, canvas.dst_height);
    let mut out = Vec::with_capacity((w * h) as usize);
    let mut px = [0f32; 1];
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = canvas.to_source(f64::from(x), f64::from(y));
            let (ex, ey) = edge_map.to_target(fx, fy);
            sample(
                edge.as_raw(),
                edge.width(),
                edge.height(),
                1,
                ex,
                ey,
                &mut px,
            );
            out.push(px[0] / 255.0);
        }
    }
    out
}

/// Renders an RGB frame onto its canvas; returns planar `(3, height, width)`
/// values in [0, 1] (image-to-image and inpainting start from it).
pub fn frame_to_canvas(frame: &image::RgbImage, canvas: &Resize) -> Vec<f32> {
    let (w, h) = (canvas.dst_width, canvas.dst_height);
    let plane = (w * h) as usize;
    let mut out = vec![0f32; 3 * plane];
    let mut px = [0f32; 3];
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = canvas.to_source(f64::from(x), f64::from(y));
            sample(
                frame.as_raw(),
                frame.width(),
                frame.height(),
                3,
                fx,
                fy,
                &mut px,
            );
            let i = (y * w + x) as usize;
            for (k, v) in px.iter().enumerate() {
                out[k * plane + i] = v / 255.0;
            }
        }
    }
    out
}

/// Resamples a canvas image (RGB, values in [0, 1], planar CHW) back to the frame.
pub fn canvas_to_frame(chw: &[f32], canvas: &Resize) -> image::RgbImage {
    let (cw, ch) = (canvas.dst_width, canvas.dst_height);
    let plane = (cw * ch) as usize;
    let interleaved: Vec<u8> = (0..plane)
        .flat_map(|i| (0..3).map(move |k| i + k * plane))
        .map(|j| {
            (chw.get(j).copied().unwrap_or(0.0) * 255.0)
                .round()
                .clamp(0.0, 255.0) as u8
        })
        .collect();
    let (w, h) = (canvas.src_width, canvas.src_height);
    let mut img = image::RgbImage::new(w, h);
    let mut px = [0f32; 3];
    for (x, y, p) in img.enumerate_pixels_mut() {
        let (cx, cy) = canvas.to_target(f64::from(x), f64::from(y));
        sample(&interleaved, cw, ch, 3, cx, cy, &mut px);
        *p = image::Rgb(px.map(|v| v.round().clamp(0.0, 255.0) as u8));
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_maps_keep_pixels() {
        let mut e = image::GrayImage::new(8, 4);
        e.put_pixel(3, 2, image::Luma([255]));
        let id = Resize::identity(8, 4);
        let v = edge_to_canvas(&e, &id, &id);
        assert_eq!(v[2 * 8 + 3], 1.0);
        assert_eq!(v.iter().filter(|&&x| x > 0.0).count(), 1);
    }

    #[test]
    fn smaller_edge_map_is_resized_to_the_canvas() {
        // Edge map at half the frame size, canvas at twice the frame size.
        let e = image::GrayImage::from_pixel(5, 5, image::Luma([255]));
        let v = edge_to_canvas(
            &e,
            &Resize::stretch(10, 10, 5, 5),
            &Resize::stretch(10, 10, 20, 20),
        );
        assert_eq!(v.len(), 400);
        assert!(v.iter().all(|&x| (x - 1.0).abs() < 1e-6));
    }

    #[test]
    fn frame_onto_an_identity_canvas_is_planar_and_exact() {
        let f = image::RgbImage::from_fn(4, 2, |x, y| image::Rgb([x as u8, y as u8, 255]));
        let v = frame_to_canvas(&f, &Resize::identity(4, 2));
        assert_eq!(v.len(), 24);
        assert_eq!(v[5], 1.0 / 255.0); // red plane, pixel (1, 1)
        assert_eq!(v[8 + 4], 1.0 / 255.0); // green plane, pixel (0, 1)
        assert!(v[16..].iter().all(|&b| b == 1.0));
    }

    #[test]
    fn canvas_back_to_frame_size() {
        let canvas = Resize::stretch(30, 20, 64, 64);
        let chw = vec![0.5f32; 3 * 64 * 64];
        let img = canvas_to_frame(&chw, &canvas);
        assert_eq!(img.dimensions(), (30, 20));
        assert!(img.pixels().all(|p| p.0 == [128, 128, 128]));
    }
}
