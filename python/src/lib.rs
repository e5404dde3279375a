//! The native part of the Python package `ellipack` (module `ellipack._ellipack`): thin
//! bindings of the workspace crates. The user-facing functions, their argument checks and
//! their docstrings are in `ellipack/__init__.py`; this module evaluates rows and runs the
//! packer with the GIL released.
#![deny(missing_docs)]

use pyo3::prelude::*;

mod packer;
mod rows;
mod scalar;

/// The extension module.
#[pymodule]
fn _ellipack(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(rows::_rows, m)?)?;
    m.add_function(wrap_pyfunction!(scalar::_one, m)?)?;
    m.add_function(wrap_pyfunction!(rows::_bench_rust_batch, m)?)?;
    m.add_function(wrap_pyfunction!(packer::_pack, m)?)?;
    m.add_function(wrap_pyfunction!(packer::_packing_from_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(packer::_container_dimension, m)?)?;
    m.add_function(wrap_pyfunction!(packer::read_packing, m)?)?;
    m.add_function(wrap_pyfunction!(packer::verify, m)?)?;
    m.add_function(wrap_pyfunction!(packer::_analyse, m)?)?;
    m.add_class::<packer::PyPacking>()?;
    m.add("NotReached", m.py().get_type::<packer::NotReached>())?;
    m.add("_MAX_ITEMS", ellipack::scene::MAX_ITEMS)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
