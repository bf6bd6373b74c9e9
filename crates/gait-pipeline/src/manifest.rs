//! `run.json`: everything needed to understand and repeat a run — the
//! resolved config, tool version, input and model checksums, timings.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};

use serde::Serialize;
use sha2::{Digest, Sha256};

use crate::input::hex;
use crate::selection::SelectionRecord;

/// The run manifest written as `run.json`.
#[derive(Debug, Clone, Serialize)]
pub struct RunManifest {
    pub tool: &'static str,
    pub version: &'static str,
    /// "done", or "no_result" when the run completed but found nothing to measure
    /// (`reason` says what); an interrupted run's run.json says "interrupted".
    pub status: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// Seconds since the Unix epoch when the run started.
    pub started_unix: u64,
    pub command: Vec<String>,
    pub input: InputRecord,
    /// The resolved configuration; `gait run --config run.json` repeats the run.
    pub config: serde_json::Value,
    pub models: Vec<ModelRecord>,
    pub stages: BTreeMap<String, StageRecord>,
    pub frames_processed: usize,
    /// Frames whose pose came from the cache (a resumed or repeated run).
    pub frames_from_cache: usize,
    /// Which frames were regenerated, kept their original-frame pose or
    /// were interpolated, and why frames were judged poor.
    pub selection: SelectionRecord,
    /// The people tracked over the input and the subject among them (absent
    /// when the pose stage cannot list people, or `[subject] enabled = false`).
    pub subject: Option<gait_subject::Subject>,
    pub keypoint_names: Vec<String>,
    pub warnings: Vec<String>,
    /// Summaries added by later steps (kinematics, reports).
    pub extra: BTreeMap<String, serde_json::Value>,
    /// Where the wall time went, step by step (completed after the report).
    pub timings: crate::timings::Timings,
    /// How each `backend = "auto"` was decided (the config holds the choice).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub backend_choices: Vec<String>,
}

/// Why a completed run has no result to report (no walking bout, no accepted cycle), or None.
pub fn no_result_reason(kin: &gait_kin::KinResult) -> Option<String> {
    if kin.bouts.is_empty() {
        return Some("no walking bout found".into());
    }
    let (yes, no) = (&kin.cycles_accepted, &kin.cycles_rejected);
    if kin.cycle_quality.is_empty() {
        let bouts: Vec<String> = kin
            .bouts
            .iter()
            .map(|b| format!("{}-{}", b.first, b.last))
            .collect();
        return Some(format!(
            "no complete gait cycle: no foot has two heel strikes within a walking bout (frames {}); the walker must be seen for a whole stride",
            bouts.join(", ")
        ));
    }
    (yes.left + yes.right == 0).then(|| {
        // The reasons, most frequent first: what a user can change (film closer, in focus).
        let mut why: BTreeMap<&str, usize> = BTreeMap::new();
        for q in &kin.cycle_quality {
            for r in &q.reasons {
                *why.entry(r.name()).or_default() += 1;
            }
        }
        let mut why: Vec<(&str, usize)> = why.into_iter().collect();
        why.sort_by_key(|w| std::cmp::Reverse(w.1));
        let why: Vec<String> = why.iter().map(|(r, k)| format!("{k} {r}")).collect();
        let why = if why.is_empty() {
            String::new()
        } else {
            format!(": {}", why.join(", "))
        };
        format!(
            "no complete gait cycle accepted ({} rejected{why})",
            no.left + no.right
        )
    })
}

#[derive(Debug, Clone, Serialize)]
pub struct InputRecord {
    /// As given on the command line.
    pub path: PathBuf,
    /// The same, absolute (how `gait review` finds the video from anywhere).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub absolute_path: Option<PathBuf>,
    pub sha256: String,
    pub width: u32,
    pub height: u32,
    pub fps: f64,
    /// A video's frame times as measured (frame_timing.rs): whether its rate varies, and the
    /// constant rate its frames were resampled to.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frame_timing: Option<crate::frame_timing::FrameTiming>,
    /// An HDR video's transfer ("arib-std-b67": HLG, "smpte2084": PQ), converted to standard
    /// range before the pose model (picture.rs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hdr_transfer: Option<String>,
    /// An interlaced video's field order, deinterlaced before the pose model (picture.rs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interlaced: Option<String>,
    pub first_frame: usize,
    pub last_frame: Option<usize>,
    /// Still images: how many had each EXIF orientation (1-8, as stored), applied as `cv2.imread`
    /// does ("6": 3 is three photographs taken upright on a phone held sideways).
    #[serde(skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub exif_orientation: BTreeMap<u16, usize>,
    /// The blur of the subject's legs (px, `gait_edge::blur_px`) in the frames measured,
    /// about six a second (sharpness.rs); the kinematics judge strides by it.
    #[serde(skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub blur_px: std::collections::BTreeMap<usize, f64>,
    /// Each foot's outline contrast along the rows (left, right; `gait_edge::edge_contrast`)
    /// per frame; the kinematics find motion blur by it.
    #[serde(skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub feet_contrast: gait_kin::FeetContrast,
}

#[derive(Debug, Clone, Serialize)]
pub struct ModelRecord {
    pub path: PathBuf,
    /// Absent when the file could not be read.
    pub sha256: Option<String>,
}

/// Work done by one stage: how many frames it computed, how many came from
/// the cache, and the seconds spent computing.
#[derive(Debug, Clone, Default, Serialize)]
pub struct StageRecord {
    pub kind: String,
    /// Where the stage ran: `[run] device` for stages with a model, else "cpu".
    pub device: String,
    pub cache_key: String,
    pub computed: usize,
    pub cached: usize,
    pub seconds: f64,
}

/// SHA-256 of a file, streamed.
pub fn sha256_file(path: &Path) -> std::io::Result<String> {
    let mut f = std::fs::File::open(path)?;
    let mut h = Sha256::new();
    let mut buf = vec![0u8; 1 << 20];
    loop {
        let n = f.read(&mut buf)?;
        if n == 0 {
            return Ok(hex(&h.finalize()));
        }
        h.update(&buf[..n]);
    }
}

pub(crate) fn model_records(paths: Vec<PathBuf>) -> Vec<ModelRecord> {
    paths
        .into_iter()
        .map(|path| ModelRecord {
            sha256: sha256_file(&path).ok(),
            path,
        })
        .collect()
}
