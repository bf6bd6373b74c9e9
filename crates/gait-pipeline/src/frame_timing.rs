//! A video's frame times, from its packets' timestamps: a constant rate, or a variable one
//! (phones record so: frames come later in dim light, and a .mov's declared rate is often its
//! 1/600 s timescale), which is then resampled to a constant rate by the decoder.
//!
//! Every later step counts time in frames at one rate (filters, events, cycles), so a
//! video whose frames are not evenly spaced is given evenly spaced frames: each frame is
//! placed at its nearest slot of the constant rate, a slot left empty repeats the frame
//! before it, and two frames in one slot keep the later one (ffmpeg's `fps` filter).

use serde::Serialize;

/// Frame times further than this from a constant rate's (in frames) make a variable rate:
/// a quarter frame is more than timestamps rounded to a container's timescale move them
/// (1/600 s at 60 fps is a tenth of a frame), and a dropped frame moves them by a half.
const MAX_CONSTANT_DEVIATION: f64 = 0.25;

/// A declared rate within this fraction of the measured one is kept as it is (30, not
/// 29.9998 from rounded timestamps).
const DECLARED_TOLERANCE: f64 = 0.01;

/// Rates cameras record at: a variable-rate video is resampled to the one nearest its
/// typical frame interval, when one is within [`NOMINAL_TOLERANCE`].
const NOMINAL_RATES: [f64; 13] = [
    24000.0 / 1001.0,
    24.0,
    25.0,
    30000.0 / 1001.0,
    30.0,
    48.0,
    50.0,
    60000.0 / 1001.0,
    60.0,
    90.0,
    100.0,
    120.0,
    240.0,
];
const NOMINAL_TOLERANCE: f64 = 0.015;

/// How a video's frames are spaced in time, as measured from its timestamps.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameTiming {
    /// The rate the container declares (ffprobe's `r_frame_rate`).
    pub declared_fps: f64,
    /// Frames per second over the whole video: (frames - 1) / (last time - first time).
    pub measured_fps: f64,
    /// The largest distance of a frame's time from where a constant rate puts it, in frames.
    pub largest_deviation_frames: f64,
    /// Frame intervals, shortest and longest, in milliseconds.
    pub interval_ms: [f64; 2],
    /// The constant rate the frames were resampled to, when their rate varies.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub resampled_fps: Option<f64>,
}

impl FrameTiming {
    /// The timing of frames presented at `times` (seconds, any order), or `None` when there
    /// are too few to tell.
    pub fn measure(declared_fps: f64, times: &[f64]) -> Option<Self> {
        let mut t: Vec<f64> = times.iter().copied().filter(|t| t.is_finite()).collect();
        t.sort_by(f64::total_cmp);
        t.dedup();
        let (first, last) = (*t.first()?, *t.last()?);
        if t.len() < 3 || last <= first {
            return None;
        }
        let measured_fps = (t.len() - 1) as f64 / (last - first);
        if !plausible(measured_fps) {
            return None;
        }
        let largest_deviation_frames = t
            .iter()
            .enumerate()
            .map(|(i, &ti)| ((ti - first) * measured_fps - i as f64).abs())
            .fold(0.0, f64::max);
        let intervals: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        let interval_ms = [
            1e3 * intervals.iter().copied().fold(f64::INFINITY, f64::min),
            1e3 * intervals.iter().copied().fold(0.0, f64::max),
        ];
        let resampled_fps = (largest_deviation_frames > MAX_CONSTANT_DEVIATION)
            .then(|| nominal_rate(1.0 / typical_interval(intervals)));
        if resampled_fps.is_some_and(|r| !plausible(r)) {
            return None;
        }
        Some(Self {
            declared_fps,
            measured_fps,
            largest_deviation_frames,
            interval_ms,
            resampled_fps,
        })
    }

    /// The rate the analysis counts frames at.
    pub fn fps(&self) -> f64 {
        if let Some(r) = self.resampled_fps {
            return r;
        }
        if (self.declared_fps / self.measured_fps - 1.0).abs() <= DECLARED_TOLERANCE {
            self.declared_fps
        } else {
            self.measured_fps
        }
    }

    /// How many frames the decoder gives (resampled: ffmpeg may end a frame short).
    pub fn frames(&self, times: usize) -> usize {
        match self.resampled_fps {
            // One slot per 1/rate from the first frame's to the last frame's time.
            Some(r) => {
                ((times.saturating_sub(1)) as f64 * r / self.measured_fps).round() as usize + 1
            }
            None => times,
        }
    }

    /// What the user should know, when anything: the frame rate varies or was not the
    /// declared one.
    pub fn warning(&self) -> Option<String> {
        let [short, long] = self.interval_ms;
        match self.resampled_fps {
            Some(r) => Some(format!(
                "the video's frame rate varies (frames {short:.0}-{long:.0} ms apart, up to {:.1} frames off a constant rate): its frames were resampled to a constant {r:.2} fps (a frame repeated where one is missing); film at a fixed frame rate if the camera allows",
                self.largest_deviation_frames
            )),
            None if self.fps() != self.declared_fps => Some(format!(
                "the video declares {:.2} fps but its frames are {:.2} fps apart: analysed at {:.2} fps",
                self.declared_fps,
                self.measured_fps,
                self.fps()
            )),
            None => None,
        }
    }
}

/// A camera's rate: finite, above one frame a minute and below 10^5 frames per second (as
/// input.rs requires of a declared rate), so hostile timestamps cannot give the decoder a rate
/// of zero or infinity.
fn plausible(fps: f64) -> bool {
    fps.is_finite() && (1.0 / 60.0..=1e5).contains(&fps)
}

/// The camera's interval between consecutive frames: each interval counted as the whole
/// number of median intervals nearest its length (a gap where a frame is missing counts two),
/// and the time divided by that count. The median is one frame's interval as long as fewer
/// than half the frames are missing.
fn typical_interval(v: Vec<f64>) -> f64 {
    let mut sorted = v.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let slots: f64 = v.iter().map(|d| (d / median).round().max(1.0)).sum();
    v.iter().sum::<f64>() / slots
}

/// The camera rate nearest `fps`, when one is near enough; else `fps` itself.
fn nominal_rate(fps: f64) -> f64 {
    NOMINAL_RATES
        .iter()
        .copied()
        .min_by(|a, b| (a / fps - 1.0).abs().total_cmp(&(b / fps - 1.0).abs()))
        .filter(|r| (r / fps - 1.0).abs() <= NOMINAL_TOLERANCE)
        .unwrap_or(fps)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn times(n: usize, f: impl Fn(usize) -> f64) -> Vec<f64> {
        (0..n).map(f).collect()
    }

    #[test]
    fn a_constant_rate_keeps_its_declared_rate_and_frames() {
        let t = times(230, |i| i as f64 / 30.0);
        let timing = FrameTiming::measure(30.0, &t).unwrap();
        assert_eq!((timing.fps(), timing.resampled_fps), (30.0, None));
        assert_eq!((timing.frames(230), timing.warning()), (230, None));
    }

    #[test]
    fn timestamps_rounded_to_a_timescale_are_a_constant_rate() {
        // 29.97 fps in a 1/600 s timescale: intervals of 20 and 21 ticks.
        let t = times(300, |i| {
            (i as f64 * 1001.0 / 30000.0 * 600.0).round() / 600.0
        });
        let timing = FrameTiming::measure(30000.0 / 1001.0, &t).unwrap();
        assert_eq!(timing.fps(), 30000.0 / 1001.0);
        assert!(timing.resampled_fps.is_none());
    }

    #[test]
    fn a_timescale_declared_as_the_rate_is_replaced_by_the_measured_one() {
        // A phone's .mov declaring 600 fps, its frames 33 ms apart give or take 7 ms.
        let t = times(230, |i| {
            (i as f64 * 20.0 + (4.0 * (i as f64 * 1.7).sin()).round()) / 600.0
        });
        let timing = FrameTiming::measure(600.0, &t).unwrap();
        assert!(timing.resampled_fps.is_none());
        assert!((timing.fps() - 30.0).abs() < 0.05, "{}", timing.fps());
        assert!(timing.warning().unwrap().contains("declares 600.00 fps"));
    }

    #[test]
    fn missing_frames_make_a_variable_rate_resampled_to_the_camera_rate() {
        // 30 fps with frames 100-139 at 15 fps (every other one missing), as in dim light.
        let t: Vec<f64> = (0..300)
            .filter(|i| !(100..140).contains(i) || i % 2 == 0)
            .map(|i| i as f64 / 30.0)
            .collect();
        let timing = FrameTiming::measure(30.0, &t).unwrap();
        assert_eq!(timing.resampled_fps, Some(30.0));
        assert_eq!(timing.fps(), 30.0);
        assert_eq!(timing.frames(t.len()), 300);
        assert!(
            timing
                .warning()
                .unwrap()
                .contains("resampled to a constant 30.00 fps")
        );
    }

    #[test]
    fn jittered_times_with_missing_frames_are_resampled_to_the_camera_rate() {
        // A 1/600 s timescale, frames 33 ms apart give or take 7 ms, every other frame of
        // 100-139 missing: the gaps must not pull the rate down to 28.6 fps.
        let t: Vec<f64> = (0..230)
            .filter(|i| !(100..140).contains(i) || i % 2 == 0)
            .map(|i| (i as f64 * 20.0 + (4.0 * (i as f64 * 1.7).sin()).round()) / 600.0)
            .collect();
        let timing = FrameTiming::measure(600.0, &t).unwrap();
        assert_eq!(timing.resampled_fps, Some(30.0));
    }

    #[test]
    fn too_few_or_equal_times_tell_nothing() {
        assert!(FrameTiming::measure(30.0, &[0.0, 0.1]).is_none());
        assert!(FrameTiming::measure(30.0, &[0.5, 0.5, 0.5]).is_none());
        assert!(FrameTiming::measure(30.0, &[f64::NAN, 1.0]).is_none());
        assert!(FrameTiming::measure(30.0, &[0.0, 1.0, 1e300]).is_none());
        assert!(FrameTiming::measure(30.0, &[0.0, 1e-9, 2e-9]).is_none());
    }
}
