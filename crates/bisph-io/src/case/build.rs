//! From a checked case to a ready [`Simulation`].

use crate::case::bodies::free_bodies;
use crate::case::dim::{oriented_wall_shapes, CaseDim};
use crate::case::fill::{block_points, relax_for_usaw};

use crate::case::error::CaseError;
use crate::case::schema::{
    BlockShape, BoundaryName, BoundaryQuadratureName, Case, ContinuityName, DiffusionName, EosName,
    FluidBlock, FluxRuleName, InitialPressure, IntegratorName, LoadedCase, MassRule, ProbeKindName,
    ShepardName, ToleranceReference, UsawGammaName, WallInterpolationName, WallShape,
};
use bisph_core::bodies::{Body, Motion, Piston, PrescribedMotion};
use bisph_core::energy::{energy_scale, fluid_energies};
use bisph_core::probes::{Probe, ProbeKind};
use bisph_core::simulation::{DiffusionChoice, UsawParams};
use bisph_core::simulation::{Integrator, MidpointParams};
use bisph_core::walls::shepard_bi::{BoundaryQuadrature, ShepardKind};
use bisph_core::walls::usaw::WallInterpolation;
use bisph_core::walls::{BoundaryElements, Stretch, Walls};
use bisph_core::{Eos, Fluid, SimConfig, Simulation, Vector, WallModelChoice, Wendland};
use std::ops::Range;

/// The equation of state of a case.
pub fn eos_of(case: &Case) -> Eos {
    let f = &case.fluid;
    match case.eos_name() {
        EosName::Linear => Eos::Linear {
            rho0: f.density,
            c0: f.sound_speed,
            p0: f.background_pressure,
        },
        EosName::Tait => Eos::Tait {
            rho0: f.density,
            c0: f.sound_speed,
            p0: f.background_pressure,
            xi: f.tait_exponent,
        },
    }
}

/// Builds the simulation of a checked case.
pub fn build_simulation<V: CaseDim>(loaded: &LoadedCase) -> Result<Simulation<V>, CaseError> {
    build_simulation_with_layout(loaded).map(|(sim, _)| sim)
}

/// Where each `[[fluid_block]]` and `[[wall]]` of a case lies in the built simulation, in
/// the order of the case file.
#[derive(Debug, Clone, Default)]
pub struct Layout {
    /// The fluid particles of each block.
    pub blocks: Vec<Range<usize>>,
    /// The boundary elements of each wall.
    pub walls: Vec<Range<usize>>,
}

/// Builds the simulation of a checked case and says which particles and elements come from
/// which block and wall.
pub fn build_simulation_with_layout<V: CaseDim>(
    loaded: &LoadedCase,
) -> Result<(Simulation<V>, Layout), CaseError> {
    let mut layout = Layout::default();
    let case = &loaded.case;
    let dx = case.resolution.dx;
    let h = case.resolution.h_over_dx * dx;
    let kernel = Wendland::for_dim::<V>(h);
    let eos = eos_of(case);
    let gravity = V::from_slice(&case.fluid.gravity);

    let mut bodies = build_bodies::<V>(case);
    let (elements, mut stretch, body_surfaces) = build_walls::<V>(loaded, &mut layout)?;
    free_bodies::<V>(loaded, &mut bodies, &body_surfaces, gravity, &elements)?;
    set_pistons(loaded, &mut bodies, &elements, &mut stretch)?;
    let fluid = build_fluid(loaded, &kernel, &eos, gravity, &elements, &mut layout)?;
    let (domain_min, domain_max) = domain_box(case, &fluid, &elements, h);
    let periodicity = periodicity_of::<V>(loaded, &kernel)?;
    let probes = build_probes::<V>(case);

    let config = SimConfig {
        kernel,
        eos,
        gravity,
        delta: case.delta(),
        delta_hydrostatic: case.fluid.delta_hydrostatic,
        courant: case.time.courant,
        fixed_dt: case.time.dt,
        min_dt: case.time.min_dt.unwrap_or(1e-6 * h / eos.c0()),
        domain_min,
        domain_max,
        max_removed: max_removed(case, fluid.len()),
        wall_model: wall_model_of(case),
        diffusion: diffusion_of(case),
        particle_spacing: case.resolution.dx,
        reorder_interval: 1,
        neighbour_skin: case.time.neighbour_skin,
        pair_list_budget: crate::case::resources::pair_list_budget(),
        elastic_bounce: case.elastic_bounce,
        periodicity,
        viscosity: bisph_core::terms::Viscosity {
            nu: case.kinematic_viscosity(),
            min_wall_distance: 0.5 * dx,
        },
        flux: flux_control_of(case, domain_min, domain_max),
        integrator: integrator_of(case, &fluid, &eos, gravity),
    };
    let mut walls = Walls::new(elements, bodies, kernel.support);
    walls.stretch = stretch;
    let mut sim = Simulation::new(config, fluid, walls, probes);
    if case.boundary == BoundaryName::Usaw
        && case
            .fluid_block
            .iter()
            .all(|b| case.mass_rule(b) == MassRule::Initial)
    {
        sim.vertex_masses_from_density();
    }
    Ok((sim, layout))
}

/// The bodies of a case: 0 = the fixed walls, then the case's bodies in order, with their
/// prescribed motion or piston (a piston's outside force is set by [`set_pistons`]).
fn build_bodies<V: CaseDim>(case: &Case) -> Vec<Body<V>> {
    let mut bodies = vec![Body::fixed("walls")];
    for b in &case.body {
        let motion = match &b.motion {
            None => Motion::Fixed,
            Some(m) => {
                let get = |v: &Option<Vec<f64>>| V::from_slice(v.as_deref().unwrap_or(&[]));
                let mut axis = get(&m.axis);
                if V::DIM == 3 {
                    let l = axis.length();
                    axis = if l > 0.0 {
                        axis / l
                    } else {
                        V::from_slice(&[0.0, 0.0, 1.0])
                    };
                }
                Motion::Prescribed(PrescribedMotion {
                    velocity: get(&m.velocity),
                    amplitude: get(&m.amplitude),
                    frequency: m.frequency,
                    phase: m.phase,
                    axis,
                    angular_velocity: m.angular_velocity,
                    angular_amplitude: m.angular_amplitude,
                    angular_frequency: m.angular_frequency,
                })
            }
        };
        let motion = match &b.piston {
            Some(p) => {
                let axis = V::from_slice(&p.axis);
                Motion::Piston(Piston {
                    axis: axis / axis.length(),
                    mass: p.mass,
                    outside_force: 0.0, // outside pressure times area, set by set_pistons
                    position: 0.0,
                    velocity: p.initial_velocity,
                    acceleration: 0.0,
                })
            }
            None => motion,
        };
        let centre = V::from_slice(b.centre.as_deref().unwrap_or(&[]));
        bodies.push(Body {
            name: b.name.clone(),
            centre,
            motion,
        });
    }
    bodies
}

/// The boundary elements of every wall (their ranges recorded in `layout`), the stretching
/// groups, and the closed surfaces of the mesh walls that belong to bodies.
#[allow(clippy::type_complexity)]
fn build_walls<V: CaseDim>(
    loaded: &LoadedCase,
    layout: &mut Layout,
) -> Result<
    (
        BoundaryElements<V>,
        Vec<Stretch>,
        Vec<(usize, bisph_core::surface::Surface)>,
    ),
    CaseError,
> {
    let case = &loaded.case;
    let mut elements = BoundaryElements::default();
    let mut stretch: Vec<Stretch> = Vec::new();
    let mut body_surfaces: Vec<(usize, bisph_core::surface::Surface)> = Vec::new();
    let element_size = case.resolution.dx * case.resolution.element_over_dx;
    for (k, w) in case.wall.iter().enumerate() {
        let element_size = w.element_size.unwrap_or(element_size);
        let body = match &w.body {
            None => 0,
            Some(name) => 1 + case.body.iter().position(|b| &b.name == name).unwrap_or(0) as u32,
        };
        let shapes = oriented_wall_shapes::<V>(loaded, k, element_size)?;
        let surface_wall = match w.shape {
            WallShape::Mesh | WallShape::Capsule | WallShape::Sphere => true,
            WallShape::Cylinder => w.open.is_empty(),
            _ => false,
        };
        if V::DIM == 3 && body > 0 && surface_wall {
            let mut surface = crate::case::mesh_walls::wall_surface(
                loaded,
                &format!("wall[{k}]"),
                w,
                element_size,
            )?;
            if surface.volume() < 0.0 {
                surface.flip();
            }
            body_surfaces.push((body as usize, surface));
        }
        if shapes.is_empty() {
            return Err(loaded.error(
                &format!("wall[{k}]"),
                "this wall has no element (zero length or every side open)",
            ));
        }
        let first = elements.len() as u32;
        for s in shapes {
            elements.push(s.centre, s.normal, s.area, body, &s.corners);
        }
        layout.walls.push(first as usize..elements.len());
        if let Some(st) = &w.stretch {
            let piston = 1 + case
                .body
                .iter()
                .position(|b| b.name == st.body)
                .unwrap_or(0) as u32;
            stretch.push(Stretch {
                body: piston,
                anchor: st.anchor,
                face: 0.0,
                elements: (first..elements.len() as u32).collect(),
            });
        }
    }
    Ok((elements, stretch, body_surfaces))
}

/// Sets each piston's outside force (outside pressure times the piston's area) and the
/// reference face of the walls stretching with it.
fn set_pistons<V: CaseDim>(
    loaded: &LoadedCase,
    bodies: &mut [Body<V>],
    elements: &BoundaryElements<V>,
    stretch: &mut [Stretch],
) -> Result<(), CaseError> {
    for (k, b) in loaded.case.body.iter().enumerate() {
        let (Some(spec), Motion::Piston(p)) = (&b.piston, &mut bodies[k + 1].motion) else {
            continue;
        };
        let ids: Vec<usize> = (0..elements.len())
            .filter(|&j| elements.body[j] as usize == k + 1)
            .collect();
        if ids.is_empty() {
            return Err(loaded.error(
                &format!("body[{k}].piston"),
                "no [[wall]] belongs to this piston",
            ));
        }
        let area: f64 = ids.iter().map(|&j| elements.area[j]).sum();
        p.outside_force = spec.outside_pressure * area;
        let face = ids
            .iter()
            .map(|&j| elements.centre[j].dot(p.axis))
            .sum::<f64>()
            / ids.len() as f64;
        for group in stretch.iter_mut().filter(|g| g.body as usize == k + 1) {
            group.face = face;
            if (face - group.anchor).abs() < 1e-12 {
                return Err(loaded.error(
                    &format!("body[{k}].piston"),
                    "a stretching wall's anchor sits on the piston face",
                ));
            }
        }
    }
    Ok(())
}

/// The fluid particles of every block (their ranges recorded in `layout`).
fn build_fluid<V: CaseDim>(
    loaded: &LoadedCase,
    kernel: &Wendland,
    eos: &Eos,
    gravity: V,
    elements: &BoundaryElements<V>,
    layout: &mut Layout,
) -> Result<Fluid<V>, CaseError> {
    let mut fluid = Fluid::default();
    for k in 0..loaded.case.fluid_block.len() {
        push_block(
            loaded, k, kernel, eos, gravity, elements, layout, &mut fluid,
        )?;
    }
    Ok(fluid)
}

/// Adds the particles of fluid block `k` to `fluid`: on its lattice (relaxed for usaw walls
/// where it asks), with its velocity, initial pressure, density and mass.
#[allow(clippy::too_many_arguments)]
fn push_block<V: CaseDim>(
    loaded: &LoadedCase,
    k: usize,
    kernel: &Wendland,
    eos: &Eos,
    gravity: V,
    elements: &BoundaryElements<V>,
    layout: &mut Layout,
    fluid: &mut Fluid<V>,
) -> Result<(), CaseError> {
    let case = &loaded.case;
    let block = &case.fluid_block[k];
    let dx = case.resolution.dx;
    let g = gravity.length();
    let key = format!("fluid_block[{k}]");
    if block.shape == BlockShape::Polyline {
        return Err(loaded.error(
            &format!("{key}.shape"),
            "a fluid block must be a closed \"box\" or \"polygon\"",
        ));
    }
    if block.solid {
        return Err(loaded.error(
            &format!("{key}.solid"),
            "solid blocks are packed by `bisph pack` only; `bisph run` moves fluid",
        ));
    }
    let block_dx = block.dx.unwrap_or(dx);
    let mass = eos.rho0() * block_dx.powi(V::DIM as i32);
    let points = block_points::<V>(loaded, k, block_dx)?;
    if points.is_empty() {
        return Err(loaded.error(
            &key,
            format!("no lattice point of spacing dx = {block_dx} fits in this block"),
        ));
    }
    let velocity = V::from_slice(block.velocity.as_deref().unwrap_or(&[]));
    let height = |r: V| if g > 0.0 { -gravity.dot(r) / g } else { 0.0 };
    let surface = block.surface.unwrap_or_else(|| {
        if matches!(block.shape, BlockShape::Box | BlockShape::Polygon)
            && crate::case::regions::transform_of(&block.shape_spec()).is_identity()
        {
            block_top(block, gravity, g)
        } else {
            // Shapes from files: the top particle plus half a spacing.
            points
                .iter()
                .map(|&r| height(r))
                .fold(f64::NEG_INFINITY, f64::max)
                + 0.5 * block_dx
        }
    });
    let mut points = points;
    layout.blocks.push(fluid.len()..fluid.len() + points.len());
    if case.fills_for_usaw(block) {
        relax_for_usaw(
            kernel,
            block_dx,
            &mut points,
            elements,
            gravity,
            surface,
            eos,
        );
    }
    // Uniform by default where gravity runs along a periodic axis (a driven channel).
    let hydrostatic = match &block.pressure {
        None => g > 0.0 && crate::case::check::gravity_along_periodic_axis(case).is_none(),
        Some(InitialPressure::Named(_)) => true,
        Some(InitialPressure::Value(_)) => false,
    };
    // "hydrostatic-eos": dp/dd = rho(p) g with the equation of state (a fluid that starts
    // compressed in equilibrium); "hydrostatic": rho0 g d.
    let exact_hydrostatic =
        matches!(&block.pressure, Some(InitialPressure::Named(n)) if n == "hydrostatic-eos");
    for r in points {
        let p = match &block.pressure {
            Some(InitialPressure::Value(p)) => *p,
            _ if hydrostatic => {
                let taper = block.pressure_taper.as_ref().map_or(1.0, |tp| {
                    let s = ((r.get(tp.axis) - tp.start) / tp.length).clamp(0.0, 1.0);
                    (0.5 * std::f64::consts::PI * s).cos()
                });
                let depth = (surface - height(r)).max(0.0);
                let hydrostatic = if exact_hydrostatic {
                    eos.hydrostatic_pressure(g, depth)
                } else {
                    eos.rho0() * g * depth
                };
                eos_background(eos) + taper * hydrostatic
            }
            _ => eos_background(eos),
        };
        let Some(rho) = eos.density(p) else {
            return Err(loaded.error(
                &format!("{key}.pressure"),
                format!("no density gives the pressure {p} Pa with this equation of state"),
            ));
        };
        let mass = match case.mass_rule(block) {
            MassRule::Reference => mass,
            MassRule::Initial => rho * dx.powi(V::DIM as i32),
        };
        fluid.push(r, velocity, rho, mass, p);
    }
    Ok(())
}

/// Most particles the run may lose through the domain's bounds: `diagnostics.removed_fraction_max`
/// of the `n` initial ones, all but one at most (the last always stops the run).
fn max_removed(case: &Case, n: usize) -> u64 {
    let allowed = (case.diagnostics.removed_fraction_max * n as f64).floor() as u64;
    allowed.min(n.saturating_sub(1) as u64)
}

/// The domain's corners: `[domain]`, or the box around the fluid and the walls with a margin
/// of a tenth of its extent plus two smoothing lengths.
fn domain_box<V: CaseDim>(
    case: &Case,
    fluid: &Fluid<V>,
    elements: &BoundaryElements<V>,
    h: f64,
) -> (V, V) {
    match &case.domain {
        Some(d) => (V::from_slice(&d.min), V::from_slice(&d.max)),
        None => {
            let mut lo = fluid.position[0];
            let mut hi = lo;
            for &r in fluid
                .position
                .iter()
                .chain(elements.reference_corners.iter())
            {
                lo = lo.min_by_component(r);
                hi = hi.max_by_component(r);
            }
            let mut margin = V::ZERO;
            for k in 0..V::DIM {
                margin.set(k, 0.1 * (hi.get(k) - lo.get(k)) + 2.0 * h);
            }
            (lo - margin, hi + margin)
        }
    }
}

/// The periodic axes of `[domain]`, each period at least three kernel supports.
fn periodicity_of<V: CaseDim>(
    loaded: &LoadedCase,
    kernel: &Wendland,
) -> Result<bisph_core::neighbours::Periodicity<V>, CaseError> {
    let mut periodicity = bisph_core::neighbours::Periodicity::<V>::none();
    if let Some(d) = &loaded.case.domain {
        for axis in d.periodic_axes() {
            periodicity.min.set(axis, d.min[axis]);
            periodicity.length.set(axis, d.max[axis] - d.min[axis]);
        }
    }
    if bisph_core::neighbours::CellGrid::with_period(kernel.support, periodicity).is_err() {
        return Err(loaded.error(
            "domain.periodic",
            "every period must hold at least three kernel supports",
        ));
    }
    Ok(periodicity)
}

/// The probes of a case.
fn build_probes<V: CaseDim>(case: &Case) -> Vec<Probe<V>> {
    case.probe
        .iter()
        .map(|p| Probe {
            name: p.name.clone(),
            kind: match p.kind {
                ProbeKindName::Pressure => ProbeKind::Pressure,
                ProbeKindName::WallPressure => ProbeKind::WallPressure,
                ProbeKindName::Height => ProbeKind::Height,
            },
            position: V::from_slice(&p.position),
        })
        .collect()
}

/// The wall model of a case with its options.
fn wall_model_of(case: &Case) -> WallModelChoice {
    match case.boundary {
        BoundaryName::Energy => WallModelChoice::Energy,
        BoundaryName::Bi => WallModelChoice::ShepardBi(
            match case.shepard {
                ShepardName::Discrete => ShepardKind::Discrete,
                ShepardName::Geometric => ShepardKind::Geometric,
                ShepardName::Integrated => ShepardKind::Integrated,
            },
            match case.boundary_quadrature() {
                BoundaryQuadratureName::Centre => BoundaryQuadrature::Centre,
                BoundaryQuadratureName::Exact => BoundaryQuadrature::Exact,
                BoundaryQuadratureName::Gauss => BoundaryQuadrature::Gauss,
            },
        ),
        BoundaryName::Usaw => WallModelChoice::Usaw(UsawParams {
            interpolation: match case.usaw.wall_interpolation {
                WallInterpolationName::Shepard => WallInterpolation::Shepard,
                WallInterpolationName::Neumann => WallInterpolation::Neumann,
                WallInterpolationName::Hydrostatic => WallInterpolation::Hydrostatic,
            },
            geometric_gamma: case.usaw.gamma == UsawGammaName::Geometric,
            no_wall_tension: !case.usaw.wall_tension,
            density_power: case.usaw.density_power,
            summation_density: case.usaw.continuity == ContinuityName::Summation,
        }),
    }
}

/// The density diffusion of a case with its coefficient.
fn diffusion_of(case: &Case) -> DiffusionChoice {
    match case.fluid.diffusion {
        DiffusionName::Delta => DiffusionChoice::Delta,
        DiffusionName::Mayrhofer => DiffusionChoice::Mayrhofer {
            eta: case.fluid.eta,
        },
        DiffusionName::Ferrari => DiffusionChoice::Ferrari {
            coefficient: case.fluid.ferrari_coefficient,
        },
    }
}

/// The flux control of `[flux]`, its slice through the domain's centre by default.
fn flux_control_of<V: CaseDim>(
    case: &Case,
    domain_min: V,
    domain_max: V,
) -> Option<bisph_core::forcing::FluxControl<V>> {
    case.flux.as_ref().map(|f| {
        let direction = V::from_slice(&f.direction);
        let centre = (domain_min + domain_max) * 0.5;
        bisph_core::forcing::FluxControl {
            direction: direction / direction.length(),
            target_velocity: f.flux / f.area,
            area: f.area,
            slice_point: f.slice_point.as_deref().map_or(centre, V::from_slice),
            slice_width: f.slice_width.unwrap_or(2.0 * case.resolution.dx),
            rule: match f.rule {
                FluxRuleName::Eq63 => bisph_core::forcing::FluxRule::Eq63,
                FluxRuleName::Eq58 => bisph_core::forcing::FluxRule::Eq58,
            },
        }
    })
}

/// The time integrator of a case; a relative midpoint tolerance is scaled by the initial
/// energy it refers to.
fn integrator_of<V: CaseDim>(case: &Case, fluid: &Fluid<V>, eos: &Eos, gravity: V) -> Integrator {
    match case.time.integrator {
        IntegratorName::Verlet => Integrator::Verlet,
        IntegratorName::Midpoint => {
            let m = &case.midpoint;
            let (kinetic, compressible, _) = fluid_energies(fluid, eos, gravity);
            let potential = energy_scale(fluid, eos, gravity) - kinetic - compressible.abs();
            let reference = match m.tolerance_reference {
                ToleranceReference::Absolute => 1.0,
                ToleranceReference::Potential => potential,
                ToleranceReference::Kinetic => kinetic,
                ToleranceReference::Compressible => compressible.abs(),
                ToleranceReference::Given => m.reference_energy.unwrap_or(1.0),
            };
            Integrator::Midpoint(MidpointParams {
                max_iterations: m.max_iterations,
                tolerance: m.tolerance * reference,
                min_decrease: m.min_decrease,
                relax_increment: m.relax_increment,
                initial_relaxation: m.initial_relaxation,
                anderson_depth: m.anderson_depth,
            })
        }
    }
}

fn eos_background(eos: &Eos) -> f64 {
    match *eos {
        Eos::Linear { p0, .. } | Eos::Tait { p0, .. } => p0,
    }
}

/// Highest point of a block along `-g`.
fn block_top<V: Vector>(block: &FluidBlock, gravity: V, g: f64) -> f64 {
    if g == 0.0 {
        return 0.0;
    }
    let corners: Vec<Vec<f64>> = match (&block.min, &block.max, &block.points) {
        (Some(lo), Some(hi), _) => {
            let d = lo.len();
            (0..1usize << d)
                .map(|mask| {
                    (0..d)
                        .map(|k| if mask >> k & 1 == 1 { hi[k] } else { lo[k] })
                        .collect()
                })
                .collect()
        }
        (_, _, Some(points)) => points.clone(),
        _ => Vec::new(),
    };
    corners
        .iter()
        .map(|c| -gravity.dot(V::from_slice(c)) / g)
        .fold(f64::NEG_INFINITY, f64::max)
}
