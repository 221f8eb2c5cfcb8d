//! The free bodies of a case: mass, centre of mass and inertia, attitude, velocities, locks
//! and coupling.

use crate::case::dim::CaseDim;
use crate::case::error::CaseError;
use crate::case::schema::LoadedCase;
use bisph_core::bodies::{Body, Coupling, FreeBody, Motion};
use bisph_core::walls::BoundaryElements;
use glam::DVec3;

/// Sets up the free bodies of a case: mass, centre of mass and inertia (given, or from the
/// body's closed mesh walls), initial attitude, velocities, locks and coupling.
pub fn free_bodies<V: CaseDim>(
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
                "a density needs closed mesh walls (shape = \"mesh\", \"capsule\", \"sphere\" or a closed \"cylinder\") on this body",
            )),
            (None, None, _) => {
                return Err(loaded.error(&format!("{key}.mass"), "missing: a mass or a density"))
            }
        };
        let mut angles = [0.0; 3];
        match &spec.rotate {
            Some(crate::case::schema::Angles::One(a)) => angles[2] = a.to_radians(),
            Some(crate::case::schema::Angles::Many(v)) => {
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
