//! The crop around the subject that a regenerator redraws instead of the
//! whole frame (`[regenerator] region = "subject"`): a rectangle of the
//! canvas's aspect centred on the body, cut out at the canvas size and pasted
//! back into the frame, so that the stages after it see a whole frame in
//! original pixels.

use image::RgbImage;
use serde::{Deserialize, Serialize};

use crate::PersonBox;

/// How the crop is sized: the canvas it is cut at, and the margin added
/// around the body box.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CropSpec {
    /// Width and height of the crop in canvas pixels.
    pub size: [u32; 2],
    /// Extra height around the body box, as a fraction of its size.
    pub margin: f64,
}

/// A crop rectangle in frame pixels and the canvas it maps to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SubjectCrop {
    /// Top-left corner, frame pixels (may lie outside the frame).
    x0: f64,
    y0: f64,
    /// Frame pixels per canvas pixel.
    scale: f64,
    /// Canvas size.
    width: u32,
    height: u32,
}

impl SubjectCrop {
    /// The crop of `spec` around `person`: the body box's height plus the
    /// margin, the canvas's aspect, centred on the body centre.
    pub fn around(person: &PersonBox, spec: &CropSpec) -> Self {
        let [width, height] = spec.size;
        let frame_h = f64::from(person.size()).max(1.0) * (1.0 + spec.margin);
        let scale = frame_h / f64::from(height);
        let [cx, cy] = person.centre.map(f64::from);
        // Canvas pixel centres sit at integers: the canvas's middle is (n - 1) / 2.
        Self {
            x0: cx - scale * (f64::from(width) - 1.0) / 2.0,
            y0: cy - scale * (f64::from(height) - 1.0) / 2.0,
            scale,
            width,
            height,
        }
    }

    /// The canvas-size image of the crop. Outside the frame the border
    /// pixels repeat: a black band would put an edge into the edge map.
    pub fn cut(&self, frame: &RgbImage) -> RgbImage {
        let (w, h) = (f64::from(frame.width()), f64::from(frame.height()));
        RgbImage::from_fn(self.width, self.height, |x, y| {
            let (fx, fy) = self.to_frame(f64::from(x), f64::from(y));
            bilinear(frame, fx.clamp(0.0, w - 1.0), fy.clamp(0.0, h - 1.0))
                .unwrap_or(image::Rgb([0, 0, 0]))
        })
    }

    /// `frame` with the crop's pixels replaced by `canvas` (the redrawn crop).
    pub fn paste(&self, frame: &RgbImage, canvas: &RgbImage) -> RgbImage {
        let mut out = frame.clone();
        let (xa, ya) = self.to_frame(-0.5, -0.5);
        let (xb, yb) = self.to_frame(f64::from(self.width) - 0.5, f64::from(self.height) - 0.5);
        let cols = xa.ceil().max(0.0) as u32..(xb.ceil().max(0.0) as u32).min(frame.width());
        let rows = ya.ceil().max(0.0) as u32..(yb.ceil().max(0.0) as u32).min(frame.height());
        for y in rows {
            for x in cols.clone() {
                let cx = (f64::from(x) - self.x0) / self.scale;
                let cy = (f64::from(y) - self.y0) / self.scale;
                if let Some(p) = bilinear(canvas, cx, cy) {
                    out.put_pixel(x, y, p);
                }
            }
        }
        out
    }

    /// Frame coordinates of canvas pixel (x, y) (pixel centres at integers).
    pub fn to_frame(&self, x: f64, y: f64) -> (f64, f64) {
        (self.x0 + x * self.scale, self.y0 + y * self.scale)
    }
}

/// Bilinear sample at (x, y), borders clamped within half a pixel; `None`
/// further outside.
fn bilinear(img: &RgbImage, x: f64, y: f64) -> Option<image::Rgb<u8>> {
    let (w, h) = (f64::from(img.width()), f64::from(img.height()));
    if img.width() == 0 || !(-0.5..w - 0.5).contains(&x) || !(-0.5..h - 0.5).contains(&y) {
        return None;
    }
    let (x, y) = (x.clamp(0.0, w - 1.0), y.clamp(0.0, h - 1.0));
    let (x0, y0) = (x.floor() as u32, y.floor() as u32);
    let (x1, y1) = (
        (x0 + 1).min(img.width() - 1),
        (y0 + 1).min(img.height() - 1),
    );
    let (fx, fy) = (x - f64::from(x0), y - f64::from(y0));
    let mut px = [0u8; 3];
    for (k, v) in px.iter_mut().enumerate() {
        let at = |xx, yy| f64::from(img.get_pixel(xx, yy)[k]);
        let top = at(x0, y0) * (1.0 - fx) + at(x1, y0) * fx;
        let bottom = at(x0, y1) * (1.0 - fx) + at(x1, y1) * fx;
        *v = (top * (1.0 - fy) + bottom * fy).round().clamp(0.0, 255.0) as u8;
    }
    Some(image::Rgb(px))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> CropSpec {
        CropSpec {
            size: [64, 128],
            margin: 0.0,
        }
    }

    #[test]
    fn the_crop_holds_the_body_box_at_the_canvas_aspect() {
        // A 200 px tall body centred at (300, 250).
        let person = PersonBox::upright(300.0, 250.0, 200.0, 1.0);
        let c = SubjectCrop::around(&person, &spec());
        let (x0, y0) = c.to_frame(-0.5, -0.5);
        let (x1, y1) = c.to_frame(63.5, 127.5);
        assert!((y1 - y0 - 200.0).abs() < 1e-9 && (x1 - x0 - 100.0).abs() < 1e-9);
        assert!(((x0 + x1) / 2.0 - 300.0).abs() < 1e-9 && ((y0 + y1) / 2.0 - 250.0).abs() < 1e-9);
    }

    #[test]
    fn cut_then_paste_changes_only_the_crop_and_repeats_the_border_outside_the_frame() {
        let frame = RgbImage::from_fn(200, 150, |x, y| image::Rgb([x as u8, y as u8, 7]));
        // Near the left border: part of the crop lies outside the frame.
        let person = PersonBox::upright(20.0, 75.0, 100.0, 1.0);
        let c = SubjectCrop::around(&person, &spec());
        let cut = c.cut(&frame);
        assert_eq!(cut.dimensions(), (64, 128));
        assert_eq!(cut.get_pixel(0, 64)[0], 0, "column 0 of the frame repeats");
        // Pasting the unchanged crop back keeps the frame within a level.
        let back = c.paste(&frame, &cut);
        let worst = frame
            .pixels()
            .zip(back.pixels())
            .flat_map(|(a, b)| (0..3).map(move |k| a[k].abs_diff(b[k])))
            .max()
            .unwrap();
        assert!(worst <= 2, "{worst}");
        // A white canvas whitens the crop's rectangle and nothing else.
        let white = RgbImage::from_pixel(64, 128, image::Rgb([255, 255, 255]));
        let pasted = c.paste(&frame, &white);
        assert_eq!(pasted.get_pixel(20, 75), &image::Rgb([255, 255, 255]));
        assert_eq!(pasted.get_pixel(150, 75), frame.get_pixel(150, 75));
        assert_eq!(pasted.get_pixel(20, 10), frame.get_pixel(20, 10));
    }
}
