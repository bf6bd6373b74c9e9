//! gait's errors as Python exceptions, with the CLI's one-line messages.

use gait_pipeline::{PipelineError, one_line};
use pyo3::exceptions::{PyException, PyKeyboardInterrupt};
use pyo3::prelude::*;

pyo3::create_exception!(gait, GaitError, PyException, "Any error of gait.");
pyo3::create_exception!(
    gait,
    ConfigError,
    GaitError,
    "A bad pipeline config or --set value."
);
pyo3::create_exception!(
    gait,
    InputError,
    GaitError,
    "An input that cannot be read or analysed."
);
pyo3::create_exception!(
    gait,
    StageError,
    GaitError,
    "A stage (model, plugin or Python stage) failed."
);
pyo3::create_exception!(
    gait,
    OutputError,
    GaitError,
    "A result could not be written (disk, permissions)."
);

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("GaitError", py.get_type::<GaitError>())?;
    m.add("ConfigError", py.get_type::<ConfigError>())?;
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("StageError", py.get_type::<StageError>())?;
    m.add("OutputError", py.get_type::<OutputError>())?;
    Ok(())
}

/// The exception for a pipeline error; an interrupted run is Python's own
/// KeyboardInterrupt.
pub(crate) fn to_py(e: PipelineError) -> PyErr {
    let message = one_line(&e.to_string());
    match e {
        PipelineError::Config { .. } => ConfigError::new_err(message),
        PipelineError::Input { .. } => InputError::new_err(message),
        PipelineError::Stage(gait_core::StageError::BadInput(_)) => InputError::new_err(message),
        PipelineError::Stage(_) => StageError::new_err(message),
        PipelineError::Interrupted { .. } => PyKeyboardInterrupt::new_err(message),
        PipelineError::Io { .. }
        | PipelineError::Cache { .. }
        | PipelineError::Output { .. }
        | PipelineError::Busy { .. } => OutputError::new_err(message),
    }
}

pub(crate) fn input_error(message: String) -> PyErr {
    InputError::new_err(one_line(&message))
}
