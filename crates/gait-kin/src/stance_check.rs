//! Toe-offs that come too soon after their own foot's heel strike to be walking.

use crate::config::Side;
use crate::event::{Event, EventKind};

/// Removes each toe-off that comes less than `min_share` of a stride after the heel strike of
/// the same foot before it: in walking a foot cannot leave the ground so soon after landing, so
/// such a toe-off comes from mislabelled legs (the other foot's push-off). The stride is the
/// time from that heel strike to the foot's next one, else the median over both feet of the
/// strides between consecutive heel strikes; with no stride at all nothing is removed. `ev`
/// must be sorted by frame.
pub fn drop_implausible_toe_offs(ev: &mut Vec<Event>, min_share: f64) {
    let strikes = |side: Side| -> Vec<usize> {
        ev.iter()
            .filter(|e| e.side == side && e.event == EventKind::HeelStrike)
            .map(|e| e.frame)
            .collect()
    };
    let hs = [strikes(Side::Left), strikes(Side::Right)];
    let mut strides: Vec<f64> = hs
        .iter()
        .flat_map(|f| f.windows(2).map(|w| (w[1] - w[0]) as f64))
        .collect();
    let typical = crate::tracks::median(&mut strides);
    ev.retain(|e| {
        if e.event != EventKind::ToeOff {
            return true;
        }
        let f = &hs[usize::from(e.side == Side::Right)];
        let Some(k) = f.iter().rposition(|&h| h <= e.frame) else {
            return true;
        };
        let stride = f.get(k + 1).map_or(typical, |&next| (next - f[k]) as f64);
        !(stride.is_finite() && ((e.frame - f[k]) as f64) < min_share * stride)
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::toe_offs;

    #[test]
    fn toe_offs_right_after_their_heel_strike_are_dropped() {
        let ev = Event::on_frame;
        let (l, r, hs, to) = (
            Side::Left,
            Side::Right,
            EventKind::HeelStrike,
            EventKind::ToeOff,
        );
        // Left strides of 36 frames: a toe-off 6 frames after the heel strike is the right
        // foot's, mislabelled; the one at 60 % stays. Without a next heel strike the typical
        // stride (median over both feet) decides.
        let mut e = vec![
            ev(l, hs, 100),
            ev(l, to, 106),
            ev(r, to, 110),
            ev(r, hs, 118),
            ev(l, to, 122),
            ev(l, hs, 136),
            ev(l, to, 140),
            ev(r, to, 146),
            ev(r, hs, 154),
            ev(l, to, 158),
        ];
        drop_implausible_toe_offs(&mut e, 0.3);
        let left: Vec<usize> = toe_offs(&e)
            .into_iter()
            .filter(|x| x.0 == l)
            .map(|x| x.1)
            .collect();
        assert_eq!(left, vec![122, 158]);
        // The right toe-offs at 110 (no earlier right heel strike) and 146 (28 frames after
        // its heel strike at 118) stay.
        assert_eq!(toe_offs(&e).iter().filter(|x| x.0 == r).count(), 2);
        // No stride known: nothing to judge by.
        let mut e = vec![ev(l, hs, 10), ev(l, to, 11)];
        drop_implausible_toe_offs(&mut e, 0.3);
        assert_eq!(e.len(), 2);
    }
}
