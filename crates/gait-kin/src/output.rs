//! The CSV files of `gait kin` as tables (also what Python's DataFrames are
//! made from), each written to a temporary name and renamed when complete.

use std::fs;
use std::path::Path;

use gait_core::table::{Column, Table};

use crate::{KinError, KinResult};

/// Writes `name` in `dir` atomically, so a crash never leaves a complete-looking file.
fn atomic(
    dir: &Path,
    name: &str,
    fill: impl FnOnce(&mut Vec<u8>) -> Result<(), KinError>,
) -> Result<(), KinError> {
    let mut buf = Vec::new();
    fill(&mut buf)?;
    let dst = dir.join(name);
    gait_core::atomic::write(&dst, &buf).map_err(|e| KinError::Io {
        context: format!("writing {}", dst.display()),
        source: e,
    })
}

pub(crate) fn ints(values: impl IntoIterator<Item = usize>) -> Column {
    Column::Int(values.into_iter().map(|v| v as i64).collect())
}

pub(crate) fn nums(values: impl IntoIterator<Item = f64>) -> Column {
    Column::Num(values.into_iter().collect())
}

pub(crate) fn texts<S: ToString>(values: impl IntoIterator<Item = S>) -> Column {
    Column::Text(values.into_iter().map(|v| v.to_string()).collect())
}

/// The tables of a result, named by their file: angles.csv, events.csv,
/// bouts.csv, cycle_quality.csv, cycles.csv, cycles_all.csv (every accepted
/// cycle) and spatiotemporal.csv; a front or back view's also the frontal_*.csv files of
/// [`crate::frontal::tables`].
pub fn tables(r: &KinResult) -> Vec<(&'static str, Table)> {
    let mut all = vec![
        ("angles.csv", angles(r)),
        ("events.csv", events(r)),
        ("bouts.csv", bouts(r)),
        ("cycle_quality.csv", cycle_quality(r)),
        ("cycles.csv", cycles(r)),
        ("cycles_all.csv", cycles_all(r)),
        ("spatiotemporal.csv", spatiotemporal(r)),
    ];
    if let Some(f) = &r.frontal {
        all.extend(crate::frontal::tables::all(
            f,
            &r.view,
            r.first_frame,
            r.fps,
        ));
    }
    all
}

fn angles(r: &KinResult) -> Table {
    let a = &r.angles;
    let frames: Vec<usize> = (0..a.left.hip.len()).map(|i| r.first_frame + i).collect();
    Table::default()
        .with("frame", ints(frames.iter().copied()))
        .with("time_s", nums(frames.iter().map(|&f| f as f64 / r.fps)))
        .with("left_hip", nums(a.left.hip.iter().copied()))
        .with("right_hip", nums(a.right.hip.iter().copied()))
        .with("left_knee", nums(a.left.knee.iter().copied()))
        .with("right_knee", nums(a.right.knee.iter().copied()))
        .with("left_ankle", nums(a.left.ankle.iter().copied()))
        .with("right_ankle", nums(a.right.ankle.iter().copied()))
}

fn events(r: &KinResult) -> Table {
    let e = &r.events;
    Table::default()
        .with("side", texts(e.iter().map(|e| e.side.name())))
        .with("event", texts(e.iter().map(|e| e.event.name())))
        .with("frame", ints(e.iter().map(|e| e.frame)))
        .with("time_s", nums(e.iter().map(|e| e.time() / r.fps)))
}

fn bouts(r: &KinResult) -> Table {
    let b = &r.bouts;
    let direction = |d: crate::Direction| match d {
        crate::Direction::Right => "right",
        crate::Direction::Left => "left",
        crate::Direction::Unknown => "unknown",
    };
    Table::default()
        .with("bout", ints(0..b.len()))
        .with("first", ints(b.iter().map(|b| b.first)))
        .with("last", ints(b.iter().map(|b| b.last)))
        .with("direction", texts(b.iter().map(|b| direction(b.direction))))
        .with("mean_speed", nums(b.iter().map(|b| b.mean_speed)))
}

fn cycle_quality(r: &KinResult) -> Table {
    let q = &r.cycle_quality;
    let reasons = q.iter().map(|q| {
        let names: Vec<&str> = q.reasons.iter().map(|r| r.name()).collect();
        names.join(";")
    });
    let table = Table::default()
        .with("side", texts(q.iter().map(|q| q.side.name())))
        .with("first_frame", ints(q.iter().map(|q| q.first_frame)))
        .with("last_frame", ints(q.iter().map(|q| q.last_frame)))
        .with(
            "accepted",
            Column::Bool(q.iter().map(|q| q.accepted).collect()),
        )
        .with("reasons", texts(reasons))
        .with("stride_s", nums(q.iter().map(|q| q.stride_s)))
        .with(
            "stride_deviation",
            nums(q.iter().map(|q| q.stride_deviation)),
        )
        .with("max_filled_s", nums(q.iter().map(|q| q.max_filled_s)))
        .with("mean_likelihood", nums(q.iter().map(|q| q.mean_likelihood)))
        .with("thigh_ratio", nums(q.iter().map(|q| q.thigh_ratio)))
        .with("shank_ratio", nums(q.iter().map(|q| q.shank_ratio)))
        .with("leg_px", nums(q.iter().map(|q| q.leg_px)))
        .with("blur_px", nums(q.iter().map(|q| q.blur_px)))
        .with("swing_contrast", nums(q.iter().map(|q| q.swing_contrast)))
        .with("swapped_frames", ints(q.iter().map(|q| q.swapped_frames)))
        .with("unsure_frames", ints(q.iter().map(|q| q.unsure_frames)))
        .with(
            "bout",
            Column::OptInt(q.iter().map(|q| q.bout.map(|b| b as i64)).collect()),
        );
    // A front or back view says which frontal measures a cycle has no value for, and why.
    match &r.frontal {
        Some(f) => table.with("frontal_missing", texts(f.cycle_notes.iter())),
        None => table,
    }
}

/// One row per side, joint and percent of the mean cycle.
fn cycles(r: &KinResult) -> Table {
    curves_table(&r.cycles, "joint")
}

/// Mean curves, one row per side, curve (named in column `key`) and percent of the cycle.
pub(crate) fn curves_table(curves: &[crate::CycleCurve], key: &str) -> Table {
    let rows: Vec<(&crate::CycleCurve, usize)> = curves
        .iter()
        .flat_map(|c| (0..c.mean.len()).map(move |p| (c, p)))
        .collect();
    Table::default()
        .with("side", texts(rows.iter().map(|(c, _)| c.side.name())))
        .with(key, texts(rows.iter().map(|(c, _)| &c.joint)))
        .with("percent", ints(rows.iter().map(|(_, p)| *p)))
        .with("mean", nums(rows.iter().map(|(c, p)| c.mean[*p])))
        .with("sd", nums(rows.iter().map(|(c, p)| c.sd[*p])))
        .with("n_cycles", ints(rows.iter().map(|(c, _)| c.n_cycles)))
}

/// One row per accepted stride, joint and percent of the cycle (input frame numbers).
fn cycles_all(r: &KinResult) -> Table {
    let accepted = crate::quality::accepted(&r.cycle_quality);
    let curves = crate::cycles::each(&r.angles, r.first_frame, &accepted);
    let rows: Vec<(&_, usize, f64)> = curves
        .iter()
        .flat_map(|c| c.values.iter().enumerate().map(move |(p, v)| (c, p, *v)))
        .collect();
    Table::default()
        .with(
            "side",
            texts(rows.iter().map(|(c, _, _)| c.stride.side.name())),
        )
        .with("joint", texts(rows.iter().map(|(c, _, _)| &c.joint)))
        .with(
            "first_frame",
            ints(rows.iter().map(|(c, _, _)| c.stride.start)),
        )
        .with(
            "last_frame",
            ints(rows.iter().map(|(c, _, _)| c.stride.end)),
        )
        .with("percent", ints(rows.iter().map(|(_, p, _)| *p)))
        .with("value", nums(rows.iter().map(|(_, _, v)| *v)))
}

fn spatiotemporal(r: &KinResult) -> Table {
    let s = &r.spatiotemporal;
    Table::default()
        .with("parameter", texts(s.iter().map(|p| &p.parameter)))
        .with("side", texts(s.iter().map(|p| &p.side)))
        .with("mean", nums(s.iter().map(|p| p.mean)))
        .with("sd", nums(s.iter().map(|p| p.sd)))
        .with("n", ints(s.iter().map(|p| p.n)))
        .with("unit", texts(s.iter().map(|p| &p.unit)))
}

/// Writes every table of [`tables`], then keypoints_filtered.csv.
pub fn write_outputs(r: &KinResult, out_dir: &Path) -> Result<(), KinError> {
    fs::create_dir_all(out_dir).map_err(|e| KinError::Io {
        context: format!("creating {}", out_dir.display()),
        source: e,
    })?;
    for (name, table) in tables(r) {
        atomic(out_dir, name, |b| {
            b.extend_from_slice(&table.to_csv());
            Ok(())
        })?;
    }
    atomic(out_dir, "keypoints_filtered.csv", |b| {
        gait_core::dlc::write(&mut *b, "gait-kin", &r.filtered).map_err(|e| KinError::Io {
            context: "writing keypoints_filtered.csv".into(),
            source: std::io::Error::other(e.to_string()),
        })
    })?;
    Ok(())
}
