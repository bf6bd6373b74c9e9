//! Test regenerator plugin built with `export_regenerator!`: inverts each
//! frame and paints pixels under an edge (value > 0) pure red. Its options
//! make it return a frame of the wrong size or fail.

use gait_core::{EdgeMap, Frame, ImageRegenerator, StageContext, StageError};
use gait_plugin::PluginStage;
use serde::Deserialize;

#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Options {
    /// Return frames one pixel narrower than the input.
    pub shrink: bool,
    /// Fail with a backend error.
    pub fail: bool,
}

pub struct TestingRegen {
    options: Options,
}

impl PluginStage for TestingRegen {
    type Options = Options;

    fn create(options: Options, _ctx: &StageContext) -> Result<Self, StageError> {
        Ok(Self { options })
    }
}

impl ImageRegenerator for TestingRegen {
    fn regenerate(
        &mut self,
        frames: &[Frame],
        edges: Option<&[EdgeMap]>,
    ) -> Result<Vec<Frame>, StageError> {
        if self.options.fail {
            return Err(StageError::backend("testing", "no accelerator here"));
        }
        let mut out = Vec::new();
        for (i, frame) in frames.iter().enumerate() {
            let edge = edges.map(|e| &e[i].image);
            let width = frame.width() - u32::from(self.options.shrink);
            let image = image::RgbImage::from_fn(width, frame.height(), |x, y| {
                if edge.is_some_and(|e| e.get_pixel(x, y)[0] > 0) {
                    return [255, 0, 0].into();
                }
                let p = frame.image.get_pixel(x, y);
                [255 - p[0], 255 - p[1], 255 - p[2]].into()
            });
            out.push(Frame::new(frame.index, image));
        }
        Ok(out)
    }
}

gait_plugin::export_regenerator!(TestingRegen);
