//! The steps [`crate::analyse`] uses, built from the configuration.

use crate::config::{FilterKind, GapFillKind, KinematicsConfig, PostprocessConfig};
use crate::smooth::Smoother;
use crate::spline::GapFiller;
use crate::swap::{ContinuitySwap, SwapCorrector};
use crate::{Steps, ZeniRefined, butterworth, likelihood, one_euro, smooth, spline};

/// Calls `f` with the steps that `post` and `kin` configure.
pub(crate) fn with_configured<R>(
    post: &PostprocessConfig,
    kin: &KinematicsConfig,
    f: impl FnOnce(&Steps) -> R,
) -> R {
    let gate = likelihood::LikelihoodThreshold(post.likelihood_threshold);
    let swap = ContinuitySwap::default();
    let gap: Box<dyn GapFiller> = match post.gap_fill {
        GapFillKind::CubicSpline => Box::new(spline::CubicSplineFill),
        GapFillKind::Linear => Box::new(spline::LinearFill),
        GapFillKind::None => Box::new(spline::NoFill),
    };
    let smoother: Box<dyn Smoother> = match post.filter {
        FilterKind::Butterworth => Box::new(butterworth::Butterworth {
            order: post.butterworth_order,
            cutoff_hz: post.cutoff_hz,
        }),
        FilterKind::OneEuro => Box::new(one_euro::OneEuro {
            min_cutoff_hz: post.one_euro_min_cutoff_hz,
            beta: post.one_euro_beta,
            d_cutoff_hz: post.one_euro_d_cutoff_hz,
        }),
        FilterKind::None => Box::new(smooth::Identity),
    };
    let detector = ZeniRefined {
        min_stride_s: kin.min_stride_s,
        ..ZeniRefined::default()
    };
    let steps = Steps {
        gate: &gate,
        swap: post.swap_correction.then_some(&swap as &dyn SwapCorrector),
        gap_filler: gap.as_ref(),
        smoother: smoother.as_ref(),
        events: &detector,
    };
    f(&steps)
}
