//! The frontal CSV files: frontal_view.csv (the view and how it was decided),
//! frontal_angles.csv (per frame), frontal_cycles.csv (mean curves),
//! frontal_scalars.csv (per-cycle peaks and ranges, the sides' difference) and
//! frontal_feet.csv (step width per heel strike, circumduction per stride).

use gait_core::table::Table;

use crate::config::Side;
use crate::frontal::{FrontalResult, MEASURES};
use crate::output::{ints, nums, texts};
use crate::view::ViewDecision;

/// The frontal tables, named by their file.
pub fn all(
    f: &FrontalResult,
    v: &ViewDecision,
    first_frame: usize,
    fps: f64,
) -> Vec<(&'static str, Table)> {
    vec![
        ("frontal_view.csv", view(v, f.line_offset_leg)),
        ("frontal_angles.csv", angles(f, first_frame, fps)),
        ("frontal_cycles.csv", cycles(f)),
        ("frontal_scalars.csv", scalars(f)),
        ("frontal_feet.csv", feet(f)),
    ]
}

/// One row: the view analysed and how it was decided (also in run.json), and how far beside
/// the camera the walk's line runs.
fn view(v: &ViewDecision, line_offset_leg: f64) -> Table {
    Table::default()
        .with("view", texts([crate::frontal::view_name(v.view)]))
        .with("declared", texts([v.declared.name()]))
        .with("how", texts([&v.how]))
        .with("frontal_share", nums([v.frontal_share]))
        .with("growth", nums([v.growth]))
        .with("walk_angle_deg", nums([v.walk_angle_deg]))
        .with("line_offset_leg", nums([line_offset_leg]))
}

fn angles(f: &FrontalResult, first_frame: usize, fps: f64) -> Table {
    let n = f.angles.left[0].len();
    let frames: Vec<usize> = (first_frame..first_frame + n).collect();
    let mut t = Table::default()
        .with("frame", ints(frames.iter().copied()))
        .with("time_s", nums(frames.iter().map(|&i| i as f64 / fps)));
    for (k, m) in MEASURES.iter().enumerate() {
        for side in Side::BOTH {
            let name = format!("{}_{m}", side.name());
            t = t.with(&name, nums(f.angles.side(side)[k].iter().copied()));
        }
    }
    t.with("body_size_px", nums(f.size.iter().copied()))
}

fn cycles(f: &FrontalResult) -> Table {
    crate::output::curves_table(&f.cycles, "measure")
}

fn scalars(f: &FrontalResult) -> Table {
    let s = &f.scalars;
    Table::default()
        .with("measure", texts(s.iter().map(|r| &r.measure)))
        .with("statistic", texts(s.iter().map(|r| r.statistic)))
        .with("side", texts(s.iter().map(|r| &r.side)))
        .with("mean", nums(s.iter().map(|r| r.mean)))
        .with("sd", nums(s.iter().map(|r| r.sd)))
        .with("n", ints(s.iter().map(|r| r.n)))
        .with("unit", texts(s.iter().map(|r| &r.unit)))
}

fn feet(f: &FrontalResult) -> Table {
    let r = &f.feet;
    Table::default()
        .with("side", texts(r.iter().map(|r| r.side.name())))
        .with("measure", texts(r.iter().map(|r| r.measure)))
        .with("first_frame", ints(r.iter().map(|r| r.first_frame)))
        .with("last_frame", ints(r.iter().map(|r| r.last_frame)))
        .with("value", nums(r.iter().map(|r| r.value)))
        .with("unit", texts(r.iter().map(|r| r.unit)))
}
