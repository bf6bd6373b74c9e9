//! Figures as PNG and SVG, drawn with plotters and the embedded DejaVu Sans
//! font (no system font libraries).

mod cycles;
mod failure_bars;
mod gait_graphs;
mod map_bars;
mod skeleton;
mod visits;

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

pub use cycles::{CycleCurve, comparison_plot, read_curves_csv, read_cycles_csv};
pub use failure_bars::{FailureEntry, failure_bars};
pub use gait_graphs::{FRONTAL, GraphContext, consistency_plot, frontal_graphs, gait_graphs};
pub use map_bars::map_bars;
pub use skeleton::{StripOptions, skeleton_strip};
pub use visits::visits_plot;

use crate::EvalError;
use crate::fsutil::{ensure_dir, write_atomic};

/// DejaVu Sans 2.37 (Bitstream Vera licence, see `assets/DejaVuSans-LICENSE.txt`).
static DEJAVU_SANS: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// The font family name every figure uses.
pub(crate) const FONT: &str = "sans-serif";

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bytes are a valid TrueType font committed with the crate; a
        // failure here would show as missing text, which the tests catch.
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, DEJAVU_SANS);
    });
}

/// A rendered figure.
#[derive(Debug, Clone)]
pub struct Figure {
    pub name: String,
    pub svg: String,
    pub png: Vec<u8>,
}

impl Figure {
    /// Writes `<name>.svg` and `<name>.png` into `dir`; returns their paths.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, EvalError> {
        ensure_dir(dir)?;
        let svg = dir.join(format!("{}.svg", self.name));
        let png = dir.join(format!("{}.png", self.name));
        write_atomic(&svg, self.svg.as_bytes())?;
        write_atomic(&png, &self.png)?;
        Ok(vec![svg, png])
    }
}

/// Something drawable on any plotters backend.
pub(crate) trait Draw {
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        bitmap: bool,
    ) -> Result<(), String>;
}

fn err<E: std::fmt::Debug>(e: E) -> String {
    format!("{e:?}")
}

/// Renders `d` at `w` x `h` pixels as SVG and as PNG (over `background`
/// when given: an RGB image of exactly that size).
pub(crate) fn render(
    d: &impl Draw,
    name: &str,
    w: u32,
    h: u32,
    background: Option<image::RgbImage>,
) -> Result<Figure, EvalError> {
    register_font();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        root.fill(&WHITE)
            .map_err(|e| EvalError::plot(name, err(e)))?;
        d.draw(&root, false).map_err(|e| EvalError::plot(name, e))?;
        root.present().map_err(|e| EvalError::plot(name, err(e)))?;
    }
    let has_background = background.is_some();
    let mut buf = match background {
        Some(img) if img.dimensions() == (w, h) => img.into_raw(),
        Some(_) => {
            return Err(EvalError::plot(
                name,
                "background size differs from the figure",
            ));
        }
        None => vec![255u8; (w * h * 3) as usize],
    };
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        if !has_background {
            root.fill(&WHITE)
                .map_err(|e| EvalError::plot(name, err(e)))?;
        }
        d.draw(&root, true).map_err(|e| EvalError::plot(name, e))?;
        root.present().map_err(|e| EvalError::plot(name, err(e)))?;
    }
    let img = image::RgbImage::from_raw(w, h, buf)
        .ok_or_else(|| EvalError::plot(name, "pixel buffer size"))?;
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| EvalError::plot(name, e))?;
    Ok(Figure {
        name: name.to_string(),
        svg,
        png,
    })
}

/// Side colours as clinical gait reports draw them (pyCGM2): left red, right blue.
pub(crate) const LEFT: RGBColor = RGBColor(214, 39, 40);
pub(crate) const RIGHT: RGBColor = RGBColor(31, 119, 180);
pub(crate) const TRUTH: RGBColor = RGBColor(44, 160, 44);
/// Further method colours, in order.
pub(crate) const PALETTE: [RGBColor; 5] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

/// A chart over 0..100 % of the gait cycle with angle values `lo..hi`.
pub(crate) type CycleChart<'a, DB> = ChartContext<
    'a,
    DB,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// The axes of a gait-cycle panel: `caption` above, % gait cycle along x.
pub(crate) fn cycle_axes<'a, DB: DrawingBackend + 'a>(
    area: &'a DrawingArea<DB, Shift>,
    caption: &str,
    lo: f64,
    hi: f64,
) -> Result<CycleChart<'a, DB>, String> {
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FONT, 16))
        .margin(8)
        // The "100" under the right edge needs half its width beyond the axis.
        .margin_right(16)
        .x_label_area_size(32)
        .y_label_area_size(44)
        .build_cartesian_2d(0f64..100f64, lo..hi)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_labels(11)
        .x_label_formatter(&|x| format!("{x:.0}"))
        // Whole degrees read as "10", not "10.0"; a finer step keeps its decimal.
        .y_label_formatter(&|y| {
            let s = format!("{y:.1}");
            s.strip_suffix(".0").map_or(s.clone(), str::to_string)
        })
        .x_desc("% gait cycle")
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 12))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(err)?;
    Ok(chart)
}

/// The legend's sample of a line series in `colour`.
pub(crate) fn line_key(
    colour: RGBColor,
    width: u32,
) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(width))
}

/// The legend box every figure draws, at `position`.
pub(crate) fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> Result<(), String> {
    chart
        .configure_series_labels()
        .label_font((FONT, 12))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK.mix(0.3))
        .position(position)
        .draw()
        .map_err(err)
}

/// Range of finite values padded by 5 %, or (-1, 1) when there are none.
pub(crate) fn padded_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1.0);
    (lo - pad, hi + pad)
}
