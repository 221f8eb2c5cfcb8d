//! File formats: VTK frames, CSV series, plots, mesh and point files, atomic writes.

pub mod files;
pub mod mesh_files;
pub mod plot;
pub mod series;
pub mod vtk;
