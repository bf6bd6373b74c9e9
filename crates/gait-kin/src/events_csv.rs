//! A user's gait events, read from `side,event,frame` CSV (`kinematics.events_csv`).

use std::path::Path;

use crate::KinError;
use crate::config::Side;
use crate::event::{Event, EventKind, sort};

/// Reads `side,event,frame[,time_s]` (header required; extra columns ignored).
pub fn read_csv(path: &Path) -> Result<Vec<Event>, KinError> {
    let bad = |why: String| KinError::EventsCsv {
        path: path.to_path_buf(),
        reason: why,
    };
    let mut r = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| bad(e.to_string()))?;
    let headers = r.headers().map_err(|e| bad(e.to_string()))?.clone();
    let col = |name: &str| {
        headers
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| bad(format!("no `{name}` column (need side,event,frame)")))
    };
    let (cs, ce, cf) = (col("side")?, col("event")?, col("frame")?);
    let mut out = Vec::new();
    for (row, rec) in r.records().enumerate() {
        let rec = rec.map_err(|e| bad(e.to_string()))?;
        let line = row + 2;
        let get = |c: usize| rec.get(c).unwrap_or("");
        let side = match get(cs) {
            "left" => Side::Left,
            "right" => Side::Right,
            s => return Err(bad(format!("line {line}: side `{s}` is not left or right"))),
        };
        let event = match get(ce) {
            "heel_strike" => EventKind::HeelStrike,
            "toe_off" => EventKind::ToeOff,
            s => {
                return Err(bad(format!(
                    "line {line}: event `{s}` is not heel_strike or toe_off"
                )));
            }
        };
        let frame = get(cf).parse::<usize>().map_err(|_| {
            bad(format!(
                "line {line}: frame `{}` is not a frame number",
                get(cf)
            ))
        })?;
        out.push(Event::on_frame(side, event, frame));
    }
    sort(&mut out);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_and_rejects_event_files() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("e.csv");
        std::fs::write(
            &p,
            "side,event,frame,time_s\nright,toe_off,20,0.6\nleft,heel_strike,3,0.1\n",
        )
        .unwrap();
        let ev = read_csv(&p).unwrap();
        assert_eq!(ev[0], Event::on_frame(Side::Left, EventKind::HeelStrike, 3));
        std::fs::write(&p, "side,event,frame\nleft,foot_flat,3\n").unwrap();
        let e = read_csv(&p).unwrap_err().to_string();
        assert!(e.contains("foot_flat") && e.contains("line 2"), "{e}");
        std::fs::write(&p, "side,kind\n").unwrap();
        assert!(read_csv(&p).unwrap_err().to_string().contains("`event`"));
    }
}
