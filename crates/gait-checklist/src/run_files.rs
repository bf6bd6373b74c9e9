//! What the checklist reads from a run folder (`gait run`, `gait kin`, a batch row): the files
//! a reader of the folder gets, so the checklist of any run can be made again from them.

use std::collections::BTreeMap;
use std::path::Path;

use crate::{ChecklistError, Side};

/// One stride of cycle_quality.csv that passed the quality checks (input frames).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stride {
    pub side: Side,
    pub first: usize,
    pub last: usize,
    /// The side's toe-off inside the stride, as a fraction of it (events.csv).
    pub toe_off: Option<f64>,
    /// Thigh + shank in the image (cycle_quality.csv's `leg_px`; NaN when absent).
    pub leg_px: f64,
}

/// A row of spatiotemporal.csv.
#[derive(Debug, Clone)]
pub struct Param {
    pub parameter: String,
    pub side: String,
    pub mean: f64,
    pub sd: f64,
    pub n: usize,
    pub unit: String,
}

/// A row of frontal_feet.csv.
#[derive(Debug, Clone)]
pub struct FootLength {
    pub side: Side,
    pub measure: String,
    pub first: usize,
    pub value: f64,
    pub unit: String,
}

/// The run folder's measures.
#[derive(Debug, Clone, Default)]
pub struct RunFiles {
    /// `sagittal`, `anterior` or `posterior`.
    pub view: String,
    /// The walk's angle to the camera's axis (frontal_view.csv, else run.json or kin.json; NaN
    /// where not known).
    pub walk_angle_deg: f64,
    /// A front or back view's walking line beside the camera, in leg lengths (frontal_view.csv;
    /// NaN where not known).
    pub line_offset_leg: f64,
    pub strides: Vec<Stride>,
    /// cycles_all.csv: (side, joint, first frame) -> 101 values.
    pub sagittal: BTreeMap<(Side, String, usize), Vec<f64>>,
    pub spatiotemporal: Vec<Param>,
    /// frontal_angles.csv: `left_trunk_lean` ... -> (frame -> degrees).
    pub frontal: BTreeMap<String, BTreeMap<usize, f64>>,
    pub feet: Vec<FootLength>,
    /// keypoints_filtered.csv: each heel's image y per frame.
    pub heel_y: BTreeMap<Side, BTreeMap<usize, f64>>,
    /// keypoints_filtered.csv: the image (x, y) per frame of the keypoints in [`POINTS`]
    /// that the run has.
    pub points: BTreeMap<String, BTreeMap<usize, [f64; 2]>>,
    /// bouts.csv: (first, last, +1 walking to the image right or -1 to the left).
    pub bouts: Vec<(usize, usize, f64)>,
}

/// The keypoints the trunk, arm and foot items read (BlazePose's wrists under their `bp_` names).
pub const POINTS: [&str; 11] = [
    "left_shoulder",
    "right_shoulder",
    "mid_hip",
    "left_heel",
    "right_heel",
    "left_toe",
    "right_toe",
    "left_hip",
    "right_hip",
    "bp_left_wrist",
    "bp_right_wrist",
];

type Rows = (Vec<String>, Vec<Vec<String>>);

/// A CSV's header and rows; `None` when the file is absent.
fn read(path: &Path) -> Result<Option<Rows>, ChecklistError> {
    if !path.exists() {
        return Ok(None);
    }
    let bad = |e: csv::Error| ChecklistError::Input(format!("{}: {e}", path.display()));
    let mut r = csv::Reader::from_path(path).map_err(bad)?;
    let header = r.headers().map_err(bad)?.iter().map(String::from).collect();
    let rows = r
        .records()
        .map(|rec| rec.map(|rec| rec.iter().map(String::from).collect()))
        .collect::<Result<_, _>>()
        .map_err(bad)?;
    Ok(Some((header, rows)))
}

/// Column `name` of a header, or an error naming the file.
fn col(h: &[String], name: &str, file: &str) -> Result<usize, ChecklistError> {
    h.iter()
        .position(|c| c == name)
        .ok_or_else(|| ChecklistError::Input(format!("{file}: no `{name}` column")))
}

/// The walk's angle to the camera's axis from a run's run.json (its kinematics' view decision)
/// or a `gait kin` folder's kin.json; NaN where neither says (folders written before either
/// did; a side view has no frontal_view.csv).
fn manifest_walk_angle(dir: &Path) -> f64 {
    let read = |file: &str, path: &[&str]| -> Option<f64> {
        let text = std::fs::read_to_string(dir.join(file)).ok()?;
        let json: serde_json::Value = serde_json::from_str(&text).ok()?;
        path.iter().try_fold(&json, |v, key| v.get(key))?.as_f64()
    };
    read(
        "run.json",
        &["extra", "kinematics", "view", "walk_angle_deg"],
    )
    .or_else(|| read("kin.json", &["view", "walk_angle_deg"]))
    .unwrap_or(f64::NAN)
}

fn num(s: &str) -> f64 {
    s.trim().parse().unwrap_or(f64::NAN)
}

fn side(s: &str) -> Option<Side> {
    match s {
        "left" => Some(Side::Left),
        "right" => Some(Side::Right),
        _ => None,
    }
}

impl RunFiles {
    /// Reads `dir`; absent files leave their part empty.
    pub fn read(dir: &Path) -> Result<Self, ChecklistError> {
        let mut r = RunFiles {
            view: "sagittal".into(),
            walk_angle_deg: f64::NAN,
            line_offset_leg: f64::NAN,
            ..Default::default()
        };
        if let Some((h, rows)) = read(&dir.join("frontal_view.csv"))? {
            let c = col(&h, "view", "frontal_view.csv")?;
            // Run folders written before the walk's angle was estimated have no such column.
            let angle = h.iter().position(|x| x == "walk_angle_deg");
            let offset = h.iter().position(|x| x == "line_offset_leg");
            if let Some(v) = rows.first() {
                r.view = v[c].clone();
                r.walk_angle_deg = angle.map_or(f64::NAN, |a| num(&v[a]));
                r.line_offset_leg = offset.map_or(f64::NAN, |a| num(&v[a]));
            }
        }
        if r.walk_angle_deg.is_nan() {
            r.walk_angle_deg = manifest_walk_angle(dir);
        }
        r.strides = strides(dir)?;
        r.points = points(&dir.join("keypoints_filtered.csv"))?;
        for sd in Side::BOTH {
            if let Some(p) = r.points.get(&format!("{}_heel", sd.name())) {
                r.heel_y
                    .insert(sd, p.iter().map(|(&f, xy)| (f, xy[1])).collect());
            }
        }
        if let Some((h, rows)) = read(&dir.join("bouts.csv"))? {
            let f = "bouts.csv";
            let (a, b, d) = (
                col(&h, "first", f)?,
                col(&h, "last", f)?,
                col(&h, "direction", f)?,
            );
            r.bouts = rows
                .iter()
                .filter_map(|row| {
                    let sign = match row[d].as_str() {
                        "right" => 1.0,
                        "left" => -1.0,
                        _ => return None,
                    };
                    Some((num(&row[a]) as usize, num(&row[b]) as usize, sign))
                })
                .collect();
        }
        if let Some((h, rows)) = read(&dir.join("cycles_all.csv"))? {
            let f = "cycles_all.csv";
            let [s, j, first, p, v] =
                ["side", "joint", "first_frame", "percent", "value"].map(|n| col(&h, n, f));
            let (s, j, first, p, v) = (s?, j?, first?, p?, v?);
            for row in rows {
                let Some(sd) = side(&row[s]) else { continue };
                let key = (sd, row[j].clone(), num(&row[first]) as usize);
                let curve = r.sagittal.entry(key).or_insert_with(|| vec![f64::NAN; 101]);
                let k = num(&row[p]) as usize;
                if k < 101 {
                    curve[k] = num(&row[v]);
                }
            }
        }
        if let Some((h, rows)) = read(&dir.join("spatiotemporal.csv"))? {
            let f = "spatiotemporal.csv";
            let (p, s, m, sd, u) = (
                col(&h, "parameter", f)?,
                col(&h, "side", f)?,
                col(&h, "mean", f)?,
                col(&h, "sd", f)?,
                col(&h, "unit", f)?,
            );
            let n = col(&h, "n", f)?;
            r.spatiotemporal = rows
                .iter()
                .map(|row| Param {
                    parameter: row[p].clone(),
                    side: row[s].clone(),
                    mean: num(&row[m]),
                    sd: num(&row[sd]),
                    n: num(&row[n]) as usize,
                    unit: row[u].clone(),
                })
                .collect();
        }
        if let Some((h, rows)) = read(&dir.join("frontal_angles.csv"))? {
            let frame = col(&h, "frame", "frontal_angles.csv")?;
            for (k, name) in h.iter().enumerate() {
                if name.starts_with("left_") || name.starts_with("right_") {
                    let series = rows
                        .iter()
                        .map(|row| (num(&row[frame]) as usize, num(&row[k])));
                    r.frontal.insert(name.clone(), series.collect());
                }
            }
        }
        if let Some((h, rows)) = read(&dir.join("frontal_feet.csv"))? {
            let f = "frontal_feet.csv";
            let (s, m, first, v, u) = (
                col(&h, "side", f)?,
                col(&h, "measure", f)?,
                col(&h, "first_frame", f)?,
                col(&h, "value", f)?,
                col(&h, "unit", f)?,
            );
            r.feet = rows
                .iter()
                .filter_map(|row| {
                    Some(FootLength {
                        side: side(&row[s])?,
                        measure: row[m].clone(),
                        first: num(&row[first]) as usize,
                        value: num(&row[v]),
                        unit: row[u].clone(),
                    })
                })
                .collect();
        }
        Ok(r)
    }

    /// The accepted strides of `side`.
    pub fn strides_of(&self, side: Side) -> impl Iterator<Item = &Stride> {
        self.strides.iter().filter(move |s| s.side == side)
    }

    /// +1 when the walker goes to the image right at `frame`, -1 to the left, `None` outside
    /// the bouts.
    pub fn direction(&self, frame: usize) -> Option<f64> {
        self.bouts
            .iter()
            .find(|(a, b, _)| (*a..=*b).contains(&frame))
            .map(|b| b.2)
    }

    /// Keypoint `name` at `frame`, when seen.
    pub fn at(&self, name: &str, frame: usize) -> Option<[f64; 2]> {
        let p = *self.points.get(name)?.get(&frame)?;
        (p[0].is_finite() && p[1].is_finite()).then_some(p)
    }

    /// A spatiotemporal row.
    pub fn param(&self, parameter: &str, side: &str) -> Option<&Param> {
        self.spatiotemporal
            .iter()
            .find(|p| p.parameter == parameter && p.side == side)
    }
}

/// The accepted strides of cycle_quality.csv with their toe-offs from events.csv.
fn strides(dir: &Path) -> Result<Vec<Stride>, ChecklistError> {
    let Some((h, rows)) = read(&dir.join("cycle_quality.csv"))? else {
        return Ok(Vec::new());
    };
    let f = "cycle_quality.csv";
    let (s, a, b, ok) = (
        col(&h, "side", f)?,
        col(&h, "first_frame", f)?,
        col(&h, "last_frame", f)?,
        col(&h, "accepted", f)?,
    );
    let leg = h.iter().position(|c| c == "leg_px");
    let mut toe_offs: Vec<(Side, usize)> = Vec::new();
    if let Some((eh, erows)) = read(&dir.join("events.csv"))? {
        let (es, ee, ef) = (
            col(&eh, "side", "events.csv")?,
            col(&eh, "event", "events.csv")?,
            col(&eh, "frame", "events.csv")?,
        );
        toe_offs = erows
            .iter()
            .filter(|r| r[ee] == "toe_off")
            .filter_map(|r| Some((side(&r[es])?, num(&r[ef]) as usize)))
            .collect();
    }
    Ok(rows
        .iter()
        .filter(|row| row[ok] == "true")
        .filter_map(|row| {
            let sd = side(&row[s])?;
            let (first, last) = (num(&row[a]) as usize, num(&row[b]) as usize);
            let toe_off = toe_offs
                .iter()
                .find(|(ts, f)| *ts == sd && *f > first && *f < last)
                .map(|(_, f)| (f - first) as f64 / (last - first) as f64);
            Some(Stride {
                side: sd,
                first,
                last,
                toe_off,
                leg_px: leg.map_or(f64::NAN, |c| num(&row[c])),
            })
        })
        .collect())
}

/// The [`POINTS`] of a keypoints CSV (DeepLabCut layout: rows `scorer`, `bodyparts`, `coords`,
/// then one row per frame), per frame; empty when absent. Points at (0, 0) are motion capture's
/// missing markers and are left out.
fn points(path: &Path) -> Result<BTreeMap<String, BTreeMap<usize, [f64; 2]>>, ChecklistError> {
    let mut out = BTreeMap::new();
    if !path.exists() {
        return Ok(out);
    }
    let bad = |e: csv::Error| ChecklistError::Input(format!("{}: {e}", path.display()));
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_path(path)
        .map_err(bad)?;
    let rows: Vec<csv::StringRecord> = r.records().collect::<Result<_, _>>().map_err(bad)?;
    let (Some(parts), Some(coords)) = (rows.get(1), rows.get(2)) else {
        return Ok(out);
    };
    for name in POINTS {
        let find =
            |c: &str| (0..parts.len()).find(|&k| &parts[k] == name && coords.get(k) == Some(c));
        let (Some(cx), Some(cy)) = (find("x"), find("y")) else {
            continue;
        };
        let series: BTreeMap<usize, [f64; 2]> = rows[3..]
            .iter()
            .filter_map(|row| {
                let xy = [num(row.get(cx)?), num(row.get(cy)?)];
                (xy != [0.0, 0.0]).then_some((row.get(0)?.parse().ok()?, xy))
            })
            .collect();
        if !series.is_empty() {
            out.insert(name.to_string(), series);
        }
    }
    Ok(out)
}
