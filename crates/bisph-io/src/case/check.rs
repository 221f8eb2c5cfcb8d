//! Checks of a parsed case for physical sense and consistency; errors name the key and the
//! allowed range.

use crate::case::error::CaseError;
use crate::case::primitives::{
    check_round, check_round_wall, refuse_round_keys, refuse_round_shape_keys, round_bounds, Round,
    RoundKeys,
};
use crate::case::schema::LoadedCase;
use crate::case::schema::*;

/// Checks values for physical sense and consistency; errors name the key and the allowed range.
pub fn check_case(loaded: &LoadedCase) -> Result<(), CaseError> {
    let c = &loaded.case;
    if c.dim != 2 && c.dim != 3 {
        return Err(loaded.error("dim", format!("expected 2 or 3, found {}", c.dim)));
    }
    check_scales(loaded)?;
    check_time(loaded)?;
    check_midpoint(loaded)?;
    check_viscosity(loaded)?;
    check_flux(loaded)?;
    check_diffusion(loaded)?;
    check_wall_model(loaded)?;
    check_forces_and_output(loaded)?;
    check_fluid_blocks(loaded)?;
    check_walls(loaded)?;
    check_bodies(loaded)?;
    check_domain(loaded)?;
    check_pack(loaded)?;
    check_reliability(loaded)?;
    check_settle(loaded)?;
    check_probes(loaded)
}

/// A positive, finite number at `key`.
fn positive(loaded: &LoadedCase, key: &str, v: f64) -> Result<(), CaseError> {
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(loaded.error(key, format!("expected a positive number, found {v}")))
    }
}

/// Checks the fluid's density, sound speed and Tait exponent, the spacing against the
/// domain, the smoothing length and the end time.
fn check_scales(loaded: &LoadedCase) -> Result<(), CaseError> {
    let c = &loaded.case;
    positive(loaded, "fluid.density", c.fluid.density)?;
    positive(loaded, "fluid.sound_speed", c.fluid.sound_speed)?;
    positive(loaded, "resolution.dx", c.resolution.dx)?;
    positive(loaded, "time.end", c.time.end)?;
    positive(
        loaded,
        "resolution.element_over_dx",
        c.resolution.element_over_dx,
    )?;
    if c.fluid.tait_exponent.is_nan() || c.fluid.tait_exponent <= 1.0 {
        return Err(loaded.error(
            "fluid.tait_exponent",
            format!("expected a number above 1, found {}", c.fluid.tait_exponent),
        ));
    }
    if let Some(dom) = &c.domain {
        if let Some((k, w)) = dom
            .min
            .iter()
            .zip(&dom.max)
            .map(|(a, b)| b - a)
            .enumerate()
            .find(|(_, w)| *w < c.resolution.dx)
        {
            return Err(loaded.error(
                "resolution.dx",
                format!(
                    "expected dx at most the domain's extent {w} in direction {k}, found {}",
                    c.resolution.dx
                ),
            ));
        }
    }
    if !(1.0..=4.0).contains(&c.resolution.h_over_dx) {
        return Err(loaded.error(
            "resolution.h_over_dx",
            format!(
                "expected a value in [1, 4], found {}",
                c.resolution.h_over_dx
            ),
        ));
    }
    Ok(())
}

/// Checks `[time]`: the neighbour skin, the Courant number and the fixed and least steps.
fn check_time(loaded: &LoadedCase) -> Result<(), CaseError> {
    let t = &loaded.case.time;
    if !(t.neighbour_skin >= 0.0 && t.neighbour_skin <= 1.0) {
        return Err(loaded.error(
            "time.neighbour_skin",
            format!(
                "expected a fraction of the kernel support in [0, 1], found {}",
                t.neighbour_skin
            ),
        ));
    }
    if !(t.courant > 0.0 && t.courant <= 1.0) {
        return Err(loaded.error(
            "time.courant",
            format!("expected a value in (0, 1], found {}", t.courant),
        ));
    }
    if let Some(dt) = t.dt {
        positive(loaded, "time.dt", dt)?;
    }
    if let Some(dt) = t.min_dt {
        positive(loaded, "time.min_dt", dt)?;
    }
    Ok(())
}

/// Checks `[midpoint]`: iteration count, tolerance, relaxation fractions and the reference
/// energy a `"given"` tolerance needs.
fn check_midpoint(loaded: &LoadedCase) -> Result<(), CaseError> {
    let mp = &loaded.case.midpoint;
    if mp.max_iterations == 0 || mp.max_iterations > 1000 {
        return Err(loaded.error(
            "midpoint.max_iterations",
            format!("expected 1 to 1000, found {}", mp.max_iterations),
        ));
    }
    if mp.anderson_depth > 10 {
        return Err(loaded.error(
            "midpoint.anderson_depth",
            format!("expected 0 to 10, found {}", mp.anderson_depth),
        ));
    }
    if mp.tolerance.is_nan() || mp.tolerance < 0.0 {
        return Err(loaded.error(
            "midpoint.tolerance",
            format!("expected zero or a positive number, found {}", mp.tolerance),
        ));
    }
    for (key, v) in [
        ("midpoint.min_decrease", mp.min_decrease),
        ("midpoint.relax_increment", mp.relax_increment),
        ("midpoint.initial_relaxation", mp.initial_relaxation),
    ] {
        if !(0.0..1.0).contains(&v) {
            return Err(loaded.error(key, format!("expected a value in [0, 1), found {v}")));
        }
    }
    if mp.tolerance_reference == ToleranceReference::Given && mp.reference_energy.is_none() {
        return Err(loaded.error(
            "midpoint.reference_energy",
            "missing: needed by tolerance_reference = \"given\"",
        ));
    }
    Ok(())
}

/// Checks the delta-SPH coefficient, the artificial and the laminar viscosity.
fn check_viscosity(loaded: &LoadedCase) -> Result<(), CaseError> {
    let c = &loaded.case;
    if !(c.delta() >= 0.0 && c.delta() <= 1.0) {
        return Err(loaded.error(
            "fluid.delta",
            format!("expected a value in [0, 1], found {}", c.delta()),
        ));
    }
    if !(c.artificial_viscosity() >= 0.0 && c.artificial_viscosity() <= 1.0) {
        return Err(loaded.error(
            "fluid.artificial_viscosity",
            format!(
                "expected a value in [0, 1], found {}",
                c.artificial_viscosity()
            ),
        ));
    }
    if !(c.fluid.viscosity >= 0.0 && c.fluid.viscosity.is_finite()) {
        return Err(loaded.error(
            "fluid.viscosity",
            format!(
                "expected zero or a positive kinematic viscosity, found {}",
                c.fluid.viscosity
            ),
        ));
    }
    Ok(())
}

/// Checks `[flux]`: a finite flux, a positive area, a non-zero direction, the slice, and a
/// periodic domain to drive.
fn check_flux(loaded: &LoadedCase) -> Result<(), CaseError> {
    let c = &loaded.case;
    let d = c.dim as usize;
    let Some(f) = &c.flux else {
        return Ok(());
    };
    if !f.flux.is_finite() {
        return Err(loaded.error("flux.flux", "expected a finite number"));
    }
    positive(loaded, "flux.area", f.area)?;
    vector(loaded, "flux.direction", &f.direction, d)?;
    if f.direction.iter().all(|x| *x == 0.0) {
        return Err(loaded.error("flux.direction", "expected a non-zero vector"));
    }
    if let Some(p) = &f.slice_point {
        vector(loaded, "flux.slice_point", p, d)?;
    }
    if let Some(w) = f.slice_width {
        positive(loaded, "flux.slice_width", w)?;
    }
    if c.domain.as_ref().is_none_or(|dom| dom.periodic.is_empty()) {
        return Err(loaded.error(
            "flux",
            "a flux-driven flow needs a periodic [domain] (domain.periodic)",
        ));
    }
    Ok(())
}

/// Checks the coefficients of Mayrhofer's and Ferrari's density diffusion.
fn check_diffusion(loaded: &LoadedCase) -> Result<(), CaseError> {
    let f = &loaded.case.fluid;
    if !(f.eta.is_finite() && f.eta > 0.0) {
        return Err(loaded.error(
            "fluid.eta",
            format!("expected a positive number, found {}", f.eta),
        ));
    }
    if !(f.ferrari_coefficient.is_finite() && f.ferrari_coefficient >= 0.0) {
        return Err(loaded.error(
            "fluid.ferrari_coefficient",
            format!(
                "expected zero or a positive number, found {}",
                f.ferrari_coefficient
            ),
        ));
    }
    Ok(())
}

/// Checks that the wall model's options fit together: `[usaw]` settings, the dimension of
/// `usaw` walls and of the integrated gamma, `boundary_quadrature` with `bi` walls only, and
/// fixed walls under an integrated gamma.
fn check_wall_model(loaded: &LoadedCase) -> Result<(), CaseError> {
    let c = &loaded.case;
    if c.usaw.density_power > 1 {
        return Err(loaded.error(
            "usaw.density_power",
            format!("expected 0 or 1, found {}", c.usaw.density_power),
        ));
    }
    let integrated = c.boundary == BoundaryName::Usaw && c.usaw.gamma == UsawGammaName::Integrated
        || c.boundary == BoundaryName::Bi && c.shepard == ShepardName::Integrated;
    if c.boundary == BoundaryName::Usaw
        && c.usaw.continuity == ContinuityName::Summation
        && c.time.integrator != IntegratorName::Verlet
    {
        return Err(loaded.error(
            "usaw.continuity",
            "\"summation\" needs time.integrator = \"verlet\"",
        ));
    }
    if c.boundary == BoundaryName::Usaw && c.dim != 2 {
        return Err(loaded.error(
            "boundary",
            format!("\"usaw\" walls are 2-D only, found dim = {}", c.dim),
        ));
    }
    if c.boundary_quadrature.is_some() && c.boundary != BoundaryName::Bi {
        return Err(loaded.error(
            "boundary_quadrature",
            format!(
                "applies to boundary = \"bi\" only, found boundary = {:?}",
                c.boundary
            )
            .to_lowercase(),
        ));
    }
    if c.shepard == ShepardName::Integrated && c.dim != 2 {
        return Err(loaded.error(
            "shepard",
            format!("\"integrated\" gamma is 2-D only, found dim = {}", c.dim),
        ));
    }
    let moving = |b: &BodySpec| b.motion.is_some() || b.piston.is_some() || b.free.is_some();
    if integrated && c.body.iter().any(moving) {
        return Err(loaded.error(
            "body",
            "the integrated gamma (paper 3, eq 4) is built for fixed walls: use usaw.gamma = \"geometric\" or shepard = \"geometric\" with moving bodies",
        ));
    }
    Ok(())
}

/// Checks the background pressure, the gravity vector and the output intervals.
fn check_forces_and_output(loaded: &LoadedCase) -> Result<(), CaseError> {
    let c = &loaded.case;
    if !c.fluid.background_pressure.is_finite() {
        return Err(loaded.error("fluid.background_pressure", "expected a finite number"));
    }
    if !c.fluid.gravity.is_empty() {
        vector(loaded, "fluid.gravity", &c.fluid.gravity, c.dim as usize)?;
    }
    if c.output.vtk_interval < 0.0 || c.output.series_interval < 0.0 {
        return Err(loaded.error("output", "intervals must be zero or positive"));
    }
    Ok(())
}

/// Checks `[[fluid_block]]`: at least one, each with its shape, holes, fill, spacing,
/// velocity and initial pressure.
fn check_fluid_blocks(loaded: &LoadedCase) -> Result<(), CaseError> {
    if loaded.case.fluid_block.is_empty() {
        return Err(loaded.error(
            "fluid_block",
            "expected at least one [[fluid_block]]: the case has no fluid",
        ));
    }
    for k in 0..loaded.case.fluid_block.len() {
        check_fluid_block(loaded, k)?;
    }
    Ok(())
}

/// Checks fluid block `k`.
fn check_fluid_block(loaded: &LoadedCase, k: usize) -> Result<(), CaseError> {
    let c = &loaded.case;
    let d = c.dim as usize;
    let b = &c.fluid_block[k];
    let key = format!("fluid_block[{k}]");
    if b.shape == BlockShape::Walls {
        check_walls_block(loaded, k)?;
    } else {
        check_shape(loaded, &key, &b.shape_spec(), d, true)?;
        if b.level.is_some() || b.clearance.is_some() {
            return Err(loaded.error(
                &key,
                "`level` and `clearance` belong to a shape = \"walls\" block",
            ));
        }
    }
    for (m, hole) in b.hole.iter().enumerate() {
        let hkey = format!("{key}.hole[{m}]");
        if hole.shape == BlockShape::Particles {
            return Err(loaded.error(
                &format!("{hkey}.shape"),
                "a hole must be a shape, not \"particles\"",
            ));
        }
        check_shape(loaded, &hkey, hole, d, false)?;
    }
    if let Some(fill) = b.fill {
        check_fill(loaded, &key, b, fill)?;
    }
    if let Some(dx) = b.dx {
        positive(loaded, &format!("{key}.dx"), dx)?;
    }
    if let Some(v) = &b.velocity {
        vector(loaded, &format!("{key}.velocity"), v, d)?;
    }
    if let Some(tp) = &b.pressure_taper {
        if tp.axis >= d {
            return Err(loaded.error(
                &format!("{key}.pressure_taper.axis"),
                format!("expected 0 to {}, found {}", d - 1, tp.axis),
            ));
        }
        positive(loaded, &format!("{key}.pressure_taper.length"), tp.length)?;
    }
    if let Some(InitialPressure::Named(name)) = &b.pressure {
        check_named_pressure(loaded, &key, name)?;
    }
    Ok(())
}

/// Checks the `fill` of the block at `key`: `"usaw"` for a 2-D lattice block with usaw walls,
/// `"bipi"` for a shape with a region (not particles).
fn check_fill(
    loaded: &LoadedCase,
    key: &str,
    b: &FluidBlock,
    fill: FillName,
) -> Result<(), CaseError> {
    let c = &loaded.case;
    if fill == FillName::Usaw
        && (c.boundary != BoundaryName::Usaw || c.dim != 2 || b.shape == BlockShape::Particles)
    {
        return Err(loaded.error(
            &format!("{key}.fill"),
            "\"usaw\" relaxes a 2-D lattice block for boundary = \"usaw\"",
        ));
    }
    if fill == FillName::Bipi && b.shape == BlockShape::Particles {
        return Err(loaded.error(
            &format!("{key}.fill"),
            "a \"particles\" block is already placed; it cannot be packed",
        ));
    }
    Ok(())
}

/// Checks a named initial pressure of the block at `key`: a known profile, and no gravity
/// along a periodic axis.
fn check_named_pressure(loaded: &LoadedCase, key: &str, name: &str) -> Result<(), CaseError> {
    if name != "hydrostatic" && name != "hydrostatic-eos" {
        return Err(loaded.error(
            &format!("{key}.pressure"),
            format!("expected \"hydrostatic\", \"hydrostatic-eos\" or a number, found \"{name}\""),
        ));
    }
    if let Some(axis) = gravity_along_periodic_axis(&loaded.case) {
        return Err(loaded.error(
            &format!("{key}.pressure"),
            format!(
                "\"{name}\" with gravity along the periodic axis {axis}: the pressure \
                 would jump where the period closes and start density waves; expected a \
                 uniform pressure (a number, e.g. 0; the default there) or gravity \
                 perpendicular to the periodic axes"
            ),
        ));
    }
    Ok(())
}

/// Checks `[[wall]]`: at least one (or a domain), each with its element size, shape, fluid
/// side, open sides and owning body.
fn check_walls(loaded: &LoadedCase) -> Result<(), CaseError> {
    let c = &loaded.case;
    let d = c.dim as usize;
    if c.wall.is_empty() && c.domain.is_none() {
        return Err(loaded.error(
            "wall",
            "expected at least one [[wall]], or a [domain] for a case without walls",
        ));
    }
    for (k, w) in c.wall.iter().enumerate() {
        let key = format!("wall[{k}]");
        if let Some(size) = w.element_size {
            positive(loaded, &format!("{key}.element_size"), size)?;
        }
        if let Some(round) = Round::of_wall(w.shape) {
            check_round_wall(loaded, &key, round, w, d)?;
            check_owner(loaded, &key, w)?;
            continue;
        }
        refuse_round_keys(loaded, &key, w)?;
        if d == 3 && matches!(w.shape, WallShape::Mesh | WallShape::Capsule) {
            crate::case::mesh_walls::check_wall(loaded, &key, w)?;
        } else {
            let outline = match w.shape {
                WallShape::Box => Some(Outline::Box),
                WallShape::Polygon => Some(Outline::Polygon),
                WallShape::Polyline => Some(Outline::Polyline),
                _ => None,
            };
            let points = (&w.min, &w.max, &w.points);
            shape_points(loaded, &key, w.shape.name(), outline, points, d)?;
            if let Some(f) = &w.fluid {
                if w.shape != WallShape::Box || (f != "inside" && f != "outside") {
                    return Err(loaded.error(
                        &format!("{key}.fluid"),
                        format!("expected \"inside\" or \"outside\" on a box, mesh, circle, sphere or cylinder wall, found \"{f}\" on a \"{}\"", w.shape.name()),
                    ));
                }
            }
        }
        let sides: &[&str] = if d == 2 {
            &bisph_core::geometry::BOX_SIDES_2D
        } else {
            &bisph_core::geometry::BOX_FACES_3D
        };
        for o in &w.open {
            if !sides.contains(&o.as_str()) {
                return Err(loaded.error(
                    &format!("{key}.open"),
                    format!("expected sides among {sides:?}, found \"{o}\""),
                ));
            }
        }
        check_owner(loaded, &key, w)?;
    }
    Ok(())
}

/// Checks that the `[[body]]` owning the wall at `key`, if any, exists.
fn check_owner(loaded: &LoadedCase, key: &str, w: &WallSpec) -> Result<(), CaseError> {
    if let Some(body) = &w.body {
        if !loaded.case.body.iter().any(|b| &b.name == body) {
            return Err(loaded.error(
                &format!("{key}.body"),
                format!("no [[body]] is named \"{body}\""),
            ));
        }
    }
    Ok(())
}

/// Checks `[[body]]`: unique names, the centre, and one of a free, piston or prescribed
/// motion with its vectors.
fn check_bodies(loaded: &LoadedCase) -> Result<(), CaseError> {
    let c = &loaded.case;
    let d = c.dim as usize;
    for (k, b) in c.body.iter().enumerate() {
        let key = format!("body[{k}]");
        if b.name.is_empty() || c.body.iter().filter(|o| o.name == b.name).count() > 1 {
            return Err(loaded.error(
                &format!("{key}.name"),
                format!("expected a unique, non-empty name, found \"{}\"", b.name),
            ));
        }
        if let Some(centre) = &b.centre {
            vector(loaded, &format!("{key}.centre"), centre, d)?;
        }
        if let Some(fs) = &b.free {
            if b.motion.is_some() || b.piston.is_some() {
                return Err(loaded.error(
                    &format!("{key}.free"),
                    "a body has one of motion, piston or free, not several",
                ));
            }
            check_free(loaded, &key, fs, d)?;
        }
        if let Some(p) = &b.piston {
            if b.motion.is_some() {
                return Err(loaded.error(
                    &format!("{key}.piston"),
                    "a body has either a motion or a piston, not both",
                ));
            }
            vector(loaded, &format!("{key}.piston.axis"), &p.axis, d)?;
            if p.axis.iter().all(|x| *x == 0.0) {
                return Err(
                    loaded.error(&format!("{key}.piston.axis"), "expected a non-zero vector")
                );
            }
            positive(loaded, &format!("{key}.piston.mass"), p.mass)?;
        }
        if let Some(m) = &b.motion {
            for (name, v) in [
                ("velocity", &m.velocity),
                ("amplitude", &m.amplitude),
                ("axis", &m.axis),
            ] {
                if let Some(v) = v {
                    vector(
                        loaded,
                        &format!("{key}.motion.{name}"),
                        v,
                        if name == "axis" { 3 } else { d },
                    )?;
                }
            }
        }
    }
    Ok(())
}

/// Checks `[domain]`: its corners, and periodic axes named once, each at least three kernel
/// supports long.
fn check_domain(loaded: &LoadedCase) -> Result<(), CaseError> {
    let c = &loaded.case;
    let d = c.dim as usize;
    let Some(dom) = &c.domain else {
        return Ok(());
    };
    vector(loaded, "domain.min", &dom.min, d)?;
    vector(loaded, "domain.max", &dom.max, d)?;
    if dom.min.iter().zip(&dom.max).any(|(a, b)| a >= b) {
        return Err(loaded.error("domain", "expected min < max in every direction"));
    }
    let names = &["x", "y", "z"][..d];
    for (k, a) in dom.periodic.iter().enumerate() {
        let Some(axis) = names.iter().position(|n| n == a) else {
            return Err(loaded.error(
                "domain.periodic",
                format!("expected axes among {names:?}, found \"{a}\""),
            ));
        };
        if dom.periodic[..k].contains(a) {
            return Err(loaded.error("domain.periodic", format!("axis \"{a}\" is listed twice")));
        }
        let support = 2.0 * c.resolution.h_over_dx * c.resolution.dx;
        let period = dom.max[axis] - dom.min[axis];
        if period < 3.0 * support {
            return Err(loaded.error(
                "domain.periodic",
                format!(
                    "the period along {a} (domain extent {period}) must be at least three kernel supports ({})",
                    3.0 * support
                ),
            ));
        }
    }
    Ok(())
}

/// Checks `[[probe]]`: a position of the case's dimension.
fn check_probes(loaded: &LoadedCase) -> Result<(), CaseError> {
    let d = loaded.case.dim as usize;
    for (k, p) in loaded.case.probe.iter().enumerate() {
        vector(loaded, &format!("probe[{k}].position"), &p.position, d)?;
    }
    Ok(())
}

/// Checks of the `[checkpoint]` and `[diagnostics]` keys, and placement checks: fluid blocks and
/// probes inside the domain (or, without a domain, inside the box around the walls).
fn check_reliability(loaded: &LoadedCase) -> Result<(), CaseError> {
    let c = &loaded.case;
    let d = c.dim as usize;
    let e = |key: &str, msg: String| Err(loaded.error(key, msg));
    let ck = &c.checkpoint;
    if !(ck.every_minutes >= 0.0 && ck.every_minutes.is_finite()) {
        return e(
            "checkpoint.every_minutes",
            format!(
                "expected zero (off) or a positive number of minutes, found {}",
                ck.every_minutes
            ),
        );
    }
    let g = &c.diagnostics;
    if !(g.density_ratio_min > 0.0 && g.density_ratio_min <= 1.0) {
        return e(
            "diagnostics.density_ratio_min",
            format!("expected a value in (0, 1], found {}", g.density_ratio_min),
        );
    }
    if !(g.density_ratio_max >= 1.0 && g.density_ratio_max.is_finite()) {
        return e(
            "diagnostics.density_ratio_max",
            format!(
                "expected a finite value >= 1, found {}",
                g.density_ratio_max
            ),
        );
    }
    if !(g.speed_over_c0 > 0.0 && g.speed_over_c0.is_finite()) {
        return e(
            "diagnostics.speed_over_c0",
            format!("expected a positive number, found {}", g.speed_over_c0),
        );
    }
    if !(0.0..1.0).contains(&g.dt_collapse) {
        return e(
            "diagnostics.dt_collapse",
            format!(
                "expected a value in [0, 1) (0 = off), found {}",
                g.dt_collapse
            ),
        );
    }
    if !(g.energy_growth >= 0.0 && g.energy_growth.is_finite()) {
        return e(
            "diagnostics.energy_growth",
            format!(
                "expected zero (off) or a positive number, found {}",
                g.energy_growth
            ),
        );
    }
    if !(0.0..=1.0).contains(&g.removed_fraction_max) {
        return e(
            "diagnostics.removed_fraction_max",
            format!(
                "expected a fraction in [0, 1] (0 = stop at the first particle leaving the domain), found {}",
                g.removed_fraction_max
            ),
        );
    }
    if let Some(dt) = c.time.min_dt {
        if dt >= c.time.end {
            return e(
                "time.min_dt",
                format!(
                    "expected a value below time.end = {}, found {dt}",
                    c.time.end
                ),
            );
        }
    }
    // The region particles and probes must lie in: the domain, else the walls' bounding box.
    let (lo, hi, region) = match &c.domain {
        Some(dom) => (dom.min.clone(), dom.max.clone(), "the domain"),
        None => {
            let mut lo = vec![f64::INFINITY; d];
            let mut hi = vec![f64::NEG_INFINITY; d];
            let mut grow = |p: &[f64]| {
                for k in 0..d.min(p.len()) {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            };
            for w in &c.wall {
                if matches!(w.shape, WallShape::Mesh | WallShape::Capsule) {
                    return Ok(()); // walls from files: no box known before building
                }
                if let Some(round) = Round::of_wall(w.shape) {
                    let (a, z) = round_bounds(round, RoundKeys::of_wall(w), d);
                    grow(&a);
                    grow(&z);
                }
                for p in w.min.iter().chain(w.max.iter()) {
                    grow(p);
                }
                for p in w.points.iter().flatten() {
                    grow(p);
                }
            }
            if lo.iter().any(|x| !x.is_finite()) {
                return Ok(());
            }
            (lo, hi, "the box around the walls")
        }
    };
    let outside = |p: &[f64]| {
        p.iter()
            .zip(lo.iter().zip(&hi))
            .any(|(x, (a, b))| !(x >= a && x <= b))
    };
    let range = format!("{lo:?} to {hi:?}");
    for (k, p) in c.probe.iter().enumerate() {
        if p.position.len() == d && outside(&p.position) {
            return e(
                &format!("probe[{k}].position"),
                format!(
                    "expected a point inside {region}, {range}, found {:?}",
                    p.position
                ),
            );
        }
    }
    if c.domain.is_some() {
        for (k, b) in c.fluid_block.iter().enumerate() {
            let corners: Vec<&Vec<f64>> = match (&b.min, &b.max, &b.points) {
                (Some(a), Some(z), _) if b.shape == BlockShape::Box => vec![a, z],
                (_, _, Some(pts)) if b.shape == BlockShape::Polygon => pts.iter().collect(),
                _ => continue,
            };
            if let Some(p) = corners.iter().find(|p| p.len() == d && outside(p)) {
                return e(
                    &format!("fluid_block[{k}]"),
                    format!(
                        "expected the block inside {region}, {range}; its corner {p:?} is outside"
                    ),
                );
            }
        }
    }
    Ok(())
}

/// Checks a `[body.free]` table.
fn check_free(loaded: &LoadedCase, key: &str, f: &FreeSpec, d: usize) -> Result<(), CaseError> {
    let key = format!("{key}.free");
    let err = |k: &str, m: String| Err(loaded.error(&format!("{key}.{k}"), m));
    for (name, v) in [("mass", f.mass), ("density", f.density)] {
        if let Some(v) = v {
            if !(v.is_finite() && v > 0.0) {
                return err(name, format!("expected a positive number, found {v}"));
            }
        }
    }
    if f.mass.is_some() && f.density.is_some() {
        return err("density", "give mass or density, not both".into());
    }
    if f.mass.is_none() && f.density.is_none() {
        return err(
            "mass",
            "missing: a mass (or a density with closed mesh walls)".into(),
        );
    }
    if d == 2 && (f.inertia.is_none() || f.mass.is_none()) {
        return err(
            "inertia",
            "a 2-D body needs its mass and inertia (I_zz)".into(),
        );
    }
    if let Some(i) = &f.inertia {
        let ok = if d == 2 {
            i.len() == 1
        } else {
            i.len() == 3 || i.len() == 9
        };
        if !ok || i.iter().any(|x| !x.is_finite()) {
            return err(
                "inertia",
                format!(
                    "expected {}, found {} values",
                    if d == 2 {
                        "1 value (I_zz)"
                    } else {
                        "3 principal moments or 9 values"
                    },
                    i.len()
                ),
            );
        }
        let diagonal: Vec<f64> = if i.len() == 9 {
            vec![i[0], i[4], i[8]]
        } else {
            i.clone()
        };
        if diagonal.iter().any(|x| *x <= 0.0) {
            return err("inertia", "expected positive moments of inertia".into());
        }
    }
    if let Some(v) = &f.velocity {
        vector(loaded, &format!("{key}.velocity"), v, d)?;
    }
    if let Some(w) = &f.angular_velocity {
        vector(
            loaded,
            &format!("{key}.angular_velocity"),
            w,
            if d == 2 { 1 } else { 3 },
        )?;
    }
    for (name, list) in [
        ("lock_translation", &f.lock_translation),
        ("lock_rotation", &f.lock_rotation),
    ] {
        for a in list {
            if !["x", "y", "z"].contains(&a.as_str()) {
                return err(
                    name,
                    format!("expected axes among \"x\", \"y\", \"z\", found \"{a}\""),
                );
            }
        }
    }
    if let Some(c) = &f.coupling {
        if c != "iterated" && c != "staggered" {
            return err(
                "coupling",
                format!("expected \"iterated\" or \"staggered\", found \"{c}\""),
            );
        }
    }
    Ok(())
}

fn vector(loaded: &LoadedCase, key: &str, v: &[f64], d: usize) -> Result<(), CaseError> {
    if v.len() != d {
        return Err(loaded.error(key, format!("expected {d} numbers, found {}", v.len())));
    }
    if v.iter().any(|x| !x.is_finite()) {
        return Err(loaded.error(key, "expected finite numbers".to_string()));
    }
    Ok(())
}

/// How a shape given in the case file by its points lays them out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Outline {
    /// `min` and `max` corners.
    Box,
    /// Closed vertices.
    Polygon,
    /// Open vertices.
    Polyline,
}

/// The `min`, `max` and `points` of a shape.
type ShapePoints<'a> = (
    &'a Option<Vec<f64>>,
    &'a Option<Vec<f64>>,
    &'a Option<Vec<Vec<f64>>>,
);

/// Checks the points of the shape named `shape` at `key` laid out as `outline`: a box's
/// corners, or the vertices of a 2-D polygon or polyline; other shapes are refused.
fn shape_points(
    loaded: &LoadedCase,
    key: &str,
    shape: &str,
    outline: Option<Outline>,
    (min, max, points): ShapePoints,
    d: usize,
) -> Result<(), CaseError> {
    match outline {
        Some(Outline::Box) => {
            let (Some(lo), Some(hi)) = (min, max) else {
                return Err(loaded.error(key, "a box needs `min` and `max`"));
            };
            vector(loaded, &format!("{key}.min"), lo, d)?;
            vector(loaded, &format!("{key}.max"), hi, d)?;
            if lo.iter().zip(hi).any(|(a, b)| a >= b) {
                return Err(loaded.error(key, "expected min < max in every direction"));
            }
            Ok(())
        }
        Some(o @ (Outline::Polygon | Outline::Polyline)) if d == 2 => {
            let Some(pts) = points else {
                return Err(loaded.error(
                    &format!("{key}.points"),
                    "missing: a list of [x, y] vertices",
                ));
            };
            let needed = if o == Outline::Polygon { 3 } else { 2 };
            if pts.len() < needed {
                return Err(loaded.error(
                    &format!("{key}.points"),
                    format!("expected at least {needed} vertices, found {}", pts.len()),
                ));
            }
            for (k, p) in pts.iter().enumerate() {
                vector(loaded, &format!("{key}.points[{k}]"), p, 2)?;
            }
            Ok(())
        }
        _ => {
            let allowed = if d == 2 {
                "\"box\", \"polygon\", \"polyline\" or \"circle\""
            } else {
                "\"box\", \"mesh\", \"capsule\", \"sphere\" or \"cylinder\""
            };
            Err(loaded.error(
                &format!("{key}.shape"),
                format!("expected {allowed} in {d}-D, found \"{shape}\""),
            ))
        }
    }
}

/// Checks one shape of a fluid block or hole (`particles` allowed for blocks only).
fn check_shape(
    loaded: &LoadedCase,
    key: &str,
    s: &ShapeSpec,
    d: usize,
    allow_particles: bool,
) -> Result<(), CaseError> {
    let e = |k: &str, msg: String| Err(loaded.error(k, msg));
    refuse_round_shape_keys(loaded, key, s)?;
    match s.shape {
        BlockShape::Box | BlockShape::Polygon | BlockShape::Polyline => {
            let outline = match s.shape {
                BlockShape::Box => Outline::Box,
                BlockShape::Polygon => Outline::Polygon,
                _ => Outline::Polyline,
            };
            let points = (&s.min, &s.max, &s.points);
            shape_points(loaded, key, s.shape.name(), Some(outline), points, d)?
        }
        BlockShape::PolygonFile | BlockShape::Stl | BlockShape::Particles => {
            let needed_dim = match s.shape {
                BlockShape::PolygonFile => Some(2),
                BlockShape::Stl => Some(3),
                _ => None,
            };
            if let Some(nd) = needed_dim {
                if nd != d {
                    return e(
                        &format!("{key}.shape"),
                        format!(
                            "\"{}\" is a {nd}-D shape, but the case is {d}-D",
                            s.shape.name()
                        ),
                    );
                }
            }
            if s.shape == BlockShape::Particles && !allow_particles {
                return e(&format!("{key}.shape"), "expected a shape".into());
            }
            match &s.file {
                Some(f) if !f.trim().is_empty() => {}
                _ => {
                    return e(
                        &format!("{key}.file"),
                        format!(
                            "missing: shape \"{}\" reads its data from a file",
                            s.shape.name()
                        ),
                    )
                }
            }
        }
        BlockShape::Sphere | BlockShape::Circle | BlockShape::Cylinder => {
            let round = Round::of_block(s.shape).expect("a round shape");
            check_round(loaded, key, round, RoundKeys::of_shape(s), d)?;
            if let (Some(_), false) = (s.subdivisions, round == Round::Sphere) {
                return e(
                    &format!("{key}.subdivisions"),
                    format!("a {} takes no `subdivisions`", round.name()),
                );
            }
            if let Some(n) = s.subdivisions {
                if n > 8 {
                    return e(
                        &format!("{key}.subdivisions"),
                        format!("expected at most 8 (20 * 4^8 triangles), found {n}"),
                    );
                }
            }
        }
        other => {
            let allowed = if d == 2 {
                "\"box\", \"polygon\", \"polygon_file\", \"circle\" or \"particles\""
            } else {
                "\"box\", \"stl\", \"sphere\", \"cylinder\" or \"particles\""
            };
            return e(
                &format!("{key}.shape"),
                format!("expected {allowed} in {d}-D, found \"{}\"", other.name()),
            );
        }
    }
    if let Some(u) = &s.units {
        if unit_factor(u).is_none() {
            return e(
                &format!("{key}.units"),
                format!("expected \"m\", \"cm\" or \"mm\", found \"{u}\""),
            );
        }
    }
    if let Some(sc) = s.scale {
        if !(sc > 0.0 && sc.is_finite()) {
            return e(
                &format!("{key}.scale"),
                format!("expected a positive number, found {sc}"),
            );
        }
    }
    if let Some(t) = &s.translate {
        vector(loaded, &format!("{key}.translate"), t, d)?;
    }
    if let Some(r) = &s.rotate {
        let n = match r {
            Angles::One(a) => {
                if !a.is_finite() {
                    return e(&format!("{key}.rotate"), "expected finite angles".into());
                }
                1
            }
            Angles::Many(v) => {
                vector(loaded, &format!("{key}.rotate"), v, v.len())?;
                v.len()
            }
        };
        let want = if d == 2 { 1 } else { 3 };
        if n != want {
            return e(
                &format!("{key}.rotate"),
                format!("expected {want} angle(s) in degrees in {d}-D, found {n}"),
            );
        }
    }
    Ok(())
}

/// Checks the `[pack]` table.
fn check_pack(loaded: &LoadedCase) -> Result<(), CaseError> {
    let p = &loaded.case.pack;
    let range = |key: &str, v: Option<f64>, lo: f64, hi: f64| -> Result<(), CaseError> {
        match v {
            Some(x) if !(x >= lo && x <= hi) => Err(loaded.error(
                &format!("pack.{key}"),
                format!("expected a value in [{lo}, {hi}], found {x}"),
            )),
            _ => Ok(()),
        }
    };
    range("diffusion", p.diffusion, 1e-6, 10.0)?;
    range("max_shift", p.max_shift, 1e-6, 1.0)?;
    range("push_radius", p.push_radius, 0.0, 2.0)?;
    range("plateau_tolerance", p.plateau_tolerance, 0.0, 1.0)?;
    range("freeze_distance", p.freeze_distance, 0.0, 4.0)?;
    range("stage_c_tolerance", p.stage_c_tolerance, 0.0, 1.0)?;
    range("step_damping", p.step_damping, 1e-3, 1.0)?;
    if p.plateau_window == Some(0) {
        return Err(loaded.error("pack.plateau_window", "expected at least 1 iteration"));
    }
    if p.report_interval == Some(0) {
        return Err(loaded.error("pack.report_interval", "expected at least 1 iteration"));
    }
    Ok(())
}

/// Checks `[settle]`: positive numbers, and, when enabled, a case that starts at rest under
/// gravity with fixed walls and no driving force.
fn check_settle(loaded: &LoadedCase) -> Result<(), CaseError> {
    let c = &loaded.case;
    let s = &c.settle;
    for (key, value) in [
        ("settle.damping", s.damping),
        ("settle.tolerance", s.tolerance),
        ("settle.max_time", s.max_time),
    ] {
        if let Some(v) = value {
            if !(v > 0.0 && v.is_finite()) {
                return Err(loaded.error(key, format!("expected a positive number, found {v}")));
            }
        }
    }
    if s.enabled != Some(true) {
        return Ok(());
    }
    match c.settle_obstacle() {
        Some(why) => Err(loaded.error(
            "settle.enabled",
            format!("settling needs fluid at rest under gravity with fixed walls: {why}"),
        )),
        None => Ok(()),
    }
}

/// A `shape = "walls"` block: walls to fill, gravity, a finite `level` and `clearance`, no
/// holes (obstacles are walls) and no packing.
fn check_walls_block(loaded: &LoadedCase, k: usize) -> Result<(), CaseError> {
    let c = &loaded.case;
    let b = &c.fluid_block[k];
    let key = format!("fluid_block[{k}]");
    let e = |sub: &str, msg: &str| Err(loaded.error(&format!("{key}{sub}"), msg.to_string()));
    if c.wall.is_empty() {
        return e(
            ".shape",
            "\"walls\" fills the case's walls, but it has no [[wall]]",
        );
    }
    if c.fluid.gravity.iter().all(|g| *g == 0.0) {
        return e(
            ".shape",
            "\"walls\" fills up to a level along gravity: fluid.gravity must not be zero",
        );
    }
    match b.level {
        None => {
            return e(
                ".level",
                "missing: the height along -g up to which the walls are filled",
            )
        }
        Some(l) if !l.is_finite() => {
            return e(".level", &format!("expected a finite height, found {l}"))
        }
        _ => {}
    }
    if let Some(r) = b.clearance {
        if !(r.is_finite() && r >= 0.0) {
            return e(
                ".clearance",
                &format!("expected zero or a positive fraction of dx, found {r}"),
            );
        }
    }
    if !b.hole.is_empty() {
        return e(
            ".hole",
            "a \"walls\" block has no holes: obstacles inside the walls are cut out already",
        );
    }
    Ok(())
}

/// The first periodic axis (`"x"`, `"y"` or `"z"`) along which gravity has a component: a
/// hydrostatic pressure along it cannot be periodic.
pub(crate) fn gravity_along_periodic_axis(c: &Case) -> Option<&'static str> {
    c.domain
        .as_ref()?
        .periodic_axes()
        .into_iter()
        .find(|&a| c.fluid.gravity.get(a).is_some_and(|&g| g != 0.0))
        .map(|a| ["x", "y", "z"][a])
}

#[cfg(test)]
mod tests {
    use crate::case::load::parse_case;

    /// `fill = "usaw"` relaxes for usaw walls only: elsewhere a named error.
    #[test]
    fn usaw_fill_needs_usaw_walls() {
        let text = include_str!("../../../../cases/usaw-tank-corner.toml");
        assert!(parse_case("tank", text, &[]).is_ok());
        let Err(err) = parse_case("tank", text, &["boundary=\"bi\"".to_string()]) else {
            panic!("fill = \"usaw\" with bi walls must be refused");
        };
        let err = err.to_string();
        assert!(err.contains("fluid_block[0].fill"), "{err}");
    }
}
