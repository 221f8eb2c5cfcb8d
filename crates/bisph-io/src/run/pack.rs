//! `bisph pack`: BIPI (paper 4) on every block of a case, with its outputs.
//!
//! Writes into the output folder:
//! - `pack.csv`: `iteration,kinetic,tpd,gradc_mean,gradc_max` (contract; `gradc_*` over
//!   particles with `gamma = 1`, as paper 4's figs 6, 7, 10), then `gradc_mean_all,
//!   gradc_max_all` (over all particles), `moved`, `stage` (0 lattice, 1 step 2a, 3 step 2c),
//!   `block`, `first_layer` (mean wall distance / dx of the particles closer than dx to a
//!   wall), `gradc_mean_deep` (mean over the particles beyond the first layer). `kinetic = 1/2 sum m |dx|^2` takes the shift per iteration as the velocity;
//!   `tpd = sum |x - x0|` [m]. Units of `|grad C|`: 1/m.
//! - `particles.vtu` (packed, with `block`, `grad_c`, `wall_distance`, `displacement`,
//!   `frozen`), `lattice.vtu` (the start), `walls.vtu` (the boundary elements);
//! - `particles-<k>.csv` (`x,y[,z]`) per block and `packed.toml`: the case with every
//!   fluid block read from its packed file (extra columns `grad_c,wall_distance,frozen`
//!   are for inspection), ready for `bisph run packed.toml`;
//! - `summary.json` (per block: counts, iterations, timings, `|grad C|` before and after, the
//!   first layer's distance to the wall); `pack-<k>.png` plots.

use crate::case::dim::CaseDim;
use crate::case::fill::{pack_block, PackedBlock};
use crate::case::schema::{BlockShape, LoadedCase};
use crate::formats::files::{at, write_atomic};
use crate::formats::plot::{write_png, Plot, Series as PlotSeries, Style};
use crate::formats::vtk::{write_cells_vtu, write_points_vtu, DataArray};
use crate::run::error::RunError;
use bisph_core::packing::{IterationStats, Packer, Stage};
use serde::Serialize;
use std::fmt::Write as _;
use std::ops::ControlFlow;
use std::path::Path;
use std::time::Instant;

/// Distances of the first layer to the wall, in units of `dx`.
#[derive(Debug, Clone, Copy, Serialize, Default)]
pub struct LayerStats {
    /// Particles closer than `dx` to a wall.
    pub count: usize,
    /// Mean distance / dx.
    pub mean: f64,
    /// Standard deviation / dx.
    pub std: f64,
    /// Smallest / dx.
    pub min: f64,
    /// Largest / dx.
    pub max: f64,
}

impl LayerStats {
    /// Statistics of the distances below `dx` (the first layer).
    pub fn of(distances: &[f64], dx: f64) -> Self {
        let d: Vec<f64> = distances
            .iter()
            .filter(|&&d| d < dx)
            .map(|d| d / dx)
            .collect();
        if d.is_empty() {
            return LayerStats::default();
        }
        let n = d.len() as f64;
        let mean = d.iter().sum::<f64>() / n;
        let var = d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n;
        LayerStats {
            count: d.len(),
            mean,
            std: var.sqrt(),
            min: d.iter().copied().fold(f64::INFINITY, f64::min),
            max: d.iter().copied().fold(0.0, f64::max),
        }
    }
}

/// `summary.json` entry of one block.
#[derive(Debug, Clone, Serialize)]
pub struct BlockSummary {
    /// Block index.
    pub block: usize,
    /// A solid body's particles.
    pub solid: bool,
    /// Particles.
    pub particles: usize,
    /// Spacing.
    pub dx: f64,
    /// Smoothing length.
    pub h: f64,
    /// Boundary elements.
    pub boundary_elements: usize,
    /// Radius of the boundary push in use, in `dx`.
    pub push_radius: f64,
    /// Area (2-D) or volume (3-D) of the region.
    pub region_measure: f64,
    /// Particles times `dx^d`.
    pub particle_measure: f64,
    /// Iterations of step 2a.
    pub stage_a_iterations: usize,
    /// Iterations of step 2c.
    pub stage_c_iterations: usize,
    /// Seconds of step 2.
    pub seconds: f64,
    /// Seconds per iteration.
    pub seconds_per_iteration: f64,
    /// Mean |grad C| over particles with gamma = 1, lattice / packed.
    pub gradc_mean: [f64; 2],
    /// Largest |grad C| over particles with gamma = 1, lattice / packed.
    pub gradc_max: [f64; 2],
    /// Mean |grad C| over all particles, lattice / packed.
    pub gradc_mean_all: [f64; 2],
    /// Largest |grad C| over all particles, lattice / packed.
    pub gradc_max_all: [f64; 2],
    /// Mean |grad C| over the particles at least dx from every wall, lattice / packed.
    pub gradc_mean_deep: [f64; 2],
    /// Change of the first layer's mean wall distance (/ dx) over the second half of step
    /// 2a (between its last evaluated iteration and the latest one at or before half-way):
    /// how settled the layer that step 2b freezes is (NaN without such iterations).
    pub first_layer_drift: f64,
    /// First layer (closer than dx to a wall) on the lattice.
    pub first_layer_lattice: LayerStats,
    /// First layer after packing.
    pub first_layer: LayerStats,
    /// Packed particles not strictly inside the region (must be 0).
    pub outside: usize,
}

/// `summary.json` of `bisph pack`.
#[derive(Debug, Clone, Serialize)]
pub struct PackSummary {
    /// Case name.
    pub case: String,
    /// Dimension.
    pub dim: usize,
    /// Blocks.
    pub blocks: Vec<BlockSummary>,
    /// Wall seconds in all.
    pub wall_seconds: f64,
}

/// Packs every block of a case and writes the outputs (see the module doc) into `out`.
pub fn pack_case(
    loaded: &LoadedCase,
    out: &Path,
    progress: &mut dyn FnMut(usize, &IterationStats),
) -> Result<PackSummary, RunError> {
    if loaded.case.dim == 2 {
        pack_dim::<glam::DVec2>(loaded, out, progress)
    } else {
        pack_dim::<glam::DVec3>(loaded, out, progress)
    }
}

/// `|L(end) - L(mid)|` of the first layer's mean wall distance `L` over step 2a, where `end`
/// is 2a's last evaluated iteration and `mid` the latest evaluated one at or before half of
/// it (see [`BlockSummary::first_layer_drift`]).
fn first_layer_drift(history: &[IterationStats]) -> f64 {
    let a: Vec<&IterationStats> = history
        .iter()
        .filter(|s| s.stage == Stage::A && s.first_layer.is_finite())
        .collect();
    let Some(end) = a.last() else {
        return f64::NAN;
    };
    let half = end.iteration / 2;
    a.iter()
        .rev()
        .find(|s| s.iteration <= half)
        .map_or(f64::NAN, |mid| (end.first_layer - mid.first_layer).abs())
}

fn stage_code(s: Stage) -> f64 {
    match s {
        Stage::Start => 0.0,
        Stage::A => 1.0,
        Stage::C => 3.0,
    }
}

/// The header of `pack.csv`.
const PACK_CSV_HEADER: &str =
    "iteration,kinetic,tpd,gradc_mean,gradc_max,gradc_mean_all,gradc_max_all,moved,stage,block,\
     first_layer,gradc_mean_deep\n";

/// What the blocks of a case add up to across the pack: `pack.csv` rows, the points and
/// point data of `particles.vtu` and `lattice.vtu`, the cells of `walls.vtu`.
#[derive(Default)]
struct PackOutputs {
    csv: String,
    all_points: Vec<[f64; 3]>,
    lattice_points: Vec<[f64; 3]>,
    block_id: Vec<f64>,
    gradc: Vec<f64>,
    dist: Vec<f64>,
    disp: Vec<f64>,
    frozen: Vec<f64>,
    wall_vertices: Vec<[f64; 3]>,
    wall_cells: Vec<Vec<u32>>,
    wall_normals: Vec<f64>,
    wall_block: Vec<f64>,
}

/// Packs every block of a case in `V`'s dimension and writes the outputs into `out`.
fn pack_dim<V: CaseDim>(
    loaded: &LoadedCase,
    out: &Path,
    progress: &mut dyn FnMut(usize, &IterationStats),
) -> Result<PackSummary, RunError> {
    let started = Instant::now();
    at(out, std::fs::create_dir_all(out))?;
    write_atomic(&out.join("case.toml"), loaded.text.as_bytes())?;
    let case = &loaded.case;
    let mut outputs = PackOutputs {
        csv: String::from(PACK_CSV_HEADER),
        ..PackOutputs::default()
    };
    let mut summaries = Vec::new();
    let mut packed_doc: toml::Table = loaded
        .text
        .parse()
        .map_err(|e: toml::de::Error| RunError::Case(loaded.error("", e.to_string())))?;
    let mut kept_blocks = Vec::new();
    for (k, block) in case.fluid_block.iter().enumerate() {
        if block.shape == BlockShape::Particles {
            if let Some(b) = case_block(&packed_doc, k) {
                kept_blocks.push(b.clone());
            }
            continue;
        }
        let observe = &mut |s: &IterationStats| {
            progress(k, s);
            ControlFlow::Continue(())
        };
        let mut packed = pack_block::<V>(loaded, k, observe).map_err(RunError::Case)?;
        append_history_rows(&mut outputs.csv, k, &packed.history);
        let distances = packed.packer.wall_distances();
        summaries.push(block_summary(k, block.solid, &packed, &distances));
        let name = format!("particles-{k}.csv");
        let file = particle_rows(&mut packed, k, &distances, &mut outputs);
        write_atomic(&out.join(&name), file.as_bytes())?;
        append_walls(&packed.packer, k, &mut outputs);
        if !block.solid {
            if let Some(b) = packed_block_entry(&packed_doc, k, &name, packed.packer.params.dx) {
                kept_blocks.push(b);
            }
        }
        plot_block(out, k, &packed.history)?;
        packed.history.clear();
    }
    write_vtk_files(out, &outputs)?;
    write_atomic(&out.join("pack.csv"), outputs.csv.as_bytes())?;
    packed_doc.insert("fluid_block".into(), toml::Value::Array(kept_blocks));
    write_packed_toml(out, &case.name, &packed_doc)?;
    let summary = PackSummary {
        case: case.name.clone(),
        dim: V::DIM,
        blocks: summaries,
        wall_seconds: started.elapsed().as_secs_f64(),
    };
    let json = serde_json::to_string_pretty(&summary).unwrap_or_default();
    write_atomic(&out.join("summary.json"), json.as_bytes())?;
    Ok(summary)
}

/// Entry `k` of the case's `[[fluid_block]]` array in its TOML document.
fn case_block(doc: &toml::Table, k: usize) -> Option<&toml::Value> {
    doc.get("fluid_block")
        .and_then(|v| v.as_array())
        .and_then(|a| a.get(k))
}

/// Appends the `pack.csv` rows of block `k`'s iterations.
fn append_history_rows(csv: &mut String, k: usize, history: &[IterationStats]) {
    for s in history {
        let _ = writeln!(
            csv,
            "{},{:e},{:e},{:e},{:e},{:e},{:e},{},{},{},{:e},{:e}",
            s.iteration,
            s.kinetic,
            s.tpd,
            s.gradc_mean,
            s.gradc_max,
            s.gradc_mean_all,
            s.gradc_max_all,
            s.moved,
            stage_code(s.stage),
            k,
            s.first_layer,
            s.gradc_mean_deep
        );
    }
}

/// The `summary.json` entry of packed block `k`, given its particles' wall distances.
fn block_summary<V: CaseDim>(
    k: usize,
    solid: bool,
    packed: &PackedBlock<V>,
    distances: &[f64],
) -> BlockSummary {
    let p = &packed.packer;
    let start_distances: Vec<f64> = p.start.iter().map(|&x| p.walls.distance(x)).collect();
    let dx = p.params.dx;
    let outside = p
        .positions
        .iter()
        .filter(|&&x| !packed.region.contains(x))
        .count();
    let (first, last) = (packed.history[0], *packed.history.last().unwrap());
    let iterations_a = packed
        .history
        .iter()
        .filter(|s| s.stage == Stage::A)
        .count();
    let iterations_c = packed
        .history
        .iter()
        .filter(|s| s.stage == Stage::C)
        .count()
        .saturating_sub(1);
    let iterations = (iterations_a + iterations_c).max(1);
    BlockSummary {
        block: k,
        solid,
        particles: p.positions.len(),
        dx,
        h: p.params.h,
        boundary_elements: p.walls.elements.len(),
        push_radius: p.push_radius,
        region_measure: packed.region.measure,
        particle_measure: p.positions.len() as f64 * p.volume(),
        stage_a_iterations: iterations_a,
        stage_c_iterations: iterations_c,
        seconds: packed.seconds,
        seconds_per_iteration: packed.seconds / iterations as f64,
        gradc_mean: [first.gradc_mean, last.gradc_mean],
        gradc_max: [first.gradc_max, last.gradc_max],
        gradc_mean_all: [first.gradc_mean_all, last.gradc_mean_all],
        gradc_max_all: [first.gradc_max_all, last.gradc_max_all],
        gradc_mean_deep: [first.gradc_mean_deep, last.gradc_mean_deep],
        first_layer_drift: first_layer_drift(&packed.history),
        first_layer_lattice: LayerStats::of(&start_distances, dx),
        first_layer: LayerStats::of(distances, dx),
        outside,
    }
}

/// The text of `particles-<k>.csv` for packed block `k`; adds its particles to the VTK point
/// data.
fn particle_rows<V: CaseDim>(
    packed: &mut PackedBlock<V>,
    k: usize,
    distances: &[f64],
    outputs: &mut PackOutputs,
) -> String {
    let mags = packed.packer.gradc_magnitudes();
    let p = &packed.packer;
    let mut file = String::new();
    let names = ["x", "y", "z"];
    let _ = writeln!(
        file,
        "{},grad_c,wall_distance,frozen",
        names[..V::DIM].join(",")
    );
    for (i, &x) in p.positions.iter().enumerate() {
        let xyz = x.to_xyz();
        let row: Vec<String> = xyz[..V::DIM].iter().map(|c| format!("{c:.17e}")).collect();
        let _ = writeln!(
            file,
            "{},{:e},{:e},{}",
            row.join(","),
            mags[i].0,
            distances[i],
            u8::from(p.frozen[i])
        );
        outputs.all_points.push(xyz);
        outputs.lattice_points.push(p.start[i].to_xyz());
        outputs.block_id.push(k as f64);
        outputs.gradc.push(mags[i].0);
        outputs.dist.push(distances[i]);
        outputs.disp.extend((x - p.start[i]).to_xyz());
        outputs.frozen.push(if p.frozen[i] { 1.0 } else { 0.0 });
    }
    file
}

/// Adds the boundary elements block `k` was packed against to the cells of `walls.vtu`.
fn append_walls<V: CaseDim>(p: &Packer<V>, k: usize, outputs: &mut PackOutputs) {
    let e = &p.walls.elements;
    for j in 0..e.len() {
        let base = outputs.wall_vertices.len() as u32;
        let corners = e.current_corners(j);
        outputs
            .wall_vertices
            .extend(corners.iter().map(|c| c.to_xyz()));
        outputs.wall_cells.push(
            (0..corners.len() as u32)
                .map(|m| base + m)
                .collect::<Vec<u32>>(),
        );
        outputs.wall_normals.extend(e.normal[j].to_xyz());
        outputs.wall_block.push(k as f64);
    }
}

/// Block `k` of the case as `packed.toml` holds it: its geometry replaced by its packed
/// particle file `name` at spacing `dx`.
fn packed_block_entry(doc: &toml::Table, k: usize, name: &str, dx: f64) -> Option<toml::Value> {
    let mut b = case_block(doc, k)?.as_table()?.clone();
    for key in [
        "min",
        "max",
        "points",
        "centre",
        "radius",
        "subdivisions",
        "units",
        "scale",
        "rotate",
        "translate",
        "hole",
        "fill",
    ] {
        b.remove(key);
    }
    b.insert("shape".into(), toml::Value::String("particles".into()));
    b.insert("file".into(), toml::Value::String(name.to_string()));
    b.insert("dx".into(), toml::Value::Float(dx));
    Some(toml::Value::Table(b))
}

/// Writes `particles.vtu`, `lattice.vtu` and `walls.vtu`.
fn write_vtk_files(out: &Path, o: &PackOutputs) -> Result<(), RunError> {
    let vtk_err =
        |path: &Path, e: std::io::Error| RunError::Output(at::<()>(path, Err(e)).unwrap_err());
    let scalar = |name, values| DataArray {
        name,
        components: 1,
        values,
        integer: false,
    };
    let path = out.join("particles.vtu");
    write_points_vtu(
        &path,
        &o.all_points,
        &[
            scalar("block", &o.block_id),
            scalar("grad_c", &o.gradc),
            scalar("wall_distance", &o.dist),
            DataArray {
                name: "displacement",
                components: 3,
                values: &o.disp,
                integer: false,
            },
            scalar("frozen", &o.frozen),
        ],
    )
    .map_err(|e| vtk_err(&path, e))?;
    let path = out.join("lattice.vtu");
    write_points_vtu(&path, &o.lattice_points, &[scalar("block", &o.block_id)])
        .map_err(|e| vtk_err(&path, e))?;
    let path = out.join("walls.vtu");
    write_cells_vtu(
        &path,
        &o.wall_vertices,
        &o.wall_cells,
        &[
            DataArray {
                name: "normal",
                components: 3,
                values: &o.wall_normals,
                integer: false,
            },
            scalar("block", &o.wall_block),
        ],
    )
    .map_err(|e| vtk_err(&path, e))
}

/// Writes `packed.toml`: the case document with its packed blocks, under a header line.
fn write_packed_toml(
    out: &Path,
    case_name: &str,
    packed_doc: &toml::Table,
) -> Result<(), RunError> {
    let packed_text = toml::to_string(packed_doc).unwrap_or_default();
    write_atomic(
        &out.join("packed.toml"),
        format!(
            "# {case_name} packed by `bisph pack`: every fluid block starts from its packed particles.\n{packed_text}"
        )
        .as_bytes(),
    )?;
    Ok(())
}

/// `pack-<k>.png`: kinetic energy, TPD and |grad C| against the iteration.
fn plot_block(out: &Path, k: usize, history: &[IterationStats]) -> Result<(), RunError> {
    // Rows without a value (metrics not evaluated that iteration) are left out, so lines join.
    let series = |label: &str, f: &dyn Fn(&IterationStats) -> f64| {
        let (x, y) = history
            .iter()
            .filter(|s| f(s).is_finite())
            .map(|s| (s.iteration as f64, f(s)))
            .unzip();
        (
            PlotSeries {
                label: label.into(),
                x,
                y,
            },
            Style::Line,
        )
    };
    let plots = [
        (
            format!("pack-{k}-gradc.png"),
            Plot {
                title: format!("BIPI block {k}: |grad C|"),
                x_label: "iteration".into(),
                y_label: "|grad C| [1/m]".into(),
                series: vec![
                    series("mean, gamma = 1", &|s| s.gradc_mean),
                    series("max, gamma = 1", &|s| s.gradc_max),
                    series("mean, all", &|s| s.gradc_mean_all),
                    series("max, all", &|s| s.gradc_max_all),
                ],
            },
        ),
        (
            format!("pack-{k}-tpd.png"),
            Plot {
                title: format!("BIPI block {k}: total particle displacement"),
                x_label: "iteration".into(),
                y_label: "TPD [m]".into(),
                series: vec![series("TPD", &|s| s.tpd)],
            },
        ),
        (
            format!("pack-{k}-kinetic.png"),
            Plot {
                title: format!("BIPI block {k}: kinetic energy of the shifts"),
                x_label: "iteration".into(),
                y_label: "1/2 sum m |dx|^2".into(),
                series: vec![series("kinetic", &|s| s.kinetic)],
            },
        ),
    ];
    for (name, plot) in plots {
        let path = out.join(name);
        write_png(&plot, &path, 900, 600).map_err(|e| {
            RunError::Output(
                at::<()>(&path, Err(std::io::Error::other(e.to_string()))).unwrap_err(),
            )
        })?;
    }
    Ok(())
}
