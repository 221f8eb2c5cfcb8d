//! What differs between 2-D and 3-D when building a case: regions, wall elements, lattices.

use crate::case::error::CaseError;
use crate::case::regions::BlockRegion;
use crate::case::schema::LoadedCase;
use crate::case::schema::{BlockShape, FluidBlock, WallShape, WallSpec};
use bisph_core::bi::ElementIntegrals as WallIntegrals;
use bisph_core::geometry::{self, ElementShape};
use bisph_core::Vector;
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

/// The elements of wall `k`, about `element_size` across, normals out of the fluid.
pub fn oriented_wall_shapes<V: CaseDim>(
    loaded: &LoadedCase,
    k: usize,
    element_size: f64,
) -> Result<Vec<ElementShape<V>>, CaseError> {
    let w = &loaded.case.wall[k];
    let mut shapes = V::wall_shapes(loaded, &format!("wall[{k}]"), w, element_size)?;
    if w.shape == WallShape::Box && w.fluid.as_deref() == Some("outside") {
        // A box obstacle or body: normals into the box, out of the fluid around it.
        for s in &mut shapes {
            s.normal = -s.normal;
            s.corners.reverse();
        }
    }
    Ok(shapes)
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
        crate::case::regions::region_2d(
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
        Ok(match wall.shape {
            WallShape::Box => {
                geometry::box_elements_2d(vec2(&wall.min), vec2(&wall.max), &wall.open, size)
            }
            WallShape::Polygon => geometry::polyline_elements(&points2(&wall.points), true, size),
            WallShape::Circle => crate::case::primitives::circle_elements(wall, size)
                .map_err(|m| loaded.error(key, m))?,
            _ => geometry::polyline_elements(&points2(&wall.points), false, size),
        })
    }
    fn fill(block: &FluidBlock, dx: f64) -> Vec<Self> {
        match block.shape {
            BlockShape::Box => geometry::lattice_box(vec2(&block.min), vec2(&block.max), dx),
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
        crate::case::regions::region_3d(
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
        match wall.shape {
            WallShape::Mesh | WallShape::Capsule | WallShape::Sphere | WallShape::Cylinder => {
                crate::case::mesh_walls::wall_elements(loaded, key, wall, size)
            }
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
