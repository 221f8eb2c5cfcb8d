//! Unified semi-analytical walls (paper 3, sections 2-4 and 7): walls are segments between
//! vertex particles (paper 3, fig 1 and table 1). 2-D.
//!
//! Paper 3 orients normals **into** the fluid; this code keeps the project's convention
//! (element normals out of the fluid, [`super`]) and converts here:
//! `grad gamma_as = -n_s int_s W(|x_a - y|) dy` (paper 3, eq 9) points into the fluid.
//!
//! - `int_s W`: in closed form for the Wendland kernel, the segment clipped to the support
//!   circle first ([`crate::bi::segment::segment_kernel_integral`]).
//! - [`grad_gamma`]: `grad gamma_a = sum_s grad gamma_as` (eq 10).
//! - Integrated gamma (eq 4): `gamma^{n+1} = gamma^n + (grad gamma^n + grad gamma^{n+1})/2 .
//!   (r^{n+1} - r^n)` (trapezoidal line integral along the displacement, fixed walls), with the
//!   geometric gamma (paper 2) as the initial value ([`crate::simulation`] drives it).
//! - [`Vertices`]: the vertex particles; their pressure and density are extrapolated from the
//!   fluid (eqs 16-17, optionally with the hydrostatic corrections of section 7.2), segment
//!   values are the mean of their two vertices.
//! - [`UsawWalls`]: the wall model. With the fluid sums of [`crate::terms`] it gives the
//!   operators `Grad^{gamma,k}` and `Div^{gamma,k}` of eqs 37-38: the vertex particles join the
//!   volume sums, the segments add `-(rho_a^{2k} f_s + rho_s^{2k} f_a)/(rho_a^k rho_s^k)
//!   grad gamma_as` and `-(rho_s/rho_a)^k (B_s - B_a) . grad gamma_as`, and the whole is
//!   divided by `gamma_a`.
//! - [`relax_positions`], [`balance_positions`]: the particle start that fits these walls
//!   (`fill = "usaw"`): the lattice relaxed down the zero-order residual of the operators, then
//!   balanced at hydrostatic rest.
//!
//! The wall model is in `model.rs`, the fit of the fluid particles to it in `fit.rs`.

mod fit;
mod model;

pub use fit::{balance_positions, relax_positions, FitSetting, Relaxation};
pub use model::{grad_gamma, UsawWalls, Vertices, WallInterpolation};
