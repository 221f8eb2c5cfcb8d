//! 3-D walls from meshes: `[[wall]] shape = "mesh"` (STL, binary or ASCII, or OBJ with
//! triangles and quads), `shape = "capsule"` (the parametric Apollo-like capsule) with the
//! case's transform, and the generated `sphere` and `cylinder`; checked (closed, consistent,
//! not inverted, no degenerate face) and oriented so the element normals point out of the
//! fluid (paper 1, 5.4).

use crate::case::schema::LoadedCase;

use crate::case::error::CaseError;
use crate::case::regions::transform_from;
use crate::case::schema::{WallShape, WallSpec, MAX_MESH_ELEMENTS};
use crate::formats::mesh_files::{read_obj, read_stl_facets, Transform};
use bisph_core::geometry::ElementShape;
use bisph_core::surface::{Capsule, Surface};
use glam::DVec3;

/// The wall's transform (units, scale, rotation, translation).
pub fn wall_transform(w: &WallSpec) -> Transform {
    transform_from(&w.units, w.scale, &w.rotate, &w.translate)
}

/// Static checks of a mesh or capsule wall, then the mesh itself (read and checked).
pub fn check_wall(loaded: &LoadedCase, key: &str, w: &WallSpec) -> Result<(), CaseError> {
    if let Some(f) = &w.fluid {
        if f != "inside" && f != "outside" {
            return Err(loaded.error(
                &format!("{key}.fluid"),
                format!("expected \"inside\" or \"outside\", found \"{f}\""),
            ));
        }
    }
    if let Some(u) = &w.units {
        if crate::case::schema::unit_factor(u).is_none() {
            return Err(loaded.error(
                &format!("{key}.units"),
                format!("expected \"m\", \"cm\" or \"mm\", found \"{u}\""),
            ));
        }
    }
    if let Some(s) = w.scale {
        if !(s > 0.0 && s.is_finite()) {
            return Err(loaded.error(
                &format!("{key}.scale"),
                format!("expected a positive number, found {s}"),
            ));
        }
    }
    if let Some(t) = &w.translate {
        if t.len() != 3 || t.iter().any(|x| !x.is_finite()) {
            return Err(loaded.error(
                &format!("{key}.translate"),
                format!("expected 3 finite numbers, found {t:?}"),
            ));
        }
    }
    if let Some(crate::case::schema::Angles::Many(a)) = &w.rotate {
        if a.len() != 3 {
            return Err(loaded.error(
                &format!("{key}.rotate"),
                format!(
                    "expected 3 angles (degrees about x, y, z), found {}",
                    a.len()
                ),
            ));
        }
    }
    if w.shape == WallShape::Capsule && w.closed == Some(false) {
        return Err(loaded.error(&format!("{key}.closed"), "a capsule is always closed"));
    }
    if w.closed == Some(false) && w.fluid.is_some() {
        return Err(loaded.error(
            &format!("{key}.fluid"),
            "an open mesh has no inside: orient it with `flip` instead",
        ));
    }
    wall_surface(loaded, key, w, 1.0).map(|_| ())
}

/// Reads (or generates) the wall's surface, transformed, checked and oriented with its
/// normals out of the fluid. `size` is the target face size of a generated capsule, sphere
/// or cylinder.
pub fn wall_surface(
    loaded: &LoadedCase,
    key: &str,
    w: &WallSpec,
    size: f64,
) -> Result<Surface, CaseError> {
    let bad = |m: String| loaded.error(key, m);
    let closed = if w.shape.is_round() {
        w.open.is_empty()
    } else {
        w.closed.unwrap_or(true)
    };
    let mut surface = match w.shape {
        WallShape::Sphere | WallShape::Cylinder => {
            let faces = crate::case::primitives::round_wall_faces(w, size)
                .map_err(|m| loaded.error(key, m))?;
            let mut extent = 0.0f64;
            for p in faces.iter().flatten() {
                extent = extent.max(p.abs().max_element());
            }
            Surface::from_polygons(&faces, None, 1e-9 * extent.max(1e-300))
                .map_err(|e| loaded.error(key, e.to_string()))?
        }
        WallShape::Capsule => {
            let Some(c) = &w.capsule else {
                return Err(loaded.error(
                    &format!("{key}.capsule"),
                    "missing: heat_shield_radius, diameter, shoulder_radius, cone_half_angle, height",
                ));
            };
            let capsule = Capsule {
                heat_shield_radius: c.heat_shield_radius,
                diameter: c.diameter,
                shoulder_radius: c.shoulder_radius,
                cone_half_angle: c.cone_half_angle.to_radians(),
                height: c.height,
            };
            let scale = wall_transform(w).scale;
            capsule.surface(size / scale).ok_or_else(|| {
                loaded.error(
                    &format!("{key}.capsule"),
                    "these dimensions do not make a capsule (need 0 < shoulder_radius < diameter/2 < heat_shield_radius, 0 < cone_half_angle < 86 degrees, and a cone that stays open up to the height)",
                )
            })?
        }
        WallShape::Mesh => {
            let Some(file) = &w.file else {
                return Err(loaded.error(&format!("{key}.file"), "missing: an .stl or .obj file"));
            };
            let path = loaded.resolve(file);
            let lower = file.to_ascii_lowercase();
            let (polygons, normals): (Vec<Vec<DVec3>>, Option<Vec<DVec3>>) =
                if lower.ends_with(".obj") {
                    let p = read_obj(&path).map_err(|m| loaded.error(&format!("{key}.file"), m))?;
                    (p, None)
                } else if lower.ends_with(".stl") {
                    let facets = read_stl_facets(&path)
                        .map_err(|m| loaded.error(&format!("{key}.file"), m))?;
                    let normals = facets.iter().map(|f| f.1).collect();
                    (
                        facets.into_iter().map(|f| f.0.to_vec()).collect(),
                        Some(normals),
                    )
                } else {
                    return Err(loaded.error(
                        &format!("{key}.file"),
                        format!("expected an .stl or .obj file, found \"{file}\""),
                    ));
                };
            let mut size = 0.0f64;
            for p in polygons.iter().flatten() {
                size = size.max(p.abs().max_element());
            }
            Surface::from_polygons(&polygons, normals.as_deref(), 1e-9 * size.max(1e-300))
                .map_err(|e| loaded.error(&format!("{key}.file"), format!("{}: {e}", file)))?
        }
        other => return Err(bad(format!("\"{}\" is not a mesh wall", other.name()))),
    };
    surface
        .check_topology(closed)
        .map_err(|e| loaded.error(key, e.to_string()))?;
    let t = wall_transform(w);
    surface.map(|p| t.apply3(p));
    if surface.vertices.iter().any(|p| !p.is_finite()) {
        return Err(loaded.error(
            key,
            "the transformed mesh has a non-finite coordinate (check scale and units)",
        ));
    }
    if closed {
        let volume = surface.volume();
        if volume < 0.0 {
            surface.flip();
        }
        if w.fluid_outside() {
            surface.flip();
        }
    } else if w.shape.is_round() {
        // Generated with its normals out of the solid: a cylinder open at an end.
        if w.fluid_outside() {
            surface.flip();
        }
    } else if w.flip {
        surface.flip();
    }
    Ok(surface)
}

/// Boundary elements of a mesh or capsule wall, about `size` across, normals out of the fluid.
pub fn wall_elements(
    loaded: &LoadedCase,
    key: &str,
    w: &WallSpec,
    size: f64,
) -> Result<Vec<ElementShape<DVec3>>, CaseError> {
    let surface = wall_surface(loaded, key, w, size)?;
    checked_elements(&surface, size).map_err(|m| loaded.error(key, m))
}

/// The surface's elements of about `size`, refused (with the count) beyond
/// [`MAX_MESH_ELEMENTS`] or the memory available.
pub fn checked_elements(surface: &Surface, size: f64) -> Result<Vec<ElementShape<DVec3>>, String> {
    let count = surface.element_count(size);
    let bytes = count * crate::case::resources::bytes_per_element(3) as f64;
    let available = crate::case::resources::available_memory().map_or(f64::INFINITY, |b| b as f64);
    if !(count <= MAX_MESH_ELEMENTS && bytes <= available) {
        return Err(format!(
            "the mesh makes {count:.3e} boundary elements of size {size} (about {:.3} GiB; at most \
             {MAX_MESH_ELEMENTS:e}): check its units, scale and element_size",
            bytes / (1u64 << 30) as f64
        ));
    }
    Ok(surface.elements(size))
}
