//! The native part of the `bisph` Python package: cases, simulations with their state as
//! NumPy arrays, the Shepard factor and BIPI packing, over the same core and run loop as
//! the `bisph` command line.

mod case;
mod errors;
mod run;
mod sim;
mod solver;
mod tools;

use pyo3::prelude::*;

/// bisph, the boundary-integral SPH solver, from Python (native module; import `bisph`).
#[pymodule]
fn _bisph(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<case::Case>()?;
    m.add_class::<sim::Simulation>()?;
    m.add_class::<run::Progress>()?;
    m.add("CaseError", py.get_type::<errors::CaseError>())?;
    m.add("RunError", py.get_type::<errors::RunError>())?;
    m.add_function(wrap_pyfunction!(tools::shepard, m)?)?;
    m.add_function(wrap_pyfunction!(tools::pack, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
