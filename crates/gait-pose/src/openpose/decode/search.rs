//! The multi-scale search around the network: image scaling and padding,
//! and the per-channel upsampling and averaging of its output maps.

use gait_core::{Frame, StageError};

use super::super::{NetInput, NetOutput, OpenposeModel};
use super::cv_resize::{Geometry, Interp, resize_f32, resize_u8};
use super::{Accumulate, ResizeMode, SearchParams, Stride8Maps};

/// The network's input stride.
pub(crate) const STRIDE: usize = 8;

/// One scale's prepared input: its size before padding.
pub(crate) struct Scaled {
    pub input: NetInput,
    pub height: usize,
    pub width: usize,
}

/// Resizes a BGR `u8` image for one scale multiplier and pads it.
pub(crate) fn prepare(
    bgr: &[u8],
    width: usize,
    height: usize,
    multiplier: f64,
    params: &SearchParams,
) -> Scaled {
    let (g, interp) = match params.resize {
        ResizeMode::ControlnetAux => {
            // util.smart_resize_k: size int(w * f), AREA when shrinking (by the
            // mean of both sides), else LANCZOS4.
            let (ht, wt) = (height as f64 * multiplier, width as f64 * multiplier);
            let k = (ht + wt) / (height + width) as f64;
            let g = Geometry::to_size(width, height, (wt as usize).max(1), (ht as usize).max(1));
            (
                g,
                if k < 1.0 {
                    Interp::Area
                } else {
                    Interp::Lanczos4
                },
            )
        }
        ResizeMode::Cubic => {
            let mut g = Geometry::by_factor(width, height, multiplier);
            if g.dw == 0 || g.dh == 0 {
                g = Geometry::to_size(width, height, g.dw.max(1), g.dh.max(1));
            }
            (g, Interp::Cubic)
        }
    };
    let small = resize_u8(bgr, 3, g, interp);
    let (h, w) = (g.dh, g.dw);
    let hp = h.div_ceil(STRIDE) * STRIDE;
    let wp = w.div_ceil(STRIDE) * STRIDE;
    let pad = params.pad_value as f32 / 256.0 - 0.5;
    let mut data = vec![pad; 3 * hp * wp];
    for y in 0..h {
        for x in 0..w {
            for c in 0..3 {
                data[c * hp * wp + y * wp + x] = small[(y * w + x) * 3 + c] as f32 / 256.0 - 0.5;
            }
        }
    }
    Scaled {
        input: NetInput {
            data,
            height: hp,
            width: wp,
        },
        height: h,
        width: w,
    }
}

/// Upsamples one stride-8 channel x8, crops the padding and resizes it to
/// the image size, as controlnet_aux (or the original cubic code) does.
fn to_full(
    plane: &[f32],
    out: &NetOutput,
    scaled: (usize, usize),
    full: (usize, usize),
    mode: ResizeMode,
) -> Vec<f32> {
    let up_interp = match mode {
        ResizeMode::ControlnetAux => Interp::Lanczos4,
        ResizeMode::Cubic => Interp::Cubic,
    };
    let g = Geometry::by_factor(out.width, out.height, STRIDE as f64);
    let up = resize_f32(plane, 1, g, up_interp);
    let (sh, sw) = (scaled.0.min(g.dh), scaled.1.min(g.dw));
    let mut crop = Vec::with_capacity(sh * sw);
    for y in 0..sh {
        crop.extend_from_slice(&up[y * g.dw..y * g.dw + sw]);
    }
    let (fh, fw) = full;
    let interp = match mode {
        ResizeMode::ControlnetAux if ((fh + fw) as f64 / (sh + sw) as f64) < 1.0 => Interp::Area,
        ResizeMode::ControlnetAux => Interp::Lanczos4,
        ResizeMode::Cubic => Interp::Cubic,
    };
    resize_f32(&crop, 1, Geometry::to_size(sw, sh, fw, fh), interp)
}

/// Checks one network output against the model and the input it was given.
pub(crate) fn check_output(
    out: &NetOutput,
    input: &NetInput,
    model: OpenposeModel,
) -> Result<(), StageError> {
    let (h, w) = (input.height / STRIDE, input.width / STRIDE);
    let n = out.height * out.width;
    if out.height != h
        || out.width != w
        || out.heatmaps.len() != model.heatmap_channels() * n
        || out.pafs.len() != model.paf_channels() * n
    {
        return Err(StageError::BadInput(format!(
            "OpenPose network output is {}x{} with {} heatmap and {} PAF values; expected {h}x{w} with {} and {} channels",
            out.height,
            out.width,
            out.heatmaps.len(),
            out.pafs.len(),
            model.heatmap_channels(),
            model.paf_channels()
        )));
    }
    Ok(())
}

/// Network outputs of all scales; channels are brought to full resolution
/// one at a time, so memory stays at a few full-size planes.
pub(crate) struct MultiScale {
    pub outputs: Vec<(NetOutput, usize, usize)>,
    pub height: usize,
    pub width: usize,
    pub mode: ResizeMode,
    pub accumulate: Accumulate,
}

impl MultiScale {
    /// Runs the network on every scale of `frame`.
    pub fn run(
        frame: &Frame,
        model: OpenposeModel,
        params: &SearchParams,
        net: &mut dyn FnMut(&NetInput) -> Result<NetOutput, StageError>,
    ) -> Result<Self, StageError> {
        let (width, height) = (frame.width() as usize, frame.height() as usize);
        let bgr: Vec<u8> = frame
            .image
            .pixels()
            .flat_map(|p| [p.0[2], p.0[1], p.0[0]])
            .collect();
        let mut outputs = Vec::new();
        for &s in &params.scales {
            let multiplier = s * params.box_size as f64 / height as f64;
            if !(multiplier > 0.0 && multiplier.is_finite()) {
                return Err(StageError::BadInput(format!(
                    "OpenPose scale {s} gives no image"
                )));
            }
            let scaled = prepare(&bgr, width, height, multiplier, params);
            let out = net(&scaled.input)?;
            check_output(&out, &scaled.input, model)?;
            outputs.push((out, scaled.height, scaled.width));
        }
        Ok(Self {
            outputs,
            height,
            width,
            mode: params.resize,
            accumulate: params.accumulate,
        })
    }

    /// Wraps stride-8 maps given directly (one per scale with its unpadded size).
    pub fn from_maps(
        maps: Vec<Stride8Maps>,
        height: usize,
        width: usize,
        params: &SearchParams,
    ) -> Self {
        Self {
            outputs: maps
                .into_iter()
                .map(|m| (m.output, m.scaled_height, m.scaled_width))
                .collect(),
            height,
            width,
            mode: params.resize,
            accumulate: params.accumulate,
        }
    }

    /// The averaged full-resolution heatmap (`paf == false`) or PAF channel.
    pub fn channel(&self, c: usize, paf: bool) -> Vec<f64> {
        let n = self.outputs.len() as f32;
        let mut avg = vec![0f64; self.height * self.width];
        for (out, sh, sw) in &self.outputs {
            let plane_len = out.height * out.width;
            let src = if paf { &out.pafs } else { &out.heatmaps };
            let Some(plane) = src.get(c * plane_len..(c + 1) * plane_len) else {
                continue;
            };
            let full = to_full(plane, out, (*sh, *sw), (self.height, self.width), self.mode);
            for (a, v) in avg.iter_mut().zip(full) {
                // numpy: float32 map / n stays float32, then adds into float64.
                let q = (v / n) as f64;
                *a = match (self.accumulate, paf) {
                    // controlnet_aux's `heatmap_avg += heatmap_avg + heatmap / n`.
                    (Accumulate::ControlnetAux, false) => *a + (*a + q),
                    _ => *a + q,
                };
            }
        }
        avg
    }
}
