//! `gait edges`: the configured edge detector over every frame, written as
//! PNGs (white edges on black, at the detector's working size) so edge maps
//! can be inspected and compared with other tools.

use std::path::{Path, PathBuf};

use gait_core::StageContext;
use indicatif::ProgressBar;

use crate::input::InputInfo;
use crate::{PipelineConfig, PipelineError, atomic};

/// Writes `<out>/<frame index:06>.png` for every selected frame; returns how many.
pub fn export_edges(
    config: &PipelineConfig,
    input: &Path,
    out: &Path,
    models_dir: &Path,
    progress: bool,
) -> Result<usize, PipelineError> {
    let info = InputInfo::open(input)?;
    crate::registry::check_devices(config)?;
    let ctx = StageContext::new(models_dir).on(crate::registry::stage_devices(config)[0]);
    let mut detector = config.edge.build(&ctx)?.ok_or_else(|| {
        PipelineError::config(
            "edge.kind",
            "\"none\": there are no edge maps to write; set edge.kind (e.g. --set edge.kind=canny)",
        )
    })?;
    std::fs::create_dir_all(out)
        .map_err(|e| PipelineError::io(format!("creating {}", out.display()), e))?;
    let bar = if progress {
        ProgressBar::new(info.frames.unwrap_or(0) as u64)
    } else {
        ProgressBar::hidden()
    };
    let mut reader = info.frames()?;
    let mut batch = Vec::new();
    let mut written = 0;
    loop {
        let frame = reader.next_frame()?;
        let past_end = frame
            .as_ref()
            .is_none_or(|f| config.input.last_frame.is_some_and(|l| f.index > l));
        if let Some(f) = frame.filter(|f| f.index >= config.input.first_frame && !past_end) {
            batch.push(f);
        }
        if batch.len() == config.run.batch_size || (past_end && !batch.is_empty()) {
            for map in detector.detect(&batch)? {
                let path = png_path(out, map.index);
                atomic::write_with(&path, |w| {
                    image::ImageEncoder::write_image(
                        image::codecs::png::PngEncoder::new(w),
                        map.image.as_raw(),
                        map.image.width(),
                        map.image.height(),
                        image::ExtendedColorType::L8,
                    )
                    .map_err(std::io::Error::other)
                })
                .map_err(|e| PipelineError::io(format!("writing {}", path.display()), e))?;
                written += 1;
            }
            bar.inc(batch.len() as u64);
            batch.clear();
        }
        if past_end {
            break;
        }
    }
    bar.finish_and_clear();
    if written == 0 {
        return Err(PipelineError::input(
            input,
            info.no_frames_in(config.input.first_frame, config.input.last_frame),
        ));
    }
    Ok(written)
}

fn png_path(out: &Path, index: usize) -> PathBuf {
    out.join(format!("{index:06}.png"))
}
