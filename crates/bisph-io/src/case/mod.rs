//! The case: its schema, reading it (with `--set` overrides), the checks, and building a
//! [`Simulation`](bisph_core::Simulation) from it (fluid blocks and their fill, walls from
//! shapes and meshes, bodies).

pub mod bodies;
pub mod build;
pub mod check;
pub mod dim;
pub mod error;
pub mod fill;
pub mod geometry_check;
pub mod load;
pub mod mesh_walls;
pub mod primitives;
pub mod regions;
pub mod resources;
pub mod schema;
pub mod wall_fill;
pub mod wall_region;

pub use build::build_simulation;
pub use check::check_case;
pub use dim::CaseDim;
pub use error::CaseError;
pub use load::{default_out_dir, load_case, parse_case, DEFAULT_CASE};
pub use schema::*;
