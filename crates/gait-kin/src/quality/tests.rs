//! Each rejection reason on a synthetic walker.

use super::*;
use crate::direction::Direction;
use crate::testing::walker;

/// A 30 fps walker at 400 px/s over 6 s, seen as one bout, and the data to judge it.
struct Case {
    t: Tracks,
    gated: Tracks,
    lik: Vec<Vec<f64>>,
    swapped: Vec<bool>,
    unsure: Vec<bool>,
    bouts: Vec<Bout>,
    excluded: Vec<FrameRange>,
}

impl Case {
    fn new() -> Self {
        let t = walker(30.0, 180, |i| 100.0 + 400.0 * i as f64 / 30.0);
        let n = t.len();
        Case {
            gated: t.clone(),
            lik: vec![vec![0.9; n]; t.names.len()],
            swapped: vec![false; n],
            unsure: vec![false; n],
            bouts: vec![bout(0, 179)],
            excluded: Vec::new(),
            t,
        }
    }

    fn judge(&self, strides: &[Stride], kin: &KinematicsConfig) -> Vec<CycleQuality> {
        let ev = Evidence {
            clean: &self.t,
            gated: &self.gated,
            raw_likelihood: &self.lik,
            swapped: &self.swapped,
            unsure: &self.unsure,
            bouts: &self.bouts,
            enforce_bouts: true,
            excluded: &self.excluded,
            size: None,
        };
        assess(&ev, strides, kin)
    }

    fn reasons(&self, strides: &[Stride]) -> Vec<Vec<Reason>> {
        let q = self.judge(strides, &KinematicsConfig::default());
        q.into_iter().map(|c| c.reasons).collect()
    }
}

fn bout(first: usize, last: usize) -> Bout {
    Bout {
        first,
        last,
        direction: Direction::Right,
        mean_speed: 1.3,
    }
}

/// Four left strides of 34 frames (1.13 s, the walker's) from frame 10.
fn strides() -> Vec<Stride> {
    (0..4)
        .map(|k| Stride::on_frames(Side::Left, 10 + 34 * k, 44 + 34 * k))
        .collect()
}

fn only(k: usize, r: Vec<Reason>) -> Vec<Vec<Reason>> {
    (0..4)
        .map(|i| if i == k { r.clone() } else { vec![] })
        .collect()
}

#[test]
fn clean_strides_are_accepted_with_their_numbers() {
    let c = Case::new();
    let q = c.judge(&strides(), &KinematicsConfig::default());
    assert!(q.iter().all(|q| q.accepted && q.bout == Some(0)), "{q:?}");
    let q0 = &q[0];
    assert!((q0.stride_s - 34.0 / 30.0).abs() < 1e-12 && q0.stride_deviation == 0.0);
    assert!((q0.mean_likelihood - 0.9).abs() < 1e-12 && q0.max_filled_s == 0.0);
    assert!((q0.thigh_ratio - 1.0).abs() < 0.1 && (q0.shank_ratio - 1.0).abs() < 0.1);
    assert_eq!(counts(&q).0, SideCounts { left: 4, right: 0 });
    assert!(warn::per_reason(&q, &KinematicsConfig::default()).is_empty());
}

#[test]
fn an_odd_stride_time_is_rejected() {
    let c = Case::new();
    let mut s = strides();
    s[3].end += 12; // 46 frames against a median of 34: 35 % longer
    assert_eq!(c.reasons(&s), only(3, vec![Reason::StrideTime]));
}

#[test]
fn a_long_filled_gap_is_rejected_a_short_one_kept() {
    let mut c = Case::new();
    let k = c.gated.index("left_knee").unwrap();
    c.gated.x[k][20..23].fill(f64::NAN); // 3 frames = 0.1 s: at the limit
    c.gated.x[k][50..55].fill(f64::NAN); // 5 frames = 0.17 s
    assert_eq!(c.reasons(&strides()), only(1, vec![Reason::FilledGap]));
    // The other leg's gaps are no reason for this leg's stride.
    let mut c = Case::new();
    let k = c.gated.index("right_knee").unwrap();
    c.gated.x[k][50..60].fill(f64::NAN);
    assert_eq!(c.reasons(&strides()), only(4, vec![]));
}

#[test]
fn low_likelihood_is_rejected() {
    let mut c = Case::new();
    for p in LEG {
        let j = c.t.leg_index(Side::Left, p).unwrap();
        c.lik[j][80..110].fill(0.2);
    }
    assert_eq!(c.reasons(&strides()), only(2, vec![Reason::LowLikelihood]));
}

#[test]
fn a_segment_out_of_line_is_rejected() {
    let mut c = Case::new();
    let (h, k) = (
        c.t.index("left_hip").unwrap(),
        c.t.index("left_knee").unwrap(),
    );
    for i in 44..78 {
        // Thigh 40 % longer over the second stride.
        c.t.y[k][i] = c.t.y[h][i] + 1.4 * (c.t.y[k][i] - c.t.y[h][i]);
    }
    let q = c.judge(&strides(), &KinematicsConfig::default());
    assert_eq!(q[1].reasons, vec![Reason::SegmentLength], "{:?}", q[1]);
    assert!(q[1].thigh_ratio > 1.3, "{}", q[1].thigh_ratio);
    assert!(q.iter().filter(|q| q.accepted).count() == 3);
}

#[test]
fn labels_in_doubt_reject_unless_allowed() {
    let mut c = Case::new();
    c.unsure[100] = true;
    // One frame in doubt is within the default share; with none allowed it rejects.
    let strict = KinematicsConfig {
        cycle_max_swapped_share: 0.0,
        ..Default::default()
    };
    let q = c.judge(&strides(), &strict);
    assert_eq!(q[2].reasons, vec![Reason::Swap]);
    for k in 95..=105 {
        c.unsure[k] = true;
    }
    assert_eq!(c.reasons(&strides()), only(2, vec![Reason::Swap]));
    let kin = KinematicsConfig {
        cycle_max_swapped_share: 1.0,
        ..Default::default()
    };
    let q = c.judge(&strides(), &kin);
    assert!(q.iter().all(|q| q.accepted) && q[2].unsure_frames == 11);
}

/// Labels exchanged and surely corrected are no reason: they are counted, not judged.
#[test]
fn corrected_labels_without_doubt_are_accepted() {
    let mut c = Case::new();
    for k in 95..=105 {
        c.swapped[k] = true;
    }
    let q = c.judge(&strides(), &KinematicsConfig::default());
    assert!(q.iter().all(|q| q.accepted) && q[2].swapped_frames == 11);
    assert_eq!(q[2].unsure_frames, 0);
}

#[test]
fn a_stride_across_two_bouts_is_rejected() {
    let mut c = Case::new();
    c.bouts = vec![bout(0, 60), bout(62, 179)];
    let q = c.judge(&strides(), &KinematicsConfig::default());
    assert_eq!(q[1].reasons, vec![Reason::CrossesBout]);
    assert_eq!(
        q.iter().map(|q| q.bout).collect::<Vec<_>>(),
        vec![Some(0), None, Some(1), Some(1)]
    );
    let w = warn::per_reason(&q, &KinematicsConfig::default());
    assert_eq!(w.len(), 1);
    assert!(
        w[0].starts_with("1 of 4 strides rejected (crosses_bout)"),
        "{w:?}"
    );
    // A step inside the rejected stride does not count; one in an accepted stride does,
    // none across the bouts, and one outside every stride does when inside a bout.
    assert!(!step_ok(&q, &c.bouts, true, 50, 55));
    assert!(step_ok(&q, &c.bouts, true, 90, 100));
    assert!(!step_ok(&q, &c.bouts, true, 59, 63));
    assert!(step_ok(&q, &c.bouts, true, 160, 175));
    assert!(!step_ok(&q, &c.bouts, true, 170, 185));
}

/// A walk there and back: the first bout to the image right (the right leg near the camera),
/// the second to the left. The left leg's strides of the first bout are far from the camera
/// and the same leg has strides near it in the second: those far ones are rejected, named; the
/// right leg keeps only its first-bout strides the same way. One bout alone keeps everything.
#[test]
fn far_leg_strides_give_way_to_the_same_leg_near_the_camera() {
    let mut c = Case::new();
    let back = Bout {
        direction: Direction::Left,
        ..bout(90, 179)
    };
    c.bouts = vec![bout(0, 89), back];
    let strides: Vec<Stride> = [
        (Side::Left, 10),
        (Side::Right, 27),
        (Side::Left, 100),
        (Side::Right, 117),
    ]
    .into_iter()
    .map(|(side, start)| Stride::on_frames(side, start, start + 34))
    .collect();
    let q = c.judge(&strides, &KinematicsConfig::default());
    let got: Vec<(Side, bool, Vec<Reason>)> = q
        .iter()
        .map(|q| (q.side, q.accepted, q.reasons.clone()))
        .collect();
    assert_eq!(
        got,
        vec![
            (Side::Left, false, vec![Reason::FarSide]),
            (Side::Right, true, vec![]),
            (Side::Left, true, vec![]),
            (Side::Right, false, vec![Reason::FarSide]),
        ]
    );
    c.bouts = vec![bout(0, 179)];
    let q = c.judge(&strides, &KinematicsConfig::default());
    assert!(q.iter().all(|q| q.accepted), "one walk keeps every stride");
}

#[test]
fn strides_over_excluded_frames_are_rejected() {
    let mut c = Case::new();
    let stride = |start: usize, end: usize| Stride::on_frames(Side::Left, start, end);
    // Two strides of 46 frames between two of 34: over all four the median would be 40.
    let s = [
        stride(10, 44),
        stride(44, 90),
        stride(90, 136),
        stride(136, 170),
    ];
    // 50-52 lies in the second stride only; 136 is the heel strike ending the third and
    // starting the fourth.
    c.excluded = vec![
        FrameRange {
            first: 50,
            last: 52,
        },
        FrameRange {
            first: 136,
            last: 136,
        },
    ];
    let q = c.judge(&s, &KinematicsConfig::default());
    let reasons: Vec<Vec<Reason>> = q.iter().map(|q| q.reasons.clone()).collect();
    assert_eq!(
        reasons,
        vec![
            vec![],
            vec![Reason::StrideTime, Reason::Excluded],
            vec![Reason::StrideTime, Reason::Excluded],
            vec![Reason::Excluded]
        ]
    );
    // Excluded strides leave the median stride time alone.
    assert_eq!(q[0].stride_deviation, 0.0, "{:?}", q[0]);
    let w = warn::per_reason(&q, &KinematicsConfig::default());
    assert!(
        w.contains(&"3 of 4 strides rejected (excluded): over frames excluded in the corrections (see cycle_quality.csv)".to_string()),
        "{w:?}"
    );
    c.excluded.clear();
    let q = c.judge(&s, &KinematicsConfig::default());
    assert!(
        (q[0].stride_deviation - 6.0 / 40.0).abs() < 1e-12,
        "{:?}",
        q[0]
    );
}

/// The synthetic walker's legs are about 300 px: under a 400 px minimum every stride is
/// rejected as too small, the warning names the measured length and the frames, and 0 turns
/// the check off.
#[test]
fn a_walker_too_small_in_the_image_is_rejected_and_named() {
    let c = Case::new();
    let small = KinematicsConfig {
        cycle_min_leg_px: 400.0,
        ..KinematicsConfig::default()
    };
    let q = c.judge(&strides(), &small);
    assert!(
        q.iter().all(|q| q.reasons == vec![Reason::SmallSubject]),
        "{q:?}"
    );
    assert!(
        q.iter().all(|q| (250.0..350.0).contains(&q.leg_px)),
        "{q:?}"
    );
    let mut warnings = Vec::new();
    warn::small_subject(&c.t, &small, &mut warnings);
    assert_eq!(warnings.len(), 1);
    assert!(
        warnings[0].contains("px long") && warnings[0].contains("frames 0-179"),
        "{warnings:?}"
    );
    let off = KinematicsConfig {
        cycle_min_leg_px: 0.0,
        ..KinematicsConfig::default()
    };
    assert!(c.judge(&strides(), &off).iter().all(|q| q.accepted));
    warnings.clear();
    warn::small_subject(&c.t, &KinematicsConfig::default(), &mut warnings);
    assert!(warnings.is_empty());
}

/// Legs of about 300 px: a stride whose frames read a blur over 1.5 % of that (4.5 px) is
/// rejected as blurred, judged by the median of its frames (one soft frame does not reject),
/// the warning names the blur, the leg and the frames, and without measures nothing changes.
#[test]
fn a_blurred_walker_is_rejected_by_the_median_blur_of_each_stride() {
    let c = Case::new();
    let s = strides();
    // Sharp everywhere but in the second stride, and one very soft frame in the first.
    let mut blur: std::collections::BTreeMap<usize, f64> =
        (0..180).step_by(5).map(|f| (f, 1.6)).collect();
    for (_, b) in blur.range_mut(s[1].start..=s[1].end) {
        *b = 6.0;
    }
    blur.insert(s[0].start + 5, 9.0);
    let kin = KinematicsConfig {
        image_blur_px: Some(blur),
        ..KinematicsConfig::default()
    };
    let q = c.judge(&s, &kin);
    let blurred: Vec<bool> = q
        .iter()
        .map(|q| q.reasons.contains(&Reason::Blurred))
        .collect();
    assert_eq!(blurred, vec![false, true, false, false], "{q:?}");
    assert!(
        (q[1].blur_px - 6.0).abs() < 1e-9 && (q[0].blur_px - 1.6).abs() < 1e-9,
        "{q:?}"
    );
    let mut warnings = Vec::new();
    warn::blurred(&q, &kin, &mut warnings);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    let range = format!("frames {}-{}", s[1].start, s[1].end);
    assert!(
        warnings[0].contains("edges spread over 6.0 px") && warnings[0].contains(&range),
        "{warnings:?}"
    );
    let unmeasured = c.judge(&s, &KinematicsConfig::default());
    assert!(
        unmeasured
            .iter()
            .all(|q| q.blur_px.is_nan() && !q.reasons.contains(&Reason::Blurred))
    );
}

/// The feet's outline as sharp swinging as standing, but the second stride's foot smeared to
/// 40 % of its standing contrast: that stride alone is rejected as motion blurred, with a
/// warning naming the share and frames; without measures, or in a front view, nothing changes.
#[test]
fn a_foot_smeared_in_swing_rejects_its_stride() {
    let c = Case::new();
    let s = strides();
    let column = usize::from(s[1].side == Side::Right);
    let mut feet: crate::config::FeetContrast = (0..180).map(|f| (f, [Some(25.0); 2])).collect();
    for (_, pair) in feet.range_mut(s[1].start..=s[1].end) {
        pair[column] = Some(10.0);
    }
    let kin = KinematicsConfig {
        image_feet_contrast: Some(feet),
        ..KinematicsConfig::default()
    };
    let q = c.judge(&s, &kin);
    let smeared: Vec<bool> = q
        .iter()
        .map(|q| q.reasons.contains(&Reason::MotionBlurred))
        .collect();
    assert_eq!(smeared, vec![false, true, false, false], "{q:?}");
    assert!((q[1].swing_contrast - 0.4).abs() < 1e-9, "{q:?}");
    assert!(
        [0, 2, 3]
            .iter()
            .all(|&k| (q[k].swing_contrast - 1.0).abs() < 1e-9),
        "{q:?}"
    );
    let mut warnings = Vec::new();
    warn::motion_blurred(&q, &kin, &mut warnings);
    let range = format!("frames {}-{}", s[1].start, s[1].end);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].contains("keeps 40 % of its contrast standing") && warnings[0].contains(&range),
        "{warnings:?}"
    );
    let unmeasured = c.judge(&s, &KinematicsConfig::default());
    assert!(
        unmeasured
            .iter()
            .all(|q| q.swing_contrast.is_nan() && q.accepted)
    );
    // Outlines too faint to compare (a walker out of focus): no figure, no rejection.
    let faint = KinematicsConfig {
        image_feet_contrast: kin.image_feet_contrast.clone().map(|f| {
            f.into_iter()
                .map(|(k, p)| (k, p.map(|c| c.map(|c| c / 10.0))))
                .collect()
        }),
        ..KinematicsConfig::default()
    };
    assert!(
        c.judge(&s, &faint)
            .iter()
            .all(|q| q.swing_contrast.is_nan() && q.accepted)
    );
}
