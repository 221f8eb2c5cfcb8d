//! From a checked case to a ready [`Simulation`].

use crate::case::ToleranceReference;
use crate::case::{Case, CaseError, FluidBlock, InitialPressure, LoadedCase, WallSpec};
use crate::regions::BlockRegion;
use bisph_core::bi::ElementIntegrals as WallIntegrals;
use bisph_core::energy::{energy_scale, fluid_energies};
use bisph_core::geometry::{self, ElementShape};
use bisph_core::probes::{Probe, ProbeKind};
use bisph_core::simulation::{DiffusionChoice, UsawParams};
use bisph_core::simulation::{Integrator, MidpointParams};
use bisph_core::walls::shepard_bi::ShepardKind;
use bisph_core::walls::usaw::{self, FitSetting, WallInterpolation};
use bisph_core::walls::{
    Body, BoundaryElements, Coupling, FreeBody, Motion, Piston, PrescribedMotion, Stretch, Walls,
};
use bisph_core::{Eos, Fluid, SimConfig, Simulation, Vector, WallModelChoice, Wendland};
use glam::{DVec2, DVec3};

/// What differs between 2-D and 3-D when building a case.
pub trait CaseDim: Vector + WallIntegrals {
    /// The region of a block (shape minus holes, transformed) for spacing `dx`.
    fn block_region(
        loaded: &LoadedCase,
        key: &str,
        block: &FluidBlock,
        dx: f64,
        element_size: f64,
    ) -> Result<BlockRegion<Self>, CaseError>;
    /// Boundary elements of one `[[wall]]` (`key`) of about `size`.
    fn wall_shapes(
        loaded: &LoadedCase,
        key: &str,
        wall: &WallSpec,
        size: f64,
    ) -> Result<Vec<ElementShape<Self>>, CaseError>;
    /// Lattice points of one `[[fluid_block]]`.
    fn fill(block: &FluidBlock, dx: f64) -> Vec<Self>;
}

fn points2(points: &Option<Vec<Vec<f64>>>) -> Vec<DVec2> {
    points
        .iter()
        .flatten()
        .map(|p| DVec2::from_slice(p))
        .collect()
}

impl CaseDim for DVec2 {
    fn block_region(
        loaded: &LoadedCase,
        key: &str,
        block: &FluidBlock,
        dx: f64,
        element_size: f64,
    ) -> Result<BlockRegion<Self>, CaseError> {
        crate::regions::region_2d(
            loaded,
            key,
            &block.shape_spec(),
            &block.hole,
            dx,
            element_size,
        )
    }
    fn wall_shapes(
        _loaded: &LoadedCase,
        _key: &str,
        wall: &WallSpec,
        size: f64,
    ) -> Result<Vec<ElementShape<Self>>, CaseError> {
        Ok(match wall.shape.as_str() {
            "box" => geometry::box_elements_2d(vec2(&wall.min), vec2(&wall.max), &wall.open, size),
            "polygon" => geometry::polyline_elements(&points2(&wall.points), true, size),
            _ => geometry::polyline_elements(&points2(&wall.points), false, size),
        })
    }
    fn fill(block: &FluidBlock, dx: f64) -> Vec<Self> {
        match block.shape.as_str() {
            "box" => geometry::lattice_box(vec2(&block.min), vec2(&block.max), dx),
            _ => geometry::lattice_polygon(&points2(&block.points), dx),
        }
    }
}

impl CaseDim for DVec3 {
    fn block_region(
        loaded: &LoadedCase,
        key: &str,
        block: &FluidBlock,
        dx: f64,
        element_size: f64,
    ) -> Result<BlockRegion<Self>, CaseError> {
        crate::regions::region_3d(
            loaded,
            key,
            &block.shape_spec(),
            &block.hole,
            dx,
            element_size,
        )
    }
    fn wall_shapes(
        loaded: &LoadedCase,
        key: &str,
        wall: &WallSpec,
        size: f64,
    ) -> Result<Vec<ElementShape<Self>>, CaseError> {
        match wall.shape.as_str() {
            "mesh" | "capsule" => crate::mesh_walls::wall_elements(loaded, key, wall, size),
            _ => Ok(geometry::box_elements_3d(
                vec3(&wall.min),
                vec3(&wall.max),
                &wall.open,
                size,
            )),
        }
    }
    fn fill(block: &FluidBlock, dx: f64) -> Vec<Self> {
        geometry::lattice_box(vec3(&block.min), vec3(&block.max), dx)
    }
}

fn vec2(v: &Option<Vec<f64>>) -> DVec2 {
    DVec2::from_slice(v.as_deref().unwrap_or(&[0.0, 0.0]))
}
fn vec3(v: &Option<Vec<f64>>) -> DVec3 {
    DVec3::from_slice(v.as_deref().unwrap_or(&[0.0, 0.0, 0.0]))
}

/// The equation of state of a case.
pub fn eos_of(case: &Case) -> Eos {
    let f = &case.fluid;
    match f.eos {
        crate::case::EosName::Linear => Eos::Linear {
            rho0: f.density,
            c0: f.sound_speed,
            p0: f.background_pressure,
        },
        crate::case::EosName::Tait => Eos::Tait {
            rho0: f.density,
            c0: f.sound_speed,
            p0: f.background_pressure,
            xi: f.tait_exponent,
        },
    }
}

/// The initial particle positions of block `k`: read from a file (`shape = "particles"`),
/// packed with BIPI (`fill = "bipi"`) or on the lattice.
pub fn block_points<V: CaseDim>(
    loaded: &LoadedCase,
    k: usize,
    dx: f64,
) -> Result<Vec<V>, CaseError> {
    let block = &loaded.case.fluid_block[k];
    let key = format!("fluid_block[{k}]");
    if block.shape == "particles" {
        let file = block.file.clone().unwrap_or_default();
        let rows = crate::shapes::read_particles(&loaded.resolve(&file), V::DIM)
            .map_err(|m| loaded.error(&format!("{key}.file"), m))?;
        return Ok(rows.iter().map(|r| V::from_slice(r)).collect());
    }
    if block.bipi() {
        let packed = crate::pack::pack_block::<V>(loaded, k, &mut |_| {})?;
        return Ok(packed.packer.positions);
    }
    let plain = matches!(block.shape.as_str(), "box" | "polygon")
        && block.hole.is_empty()
        && crate::regions::transform_of(&block.shape_spec()).is_identity();
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
fn relax_for_usaw<V: Vector>(
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

/// Builds the simulation of a checked case.
pub fn build_simulation<V: CaseDim>(loaded: &LoadedCase) -> Result<Simulation<V>, CaseError> {
    let case = &loaded.case;
    let dx = case.resolution.dx;
    let h = case.resolution.h_over_dx * dx;
    let kernel = Wendland::for_dim::<V>(h);
    let eos = eos_of(case);
    let gravity = V::from_slice(&case.fluid.gravity);

    // Bodies: 0 = fixed walls, then the case's bodies in order.
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
                    outside_force: 0.0, // outside pressure times area, set below
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

    let mut elements = BoundaryElements::default();
    let mut stretch: Vec<Stretch> = Vec::new();
    let mut body_surfaces: Vec<(usize, bisph_core::surface::Surface)> = Vec::new();
    let element_size = dx * case.resolution.element_over_dx;
    for (k, w) in case.wall.iter().enumerate() {
        let element_size = w.element_size.unwrap_or(element_size);
        let body = match &w.body {
            None => 0,
            Some(name) => 1 + case.body.iter().position(|b| &b.name == name).unwrap_or(0) as u32,
        };
        let mut shapes = V::wall_shapes(loaded, &format!("wall[{k}]"), w, element_size)?;
        if w.shape == "box" && w.fluid.as_deref() == Some("outside") {
            // A box obstacle or body: normals into the box, out of the fluid around it.
            for s in &mut shapes {
                s.normal = -s.normal;
                s.corners.reverse();
            }
        }
        if V::DIM == 3 && body > 0 && (w.shape == "mesh" || w.shape == "capsule") {
            let mut surface =
                crate::mesh_walls::wall_surface(loaded, &format!("wall[{k}]"), w, element_size)?;
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
    free_bodies::<V>(loaded, &mut bodies, &body_surfaces, gravity, &elements)?;
    // Pistons: outside force = outside pressure x piston area; reference face along the axis.
    for (k, b) in case.body.iter().enumerate() {
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

    let mut fluid = Fluid::default();
    let g = gravity.length();
    for (k, block) in case.fluid_block.iter().enumerate() {
        let key = format!("fluid_block[{k}]");
        if block.shape == "polyline" {
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
            if matches!(block.shape.as_str(), "box" | "polygon")
                && crate::regions::transform_of(&block.shape_spec()).is_identity()
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
        if block.fill.as_deref() == Some("usaw") {
            relax_for_usaw(
                &kernel,
                block_dx,
                &mut points,
                &elements,
                gravity,
                surface,
                &eos,
            );
        }
        let hydrostatic = match &block.pressure {
            None => g > 0.0,
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
                    eos_background(&eos) + taper * hydrostatic
                }
                _ => eos_background(&eos),
            };
            let Some(rho) = eos.density(p) else {
                return Err(loaded.error(
                    &format!("{key}.pressure"),
                    format!("no density gives the pressure {p} Pa with this equation of state"),
                ));
            };
            let mass = match block.mass {
                crate::case::MassRule::Reference => mass,
                crate::case::MassRule::Initial => rho * dx.powi(V::DIM as i32),
            };
            fluid.push(r, velocity, rho, mass, p);
        }
    }

    let (domain_min, domain_max) = match &case.domain {
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
    };

    let mut periodicity = bisph_core::neighbours::Periodicity::<V>::none();
    if let Some(d) = &case.domain {
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

    let probes = case
        .probe
        .iter()
        .map(|p| Probe {
            name: p.name.clone(),
            kind: match p.kind.as_str() {
                "wall_pressure" => ProbeKind::WallPressure,
                "height" => ProbeKind::Height,
                _ => ProbeKind::Pressure,
            },
            position: V::from_slice(&p.position),
        })
        .collect();

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
        wall_model: match case.boundary {
            crate::case::BoundaryName::Energy => WallModelChoice::Energy,
            crate::case::BoundaryName::Bi => WallModelChoice::ShepardBi(match case.shepard {
                crate::case::ShepardName::Discrete => ShepardKind::Discrete,
                crate::case::ShepardName::Geometric => ShepardKind::Geometric,
                crate::case::ShepardName::Integrated => ShepardKind::Integrated,
            }),
            crate::case::BoundaryName::Usaw => WallModelChoice::Usaw(UsawParams {
                interpolation: match case.usaw.wall_interpolation {
                    crate::case::WallInterpolationName::Shepard => WallInterpolation::Shepard,
                    crate::case::WallInterpolationName::Neumann => WallInterpolation::Neumann,
                    crate::case::WallInterpolationName::Hydrostatic => {
                        WallInterpolation::Hydrostatic
                    }
                },
                geometric_gamma: case.usaw.gamma == crate::case::UsawGammaName::Geometric,
                no_wall_tension: !case.usaw.wall_tension,
            }),
        },
        diffusion: match case.fluid.diffusion {
            crate::case::DiffusionName::Delta => DiffusionChoice::Delta,
            crate::case::DiffusionName::Mayrhofer => DiffusionChoice::Mayrhofer {
                eta: case.fluid.eta,
            },
            crate::case::DiffusionName::Ferrari => DiffusionChoice::Ferrari {
                coefficient: case.fluid.ferrari_coefficient,
            },
        },
        density_power: if case.boundary == crate::case::BoundaryName::Usaw {
            case.usaw.density_power
        } else {
            0
        },
        particle_spacing: case.resolution.dx,
        summation_density: case.usaw.continuity == crate::case::ContinuityName::Summation,
        reorder_interval: 1,
        neighbour_skin: case.time.neighbour_skin,
        elastic_bounce: case.elastic_bounce,
        periodicity,
        viscosity: bisph_core::terms::Viscosity {
            nu: case.kinematic_viscosity(),
            min_wall_distance: 0.5 * dx,
        },
        flux: case.flux.as_ref().map(|f| {
            let direction = V::from_slice(&f.direction);
            let centre = (domain_min + domain_max) * 0.5;
            bisph_core::forcing::FluxControl {
                direction: direction / direction.length(),
                target_velocity: f.flux / f.area,
                area: f.area,
                slice_point: f.slice_point.as_deref().map_or(centre, V::from_slice),
                slice_width: f.slice_width.unwrap_or(2.0 * dx),
                rule: match f.rule {
                    crate::case::FluxRuleName::Eq63 => bisph_core::forcing::FluxRule::Eq63,
                    crate::case::FluxRuleName::Eq58 => bisph_core::forcing::FluxRule::Eq58,
                },
            }
        }),
        integrator: Integrator::Verlet,
        // set below, once the initial energies are known
    };
    let integrator = match case.time.integrator {
        crate::case::IntegratorName::Verlet => Integrator::Verlet,
        crate::case::IntegratorName::Midpoint => {
            let m = &case.midpoint;
            let (kinetic, compressible, _) = fluid_energies(&fluid, &eos, gravity);
            let potential = energy_scale(&fluid, &eos, gravity) - kinetic - compressible.abs();
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
            })
        }
    };
    let config = SimConfig {
        integrator,
        ..config
    };
    let mut walls = Walls::new(elements, bodies, kernel.support);
    walls.stretch = stretch;
    let mut sim = Simulation::new(config, fluid, walls, probes);
    if case.boundary == crate::case::BoundaryName::Usaw
        && case
            .fluid_block
            .iter()
            .all(|b| b.mass == crate::case::MassRule::Initial)
    {
        sim.vertex_masses_from_density();
    }
    Ok(sim)
}

/// Sets up the free bodies of a case: mass, centre of mass and inertia (given, or from the
/// body's closed mesh walls), initial attitude, velocities, locks and coupling.
fn free_bodies<V: CaseDim>(
    loaded: &LoadedCase,
    bodies: &mut [Body<V>],
    surfaces: &[(usize, bisph_core::surface::Surface)],
    gravity: V,
    elements: &BoundaryElements<V>,
) -> Result<(), CaseError> {
    use glam::{DMat3, DQuat};
    for (k, b) in loaded.case.body.iter().enumerate() {
        let Some(spec) = &b.free else { continue };
        let key = format!("body[{k}].free");
        if !elements.body.iter().any(|&j| j as usize == k + 1) {
            return Err(loaded.error(&key, "no [[wall]] belongs to this free body"));
        }
        // Solid from the body's mesh walls (uniform density).
        let mine: Vec<&bisph_core::surface::Surface> = surfaces
            .iter()
            .filter(|(i, _)| *i == k + 1)
            .map(|(_, s)| s)
            .collect();
        let solid = if mine.is_empty() {
            None
        } else {
            let (mut m, mut first, mut inertia) = (0.0, DVec3::ZERO, DMat3::ZERO);
            // Inertia about the origin, summed, then moved to the common centre of mass.
            let outer = |v: DVec3| DMat3::from_cols(v * v.x, v * v.y, v * v.z);
            let about_origin = |mass: f64, c: DVec3, i: DMat3| {
                let shift = DMat3::IDENTITY * c.length_squared() - outer(c);
                i + shift * mass
            };
            for s in &mine {
                let (mi, ci, ii) = s.mass_properties(1.0);
                m += mi;
                first += ci * mi;
                inertia += about_origin(mi, ci, ii);
            }
            let c = first / m;
            let about_c = inertia - (DMat3::IDENTITY * c.length_squared() - outer(c)) * m;
            Some((m, c, about_c))
        };
        let (mass, density) = match (spec.mass, spec.density, &solid) {
            (Some(m), _, Some((volume, _, _))) => (m, m / volume),
            (Some(m), _, None) => (m, 0.0),
            (None, Some(rho), Some((volume, _, _))) => (rho * volume, rho),
            (None, Some(_), None) => return Err(loaded.error(
                &format!("{key}.density"),
                "a density needs closed mesh walls (shape = \"mesh\" or \"capsule\") on this body",
            )),
            (None, None, _) => {
                return Err(loaded.error(&format!("{key}.mass"), "missing: a mass or a density"))
            }
        };
        let mut angles = [0.0; 3];
        match &spec.rotate {
            Some(crate::case::Angles::One(a)) => angles[2] = a.to_radians(),
            Some(crate::case::Angles::Many(v)) => {
                if V::DIM == 2 {
                    angles[2] = v.first().copied().unwrap_or(0.0).to_radians();
                } else {
                    for (i, a) in v.iter().take(3).enumerate() {
                        angles[i] = a.to_radians();
                    }
                }
            }
            None => {}
        }
        let attitude = DQuat::from_rotation_z(angles[2])
            * DQuat::from_rotation_y(angles[1])
            * DQuat::from_rotation_x(angles[0]);
        let inertia = match &spec.inertia {
            Some(i) if V::DIM == 2 => DMat3::from_diagonal(DVec3::new(1.0, 1.0, i[0])),
            Some(i) if i.len() == 3 => DMat3::from_diagonal(DVec3::new(i[0], i[1], i[2])),
            Some(i) => {
                DMat3::from_cols_array(&[i[0], i[3], i[6], i[1], i[4], i[7], i[2], i[5], i[8]])
            }
            None => match &solid {
                // World-axes tensor of the solid at time zero, in body axes.
                Some((_, _, i)) => {
                    let r = DMat3::from_quat(attitude);
                    r.transpose() * (*i * density) * r
                }
                None => {
                    return Err(loaded.error(
                        &format!("{key}.inertia"),
                        "missing: give the inertia, or closed mesh walls to compute it from",
                    ))
                }
            },
        };
        if inertia.determinant().abs() < f64::MIN_POSITIVE || !inertia.is_finite() {
            return Err(loaded.error(&format!("{key}.inertia"), "a singular inertia tensor"));
        }
        let centre = match (&b.centre, &solid) {
            (Some(c), _) => V::from_slice(c),
            (None, Some((_, c, _))) => V::from_slice(&c.to_array()),
            (None, None) => {
                return Err(loaded.error(
                    &format!("body[{k}].centre"),
                    "missing: the centre of mass (no closed mesh wall to compute it from)",
                ))
            }
        };
        let g = DVec3::from_array(gravity.to_xyz());
        let mut free = FreeBody::new(mass, inertia, attitude, g);
        if let Some(v) = &spec.velocity {
            free.velocity = DVec3::from_array(V::from_slice(v).to_xyz());
        }
        if let Some(w) = &spec.angular_velocity {
            free.angular_velocity = if V::DIM == 2 {
                DVec3::new(0.0, 0.0, w[0])
            } else {
                DVec3::from_slice(w)
            };
        }
        let axis = |a: &str| match a {
            "x" => 0,
            "y" => 1,
            _ => 2,
        };
        for a in &spec.lock_translation {
            free.locked_translation[axis(a)] = true;
        }
        for a in &spec.lock_rotation {
            free.locked_rotation[axis(a)] = true;
        }
        if V::DIM == 2 {
            free = free.planar();
        }
        if spec.coupling.as_deref() == Some("staggered") {
            free.coupling = Coupling::Staggered;
        }
        bodies[k + 1].centre = centre;
        bodies[k + 1].motion = Motion::Free(free);
    }
    Ok(())
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
