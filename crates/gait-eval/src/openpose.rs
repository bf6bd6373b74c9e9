//! OpenPose per-frame JSON (`<name>_<frame>_keypoints.json`, the first person's
//! `pose_keypoints_2d` as x, y, confidence triples) in BODY_25 or COCO-18 order.

use std::path::{Path, PathBuf};

use gait_core::{CANONICAL, Keypoint, Pose, PoseSequence};
use serde_json::{Value, json};

use crate::EvalError;

pub use gait_core::openpose_layout::{BODY_25, COCO_18};

/// Names of a sequence read from OpenPose: the canonical names, then the
/// model's extra keypoints in its own order.
fn sequence_names(layout: &[&str]) -> Vec<String> {
    let mut names: Vec<String> = CANONICAL.iter().map(|s| s.to_string()).collect();
    names.extend(
        layout
            .iter()
            .filter(|n| !CANONICAL.contains(n))
            .map(|s| s.to_string()),
    );
    names
}

/// Frame number in an OpenPose file name: the last run of digits before `_keypoints`.
fn frame_number(file_name: &str) -> Option<usize> {
    let stem = file_name.strip_suffix("_keypoints.json")?;
    let digits: String = stem
        .chars()
        .rev()
        .take_while(char::is_ascii_digit)
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect();
    digits.parse().ok()
}

/// One of the keypoint orders, [`BODY_25`] or [`COCO_18`].
type Layout = &'static [&'static str];

/// Keypoints of the first person in one OpenPose JSON document, with the layout found.
fn parse_frame(path: &Path, text: &str) -> Result<Option<(Vec<Keypoint>, Layout)>, EvalError> {
    let doc: Value = serde_json::from_str(text).map_err(|e| EvalError::input(path, e))?;
    let people = doc
        .get("people")
        .and_then(Value::as_array)
        .ok_or_else(|| EvalError::input(path, "no `people` array (not an OpenPose JSON file)"))?;
    let Some(person) = people.first() else {
        return Ok(None);
    };
    let values = person
        .get("pose_keypoints_2d")
        .and_then(Value::as_array)
        .ok_or_else(|| EvalError::input(path, "people[0] has no `pose_keypoints_2d` array"))?;
    let layout: Layout = match values.len() {
        75 => &BODY_25,
        54 => &COCO_18,
        n => {
            return Err(EvalError::input(
                path,
                format!("pose_keypoints_2d has {n} values; expected 75 (BODY_25) or 54 (COCO-18)"),
            ));
        }
    };
    let mut kps = Vec::with_capacity(layout.len());
    for t in values.chunks(3) {
        let num = |v: &Value| {
            v.as_f64().ok_or_else(|| {
                EvalError::input(path, format!("`{v}` in pose_keypoints_2d is not a number"))
            })
        };
        let (x, y, c) = (num(&t[0])?, num(&t[1])?, num(&t[2])?);
        // OpenPose writes 0, 0, 0 for a part it did not find.
        kps.push(if c > 0.0 && x.is_finite() && y.is_finite() {
            Keypoint::new(x, y, c)
        } else {
            Keypoint::missing()
        });
    }
    Ok(Some((kps, layout)))
}

/// Reads a folder of OpenPose `*_keypoints.json` files, ordered by the frame
/// number in their names. COCO-18 has no mid-hip: it is the midpoint of the
/// hips when both were found. Frames without a person are all missing.
pub fn read_dir(dir: &Path, fps: f64) -> Result<PoseSequence, EvalError> {
    let entries = std::fs::read_dir(dir)
        .map_err(|e| EvalError::io(format!("reading {}", dir.display()), e))?;
    let mut files: Vec<(usize, PathBuf)> = Vec::new();
    for entry in entries {
        let path = entry
            .map_err(|e| EvalError::io(format!("reading {}", dir.display()), e))?
            .path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if let Some(frame) = frame_number(name) {
            files.push((frame, path));
        }
    }
    if files.is_empty() {
        return Err(EvalError::input(
            dir,
            "no OpenPose `*_<frame>_keypoints.json` files in the folder",
        ));
    }
    files.sort();
    if let Some(w) = files.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(EvalError::input(
            dir,
            format!(
                "two files for frame {}: {} and {}",
                w[0].0,
                w[0].1.display(),
                w[1].1.display()
            ),
        ));
    }
    let mut layout: Option<Layout> = None;
    let mut raw = Vec::with_capacity(files.len());
    for (frame, path) in &files {
        let text = std::fs::read_to_string(path)
            .map_err(|e| EvalError::io(format!("reading {}", path.display()), e))?;
        let parsed = parse_frame(path, &text)?;
        if let Some((_, l)) = &parsed {
            match layout {
                Some(prev) if prev.len() != l.len() => {
                    return Err(EvalError::input(
                        path,
                        "mixes BODY_25 and COCO-18 keypoints with other files",
                    ));
                }
                _ => layout = Some(l),
            }
        }
        raw.push((*frame, parsed.map(|(k, _)| k)));
    }
    let layout = layout.unwrap_or(&BODY_25);
    let names = sequence_names(layout);
    let mut frames = Vec::with_capacity(raw.len());
    let mut poses = Vec::with_capacity(raw.len());
    for (frame, kps) in raw {
        let mut pose = Pose::empty(names.len());
        if let Some(kps) = kps {
            for (native, kp) in layout.iter().zip(kps) {
                if let Some(i) = names.iter().position(|n| n == native) {
                    pose.keypoints[i] = kp;
                }
            }
            if layout.len() == COCO_18.len() {
                let (l, r) = (pose.keypoints[5], pose.keypoints[6]);
                if l.is_found() && r.is_found() {
                    pose.keypoints[4] = Keypoint::new(
                        (l.x + r.x) / 2.0,
                        (l.y + r.y) / 2.0,
                        l.likelihood.min(r.likelihood),
                    );
                }
            }
        }
        frames.push(frame);
        poses.push(pose);
    }
    Ok(PoseSequence {
        fps,
        names,
        frames,
        poses,
    })
}

/// Writes one BODY_25 `<stem>_<frame:012>_keypoints.json` per frame into `dir`
/// (created if needed). Keypoints without a BODY_25 counterpart are left out;
/// missing ones are written as 0, 0, 0 and a frame with no keypoint found has
/// no person, as OpenPose does.
pub fn write_dir(seq: &PoseSequence, dir: &Path, stem: &str) -> Result<Vec<PathBuf>, EvalError> {
    std::fs::create_dir_all(dir)
        .map_err(|e| EvalError::io(format!("creating {}", dir.display()), e))?;
    let columns: Vec<Option<usize>> = BODY_25.iter().map(|n| seq.index_of(n)).collect();
    let mut written = Vec::with_capacity(seq.len());
    for (frame, pose) in seq.frames.iter().zip(&seq.poses) {
        let mut values = Vec::with_capacity(75);
        let mut any = false;
        for col in &columns {
            match col
                .and_then(|i| pose.keypoints.get(i))
                .filter(|k| k.is_found())
            {
                Some(k) => {
                    any = true;
                    values.extend([json!(k.x), json!(k.y), json!(k.likelihood)]);
                }
                None => values.extend([json!(0.0), json!(0.0), json!(0.0)]),
            }
        }
        let people = if any {
            vec![json!({
                "person_id": [-1],
                "pose_keypoints_2d": values,
                "face_keypoints_2d": [],
                "hand_left_keypoints_2d": [],
                "hand_right_keypoints_2d": [],
                "pose_keypoints_3d": [],
                "face_keypoints_3d": [],
                "hand_left_keypoints_3d": [],
                "hand_right_keypoints_3d": []
            })]
        } else {
            Vec::new()
        };
        let doc = json!({ "version": 1.3, "people": people });
        let path = dir.join(format!("{stem}_{frame:012}_keypoints.json"));
        crate::fsutil::write_atomic(&path, doc.to_string().as_bytes())?;
        written.push(path);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_numbers_come_from_the_name() {
        assert_eq!(frame_number("walk_000000000012_keypoints.json"), Some(12));
        assert_eq!(frame_number("3_keypoints.json"), Some(3));
        assert_eq!(frame_number("walk_keypoints.json"), None);
        assert_eq!(frame_number("walk_000001.json"), None);
    }

    #[test]
    fn round_trip_body25() {
        let dir = tempfile::tempdir().unwrap();
        let names = sequence_names(&BODY_25);
        let mut pose = Pose::empty(names.len());
        let knee = names.iter().position(|n| n == "left_knee").unwrap();
        let small = names.iter().position(|n| n == "right_small_toe").unwrap();
        pose.keypoints[knee] = Keypoint::new(10.5, 20.25, 0.8);
        pose.keypoints[small] = Keypoint::new(1.0, 2.0, 0.5);
        let n = names.len();
        let seq = PoseSequence {
            fps: 30.0,
            names,
            frames: vec![7, 8],
            poses: vec![pose, Pose::empty(n)],
        };
        write_dir(&seq, dir.path(), "walk").unwrap();
        let back = read_dir(dir.path(), 30.0).unwrap();
        assert_eq!(back.frames, vec![7, 8]);
        // NaN != NaN, so compare what was found.
        let found = |p: &Pose| -> Vec<(usize, Keypoint)> {
            p.keypoints
                .iter()
                .copied()
                .enumerate()
                .filter(|(_, k)| k.is_found())
                .collect()
        };
        assert_eq!(found(&back.poses[0]), found(&seq.poses[0]));
        assert_eq!(found(&back.poses[0]).len(), 2);
        assert!(back.poses[1].keypoints.iter().all(|k| !k.is_found()));
        let text =
            std::fs::read_to_string(dir.path().join("walk_000000000008_keypoints.json")).unwrap();
        assert!(text.contains("\"people\":[]"), "{text}");
    }

    #[test]
    fn coco18_gets_a_mid_hip() {
        let dir = tempfile::tempdir().unwrap();
        let mut v = vec![0.0; 54];
        v[8 * 3..8 * 3 + 3].copy_from_slice(&[10.0, 50.0, 0.9]); // right hip
        v[11 * 3..11 * 3 + 3].copy_from_slice(&[20.0, 52.0, 0.7]); // left hip
        let doc = json!({"version": 1.2, "people": [{"pose_keypoints_2d": v}]});
        std::fs::write(dir.path().join("a_0_keypoints.json"), doc.to_string()).unwrap();
        let s = read_dir(dir.path(), 25.0).unwrap();
        let mid = s.track("mid_hip").unwrap()[0];
        assert_eq!((mid.x, mid.y, mid.likelihood), (15.0, 51.0, 0.7));
        assert!(!s.track("left_heel").unwrap()[0].is_found());
    }

    #[test]
    fn bad_files_name_the_problem() {
        let dir = tempfile::tempdir().unwrap();
        assert!(
            read_dir(dir.path(), 30.0)
                .unwrap_err()
                .to_string()
                .contains("no OpenPose")
        );
        std::fs::write(
            dir.path().join("a_0_keypoints.json"),
            r#"{"people":[{"pose_keypoints_2d":[1,2,3]}]}"#,
        )
        .unwrap();
        let e = read_dir(dir.path(), 30.0).unwrap_err().to_string();
        assert!(e.contains("3 values") && e.contains("BODY_25"), "{e}");
    }
}
