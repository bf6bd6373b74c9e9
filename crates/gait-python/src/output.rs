//! Copies what a stage returned into owned gait types, checking the count,
//! shape, dtype and values first; a bad result is refused whole, with the
//! frame it was for.

use pyo3::prelude::*;

/// One item per frame: the result as a sequence of `n` items.
pub(crate) fn items<'py>(
    result: &Bound<'py, PyAny>,
    n: usize,
) -> Result<Vec<Bound<'py, PyAny>>, String> {
    let items: Vec<Bound<'py, PyAny>> = result
        .try_iter()
        .and_then(|it| it.collect::<PyResult<_>>())
        .map_err(|_| {
            format!(
                "{}, expected a list with one item per frame",
                type_name(result)
            )
        })?;
    if items.len() != n {
        return Err(format!("{} items for {n} frames", items.len()));
    }
    Ok(items)
}

/// `None` (no person), or the (K, 3) float rows x, y, confidence.
pub(crate) fn keypoints(
    np: &Bound<'_, PyModule>,
    item: &Bound<'_, PyAny>,
    k: usize,
) -> Result<Option<Vec<[f64; 3]>>, String> {
    if item.is_none() {
        return Ok(None);
    }
    let array = as_array(np, item)?;
    let kind: String = attr(&array, "dtype")?
        .getattr("kind")
        .and_then(|k| k.extract())
        .map_err(py_text)?;
    if kind != "f" {
        return Err(format!(
            "dtype {}, expected float32 or float64 (or None for no person)",
            dtype(&array)
        ));
    }
    expect_shape(&array, &[k, 3])?;
    let values = bytes(np, &array, "float64")?;
    let rows: Vec<[f64; 3]> = values
        .chunks_exact(24)
        .map(|row| {
            let v =
                |i: usize| f64::from_ne_bytes(row[i * 8..i * 8 + 8].try_into().unwrap_or([0; 8]));
            [v(0), v(1), v(2)]
        })
        .collect();
    if let Some(i) = rows.iter().position(|r| r.iter().any(|v| !v.is_finite())) {
        return Err(format!(
            "keypoint {i} is {:?}: coordinates and confidences must be finite (give confidence 0 to a keypoint not found)",
            rows[i]
        ));
    }
    Ok(Some(rows))
}

/// The pixels of a uint8 image of `shape` ((H, W) or (H, W, 3)).
pub(crate) fn image(
    np: &Bound<'_, PyModule>,
    item: &Bound<'_, PyAny>,
    shape: &[usize],
) -> Result<Vec<u8>, String> {
    let array = as_array(np, item)?;
    if dtype(&array) != "uint8" {
        return Err(format!("dtype {}, expected uint8", dtype(&array)));
    }
    expect_shape(&array, shape)?;
    bytes(np, &array, "uint8")
}

fn as_array<'py>(
    np: &Bound<'py, PyModule>,
    item: &Bound<'py, PyAny>,
) -> Result<Bound<'py, PyAny>, String> {
    np.call_method1("asarray", (item,))
        .map_err(|_| format!("{}, expected a numpy array", type_name(item)))
}

fn expect_shape(array: &Bound<'_, PyAny>, shape: &[usize]) -> Result<(), String> {
    let found: Vec<usize> = attr(array, "shape")?.extract().map_err(py_text)?;
    if found != shape {
        return Err(format!(
            "shape {}, expected {}",
            tuple(&found),
            tuple(shape)
        ));
    }
    Ok(())
}

/// The array's elements as `dtype`, C order, in native byte order.
fn bytes(
    np: &Bound<'_, PyModule>,
    array: &Bound<'_, PyAny>,
    dtype: &str,
) -> Result<Vec<u8>, String> {
    np.call_method1("ascontiguousarray", (array, dtype))
        .and_then(|a| a.call_method0("tobytes"))
        .and_then(|b| b.extract())
        .map_err(py_text)
}

fn attr<'py>(array: &Bound<'py, PyAny>, name: &str) -> Result<Bound<'py, PyAny>, String> {
    array.getattr(name).map_err(py_text)
}

/// numpy's name of the array's element type, e.g. "uint8".
fn dtype(array: &Bound<'_, PyAny>) -> String {
    array
        .getattr("dtype")
        .and_then(|d| d.str())
        .map_or_else(|_| "unknown".into(), |s| s.to_string())
}

fn type_name(item: &Bound<'_, PyAny>) -> String {
    item.get_type()
        .name()
        .map_or_else(|_| "an object".into(), |n| format!("a {n}"))
}

fn tuple(shape: &[usize]) -> String {
    let parts: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    if parts.len() == 1 {
        format!("({},)", parts[0])
    } else {
        format!("({})", parts.join(", "))
    }
}

fn py_text(e: PyErr) -> String {
    e.to_string()
}
