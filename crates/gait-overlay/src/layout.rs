//! Composes one output frame: panels, skeleton, markers and labels.

use image::RgbImage;

use crate::canvas::Canvas;
use crate::draw::{Skeleton, Style, side_colour};
use crate::text::TextPainter;
use crate::{Backdrop, EventKind, FrameMarks, Layout, OverlayError};

/// Brightness of frames outside walking bouts or in rejected cycles.
pub const DIM_FACTOR: f32 = 0.4;
/// Side-by-side panels are halved when three full-size ones would be wider
/// than this: wider H.264 streams fail in many players and browsers, and
/// would encode three times slower.
const MAX_SIDE_BY_SIDE_WIDTH: usize = 3840;

const WHITE: [u8; 3] = [255, 255, 255];
const BLACK: [u8; 3] = [0, 0, 0];
const DARK: [u8; 3] = [18, 18, 18];
const CAPTION_BG: [u8; 3] = [250, 190, 50];

/// Everything needed to draw frames of one size in one layout.
pub(crate) struct Composer {
    layout: Layout,
    in_w: usize,
    in_h: usize,
    panel_w: usize,
    panel_h: usize,
    /// Panel size over input size (1 or 1/2).
    scale: f64,
    out_w: usize,
    out_h: usize,
    skeleton: Skeleton,
    text: TextPainter,
    style: Style,
}

/// `v` rounded up to even: yuv420p needs even sizes, so odd ones get one
/// black pixel of padding.
fn even(v: usize) -> usize {
    v + (v & 1)
}

impl Composer {
    /// Frames of `in_w` x `in_h` with keypoints named `names`.
    pub(crate) fn new(
        in_w: u32,
        in_h: u32,
        layout: Layout,
        names: &[String],
    ) -> Result<Self, OverlayError> {
        let (in_w, in_h) = (in_w as usize, in_h as usize);
        if in_w < 2 || in_h < 2 || in_w > 16384 || in_h > 16384 {
            return Err(OverlayError::BadInput(format!(
                "frame size {in_w}x{in_h} (2 to 16384 pixels a side)"
            )));
        }
        let (panels, halve) = match layout {
            Layout::Skeleton => (1, false),
            Layout::SideBySide { .. } => (3, 3 * in_w > MAX_SIDE_BY_SIDE_WIDTH),
        };
        let (panel_w, panel_h, scale) = if halve {
            (in_w / 2, in_h / 2, 0.5)
        } else {
            (in_w, in_h, 1.0)
        };
        let px = (panel_h as f32 / 28.0).clamp(11.0, 48.0);
        Ok(Self {
            layout,
            in_w,
            in_h,
            panel_w,
            panel_h,
            scale,
            out_w: even(panels * panel_w),
            out_h: even(panel_h),
            skeleton: Skeleton::new(names),
            text: TextPainter::new(px),
            style: Style::for_height(panel_h),
        })
    }

    /// Size of the encoded frames (always even).
    pub(crate) fn out_size(&self) -> (usize, usize) {
        (self.out_w, self.out_h)
    }

    /// Draws one frame into `buf` (RGB24, `out_size`). Bytes of the padding
    /// are never written, so a zeroed buffer keeps them black.
    pub(crate) fn render(
        &self,
        buf: &mut [u8],
        original: &RgbImage,
        regenerated: Option<&RgbImage>,
        marks: &FrameMarks,
    ) -> Result<(), OverlayError> {
        if (original.width() as usize, original.height() as usize) != (self.in_w, self.in_h) {
            return Err(OverlayError::BadInput(format!(
                "frame {} is {}x{}, the overlay was started for {}x{}",
                marks.frame,
                original.width(),
                original.height(),
                self.in_w,
                self.in_h
            )));
        }
        let header = format!("frame {}   {:.3} s", marks.frame, marks.time_s);
        match self.layout {
            Layout::Skeleton => {
                let mut c = self.panel(buf, 0);
                c.blit(original);
                if marks.dim.is_some() {
                    c.dim(DIM_FACTOR);
                }
                self.skeleton_and_events(&mut c, marks);
                let (_, h) = self.text.label(&mut c, 0, 0, &header, WHITE, BLACK);
                self.event_labels(&mut c, h, marks);
                self.dim_caption(&mut c, marks);
            }
            Layout::SideBySide { backdrop } => {
                let mut c = self.panel(buf, 0);
                c.blit(original);
                if marks.dim.is_some() {
                    c.dim(DIM_FACTOR);
                }
                let (_, h) = self.text.label(&mut c, 0, 0, "original", WHITE, BLACK);
                self.text.label(&mut c, 0, h, &header, WHITE, BLACK);
                self.dim_caption(&mut c, marks);

                let mut c = self.panel(buf, 1);
                c.blit(regenerated.unwrap_or(original));
                if marks.dim.is_some() {
                    c.dim(DIM_FACTOR);
                }
                let title = match regenerated {
                    Some(_) => "regenerated",
                    None => "not regenerated",
                };
                self.text.label(&mut c, 0, 0, title, WHITE, BLACK);
                self.dim_caption(&mut c, marks);

                let mut c = self.panel(buf, 2);
                match backdrop {
                    Backdrop::Dark => c.fill(DARK),
                    Backdrop::Original => {
                        c.blit(original);
                        if marks.dim.is_some() {
                            c.dim(DIM_FACTOR);
                        }
                    }
                }
                self.skeleton_and_events(&mut c, marks);
                let (_, h) = self.text.label(&mut c, 0, 0, "keypoints", WHITE, BLACK);
                self.event_labels(&mut c, h, marks);
                self.dim_caption(&mut c, marks);
            }
        }
        Ok(())
    }

    fn panel<'b>(&self, buf: &'b mut [u8], i: usize) -> Canvas<'b> {
        Canvas::new(
            buf,
            self.out_w,
            i * self.panel_w,
            0,
            self.panel_w,
            self.panel_h,
        )
    }

    fn skeleton_and_events(&self, c: &mut Canvas, marks: &FrameMarks) {
        if let Some(pose) = &marks.pose {
            self.skeleton.draw(c, pose, self.scale, self.style);
            for ev in &marks.events {
                self.skeleton
                    .event_marker(c, pose, ev, self.scale, self.style);
            }
        }
    }

    /// "L heel strike", "R toe-off"... stacked from `y` down, white on the
    /// side's colour.
    fn event_labels(&self, c: &mut Canvas, mut y: i32, marks: &FrameMarks) {
        for ev in &marks.events {
            let s = format!(
                "{} {}",
                ev.side.letter(),
                match ev.kind {
                    EventKind::HeelStrike => "heel strike",
                    EventKind::ToeOff => "toe-off",
                }
            );
            let (_, h) = self.text.label(c, 0, y, &s, WHITE, side_colour(ev.side));
            y += h;
        }
    }

    /// Why the frame is dimmed, bottom left, black on amber.
    fn dim_caption(&self, c: &mut Canvas, marks: &FrameMarks) {
        if let Some(reason) = &marks.dim {
            let h = self.text.line_height() + (self.text.line_height() / 4).max(1);
            let y = c.height() as i32 - h;
            self.text.label(c, 0, y, reason, BLACK, CAPTION_BG);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{EventMark, Side};
    use gait_core::{Keypoint, Pose};

    fn names() -> Vec<String> {
        vec!["left_knee".into(), "right_knee".into()]
    }

    fn marks(dim: Option<&str>) -> FrameMarks {
        FrameMarks {
            frame: 3,
            time_s: 0.1,
            pose: Some(Pose {
                keypoints: vec![
                    Keypoint::new(20.0, 60.0, 1.0),
                    Keypoint::new(40.0, 60.0, 1.0),
                ],
            }),
            events: vec![EventMark {
                side: Side::Left,
                kind: EventKind::HeelStrike,
                age_frames: 0,
            }],
            dim: dim.map(str::to_string),
        }
    }

    fn px(buf: &[u8], w: usize, x: usize, y: usize) -> [u8; 3] {
        let i = (y * w + x) * 3;
        [buf[i], buf[i + 1], buf[i + 2]]
    }

    #[test]
    fn dimmed_frames_are_darker_but_keypoints_are_not() {
        let img = RgbImage::from_pixel(161, 121, image::Rgb([200, 200, 200]));
        let c = Composer::new(161, 121, Layout::Skeleton, &names()).unwrap();
        assert_eq!(c.out_size(), (162, 122), "odd sizes are padded");
        let (w, h) = c.out_size();
        let mut plain = vec![0u8; w * h * 3];
        c.render(&mut plain, &img, None, &marks(None)).unwrap();
        let mut dim = vec![0u8; w * h * 3];
        c.render(&mut dim, &img, None, &marks(Some("outside walking bout")))
            .unwrap();
        assert_eq!(px(&plain, w, 150, 60), [200, 200, 200]);
        assert_eq!(px(&dim, w, 150, 60), [80, 80, 80]);
        assert_eq!(px(&dim, w, 20, 60), crate::draw::LEFT_COLOUR);
        assert_eq!(px(&dim, w, 40, 60), crate::draw::RIGHT_COLOUR);
        assert_eq!(px(&dim, w, 161, 60), [0, 0, 0], "padding column");
        // The caption sits bottom left, on amber.
        let amber = (0..w * h)
            .filter(|&i| dim[i * 3..i * 3 + 3] == CAPTION_BG)
            .count();
        assert!(amber > 50);
        assert!(!plain.chunks(3).any(|p| p == CAPTION_BG));
    }

    #[test]
    fn side_by_side_has_three_panels() {
        let img = RgbImage::from_pixel(90, 80, image::Rgb([100, 150, 200]));
        let regen = RgbImage::from_pixel(45, 40, image::Rgb([10, 20, 30]));
        let layout = Layout::SideBySide {
            backdrop: Backdrop::Dark,
        };
        let c = Composer::new(90, 80, layout, &names()).unwrap();
        let (w, h) = c.out_size();
        assert_eq!((w, h), (270, 80));
        let mut buf = vec![0u8; w * h * 3];
        c.render(&mut buf, &img, Some(&regen), &marks(None))
            .unwrap();
        assert_eq!(px(&buf, w, 80, 70), [100, 150, 200], "original");
        assert_eq!(
            px(&buf, w, 90 + 80, 70),
            [10, 20, 30],
            "regenerated, resized"
        );
        assert_eq!(px(&buf, w, 180 + 80, 70), DARK, "keypoints on dark");
        assert_eq!(px(&buf, w, 180 + 40, 60), crate::draw::RIGHT_COLOUR);
        assert_eq!(
            px(&buf, w, 40, 60),
            [100, 150, 200],
            "no skeleton on the original"
        );
    }

    #[test]
    fn wide_side_by_side_is_halved_and_wrong_sizes_are_refused() {
        let layout = Layout::SideBySide {
            backdrop: Backdrop::Original,
        };
        let c = Composer::new(1920, 1080, layout, &names()).unwrap();
        assert_eq!(c.out_size(), (2880, 540));
        let small = RgbImage::new(10, 10);
        let mut buf = vec![0u8; 2880 * 540 * 3];
        let e = c.render(&mut buf, &small, None, &marks(None)).unwrap_err();
        assert!(e.to_string().contains("10x10"), "{e}");
        assert!(Composer::new(0, 10, Layout::Skeleton, &names()).is_err());
    }
}
