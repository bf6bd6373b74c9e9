//! OpenPose decoding against its references: cv2.resize, scipy's
//! gaussian_filter and controlnet_aux's `Body.__call__` (fixtures from
//! `tools/openpose/make_decode_fixtures.py`).

use std::path::PathBuf;

use gait_core::{Frame, StageError};
use gait_pose::openpose::decode::{
    Geometry, Interp, SearchParams, detect, gaussian_filter, resize_f32, resize_u8,
};
use gait_pose::openpose::{NetInput, NetOutput, OpenposeModel};
use serde_json::Value;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/openpose/decode")
        .join(name)
}

fn json(name: &str) -> Value {
    let text = std::fs::read_to_string(fixture(name))
        .expect("fixture missing; run tools/openpose/make_decode_fixtures.py");
    serde_json::from_str(&text).expect("fixture is not JSON")
}

fn unhex(s: &str) -> Vec<u8> {
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&s[i..i + 2], 16).expect("hex"))
        .collect()
}

fn f32s(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

fn usizes(v: &Value) -> Vec<usize> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_u64().expect("uint") as usize)
        .collect()
}

#[test]
fn resize_matches_cv2() {
    let cases = json("resize.json");
    let mut max_f32 = 0f32;
    let mut checked = 0;
    let mut ipp_off = (0, 0);
    for case in cases["cases"].as_array().expect("cases") {
        let name = case["name"].as_str().expect("name");
        let interp = match case["interp"].as_str().expect("interp") {
            "cubic" => Interp::Cubic,
            "lanczos4" => Interp::Lanczos4,
            "area" => Interp::Area,
            other => panic!("unknown interpolation {other}"),
        };
        let shape = usizes(&case["src_shape"]);
        let (sh, sw, cn) = (shape[0], shape[1], shape.get(2).copied().unwrap_or(1));
        let g = match case["factor"].as_f64() {
            Some(f) => Geometry::by_factor(sw, sh, f),
            None => {
                let d = usizes(&case["dsize"]);
                Geometry::to_size(sw, sh, d[0], d[1])
            }
        };
        let dshape = usizes(&case["dst_shape"]);
        assert_eq!(
            (g.dh, g.dw),
            (dshape[0], dshape[1]),
            "{name}/{interp:?}: output size"
        );
        let src = unhex(case["src"].as_str().expect("src"));
        let dst = unhex(case["dst"].as_str().expect("dst"));
        let default = case["dst_default"].as_str().map(unhex);
        if case["dtype"] == "uint8" {
            let ours = resize_u8(&src, cn, g, interp);
            assert_eq!(ours.len(), dst.len());
            let diffs = ours.iter().zip(&dst).filter(|(a, b)| a != b).count();
            assert_eq!(
                diffs,
                0,
                "{name}/{interp:?}: {diffs} of {} uint8 values differ from cv2",
                dst.len()
            );
            if let Some(default) = default {
                // Intel IPP's cubic (opencv-python's default) rounds differently: by at most 1.
                let off = ours.iter().zip(&default).filter(|(a, b)| a != b).count();
                let worst = ours
                    .iter()
                    .zip(&default)
                    .map(|(a, b)| (*a as i32 - *b as i32).abs())
                    .max();
                assert!(
                    worst <= Some(1),
                    "{name}/{interp:?}: {worst:?} from IPP's result"
                );
                ipp_off = (ipp_off.0 + off, ipp_off.1 + default.len());
            }
        } else {
            let ours = resize_f32(&f32s(&src), cn, g, interp);
            for want in [Some(dst), default].into_iter().flatten() {
                let want = f32s(&want);
                assert_eq!(ours.len(), want.len());
                let worst = ours
                    .iter()
                    .zip(&want)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0f32, f32::max);
                assert!(worst <= 1e-5, "{name}/{interp:?}: max abs diff {worst}");
                max_f32 = max_f32.max(worst);
            }
        }
        checked += 1;
    }
    assert!(checked >= 20);
    eprintln!(
        "resize: {checked} cases, uint8 identical to OpenCV (IPP off); {} of {} uint8 values off by 1 from IPP; float32 max abs diff {max_f32:e}",
        ipp_off.0, ipp_off.1
    );
}

#[test]
fn gaussian_matches_scipy() {
    let cases = json("gaussian.json");
    let mut max = 0f64;
    for case in cases["cases"].as_array().expect("cases") {
        let shape = usizes(&case["shape"]);
        let src: Vec<f64> = case["src"]
            .as_array()
            .expect("src")
            .iter()
            .map(|v| v.as_f64().expect("f64"))
            .collect();
        let want: Vec<f64> = case["dst"]
            .as_array()
            .expect("dst")
            .iter()
            .map(|v| v.as_f64().expect("f64"))
            .collect();
        let ours = gaussian_filter(&src, shape[1], shape[0], 3.0, 4.0);
        let worst = ours
            .iter()
            .zip(&want)
            .map(|(a, b)| (a - b).abs())
            .fold(0f64, f64::max);
        assert!(worst <= 1e-12, "{}: max abs diff {worst}", case["name"]);
        max = max.max(worst);
    }
    eprintln!("gaussian: max abs diff {max:e}");
}

fn f16_to_f32(h: u16) -> f32 {
    let sign = if h >> 15 == 1 { -1.0 } else { 1.0 };
    let exp = ((h >> 10) & 0x1f) as i32;
    let man = (h & 0x3ff) as f32;
    match exp {
        0 => sign * man * 2f32.powi(-24),
        31 if man == 0.0 => sign * f32::INFINITY,
        31 => f32::NAN,
        _ => sign * (1.0 + man / 1024.0) * 2f32.powi(exp - 15),
    }
}

/// Runs `detect` on a decode fixture with a fake network returning its maps.
fn check_case(name: &str) {
    let meta = json(&format!("{name}.json"));
    let bytes = std::fs::read(fixture(&format!("{name}.bin"))).expect("bin fixture");
    let values: Vec<f32> = bytes
        .chunks_exact(2)
        .map(|c| f16_to_f32(u16::from_le_bytes([c[0], c[1]])))
        .collect();
    let model = match meta["model"].as_str().expect("model") {
        "coco18" => OpenposeModel::Coco18,
        _ => OpenposeModel::Body25,
    };
    let (h, w) = (
        meta["height"].as_u64().expect("h") as u32,
        meta["width"].as_u64().expect("w") as u32,
    );
    let mut outputs = Vec::new();
    let mut at = 0;
    for m in meta["maps"].as_array().expect("maps") {
        let (oh, ow) = (
            m["out_h"].as_u64().expect("oh") as usize,
            m["out_w"].as_u64().expect("ow") as usize,
        );
        let nh = model.heatmap_channels() * oh * ow;
        let np = model.paf_channels() * oh * ow;
        outputs.push(NetOutput {
            heatmaps: values[at..at + nh].to_vec(),
            pafs: values[at + nh..at + nh + np].to_vec(),
            height: oh,
            width: ow,
        });
        at += nh + np;
    }
    assert_eq!(at, values.len(), "{name}: map sizes");
    let params = SearchParams {
        scales: meta["scales"]
            .as_array()
            .expect("scales")
            .iter()
            .map(|s| s.as_f64().expect("scale"))
            .collect(),
        ..SearchParams::default()
    };
    let mut calls = 0;
    let mut net = |input: &NetInput| -> Result<NetOutput, StageError> {
        let out = outputs
            .get(calls)
            .cloned()
            .ok_or_else(|| StageError::BadInput("too many calls".into()))?;
        let m = &meta["maps"][calls];
        assert_eq!(
            (input.height as u64, input.width as u64),
            (
                m["padded_h"].as_u64().expect("ph"),
                m["padded_w"].as_u64().expect("pw")
            ),
            "{name}: padded input size of scale {calls}"
        );
        assert_eq!(input.data.len(), 3 * input.height * input.width);
        calls += 1;
        Ok(out)
    };
    let frame = Frame::new(
        0,
        image::RgbImage::from_pixel(w, h, image::Rgb([90, 120, 200])),
    );
    let det = detect(&frame, model, &params, &mut net).expect("detect");
    assert_eq!(calls, outputs.len());

    let cand = meta["candidate"].as_array().expect("candidate");
    assert_eq!(det.peaks.len(), cand.len(), "{name}: number of peaks");
    let mut max_score = 0f64;
    for (p, c) in det.peaks.iter().zip(cand) {
        let c: Vec<f64> = c
            .as_array()
            .expect("row")
            .iter()
            .map(|v| v.as_f64().expect("f64"))
            .collect();
        assert_eq!(
            (p.x as f64, p.y as f64, p.id as f64),
            (c[0], c[1], c[3]),
            "{name}: peak {}",
            p.id
        );
        max_score = max_score.max((p.score - c[2]).abs());
    }
    assert!(max_score <= 1e-5, "{name}: peak score diff {max_score}");

    let subset = meta["subset"].as_array().expect("subset");
    assert_eq!(det.people.len(), subset.len(), "{name}: number of people");
    let n = model.keypoints().len();
    let mut max_person = 0f64;
    for (i, (person, row)) in det.people.iter().zip(subset).enumerate() {
        let row: Vec<f64> = row
            .as_array()
            .expect("row")
            .iter()
            .map(|v| v.as_f64().expect("f64"))
            .collect();
        let want: Vec<Option<usize>> = row[..n]
            .iter()
            .map(|&v| (v >= 0.0).then_some(v as usize))
            .collect();
        assert_eq!(person.peak_ids, want, "{name}: person {i} keypoints");
        assert_eq!(person.parts as f64, row[n + 1], "{name}: person {i} parts");
        let d = (person.score as f64 - row[n]).abs();
        assert!(
            d <= 1e-4,
            "{name}: person {i} score {} vs {}",
            person.score,
            row[n]
        );
        max_person = max_person.max(d);
        for (k, id) in want.iter().enumerate() {
            let kp = person.keypoints[k];
            match id {
                Some(id) => {
                    let p = det.peaks[*id];
                    assert_eq!(kp, Some([p.x as f32, p.y as f32, p.score as f32]));
                }
                None => assert_eq!(kp, None),
            }
        }
    }
    eprintln!(
        "{name}: {} peaks, {} people identical; max |peak score diff| {max_score:e}, max |person score diff| {max_person:e}",
        det.peaks.len(),
        det.people.len()
    );
}

#[test]
fn single_person_matches_controlnet_aux() {
    check_case("single");
}

#[test]
fn three_people_with_crossing_limbs_match_controlnet_aux() {
    check_case("three_crossing");
}

#[test]
fn missing_limbs_and_distractors_match_controlnet_aux() {
    check_case("missing_limbs");
}

#[test]
fn two_scales_match_controlnet_aux() {
    check_case("two_scales");
}

#[test]
fn three_scales_match_controlnet_aux() {
    check_case("three_scales");
}

#[test]
fn empty_maps_match_controlnet_aux() {
    check_case("empty");
}

#[test]
fn body25_tables_match_numpy_decoding() {
    check_case("body25");
}

#[test]
fn tiny_and_failing_inputs_do_not_panic() {
    let params = SearchParams::default();
    for (w, h) in [(1, 1), (3, 2), (2, 40)] {
        let frame = Frame::new(0, image::RgbImage::new(w, h));
        let mut net = |input: &NetInput| -> Result<NetOutput, StageError> {
            let (oh, ow) = (input.height / 8, input.width / 8);
            Ok(NetOutput {
                heatmaps: vec![f32::NAN; 19 * oh * ow],
                pafs: vec![0.0; 38 * oh * ow],
                height: oh,
                width: ow,
            })
        };
        let det = detect(&frame, OpenposeModel::Coco18, &params, &mut net).expect("detect");
        assert!(det.people.is_empty());
    }
    let frame = Frame::new(0, image::RgbImage::new(20, 20));
    let mut wrong = |_: &NetInput| -> Result<NetOutput, StageError> {
        Ok(NetOutput {
            heatmaps: vec![0.0; 3],
            pafs: vec![],
            height: 1,
            width: 1,
        })
    };
    let err = detect(&frame, OpenposeModel::Coco18, &params, &mut wrong).unwrap_err();
    assert!(err.to_string().contains("expected"), "{err}");
}
