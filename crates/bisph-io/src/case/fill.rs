//! The initial particles of a fluid block: a lattice, positions read from a file, a BIPI
//! packing (paper 4) or a lattice relaxed to fit usaw walls.

use crate::case::dim::CaseDim;
use crate::case::error::CaseError;
use crate::case::regions::BlockRegion;
use crate::case::schema::LoadedCase;
use crate::case::schema::{BlockShape, Case};
use bisph_core::packing::{IterationStats, PackParams, PackWalls, Packer};
use bisph_core::walls::usaw::{self, FitSetting};
use bisph_core::walls::BoundaryElements;
use bisph_core::{Eos, Vector, Wendland};
use std::ops::ControlFlow;
use std::time::Instant;

/// The initial particle positions of block `k`: read from a file (`shape = "particles"`),
/// packed with BIPI (`fill = "bipi"`) or on the lattice (trimmed to the walls for
/// `shape = "walls"`).
pub fn block_points<V: CaseDim>(
    loaded: &LoadedCase,
    k: usize,
    dx: f64,
) -> Result<Vec<V>, CaseError> {
    let block = &loaded.case.fluid_block[k];
    let key = format!("fluid_block[{k}]");
    if block.shape == BlockShape::Particles {
        let file = block.file.clone().unwrap_or_default();
        let rows = crate::formats::mesh_files::read_particles(&loaded.resolve(&file), V::DIM)
            .map_err(|m| loaded.error(&format!("{key}.file"), m))?;
        return Ok(rows.iter().map(|r| V::from_slice(r)).collect());
    }
    if block.bipi() {
        let packed =
            crate::case::fill::pack_block::<V>(loaded, k, &mut |_| ControlFlow::Continue(()))?;
        return Ok(packed.packer.positions);
    }
    if block.shape == BlockShape::Walls {
        return crate::case::wall_fill::fill_inside_walls::<V>(loaded, k, dx);
    }
    let plain = matches!(block.shape, BlockShape::Box | BlockShape::Polygon)
        && block.hole.is_empty()
        && crate::case::regions::transform_of(&block.shape_spec()).is_identity();
    if plain {
        return Ok(V::fill(block, dx));
    }
    let element_size = dx * loaded.case.resolution.element_over_dx;
    Ok(V::block_region(loaded, &key, block, dx, element_size)?.lattice)
}

/// `fill = "usaw"`: a start that fits usaw walls. Relaxes a block's lattice `points` in two
/// stages ([`bisph_core::walls::usaw`]): [`relax_positions`](bisph_core::walls::usaw::relax_positions)
/// zeroes the operators' zero-order residual (a constant pressure exerts no force; the free
/// surface at height `surface` is a mirror), then, under gravity,
/// [`balance_positions`](bisph_core::walls::usaw::balance_positions) zeroes the acceleration
/// at hydrostatic rest (every pressure the still water's at its height, the equation of
/// state's `dp/dd = rho(p) g`). At most [`USAW_FILL_ITERATIONS`] iterations each. The vertex
/// particles are those of all walls at `rho0`; other blocks are not seen.
pub fn relax_for_usaw<V: Vector>(
    kernel: &Wendland,
    dx: f64,
    points: &mut [V],
    elements: &BoundaryElements<V>,
    gravity: V,
    surface: f64,
    eos: &Eos,
) {
    let Some(vertices) = usaw::Vertices::from_elements(
        elements,
        eos.rho0(),
        kernel.support,
        dx,
        bisph_core::neighbours::Periodicity::none(),
    ) else {
        return;
    };
    let g = gravity.length();
    let up = if g > 0.0 {
        gravity * (-1.0 / g)
    } else {
        V::ZERO
    };
    let fit = FitSetting {
        kernel,
        dx,
        volume: dx.powi(V::DIM as i32),
        vertices: &vertices,
        elements,
        up,
        surface,
        max_iterations: USAW_FILL_ITERATIONS,
    };
    // Without gravity there is no free surface to mirror.
    let mirror = if g > 0.0 { surface } else { f64::INFINITY };
    usaw::relax_positions(
        &FitSetting {
            surface: mirror,
            ..fit
        },
        points,
    );
    if g > 0.0 {
        let pressure = |d: f64| eos.hydrostatic_pressure(g, d);
        let density = |p: f64| eos.density(p).unwrap_or(eos.rho0());
        usaw::balance_positions(&fit, points, g, &pressure, &density);
    }
}

/// Most iterations of each stage of `fill = "usaw"`.
pub const USAW_FILL_ITERATIONS: usize = 5000;

/// BIPI parameters of a case for spacing `dx` (defaults of paper 4 where the case is silent).
pub fn pack_params(case: &Case, dx: f64) -> PackParams {
    let p = &case.pack;
    let mut q = PackParams::new(dx, case.resolution.h_over_dx * dx);
    q.mass = case.fluid.density * dx.powi(case.dim as i32);
    q.diffusion = p.diffusion.unwrap_or(q.diffusion);
    q.max_shift = p.max_shift.unwrap_or(q.max_shift);
    q.push_radius = p.push_radius.or(q.push_radius);
    q.stage_a_max = p.stage_a_max.unwrap_or(q.stage_a_max);
    q.plateau_window = p.plateau_window.unwrap_or(q.plateau_window);
    q.plateau_tolerance = p.plateau_tolerance.unwrap_or(q.plateau_tolerance);
    q.freeze_distance = p.freeze_distance.unwrap_or(q.freeze_distance);
    q.stage_c_iterations = p.stage_c_iterations.unwrap_or(q.stage_c_iterations);
    q.stage_c_tolerance = p.stage_c_tolerance.unwrap_or(q.stage_c_tolerance);
    q.step_damping = p.step_damping.unwrap_or(q.step_damping);
    q.report_interval = p.report_interval.unwrap_or(q.report_interval);
    q
}

/// One packed block.
pub struct PackedBlock<V: CaseDim> {
    /// Its region.
    pub region: BlockRegion<V>,
    /// The packer after the run (positions, walls, frozen flags).
    pub packer: Packer<V>,
    /// Metrics of every iteration.
    pub history: Vec<IterationStats>,
    /// Wall-clock seconds of step 2.
    pub seconds: f64,
}

/// Packs block `k` of a case (steps 1 and 2 of paper 4); `observe` sees every iteration and
/// may stop packing there (`Break`).
pub fn pack_block<V: CaseDim>(
    loaded: &LoadedCase,
    k: usize,
    observe: &mut dyn FnMut(&IterationStats) -> ControlFlow<()>,
) -> Result<PackedBlock<V>, CaseError> {
    let case = &loaded.case;
    let block = &case.fluid_block[k];
    let key = format!("fluid_block[{k}]");
    if block.shape == BlockShape::Particles {
        return Err(loaded.error(
            &format!("{key}.shape"),
            "a \"particles\" block has no geometry to pack",
        ));
    }
    let dx = block.dx.unwrap_or(case.resolution.dx);
    let params = pack_params(case, dx);
    // The wall integrals are exact for elements of any size: elements as large as the
    // support keep the count (and the cost) down.
    let element_size = (dx * case.resolution.element_over_dx).max(2.0 * params.h);
    let region = if block.shape == BlockShape::Walls {
        crate::case::wall_region::region_inside_walls::<V>(loaded, k, dx, element_size)?
    } else {
        V::block_region(loaded, &key, block, dx, element_size)?
    };
    let walls = PackWalls::new(&region.elements, 2.0 * params.h);
    let mut packer = Packer::new(params, region.lattice.clone(), walls)
        .map_err(|e| loaded.error(&key, e.to_string()))?;
    let started = Instant::now();
    let history = packer.run(|s| observe(s));
    Ok(PackedBlock {
        region,
        packer,
        history,
        seconds: started.elapsed().as_secs_f64(),
    })
}
