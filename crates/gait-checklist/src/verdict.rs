//! One checklist item's verdict on one side, and how verdicts are written (checklist.csv).

use serde::Serialize;

use crate::Side;

/// Whether a deviation is there.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    Present,
    Absent,
    /// The view, the cycles or the keypoints it needs are missing (`reason` says which).
    NotAssessable,
}

impl Status {
    pub fn name(self) -> &'static str {
        match self {
            Status::Present => "present",
            Status::Absent => "absent",
            Status::NotAssessable => "not assessable",
        }
    }
}

/// A checklist item as the published lists name it, and how gait measures it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Item {
    pub id: &'static str,
    pub name: &'static str,
    /// The measure and its formula, in words.
    pub measure: &'static str,
    pub unit: &'static str,
    /// `front or back` or `side`: the view that shows it.
    pub view: &'static str,
    /// `transtibial`, `transfemoral` or `both`: the amputation levels the lists give it for.
    pub amputation: &'static str,
    /// Judged by comparing the two sides (a symmetry index, one side over the other): both
    /// sides' verdicts must come from one judgement, never one side from each of two runs.
    pub paired: bool,
}

/// One item's verdict on one side.
#[derive(Debug, Clone, Serialize)]
pub struct Verdict {
    pub item: Item,
    pub side: Side,
    pub status: Status,
    /// Mean over the side's cycles (or steps), and their SD.
    pub value: f64,
    pub spread: f64,
    /// How many cycles (or steps) the value is the mean of.
    pub n: usize,
    /// The unit of value, spread and threshold (the item's, or leg lengths without a scale).
    pub unit: String,
    pub threshold: f64,
    /// The threshold's unit: the value's, or `%` for a symmetry index.
    pub threshold_unit: String,
    /// `above` or `below`: which side of the threshold is the deviation.
    pub beyond: &'static str,
    /// Where the threshold comes from.
    pub source: String,
    /// First frame of each cycle (or step) in which the measure passes the threshold, and the
    /// frame where it does most.
    pub cycles: Vec<usize>,
    pub frames: Vec<usize>,
    /// Why it is not assessable.
    pub reason: String,
    /// The run folder the frames are in (`gait review RUN --frame N` opens one).
    pub run: String,
    /// The mean the threshold was applied to where it is not `value`: an item judged on sizes
    /// whose reported value keeps its sign (the whip: lateral +, medial -). Passes pool on it.
    #[serde(skip)]
    pub judged: Option<f64>,
}

impl Verdict {
    /// An item that cannot be judged, for `reason`.
    pub fn not_assessable(item: Item, side: Side, reason: impl Into<String>) -> Self {
        Self {
            item,
            side,
            status: Status::NotAssessable,
            value: f64::NAN,
            spread: f64::NAN,
            n: 0,
            unit: item.unit.into(),
            threshold: f64::NAN,
            threshold_unit: item.unit.into(),
            beyond: "above",
            source: String::new(),
            cycles: Vec::new(),
            frames: Vec::new(),
            reason: reason.into(),
            run: String::new(),
            judged: None,
        }
    }
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3}")
    } else {
        String::new()
    }
}

fn list(v: &[usize]) -> String {
    v.iter().map(usize::to_string).collect::<Vec<_>>().join(";")
}

/// checklist.csv: one row per item and side.
pub fn csv(verdicts: &[Verdict]) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    let _ = w.write_record([
        "item",
        "side",
        "verdict",
        "measure",
        "value",
        "spread",
        "n",
        "unit",
        "threshold",
        "threshold_unit",
        "beyond",
        "source",
        "cycles",
        "frames",
        "view",
        "amputation",
        "reason",
    ]);
    for v in verdicts {
        let _ = w.write_record([
            v.item.id,
            v.side.name(),
            v.status.name(),
            v.item.measure,
            &num(v.value),
            &num(v.spread),
            &v.n.to_string(),
            &v.unit,
            &num(v.threshold),
            &v.threshold_unit,
            v.beyond,
            &v.source,
            &list(&v.cycles),
            &list(&v.frames),
            v.item.view,
            v.item.amputation,
            &v.reason,
        ]);
    }
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}
