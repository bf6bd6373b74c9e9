//! The smallest real change of each spatiotemporal parameter (minimal detectable change,
//! MDC95), printed beside the measures in the report: a difference between two analyses that
//! re-encoding and keypoint noise alone do not produce. The figures are those of the
//! robustness matrix on the bundled sample (`tools/robustness/matrix.py --mode full`;
//! `data/reliability/README.md` says how they were made); lengths in pixels are left out,
//! since they depend on the camera.

/// `mdc.csv` of the matrix: `measure,repeats,sd,mdc95`, measure as `parameter side (unit)`.
const MDC_CSV: &str = include_str!("../data/reliability/mdc.csv");

/// MDC95 of `parameter` in `unit` (the larger over the sides), if the matrix measured it.
pub fn mdc(parameter: &str, unit: &str) -> Option<f64> {
    MDC_CSV
        .lines()
        .skip(1)
        .filter_map(|line| {
            let (measure, rest) = line.strip_prefix('"')?.split_once("\",")?;
            let (name, measured_unit) = measure.split_once(" (")?;
            let measured_unit = measured_unit.strip_suffix(')')?;
            let (param, _side) = name.split_once(' ')?;
            let value: f64 = rest.rsplit(',').next()?.parse().ok()?;
            (param == parameter && measured_unit == unit && !unit.starts_with("px"))
                .then_some(value)
        })
        .reduce(f64::max)
}

/// MDC95 of a joint angle's measure (`ankle`, `peak extension`), the larger over the sides.
pub fn angle_mdc(joint: &str, measure: &str) -> Option<f64> {
    larger_of(["left", "right"].map(|s| format!("\"{s} {joint} {measure} (deg)\",")))
}

/// MDC95 of a checklist item's measure in `unit` (`vaulting`, `% leg`), the larger over the
/// sides, where the matrix measured it: the side-view items (its walk is filmed from the side);
/// none in image pixels.
pub fn checklist_mdc(item: &str, unit: &str) -> Option<f64> {
    larger_of(["left", "right"].map(|s| format!("\"checklist {item} {s} ({unit})\",")))
}

/// The larger MDC95 of the rows starting with `rows`.
fn larger_of(rows: [String; 2]) -> Option<f64> {
    MDC_CSV
        .lines()
        .filter(|line| rows.iter().any(|r| line.starts_with(r.as_str())))
        .filter_map(|line| line.rsplit(',').next()?.parse::<f64>().ok())
        .reduce(f64::max)
}

/// The cell of the report: the parameter's MDC95 and its symmetry index's, where known.
pub fn cell(parameter: &str, unit: &str) -> String {
    let own = mdc(parameter, unit).map(|v| format!("{v:.2} {unit}"));
    let si = mdc(&format!("symmetry_index_{parameter}"), "%").map(|v| format!("SI {v:.1}"));
    match (own, si) {
        (None, None) => "—".into(),
        (a, b) => [a, b].into_iter().flatten().collect::<Vec<_>>().join("; "),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_bundled_figures_and_leaves_pixels_out() {
        let stride = mdc("stride_time", "s").expect("stride time measured");
        assert!(stride > 0.0 && stride < 0.5, "{stride}");
        assert!(mdc("stride_length", "px").is_none());
        assert!(mdc("no_such_parameter", "s").is_none());
        assert!(cell("stride_time", "s").contains("SI "));
        // A length in pixels has no MDC of its own; its symmetry index (a ratio) has one.
        assert!(cell("stride_length", "px").starts_with("SI "));
        assert_eq!(cell("no_such_parameter", "s"), "—");
    }
}
