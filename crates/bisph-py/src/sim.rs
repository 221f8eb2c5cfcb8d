//! `bisph.Simulation`: a built case, stepped and run from Python, with its state as NumPy
//! arrays.

use crate::case::Case;
use crate::errors::{bad_argument, case_error, run_error};
use crate::run::{progress_callable, run_released, Stop};
use crate::solver::{ElementField, ParticleField, Solver};
use bisph_io::case::CaseDim;
use bisph_io::run::settle::SettlingSummary;
use bisph_io::run::{build_checked, settle_fresh};
use bisph_io::{parse_case, LoadedCase, RunError, RunOptions};
use numpy::ndarray::{Array2, ArrayView1, ArrayView2};
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use rayon::{ThreadPool, ThreadPoolBuilder};
use std::path::PathBuf;
use std::sync::Arc;

/// A simulation built from a `bisph.Case` (by `Case.build`): the state of `bisph run` at
/// `t = 0`, settled when the case settles, advanced by `step()` and `run()`.
///
/// Particle arrays (`positions`, `velocities`, `accelerations`, `density`, `pressure`,
/// `mass`, `gamma`) are copies, in particle-id order (the order in which the case's blocks
/// created them): the solver reorders its particles by cell and swaps its buffers while it
/// steps, so a view would dangle. Element arrays (`element_centres`, `element_normals`,
/// `element_areas`, `element_pressures`, `element_velocities`, `element_bodies`) are
/// read-only views of the solver's own buffers, which are allocated once when the case is
/// built and updated in place: they show the current values after every step (take
/// `.copy()` to keep one), and each keeps its simulation alive.
#[pyclass(module = "bisph")]
pub struct Simulation {
    solver: Box<dyn Solver>,
    loaded: LoadedCase,
    pool: Option<Arc<ThreadPool>>,
    settling: Option<SettlingSummary>,
}

/// Builds the simulation of `loaded` (see `Case.build`).
pub fn build(
    py: Python<'_>,
    loaded: LoadedCase,
    threads: Option<usize>,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<Simulation> {
    let progress = progress_callable(progress)?;
    let pool = match threads {
        Some(0) => return Err(bad_argument("threads: expected a positive number")),
        Some(n) => Some(Arc::new(
            ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| bad_argument(format!("threads: {e}")))?,
        )),
        None => None,
    };
    let stop = Stop::default();
    let progress = progress.as_ref();
    let built = run_released(py, pool.as_deref(), &stop, || {
        if loaded.case.dim == 2 {
            build_in::<glam::DVec2>(&loaded, &stop, progress)
        } else {
            build_in::<glam::DVec3>(&loaded, &stop, progress)
        }
    });
    if let Some(e) = stop.take_error() {
        return Err(e);
    }
    let (solver, settling) = built.map_err(|e| run_error(&e))?;
    Ok(Simulation {
        solver,
        loaded,
        pool,
        settling,
    })
}

/// The memory check, the build, the geometry checks and settling of `bisph run`, in `V`'s
/// dimension.
fn build_in<V: CaseDim>(
    loaded: &LoadedCase,
    stop: &Stop,
    progress: Option<&Py<PyAny>>,
) -> Result<(Box<dyn Solver>, Option<SettlingSummary>), RunError> {
    let mut sim = build_checked::<V>(loaded)?;
    let report = &mut |p: bisph_io::Progress| stop.report(progress, p.into());
    let settling = settle_fresh(loaded, &mut sim, Some(&stop.flag), report)?;
    Ok((Box::new(sim), settling))
}

/// A JSON text as Python objects.
fn from_json<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (text,))
}

impl Simulation {
    /// A copy of a particle quantity: shape `(n,)` or `(n, dim)`.
    fn particles<'py>(&self, py: Python<'py>, field: ParticleField) -> Bound<'py, PyAny> {
        let (values, cols) = self.solver.particle_field(field);
        if cols == 1 {
            return PyArray1::from_vec(py, values).into_any();
        }
        let rows = values.len() / cols;
        match Array2::from_shape_vec((rows, cols), values) {
            Ok(a) => a.into_pyarray(py).into_any(),
            Err(_) => unreachable!("{rows} rows of {cols} values make a ({rows}, {cols}) array"),
        }
    }

    /// A read-only view of an element quantity: shape `(m,)` or `(m, dim)`.
    fn elements<'py>(slf: &Bound<'py, Self>, field: ElementField) -> PyResult<Bound<'py, PyAny>> {
        let this = slf.try_borrow()?;
        let (values, cols) = this.solver.element_field(field);
        let owner = slf.clone().into_any();
        // SAFETY: the element buffers are allocated when the case is built and only written
        // in place afterwards (never reallocated), and `owner` keeps them alive.
        let array = unsafe {
            if cols == 1 {
                PyArray1::borrow_from_array(&ArrayView1::from(values), owner).into_any()
            } else {
                let view = ArrayView2::from_shape((values.len() / cols, cols), values)
                    .map_err(|e| bad_argument(e.to_string()))?;
                PyArray2::borrow_from_array(&view, owner).into_any()
            }
        };
        read_only(array)
    }
}

/// `array` with its write flag cleared.
fn read_only(array: Bound<'_, PyAny>) -> PyResult<Bound<'_, PyAny>> {
    let flags = PyDict::new(array.py());
    flags.set_item("write", false)?;
    array.call_method("setflags", (), Some(&flags))?;
    Ok(array)
}

#[pymethods]
impl Simulation {
    /// Simulated time t [s] (0 after building; settling happens before t = 0).
    #[getter]
    fn time(&self) -> f64 {
        self.solver.time()
    }

    /// The size of the next step [s]: `Co min(h/c0, sqrt(h / max|a|))`, at most
    /// `h^2 / (8 nu)` (`time.courant`, or `time.dt` when fixed).
    #[getter]
    fn dt(&self) -> f64 {
        self.solver.next_dt()
    }

    /// Steps taken since t = 0.
    #[getter]
    fn steps(&self) -> u64 {
        self.solver.steps()
    }

    /// The dimension, 2 or 3.
    #[getter]
    fn dim(&self) -> usize {
        self.solver.dim()
    }

    /// The number of fluid particles.
    #[getter]
    fn n_particles(&self) -> usize {
        self.solver.particle_count()
    }

    /// The number of boundary elements.
    #[getter]
    fn n_elements(&self) -> usize {
        self.solver.element_count()
    }

    /// The threads this simulation steps on (its own pool when built with `threads=`).
    #[getter]
    fn threads(&self) -> usize {
        match &self.pool {
            Some(pool) => pool.current_num_threads(),
            None => rayon::current_num_threads(),
        }
    }

    /// The case it was built from.
    #[getter]
    fn case(&self) -> Case {
        Case {
            loaded: self.loaded.clone(),
        }
    }

    /// What settling before t = 0 did (the `settling` entry of `summary.json`), or `None`
    /// when the case does not settle.
    #[getter]
    fn settling<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        match &self.settling {
            None => Ok(None),
            Some(s) => {
                let text = serde_json::to_string(s).map_err(|e| bad_argument(e.to_string()))?;
                from_json(py, &text).map(Some)
            }
        }
    }

    /// Particle ids, shape (n,), uint32, increasing: the rows of the particle arrays (ids
    /// count from 0 in the order the case's blocks created the particles; the ids of
    /// particles removed as they left the domain are missing).
    #[getter]
    fn ids<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        PyArray1::from_vec(py, self.solver.particle_ids())
    }

    /// Particle positions r_i [m], shape (n, dim), float64; a copy in particle-id order.
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        self.particles(py, ParticleField::Position)
    }

    /// Particle velocities u_i [m/s], shape (n, dim), float64; a copy in particle-id order.
    #[getter]
    fn velocities<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        self.particles(py, ParticleField::Velocity)
    }

    /// Particle accelerations du_i/dt of the last rate evaluation [m/s^2], shape (n, dim),
    /// float64; a copy in particle-id order.
    #[getter]
    fn accelerations<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        self.particles(py, ParticleField::Acceleration)
    }

    /// Particle densities rho_i [kg/m^3], shape (n,), float64; a copy in particle-id order.
    #[getter]
    fn density<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        self.particles(py, ParticleField::Density)
    }

    /// Particle pressures p_i [Pa] from the equation of state (linear, paper 1 eq 3, or
    /// Tait, paper 3 eq 15), shape (n,), float64; a copy in particle-id order.
    #[getter]
    fn pressure<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        self.particles(py, ParticleField::Pressure)
    }

    /// Particle masses m_i [kg; kg/m in 2-D], shape (n,), float64; a copy in particle-id
    /// order.
    #[getter]
    fn mass<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        self.particles(py, ParticleField::Mass)
    }

    /// Shepard factors gamma_i [-] (1 where the wall model does not carry one; paper 2 and
    /// paper 3 eq 4), shape (n,), float64; a copy in particle-id order.
    #[getter]
    fn gamma<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        self.particles(py, ParticleField::Gamma)
    }

    /// Element centres r_j [m], shape (m, dim), float64; a read-only live view.
    #[getter]
    fn element_centres<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Simulation::elements(slf, ElementField::Centre)
    }

    /// Element unit normals n_j, out of the fluid, shape (m, dim), float64; a read-only
    /// live view.
    #[getter]
    fn element_normals<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Simulation::elements(slf, ElementField::Normal)
    }

    /// Element areas s_j [m^2; lengths in m in 2-D], shape (m,), float64; a read-only live
    /// view.
    #[getter]
    fn element_areas<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Simulation::elements(slf, ElementField::Area)
    }

    /// Wall pressures P_j [Pa] (paper 1 eq 71 for `boundary = "energy"`; extrapolated from
    /// the fluid for `bi` and `usaw`), shape (m,), float64; a read-only live view.
    #[getter]
    fn element_pressures<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Simulation::elements(slf, ElementField::Pressure)
    }

    /// Element velocities U_j [m/s], shape (m, dim), float64; a read-only live view.
    #[getter]
    fn element_velocities<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Simulation::elements(slf, ElementField::Velocity)
    }

    /// The owning body of each element (an index into `bodies`), shape (m,), uint32; a
    /// read-only view.
    #[getter]
    fn element_bodies<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let this = slf.try_borrow()?;
        let view = ArrayView1::from(this.solver.element_bodies());
        // SAFETY: as for the other element views.
        let array = unsafe { PyArray1::borrow_from_array(&view, slf.clone().into_any()) };
        read_only(array.into_any())
    }

    /// The energy budget now [J; J/m in 2-D], the columns of `energy.csv`: `kinetic`,
    /// `compressible` (sum m e(rho)), `potential` (-sum m g . r), `wall_work`
    /// (int sum F_j . U_j dt, paper 1), `viscous_dissipation`, `forcing_work`, `diffusion_dissipation`
    /// (the compressible energy the density diffusion removed), `removed` (the energy of the
    /// particles removed as they left the domain) and `total`.
    #[getter]
    fn energy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let e = self.solver.energy();
        let d = PyDict::new(py);
        d.set_item("kinetic", e.kinetic)?;
        d.set_item("compressible", e.compressible)?;
        d.set_item("potential", e.potential)?;
        d.set_item("wall_work", e.wall_work)?;
        d.set_item("total", e.total)?;
        d.set_item("viscous_dissipation", e.viscous_dissipation)?;
        d.set_item("forcing_work", e.forcing_work)?;
        d.set_item("diffusion_dissipation", e.diffusion_dissipation)?;
        d.set_item("removed", e.removed)?;
        Ok(d)
    }

    /// The case's probes now, by name: pressures [Pa] (`pressure`, `wall_pressure`) and water
    /// heights [m] (`height`), as in `probes.csv`.
    #[getter]
    fn probes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (name, value) in self.solver.probes() {
            d.set_item(name, value)?;
        }
        Ok(d)
    }

    /// The bodies now, one dict each: `name`, `motion` (`fixed`, `prescribed`, `piston`,
    /// `free`), `centre` [m], `velocity` [m/s], `rotation` [rad], `angular_velocity`
    /// [rad/s], and the fluid's `force` [N; N/m in 2-D] and `moment` about the centre on its
    /// walls (as in `forces.csv`).
    #[getter]
    fn bodies<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for b in self.solver.bodies() {
            let d = PyDict::new(py);
            d.set_item("name", b.name)?;
            d.set_item("motion", b.motion)?;
            d.set_item("centre", PyArray1::from_vec(py, b.centre))?;
            d.set_item("velocity", PyArray1::from_vec(py, b.velocity))?;
            d.set_item("rotation", PyArray1::from_vec(py, b.rotation))?;
            d.set_item(
                "angular_velocity",
                PyArray1::from_vec(py, b.angular_velocity),
            )?;
            d.set_item("force", PyArray1::from_vec(py, b.force))?;
            d.set_item("moment", PyArray1::from_vec(py, b.moment))?;
            list.append(d)?;
        }
        Ok(list)
    }

    /// Advances one step of size `dt`, with the GIL released. A failed step raises
    /// `bisph.RunError`.
    fn step(&mut self, py: Python<'_>) -> PyResult<()> {
        let solver = &mut self.solver;
        let result = py.detach(|| match &self.pool {
            Some(pool) => pool.install(|| solver.step(None)),
            None => solver.step(None),
        });
        result.map_err(|f| f.into_py())
    }

    /// Runs to time `until` [s] (the case's `time.end` by default) with the GIL released.
    ///
    /// With `out`, this is `bisph run`'s own loop: it writes the same files into the folder
    /// `out` (energy.csv, forces.csv, probes.csv, VTK frames, summary.json, plots) with
    /// values identical to the command line's for the same case, the series starting at the
    /// current time, and returns the summary (`summary.json`) as a dict. Without `out` it
    /// takes the same steps and writes nothing (and returns `None`); the divergence watches
    /// of `[diagnostics]` run only with `out`.
    ///
    /// `progress`: a callable given a `bisph.Progress` after every step. Ctrl-C (or any
    /// signal handler that raises) stops the run at the next step boundary and raises
    /// KeyboardInterrupt; the simulation stays usable at the state reached (with `out`, a
    /// checkpoint is written there, as `bisph run` does, so `bisph run --resume out`
    /// continues it). An exception raised by `progress` stops the run the same way.
    #[pyo3(signature = (until = None, out = None, progress = None))]
    fn run<'py>(
        &mut self,
        py: Python<'py>,
        until: Option<f64>,
        out: Option<PathBuf>,
        progress: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Option<Bound<'py, PyAny>>> {
        let progress = progress_callable(progress)?;
        let case_end = self.loaded.case.time.end;
        let end = until.unwrap_or(case_end);
        if !end.is_finite() {
            return Err(bad_argument(format!(
                "until: expected a finite time, found {end}"
            )));
        }
        let stop = Stop::default();
        let progress = progress.as_ref();
        let solver = &mut self.solver;
        let pool = self.pool.as_deref();
        let Some(out) = out else {
            let result = run_released(py, pool, &stop, || solver.run_to(end, &stop, progress));
            if let Some(e) = stop.take_error() {
                return Err(e);
            }
            return result.map(|()| None).map_err(|f| f.into_py());
        };
        let loaded = if end == case_end {
            self.loaded.clone()
        } else {
            let l = &self.loaded;
            parse_case(&l.source, &l.text, &[format!("time.end={end:?}")])
                .map_err(|e| case_error(&e))?
        };
        // The settling report belongs to a run from the settled start.
        let settling = self.settling.clone().filter(|_| solver.steps() == 0);
        let options = RunOptions {
            stop: Some(&stop.flag),
            ..RunOptions::default()
        };
        let report = &mut |p: bisph_io::Progress| stop.report(progress, p.into());
        let result = run_released(py, pool, &stop, || {
            solver.run_with_outputs(&loaded, settling, &out, &options, report)
        });
        if let Some(e) = stop.take_error() {
            return Err(e);
        }
        let summary = result.map_err(|e| run_error(&e))?;
        let text = serde_json::to_string(&summary).map_err(|e| bad_argument(e.to_string()))?;
        from_json(py, &text).map(Some)
    }

    fn __repr__(&self) -> String {
        format!(
            "Simulation(case={:?}, dim={}, particles={}, elements={}, time={}, steps={})",
            self.loaded.case.name,
            self.solver.dim(),
            self.solver.particle_count(),
            self.solver.element_count(),
            self.solver.time(),
            self.solver.steps()
        )
    }
}
