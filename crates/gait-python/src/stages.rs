//! The stage objects: each wraps one Python instance and implements the
//! matching gait-core stage trait.

use gait_core::pose_layout::PoseLayout;
use gait_core::{
    EdgeDetector, EdgeMap, Frame, ImageRegenerator, Keypoint, PersonBox, Pose, PoseEstimator,
    Resize, StageContext, StageError,
};
use image::{GrayImage, RgbImage};
use pyo3::prelude::*;

use crate::boxes;
use crate::frames::Views;
use crate::interpreter::{self, describe};
use crate::{PythonStageConfig, PythonStageError, output};

/// Loads a `[pose] kind = "python"` stage; its keypoint layout is read and checked once, here.
pub fn load_pose_estimator(
    cfg: &PythonStageConfig,
    _ctx: &StageContext,
) -> Result<Box<dyn PoseEstimator>, StageError> {
    let stage = Stage::load(cfg, Family::POSE)?;
    let takes_boxes = Python::attach(|py| boxes::wanted(py, stage.object.bind(py)));
    let layout = Python::attach(|py| {
        let found: String = stage
            .object
            .bind(py)
            .getattr("keypoints")
            .and_then(|k| k.extract())
            .unwrap_or_default();
        PoseLayout::parse(&found).ok_or_else(|| PythonStageError::Layout {
            found,
            known: PoseLayout::ALL.map(|(n, _)| format!("\"{n}\"")).join(", "),
        })
    })
    .map_err(|e| e.at(&stage.label))?;
    Ok(Box::new(PythonPose {
        names: layout.names(),
        layout,
        stage,
        takes_boxes,
    }))
}

/// Loads an `[edge] kind = "python"` stage.
pub fn load_edge_detector(
    cfg: &PythonStageConfig,
    _ctx: &StageContext,
) -> Result<Box<dyn EdgeDetector>, StageError> {
    Ok(Box::new(PythonEdge {
        stage: Stage::load(cfg, Family::EDGE)?,
    }))
}

/// Loads a `[regenerator] kind = "python"` stage.
pub fn load_regenerator(
    cfg: &PythonStageConfig,
    _ctx: &StageContext,
) -> Result<Box<dyn ImageRegenerator>, StageError> {
    Ok(Box::new(PythonRegenerator {
        stage: Stage::load(cfg, Family::REGENERATOR)?,
    }))
}

/// What a stage family's class must define.
struct Family {
    name: &'static str,
    method: &'static str,
    /// The method's second argument is the edge maps (or None).
    takes_edges: bool,
    signature: &'static str,
}

impl Family {
    const POSE: Family = Family {
        name: "pose",
        method: "estimate",
        takes_edges: false,
        signature: "`keypoints = \"blazepose33\"` (or \"coco17\", \"coco18\") and `estimate(self, frames)` or `estimate(self, frames, boxes)`",
    };
    const EDGE: Family = Family {
        name: "edge",
        method: "detect",
        takes_edges: false,
        signature: "`detect(self, frames)`",
    };
    const REGENERATOR: Family = Family {
        name: "regenerator",
        method: "regenerate",
        takes_edges: true,
        signature: "`regenerate(self, frames, edges)`",
    };
}

/// What a stage's method gets after the frames.
enum Extra<'a> {
    /// Nothing (a pose or edge stage), or `None` where the method takes edges.
    Nothing,
    Edges(&'a [EdgeMap]),
    /// The subject's box per frame (`estimate(self, frames, boxes)`).
    Boxes(&'a [Option<PersonBox>]),
}

/// One Python stage object and numpy, which its arrays come from.
struct Stage {
    label: String,
    method: &'static str,
    takes_edges: bool,
    object: Py<PyAny>,
    numpy: Py<PyModule>,
}

impl Stage {
    fn load(cfg: &PythonStageConfig, family: Family) -> Result<Self, StageError> {
        interpreter::ensure();
        let label = cfg.label();
        Python::attach(|py| {
            let numpy = interpreter::numpy(py)?;
            let object = interpreter::instantiate(py, cfg)?;
            if !object.hasattr(family.method).unwrap_or(false) {
                return Err(PythonStageError::NoMethod {
                    method: family.method,
                    family: family.name,
                    wanted: family.signature,
                });
            }
            Ok(Self {
                label: label.clone(),
                method: family.method,
                takes_edges: family.takes_edges,
                object: object.unbind(),
                numpy: numpy.unbind(),
            })
        })
        .map_err(|e| e.at(&label))
    }

    /// Calls the stage's method on numpy views of `frames` (and `edges`),
    /// then `read`s the result into owned values before the views go.
    fn call<T>(
        &self,
        frames: &[Frame],
        extra: Extra,
        read: impl for<'py> FnOnce(
            &Bound<'py, PyModule>,
            &Bound<'py, PyAny>,
        ) -> Result<T, (usize, String)>,
    ) -> Result<T, StageError> {
        let first = frames.first().map_or(0, |f| f.index);
        let method = self.method;
        Python::attach(|py| {
            let np = self.numpy.bind(py);
            let raised = |e: PyErr| PythonStageError::Raised {
                method,
                frame: first,
                reason: describe(py, &e),
            };
            let views = Views::rgb(np, frames).map_err(raised)?;
            let edge_views = match extra {
                Extra::Edges(e) => Some(Views::gray(np, e).map_err(raised)?),
                _ => None,
            };
            let second = match (&extra, &edge_views) {
                (Extra::Boxes(b), _) => Some(boxes::to_python(py, b).map_err(raised)?),
                (_, Some(v)) => Some(v.list.clone().into_any()),
                _ if self.takes_edges => Some(py.None().into_bound(py)),
                _ => None,
            };
            let object = self.object.bind(py);
            let called = match second {
                Some(arg) => object.call_method1(method, (&views.list, arg)),
                None => object.call_method1(method, (&views.list,)),
            };
            let result = called.map_err(raised).and_then(|r| {
                read(np, &r).map_err(|(frame, reason)| PythonStageError::Malformed {
                    method,
                    frame,
                    reason,
                })
            });
            let kept = !views.release() | !edge_views.is_none_or(|v| v.release());
            match result {
                Ok(_) if kept => Err(PythonStageError::KeptFrame {
                    method,
                    frame: first,
                }),
                other => other,
            }
        })
        .map_err(|e| e.at(&self.label))
    }

    /// Calls an optional method without arguments, if the class has it.
    fn call_optional(&self, name: &str) {
        Python::attach(|py| {
            let object = self.object.bind(py);
            if object.hasattr(name).unwrap_or(false) {
                // A failing reset shows up at the next call, which names the frame.
                let _ = object.call_method0(name);
            }
        })
    }
}

struct PythonPose {
    stage: Stage,
    layout: PoseLayout,
    names: Vec<String>,
    /// `estimate(self, frames, boxes)`: the stage wants the subject's boxes.
    takes_boxes: bool,
}

impl PythonPose {
    /// The poses of `frames` from the stage's `estimate`, with `boxes` as its second argument
    /// when given (the stage takes them).
    fn run(
        &mut self,
        frames: &[Frame],
        boxes: Option<&[Option<PersonBox>]>,
    ) -> Result<Vec<Pose>, StageError> {
        let k = self.layout.native().len();
        let (layout, n) = (self.layout, self.names.len());
        let extra = boxes.map_or(Extra::Nothing, Extra::Boxes);
        self.stage.call(frames, extra, |np, result| {
            let items = output::items(result, frames.len()).map_err(|r| (first(frames), r))?;
            items
                .iter()
                .zip(frames)
                .map(|(item, frame)| {
                    let rows = output::keypoints(np, item, k).map_err(|r| (frame.index, r))?;
                    Ok(match rows {
                        None => Pose::empty(n),
                        Some(rows) => {
                            let native: Vec<Keypoint> = rows
                                .iter()
                                .map(|[x, y, c]| Keypoint::new(*x, *y, *c))
                                .collect();
                            Pose {
                                keypoints: layout.to_keypoints(&native),
                            }
                        }
                    })
                })
                .collect()
        })
    }
}

impl PoseEstimator for PythonPose {
    fn keypoint_names(&self) -> Vec<String> {
        self.names.clone()
    }

    fn estimate(&mut self, frames: &[Frame]) -> Result<Vec<Pose>, StageError> {
        self.run(frames, None)
    }

    /// A stage whose `estimate` takes a second argument gets the subject's box per frame (a
    /// top-down model crops there); either way the frames without the subject are empty.
    fn estimate_subject(
        &mut self,
        frames: &[Frame],
        subject: &[Option<PersonBox>],
    ) -> Result<Vec<Pose>, StageError> {
        let boxes = self.takes_boxes.then_some(subject);
        let mut poses = self.run(frames, boxes)?;
        for (pose, at) in poses.iter_mut().zip(subject) {
            if at.is_none() {
                *pose = Pose::empty(pose.keypoints.len());
            }
        }
        Ok(poses)
    }

    fn reset(&mut self) {
        self.stage.call_optional("reset");
    }
}

struct PythonEdge {
    stage: Stage,
}

impl EdgeDetector for PythonEdge {
    fn detect(&mut self, frames: &[Frame]) -> Result<Vec<EdgeMap>, StageError> {
        let maps = self.stage.call(frames, Extra::Nothing, |np, result| {
            images(np, result, frames, 1)
        })?;
        Ok(maps
            .into_iter()
            .zip(frames)
            .map(|(pixels, frame)| {
                let (w, h) = (frame.width(), frame.height());
                EdgeMap {
                    index: frame.index,
                    image: GrayImage::from_raw(w, h, pixels)
                        .unwrap_or_else(|| GrayImage::new(w, h)),
                    resize: Resize::identity(w, h),
                }
            })
            .collect())
    }
}

struct PythonRegenerator {
    stage: Stage,
}

impl ImageRegenerator for PythonRegenerator {
    fn regenerate(
        &mut self,
        frames: &[Frame],
        edges: Option<&[EdgeMap]>,
    ) -> Result<Vec<Frame>, StageError> {
        let images = self.stage.call(
            frames,
            edges.map_or(Extra::Nothing, Extra::Edges),
            |np, result| images(np, result, frames, 3),
        )?;
        Ok(images
            .into_iter()
            .zip(frames)
            .map(|(pixels, frame)| {
                let (w, h) = (frame.width(), frame.height());
                let image = RgbImage::from_raw(w, h, pixels).unwrap_or_else(|| RgbImage::new(w, h));
                Frame::new(frame.index, image)
            })
            .collect())
    }
}

/// The pixels of one `uint8` image per frame, of the frame's size with
/// `channels` (1: height x width, 3: height x width x 3), checked.
fn images(
    np: &Bound<'_, PyModule>,
    result: &Bound<'_, PyAny>,
    frames: &[Frame],
    channels: usize,
) -> Result<Vec<Vec<u8>>, (usize, String)> {
    let items = output::items(result, frames.len()).map_err(|r| (first(frames), r))?;
    items
        .iter()
        .zip(frames)
        .map(|(item, frame)| {
            let mut shape = vec![frame.height() as usize, frame.width() as usize];
            if channels > 1 {
                shape.push(channels);
            }
            output::image(np, item, &shape).map_err(|r| (frame.index, r))
        })
        .collect()
}

fn first(frames: &[Frame]) -> usize {
    frames.first().map_or(0, |f| f.index)
}
