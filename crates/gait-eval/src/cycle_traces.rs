//! Every accepted cycle's curve (gait-kin's `cycles_all.csv`), for the
//! all-cycles ("consistency") plot.

use std::path::Path;

use crate::EvalError;
use crate::names::Side;

/// One joint's angle over one accepted stride, 101 points.
#[derive(Debug, Clone, PartialEq)]
pub struct CycleTrace {
    pub side: Side,
    pub joint: String,
    /// Input frame of the stride's first heel strike.
    pub first_frame: usize,
    pub values: Vec<f64>,
}

/// The header gait-kin writes.
const HEADER: &str = "side,joint,first_frame,last_frame,percent,value";

/// Reads `cycles_all.csv`; rows of one side, joint and first frame form a trace.
pub fn read_cycles_all_csv(path: &Path) -> Result<Vec<CycleTrace>, EvalError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| EvalError::io(format!("reading {}", path.display()), e))?;
    let mut lines = text.lines().enumerate();
    let first = lines.next().map(|(_, l)| l.trim()).unwrap_or("");
    if first != HEADER {
        return Err(EvalError::input(
            path,
            format!("the header is `{first}`; expected `{HEADER}`"),
        ));
    }
    let mut out: Vec<CycleTrace> = Vec::new();
    for (i, line) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        let bad = |what: &str| EvalError::input(path, format!("line {}: {what}", i + 1));
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let [side, joint, first_frame, _, _, value] = cells[..] else {
            return Err(bad("expected 6 cells"));
        };
        let side: Side = side.parse().map_err(|e: String| bad(&e))?;
        let first_frame: usize = first_frame
            .parse()
            .map_err(|_| bad("first_frame is not a frame number"))?;
        let value: f64 = value.parse().map_err(|_| bad("value is not a number"))?;
        match out.last_mut() {
            Some(t) if t.side == side && t.joint == joint && t.first_frame == first_frame => {
                t.values.push(value)
            }
            _ => out.push(CycleTrace {
                side,
                joint: joint.into(),
                first_frame,
                values: vec![value],
            }),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_group_into_traces() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("cycles_all.csv");
        std::fs::write(
            &p,
            format!("{HEADER}\nleft,hip,10,40,0,1.5\nleft,hip,10,40,1,2\nleft,knee,10,40,0,3\nright,hip,25,55,0,4\n"),
        )
        .unwrap();
        let t = read_cycles_all_csv(&p).unwrap();
        assert_eq!(t.len(), 3);
        assert_eq!(t[0].values, vec![1.5, 2.0]);
        assert_eq!((t[2].side, t[2].first_frame), (Side::Right, 25));
        std::fs::write(&p, "side,joint\n").unwrap();
        assert!(
            read_cycles_all_csv(&p)
                .unwrap_err()
                .to_string()
                .contains(HEADER)
        );
    }
}
