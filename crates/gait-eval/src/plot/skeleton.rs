//! A strip of frames with the detected skeleton drawn over them.

use std::collections::BTreeMap;

use gait_core::{Frame, PoseSequence};
use image::RgbImage;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::{Draw, FONT, Figure, LEFT, RIGHT, err, render};
use crate::EvalError;
use crate::names::to_canonical;

/// Size of the strip.
#[derive(Debug, Clone, PartialEq)]
pub struct StripOptions {
    /// At most this many frames, evenly spaced over the sequence.
    pub max_frames: usize,
    /// Height of the strip in pixels; frames are scaled to it.
    pub height: u32,
}

impl Default for StripOptions {
    fn default() -> Self {
        Self {
            max_frames: 6,
            height: 360,
        }
    }
}

/// One panel: where it sits and how image coordinates map into it.
struct Panel {
    frame: usize,
    x_offset: f64,
    origin: (f64, f64),
    scale: f64,
    /// Canonical name -> position in image pixels, for found keypoints.
    points: BTreeMap<String, (f64, f64)>,
}

struct Strip {
    panels: Vec<Panel>,
}

fn colour(name: &str) -> RGBColor {
    if name.starts_with("left_") {
        LEFT
    } else if name.starts_with("right_") {
        RIGHT
    } else {
        RGBColor(90, 90, 90)
    }
}

impl Draw for Strip {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        _bitmap: bool,
    ) -> Result<(), String> {
        for p in &self.panels {
            let at = |(x, y): (f64, f64)| -> (i32, i32) {
                (
                    (p.x_offset + (x - p.origin.0) * p.scale).round() as i32,
                    ((y - p.origin.1) * p.scale).round() as i32,
                )
            };
            for &(a, b) in gait_core::keypoint::UPPER_SEGMENTS
                .iter()
                .chain(&gait_core::keypoint::LEG_SEGMENTS)
            {
                if let (Some(&pa), Some(&pb)) = (p.points.get(a), p.points.get(b)) {
                    let c = if colour(a) == colour(b) {
                        colour(a)
                    } else {
                        colour(b)
                    };
                    root.draw(&PathElement::new(vec![at(pa), at(pb)], c.stroke_width(3)))
                        .map_err(err)?;
                }
            }
            for (name, &pt) in &p.points {
                root.draw(&Circle::new(at(pt), 4, colour(name).filled()))
                    .map_err(err)?;
            }
            let x = p.x_offset.round() as i32;
            root.draw(&Text::new(
                format!("frame {}", p.frame),
                (x + 6, 6),
                (FONT, 16).into_font().color(&BLACK),
            ))
            .map_err(err)?;
        }
        Ok(())
    }
}

/// Up to `opts.max_frames` evenly spaced frames of `seq` (of those with a
/// pose, when any has one) side by side with
/// the skeleton drawn over them (left blue, right red). Frames are taken from
/// `images` by index; where an image is missing the skeleton is drawn on
/// white. The SVG holds the skeletons only; the PNG has the frames too.
pub fn skeleton_strip(
    seq: &PoseSequence,
    images: &[Frame],
    opts: &StripOptions,
) -> Result<Figure, EvalError> {
    if seq.is_empty() || opts.max_frames == 0 || opts.height < 16 {
        return Err(EvalError::plot(
            "skeleton_strip",
            "no frames to draw (or max_frames 0 / height below 16 pixels)",
        ));
    }
    let none = BTreeMap::new();
    let canonical: Vec<Option<String>> = seq.names.iter().map(|n| to_canonical(n, &none)).collect();
    // Frames with somebody in them: a subject-tracked run leaves the frames
    // where the subject is out of view empty, and a strip of empty panels
    // shows nothing. Without any pose, every frame.
    let mut seen: Vec<usize> = (0..seq.len())
        .filter(|&i| seq.poses[i].keypoints.iter().any(|k| k.is_found()))
        .collect();
    if seen.is_empty() {
        seen = (0..seq.len()).collect();
    }
    let n = opts.max_frames.min(seen.len());
    let rows: Vec<usize> = (0..n)
        .map(|i| {
            if n == 1 {
                seen[0]
            } else {
                seen[i * (seen.len() - 1) / (n - 1)]
            }
        })
        .collect();
    let h = f64::from(opts.height);
    let mut panels = Vec::with_capacity(n);
    let mut tiles: Vec<(u32, Option<RgbImage>)> = Vec::with_capacity(n);
    let mut x_offset = 0.0;
    for &row in &rows {
        let frame = seq.frames[row];
        let points: BTreeMap<String, (f64, f64)> = canonical
            .iter()
            .zip(&seq.poses[row].keypoints)
            .filter_map(|(c, k)| Some((c.clone()?, (k.x, k.y))).filter(|_| k.is_found()))
            .collect();
        let (origin, scale, width, tile) = match images.iter().find(|f| f.index == frame) {
            Some(f) if f.height() > 0 && f.width() > 0 => {
                let s = h / f64::from(f.height());
                let w = ((f64::from(f.width()) * s).round() as u32).max(1);
                let tile = image::imageops::resize(
                    &f.image,
                    w,
                    opts.height,
                    image::imageops::FilterType::Triangle,
                );
                ((0.0, 0.0), s, w, Some(tile))
            }
            _ => {
                let (mut x0, mut y0, mut x1, mut y1) = (
                    f64::INFINITY,
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                    f64::NEG_INFINITY,
                );
                for &(x, y) in points.values() {
                    (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
                }
                if !x0.is_finite() {
                    (x0, y0, x1, y1) = (0.0, 0.0, 1.0, 1.0);
                }
                // Pad the skeleton's box by 10 % and keep the panel's aspect sane.
                let pad = 0.1 * (x1 - x0).max(y1 - y0).max(1.0);
                let (bw, bh) = (x1 - x0 + 2.0 * pad, y1 - y0 + 2.0 * pad);
                let s = h / bh;
                let w = (bw * s).clamp(0.4 * h, 1.5 * h).round() as u32;
                let cx = (x0 + x1) / 2.0 - f64::from(w) / s / 2.0;
                ((cx, y0 - pad), s, w, None)
            }
        };
        panels.push(Panel {
            frame,
            x_offset,
            origin,
            scale,
            points,
        });
        tiles.push((width, tile));
        x_offset += f64::from(width);
    }
    let total_w = (x_offset.round() as u32).max(1);
    let mut background = RgbImage::from_pixel(total_w, opts.height, image::Rgb([255, 255, 255]));
    let mut x = 0i64;
    for (w, tile) in &tiles {
        if let Some(t) = tile {
            image::imageops::replace(&mut background, t, x, 0);
        }
        x += i64::from(*w);
    }
    render(
        &Strip { panels },
        "skeleton_strip",
        total_w,
        opts.height,
        Some(background),
    )
}
