//! `illume._illume`: the native half of the `illume` Python package (issue 37).
//!
//! Each call goes to the engine the command line uses: scenes load through
//! `illume_scene::load_scene_with`, settings through `Config::layered` and
//! `Config::with_value` (so unknown keys and bad values are refused with the CLI's
//! messages), stills through `render_still`, frames through `Engine::step`, metrics
//! through `illume_metrics`, scenarios through `illume_bench::run`.
//!
//! Three rules hold for every function here:
//! - the engine's work runs with the GIL released ([`detached`]), so other Python threads
//!   keep running;
//! - no Rust panic crosses into Python: a caught panic is a `RuntimeError`;
//! - bad input is a `ValueError` with the engine's (the CLI's) message, never a crash.

mod bench;
mod edit;
mod engine;
mod images;
mod scene;

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use std::panic::{AssertUnwindSafe, catch_unwind};

/// A Python exception raised inside engine work (a progress callback's, or Ctrl-C's
/// `KeyboardInterrupt`), carried out of it by unwinding: the engine has no way to be
/// told to stop, so the callback unwinds through it and [`detached`] hands the
/// exception back to Python.
pub(crate) struct Interrupted(pub PyErr);

/// Runs `f` with the GIL released; a panic inside it becomes a `RuntimeError` naming
/// its message (an [`Interrupted`] unwind, its exception).
pub(crate) fn detached<T: Send>(
    py: Python<'_>,
    f: impl FnOnce() -> PyResult<T> + Send,
) -> PyResult<T> {
    py.detach(|| caught(f))
}

/// `f`, a panic inside it becoming a `RuntimeError` (see [`detached`]).
pub(crate) fn caught<T>(f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(result) => result,
        Err(payload) => Err(match payload.downcast::<Interrupted>() {
            Ok(interrupted) => interrupted.0,
            Err(payload) => {
                let message = payload
                    .downcast_ref::<String>()
                    .map(String::as_str)
                    .or_else(|| payload.downcast_ref::<&str>().copied())
                    .unwrap_or("no message");
                PyRuntimeError::new_err(format!("internal error in illume: {message}"))
            }
        }),
    }
}

/// A `ValueError` with `e`'s message.
pub(crate) fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// The native module.
#[pymodule]
fn _illume(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<scene::Scene>()?;
    m.add_class::<edit::Edit>()?;
    m.add_class::<engine::Engine>()?;
    m.add_function(wrap_pyfunction!(engine::render, m)?)?;
    m.add_function(wrap_pyfunction!(engine::techniques, m)?)?;
    m.add_function(wrap_pyfunction!(images::compare, m)?)?;
    m.add_function(wrap_pyfunction!(images::read_image, m)?)?;
    m.add_function(wrap_pyfunction!(images::write_image, m)?)?;
    m.add_function(wrap_pyfunction!(bench::bench, m)?)?;
    m.add_function(wrap_pyfunction!(panic_for_test, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}

/// Panics inside engine work (with the GIL released), for the test that no panic
/// crosses into Python: raises `RuntimeError`.
#[pyfunction]
fn panic_for_test(py: Python<'_>) -> PyResult<()> {
    detached(py, || -> PyResult<()> {
        panic!("a panic on purpose (illume._illume.panic_for_test)")
    })
}
