//! Left and right in a front or back view. The hips never cross: facing the camera the
//! subject's left hip is on the image right, from behind on the image left. A frame whose hip
//! labels say otherwise (a pose model unsure whether it sees a face or a back) has all its
//! leg labels exchanged.

use crate::config::Side;
use crate::swap::swap_frame;
use crate::tracks::Tracks;
use crate::view::View;

/// Exchanges the leg labels of every frame whose hips contradict `view`; returns those frames.
pub fn fix(t: &mut Tracks, view: View) -> Vec<bool> {
    let n = t.len();
    let mut swapped = vec![false; n];
    let (Some(lh), Some(rh)) = (
        t.leg_index(Side::Left, "hip"),
        t.leg_index(Side::Right, "hip"),
    ) else {
        return swapped;
    };
    for (i, s) in swapped.iter_mut().enumerate() {
        if let (Some(l), Some(r)) = (t.at(lh, i), t.at(rh, i))
            && view.left_sign() * (l.0 - r.0) < 0.0
        {
            swap_frame(t, i);
            if let (Some(a), Some(b)) = (t.index("left_shoulder"), t.index("right_shoulder")) {
                for v in [&mut t.x, &mut t.y, &mut t.likelihood] {
                    let tmp = v[a][i];
                    v[a][i] = v[b][i];
                    v[b][i] = tmp;
                }
            }
            *s = true;
        }
    }
    swapped
}
