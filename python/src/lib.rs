//! `gait._gait`, the native half of the `gait` Python package: the same
//! pipeline, kinematics and config code as the `gait` command, with results
//! handed over as columns for pandas. The Python half (python/gait/) makes
//! the DataFrames, the progress bar and the public API.

mod errors;
mod run;
mod tables;
mod visit;

use pyo3::prelude::*;

#[pymodule]
fn _gait(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(run::run, m)?)?;
    m.add_function(wrap_pyfunction!(run::kin, m)?)?;
    m.add_function(wrap_pyfunction!(run::resolve_config, m)?)?;
    m.add_function(wrap_pyfunction!(run::default_models_dir, m)?)?;
    m.add_function(wrap_pyfunction!(visit::visit, m)?)?;
    Ok(())
}
