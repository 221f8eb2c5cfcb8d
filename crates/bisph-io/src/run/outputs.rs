//! The output files of a run besides the CSV series: VTK frames of the fluid and the walls
//! with their `.pvd` indices, and the rows of `body_<name>.csv` for free rigid bodies
//! (position, attitude as quaternion and Euler angles, velocities and accelerations in world
//! and body axes, energies and the fluid's load).

use crate::formats::files::{at, OutputError};
use crate::formats::vtk::{
    write_cells_vtu, write_points_pvtu, write_points_vtu, DataArray, PvdCollection,
};
use bisph_core::bodies::angular_to_3d;
use bisph_core::bodies::FreeBody;
use bisph_core::{Simulation, Vector};
use glam::{DVec3, EulerRot};
use std::path::{Path, PathBuf};

/// VTK frames of the fluid and the walls with their `.pvd` indices. A whole run writes the
/// fluid of a frame as one `.vtu`; a split run writes one `.vtu` piece per part, of its own
/// particles, and the first part writes their `.pvtu` index, the walls and the `.pvd` files.
pub struct Frames {
    dir: PathBuf,
    fluid: PvdCollection,
    walls: PvdCollection,
    times: Vec<f64>,
    /// The fluid file of each frame, relative to `dir`.
    fluid_files: Vec<String>,
}

impl Frames {
    /// Frames written under `dir/vtk`, indexed by `dir/fluid.pvd` and `dir/walls.pvd`.
    pub fn new(dir: &Path) -> Result<Self, OutputError> {
        let vtk = dir.join("vtk");
        at(&vtk, std::fs::create_dir_all(&vtk))?;
        Ok(Frames {
            dir: dir.to_path_buf(),
            fluid: PvdCollection::new(),
            walls: PvdCollection::new(),
            times: Vec::new(),
            fluid_files: Vec::new(),
        })
    }

    /// Frames already written at `times` (a resumed run, split or not as before): the `.pvd`
    /// indices are rewritten by `writer` to list exactly these, and later frames continue the
    /// numbering.
    pub fn resume(dir: &Path, times: &[f64], writer: bool) -> Result<Self, OutputError> {
        let mut frames = Frames::new(dir)?;
        for (k, &t) in times.iter().enumerate() {
            let split = fluid_file(k, true);
            let name = match dir.join(&split).exists() {
                true => split,
                false => fluid_file(k, false),
            };
            frames.push(t, name, k);
        }
        if writer {
            frames.write_indices()?;
        }
        Ok(frames)
    }

    /// Number of frames written.
    pub fn count(&self) -> usize {
        self.times.len()
    }

    /// Times of the frames written.
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// The fluid file of the last frame, relative to the output directory.
    pub fn last_fluid_file(&self) -> Option<String> {
        self.fluid_files.last().cloned()
    }

    fn push(&mut self, time: f64, fluid_name: String, k: usize) {
        self.fluid.push(time, 0, &fluid_name);
        self.walls.push(time, 0, &walls_file(k));
        self.fluid_files.push(fluid_name);
        self.times.push(time);
    }

    fn write_indices(&self) -> Result<(), OutputError> {
        let fluid_pvd = self.dir.join("fluid.pvd");
        at(&fluid_pvd, self.fluid.write(&fluid_pvd))?;
        let walls_pvd = self.dir.join("walls.pvd");
        at(&walls_pvd, self.walls.write(&walls_pvd))
    }

    /// Writes one frame of the current state (every part of a split run must call it).
    pub fn write<V: Vector>(&mut self, sim: &Simulation<V>) -> Result<(), OutputError> {
        let k = self.times.len();
        let wall_pressure = sim.gathered_wall_pressures();
        let name = fluid_file(k, sim.is_part());
        let f = &sim.fluid;
        let own = 0..sim.owned_len();
        let points: Vec<[f64; 3]> = f.position[own.clone()].iter().map(|r| r.to_xyz()).collect();
        let velocity: Vec<f64> = f.velocity[own.clone()]
            .iter()
            .flat_map(|u| u.to_xyz())
            .collect();
        let acceleration: Vec<f64> = f.acceleration[own.clone()]
            .iter()
            .flat_map(|a| a.to_xyz())
            .collect();
        let id: Vec<f64> = f.id[own.clone()].iter().map(|&i| i as f64).collect();
        let array = |name, components, values, integer| DataArray {
            name,
            components,
            values,
            integer,
        };
        let arrays = [
            array("velocity", 3, &velocity, false),
            array("acceleration", 3, &acceleration, false),
            array("pressure", 1, &f.pressure[own.clone()], false),
            array("density", 1, &f.density[own], false),
            array("id", 1, &id, true),
        ];
        let piece = match sim.is_part() {
            true => piece_file(k, sim.rank()),
            false => name.clone(),
        };
        let path = self.dir.join(&piece);
        at(&path, write_points_vtu(&path, &points, &arrays))?;
        if sim.rank() == 0 {
            self.remove_stale(k, sim.is_part().then_some(sim.parts()))?;
            if sim.is_part() {
                // The pieces lie next to their index.
                let pieces: Vec<String> = (0..sim.parts())
                    .map(|r| piece_file(k, r).trim_start_matches("vtk/").to_string())
                    .collect();
                let path = self.dir.join(&name);
                at(&path, write_points_pvtu(&path, &pieces, &arrays))?;
            }
            self.write_walls(sim, &wall_pressure, k)?;
        }
        self.push(sim.time, name, k);
        match sim.rank() {
            0 => self.write_indices(),
            _ => Ok(()),
        }
    }

    /// Removes what an earlier invocation of a resumed run wrote for frame `k` that this one
    /// does not overwrite: the file of the other kind (`.vtu` or `.pvtu`), and the pieces of
    /// parts it does not have (`split`: the number of parts of this run).
    fn remove_stale(&self, k: usize, split: Option<usize>) -> Result<(), OutputError> {
        let mut stale = vec![self.dir.join(fluid_file(k, split.is_none()))];
        let first = split.unwrap_or(0);
        stale.extend(
            (first..)
                .map(|r| self.dir.join(piece_file(k, r)))
                .take_while(|p| p.exists()),
        );
        for path in stale.into_iter().filter(|p| p.exists()) {
            at(&path, std::fs::remove_file(&path))?;
        }
        Ok(())
    }

    /// The walls of frame `k`.
    fn write_walls<V: Vector>(
        &self,
        sim: &Simulation<V>,
        pressure: &[f64],
        k: usize,
    ) -> Result<(), OutputError> {
        let e = &sim.walls.elements;
        let mut vertices = Vec::new();
        let mut cells = Vec::with_capacity(e.len());
        for j in 0..e.len() {
            let start = vertices.len() as u32;
            let corners = e.current_corners(j);
            vertices.extend(corners.iter().map(|c| c.to_xyz()));
            cells.push((start..vertices.len() as u32).collect::<Vec<u32>>());
        }
        let normal: Vec<f64> = e.normal.iter().flat_map(|n| n.to_xyz()).collect();
        let wall_velocity: Vec<f64> = e.velocity.iter().flat_map(|n| n.to_xyz()).collect();
        let body: Vec<f64> = e.body.iter().map(|&b| b as f64).collect();
        let path = self.dir.join(walls_file(k));
        at(
            &path,
            write_cells_vtu(
                &path,
                &vertices,
                &cells,
                &[
                    DataArray {
                        name: "normal",
                        components: 3,
                        values: &normal,
                        integer: false,
                    },
                    DataArray {
                        name: "area",
                        components: 1,
                        values: &e.area,
                        integer: false,
                    },
                    DataArray {
                        name: "pressure",
                        components: 1,
                        values: pressure,
                        integer: false,
                    },
                    DataArray {
                        name: "velocity",
                        components: 3,
                        values: &wall_velocity,
                        integer: false,
                    },
                    DataArray {
                        name: "body",
                        components: 1,
                        values: &body,
                        integer: false,
                    },
                ],
            ),
        )
    }
}

/// The fluid file of frame `k`: a `.vtu`, or the `.pvtu` index of a split run's pieces.
fn fluid_file(k: usize, split: bool) -> String {
    match split {
        true => format!("vtk/fluid_{k:06}.pvtu"),
        false => format!("vtk/fluid_{k:06}.vtu"),
    }
}

/// The piece of frame `k` written by part `rank` of a split run.
fn piece_file(k: usize, rank: usize) -> String {
    format!("vtk/fluid_{k:06}_{rank}.vtu")
}

/// The walls file of frame `k`.
fn walls_file(k: usize) -> String {
    format!("vtk/walls_{k:06}.vtu")
}

/// Columns of `body_<name>.csv`. World axes: `x..`, `vx..`, `ax..`, `wx..` (angular velocity),
/// `alphax..`, `fx..`, `mx..` (fluid force and torque about the centre of mass); body axes:
/// `u, v, w` (velocity), `bax..` (acceleration), `p, q, r` (angular velocity), `balphax..`;
/// attitude: quaternion `qw, qx, qy, qz` (body to world) and Euler angles `roll, pitch, yaw`
/// in degrees (z-y-x sequence: yaw about z, then pitch about y, then roll about x);
/// `kinetic` (translation + rotation) and `potential` (gravity, zero at the start) [J].
pub const FREE_BODY_COLUMNS: [&str; 43] = [
    "t",
    "x",
    "y",
    "z",
    "qw",
    "qx",
    "qy",
    "qz",
    "roll",
    "pitch",
    "yaw",
    "vx",
    "vy",
    "vz",
    "u",
    "v",
    "w",
    "wx",
    "wy",
    "wz",
    "p",
    "q",
    "r",
    "ax",
    "ay",
    "az",
    "bax",
    "bay",
    "baz",
    "alphax",
    "alphay",
    "alphaz",
    "balphax",
    "balphay",
    "balphaz",
    "kinetic",
    "potential",
    "fx",
    "fy",
    "fz",
    "mx",
    "my",
    "mz",
];

/// One row of `body_<name>.csv`.
pub fn free_body_row<V: Vector>(
    t: f64,
    b: &FreeBody,
    centre: V,
    force: V,
    torque: V::Angular,
) -> Vec<f64> {
    let q = b.attitude;
    let inv = q.inverse();
    let (yaw, pitch, roll) = q.to_euler(EulerRot::ZYX);
    let x = DVec3::from_array(centre.to_xyz());
    let f = DVec3::from_array(force.to_xyz());
    let m = angular_to_3d::<V>(torque);
    let mut row = vec![t];
    row.extend(x.to_array());
    row.extend([q.w, q.x, q.y, q.z]);
    row.extend([roll.to_degrees(), pitch.to_degrees(), yaw.to_degrees()]);
    row.extend(b.velocity.to_array());
    row.extend((inv * b.velocity).to_array());
    row.extend(b.world_angular_velocity().to_array());
    row.extend(b.angular_velocity.to_array());
    row.extend(b.acceleration.to_array());
    row.extend((inv * b.acceleration).to_array());
    row.extend(b.world_angular_acceleration().to_array());
    row.extend(b.angular_acceleration.to_array());
    row.extend([b.kinetic_energy(), b.potential_energy()]);
    row.extend(f.to_array());
    row.extend(m.to_array());
    row
}
