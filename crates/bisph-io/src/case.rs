//! The case file: a TOML document describing one simulation.
//!
//! Parsing is strict: unknown keys, wrong types and missing values are errors that name the
//! file, the key and what was expected. `--set a.b=value` overrides any key before checking.

use serde::Deserialize;
use std::fmt;
use std::path::{Path, PathBuf};

/// An error in a case file: which file, which key, what was expected.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseError {
    /// The case file (or `<built-in>`).
    pub file: String,
    /// Dotted key path (empty when the whole file is at fault).
    pub key: String,
    /// What was wrong and what was expected.
    pub message: String,
}

impl fmt::Display for CaseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.key.is_empty() {
            write!(f, "{}: {}", self.file, self.message)
        } else {
            write!(f, "{}: key `{}`: {}", self.file, self.key, self.message)
        }
    }
}

impl std::error::Error for CaseError {}

/// Equation of state name.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum EosName {
    /// `p = p0 + c0^2 (rho - rho0)` (paper 1, eq 3).
    #[default]
    Linear,
    /// Tait (paper 3, eq 15).
    Tait,
}

/// Wall model name.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum BoundaryName {
    /// Energy-conserving boundary integrals (paper 1).
    #[default]
    Energy,
    /// Classic boundary integrals with discrete Shepard renormalisation (paper 1, eqs 24-25).
    Bi,
    /// Unified semi-analytical walls with vertex particles (paper 3), 2-D.
    Usaw,
}

/// Shepard factor name.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum ShepardName {
    /// `sum_j W_ij V_j` over the fluid (lowered by free surfaces too).
    Discrete,
    /// From the wall elements alone (paper 2). The default.
    #[default]
    Geometric,
    /// Integrated in time, `dgamma/dt = v_rel . grad gamma` (paper 3, eq 4).
    Integrated,
}

/// Density diffusion name.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum DiffusionName {
    /// delta-SPH with `fluid.delta`.
    #[default]
    Delta,
    /// Mayrhofer's volume diffusion (paper 3, eqs 44, 48) with `fluid.eta`.
    Mayrhofer,
    /// Ferrari's Riemann form (paper 3, eqs 49-51) times `fluid.ferrari_coefficient`.
    Ferrari,
}

/// Vertex-value extrapolation name (`usaw.wall_interpolation`).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum WallInterpolationName {
    /// Paper 3, eqs 16-17.
    #[default]
    Shepard,
    /// Neumann with gravity (`dp/dn = rho g . n`), the constraint of eq 82.
    Neumann,
    /// Hydrostatic-corrected, eq 83.
    Hydrostatic,
}

/// Gamma of the semi-analytical walls (`usaw.gamma`).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum UsawGammaName {
    /// Integrated in time (paper 3, eq 4) from the geometric value.
    #[default]
    Integrated,
    /// Geometric (paper 2) every step.
    Geometric,
}

/// `[usaw]`: options of the semi-analytical walls.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct UsawSection {
    /// Vertex pressure extrapolation.
    #[serde(default)]
    pub wall_interpolation: WallInterpolationName,
    /// How gamma is obtained.
    #[serde(default)]
    pub gamma: UsawGammaName,
    /// The power `k` of the operators (paper 3, eqs 37-38): 0 or 1.
    #[serde(default)]
    pub density_power: u8,
    /// `"differential"` (eq 12, default) or `"summation"` (eqs 13 and 84).
    #[serde(default)]
    pub continuity: ContinuityName,
    /// `true` (default): the wall terms carry negative pressures (walls pull in tension, as
    /// in paper 3); `false`: walls push but never pull (`max(p, 0)` in the wall terms).
    #[serde(default = "yes")]
    pub wall_tension: bool,
}

impl Default for UsawSection {
    fn default() -> Self {
        UsawSection {
            wall_interpolation: WallInterpolationName::default(),
            gamma: UsawGammaName::default(),
            density_power: 0,
            continuity: ContinuityName::default(),
            wall_tension: true,
        }
    }
}

/// Continuity equation of the semi-analytical walls (`usaw.continuity`).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum ContinuityName {
    /// `drho/dt = -rho Div^{gamma,k}(v)` (paper 3, eq 12).
    #[default]
    Differential,
    /// `gamma rho = sum_P m W` (eq 13) with the diffusion integrated in time (eq 84).
    Summation,
}

/// `[fluid]`: material and physics.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FluidSection {
    /// Reference density `rho0` [kg/m^d].
    pub density: f64,
    /// Speed of sound `c0` [m/s].
    pub sound_speed: f64,
    /// Equation of state.
    #[serde(default)]
    pub eos: EosName,
    /// Background pressure `p0` [Pa].
    #[serde(default)]
    pub background_pressure: f64,
    /// Tait exponent.
    #[serde(default = "default_tait_exponent")]
    pub tait_exponent: f64,
    /// Gravity vector [m/s^2] (`dim` components).
    #[serde(default)]
    pub gravity: Vec<f64>,
    /// delta-SPH coefficient (0 = off; default [`DEFAULT_BI_DELTA`] with `boundary = "bi"`,
    /// whose operators are not skew-adjoint and gain energy without diffusion, else 0).
    pub delta: Option<f64>,
    /// Hydrostatic correction of the density diffusion (delta-SPH, or paper 3 eq 81).
    #[serde(default = "yes")]
    pub delta_hydrostatic: bool,
    /// Kinematic viscosity `nu` [m^2/s] (0 = inviscid): the Morris Laplacian with the laminar
    /// wall shear (paper 3, eqs 18-20).
    #[serde(default)]
    pub viscosity: f64,
    /// Artificial viscosity `alpha` (Monaghan), applied through the same Laplacian as the
    /// laminar viscosity with the equivalent `nu = alpha h c0 / (2 (d + 2))`, its dissipation
    /// booked in `energy.csv` (default [`DEFAULT_BI_ALPHA`] with `boundary = "bi"`, else 0).
    pub artificial_viscosity: Option<f64>,
    /// Density diffusion form.
    #[serde(default)]
    pub diffusion: DiffusionName,
    /// `eta` of Mayrhofer's volume diffusion, `K = c0 dx / eta` (paper 3, eq 48).
    #[serde(default = "default_eta")]
    pub eta: f64,
    /// Multiplier of Ferrari's diffusion term.
    #[serde(default = "one")]
    pub ferrari_coefficient: f64,
}

/// The delta-SPH coefficient `boundary = "bi"` gets when `fluid.delta` is left out.
pub const DEFAULT_BI_DELTA: f64 = 0.1;

/// The artificial viscosity `boundary = "bi"` gets when `fluid.artificial_viscosity` is left
/// out: with it a tank at rest stays within 1% of `sqrt(g H)` (`bisph validate still-water`).
pub const DEFAULT_BI_ALPHA: f64 = 0.05;

impl Case {
    /// The delta-SPH coefficient in force: `fluid.delta`, or the wall model's default.
    pub fn delta(&self) -> f64 {
        self.fluid.delta.unwrap_or(match self.boundary {
            BoundaryName::Bi => DEFAULT_BI_DELTA,
            BoundaryName::Energy | BoundaryName::Usaw => 0.0,
        })
    }

    /// The artificial viscosity `alpha` in force: `fluid.artificial_viscosity`, or the wall
    /// model's default.
    pub fn artificial_viscosity(&self) -> f64 {
        self.fluid
            .artificial_viscosity
            .unwrap_or(match self.boundary {
                BoundaryName::Bi => DEFAULT_BI_ALPHA,
                BoundaryName::Energy | BoundaryName::Usaw => 0.0,
            })
    }

    /// The kinematic viscosity of the Laplacian [m^2/s]: `fluid.viscosity` plus the
    /// artificial viscosity's equivalent `alpha h c0 / (2 (d + 2))` (Monaghan 2005).
    pub fn kinematic_viscosity(&self) -> f64 {
        let h = self.resolution.h_over_dx * self.resolution.dx;
        let d = self.dim as f64;
        self.fluid.viscosity
            + self.artificial_viscosity() * h * self.fluid.sound_speed / (2.0 * (d + 2.0))
    }
}

/// `[flux]`: a driving body force imposing a volume flux (paper 3, section 5).
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FluxSection {
    /// Volume flux `Q` to impose [m^3/s, m^2/s in 2-D].
    pub flux: f64,
    /// Cross-section area `A` [m^2, m in 2-D]; the target bulk velocity is `Q / A`.
    pub area: f64,
    /// Flow direction (`dim` numbers; normalised).
    pub direction: Vec<f64>,
    /// A point on the measuring slice (default: the domain centre).
    pub slice_point: Option<Vec<f64>>,
    /// Slice width (default `2 dx`, as in the paper).
    pub slice_width: Option<f64>,
    /// `"eq63"` (paper 3, the default) or `"eq58"` (Violeau).
    #[serde(default)]
    pub rule: FluxRuleName,
}

/// Flux update rule name.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum FluxRuleName {
    /// Paper 3 eq 63.
    #[default]
    Eq63,
    /// Paper 3 eq 58.
    Eq58,
}

fn default_eta() -> f64 {
    50.0
}

fn default_tait_exponent() -> f64 {
    7.0
}
fn yes() -> bool {
    true
}

/// `[resolution]`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Resolution {
    /// Particle spacing `dx` [m].
    pub dx: f64,
    /// Smoothing length over spacing, `h / dx` (support `2h`).
    #[serde(default = "default_h_over_dx")]
    pub h_over_dx: f64,
    /// Boundary element size over `dx`.
    #[serde(default = "one")]
    pub element_over_dx: f64,
}

fn default_h_over_dx() -> f64 {
    2.0
}
fn one() -> f64 {
    1.0
}

/// `[time]`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TimeSection {
    /// End time [s].
    pub end: f64,
    /// Courant number.
    #[serde(default = "default_courant")]
    pub courant: f64,
    /// Fixed time step [s] (overrides the Courant rule).
    pub dt: Option<f64>,
    /// Smallest allowed time step [s]; the run stops below it (default 1e-6 of `h / c0`).
    pub min_dt: Option<f64>,
    /// `"verlet"` (explicit) or `"midpoint"` (semi-implicit, paper 1).
    #[serde(default)]
    pub integrator: IntegratorName,
    /// Skin of the explicit scheme's neighbour (Verlet) list as a fraction of the kernel
    /// support: candidates within `(1 + skin)` supports are kept across steps until a
    /// particle has moved half the skin (0 = search the cell grid at every step; default
    /// [`DEFAULT_NEIGHBOUR_SKIN`]).
    #[serde(default = "default_neighbour_skin")]
    pub neighbour_skin: f64,
}

/// Time integrator name.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum IntegratorName {
    /// Explicit velocity Verlet.
    #[default]
    Verlet,
    /// Semi-implicit midpoint (paper 1).
    Midpoint,
}

/// Energy a relative midpoint tolerance refers to.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum ToleranceReference {
    /// The tolerance is an absolute power.
    #[default]
    Absolute,
    /// Times the initial potential energy above the lowest particle.
    Potential,
    /// Times the initial kinetic energy.
    Kinetic,
    /// Times the initial compression energy.
    Compressible,
    /// Times an energy given in `reference_energy`.
    Given,
}

/// `[midpoint]`: the semi-implicit midpoint iterations.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MidpointSection {
    /// Most iterations per step.
    #[serde(default = "default_iterations")]
    pub max_iterations: u32,
    /// Residue tolerance (paper 1, eq 53), absolute or relative to `tolerance_reference`.
    #[serde(default)]
    pub tolerance: f64,
    /// What `tolerance` is relative to.
    #[serde(default)]
    pub tolerance_reference: ToleranceReference,
    /// The energy for `tolerance_reference = "given"`.
    pub reference_energy: Option<f64>,
    /// Geometric rate at which the residue must fall before relaxation grows.
    #[serde(default = "default_min_decrease")]
    pub min_decrease: f64,
    /// Relaxation increment.
    #[serde(default = "default_relax_increment")]
    pub relax_increment: f64,
    /// Relaxation at the start of each step.
    #[serde(default)]
    pub initial_relaxation: f64,
}

fn default_iterations() -> u32 {
    10
}
fn default_min_decrease() -> f64 {
    0.2
}
fn default_relax_increment() -> f64 {
    0.25
}

impl Default for MidpointSection {
    fn default() -> Self {
        MidpointSection {
            max_iterations: default_iterations(),
            tolerance: 0.0,
            tolerance_reference: ToleranceReference::Absolute,
            reference_energy: None,
            min_decrease: default_min_decrease(),
            relax_increment: default_relax_increment(),
            initial_relaxation: 0.0,
        }
    }
}

/// Default skin of the explicit scheme's neighbour list (`time.neighbour_skin`): between 0.05
/// and 0.1 the filtered candidates and the rebuilds balance on the dam break
/// (docs/performance.md); the larger one rebuilds less often in faster flows.
pub const DEFAULT_NEIGHBOUR_SKIN: f64 = 0.1;

fn default_neighbour_skin() -> f64 {
    DEFAULT_NEIGHBOUR_SKIN
}

fn default_courant() -> f64 {
    0.2
}

/// `[output]`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct OutputSection {
    /// Interval between VTK frames [s] (0 = none).
    #[serde(default)]
    pub vtk_interval: f64,
    /// Interval between rows of `energy.csv`, `forces.csv`, `probes.csv` [s] (0 = every step).
    #[serde(default)]
    pub series_interval: f64,
    /// Write PNG plots at the end.
    #[serde(default = "yes")]
    pub plots: bool,
}

impl Default for OutputSection {
    fn default() -> Self {
        OutputSection {
            vtk_interval: 0.0,
            series_interval: 0.0,
            plots: true,
        }
    }
}

/// `[checkpoint]`: when `bisph run` saves its state for `--resume` (also on SIGINT/SIGTERM).
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CheckpointSection {
    /// Write a checkpoint every this many steps (0 = not by steps).
    #[serde(default)]
    pub every_steps: u64,
    /// Write a checkpoint every this many wall-clock minutes (0 = not by time).
    #[serde(default = "default_checkpoint_minutes")]
    pub every_minutes: f64,
    /// Write a checkpoint when the run is interrupted by SIGINT or SIGTERM.
    #[serde(default = "yes")]
    pub on_signal: bool,
}

fn default_checkpoint_minutes() -> f64 {
    10.0
}

impl Default for CheckpointSection {
    fn default() -> Self {
        CheckpointSection {
            every_steps: 0,
            every_minutes: default_checkpoint_minutes(),
            on_signal: true,
        }
    }
}

/// `[diagnostics]`: divergence watches (see `bisph_io::diagnostics`).
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DiagnosticsSection {
    /// Watch at all.
    #[serde(default = "yes")]
    pub enabled: bool,
    /// Smallest allowed `rho / rho0`.
    #[serde(default = "default_density_ratio_min")]
    pub density_ratio_min: f64,
    /// Largest allowed `rho / rho0`.
    #[serde(default = "default_density_ratio_max")]
    pub density_ratio_max: f64,
    /// Largest allowed particle speed over `c0`.
    #[serde(default = "one")]
    pub speed_over_c0: f64,
    /// Smallest allowed time step over the first step's (0 = off).
    #[serde(default = "default_dt_collapse")]
    pub dt_collapse: f64,
    /// Stop when a particle crosses a wall element.
    #[serde(default = "yes")]
    pub wall_crossing: bool,
    /// Largest allowed growth of the total energy over `E_scale` (0 = off).
    #[serde(default = "default_energy_growth")]
    pub energy_growth: f64,
}

fn default_density_ratio_min() -> f64 {
    0.5
}
fn default_density_ratio_max() -> f64 {
    2.0
}
fn default_dt_collapse() -> f64 {
    1e-3
}
fn default_energy_growth() -> f64 {
    0.5
}

impl Default for DiagnosticsSection {
    fn default() -> Self {
        DiagnosticsSection {
            enabled: true,
            density_ratio_min: default_density_ratio_min(),
            density_ratio_max: default_density_ratio_max(),
            speed_over_c0: one(),
            dt_collapse: default_dt_collapse(),
            wall_crossing: true,
            energy_growth: default_energy_growth(),
        }
    }
}

/// `[domain]`: particles outside stop the run.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DomainSection {
    /// Lower corner.
    pub min: Vec<f64>,
    /// Upper corner.
    pub max: Vec<f64>,
    /// Periodic axes (`"x"`, `"y"`, `"z"`): the period along each is the domain's extent
    /// `max - min`; particles leaving one side come back on the other.
    #[serde(default)]
    pub periodic: Vec<String>,
}

impl DomainSection {
    /// Indices of the periodic axes (unknown names are rejected by `check_case`).
    pub fn periodic_axes(&self) -> Vec<usize> {
        self.periodic
            .iter()
            .filter_map(|a| ["x", "y", "z"].iter().position(|n| n == a))
            .collect()
    }
}

/// Initial pressure of a fluid block: `"hydrostatic"` or a number [Pa].
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum InitialPressure {
    /// A uniform value.
    Value(f64),
    /// `"hydrostatic"`.
    Named(String),
}

/// `[[fluid_block]]`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FluidBlock {
    /// `"box"`, `"polygon"` (2-D), `"polygon_file"` (2-D), `"stl"` (3-D), `"sphere"` (3-D,
    /// a generated closed mesh) or `"particles"` (positions from a CSV file).
    pub shape: String,
    /// Box lower corner.
    pub min: Option<Vec<f64>>,
    /// Box upper corner.
    pub max: Option<Vec<f64>>,
    /// Polygon vertices.
    pub points: Option<Vec<Vec<f64>>>,
    /// Geometry or particle file, relative to the case file's folder.
    pub file: Option<String>,
    /// Sphere centre.
    pub centre: Option<Vec<f64>>,
    /// Sphere radius.
    pub radius: Option<f64>,
    /// Sphere mesh refinement (icosahedron subdivisions; default: edges of about `dx`).
    pub subdivisions: Option<u32>,
    /// Length unit of the file or points: `"m"` (default), `"cm"` or `"mm"`.
    pub units: Option<String>,
    /// Uniform scale applied to the geometry (after units).
    pub scale: Option<f64>,
    /// Rotation in degrees (2-D: one angle; 3-D: about x, then y, then z), after scaling.
    pub rotate: Option<Angles>,
    /// Translation, applied last.
    pub translate: Option<Vec<f64>>,
    /// Regions cut out of the block (e.g. an airfoil in a box).
    #[serde(default)]
    pub hole: Vec<ShapeSpec>,
    /// `"lattice"` (default), `"bipi"`: pack the block with BIPI before running, or `"usaw"`
    /// (2-D, `boundary = "usaw"`): relax the lattice so that the usaw operators' zero-order
    /// residual (vertex particles included) vanishes and, under gravity, so that still water
    /// is at rest (`bisph_core::walls::usaw::relax_positions`, `balance_positions`).
    pub fill: Option<String>,
    /// Particle spacing of this block (default `resolution.dx`).
    pub dx: Option<f64>,
    /// Particles of a solid body: packed by `bisph pack`, not run as fluid.
    #[serde(default)]
    pub solid: bool,
    /// Initial velocity.
    pub velocity: Option<Vec<f64>>,
    /// Initial pressure (default: hydrostatic under gravity, else zero): a number,
    /// `"hydrostatic"` (`rho0 g d` at depth `d`) or `"hydrostatic-eos"` (the exact profile of
    /// the equation of state, `dp/dd = rho(p) g`, for a fluid that starts compressed in
    /// equilibrium; use it with `mass = "initial"`).
    pub pressure: Option<InitialPressure>,
    /// Free-surface level along `-g` for the hydrostatic pressure (default: top of the block).
    pub surface: Option<f64>,
    /// Multiplies the hydrostatic part of the initial pressure by
    /// `cos(pi/2 (r_axis - start) / length)` (the Lobovsky initial condition: hydrostatic at
    /// the back wall, zero at the dam face).
    pub pressure_taper: Option<TaperSpec>,
    /// Particle masses: `"reference"` (`rho0 dx^d`, default) or `"initial"` (`rho dx^d` with
    /// the initial density, for a fluid that starts compressed). With `boundary = "usaw"` and
    /// every block `"initial"`, the vertex particles' masses follow: `rho_v V_v` with their
    /// initial extrapolated densities.
    #[serde(default)]
    pub mass: MassRule,
}

/// `pressure_taper` of a fluid block.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TaperSpec {
    /// Axis index (0 = x, 1 = y, 2 = z).
    pub axis: usize,
    /// Where the taper factor is 1.
    pub start: f64,
    /// Distance over which it falls to 0.
    pub length: f64,
}

/// How particle masses are set.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum MassRule {
    /// `rho0 dx^d`.
    #[default]
    Reference,
    /// `rho_i dx^d` with the initial density.
    Initial,
}

/// Rotation angles in degrees: one number (2-D) or a list.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum Angles {
    /// One angle.
    One(f64),
    /// Angles about x, y, z (3-D) or a one-element list (2-D).
    Many(Vec<f64>),
}

/// `[[fluid_block.hole]]`: a shape, as in a fluid block.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct ShapeSpec {
    /// `"box"`, `"polygon"`, `"polygon_file"`, `"stl"` or `"sphere"`.
    pub shape: String,
    /// Box lower corner.
    pub min: Option<Vec<f64>>,
    /// Box upper corner.
    pub max: Option<Vec<f64>>,
    /// Polygon vertices.
    pub points: Option<Vec<Vec<f64>>>,
    /// Geometry file, relative to the case file's folder.
    pub file: Option<String>,
    /// Sphere centre.
    pub centre: Option<Vec<f64>>,
    /// Sphere radius.
    pub radius: Option<f64>,
    /// Sphere mesh refinement.
    pub subdivisions: Option<u32>,
    /// `"m"`, `"cm"` or `"mm"`.
    pub units: Option<String>,
    /// Uniform scale.
    pub scale: Option<f64>,
    /// Rotation in degrees.
    pub rotate: Option<Angles>,
    /// Translation.
    pub translate: Option<Vec<f64>>,
}

impl FluidBlock {
    /// The block's own shape (without its holes).
    pub fn shape_spec(&self) -> ShapeSpec {
        ShapeSpec {
            shape: self.shape.clone(),
            min: self.min.clone(),
            max: self.max.clone(),
            points: self.points.clone(),
            file: self.file.clone(),
            centre: self.centre.clone(),
            radius: self.radius,
            subdivisions: self.subdivisions,
            units: self.units.clone(),
            scale: self.scale,
            rotate: self.rotate.clone(),
            translate: self.translate.clone(),
        }
    }

    /// `true` when the block asks to be packed with BIPI.
    pub fn bipi(&self) -> bool {
        self.fill.as_deref() == Some("bipi")
    }
}

/// `[pack]`: BIPI parameters (paper 4); lengths in units of the block's `dx`.
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct PackSection {
    /// `D / h^2` of the shift (0.5).
    pub diffusion: Option<f64>,
    /// Largest shift per iteration (0.25).
    pub max_shift: Option<f64>,
    /// Radius of the boundary push (default: the relaxed balance distance in 2-D, 0.472 at
    /// h = 2 dx; the balanced radius in 3-D, 0.62 at h = 2 dx; see
    /// `bisph_core::packing::default_push_radius`).
    pub push_radius: Option<f64>,
    /// Most iterations of stage 2a (10000).
    pub stage_a_max: Option<usize>,
    /// TPD plateau window (100 iterations).
    pub plateau_window: Option<usize>,
    /// TPD plateau relative change (0.01).
    pub plateau_tolerance: Option<f64>,
    /// Stage 2b freezes particles closer than this to a wall (0.6).
    pub freeze_distance: Option<f64>,
    /// Iterations of stage 2c (1000).
    pub stage_c_iterations: Option<usize>,
    /// Early stop of stage 2c on mean |grad C| (0: off).
    pub stage_c_tolerance: Option<f64>,
    /// Step factor applied when a particle's shift reverses (0.5; 1: off, plain eq 15).
    pub step_damping: Option<f64>,
    /// Metrics over all particles every this many iterations in stage 2a (10).
    pub report_interval: Option<usize>,
}

/// `[[wall]]`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct WallSpec {
    /// `"box"`, `"polyline"` or `"polygon"` (2-D); `"mesh"` (an STL or OBJ file) or
    /// `"capsule"` (3-D).
    pub shape: String,
    /// Mesh file (`.stl`, binary or ASCII, or `.obj`), relative to the case file's folder.
    pub file: Option<String>,
    /// Length unit of the mesh file: `"m"` (default), `"cm"` or `"mm"`.
    pub units: Option<String>,
    /// Uniform scale of a mesh or capsule (after units).
    pub scale: Option<f64>,
    /// Rotation of a mesh or capsule in degrees, about x, then y, then z (after scaling).
    pub rotate: Option<Angles>,
    /// Translation of a mesh or capsule, applied last.
    pub translate: Option<Vec<f64>>,
    /// Which side of a closed mesh the fluid is on: `"inside"` (a tank, default) or
    /// `"outside"` (an obstacle or a floating body). Closed meshes are oriented automatically.
    pub fluid: Option<String>,
    /// A mesh must be closed (every edge shared by two faces; default `true`). An open mesh
    /// (e.g. a tank without a lid) keeps the normals of its corner order, flipped with `flip`.
    pub closed: Option<bool>,
    /// Flip the normals of an open mesh.
    #[serde(default)]
    pub flip: bool,
    /// Dimensions of a `"capsule"` wall.
    pub capsule: Option<CapsuleSpec>,
    /// Size of this wall's elements (default `resolution.dx * resolution.element_over_dx`),
    /// e.g. a finely meshed body in a coarse tank.
    pub element_size: Option<f64>,
    /// Box lower corner.
    pub min: Option<Vec<f64>>,
    /// Box upper corner.
    pub max: Option<Vec<f64>>,
    /// Box sides left open (`"-x"`, `"+x"`, `"-y"`, `"+y"`, `"-z"`, `"+z"`).
    #[serde(default)]
    pub open: Vec<String>,
    /// Polyline / polygon vertices; the fluid lies on their left.
    pub points: Option<Vec<Vec<f64>>>,
    /// Owning body (default: the fixed walls).
    pub body: Option<String>,
    /// Stretch with a piston (the wall must lie along the piston axis).
    pub stretch: Option<StretchSpec>,
}

/// `capsule` of a `[[wall]]`: an Apollo-like capsule (paper 1, 5.4), axis `+z`, heat-shield
/// apex at the origin before the wall's transform.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CapsuleSpec {
    /// Radius of the spherical heat shield [m].
    pub heat_shield_radius: f64,
    /// Largest diameter [m].
    pub diameter: f64,
    /// Radius of the toroidal shoulder [m].
    pub shoulder_radius: f64,
    /// Half-angle of the conical afterbody [degrees].
    pub cone_half_angle: f64,
    /// Height from the heat-shield apex to the top [m].
    pub height: f64,
}

/// `[body.motion]`: prescribed motion (see `PrescribedMotion`).
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct MotionSpec {
    /// Constant velocity.
    pub velocity: Option<Vec<f64>>,
    /// Oscillation amplitude.
    pub amplitude: Option<Vec<f64>>,
    /// Oscillation frequency [Hz].
    #[serde(default)]
    pub frequency: f64,
    /// Oscillation phase [rad].
    #[serde(default)]
    pub phase: f64,
    /// Rotation axis (3-D).
    pub axis: Option<Vec<f64>>,
    /// Constant angular velocity [rad/s].
    #[serde(default)]
    pub angular_velocity: f64,
    /// Angular oscillation amplitude [rad].
    #[serde(default)]
    pub angular_amplitude: f64,
    /// Angular oscillation frequency [Hz].
    #[serde(default)]
    pub angular_frequency: f64,
}

/// `[body.piston]`: a wall sliding along its outward normal, driven by the fluid.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PistonSpec {
    /// Axis of motion (normalised), pointing out of the fluid.
    pub axis: Vec<f64>,
    /// Mass (per unit depth in 2-D).
    pub mass: f64,
    /// Outside pressure pushing the piston into the fluid.
    #[serde(default)]
    pub outside_pressure: f64,
    /// Initial velocity along the axis.
    #[serde(default)]
    pub initial_velocity: f64,
}

/// `[[body]]`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Name (referred to by walls, used in `forces.csv`).
    pub name: String,
    /// Reference point (centre of rotation and moments).
    pub centre: Option<Vec<f64>>,
    /// Prescribed motion (none: fixed).
    pub motion: Option<MotionSpec>,
    /// Piston dynamics (instead of a prescribed motion).
    pub piston: Option<PistonSpec>,
    /// Free rigid-body dynamics (instead of a prescribed motion or a piston).
    pub free: Option<FreeSpec>,
}

/// `[body.free]`: a free rigid body driven by the fluid and gravity. `body.centre` is its
/// centre of mass (computed from its closed mesh walls when left out).
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct FreeSpec {
    /// Mass [kg] (per unit depth in 2-D). With `density` instead, computed from the body's
    /// closed mesh walls.
    pub mass: Option<f64>,
    /// Uniform density of the solid, for mass and inertia from the body's closed mesh walls.
    pub density: Option<f64>,
    /// Inertia about the centre of mass in body axes: 3 principal moments, or 9 numbers
    /// (row by row) in 3-D; 1 number (`I_zz`) in 2-D. Left out: from the mesh walls
    /// (uniform density).
    pub inertia: Option<Vec<f64>>,
    /// Body axes at time zero: rotation in degrees about x, then y, then z (3-D) or one angle
    /// (2-D) from the world axes.
    pub rotate: Option<Angles>,
    /// Initial velocity of the centre of mass.
    pub velocity: Option<Vec<f64>>,
    /// Initial angular velocity in body axes (3-D) or about z (2-D, one number).
    pub angular_velocity: Option<Vec<f64>>,
    /// Locked translations (world axes: "x", "y", "z"); they keep their initial velocity.
    #[serde(default)]
    pub lock_translation: Vec<String>,
    /// Locked rotations (body axes: "x", "y", "z"); they keep their initial rate.
    #[serde(default)]
    pub lock_rotation: Vec<String>,
    /// `"iterated"` (default: inside the midpoint iterations) or `"staggered"`.
    pub coupling: Option<String>,
}

/// `stretch` of a `[[wall]]`: the wall stretches with a piston between a fixed anchor and the
/// piston face.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StretchSpec {
    /// The piston body.
    pub body: String,
    /// The fixed end, as a coordinate along the piston axis.
    pub anchor: f64,
}

/// `[[probe]]`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ProbeSpec {
    /// Column name.
    pub name: String,
    /// `"pressure"` (fluid, Shepard-normalised), `"wall_pressure"` (`2 sum p W V`) or
    /// `"height"` (water height of the vertical column through the position).
    pub kind: String,
    /// Position.
    pub position: Vec<f64>,
}

/// A whole case file.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// Case name.
    pub name: String,
    /// Dimension, 2 or 3.
    pub dim: u32,
    /// Wall model.
    #[serde(default)]
    pub boundary: BoundaryName,
    /// Shepard factor of the `bi` walls: `"geometric"` (default), `"discrete"` or
    /// `"integrated"`.
    #[serde(default)]
    pub shepard: ShepardName,
    /// Options of the semi-analytical walls (`boundary = "usaw"`).
    #[serde(default)]
    pub usaw: UsawSection,
    /// Reflect particles about to cross a wall (energy-neutral on fixed walls).
    #[serde(default = "yes")]
    pub elastic_bounce: bool,
    /// Material and physics.
    pub fluid: FluidSection,
    /// Resolution.
    pub resolution: Resolution,
    /// Time stepping.
    pub time: TimeSection,
    /// Midpoint iterations (with `time.integrator = "midpoint"`).
    #[serde(default)]
    pub midpoint: MidpointSection,
    /// Outputs.
    #[serde(default)]
    pub output: OutputSection,
    /// Checkpoints.
    #[serde(default)]
    pub checkpoint: CheckpointSection,
    /// Divergence watches.
    #[serde(default)]
    pub diagnostics: DiagnosticsSection,
    /// Domain.
    pub domain: Option<DomainSection>,
    /// Flux-driven forcing.
    pub flux: Option<FluxSection>,
    /// Fluid blocks.
    #[serde(default)]
    pub fluid_block: Vec<FluidBlock>,
    /// Walls.
    #[serde(default)]
    pub wall: Vec<WallSpec>,
    /// Moving bodies.
    #[serde(default)]
    pub body: Vec<BodySpec>,
    /// Probes.
    #[serde(default)]
    pub probe: Vec<ProbeSpec>,
    /// BIPI packing parameters.
    #[serde(default)]
    pub pack: PackSection,
    /// Settling of a resting start before `t = 0`.
    #[serde(default)]
    pub settle: SettleSection,
}

/// `[settle]`: settle fluid that starts at rest into a discrete equilibrium of the case's own
/// operators before `t = 0` ([`bisph_core::simulation::SettleParams`]).
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct SettleSection {
    /// Settle before the run (fluid at rest under gravity, walls fixed).
    #[serde(default)]
    pub enabled: bool,
    /// Damping rate `beta` [1/s] (default: twice the lowest sloshing frequency of the fluid,
    /// `2 sqrt(g k tanh(k H))` with `k = pi / L`, `L` and `H` its width and depth).
    pub damping: Option<f64>,
    /// At rest when speeds are below `tolerance sqrt(g H)` and accelerations below
    /// `tolerance sqrt(g H) beta` (default 1e-3).
    pub tolerance: Option<f64>,
    /// Most settling time [s] (default `50 / beta`).
    pub max_time: Option<f64>,
}

/// The built-in default case: the 2-D dam break (`cases/dam-break-2d.toml`).
pub const DEFAULT_CASE: &str = include_str!("../../../cases/dam-break-2d.toml");

/// A parsed case and where it came from.
#[derive(Debug, Clone)]
pub struct LoadedCase {
    /// The case.
    pub case: Case,
    /// Its file (or `<built-in>`).
    pub source: String,
    /// The TOML text after overrides (copied to the output directory).
    pub text: String,
}

impl LoadedCase {
    /// A path named in the case, resolved against the case file's folder.
    pub fn resolve(&self, file: &str) -> PathBuf {
        let p = Path::new(file);
        if p.is_absolute() {
            return p.to_path_buf();
        }
        match Path::new(&self.source).parent() {
            Some(dir) if !self.source.starts_with('<') => dir.join(p),
            _ => p.to_path_buf(),
        }
    }

    /// A key error for this case.
    pub fn error(&self, key: &str, message: impl Into<String>) -> CaseError {
        CaseError {
            file: self.source.clone(),
            key: key.to_string(),
            message: message.into(),
        }
    }
}

/// Reads a case file (or the built-in default with `None`) and applies `key=value` overrides.
pub fn load_case(path: Option<&Path>, overrides: &[String]) -> Result<LoadedCase, CaseError> {
    let (source, text) = match path {
        Some(p) => {
            let source = p.display().to_string();
            let text = std::fs::read_to_string(p).map_err(|e| CaseError {
                file: source.clone(),
                key: String::new(),
                message: format!("cannot read the case file: {e}"),
            })?;
            (source, text)
        }
        None => (
            "<built-in dam-break-2d>".to_string(),
            DEFAULT_CASE.to_string(),
        ),
    };
    parse_case(&source, &text, overrides)
}

/// Parses case text, applies overrides, checks it.
pub fn parse_case(source: &str, text: &str, overrides: &[String]) -> Result<LoadedCase, CaseError> {
    let err = |key: &str, message: String| CaseError {
        file: source.to_string(),
        key: key.to_string(),
        message,
    };
    let mut doc: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| err("", format!("not valid TOML: {}", e.message())))?;
    for item in overrides {
        let Some((key, value)) = item.split_once('=') else {
            return Err(err(
                item,
                "an override must read key=value (e.g. resolution.dx=0.01)".into(),
            ));
        };
        let value = parse_override_value(value.trim());
        set_dotted(&mut doc, key.trim(), value).map_err(|m| err(key.trim(), m))?;
    }
    let text =
        toml::to_string(&doc).map_err(|e| err("", format!("cannot re-serialise the case: {e}")))?;
    let case: Case = toml::from_str(&text).map_err(|e| {
        let span_key = key_of_error(&text, &e);
        err(&span_key, e.message().to_string())
    })?;
    let loaded = LoadedCase {
        case,
        source: source.to_string(),
        text,
    };
    check_case(&loaded)?;
    Ok(loaded)
}

/// An override value: TOML if it parses as one (number, bool, array), else a string.
fn parse_override_value(raw: &str) -> toml::Value {
    let wrapped = format!("v = {raw}");
    match wrapped.parse::<toml::Table>() {
        Ok(mut t) => t
            .remove("v")
            .unwrap_or(toml::Value::String(raw.to_string())),
        Err(_) => toml::Value::String(raw.to_string()),
    }
}

/// Sets `a.b.c` (array entries by index, `fluid_block.0.min`) in a TOML table.
fn set_dotted(doc: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), String> {
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err("an empty segment in the dotted key".into());
    }
    let mut node = doc
        .entry(parts[0].to_string())
        .or_insert_with(|| toml::Value::Table(toml::Table::new()));
    if parts.len() == 1 {
        *node = value;
        return Ok(());
    }
    for (depth, part) in parts.iter().enumerate().skip(1) {
        let last = depth == parts.len() - 1;
        node = match node {
            toml::Value::Table(t) => {
                if last {
                    t.insert(part.to_string(), value);
                    return Ok(());
                }
                t.entry(part.to_string())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            }
            toml::Value::Array(a) => {
                let index: usize = part
                    .parse()
                    .map_err(|_| format!("`{part}` should be an index into a list"))?;
                let len = a.len();
                let slot = a
                    .get_mut(index)
                    .ok_or_else(|| format!("index {index} is past the list's {len} entries"))?;
                if last {
                    *slot = value;
                    return Ok(());
                }
                slot
            }
            _ => return Err(format!("`{}` is not a table", parts[..depth].join("."))),
        };
    }
    Ok(())
}

/// The dotted key at the error's span, found from the TOML text (best effort).
fn key_of_error(text: &str, e: &toml::de::Error) -> String {
    let Some(span) = e.span() else {
        return String::new();
    };
    let before = &text[..span.start.min(text.len())];
    let mut table = String::new();
    let mut index: std::collections::HashMap<String, usize> = Default::default();
    for line in before.lines() {
        let l = line.trim();
        if let Some(name) = l.strip_prefix("[[").and_then(|s| s.strip_suffix("]]")) {
            let n = index
                .entry(name.to_string())
                .and_modify(|n| *n += 1)
                .or_insert(0);
            table = format!("{name}[{n}]");
        } else if let Some(name) = l.strip_prefix('[').and_then(|s| s.strip_suffix(']')) {
            table = name.to_string();
        }
    }
    let line_start = before.rfind('\n').map_or(0, |k| k + 1);
    let line = text[line_start..].lines().next().unwrap_or("");
    let key = line
        .split('=')
        .next()
        .unwrap_or("")
        .trim()
        .trim_matches('"');
    let key = if key.starts_with('[') { "" } else { key };
    match (table.is_empty(), key.is_empty()) {
        (true, _) => key.to_string(),
        (false, true) => table,
        (false, false) => format!("{table}.{key}"),
    }
}

/// Checks values for physical sense and consistency; errors name the key and the allowed range.
pub fn check_case(loaded: &LoadedCase) -> Result<(), CaseError> {
    let c = &loaded.case;
    let e = |key: &str, msg: String| Err(loaded.error(key, msg));
    if c.dim != 2 && c.dim != 3 {
        return e("dim", format!("expected 2 or 3, found {}", c.dim));
    }
    let d = c.dim as usize;
    let positive = |key: &str, v: f64| -> Result<(), CaseError> {
        if v > 0.0 && v.is_finite() {
            Ok(())
        } else {
            Err(loaded.error(key, format!("expected a positive number, found {v}")))
        }
    };
    positive("fluid.density", c.fluid.density)?;
    positive("fluid.sound_speed", c.fluid.sound_speed)?;
    positive("resolution.dx", c.resolution.dx)?;
    positive("time.end", c.time.end)?;
    positive("resolution.element_over_dx", c.resolution.element_over_dx)?;
    if c.fluid.tait_exponent.is_nan() || c.fluid.tait_exponent <= 1.0 {
        return e(
            "fluid.tait_exponent",
            format!("expected a number above 1, found {}", c.fluid.tait_exponent),
        );
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
            return e(
                "resolution.dx",
                format!(
                    "expected dx at most the domain's extent {w} in direction {k}, found {}",
                    c.resolution.dx
                ),
            );
        }
    }
    if !(1.0..=4.0).contains(&c.resolution.h_over_dx) {
        return e(
            "resolution.h_over_dx",
            format!(
                "expected a value in [1, 4], found {}",
                c.resolution.h_over_dx
            ),
        );
    }
    if !(c.time.neighbour_skin >= 0.0 && c.time.neighbour_skin <= 1.0) {
        return e(
            "time.neighbour_skin",
            format!(
                "expected a fraction of the kernel support in [0, 1], found {}",
                c.time.neighbour_skin
            ),
        );
    }
    if !(c.time.courant > 0.0 && c.time.courant <= 1.0) {
        return e(
            "time.courant",
            format!("expected a value in (0, 1], found {}", c.time.courant),
        );
    }
    if let Some(dt) = c.time.dt {
        positive("time.dt", dt)?;
    }
    if let Some(dt) = c.time.min_dt {
        positive("time.min_dt", dt)?;
    }
    let mp = &c.midpoint;
    if mp.max_iterations == 0 || mp.max_iterations > 1000 {
        return e(
            "midpoint.max_iterations",
            format!("expected 1 to 1000, found {}", mp.max_iterations),
        );
    }
    if mp.tolerance.is_nan() || mp.tolerance < 0.0 {
        return e(
            "midpoint.tolerance",
            format!("expected zero or a positive number, found {}", mp.tolerance),
        );
    }
    for (key, v) in [
        ("midpoint.min_decrease", mp.min_decrease),
        ("midpoint.relax_increment", mp.relax_increment),
        ("midpoint.initial_relaxation", mp.initial_relaxation),
    ] {
        if !(0.0..1.0).contains(&v) {
            return e(key, format!("expected a value in [0, 1), found {v}"));
        }
    }
    if mp.tolerance_reference == ToleranceReference::Given && mp.reference_energy.is_none() {
        return e(
            "midpoint.reference_energy",
            "missing: needed by tolerance_reference = \"given\"".into(),
        );
    }
    if !(c.delta() >= 0.0 && c.delta() <= 1.0) {
        return e(
            "fluid.delta",
            format!("expected a value in [0, 1], found {}", c.delta()),
        );
    }
    if !(c.artificial_viscosity() >= 0.0 && c.artificial_viscosity() <= 1.0) {
        return e(
            "fluid.artificial_viscosity",
            format!(
                "expected a value in [0, 1], found {}",
                c.artificial_viscosity()
            ),
        );
    }
    if !(c.fluid.viscosity >= 0.0 && c.fluid.viscosity.is_finite()) {
        return e(
            "fluid.viscosity",
            format!(
                "expected zero or a positive kinematic viscosity, found {}",
                c.fluid.viscosity
            ),
        );
    }
    if let Some(f) = &c.flux {
        if !f.flux.is_finite() {
            return e("flux.flux", "expected a finite number".into());
        }
        positive("flux.area", f.area)?;
        vector(loaded, "flux.direction", &f.direction, d)?;
        if f.direction.iter().all(|x| *x == 0.0) {
            return e("flux.direction", "expected a non-zero vector".into());
        }
        if let Some(p) = &f.slice_point {
            vector(loaded, "flux.slice_point", p, d)?;
        }
        if let Some(w) = f.slice_width {
            positive("flux.slice_width", w)?;
        }
        if c.domain.as_ref().is_none_or(|dom| dom.periodic.is_empty()) {
            return e(
                "flux",
                "a flux-driven flow needs a periodic [domain] (domain.periodic)".into(),
            );
        }
    }
    if !(c.fluid.eta.is_finite() && c.fluid.eta > 0.0) {
        return e(
            "fluid.eta",
            format!("expected a positive number, found {}", c.fluid.eta),
        );
    }
    if !(c.fluid.ferrari_coefficient.is_finite() && c.fluid.ferrari_coefficient >= 0.0) {
        return e(
            "fluid.ferrari_coefficient",
            format!(
                "expected zero or a positive number, found {}",
                c.fluid.ferrari_coefficient
            ),
        );
    }
    if c.usaw.density_power > 1 {
        return e(
            "usaw.density_power",
            format!("expected 0 or 1, found {}", c.usaw.density_power),
        );
    }
    let integrated = c.boundary == BoundaryName::Usaw && c.usaw.gamma == UsawGammaName::Integrated
        || c.boundary == BoundaryName::Bi && c.shepard == ShepardName::Integrated;
    if c.boundary == BoundaryName::Usaw
        && c.usaw.continuity == ContinuityName::Summation
        && c.time.integrator != IntegratorName::Verlet
    {
        return e(
            "usaw.continuity",
            "\"summation\" needs time.integrator = \"verlet\"".into(),
        );
    }
    if c.boundary == BoundaryName::Usaw && c.dim != 2 {
        return e(
            "boundary",
            format!("\"usaw\" walls are 2-D only, found dim = {}", c.dim),
        );
    }
    if c.shepard == ShepardName::Integrated && c.dim != 2 {
        return e(
            "shepard",
            format!("\"integrated\" gamma is 2-D only, found dim = {}", c.dim),
        );
    }
    let moving = |b: &BodySpec| b.motion.is_some() || b.piston.is_some() || b.free.is_some();
    if integrated && c.body.iter().any(moving) {
        return e(
            "body",
            "the integrated gamma (paper 3, eq 4) is built for fixed walls: use usaw.gamma = \"geometric\" or shepard = \"geometric\" with moving bodies".into(),
        );
    }
    if !c.fluid.background_pressure.is_finite() {
        return e(
            "fluid.background_pressure",
            "expected a finite number".into(),
        );
    }
    if !c.fluid.gravity.is_empty() {
        vector(loaded, "fluid.gravity", &c.fluid.gravity, d)?;
    }
    if c.output.vtk_interval < 0.0 || c.output.series_interval < 0.0 {
        return e("output", "intervals must be zero or positive".into());
    }
    if c.fluid_block.is_empty() {
        return e(
            "fluid_block",
            "expected at least one [[fluid_block]]: the case has no fluid".into(),
        );
    }
    for (k, b) in c.fluid_block.iter().enumerate() {
        let key = format!("fluid_block[{k}]");
        check_shape(loaded, &key, &b.shape_spec(), d, true)?;
        for (m, hole) in b.hole.iter().enumerate() {
            let hkey = format!("{key}.hole[{m}]");
            if hole.shape == "particles" {
                return e(
                    &format!("{hkey}.shape"),
                    "a hole must be a shape, not \"particles\"".into(),
                );
            }
            check_shape(loaded, &hkey, hole, d, false)?;
        }
        if let Some(fill) = &b.fill {
            if fill != "lattice" && fill != "bipi" && fill != "usaw" {
                return e(
                    &format!("{key}.fill"),
                    format!("expected \"lattice\", \"bipi\" or \"usaw\", found \"{fill}\""),
                );
            }
            if fill == "usaw"
                && (c.boundary != BoundaryName::Usaw || d != 2 || b.shape == "particles")
            {
                return e(
                    &format!("{key}.fill"),
                    "\"usaw\" relaxes a 2-D lattice block for boundary = \"usaw\"".into(),
                );
            }
            if fill == "bipi" && b.shape == "particles" {
                return e(
                    &format!("{key}.fill"),
                    "a \"particles\" block is already placed; it cannot be packed".into(),
                );
            }
        }
        if let Some(dx) = b.dx {
            positive(&format!("{key}.dx"), dx)?;
        }
        if let Some(v) = &b.velocity {
            vector(loaded, &format!("{key}.velocity"), v, d)?;
        }
        if let Some(tp) = &b.pressure_taper {
            if tp.axis >= d {
                return e(
                    &format!("{key}.pressure_taper.axis"),
                    format!("expected 0 to {}, found {}", d - 1, tp.axis),
                );
            }
            positive(&format!("{key}.pressure_taper.length"), tp.length)?;
        }
        if let Some(InitialPressure::Named(name)) = &b.pressure {
            if name != "hydrostatic" && name != "hydrostatic-eos" {
                return e(
                    &format!("{key}.pressure"),
                    format!("expected \"hydrostatic\", \"hydrostatic-eos\" or a number, found \"{name}\""),
                );
            }
        }
    }
    if c.wall.is_empty() && c.domain.is_none() {
        return e(
            "wall",
            "expected at least one [[wall]], or a [domain] for a case without walls".into(),
        );
    }
    for (k, w) in c.wall.iter().enumerate() {
        let key = format!("wall[{k}]");
        if let Some(size) = w.element_size {
            positive(&format!("{key}.element_size"), size)?;
        }
        if d == 3 && (w.shape == "mesh" || w.shape == "capsule") {
            crate::mesh_walls::check_wall(loaded, &key, w)?;
        } else {
            shape_points(loaded, &key, &w.shape, &w.min, &w.max, &w.points, d)?;
            if let Some(f) = &w.fluid {
                if w.shape != "box" || (f != "inside" && f != "outside") {
                    return e(
                        &format!("{key}.fluid"),
                        format!("expected \"inside\" or \"outside\" on a box or mesh wall, found \"{f}\" on a \"{}\"", w.shape),
                    );
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
                return e(
                    &format!("{key}.open"),
                    format!("expected sides among {sides:?}, found \"{o}\""),
                );
            }
        }
        if let Some(body) = &w.body {
            if !c.body.iter().any(|b| &b.name == body) {
                return e(
                    &format!("{key}.body"),
                    format!("no [[body]] is named \"{body}\""),
                );
            }
        }
    }
    for (k, b) in c.body.iter().enumerate() {
        let key = format!("body[{k}]");
        if b.name.is_empty() || c.body.iter().filter(|o| o.name == b.name).count() > 1 {
            return e(
                &format!("{key}.name"),
                format!("expected a unique, non-empty name, found \"{}\"", b.name),
            );
        }
        if let Some(centre) = &b.centre {
            vector(loaded, &format!("{key}.centre"), centre, d)?;
        }
        if let Some(fs) = &b.free {
            if b.motion.is_some() || b.piston.is_some() {
                return e(
                    &format!("{key}.free"),
                    "a body has one of motion, piston or free, not several".into(),
                );
            }
            check_free(loaded, &key, fs, d)?;
        }
        if let Some(p) = &b.piston {
            if b.motion.is_some() {
                return e(
                    &format!("{key}.piston"),
                    "a body has either a motion or a piston, not both".into(),
                );
            }
            vector(loaded, &format!("{key}.piston.axis"), &p.axis, d)?;
            if p.axis.iter().all(|x| *x == 0.0) {
                return e(
                    &format!("{key}.piston.axis"),
                    "expected a non-zero vector".into(),
                );
            }
            positive(&format!("{key}.piston.mass"), p.mass)?;
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
    if let Some(dom) = &c.domain {
        vector(loaded, "domain.min", &dom.min, d)?;
        vector(loaded, "domain.max", &dom.max, d)?;
        if dom.min.iter().zip(&dom.max).any(|(a, b)| a >= b) {
            return e("domain", "expected min < max in every direction".into());
        }
        let names = &["x", "y", "z"][..d];
        for (k, a) in dom.periodic.iter().enumerate() {
            let Some(axis) = names.iter().position(|n| n == a) else {
                return e(
                    "domain.periodic",
                    format!("expected axes among {names:?}, found \"{a}\""),
                );
            };
            if dom.periodic[..k].contains(a) {
                return e("domain.periodic", format!("axis \"{a}\" is listed twice"));
            }
            let support = 2.0 * c.resolution.h_over_dx * c.resolution.dx;
            let period = dom.max[axis] - dom.min[axis];
            if period < 3.0 * support {
                return e(
                    "domain.periodic",
                    format!(
                        "the period along {a} (domain extent {period}) must be at least three kernel supports ({})",
                        3.0 * support
                    ),
                );
            }
        }
    }
    check_pack(loaded)?;
    check_reliability(loaded)?;
    crate::settle::check(loaded)?;
    for (k, p) in c.probe.iter().enumerate() {
        let key = format!("probe[{k}]");
        vector(loaded, &format!("{key}.position"), &p.position, d)?;
        if p.kind != "pressure" && p.kind != "wall_pressure" && p.kind != "height" {
            return e(
                &format!("{key}.kind"),
                format!(
                    "expected \"pressure\", \"wall_pressure\" or \"height\", found \"{}\"",
                    p.kind
                ),
            );
        }
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
                if w.shape != "box" && w.shape != "polygon" && w.shape != "polyline" {
                    return Ok(()); // walls from files: no box known before building
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
                (Some(a), Some(z), _) if b.shape == "box" => vec![a, z],
                (_, _, Some(pts)) if b.shape == "polygon" => pts.iter().collect(),
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

fn shape_points(
    loaded: &LoadedCase,
    key: &str,
    shape: &str,
    min: &Option<Vec<f64>>,
    max: &Option<Vec<f64>>,
    points: &Option<Vec<Vec<f64>>>,
    d: usize,
) -> Result<(), CaseError> {
    match shape {
        "box" => {
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
        "polygon" | "polyline" if d == 2 => {
            let Some(pts) = points else {
                return Err(loaded.error(
                    &format!("{key}.points"),
                    "missing: a list of [x, y] vertices",
                ));
            };
            let needed = if shape == "polygon" { 3 } else { 2 };
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
        other => {
            let allowed = if d == 2 {
                "\"box\", \"polygon\" or \"polyline\""
            } else {
                "\"box\", \"mesh\" or \"capsule\""
            };
            Err(loaded.error(
                &format!("{key}.shape"),
                format!("expected {allowed} in {d}-D, found \"{other}\""),
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
    match s.shape.as_str() {
        "box" | "polygon" | "polyline" => {
            shape_points(loaded, key, &s.shape, &s.min, &s.max, &s.points, d)?
        }
        "polygon_file" | "stl" | "particles" => {
            let needed_dim = match s.shape.as_str() {
                "polygon_file" => Some(2),
                "stl" => Some(3),
                _ => None,
            };
            if let Some(nd) = needed_dim {
                if nd != d {
                    return e(
                        &format!("{key}.shape"),
                        format!("\"{}\" is a {nd}-D shape, but the case is {d}-D", s.shape),
                    );
                }
            }
            if s.shape == "particles" && !allow_particles {
                return e(&format!("{key}.shape"), "expected a shape".into());
            }
            match &s.file {
                Some(f) if !f.trim().is_empty() => {}
                _ => {
                    return e(
                        &format!("{key}.file"),
                        format!("missing: shape \"{}\" reads its data from a file", s.shape),
                    )
                }
            }
        }
        "sphere" if d == 3 => {
            let Some(c) = &s.centre else {
                return e(
                    &format!("{key}.centre"),
                    "missing: a sphere needs `centre`".into(),
                );
            };
            vector(loaded, &format!("{key}.centre"), c, 3)?;
            match s.radius {
                Some(r) if r > 0.0 && r.is_finite() => {}
                other => {
                    return e(
                        &format!("{key}.radius"),
                        format!("expected a positive radius, found {other:?}"),
                    )
                }
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
                "\"box\", \"polygon\", \"polygon_file\" or \"particles\""
            } else {
                "\"box\", \"stl\", \"sphere\" or \"particles\""
            };
            return e(
                &format!("{key}.shape"),
                format!("expected {allowed} in {d}-D, found \"{other}\""),
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

/// Metres per unit: `"m"`, `"cm"`, `"mm"`.
pub fn unit_factor(units: &str) -> Option<f64> {
    match units {
        "m" => Some(1.0),
        "cm" => Some(0.01),
        "mm" => Some(0.001),
        _ => None,
    }
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

/// Where a run writes by default: `out/<case name>`.
pub fn default_out_dir(case: &Case) -> PathBuf {
    PathBuf::from("out").join(&case.name)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `fill = "usaw"` relaxes for usaw walls only: elsewhere a named error.
    #[test]
    fn usaw_fill_needs_usaw_walls() {
        let text = include_str!("../../../cases/usaw-tank-corner.toml");
        assert!(parse_case("tank", text, &[]).is_ok());
        let Err(err) = parse_case("tank", text, &["boundary=\"bi\"".to_string()]) else {
            panic!("fill = \"usaw\" with bi walls must be refused");
        };
        let err = err.to_string();
        assert!(err.contains("fluid_block[0].fill"), "{err}");
    }
}
