//! The report's provenance appendix: what a printed report needs to be traced
//! back to its run (tool version, date, input and config checksums), with the
//! full manifest left in run.json beside it rather than printed.

use serde_json::Value;
use sha2::{Digest, Sha256};

use crate::html::{escape, table};

/// sha256 of a run's resolved config: run.json's `config` as compact JSON (keys sorted).
pub fn config_sha256(manifest: &Value) -> Option<String> {
    let config = manifest.get("config").filter(|c| !c.is_null())?;
    let text = serde_json::to_string(config).ok()?;
    Some(
        Sha256::digest(text.as_bytes())
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect(),
    )
}

/// `unix` seconds as a UTC date and time, e.g. "2026-12-04 04:08 UTC".
pub fn utc_date(unix: u64) -> String {
    let days = (unix / 86_400) as i64;
    let secs = unix % 86_400;
    // Howard Hinnant's civil_from_days: days since 1970-01-01 to (year, month, day).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02} {:02}:{:02} UTC",
        secs / 3600,
        secs % 3600 / 60
    )
}

/// The appendix as HTML: a short table, and where the full manifest is.
pub fn section(manifest: &Value) -> String {
    let text = |p: &str| manifest.pointer(p).and_then(Value::as_str).unwrap_or("—");
    let mut rows = vec![
        vec![
            "Tool".to_string(),
            format!("{} {}", text("/tool"), text("/version")),
        ],
        vec![
            "Run started".into(),
            manifest
                .get("started_unix")
                .and_then(Value::as_u64)
                .map_or("—".into(), utc_date),
        ],
        vec!["Input".into(), text("/input/path").to_string()],
        vec!["Input sha256".into(), text("/input/sha256").to_string()],
        vec![
            "Config sha256".into(),
            config_sha256(manifest).unwrap_or_else(|| "—".into()),
        ],
    ];
    if let Some(models) = manifest.get("models").and_then(Value::as_array) {
        for m in models {
            let path = m.get("path").and_then(Value::as_str).unwrap_or("");
            let name = path.rsplit('/').next().unwrap_or(path);
            let sha = m.get("sha256").and_then(Value::as_str).unwrap_or("—");
            rows.push(vec![format!("Model {name}"), sha.to_string()]);
        }
    }
    format!(
        "<h2 id=\"provenance\">Provenance</h2>{}<p class=\"provenance\">The full run manifest (resolved config, command, \
         stage timings, model files) is <a href=\"run.json\">run.json</a> in the run folder; \
         the config checksum is the sha256 of its <code>config</code> as compact JSON.</p>",
        table(&["Item".to_string(), "Value".to_string()], &rows)
    )
    .replace("<table>", "<table class=\"provenance\">")
        + &manifest_details(manifest)
}

/// The whole manifest, on screen only (folded; never printed).
fn manifest_details(manifest: &Value) -> String {
    let text = serde_json::to_string_pretty(manifest).unwrap_or_default();
    format!(
        "<details class=\"manifest\"><summary>Run manifest (run.json)</summary><pre>{}</pre></details>",
        escape(&text)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_are_utc_calendar_dates() {
        assert_eq!(utc_date(0), "1970-01-01 00:00 UTC");
        assert_eq!(utc_date(951_782_400), "2000-02-29 00:00 UTC");
        assert_eq!(utc_date(1_796_357_280), "2026-12-04 04:08 UTC");
    }

    #[test]
    fn appendix_has_version_date_checksums_and_points_at_run_json() {
        let m = serde_json::json!({"tool": "gait", "version": "0.1.0", "started_unix": 0,
            "input": {"path": "walk.mp4", "sha256": "ab12"}, "config": {"run": {"batch_size": 4}}});
        let html = section(&m);
        for want in ["gait 0.1.0", "1970-01-01", "walk.mp4", "ab12", "run.json"] {
            assert!(html.contains(want), "{want}: {html}");
        }
        let sha = config_sha256(&m).unwrap();
        assert_eq!(sha.len(), 64);
        assert!(html.contains(&sha));
        let other = serde_json::json!({"config": {"run": {"batch_size": 5}}});
        assert_ne!(config_sha256(&other).unwrap(), sha);
    }
}
