//! The OpenPose estimator: network + decoding per frame, then the choice of
//! the person to follow (see [`crate::person`]).

use gait_core::{Frame, PersonBox, Pose, PoseEstimator, StageContext, StageError};

use super::config::OpenposeConfig;
use super::decode::{self, Person};
use super::{OpenposeNet, names, net};
use crate::person::{self, Candidate};

/// The OpenPose estimator (implements [`PoseEstimator`]).
pub struct Openpose {
    net: Box<dyn OpenposeNet>,
    config: OpenposeConfig,
    /// Centre of the person followed in the previous frame (pixels).
    last_centre: Option<(f32, f32)>,
}

impl Openpose {
    /// Loads the network named by the config.
    pub fn new(config: &OpenposeConfig, ctx: &StageContext) -> Result<Self, StageError> {
        let path = config.weights(ctx);
        Ok(Self {
            net: net::load_on(&path, config.model, config.backend, ctx.device)?,
            config: config.clone(),
            last_centre: None,
        })
    }

    /// Everybody the network finds in `frame`.
    fn everyone(&mut self, frame: &Frame) -> Result<Vec<Person>, StageError> {
        let net = &mut self.net;
        let found = decode::detect(
            frame,
            self.config.model,
            &self.config.search,
            &mut |input| net.run(input),
        )?;
        Ok(found.people)
    }

    /// The person whose box lies on the subject's, as a pose.
    fn estimate_at(
        &mut self,
        frame: &Frame,
        subject: Option<&PersonBox>,
    ) -> Result<Pose, StageError> {
        let model = self.config.model;
        let Some(s) = subject else {
            return Ok(Pose {
                keypoints: names::to_keypoints(model, &[]),
            });
        };
        let people = self.everyone(frame)?;
        let size = s.size().max(1.0);
        let nearest = people
            .iter()
            .map(|p| {
                let c = candidate(p);
                ((c.cx - s.centre[0]).hypot(c.cy - s.centre[1]), p)
            })
            .filter(|(d, _)| *d < 0.5 * size)
            .min_by(|a, b| a.0.total_cmp(&b.0));
        Ok(Pose {
            keypoints: names::to_keypoints(model, nearest.map_or(&[][..], |(_, p)| &p.keypoints)),
        })
    }

    fn estimate_one(&mut self, frame: &Frame) -> Result<Pose, StageError> {
        let model = self.config.model;
        let net = &mut self.net;
        let found = decode::detect(frame, model, &self.config.search, &mut |input| {
            net.run(input)
        })?;
        let people: Vec<Candidate> = found.people.iter().map(candidate).collect();
        let chosen = person::choose(
            &people,
            self.config.person,
            self.last_centre,
            frame.width(),
            frame.height(),
        );
        let Some(i) = chosen else {
            self.last_centre = None;
            return Ok(Pose {
                keypoints: names::to_keypoints(model, &[]),
            });
        };
        self.last_centre = Some((people[i].cx, people[i].cy));
        Ok(Pose {
            keypoints: names::to_keypoints(model, &found.people[i].keypoints),
        })
    }
}

/// A person's box centre and size from its keypoints.
fn candidate(p: &Person) -> Candidate {
    let pts: Vec<[f32; 3]> = p.keypoints.iter().flatten().copied().collect();
    let span = |k: usize| {
        let lo = pts.iter().map(|q| q[k]).fold(f32::INFINITY, f32::min);
        let hi = pts.iter().map(|q| q[k]).fold(f32::NEG_INFINITY, f32::max);
        (lo, hi)
    };
    let ((x0, x1), (y0, y1)) = (span(0), span(1));
    Candidate {
        cx: (x0 + x1) / 2.0,
        cy: (y0 + y1) / 2.0,
        size: (x1 - x0).max(y1 - y0).max(1.0),
        score: p.score,
    }
}

impl PoseEstimator for Openpose {
    fn keypoint_names(&self) -> Vec<String> {
        names::keypoint_names(self.config.model)
    }

    fn estimate(&mut self, frames: &[Frame]) -> Result<Vec<Pose>, StageError> {
        frames.iter().map(|f| self.estimate_one(f)).collect()
    }

    /// The people's boxes: centre and size of each one's keypoints.
    fn people(&mut self, frame: &Frame) -> Result<Option<Vec<PersonBox>>, StageError> {
        let people = self.everyone(frame)?;
        let boxes = people
            .iter()
            .map(|p| {
                let c = candidate(p);
                // A keypoint box is tighter than a body crop; the detector's
                // crops (BlazePose) hold the body with a margin.
                PersonBox::upright(c.cx, c.cy, 1.25 * c.size, p.score / p.parts.max(1) as f32)
            })
            .collect();
        Ok(Some(boxes))
    }

    fn estimate_subject(
        &mut self,
        frames: &[Frame],
        subject: &[Option<PersonBox>],
    ) -> Result<Vec<Pose>, StageError> {
        frames
            .iter()
            .zip(subject)
            .map(|(f, s)| self.estimate_at(f, s.as_ref()))
            .collect()
    }

    fn reset(&mut self) {
        self.last_centre = None;
    }

    /// Little-endian f32s: presence flag, centre x, centre y.
    fn state(&self) -> Option<Vec<u8>> {
        let v = self.last_centre.map_or([0.0; 3], |(x, y)| [1.0, x, y]);
        Some(v.iter().flat_map(|f| f.to_le_bytes()).collect())
    }

    fn restore(&mut self, state: &[u8]) -> bool {
        if state.len() != 12 {
            return false;
        }
        let v: Vec<f32> = state
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        self.last_centre = (v[0] == 1.0).then_some((v[1], v[2]));
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_of_found_keypoints() {
        let p = Person {
            keypoints: vec![Some([10.0, 20.0, 0.9]), None, Some([30.0, 60.0, 0.5])],
            peak_ids: vec![Some(0), None, Some(1)],
            score: 3.0,
            parts: 2,
        };
        let c = candidate(&p);
        assert_eq!((c.cx, c.cy, c.size, c.score), (20.0, 40.0, 40.0, 3.0));
    }
}
