//! Output files of a run: CSV series (appended and flushed row by row, so a killed run keeps
//! every completed row), VTK frames with `.pvd` indices, `summary.json`, plots.

use crate::vtk::{write_cells_vtu, write_points_vtu, DataArray, PvdCollection};
use bisph_core::{Simulation, Vector};
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// An I/O failure, with the file it concerns.
#[derive(Debug)]
pub struct OutputError {
    /// The file.
    pub path: PathBuf,
    /// What went wrong.
    pub source: io::Error,
}

impl std::fmt::Display for OutputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "cannot write {}: {}", self.path.display(), self.source)
    }
}

impl std::error::Error for OutputError {}

/// Attaches the path to an I/O result.
pub fn at<T>(path: &Path, r: io::Result<T>) -> Result<T, OutputError> {
    r.map_err(|source| OutputError {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes `bytes` to `path` through a temporary file (synced to disk) and a rename, so a crash
/// leaves the old file or the new one, never a half-written one. On failure the temporary file
/// is removed and the old file kept.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".tmp");
    let tmp = path.with_file_name(name);
    let written = (|| {
        let mut f = File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()
    })();
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(OutputError {
            path: path.to_path_buf(),
            source: e,
        });
    }
    at(path, std::fs::rename(&tmp, path))
}

/// A CSV time series: header first, then one flushed row per call (a killed run keeps every
/// completed row). Its length in bytes is tracked so a resumed run can cut it back to a
/// checkpoint.
pub struct Series {
    path: PathBuf,
    out: BufWriter<File>,
    len: u64,
}

impl Series {
    /// Creates the file with its header.
    pub fn create(path: PathBuf, header: &[String]) -> Result<Self, OutputError> {
        let file = at(&path, File::create(&path))?;
        let mut s = Series {
            path,
            out: BufWriter::new(file),
            len: 0,
        };
        let line = header.join(",");
        s.line(&line)?;
        Ok(s)
    }

    /// Reopens an existing series cut back to its first `len` bytes (a checkpoint's length),
    /// appending after them.
    pub fn reopen(path: PathBuf, len: u64) -> Result<Self, OutputError> {
        let file = at(
            &path,
            std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .open(&path),
        )?;
        let found = at(&path, file.metadata())?.len();
        if found < len {
            return Err(OutputError {
                path,
                source: io::Error::new(
                    io::ErrorKind::UnexpectedEof,
                    format!("the file has {found} bytes, the checkpoint expects {len}"),
                ),
            });
        }
        at(&path, file.set_len(len))?;
        let mut file = file;
        at(&path, io::Seek::seek(&mut file, io::SeekFrom::End(0)))?;
        Ok(Series {
            path,
            out: BufWriter::new(file),
            len,
        })
    }

    /// Bytes written so far (header included).
    pub fn len(&self) -> u64 {
        self.len
    }

    /// `true` before the header is written (never, once created).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn line(&mut self, line: &str) -> Result<(), OutputError> {
        at(
            &self.path,
            writeln!(self.out, "{line}").and_then(|_| self.out.flush()),
        )?;
        self.len += line.len() as u64 + 1;
        Ok(())
    }

    /// Appends one row (full precision) and flushes it.
    pub fn row(&mut self, values: &[f64]) -> Result<(), OutputError> {
        let mut line = String::with_capacity(24 * values.len());
        for (k, v) in values.iter().enumerate() {
            if k > 0 {
                line.push(',');
            }
            line.push_str(&format!("{v:e}"));
        }
        self.line(&line)
    }

    /// Appends a row whose second column is a name.
    pub fn named_row(&mut self, t: f64, name: &str, values: &[f64]) -> Result<(), OutputError> {
        let mut line = format!("{t:e},{name}");
        for v in values {
            line.push_str(&format!(",{v:e}"));
        }
        self.line(&line)
    }
}

/// VTK frames of the fluid and the walls with their `.pvd` indices.
pub struct Frames {
    dir: PathBuf,
    fluid: PvdCollection,
    walls: PvdCollection,
    times: Vec<f64>,
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
        })
    }

    /// Frames already written at `times` (a resumed run): the `.pvd` indices are rewritten
    /// to list exactly these, and later frames continue the numbering.
    pub fn resume(dir: &Path, times: &[f64]) -> Result<Self, OutputError> {
        let mut frames = Frames::new(dir)?;
        for (k, &t) in times.iter().enumerate() {
            frames.fluid.push(t, 0, &format!("vtk/fluid_{k:06}.vtu"));
            frames.walls.push(t, 0, &format!("vtk/walls_{k:06}.vtu"));
        }
        frames.times = times.to_vec();
        frames.write_indices()?;
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
        let k = self.times.len().checked_sub(1)?;
        Some(format!("vtk/fluid_{k:06}.vtu"))
    }

    fn write_indices(&self) -> Result<(), OutputError> {
        let fluid_pvd = self.dir.join("fluid.pvd");
        at(&fluid_pvd, self.fluid.write(&fluid_pvd))?;
        let walls_pvd = self.dir.join("walls.pvd");
        at(&walls_pvd, self.walls.write(&walls_pvd))
    }

    /// Writes one frame of the current state.
    pub fn write<V: Vector>(&mut self, sim: &Simulation<V>) -> Result<(), OutputError> {
        let k = self.times.len();
        let f = &sim.fluid;
        let points: Vec<[f64; 3]> = f.position.iter().map(|r| r.to_xyz()).collect();
        let velocity: Vec<f64> = f.velocity.iter().flat_map(|u| u.to_xyz()).collect();
        let acceleration: Vec<f64> = f.acceleration.iter().flat_map(|a| a.to_xyz()).collect();
        let id: Vec<f64> = f.id.iter().map(|&i| i as f64).collect();
        let fluid_name = format!("vtk/fluid_{k:06}.vtu");
        let path = self.dir.join(&fluid_name);
        at(
            &path,
            write_points_vtu(
                &path,
                &points,
                &[
                    DataArray {
                        name: "velocity",
                        components: 3,
                        values: &velocity,
                    },
                    DataArray {
                        name: "acceleration",
                        components: 3,
                        values: &acceleration,
                    },
                    DataArray {
                        name: "pressure",
                        components: 1,
                        values: &f.pressure,
                    },
                    DataArray {
                        name: "density",
                        components: 1,
                        values: &f.density,
                    },
                    DataArray {
                        name: "id",
                        components: 1,
                        values: &id,
                    },
                ],
            ),
        )?;
        self.fluid.push(sim.time, 0, &fluid_name);

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
        let walls_name = format!("vtk/walls_{k:06}.vtu");
        let path = self.dir.join(&walls_name);
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
                    },
                    DataArray {
                        name: "area",
                        components: 1,
                        values: &e.area,
                    },
                    DataArray {
                        name: "pressure",
                        components: 1,
                        values: &e.pressure,
                    },
                    DataArray {
                        name: "velocity",
                        components: 3,
                        values: &wall_velocity,
                    },
                    DataArray {
                        name: "body",
                        components: 1,
                        values: &body,
                    },
                ],
            ),
        )?;
        self.walls.push(sim.time, 0, &walls_name);
        self.times.push(sim.time);
        self.write_indices()
    }
}
