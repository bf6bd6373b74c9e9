//! gait's pixels as numpy arrays without a copy: a read-only memoryview over
//! the buffer, viewed by `numpy.frombuffer`. When the call returns, every
//! array over the memory must be gone (a weak reference to each base array
//! tells): a stage that kept one is refused, since the memory is reused.

use std::os::raw::c_char;

use gait_core::{EdgeMap, Frame};
use pyo3::prelude::*;
use pyo3::types::PyList;

/// CPython's `PyBUF_READ`: the memoryview refuses writes.
const PY_BUF_READ: i32 = 0x100;

/// The arrays of one call, weak references to the arrays under them and the memoryviews.
pub(crate) struct Views<'py> {
    pub list: Bound<'py, PyList>,
    bases: Vec<Bound<'py, PyAny>>,
    memoryviews: Vec<Bound<'py, PyAny>>,
}

impl<'py> Views<'py> {
    /// HxWx3 uint8 arrays of the frames' RGB pixels.
    pub fn rgb(np: &Bound<'py, PyModule>, frames: &[Frame]) -> PyResult<Self> {
        let buffers = frames.iter().map(|f| {
            let shape = vec![f.height() as usize, f.width() as usize, 3];
            (f.image.as_raw().as_slice(), shape)
        });
        Self::new(np, buffers)
    }

    /// HxW uint8 arrays of the edge maps.
    pub fn gray(np: &Bound<'py, PyModule>, maps: &[EdgeMap]) -> PyResult<Self> {
        let buffers = maps.iter().map(|m| {
            let shape = vec![m.image.height() as usize, m.image.width() as usize];
            (m.image.as_raw().as_slice(), shape)
        });
        Self::new(np, buffers)
    }

    fn new<'a>(
        np: &Bound<'py, PyModule>,
        buffers: impl Iterator<Item = (&'a [u8], Vec<usize>)>,
    ) -> PyResult<Self> {
        let py = np.py();
        let list = PyList::empty(py);
        let weakref = py.import("weakref")?.getattr("ref")?;
        let mut memoryviews = Vec::new();
        let mut bases = Vec::new();
        for (bytes, shape) in buffers {
            // SAFETY: the memoryview is read-only and released (or the call
            // refused) before `bytes`, borrowed from a live frame, goes away.
            let view = unsafe {
                Bound::from_owned_ptr_or_err(
                    py,
                    pyo3::ffi::PyMemoryView_FromMemory(
                        bytes.as_ptr() as *mut c_char,
                        bytes.len() as pyo3::ffi::Py_ssize_t,
                        PY_BUF_READ,
                    ),
                )?
            };
            // Every view numpy derives holds this base array (or an array over it).
            let base = np.call_method1("frombuffer", (&view, "uint8"))?;
            bases.push(weakref.call1((&base,))?);
            list.append(base.call_method1("reshape", (shape,))?)?;
            memoryviews.push(view);
        }
        Ok(Self {
            list,
            bases,
            memoryviews,
        })
    }

    /// Drops the arrays and releases the memoryviews; `false` when the stage
    /// still holds an array over gait's memory.
    pub fn release(self) -> bool {
        let Self {
            list,
            bases,
            memoryviews,
        } = self;
        let py = list.py();
        let _ = list.call_method0("clear");
        drop(list);
        let alive = || bases.iter().any(|w| w.call0().is_ok_and(|a| !a.is_none()));
        // A reference cycle (an exception's traceback, say) may hold an array
        // until the garbage collector runs.
        let kept = alive()
            && (py
                .import("gc")
                .and_then(|gc| gc.call_method0("collect"))
                .is_err()
                || alive());
        for v in &memoryviews {
            let _ = v.call_method0("release");
        }
        !kept
    }
}
