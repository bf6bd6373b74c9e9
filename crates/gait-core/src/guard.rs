//! Calls into third-party readers that may panic on malformed input (e.g. candle's unpickler
//! indexing past a short tuple): the panic becomes an error, and its message is not printed, so
//! the command still ends with its one-line error.

use std::cell::Cell;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Once;

thread_local! {
    static QUIET: Cell<bool> = const { Cell::new(false) };
}

/// Wraps the process's panic hook once: panics inside [`quietly`] are not printed.
fn install() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(Cell::get) {
                previous(info);
            }
        }));
    });
}

/// Runs `f`; a panic inside it is returned as `Err(what)` instead of unwinding further.
pub fn quietly<T>(what: &str, f: impl FnOnce() -> T) -> Result<T, String> {
    install();
    let was = QUIET.with(|q| q.replace(true));
    let result = catch_unwind(AssertUnwindSafe(f));
    QUIET.with(|q| q.set(was));
    result.map_err(|p| {
        let msg = p
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        format!("{what} failed on malformed data ({msg})")
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_panic_becomes_an_error() {
        let v: Vec<u8> = Vec::new();
        let r = super::quietly("reading", || v[3]);
        assert!(r.unwrap_err().contains("reading failed on malformed data"));
        assert_eq!(super::quietly("reading", || 7), Ok(7));
    }
}
