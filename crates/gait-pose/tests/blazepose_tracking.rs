//! BlazePose tracking (video mode) against mediapipe 0.10.14's own video mode
//! on 30 consecutive frames of the sample (tools/blazepose/make_tracking_fixtures.py):
//! with `roi_filter = "mediapipe"` each frame's crop for the next frame and
//! the landmarks match mediapipe's. Needs the real model files: run
//! `gait models fetch blazepose` and set GAIT_MODELS_DIR to the models folder.

use std::path::PathBuf;

use gait_core::{Frame, Pose, PoseEstimator, StageContext};
use gait_pose::PersonRule;
use gait_pose::blazepose::{AuxFilter, Blazepose, BlazeposeConfig, PersonChoice, RoiFilter};

fn models_dir() -> PathBuf {
    let dir = std::env::var_os("GAIT_MODELS_DIR").expect(
        "GAIT_MODELS_DIR is not set: run `gait models fetch blazepose` and point GAIT_MODELS_DIR at the models folder",
    );
    PathBuf::from(dir)
}

fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/blazepose")
}

/// Lower-limb landmarks: hips, knees, ankles, heels, toes.
const LOWER: std::ops::RangeInclusive<usize> = 23..=32;

struct Reference {
    frames: Vec<Frame>,
    /// mediapipe's 33 landmarks per frame ([x, y, z, visibility], normalised).
    landmarks: Vec<Vec<[f64; 4]>>,
    /// mediapipe's crop for the next frame (pose_rect_from_landmarks).
    rects: Vec<[f64; 5]>,
    /// Whether mediapipe detected in the frame (else it tracked).
    detected: Vec<bool>,
    /// Landmarks 33 and 34 before and after mediapipe's filter.
    aux_unfiltered: Vec<[(f32, f32); 2]>,
    aux_filtered: Vec<[(f32, f32); 2]>,
}

fn reference() -> Reference {
    let text = std::fs::read_to_string(fixtures().join("mediapipe_tracking.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut r = Reference {
        frames: Vec::new(),
        landmarks: Vec::new(),
        rects: Vec::new(),
        detected: Vec::new(),
        aux_unfiltered: Vec::new(),
        aux_filtered: Vec::new(),
    };
    let nums = |v: &serde_json::Value| -> Vec<f64> {
        v.as_array()
            .unwrap_or_else(|| panic!("not an array: {v}"))
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    for (i, f) in json["frames"].as_array().unwrap().iter().enumerate() {
        let name = f["image"].as_str().unwrap();
        let img = image::open(fixtures().join(name)).unwrap().to_rgb8();
        r.frames.push(Frame::new(i, img));
        // Every fixture frame has mediapipe's person (the script prints it).
        let lms = f["landmarks"].as_array().unwrap();
        r.landmarks
            .push(lms.iter().map(|l| nums(l).try_into().unwrap()).collect());
        r.rects
            .push(nums(&f["rect_from_landmarks"]).try_into().unwrap());
        r.detected.push(!f["rect_from_detection"].is_null());
        let aux = |key: &str| -> [(f32, f32); 2] {
            let p: Vec<Vec<f64>> = f[key].as_array().unwrap().iter().map(nums).collect();
            [
                (p[0][0] as f32, p[0][1] as f32),
                (p[1][0] as f32, p[1][1] as f32),
            ]
        };
        r.aux_unfiltered.push(aux("aux_unfiltered"));
        r.aux_filtered.push(aux("aux_filtered"));
    }
    assert_eq!(r.frames.len(), 30);
    r
}

fn estimator(roi_filter: RoiFilter) -> Blazepose {
    let config = BlazeposeConfig {
        person: PersonChoice::Rule(PersonRule::MostConfident),
        tracking: true,
        roi_filter,
        ..Default::default()
    };
    Blazepose::new(&config, &StageContext::new(models_dir())).unwrap()
}

/// The tracked crop for the next frame, [x_centre, y_centre, width, height,
/// rotation], read from the estimator's state (its first 6 f32s: a flag, then
/// the crop).
fn tracked_roi(est: &Blazepose) -> Option<[f32; 5]> {
    let s = est.state().unwrap();
    let v: Vec<f32> = s
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    (v[0] == 1.0).then(|| [v[1], v[2], v[3], v[4], v[5]])
}

struct FrameError {
    /// Largest distance in px between our next-frame crop's centre and
    /// mediapipe's, and between their sides.
    roi_centre: f64,
    roi_side: f64,
    /// Lower-limb landmark errors (px), sorted.
    lower: Vec<f64>,
    /// Largest visibility difference.
    visibility: f64,
}

/// Runs the frames in order with tracking; per frame, the differences from mediapipe.
fn run(roi_filter: RoiFilter, r: &Reference) -> Vec<FrameError> {
    let mut est = estimator(roi_filter);
    let first_native = est
        .keypoint_names()
        .iter()
        .position(|n| n == "bp_nose")
        .unwrap();
    let mut out = Vec::new();
    for (i, frame) in r.frames.iter().enumerate() {
        let (w, h) = (frame.width() as f64, frame.height() as f64);
        let pose = est.estimate(std::slice::from_ref(frame)).unwrap().remove(0);
        let roi = tracked_roi(&est).unwrap_or_else(|| panic!("frame {i}: lost the person"));
        let m = r.rects[i];
        let roi_centre = (roi[0] as f64 * w - m[0] * w).hypot(roi[1] as f64 * h - m[1] * h);
        let roi_side = (roi[2] as f64 * w - m[2] * w).abs();
        let mut lower = Vec::new();
        let mut visibility = 0f64;
        for (k, lm) in r.landmarks[i].iter().enumerate() {
            let kp = pose.keypoints[first_native + k];
            let err = (kp.x - (lm[0] * w - 0.5)).hypot(kp.y - (lm[1] * h - 0.5));
            visibility = visibility.max((kp.likelihood - lm[3]).abs());
            if LOWER.contains(&k) {
                lower.push(err);
            }
        }
        lower.sort_by(f64::total_cmp);
        if std::env::var_os("GAIT_TEST_VERBOSE").is_some() {
            eprintln!(
                "{roi_filter:?} frame {i}: crop centre {roi_centre:.4} px, side {roi_side:.4} px, \
                 lower-limb max {:.3} px, visibility {visibility:.4}",
                lower[lower.len() - 1]
            );
        }
        out.push(FrameError {
            roi_centre,
            roi_side,
            lower,
            visibility,
        });
    }
    out
}

/// Over all frames: lower-limb median and 90th percentile (px), the largest
/// crop centre and side differences (px) and visibility difference.
struct Summary {
    median: f64,
    p90: f64,
    roi_centre: f64,
    roi_side: f64,
    visibility: f64,
}

fn summary(errors: &[FrameError]) -> Summary {
    let mut all: Vec<f64> = errors.iter().flat_map(|e| e.lower.clone()).collect();
    all.sort_by(f64::total_cmp);
    let max = |f: fn(&FrameError) -> f64| errors.iter().map(f).fold(0.0, f64::max);
    Summary {
        median: all[all.len() / 2],
        p90: all[all.len() * 9 / 10],
        roi_centre: max(|e| e.roi_centre),
        roi_side: max(|e| e.roi_side),
        visibility: max(|e| e.visibility),
    }
}

/// With mediapipe's filter on landmarks 33/34 the crops follow mediapipe's
/// and so do the landmarks; without it the crops drift away by pixels. What
/// is left with the filter is the networks' float noise (0.02 px on one crop,
/// see blazepose_mediapipe.rs), which the loop from one frame's landmarks to
/// the next frame's crop carries on and sometimes amplifies (a landmark
/// crossing the heatmap refinement threshold), so the bounds are on the whole
/// run, not on every frame.
#[test]
fn tracking_with_mediapipes_roi_filter_matches_mediapipe() {
    let r = reference();
    let filtered = summary(&run(RoiFilter::Mediapipe, &r));
    let unfiltered = summary(&run(RoiFilter::None, &r));
    for (name, s) in [("mediapipe", &filtered), ("none", &unfiltered)] {
        eprintln!(
            "roi_filter = {name}: lower-limb median {:.3} px, 90th percentile {:.3} px; \
             next-frame crop: centre max {:.3} px, side max {:.3} px; visibility max {:.4}",
            s.median, s.p90, s.roi_centre, s.roi_side, s.visibility
        );
    }
    assert!(
        filtered.median <= 0.15
            && filtered.p90 <= 0.6
            && filtered.roi_centre <= 0.5
            && filtered.roi_side <= 1.0
            && filtered.visibility <= 0.05,
        "tracking with roi_filter = \"mediapipe\" is off mediapipe's (see above)"
    );
    // The filter is what makes the difference.
    assert!(
        unfiltered.median > 0.5 && unfiltered.roi_centre > 2.0,
        "without the filter the crops should drift from mediapipe's"
    );
}

/// The filter alone, on mediapipe's own landmarks 33/34 as its landmark
/// model gave them: exactly (to the bit) mediapipe's filtered landmarks.
#[test]
fn roi_filter_is_mediapipes_to_the_bit() {
    let r = reference();
    let mut filter = AuxFilter::default();
    for (i, frame) in r.frames.iter().enumerate() {
        if r.detected[i] {
            filter.reset();
        }
        let [p0, p1] = r.aux_unfiltered[i];
        let got = filter.apply(p0, p1, frame.width(), frame.height());
        assert_eq!(got, r.aux_filtered[i], "frame {i}");
    }
    // Not a pass-through: the filter moves the points.
    assert_ne!(r.aux_unfiltered[5], r.aux_filtered[5]);
}

/// A run stopped anywhere and resumed from the saved state (filter
/// included) gives exactly what the uninterrupted run gives.
#[test]
fn resumed_tracking_equals_uninterrupted() {
    let r = reference();
    let frames = &r.frames[..12];
    let mut whole = estimator(RoiFilter::Mediapipe);
    let expected: Vec<Pose> = frames
        .iter()
        .map(|f| whole.estimate(std::slice::from_ref(f)).unwrap().remove(0))
        .collect();
    let mut first = estimator(RoiFilter::Mediapipe);
    let mut got: Vec<Pose> = Vec::new();
    for f in &frames[..6] {
        got.push(first.estimate(std::slice::from_ref(f)).unwrap().remove(0));
    }
    let saved = first.state().unwrap();
    let mut second = estimator(RoiFilter::Mediapipe);
    assert!(second.restore(&saved));
    assert_eq!(second.state().unwrap(), saved);
    got.extend(second.estimate(&frames[6..]).unwrap());
    assert_eq!(got, expected);
    // reset() forgets the filter too: the next frame is a fresh start.
    second.reset();
    let mut fresh = estimator(RoiFilter::Mediapipe);
    assert_eq!(
        second.estimate(&frames[..1]).unwrap(),
        fresh.estimate(&frames[..1]).unwrap()
    );
    assert_eq!(second.state(), fresh.state());
}
