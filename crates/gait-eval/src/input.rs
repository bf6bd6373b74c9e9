//! Reading ground truth and predictions in any supported layout.

use std::path::Path;

use gait_core::PoseSequence;

use crate::{EvalError, openpose};

/// Reads keypoints from a DeepLabCut CSV file (single- or multi-animal; for
/// multi-animal files `individual` picks one, the first by default) or from a
/// folder of OpenPose per-frame JSON files. Neither layout stores the frame
/// rate, so it is given as `fps`.
pub fn read_poses(
    path: &Path,
    fps: f64,
    individual: Option<&str>,
) -> Result<PoseSequence, EvalError> {
    if path.is_dir() {
        return openpose::read_dir(path, fps);
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    match ext.as_str() {
        "csv" => {
            let file = std::fs::File::open(path)
                .map_err(|e| EvalError::io(format!("opening {}", path.display()), e))?;
            gait_core::dlc::read(std::io::BufReader::new(file), individual, fps)
                .map_err(|e| EvalError::input(path, e))
        }
        "h5" | "hdf5" => Err(EvalError::input(
            path,
            "DeepLabCut HDF5 files are not read; export the CSV (DeepLabCut writes both, or use `analyze_videos(..., save_as_csv=True)`)",
        )),
        "json" => Err(EvalError::input(
            path,
            "give the folder that holds the OpenPose `*_keypoints.json` files, not one file",
        )),
        _ => Err(EvalError::input(
            path,
            "expected a DeepLabCut `.csv` file or a folder of OpenPose `*_keypoints.json` files",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn picks_the_reader_by_path() {
        let dir = tempfile::tempdir().unwrap();
        let csv = dir.path().join("t.csv");
        std::fs::write(
            &csv,
            "scorer,s,s\nbodyparts,RKnee,RKnee\ncoords,x,y\n0,1,2\n",
        )
        .unwrap();
        let s = read_poses(&csv, 30.0, None).unwrap();
        assert_eq!(s.names, vec!["RKnee"]);
        let h5 = dir.path().join("t.h5");
        assert!(
            read_poses(&h5, 30.0, None)
                .unwrap_err()
                .to_string()
                .contains("CSV")
        );
        assert!(
            read_poses(dir.path(), 30.0, None)
                .unwrap_err()
                .to_string()
                .contains("OpenPose")
        );
    }
}
