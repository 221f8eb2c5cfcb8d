//! `bisph.Case`: a checked case file, from TOML or a dict, with the command line's `--set`.
//! The value lives here; its Python methods are in [`methods`].

mod methods;

use bisph_io::LoadedCase;
use pyo3::prelude::*;

/// A checked case: the sections and keys of a case file (docs/case-reference.md), read from
/// TOML or a dict, with the same strict parsing and named errors as `bisph run`.
///
/// A mistake raises `bisph.CaseError` with `file`, `key` and `message`.
#[pyclass(module = "bisph")]
#[derive(Clone)]
pub struct Case {
    pub(crate) loaded: LoadedCase,
}
