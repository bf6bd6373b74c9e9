//! The CSV files of `gait kin`, each written to a temporary name and renamed when complete.

use std::fs;
use std::io::Write;
use std::path::Path;

use crate::{KinError, KinResult};

/// Number cell: empty when undefined.
fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.6}")
    } else {
        String::new()
    }
}

/// Writes `name` in `dir` through `dir/.name.partial`, so a crash never leaves a complete-looking file.
fn atomic(
    dir: &Path,
    name: &str,
    fill: impl FnOnce(&mut Vec<u8>) -> Result<(), KinError>,
) -> Result<(), KinError> {
    let io = |what: String| {
        move |e: std::io::Error| KinError::Io {
            context: what,
            source: e,
        }
    };
    let mut buf = Vec::new();
    fill(&mut buf)?;
    let tmp = dir.join(format!(".{name}.partial"));
    let dst = dir.join(name);
    let mut f = fs::File::create(&tmp).map_err(io(format!("creating {}", tmp.display())))?;
    f.write_all(&buf)
        .map_err(io(format!("writing {}", tmp.display())))?;
    f.sync_all()
        .map_err(io(format!("writing {}", tmp.display())))?;
    fs::rename(&tmp, &dst).map_err(io(format!("renaming to {}", dst.display())))
}

/// One row per accepted stride, joint and percent of the cycle (input frame numbers).
const CYCLES_ALL_HEADER: &str = "side,joint,first_frame,last_frame,percent,value";

const CYCLE_QUALITY_HEADER: &str = "side,first_frame,last_frame,accepted,reasons,stride_s,\
stride_deviation,max_filled_s,mean_likelihood,thigh_ratio,shank_ratio,swapped_frames,bout";

fn cycle_quality_row(q: &crate::CycleQuality) -> String {
    let reasons: Vec<&str> = q.reasons.iter().map(|r| r.name()).collect();
    format!(
        "{},{},{},{},{},{},{},{},{},{},{},{},{}",
        q.side.name(),
        q.first_frame,
        q.last_frame,
        q.accepted,
        reasons.join(";"),
        num(q.stride_s),
        num(q.stride_deviation),
        num(q.max_filled_s),
        num(q.mean_likelihood),
        num(q.thigh_ratio),
        num(q.shank_ratio),
        q.swapped_frames,
        q.bout.map_or(String::new(), |b| b.to_string())
    )
}

fn lines(buf: &mut Vec<u8>, rows: impl IntoIterator<Item = String>) {
    for r in rows {
        buf.extend_from_slice(r.as_bytes());
        buf.push(b'\n');
    }
}

/// Writes angles.csv, events.csv, bouts.csv, cycle_quality.csv, cycles.csv,
/// cycles_all.csv (every accepted cycle), spatiotemporal.csv and keypoints_filtered.csv.
pub fn write_outputs(r: &KinResult, out_dir: &Path) -> Result<(), KinError> {
    fs::create_dir_all(out_dir).map_err(|e| KinError::Io {
        context: format!("creating {}", out_dir.display()),
        source: e,
    })?;
    let fps = r.fps;
    atomic(out_dir, "angles.csv", |b| {
        let a = &r.angles;
        lines(
            b,
            [
                "frame,time_s,left_hip,right_hip,left_knee,right_knee,left_ankle,right_ankle"
                    .to_string(),
            ],
        );
        lines(
            b,
            (0..a.left.hip.len()).map(|i| {
                let f = r.first_frame + i;
                let cols = [
                    &a.left.hip,
                    &a.right.hip,
                    &a.left.knee,
                    &a.right.knee,
                    &a.left.ankle,
                    &a.right.ankle,
                ];
                let mut row = format!("{f},{}", num(f as f64 / fps));
                for c in cols {
                    row.push(',');
                    row.push_str(&num(c[i]));
                }
                row
            }),
        );
        Ok(())
    })?;
    atomic(out_dir, "events.csv", |b| {
        lines(b, ["side,event,frame,time_s".to_string()]);
        lines(
            b,
            r.events.iter().map(|e| {
                format!(
                    "{},{},{},{}",
                    e.side.name(),
                    e.event.name(),
                    e.frame,
                    num(e.frame as f64 / fps)
                )
            }),
        );
        Ok(())
    })?;
    atomic(out_dir, "bouts.csv", |b| {
        lines(b, ["bout,first,last,direction,mean_speed".to_string()]);
        lines(
            b,
            r.bouts.iter().enumerate().map(|(k, bout)| {
                let dir = match bout.direction {
                    crate::Direction::Right => "right",
                    crate::Direction::Left => "left",
                    crate::Direction::Unknown => "unknown",
                };
                let speed = num(bout.mean_speed);
                format!("{k},{},{},{dir},{speed}", bout.first, bout.last)
            }),
        );
        Ok(())
    })?;
    atomic(out_dir, "cycle_quality.csv", |b| {
        lines(b, [CYCLE_QUALITY_HEADER.to_string()]);
        lines(b, r.cycle_quality.iter().map(cycle_quality_row));
        Ok(())
    })?;
    atomic(out_dir, "cycles.csv", |b| {
        lines(b, ["side,joint,percent,mean,sd,n_cycles".to_string()]);
        for c in &r.cycles {
            lines(
                b,
                (0..c.mean.len()).map(|p| {
                    format!(
                        "{},{},{p},{},{},{}",
                        c.side.name(),
                        c.joint,
                        num(c.mean[p]),
                        num(c.sd[p]),
                        c.n_cycles
                    )
                }),
            );
        }
        Ok(())
    })?;
    atomic(out_dir, "cycles_all.csv", |b| {
        lines(b, [CYCLES_ALL_HEADER.to_string()]);
        let accepted = crate::quality::accepted(&r.cycle_quality);
        for c in crate::cycles::each(&r.angles, r.first_frame, &accepted) {
            let s = c.stride;
            lines(
                b,
                c.values.iter().enumerate().map(|(p, v)| {
                    format!(
                        "{},{},{},{},{p},{}",
                        s.side.name(),
                        c.joint,
                        s.start,
                        s.end,
                        num(*v)
                    )
                }),
            );
        }
        Ok(())
    })?;
    atomic(out_dir, "spatiotemporal.csv", |b| {
        lines(b, ["parameter,side,mean,sd,n,unit".to_string()]);
        lines(
            b,
            r.spatiotemporal.iter().map(|p| {
                format!(
                    "{},{},{},{},{},{}",
                    p.parameter,
                    p.side,
                    num(p.mean),
                    num(p.sd),
                    p.n,
                    p.unit
                )
            }),
        );
        Ok(())
    })?;
    atomic(out_dir, "keypoints_filtered.csv", |b| {
        gait_core::dlc::write(&mut *b, "gait-kin", &r.filtered).map_err(|e| KinError::Io {
            context: "writing keypoints_filtered.csv".into(),
            source: std::io::Error::other(e.to_string()),
        })
    })?;
    Ok(())
}
