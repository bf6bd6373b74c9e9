//! What ffprobe says of a video before it is decoded: which stream is analysed, its size,
//! rotation, frame rate and frame times, whether it is HDR or interlaced.

use std::path::Path;
use std::process::{Command, Stdio};

use crate::PipelineError;
use crate::frame_timing::FrameTiming;
use crate::input::{DecodeWarnings, InputInfo, Kind, ReadClock, ffmpeg_missing};

/// The ffprobe command that describes `path` in the JSON [`parse_ffprobe`] reads: every video
/// stream that is not a cover picture (`V`; the video is chosen among them) and their packets'
/// times (frame_timing.rs), one packet a line.
pub fn ffprobe_command(path: &Path) -> Command {
    let mut cmd = Command::new("ffprobe");
    cmd.args(["-v", "error", "-select_streams", "V", "-show_entries"])
        .arg(concat!(
            "stream=index,codec_type,width,height,r_frame_rate,nb_frames,color_transfer,field_order",
            ",pix_fmt,color_space,color_range",
            ":stream_disposition=attached_pic:stream_side_data=rotation",
            ":packet=stream_index,pts_time"
        ))
        .args(["-of", "json=compact=1"])
        .arg(path);
    cmd
}

/// The stream analysed: the video stream with the most pixels that is not a cover picture (the
/// one ffmpeg itself would take; a camera's small preview stream may come first). A stream
/// without a `codec_type` counts as video (older recordings of ffprobe's output).
fn video_stream(streams: &serde_json::Value) -> Option<&serde_json::Value> {
    let pixels = |s: &serde_json::Value| {
        // Saturating: a hostile description may declare any width; the size check follows.
        (s["width"].as_u64().unwrap_or(0)).saturating_mul(s["height"].as_u64().unwrap_or(0))
    };
    streams
        .as_array()?
        .iter()
        .filter(|s| s["codec_type"].as_str().is_none_or(|t| t == "video"))
        .filter(|s| s["disposition"]["attached_pic"].as_u64() != Some(1))
        .rev()
        .max_by_key(|s| pixels(s))
}

pub(crate) fn probe_video(path: &Path) -> Result<InputInfo, PipelineError> {
    let out = ffprobe_command(path)
        .stdin(Stdio::null())
        .output()
        .map_err(|e| ffmpeg_missing(path, e))?;
    if !out.status.success() {
        let msg = String::from_utf8_lossy(&out.stderr);
        let why = msg.lines().next().unwrap_or("ffprobe failed").trim();
        return Err(not_a_video(path, why));
    }
    parse_ffprobe(path, &out.stdout)
}

fn not_a_video(path: &Path, why: &str) -> PipelineError {
    PipelineError::input(
        path,
        format!("not a readable video ({why}); check the file or re-encode it"),
    )
}

/// The largest frame a video may declare: 8192 x 8192 pixels (8K video is 7680 x 4320), so
/// a hostile container cannot make each frame's buffer gigabytes.
pub const MAX_FRAME_PIXELS: u64 = 8192 * 8192;

/// The video's size, rate and frame count from ffprobe's JSON output for `path` (public
/// for the fuzzer, which feeds it arbitrary bytes).
pub fn parse_ffprobe(path: &Path, stdout: &[u8]) -> Result<InputInfo, PipelineError> {
    let bad = |why: &str| not_a_video(path, why);
    let json: serde_json::Value =
        serde_json::from_slice(stdout).map_err(|_| bad("ffprobe output unreadable"))?;
    let stream = video_stream(&json["streams"]).ok_or_else(|| bad("no video stream"))?;
    let index = stream["index"].as_u64();
    let dim = |k: &str| {
        stream[k]
            .as_u64()
            .filter(|v| *v > 0)
            .and_then(|v| u32::try_from(v).ok())
    };
    let (mut width, mut height) = match (dim("width"), dim("height")) {
        (Some(w), Some(h)) => (w, h),
        _ => return Err(bad("no frame size")),
    };
    if width as u64 * height as u64 > MAX_FRAME_PIXELS {
        return Err(bad(&format!(
            "frames of {width}x{height} pixels; at most 8192x8192 are read"
        )));
    }
    let rotation = stream["side_data_list"]
        .as_array()
        .and_then(|l| l.iter().find_map(|d| d["rotation"].as_i64()))
        .unwrap_or(0);
    // ffmpeg applies the rotation when decoding, so the frames are turned.
    if rotation.rem_euclid(180) == 90 {
        std::mem::swap(&mut width, &mut height);
    }
    let fps = stream["r_frame_rate"]
        .as_str()
        .and_then(|r| {
            let (n, d) = r.split_once('/')?;
            let (n, d): (f64, f64) = (n.parse().ok()?, d.parse().ok()?);
            // "inf/1" parses too; a camera rate is finite and below 10^5 frames per second.
            let fps = n / d;
            (d > 0.0 && n > 0.0 && fps.is_finite() && fps <= 1e5).then_some(fps)
        })
        .ok_or_else(|| bad("no frame rate"))?;
    let mut frames = stream["nb_frames"].as_str().and_then(|n| n.parse().ok());
    let times: Vec<f64> = json["packets"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|p| p["stream_index"].as_u64() == index)
        .filter_map(|p| p["pts_time"].as_str()?.parse().ok())
        .collect();
    let timing = FrameTiming::measure(fps, &times);
    let decode_warnings = DecodeWarnings::default();
    let hdr_transfer = stream["color_transfer"]
        .as_str()
        .filter(|t| crate::picture::to_standard_range(t).is_some())
        .map(str::to_string);
    if let Some(w) = hdr_transfer.as_deref().and_then(crate::picture::warning) {
        decode_warnings.add(w);
    }
    let interlaced = stream["field_order"]
        .as_str()
        .filter(|o| crate::picture::deinterlace(o).is_some())
        .map(str::to_string);
    if let Some(o) = &interlaced {
        decode_warnings.add(format!(
            "the video is interlaced (field order {o}): its frames were deinterlaced (bwdif, a frame for a frame)"
        ));
    }
    if let Some(t) = &timing {
        if t.resampled_fps.is_some() {
            frames = Some(t.frames(times.len()));
        }
        if let Some(w) = t.warning() {
            decode_warnings.add(w);
        }
    }
    let yuv = crate::yuv::Yuv420::of_stream(
        stream["pix_fmt"].as_str(),
        stream["color_space"].as_str(),
        stream["color_range"].as_str(),
        (width, height),
    );
    Ok(InputInfo {
        path: path.to_path_buf(),
        width,
        height,
        fps: timing.as_ref().map_or(fps, FrameTiming::fps),
        frames,
        timing,
        stream: index.and_then(|i| usize::try_from(i).ok()),
        hdr_transfer,
        interlaced,
        orientations: Default::default(),
        kind: Kind::Video,
        decode_warnings,
        reading: ReadClock::default(),
        yuv,
        yuv_verdict: Default::default(),
        spool: Default::default(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hostile_ffprobe_descriptions_are_refused() {
        let p = Path::new("clip.mp4");
        let probe = |w: u64, h: u64, rate: &str| {
            let json = format!(
                r#"{{"streams": [{{"width": {w}, "height": {h}, "r_frame_rate": "{rate}", "nb_frames": "1000000000"}}]}}"#
            );
            parse_ffprobe(p, json.as_bytes()).map_err(|e| e.to_string())
        };
        let ok = probe(1768, 994, "30/1").unwrap();
        assert_eq!((ok.width, ok.height, ok.fps), (1768, 994, 30.0));
        assert!(
            probe(100_000, 100_000, "30/1")
                .unwrap_err()
                .contains("at most 8192x8192")
        );
        // A width past u32 is no frame size, not a wrapped one.
        assert!(
            probe(1 << 33, 10, "30/1")
                .unwrap_err()
                .contains("no frame size")
        );
        for rate in ["inf/1", "NaN/1", "30/0", "1e300/1e-300"] {
            assert!(
                probe(64, 48, rate).unwrap_err().contains("no frame rate"),
                "{rate}"
            );
        }
    }
}
