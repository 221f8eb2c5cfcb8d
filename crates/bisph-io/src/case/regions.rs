//! The region of a fluid block: its shape (box, polygon, polygon file, circle, STL, sphere,
//! cylinder) with the case's transform, minus its holes; boundary elements with normals out of the region, the
//! lattice of BIPI step 1, and a strict point-in-region test.

use crate::case::schema::LoadedCase;

use crate::case::error::CaseError;
use crate::case::primitives::{circle_loop, cylinder_triangles};
use crate::case::schema::{unit_factor, Angles, BlockShape, ShapeSpec};
use crate::formats::mesh_files::{read_polygon_file, read_stl, Transform};
use bisph_core::geometry::ElementShape;
use bisph_core::region::{PolygonRegion, TriMesh};
use glam::{DVec2, DVec3};

/// A block's region, ready to fill and pack.
pub struct BlockRegion<V> {
    /// Boundary elements, normals out of the region.
    pub elements: Vec<ElementShape<V>>,
    /// Lattice points strictly inside (BIPI step 1).
    pub lattice: Vec<V>,
    /// Area (2-D) or volume (3-D) of the region.
    pub measure: f64,
    inside: Box<dyn Fn(V) -> bool + Send + Sync>,
}

impl<V> BlockRegion<V> {
    /// A region from its boundary elements (normals out of it), the lattice points inside,
    /// its area or volume, and its inside test.
    pub fn new(
        elements: Vec<ElementShape<V>>,
        lattice: Vec<V>,
        measure: f64,
        inside: Box<dyn Fn(V) -> bool + Send + Sync>,
    ) -> Self {
        BlockRegion {
            elements,
            lattice,
            measure,
            inside,
        }
    }

    /// `true` when `p` lies strictly inside.
    pub fn contains(&self, p: V) -> bool {
        (self.inside)(p)
    }
}

/// The transform of a shape (units, scale, rotation, translation).
pub fn transform_of(s: &ShapeSpec) -> Transform {
    transform_from(&s.units, s.scale, &s.rotate, &s.translate)
}

/// The transform from a case's `units`, `scale`, `rotate` (degrees) and `translate`.
pub fn transform_from(
    units: &Option<String>,
    scale: Option<f64>,
    rotate: &Option<Angles>,
    translate: &Option<Vec<f64>>,
) -> Transform {
    let units = units.as_deref().and_then(unit_factor).unwrap_or(1.0);
    let mut angles = [0.0; 3];
    match rotate {
        Some(Angles::One(a)) => angles[0] = a.to_radians(),
        Some(Angles::Many(v)) => {
            for (k, a) in v.iter().take(3).enumerate() {
                angles[k] = a.to_radians();
            }
        }
        None => {}
    }
    let mut shift = [0.0; 3];
    for (k, t) in translate.iter().flatten().take(3).enumerate() {
        shift[k] = *t;
    }
    Transform {
        scale: units * scale.unwrap_or(1.0),
        angles,
        translate: shift,
    }
}

fn err(loaded: &LoadedCase, key: &str, message: String) -> CaseError {
    loaded.error(key, message)
}

/// The loops of a 2-D shape, transformed; a circle drawn with chords of about `chord` (after
/// the transform).
fn loops_of(
    loaded: &LoadedCase,
    key: &str,
    s: &ShapeSpec,
    chord: f64,
) -> Result<Vec<Vec<DVec2>>, CaseError> {
    let t = transform_of(s);
    let raw: Vec<Vec<DVec2>> = match s.shape {
        BlockShape::Box => {
            let lo = DVec2::from_slice(s.min.as_deref().unwrap_or(&[0.0, 0.0]));
            let hi = DVec2::from_slice(s.max.as_deref().unwrap_or(&[0.0, 0.0]));
            vec![vec![lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)]]
        }
        BlockShape::Polygon => vec![s
            .points
            .iter()
            .flatten()
            .map(|p| DVec2::from_slice(p))
            .collect()],
        BlockShape::PolygonFile => {
            let file = s.file.clone().unwrap_or_default();
            read_polygon_file(&loaded.resolve(&file))
                .map_err(|m| err(loaded, &format!("{key}.file"), m))?
        }
        BlockShape::Circle => {
            vec![circle_loop(s, chord / t.scale).map_err(|m| err(loaded, key, m))?]
        }
        other => {
            return Err(err(
                loaded,
                &format!("{key}.shape"),
                format!("\"{}\" is not a closed 2-D shape", other.name()),
            ))
        }
    };
    Ok(raw
        .into_iter()
        .map(|l| l.into_iter().map(|p| t.apply2(p)).collect())
        .collect())
}

/// The region of a 2-D block: its loops and its holes' loops (even-odd rule). Circles are
/// drawn with chords of `min(dx, element_size)`: the polygon of a circle wall of the same
/// centre and radius at that element size.
pub fn region_2d(
    loaded: &LoadedCase,
    key: &str,
    shape: &ShapeSpec,
    holes: &[ShapeSpec],
    dx: f64,
    element_size: f64,
) -> Result<BlockRegion<DVec2>, CaseError> {
    let chord = dx.min(element_size);
    let outer = loops_of(loaded, key, shape, chord)?;
    let outer_region = PolygonRegion::new(outer.clone())
        .map_err(|e| err(loaded, key, format!("bad polygon: {e}")))?;
    let mut loops = outer;
    for (m, h) in holes.iter().enumerate() {
        let hkey = format!("{key}.hole[{m}]");
        let hl = loops_of(loaded, &hkey, h, chord)?;
        for l in &hl {
            if let Some(p) = l.iter().find(|&&p| !outer_region.contains(p)) {
                return Err(err(
                    loaded,
                    &hkey,
                    format!(
                        "the hole must lie strictly inside the block; its vertex ({:.6}, {:.6}) does not",
                        p.x, p.y
                    ),
                ));
            }
        }
        loops.extend(hl);
    }
    let region = PolygonRegion::new(loops)
        .map_err(|e| err(loaded, key, format!("bad polygon (with its holes): {e}")))?;
    Ok(BlockRegion {
        elements: region.elements(element_size),
        lattice: region.lattice(dx),
        measure: region.area(),
        inside: Box::new(move |p| region.contains(p)),
    })
}

/// The closed mesh of a 3-D shape, transformed; a cylinder with faces of about `chord` (after
/// the transform).
fn mesh_of(
    loaded: &LoadedCase,
    key: &str,
    s: &ShapeSpec,
    dx: f64,
    chord: f64,
) -> Result<TriMesh, CaseError> {
    let t = transform_of(s);
    let soup: Vec<[DVec3; 3]> = match s.shape {
        BlockShape::Box => {
            let lo = DVec3::from_slice(s.min.as_deref().unwrap_or(&[0.0; 3]));
            let hi = DVec3::from_slice(s.max.as_deref().unwrap_or(&[0.0; 3]));
            let v = |i: usize| {
                DVec3::new(
                    if i & 1 == 1 { hi.x } else { lo.x },
                    if i & 2 == 2 { hi.y } else { lo.y },
                    if i & 4 == 4 { hi.z } else { lo.z },
                )
            };
            let faces = [
                [0, 4, 6, 2],
                [1, 3, 7, 5],
                [0, 1, 5, 4],
                [2, 6, 7, 3],
                [0, 2, 3, 1],
                [4, 5, 7, 6],
            ];
            faces
                .iter()
                .flat_map(|f| [[v(f[0]), v(f[1]), v(f[2])], [v(f[0]), v(f[2]), v(f[3])]])
                .collect()
        }
        BlockShape::Sphere => {
            let c = DVec3::from_slice(s.centre.as_deref().unwrap_or(&[0.0; 3]));
            let r = s.radius.unwrap_or(1.0);
            // Default: icosphere edges of about 2 dx (edge ~ 1.05 r / 2^n).
            let n = s.subdivisions.unwrap_or_else(|| {
                bisph_core::geometry::sphere_subdivisions(r * t.scale, 2.0 * dx).min(7)
            });
            let m = TriMesh::icosphere(c, r, n);
            (0..m.triangles.len()).map(|k| m.triangle(k)).collect()
        }
        BlockShape::Stl => {
            let file = s.file.clone().unwrap_or_default();
            read_stl(&loaded.resolve(&file)).map_err(|m| err(loaded, &format!("{key}.file"), m))?
        }
        BlockShape::Cylinder => {
            cylinder_triangles(s, chord / t.scale).map_err(|m| err(loaded, key, m))?
        }
        other => {
            return Err(err(
                loaded,
                &format!("{key}.shape"),
                format!("\"{}\" is not a closed 3-D shape", other.name()),
            ))
        }
    };
    let soup: Vec<[DVec3; 3]> = soup.iter().map(|tri| tri.map(|p| t.apply3(p))).collect();
    let (mut lo, mut hi) = (soup[0][0], soup[0][0]);
    for p in soup.iter().flatten() {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let weld = 1e-9 * (hi - lo).max_element();
    TriMesh::from_soup(&soup, weld).map_err(|e| err(loaded, key, format!("bad mesh: {e}")))
}

/// The region of a 3-D block: inside its mesh and outside every hole's mesh. Cylinders are
/// drawn with faces of about `min(dx, element_size)`, as a cylinder wall at that element size.
pub fn region_3d(
    loaded: &LoadedCase,
    key: &str,
    shape: &ShapeSpec,
    holes: &[ShapeSpec],
    dx: f64,
    element_size: f64,
) -> Result<BlockRegion<DVec3>, CaseError> {
    let chord = dx.min(element_size);
    let outer = mesh_of(loaded, key, shape, dx, chord)?;
    let mut hole_meshes = Vec::new();
    for (m, h) in holes.iter().enumerate() {
        let hkey = format!("{key}.hole[{m}]");
        let mesh = mesh_of(loaded, &hkey, h, dx, chord)?;
        if let Some(p) = mesh.vertices.iter().find(|&&p| !outer.contains(p)) {
            return Err(err(
                loaded,
                &hkey,
                format!(
                    "the hole must lie strictly inside the block; its vertex ({:.6}, {:.6}, {:.6}) does not",
                    p.x, p.y, p.z
                ),
            ));
        }
        hole_meshes.push(mesh);
    }
    let mut elements = outer.elements(element_size);
    let mut measure = outer.volume();
    for h in &hole_meshes {
        measure -= h.volume();
        elements.extend(h.elements(element_size).into_iter().map(|mut e| {
            e.normal = -e.normal;
            e.corners.reverse();
            e
        }));
    }
    let lattice: Vec<DVec3> = outer
        .lattice(dx)
        .into_iter()
        .filter(|&p| hole_meshes.iter().all(|h| !h.contains(p)))
        .collect();
    Ok(BlockRegion {
        elements,
        lattice,
        measure,
        inside: Box::new(move |p| outer.contains(p) && hole_meshes.iter().all(|h| !h.contains(p))),
    })
}
