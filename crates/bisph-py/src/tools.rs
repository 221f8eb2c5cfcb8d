//! `bisph.shepard` and `bisph.pack`: the Shepard factor of a case's walls at given points,
//! and BIPI packing of a case's blocks, returned as arrays.

use crate::case::Case;
use crate::errors::{bad_argument, case_error};
use crate::run::{run_released, Stop};
use bisph_core::packing::IterationStats;
use bisph_core::walls::shepard::ShepardKind;
use bisph_io::case::fill::pack_block;
use bisph_io::case::{BlockShape, CaseDim};
use bisph_io::run::shepard::gamma_at;
use bisph_io::LoadedCase;
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::ops::ControlFlow;

/// The Shepard factor gamma [-] of the case's walls at `points` (shape `(k, dim)`), as
/// `bisph shepard` prints it. `method`: `"geometric"` (paper 2, eq 9: from the walls alone,
/// 1/2 on a flat wall), `"discrete"` (`sum_j W_ij V_j` over the case's initial fluid
/// particles, paper 2 eq 4) or `"integrated"` (2-D, closed walls: `grad gamma` integrated
/// along a path from gamma = 1, paper 3 eq 4). Returns shape `(k,)`, float64. The GIL is
/// released while computing.
#[pyfunction]
#[pyo3(signature = (case, points, method = "geometric"))]
pub fn shepard<'py>(
    py: Python<'py>,
    case: &Case,
    points: PyReadonlyArray2<'py, f64>,
    method: &str,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let kind: ShepardKind = method
        .parse()
        .map_err(|e: String| bad_argument(format!("method: {e}")))?;
    let dim = case.loaded.case.dim as usize;
    let shape = points.shape();
    if shape[1] != dim {
        return Err(bad_argument(format!(
            "points: expected shape (k, {dim}) for a {dim}-D case, found ({}, {})",
            shape[0], shape[1]
        )));
    }
    let rows: Vec<[f64; 3]> = points
        .as_array()
        .rows()
        .into_iter()
        .map(|r| {
            let mut p = [0.0; 3];
            for (k, &v) in r.iter().enumerate() {
                p[k] = v;
            }
            p
        })
        .collect();
    let loaded = &case.loaded;
    let gamma = py.detach(|| {
        if dim == 2 {
            gamma_at::<glam::DVec2>(loaded, &rows, kind)
        } else {
            gamma_at::<glam::DVec3>(loaded, &rows, kind)
        }
    });
    Ok(PyArray1::from_vec(py, gamma.map_err(bad_argument)?))
}

/// One packed block, as arrays.
struct Packed {
    block: usize,
    dim: usize,
    positions: Vec<f64>,
    lattice: Vec<f64>,
    frozen: Vec<bool>,
    wall_distance: Vec<f64>,
    grad_c: Vec<f64>,
    iterations: usize,
}

/// Packs every block of `loaded` that has a geometry, in `V`'s dimension.
fn pack_all<V: CaseDim>(
    loaded: &LoadedCase,
    stop: &Stop,
) -> Result<Vec<Packed>, bisph_io::CaseError> {
    let mut packed = Vec::new();
    for (k, block) in loaded.case.fluid_block.iter().enumerate() {
        if block.shape == BlockShape::Particles || stop.requested() {
            continue;
        }
        let observe = &mut |_: &IterationStats| match stop.requested() {
            true => ControlFlow::Break(()),
            false => ControlFlow::Continue(()),
        };
        let mut b = pack_block::<V>(loaded, k, observe)?;
        let flat = |points: &[V]| -> Vec<f64> {
            points
                .iter()
                .flat_map(|x| x.to_xyz()[..V::DIM].to_vec())
                .collect()
        };
        let wall_distance = b.packer.wall_distances();
        let grad_c = b.packer.gradc_magnitudes().iter().map(|g| g.0).collect();
        packed.push(Packed {
            block: k,
            dim: V::DIM,
            positions: flat(&b.packer.positions),
            lattice: flat(&b.packer.start),
            frozen: b.packer.frozen.clone(),
            wall_distance,
            grad_c,
            iterations: b.history.len(),
        });
    }
    Ok(packed)
}

/// Packs the case's blocks with BIPI (paper 4: the lattice of step 1 relaxed by
/// `dx = -D (grad C - B / (2 gamma))`, eqs 4-5 and 14-15, in stages 2a-2c), as `bisph pack`
/// does, without writing files. Returns one dict per packed block (blocks of
/// `shape = "particles"` are skipped): `block` (its index in `fluid_block`), `positions`
/// (n, dim) [m], `lattice` (the start, (n, dim)) [m], `frozen` (n,) bool, `wall_distance`
/// (n,) [m], `grad_c` (n,) (|grad C|, [1/m]) and `iterations`. The GIL is released while
/// packing; Ctrl-C stops it after the iteration in progress (KeyboardInterrupt).
#[pyfunction]
pub fn pack<'py>(py: Python<'py>, case: &Case) -> PyResult<Bound<'py, PyList>> {
    let loaded = &case.loaded;
    let stop = Stop::default();
    let packed = run_released(py, None, &stop, || {
        if loaded.case.dim == 2 {
            pack_all::<glam::DVec2>(loaded, &stop)
        } else {
            pack_all::<glam::DVec3>(loaded, &stop)
        }
    });
    if let Some(e) = stop.take_error() {
        return Err(e);
    }
    let list = PyList::empty(py);
    for b in packed.map_err(|e| case_error(&e))? {
        let n = b.frozen.len();
        let d = PyDict::new(py);
        d.set_item("block", b.block)?;
        d.set_item(
            "positions",
            PyArray1::from_vec(py, b.positions).reshape([n, b.dim])?,
        )?;
        d.set_item(
            "lattice",
            PyArray1::from_vec(py, b.lattice).reshape([n, b.dim])?,
        )?;
        d.set_item("frozen", PyArray1::from_vec(py, b.frozen))?;
        d.set_item("wall_distance", PyArray1::from_vec(py, b.wall_distance))?;
        d.set_item("grad_c", PyArray1::from_vec(py, b.grad_c))?;
        d.set_item("iterations", b.iterations)?;
        list.append(d)?;
    }
    Ok(list)
}
