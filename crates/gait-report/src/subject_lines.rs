//! The report's "Subject and walking bouts" lines, read from run.json: who
//! was analysed and why, who else was in view, when the subject walked, and
//! how many cycles passed the quality checks.

use serde_json::Value;

/// Lines describing the subject, bouts and cycle counts; empty when run.json
/// has none of them (e.g. `gait kin` on a CSV without bouts).
pub fn describe(run: &Value) -> Vec<String> {
    let mut lines = Vec::new();
    if let Some(s) = run.get("subject").filter(|s| !s.is_null()) {
        subject(s, &mut lines);
    }
    let kin = run
        .get("kinematics")
        .or_else(|| run.pointer("/extra/kinematics"));
    if let Some(k) = kin {
        lines.extend(view(k));
        bouts(k, &mut lines);
        cycles(k, &mut lines);
    }
    lines.extend(legs_in_image(run).map(|l| format!("Image: {l}")));
    lines
}

/// The view analysed and how it was decided (with the walk's angle to the camera where the
/// frame size was known).
fn view(k: &Value) -> Option<String> {
    let v = k.get("view")?;
    let name = match v.get("view")?.as_str()? {
        "sagittal" => "side",
        "anterior" => "front (walking toward the camera)",
        "posterior" => "back (walking away from the camera)",
        other => other,
    };
    let how = v.get("how").and_then(Value::as_str).unwrap_or("");
    Some(format!("View: {name} ({how})."))
}

/// How large and how sharp the subject's legs were in the image of a run (its run.json), over
/// every stride found, against the limits that reject a stride (`cycle_min_leg_px`,
/// `cycle_max_blur_share`, `cycle_min_swing_contrast`): a reader sees how far the video was
/// from too small or too blurred.
/// `None` without strides.
pub fn legs_in_image(run: &Value) -> Option<String> {
    let k = run
        .get("kinematics")
        .or_else(|| run.pointer("/extra/kinematics"))?;
    image(k, run.pointer("/config/kinematics"))
}

/// [`legs_in_image`] of the kinematics summary `k` and the settings `limits`.
fn image(k: &Value, limits: Option<&Value>) -> Option<String> {
    let all = k.get("cycle_quality").and_then(Value::as_array)?;
    let median = |key: &str| {
        let mut v: Vec<f64> = all
            .iter()
            .filter_map(|c| c.get(key).and_then(Value::as_f64))
            .filter(|v| v.is_finite())
            .collect();
        v.sort_by(f64::total_cmp);
        (!v.is_empty()).then(|| v[v.len() / 2])
    };
    let limit = |key: &str| limits.and_then(|l| l.get(key)).and_then(Value::as_f64);
    let leg = median("leg_px")?;
    let mut line = format!(
        "the legs {leg:.0} px long (thigh + shank, median over the {} strides found",
        all.len()
    );
    if let Some(min) = limit("cycle_min_leg_px").filter(|m| *m > 0.0) {
        line += &format!("; a stride under {min:.0} px is rejected");
    }
    line += ")";
    if let Some(blur) = median("blur_px") {
        line += &format!(
            ", their outline blurred over {blur:.1} px ({:.1} % of the leg",
            100.0 * blur / leg
        );
        if let Some(max) = limit("cycle_max_blur_share").filter(|m| *m > 0.0) {
            line += &format!("; over {:.1} % a stride is rejected", 100.0 * max);
        }
        line += ")";
    }
    if let Some(kept) = median("swing_contrast") {
        line += &format!(
            ", and the feet swinging keep {:.0} % of their outline's contrast standing",
            100.0 * kept
        );
        if let Some(min) = limit("cycle_min_swing_contrast").filter(|m| *m > 0.0) {
            line += &format!(
                " (under {:.0} %, motion blur, a stride is rejected)",
                100.0 * min
            );
        }
    }
    Some(line + ".")
}

fn subject(s: &Value, lines: &mut Vec<String>) {
    let tracks = s
        .get("tracks")
        .and_then(Value::as_array)
        .cloned()
        .unwrap_or_default();
    let chosen = s.get("chosen").and_then(Value::as_u64);
    let reason = s.get("reason").and_then(Value::as_str).unwrap_or("");
    if let Some(t) = chosen.and_then(|c| {
        tracks
            .iter()
            .find(|t| t.get("id").and_then(Value::as_u64) == Some(c))
    }) {
        lines.push(format!(
            "Subject: track {} ({}). Chosen as {reason}.",
            num(t, "id"),
            span(t)
        ));
    }
    if let Some(ranges) = s.get("in_view").and_then(Value::as_array) {
        lines.push(format!(
            "Subject in view (followed) in frames {}.",
            ranges_text(ranges)
        ));
    }
    let others: Vec<String> = tracks
        .iter()
        .filter(|t| t.get("id").and_then(Value::as_u64) != chosen)
        .map(|t| {
            let walk = t
                .pointer("/walk/displacement")
                .and_then(Value::as_f64)
                .unwrap_or(0.0);
            format!(
                "track {} ({}, walk {walk:.1} body sizes)",
                num(t, "id"),
                span(t)
            )
        })
        .collect();
    if !others.is_empty() {
        lines.push(format!(
            "Other people tracked and not analysed: {}.",
            others.join("; ")
        ));
    }
}

fn bouts(k: &Value, lines: &mut Vec<String>) {
    let Some(bouts) = k.get("bouts").and_then(Value::as_array) else {
        return;
    };
    if bouts.is_empty() {
        lines.push("No walking bout found: no events or cycles.".into());
        return;
    }
    let text: Vec<String> = bouts
        .iter()
        .map(|b| {
            let dir = b.get("direction").and_then(Value::as_str).unwrap_or("?");
            let speed = b.get("mean_speed").and_then(Value::as_f64);
            let speed = speed.map_or(String::new(), |v| format!(", {v:.2} leg lengths/s"));
            format!(
                "frames {}-{} (walking {}{speed})",
                num(b, "first"),
                num(b, "last"),
                dir.to_lowercase()
            )
        })
        .collect();
    lines.push(format!(
        "Walking bouts (events and cycles are taken inside them only): {}.",
        text.join("; ")
    ));
}

fn cycles(k: &Value, lines: &mut Vec<String>) {
    let Some(all) = k.get("cycle_quality").and_then(Value::as_array) else {
        return;
    };
    for side in ["left", "right"] {
        let of_side: Vec<&Value> = all
            .iter()
            .filter(|c| c.get("side").and_then(Value::as_str) == Some(side))
            .collect();
        let accepted = of_side
            .iter()
            .filter(|c| c.get("accepted").and_then(Value::as_bool) == Some(true))
            .count();
        lines.push(format!(
            "{side} cycles: {accepted} accepted, {} rejected (see the cycle quality table).",
            of_side.len() - accepted
        ));
    }
}

fn num(v: &Value, key: &str) -> String {
    v.get(key).map_or("?".into(), |x| x.to_string())
}

fn span(t: &Value) -> String {
    format!(
        "frames {}-{}, seen in {}",
        num(t, "first_frame"),
        num(t, "last_frame"),
        num(t, "frames")
    )
}

fn ranges_text(ranges: &[Value]) -> String {
    let parts: Vec<String> = ranges
        .iter()
        .filter_map(|r| {
            let r = r.as_array()?;
            Some(format!("{}-{}", r.first()?, r.get(1)?))
        })
        .collect();
    if parts.is_empty() {
        "none".into()
    } else {
        parts.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_from_a_run_json() {
        let run = serde_json::json!({
            "subject": {
                "tracks": [
                    {"id": 0, "first_frame": 0, "last_frame": 229, "frames": 230, "walk": {"displacement": 0.4}},
                    {"id": 1, "first_frame": 34, "last_frame": 199, "frames": 150, "walk": {"displacement": 3.1}}
                ],
                "chosen": 1, "reason": "walker: the longest walk", "walking": true,
                "in_view": [[34, 120], [124, 199]]
            },
            "extra": {"kinematics": {
                "view": {"view": "sagittal", "how": "auto: hips or shoulders apart in 0 % of frames; the walk about 82 deg off the camera's axis"},
                "bouts": [{"first": 55, "last": 185, "direction": "left", "mean_speed": 0.8}],
                "cycle_quality": [
                    {"side": "left", "accepted": true, "leg_px": 186.9, "blur_px": 1.66, "swing_contrast": 0.91},
                    {"side": "left", "accepted": false, "leg_px": 192.0, "blur_px": null, "swing_contrast": 0.87}
                ]
            }},
            "config": {"kinematics": {"cycle_min_leg_px": 100.0, "cycle_max_blur_share": 0.015, "cycle_min_swing_contrast": 0.6}}
        });
        let lines = describe(&run);
        assert!(
            lines[0].starts_with("Subject: track 1 (frames 34-199"),
            "{lines:?}"
        );
        assert!(lines[1].contains("34-120, 124-199"), "{lines:?}");
        assert!(lines[2].contains("track 0"), "{lines:?}");
        assert_eq!(
            lines[3],
            "View: side (auto: hips or shoulders apart in 0 % of frames; the walk about 82 deg off the camera's axis)."
        );
        assert!(
            lines[4].contains("frames 55-185 (walking left, 0.80"),
            "{lines:?}"
        );
        assert!(lines[5].contains("1 accepted, 1 rejected"), "{lines:?}");
        assert_eq!(
            lines[7],
            "Image: the legs 192 px long (thigh + shank, median over the 2 strides found; a stride under 100 px is rejected), their outline blurred over 1.7 px (0.9 % of the leg; over 1.5 % a stride is rejected), and the feet swinging keep 91 % of their outline's contrast standing (under 60 %, motion blur, a stride is rejected)."
        );
        assert!(describe(&serde_json::json!({})).is_empty());
    }
}
