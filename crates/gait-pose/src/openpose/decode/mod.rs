//! Turning heatmaps and part-affinity fields into people, as OpenPose's
//! Python code (pytorch-openpose / controlnet_aux `Body.__call__`) does it:
//! multi-scale search with box size 368, Gaussian-smoothed peak detection,
//! PAF line integrals and greedy assembly.

mod assemble;
mod cv_resize;
mod gaussian;
mod limbs;
mod peaks;
mod search;

use gait_core::{Frame, StageError};
use serde::{Deserialize, Serialize};

use super::{NetInput, NetOutput, OpenposeModel};
use assemble::{AssembleParams, connect, group};
use search::MultiScale;

pub use cv_resize::{Geometry, Interp, resize_f32, resize_u8};
pub use gaussian::gaussian_filter;
pub use limbs::{Limb, limbs};
pub use peaks::Peak;

/// How images and maps are resized between scales.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ResizeMode {
    /// controlnet_aux 0.0.10 (`smart_resize`): INTER_AREA when shrinking,
    /// INTER_LANCZOS4 otherwise, sizes truncated.
    #[default]
    ControlnetAux,
    /// pytorch-openpose / OpenPose's Python demo: INTER_CUBIC everywhere.
    Cubic,
}

/// How the heatmaps of several scales are combined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Accumulate {
    /// As controlnet_aux: `avg += avg + map / n` for heatmaps (later scales
    /// weigh less; identical to the mean for one scale), the mean for PAFs.
    #[default]
    ControlnetAux,
    /// The plain mean over scales for both.
    Mean,
}

/// Search and grouping parameters; defaults are controlnet_aux's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SearchParams {
    /// Height, in network pixels, that scale 1.0 maps the image to.
    pub box_size: u32,
    /// Scale factors of `box_size` (OpenPose's classic search: 0.5, 1, 1.5, 2).
    pub scales: Vec<f64>,
    /// Value of the padding pixels (right and bottom, to a multiple of 8).
    pub pad_value: u8,
    /// Minimum smoothed heatmap value of a peak.
    pub thresh1: f64,
    /// Minimum PAF alignment of a limb sample.
    pub thresh2: f64,
    /// Sigma of the Gaussian smoothing before peak detection.
    pub sigma: f64,
    /// Samples along a limb for the PAF line integral.
    pub mid_num: usize,
    /// People with fewer keypoints are dropped.
    pub min_parts: usize,
    /// People with a lower score per keypoint are dropped.
    pub min_mean_score: f64,
    pub resize: ResizeMode,
    pub accumulate: Accumulate,
}

impl Default for SearchParams {
    fn default() -> Self {
        Self {
            box_size: 368,
            scales: vec![0.5],
            pad_value: 128,
            thresh1: 0.1,
            thresh2: 0.05,
            sigma: 3.0,
            mid_num: 10,
            min_parts: 4,
            min_mean_score: 0.4,
            resize: ResizeMode::ControlnetAux,
            accumulate: Accumulate::ControlnetAux,
        }
    }
}

/// One detected person.
#[derive(Debug, Clone, PartialEq)]
pub struct Person {
    /// Per keypoint in model order: x, y (original-image pixels) and heatmap score.
    pub keypoints: Vec<Option<[f32; 3]>>,
    /// Per keypoint: the id of its peak in [`Detection::peaks`].
    pub peak_ids: Vec<Option<usize>>,
    /// Sum of keypoint and limb scores.
    pub score: f32,
    /// Number of keypoints found.
    pub parts: usize,
}

/// Everything the decoding found: all peaks (controlnet_aux's `candidate`)
/// and the people (its `subset`), in its order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Detection {
    pub peaks: Vec<Peak>,
    pub people: Vec<Person>,
}

/// One scale's network output with the image size before padding.
#[derive(Debug, Clone, PartialEq)]
pub struct Stride8Maps {
    pub output: NetOutput,
    pub scaled_height: usize,
    pub scaled_width: usize,
}

/// Full-resolution maps (CHW, `channels` planes of `height` x `width`).
#[derive(Debug, Clone, PartialEq)]
pub struct FullMaps {
    pub data: Vec<f64>,
    pub channels: usize,
    pub height: usize,
    pub width: usize,
}

/// Runs the multi-scale search of `net` on `image` and decodes people.
pub fn detect(
    image: &Frame,
    model: OpenposeModel,
    params: &SearchParams,
    net: &mut dyn FnMut(&NetInput) -> Result<NetOutput, StageError>,
) -> Result<Detection, StageError> {
    if image.width() == 0 || image.height() == 0 {
        return Ok(Detection::default());
    }
    let ms = MultiScale::run(image, model, params, net)?;
    Ok(decode_with(
        ms.height,
        ms.width,
        model,
        params,
        &mut |c, paf| ms.channel(c, paf),
    ))
}

/// Decodes stride-8 maps already computed for each scale (as [`detect`]
/// would get them from the network) for an image of `height` x `width`.
pub fn decode_stride8(
    maps: Vec<Stride8Maps>,
    height: usize,
    width: usize,
    model: OpenposeModel,
    params: &SearchParams,
) -> Detection {
    let ms = MultiScale::from_maps(maps, height, width, params);
    decode_with(height, width, model, params, &mut |c, paf| {
        ms.channel(c, paf)
    })
}

/// Decodes full-resolution averaged heatmaps and PAFs (peaks, limbs, people).
pub fn decode(
    heatmaps: &FullMaps,
    pafs: &FullMaps,
    model: OpenposeModel,
    params: &SearchParams,
) -> Detection {
    let (h, w) = (heatmaps.height, heatmaps.width);
    let n = h * w;
    let plane = |m: &FullMaps, c: usize| -> Vec<f64> {
        if m.height != h || m.width != w {
            return vec![f64::NAN; n];
        }
        m.data
            .get(c * n..(c + 1) * n)
            .map_or_else(|| vec![f64::NAN; n], <[f64]>::to_vec)
    };
    decode_with(h, w, model, params, &mut |c, paf| {
        if paf {
            plane(pafs, c)
        } else {
            plane(heatmaps, c)
        }
    })
}

/// The decoding on channels fetched on demand (`channel(c, is_paf)`).
fn decode_with(
    height: usize,
    width: usize,
    model: OpenposeModel,
    params: &SearchParams,
    channel: &mut dyn FnMut(usize, bool) -> Vec<f64>,
) -> Detection {
    let n_parts = model.keypoints().len();
    let mut by_part: Vec<Vec<Peak>> = Vec::with_capacity(n_parts);
    let mut all: Vec<Peak> = Vec::new();
    for part in 0..n_parts {
        let map = channel(part, false);
        let found = peaks::find_peaks(&map, width, height, params.sigma, params.thresh1, all.len());
        all.extend_from_slice(&found);
        by_part.push(found);
    }
    let ap = AssembleParams {
        thresh2: params.thresh2,
        mid_num: params.mid_num,
        min_parts: params.min_parts as f64,
        min_mean_score: params.min_mean_score,
    };
    let limb_list = limbs(model);
    let connections: Vec<_> = limb_list
        .iter()
        .map(|l| {
            let (ca, cb) = (&by_part[l.a], &by_part[l.b]);
            if ca.is_empty() || cb.is_empty() {
                return None;
            }
            let (px, py) = (channel(l.paf_x, true), channel(l.paf_y, true));
            Some(connect(ca, cb, &px, &py, width, height, &ap))
        })
        .collect();
    let scores: Vec<f64> = all.iter().map(|p| p.score).collect();
    let rows = group(limb_list, &connections, &scores, n_parts, &ap);
    let people = rows
        .into_iter()
        .map(|r| Person {
            keypoints: r
                .parts
                .iter()
                .map(|id| {
                    id.and_then(|i| all.get(i))
                        .map(|p| [p.x as f32, p.y as f32, p.score as f32])
                })
                .collect(),
            peak_ids: r.parts,
            score: r.score as f32,
            parts: r.count as usize,
        })
        .collect();
    Detection { peaks: all, people }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_reject_unknown_keys_and_default() {
        let p: SearchParams = toml::from_str("scales = [0.5, 1.0]\nresize = \"cubic\"").unwrap();
        assert_eq!(p.scales, vec![0.5, 1.0]);
        assert_eq!(p.resize, ResizeMode::Cubic);
        assert_eq!(p.box_size, 368);
        let err = toml::from_str::<SearchParams>("scale = [1.0]")
            .unwrap_err()
            .to_string();
        assert!(err.contains("scale") && err.contains("scales"), "{err}");
    }

    #[test]
    fn empty_maps_give_nobody() {
        let m = |c| FullMaps {
            data: vec![0.0; c * 12],
            channels: c,
            height: 3,
            width: 4,
        };
        let d = decode(
            &m(19),
            &m(38),
            OpenposeModel::Coco18,
            &SearchParams::default(),
        );
        assert!(d.peaks.is_empty() && d.people.is_empty());
    }
}
