//! The interpreter: started when gait is the program (the `gait` command),
//! already running when gait is a Python package; and the stage objects made in it.

use std::sync::Once;

use pyo3::prelude::*;
use pyo3::types::PyTraceback;

use crate::{PythonStageConfig, PythonStageError};

/// Starts Python if it is not running and, once, puts the active virtual
/// environment's packages on `sys.path` (an embedded interpreter knows only
/// the installation it was built against).
pub(crate) fn ensure() {
    static VENV: Once = Once::new();
    Python::initialize();
    VENV.call_once(|| {
        Python::attach(|py| {
            // Without the venv a missing package is reported at import, by name.
            let _ = add_active_venv(py);
        })
    });
}

fn add_active_venv(py: Python<'_>) -> PyResult<()> {
    let Some(venv) = std::env::var_os("VIRTUAL_ENV").filter(|v| !v.is_empty()) else {
        return Ok(());
    };
    let sys = py.import("sys")?;
    let prefix: std::path::PathBuf = sys.getattr("prefix")?.extract()?;
    if prefix == std::path::Path::new(&venv) {
        return Ok(());
    }
    let (major, minor): (u8, u8) = sys
        .getattr("version_info")?
        .extract::<(u8, u8, u8, String, u8)>()
        .map(|v| (v.0, v.1))?;
    let site_packages = std::path::Path::new(&venv)
        .join("lib")
        .join(format!("python{major}.{minor}"))
        .join("site-packages");
    py.import("site")?
        .call_method1("addsitedir", (site_packages,))
        .map(|_| ())
}

/// Imports the module and makes the stage object, `Class(options)`.
pub(crate) fn instantiate<'py>(
    py: Python<'py>,
    cfg: &PythonStageConfig,
) -> Result<Bound<'py, PyAny>, PythonStageError> {
    let module = py
        .import(cfg.module.as_str())
        .map_err(|e| PythonStageError::Import {
            module: cfg.module.clone(),
            reason: describe(py, &e),
        })?;
    let class = module
        .getattr(cfg.class.as_str())
        .map_err(|_| PythonStageError::NoClass {
            module: cfg.module.clone(),
            class: cfg.class.clone(),
        })?;
    let construct = |e: PyErr| PythonStageError::Construct {
        class: cfg.class.clone(),
        reason: describe(py, &e),
    };
    let options = py
        .import("json")
        .and_then(|json| json.call_method1("loads", (cfg.options_json(),)))
        .map_err(construct)?;
    class.call1((options,)).map_err(construct)
}

/// Where `module` would be imported from, without importing it.
pub(crate) fn module_file(module: &str) -> Option<std::path::PathBuf> {
    ensure();
    Python::attach(|py| {
        let spec = py
            .import("importlib.util")
            .ok()?
            .call_method1("find_spec", (module,))
            .ok()?;
        spec.getattr("origin").ok()?.extract().ok()
    })
}

/// numpy, which every stage's frames are handed in.
pub(crate) fn numpy(py: Python<'_>) -> Result<Bound<'_, PyModule>, PythonStageError> {
    py.import("numpy").map_err(|e| PythonStageError::NoNumpy {
        reason: describe(py, &e),
    })
}

/// An exception as one line: its type, message and where it was raised.
pub(crate) fn describe(py: Python<'_>, e: &PyErr) -> String {
    let kind = e
        .get_type(py)
        .name()
        .map_or_else(|_| "exception".to_string(), |n| n.to_string());
    let message = e.value(py).to_string();
    let at = e.traceback(py).and_then(|tb| last_frame(&tb).ok());
    let text = match (message.is_empty(), at) {
        (true, None) => kind,
        (true, Some(at)) => format!("{kind} at {at}"),
        (false, None) => format!("{kind}: {message}"),
        (false, Some(at)) => format!("{kind}: {message} (at {at})"),
    };
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// "file.py:LINE" of the innermost frame of a traceback.
fn last_frame(tb: &Bound<'_, PyTraceback>) -> PyResult<String> {
    let mut tb = tb.clone().into_any();
    loop {
        let next = tb.getattr("tb_next")?;
        if next.is_none() {
            break;
        }
        tb = next;
    }
    let file: String = tb
        .getattr("tb_frame")?
        .getattr("f_code")?
        .getattr("co_filename")?
        .extract()?;
    let line: u32 = tb.getattr("tb_lineno")?.extract()?;
    let name = std::path::Path::new(&file)
        .file_name()
        .map_or(file.clone(), |n| n.to_string_lossy().into_owned());
    Ok(format!("{name}:{line}"))
}
