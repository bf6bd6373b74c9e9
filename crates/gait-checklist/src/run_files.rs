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
    pub strides: Vec<Stride>,
    /// cycles_all.csv: (side, joint, first frame) -> 101 values.
    pub sagittal: BTreeMap<(Side, String, usize), Vec<f64>>,
    pub spatiotemporal: Vec<Param>,
    /// frontal_angles.csv: `left_trunk_lean` ... -> (frame -> degrees).
    pub frontal: BTreeMap<String, BTreeMap<usize, f64>>,
    pub feet: Vec<FootLength>,
    /// keypoints_filtered.csv: each heel's image y per frame.
    pub heel_y: BTreeMap<Side, BTreeMap<usize, f64>>,
}

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
            ..Default::default()
        };
        if let Some((h, rows)) = read(&dir.join("frontal_view.csv"))? {
            let c = col(&h, "view", "frontal_view.csv")?;
            if let Some(v) = rows.first() {
                r.view = v[c].clone();
            }
        }
        r.strides = strides(dir)?;
        r.heel_y = heels(&dir.join("keypoints_filtered.csv"))?;
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

/// Each heel's image y per frame from a keypoints CSV (DeepLabCut layout: rows
/// `scorer`, `bodyparts`, `coords`, then one row per frame); empty when absent.
fn heels(path: &Path) -> Result<BTreeMap<Side, BTreeMap<usize, f64>>, ChecklistError> {
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
    for sd in Side::BOTH {
        let name = format!("{}_heel", sd.name());
        let Some(c) = (0..parts.len()).find(|&k| parts[k] == name && coords.get(k) == Some("y"))
        else {
            continue;
        };
        let series = rows[3..]
            .iter()
            .filter_map(|row| Some((row.get(0)?.parse().ok()?, num(row.get(c)?))));
        out.insert(sd, series.collect());
    }
    Ok(out)
}
