//! A recorded probe and decode of a video in one file: what ffprobe described and what ffmpeg
//! wrote, exit status and messages included. The `video_stream` target reads such files, so the
//! video reader is fuzzed in-process (thousands of inputs a second, where spawning ffmpeg per
//! input manages nine); `gait-fuzz record-video` writes them from real runs of both tools.
//!
//! Layout: one byte, ffmpeg's exit (0 = success); ffprobe's JSON and ffmpeg's messages, each as a
//! little-endian u32 length and its bytes; then ffmpeg's frame bytes to the end. Any bytes at all
//! read as a recording (a length past the end takes what is there), so every mutated input reaches
//! the reader.

use std::path::Path;

use gait_pipeline::input::{DecoderRecording, ffprobe_command};

/// Writes a recording: ffprobe's JSON and ffmpeg's run.
pub fn pack(probe: &[u8], decoded: &DecoderRecording) -> Vec<u8> {
    let mut out = vec![u8::from(!decoded.success)];
    for part in [probe, decoded.messages.as_bytes()] {
        out.extend_from_slice(&(part.len() as u32).to_le_bytes());
        out.extend_from_slice(part);
    }
    out.extend_from_slice(&decoded.frames);
    out
}

/// Reads a recording: ffprobe's JSON and ffmpeg's run.
pub fn unpack(bytes: &[u8]) -> (&[u8], DecoderRecording) {
    let (status, rest) = bytes.split_first().unwrap_or((&0, &[]));
    let (probe, rest) = part(rest);
    let (messages, frames) = part(rest);
    let decoded = DecoderRecording {
        frames: frames.to_vec(),
        success: *status == 0,
        messages: String::from_utf8_lossy(messages).into_owned(),
    };
    (probe, decoded)
}

/// A length-prefixed part and what follows it.
fn part(bytes: &[u8]) -> (&[u8], &[u8]) {
    let Some((len, rest)) = bytes.split_first_chunk::<4>() else {
        return (&[], &[]);
    };
    let n = (u32::from_le_bytes(*len) as usize).min(rest.len());
    rest.split_at(n)
}

/// Runs the product's ffprobe and ffmpeg commands on `video` and packs what they wrote.
pub fn record(video: &Path) -> std::io::Result<Vec<u8>> {
    let probe = ffprobe_command(video).output()?;
    if !probe.status.success() {
        return Err(std::io::Error::other(format!(
            "ffprobe failed on {}: {}",
            video.display(),
            String::from_utf8_lossy(&probe.stderr).trim()
        )));
    }
    Ok(pack(&probe.stdout, &DecoderRecording::record(video)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_recording_reads_back_and_any_bytes_read() {
        let decoded = DecoderRecording {
            frames: vec![1, 2, 3],
            success: false,
            messages: "bad".into(),
        };
        let packed = pack(b"{}", &decoded);
        assert_eq!(unpack(&packed), (&b"{}"[..], decoded));
        let (probe, cut) = unpack(&packed[..7]);
        assert_eq!((probe, cut.messages.as_str()), (&b"{}"[..], ""));
        assert!(unpack(&[]).1.frames.is_empty());
    }

    /// The seeds lead the mutator into the reader: mutated recordings are read as videos and
    /// end in each of the reader's outcomes, not only in the JSON parser's refusal.
    #[test]
    fn mutated_seed_recordings_reach_every_outcome_of_the_reader() {
        let t = crate::targets::target("video_stream").unwrap();
        let seeds = crate::engine::seeds(t);
        let mut rng = crate::mutate::Rng::new(5);
        let mut outcomes = std::collections::BTreeMap::<String, usize>::new();
        for i in 0..8000 {
            let (a, b) = (&seeds[i % seeds.len()].1, &seeds[(i / 7) % seeds.len()].1);
            let input = crate::mutate::variant(&mut rng, a, b);
            let (probe, decoded) = unpack(&input);
            let path = Path::new("clip.mp4");
            let outcome = match gait_pipeline::input::parse_ffprobe(path, probe) {
                Err(e) => {
                    eprintln!("REFUSED {e}");
                    "refused by the description".to_string()
                }
                Ok(info) => {
                    let mut frames = info.replay(decoded);
                    let mut end = String::from("read to the end");
                    while let r @ (Ok(Some(_)) | Err(_)) = frames.next_frame() {
                        if let Err(e) = r {
                            end = ["truncated", "cannot decode", "no frames"]
                                .into_iter()
                                .find(|k| e.to_string().contains(k))
                                .unwrap_or("other error")
                                .to_string();
                            break;
                        }
                    }
                    end
                }
            };
            *outcomes.entry(outcome).or_default() += 1;
        }
        for k in ["read to the end", "truncated", "cannot decode"] {
            assert!(outcomes.contains_key(k), "{k}: {outcomes:?}");
        }
        // An empty stream after a clean exit: no seed has one and mutations rarely make one
        // (the description must stay valid JSON), so a seed is emptied here.
        let (probe, mut decoded) = unpack(&seeds[0].1);
        decoded.frames.clear();
        decoded.messages.clear();
        decoded.success = true;
        let info = gait_pipeline::input::parse_ffprobe(Path::new("clip.mp4"), probe).unwrap();
        let e = info.replay(decoded).next_frame().unwrap_err().to_string();
        assert!(e.contains("no frames"), "{e}");
        // The description carries every frame's time (frame_timing.rs), a fifth of a seed's
        // bytes, so many mutations land in its JSON: most inputs still reach the reader or
        // near a third of them at least.
        assert!(
            outcomes["refused by the description"] < 6000,
            "{outcomes:?}"
        );
    }
}
