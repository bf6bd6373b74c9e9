//! mediapipe's One-Euro filter on the two auxiliary landmarks (33 = hip
//! centre, 34 = scale point) that the next frame's crop is built from.
//!
//! In video mode mediapipe 0.10.14 always runs this filter, even with
//! `smooth_landmarks = false` (pose_landmark_filtering.pbtxt: the last
//! `LandmarksSmoothingCalculator`, one_euro_filter { min_cutoff: 0.01,
//! beta: 10, derivate_cutoff: 1 }); only the crop sees it, the landmarks given
//! out are unfiltered. Reproduced here to the float type of every step
//! (landmarks_smoothing_calculator_utils.cc, util/filtering/one_euro_filter.cc,
//! low_pass_filter.cc):
//! - every axis (x, y; z plays no part in the crop) of every landmark has its
//!   own filter, run on pixel coordinates (`norm * width`, f32), the result
//!   divided back by the width / height;
//! - value scale = 1 / object scale, the object scale being the mean of the
//!   width and height in pixels of the unscaled alignment rectangle of the
//!   UNFILTERED landmarks 33/34 (`AlignmentPointsRectsCalculator`: side =
//!   2 |p34 - p33|); below 1e-6 (min_allowed_object_scale) the landmarks pass
//!   unfiltered;
//! - the sampling frequency comes from the timestamps: the Python solution
//!   API (solution_base.py) feeds `k * 33333` us whatever the video's rate,
//!   so the frequency is `1 / (33333000 ns * 1e-9)`; the first value after a
//!   (re)start passes through and only primes the filter (the frequency of
//!   that call is never used);
//! - the filter starts afresh whenever a frame gives no landmarks (the
//!   calculator resets on empty input), i.e. before every new detection.

/// Which filter the crop tracked into the next frame goes through.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RoiFilter {
    /// The crop straight from this frame's landmarks 33/34.
    #[default]
    None,
    /// mediapipe's One-Euro filter on landmarks 33/34 first, as its video
    /// mode (and so `mp.solutions.pose.Pose`) does.
    Mediapipe,
}

/// `options.min_cutoff()`: a proto float, widened to double.
const MIN_CUTOFF: f64 = 0.01f32 as f64;
const BETA: f64 = 10.0;
const DERIVATE_CUTOFF: f64 = 1.0;
const MIN_ALLOWED_OBJECT_SCALE: f32 = 1e-6;
/// The Python solution API's timestamp step, in nanoseconds (33333 us).
const STEP_NS: i64 = 33_333_000;

/// `OneEuroFilter::frequency_` from two timestamps `STEP_NS` apart.
fn frequency() -> f64 {
    1.0 / (STEP_NS as f64 * 1e-9)
}

/// `OneEuroFilter::GetAlpha`, narrowed to the f32 `LowPassFilter` takes.
fn alpha(cutoff: f64) -> f32 {
    let te = 1.0 / frequency();
    let tau = 1.0 / (2.0 * std::f64::consts::PI * cutoff);
    (1.0 / (1.0 + tau / te)) as f32
}

/// `LowPassFilter::Apply` once initialised: `alpha_ * value` in f32, the
/// rest in f64 (`1.0 - alpha_`), stored as f32.
fn low_pass(value: f32, alpha: f32, stored: f32) -> f32 {
    ((alpha * value) as f64 + (1.0 - alpha as f64) * stored as f64) as f32
}

/// One axis' One-Euro filter after its first value: the value low-pass's
/// last raw input and output, the derivative low-pass's last output.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Axis {
    raw: f32,
    value: f32,
    derivative: f32,
}

impl Axis {
    /// The first value: passes through (both low-passes return their input).
    fn start(value: f64) -> (Self, f32) {
        let v = value as f32;
        let axis = Axis {
            raw: v,
            value: v,
            derivative: 0.0,
        };
        (axis, v)
    }

    /// `OneEuroFilter::Apply` with a later timestamp.
    fn apply(&mut self, value_scale: f64, value: f64) -> f32 {
        let dvalue = (value - self.raw as f64) * value_scale * frequency();
        self.derivative = low_pass(dvalue as f32, alpha(DERIVATE_CUTOFF), self.derivative);
        let cutoff = MIN_CUTOFF + BETA * (self.derivative as f64).abs();
        let v = value as f32;
        self.value = low_pass(v, alpha(cutoff), self.value);
        self.raw = v;
        self.value
    }
}

/// The filter state of landmarks 33 and 34: x33, y33, x34, y34; `None`
/// before the first frame after a (re)start.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AuxFilter {
    axes: Option<[Axis; 4]>,
}

/// f32 values in [`AuxFilter::to_values`].
pub const STATE_LEN: usize = 13;

impl AuxFilter {
    /// Forgets the past: the next frame starts the filter afresh.
    pub fn reset(&mut self) {
        self.axes = None;
    }

    /// Filters this frame's landmarks 33 (`p0`) and 34 (`p1`), normalised,
    /// in a `width` x `height` image; returns them filtered, normalised.
    pub fn apply(
        &mut self,
        p0: (f32, f32),
        p1: (f32, f32),
        width: u32,
        height: u32,
    ) -> [(f32, f32); 2] {
        let (wf, hf) = (width as f32, height as f32);
        let px = [p0.0 * wf, p0.1 * hf, p1.0 * wf, p1.1 * hf];
        // GetObjectScale of the AlignmentPointsRectsCalculator rectangle.
        let (dx, dy) = (px[2] - px[0], px[3] - px[1]);
        let box_size = (dx * dx + dy * dy).sqrt() * 2.0;
        let object_scale = ((box_size / wf) * wf + (box_size / hf) * hf) / 2.0;
        if object_scale < MIN_ALLOWED_OBJECT_SCALE {
            return [p0, p1];
        }
        let value_scale = (1.0f32 / object_scale) as f64;
        let mut out = [0f32; 4];
        match &mut self.axes {
            Some(axes) => {
                for ((axis, o), v) in axes.iter_mut().zip(&mut out).zip(px) {
                    *o = axis.apply(value_scale, v as f64);
                }
            }
            None => {
                let mut axes = [Axis::start(0.0).0; 4];
                for ((axis, o), v) in axes.iter_mut().zip(&mut out).zip(px) {
                    (*axis, *o) = Axis::start(v as f64);
                }
                self.axes = Some(axes);
            }
        }
        [(out[0] / wf, out[1] / hf), (out[2] / wf, out[3] / hf)]
    }

    /// The state as [`STATE_LEN`] f32s: a started flag (1 or 0), then raw,
    /// value, derivative of each axis (zeros when not started).
    pub fn to_values(&self) -> [f32; STATE_LEN] {
        let mut v = [0f32; STATE_LEN];
        if let Some(axes) = &self.axes {
            v[0] = 1.0;
            for (i, a) in axes.iter().enumerate() {
                v[1 + 3 * i..4 + 3 * i].copy_from_slice(&[a.raw, a.value, a.derivative]);
            }
        }
        v
    }

    /// The state from [`Self::to_values`].
    pub fn from_values(v: &[f32]) -> Self {
        let axes = (v.len() == STATE_LEN && v[0] == 1.0).then(|| {
            std::array::from_fn(|i| Axis {
                raw: v[1 + 3 * i],
                value: v[2 + 3 * i],
                derivative: v[3 + 3 * i],
            })
        });
        AuxFilter { axes }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_value_passes_then_lags() {
        let mut f = AuxFilter::default();
        let (w, h) = (640, 360);
        let a = f.apply((0.5, 0.6), (0.5, 0.3), w, h);
        assert_eq!(a, [(0.5, 0.6), (0.5, 0.3)]);
        // A jump: the filtered point moves towards it, not all the way.
        let b = f.apply((0.6, 0.6), (0.6, 0.3), w, h);
        assert!(b[0].0 > 0.5 && b[0].0 < 0.6, "{b:?}");
        assert_eq!(b[0].1, 0.6);
        // Standing still afterwards: it keeps closing in.
        let c = f.apply((0.6, 0.6), (0.6, 0.3), w, h);
        assert!(c[0].0 > b[0].0 && c[0].0 <= 0.6, "{c:?}");
        f.reset();
        assert_eq!(f.apply((0.1, 0.2), (0.1, 0.1), w, h)[0], (0.1, 0.2));
    }

    #[test]
    fn alphas_are_mediapipes() {
        // pose_landmark_filtering.pbtxt: "~0.002 alpha when static", "~0.17
        // alpha in the velocity filter" (at 30 fps).
        assert!((alpha(MIN_CUTOFF) - 0.0021).abs() < 1e-4);
        assert!((alpha(DERIVATE_CUTOFF) - 0.173).abs() < 1e-3);
    }

    #[test]
    fn state_round_trips() {
        let mut f = AuxFilter::default();
        assert_eq!(AuxFilter::from_values(&f.to_values()), f);
        f.apply((0.5, 0.6), (0.5, 0.3), 100, 100);
        f.apply((0.52, 0.61), (0.5, 0.33), 100, 100);
        let mut g = AuxFilter::from_values(&f.to_values());
        assert_eq!(g, f);
        assert_eq!(
            g.apply((0.55, 0.6), (0.5, 0.3), 100, 100),
            f.apply((0.55, 0.6), (0.5, 0.3), 100, 100)
        );
    }

    #[test]
    fn degenerate_scale_passes_unfiltered() {
        let mut f = AuxFilter::default();
        f.apply((0.5, 0.5), (0.5, 0.4), 100, 100);
        // Landmarks 33 and 34 on one point: object scale 0.
        assert_eq!(
            f.apply((0.7, 0.7), (0.7, 0.7), 100, 100),
            [(0.7, 0.7), (0.7, 0.7)]
        );
    }
}
