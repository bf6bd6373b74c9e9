//! The report of a run folder as a clinical gait report lays it out: the self-contained HTML
//! page and its PDF (headless Chromium), the clinical section (curves against the normative
//! band, GPS/GVS/MAP), spatiotemporal parameters with their minimal detectable change, the
//! frontal section of a front or back view, and the provenance table. What it shows is
//! computed elsewhere (`gait-kin`, `gait-eval`); this crate reads and lays out.

mod clinical;
pub mod frontal;
pub mod html;
pub mod pdf;
pub mod provenance;
pub mod report;
mod run_dir;
pub mod spatiotemporal;
pub mod subject_lines;

pub use report::{Report, Table};
