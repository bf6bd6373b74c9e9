//! Decoding the detector's raw outputs and mediapipe's weighted non-maximum
//! suppression.

use super::anchors::DETECTOR_SIZE;

/// A person detection in normalised detector-input coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Detection {
    pub score: f32,
    /// xmin, ymin, xmax, ymax.
    pub bbox: [f32; 4],
    /// kp0 mid-hip, kp1 body size/rotation point, kp2 mid-shoulder, kp3 upper body.
    pub keypoints: [(f32, f32); 4],
}

/// Values per anchor row: box (cx, cy, w, h) and four keypoints.
pub const ROW: usize = 12;

/// Detections with score >= `threshold` from raw `regressors` (anchors x 12)
/// and `scores` (anchors) logits.
pub fn decode(
    regressors: &[f32],
    scores: &[f32],
    anchors: &[(f32, f32)],
    threshold: f32,
) -> Vec<Detection> {
    let s = DETECTOR_SIZE as f32;
    let mut out = Vec::new();
    for (i, (&(ax, ay), &logit)) in anchors.iter().zip(scores).enumerate() {
        let score = 1.0 / (1.0 + (-logit.clamp(-100.0, 100.0)).exp());
        if score < threshold {
            continue;
        }
        let Some(r) = regressors.get(i * ROW..(i + 1) * ROW) else {
            break;
        };
        let (cx, cy) = (r[0] / s + ax, r[1] / s + ay);
        let (w, h) = (r[2] / s, r[3] / s);
        let mut keypoints = [(0.0, 0.0); 4];
        for (k, kp) in keypoints.iter_mut().enumerate() {
            *kp = (r[4 + 2 * k] / s + ax, r[5 + 2 * k] / s + ay);
        }
        out.push(Detection {
            score,
            bbox: [cx - w / 2.0, cy - h / 2.0, cx + w / 2.0, cy + h / 2.0],
            keypoints,
        });
    }
    out
}

fn iou(a: &[f32; 4], b: &[f32; 4]) -> f32 {
    let iw = (a[2].min(b[2]) - a[0].max(b[0])).max(0.0);
    let ih = (a[3].min(b[3]) - a[1].max(b[1])).max(0.0);
    let inter = iw * ih;
    let union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter;
    if union > 0.0 { inter / union } else { 0.0 }
}

/// Weighted NMS: each cluster (IoU > `threshold` with its best member) is
/// replaced by the score-weighted mean of its boxes and keypoints, keeping the
/// best score. Output is sorted by score, best first.
pub fn weighted_nms(mut dets: Vec<Detection>, threshold: f32) -> Vec<Detection> {
    dets.sort_by(|a, b| b.score.total_cmp(&a.score));
    let mut out = Vec::new();
    while let Some(top) = dets.first().cloned() {
        let (cluster, rest): (Vec<_>, Vec<_>) = dets
            .into_iter()
            .partition(|d| iou(&top.bbox, &d.bbox) > threshold);
        dets = rest;
        if cluster.is_empty() {
            // Only when the top box has zero area (IoU with itself is 0).
            dets.retain(|d| d != &top);
        }
        out.push(weighted_mean(top, &cluster));
    }
    out
}

/// `top` with the score-weighted mean box and keypoints of `cluster`, in
/// mediapipe's order (sums of value x score, one division), so the crop
/// built from the keypoints is the same to the last bit.
fn weighted_mean(top: Detection, cluster: &[Detection]) -> Detection {
    let mut total = 0f32;
    let mut bbox = [0f32; 4];
    let mut keypoints = [(0f32, 0f32); 4];
    for d in cluster {
        total += d.score;
        for (m, v) in bbox.iter_mut().zip(d.bbox) {
            *m += v * d.score;
        }
        for (m, v) in keypoints.iter_mut().zip(d.keypoints) {
            m.0 += v.0 * d.score;
            m.1 += v.1 * d.score;
        }
    }
    if total.is_nan() || total <= 0.0 {
        return top;
    }
    Detection {
        score: top.score,
        bbox: bbox.map(|v| v / total),
        keypoints: keypoints.map(|(x, y)| (x / total, y / total)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn det(score: f32, x: f32) -> Detection {
        Detection {
            score,
            bbox: [x, 0.0, x + 1.0, 1.0],
            keypoints: [(x, 0.0); 4],
        }
    }

    #[test]
    fn clusters_are_averaged_by_score() {
        let out = weighted_nms(vec![det(0.6, 0.2), det(0.9, 0.0), det(0.7, 5.0)], 0.3);
        assert_eq!(out.len(), 2);
        assert_eq!(out[0].score, 0.9);
        let want = 0.2 * 0.6 / 1.5;
        assert!((out[0].bbox[0] - want).abs() < 1e-6);
        assert!((out[0].keypoints[0].0 - want).abs() < 1e-6);
        assert_eq!(out[1].bbox[0], 5.0);
    }

    #[test]
    fn decode_thresholds_and_offsets() {
        let anchors = [(0.5, 0.5), (0.25, 0.25)];
        let mut reg = vec![0.0; 24];
        reg[12] = 22.4; // cx + 0.1
        reg[14] = 44.8; // w 0.2
        reg[15] = 44.8;
        let dets = decode(&reg, &[-5.0, 5.0], &anchors, 0.5);
        assert_eq!(dets.len(), 1);
        let b = dets[0].bbox;
        assert!((b[0] - 0.25).abs() < 1e-6 && (b[2] - 0.45).abs() < 1e-6);
        assert!((b[1] - 0.15).abs() < 1e-6);
    }
}
