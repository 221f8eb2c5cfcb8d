//! The case file's schema: a TOML document describing one simulation, section by section,
//! with the defaults of every key.

use crate::case::error::CaseError;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Equation of state name.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum EosName {
    /// `p = p0 + c0^2 (rho - rho0)` (paper 1, eq 3).
    Linear,
    /// Tait (paper 3, eq 15).
    Tait,
}

/// How the `bi` boundary term integrates the kernel over an element (`boundary_quadrature`).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum BoundaryQuadratureName {
    /// `W` at the element centre times its area (paper 1, eqs 24-25).
    Centre,
    /// `int_S W dS` exactly (paper 3, eq 9; paper 4, eq 3).
    Exact,
    /// `int_S W dS` by a low-order Gauss rule per element.
    Gauss,
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
    Shepard,
    /// Neumann with gravity (`dp/dn = rho g . n`), the constraint of eq 82.
    Neumann,
    /// Hydrostatic-corrected, eq 83 (the default: without gravity it is eqs 16-17 exactly).
    #[default]
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
    /// Equation of state (default: Tait with `boundary = "usaw"`, whose model paper 3 closes
    /// with it (eq 15), else linear).
    pub eos: Option<EosName>,
    /// Background pressure `p0` [Pa].
    #[serde(default)]
    pub background_pressure: f64,
    /// Tait exponent.
    #[serde(default = "default_tait_exponent")]
    pub tait_exponent: f64,
    /// Gravity vector [m/s^2] (`dim` components).
    #[serde(default)]
    pub gravity: Vec<f64>,
    /// delta-SPH coefficient (0 = off; default [`DEFAULT_DELTA`] with `boundary = "bi"` and
    /// `"usaw"`, whose operators are not skew-adjoint, else 0).
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
    /// booked in `energy.csv` (default [`DEFAULT_ARTIFICIAL_VISCOSITY`]; 0 for exact energy
    /// conservation).
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

/// The delta-SPH coefficient `boundary = "bi"` and `boundary = "usaw"` get when `fluid.delta`
/// is left out. Neither model's operators are skew-adjoint: without density diffusion the
/// classic BI gains energy from still water, and with usaw walls a free-surface particle in an
/// acute corner against a wall goes into tension and is drawn to the wall (`bisph validate
/// still-water`, the sloped tank).
pub const DEFAULT_DELTA: f64 = 0.1;

/// The artificial viscosity every wall model gets when `fluid.artificial_viscosity` is left
/// out. The `bi` and `usaw` operators are not skew-adjoint and gain energy without
/// dissipation; the energy-conserving walls have no static rest state next to a side wall
/// (zeroth-order consistency), and without dissipation the explicit scheme blows up from
/// still water. With it a tank at rest stays within 1% of `sqrt(g H)` (`bisph validate
/// still-water`).
pub const DEFAULT_ARTIFICIAL_VISCOSITY: f64 = 0.05;

impl Case {
    /// The delta-SPH coefficient in force: `fluid.delta`, or the wall model's default.
    pub fn delta(&self) -> f64 {
        self.fluid.delta.unwrap_or(match self.boundary {
            BoundaryName::Bi | BoundaryName::Usaw => DEFAULT_DELTA,
            BoundaryName::Energy => 0.0,
        })
    }

    /// The artificial viscosity `alpha` in force: `fluid.artificial_viscosity`, or
    /// [`DEFAULT_ARTIFICIAL_VISCOSITY`].
    pub fn artificial_viscosity(&self) -> f64 {
        self.fluid
            .artificial_viscosity
            .unwrap_or(DEFAULT_ARTIFICIAL_VISCOSITY)
    }

    /// The `bi` boundary quadrature in force: `boundary_quadrature`, or exact in 2-D (closed
    /// form per segment) and a Gauss rule per element in 3-D.
    pub fn boundary_quadrature(&self) -> BoundaryQuadratureName {
        self.boundary_quadrature.unwrap_or(if self.dim == 2 {
            BoundaryQuadratureName::Exact
        } else {
            BoundaryQuadratureName::Gauss
        })
    }

    /// Why the case cannot settle before `t = 0`, or `None` when it can: settling needs fluid
    /// at rest under gravity (no block velocity, no flux forcing, no periodic axis along
    /// gravity) with fixed walls (no moving, piston or free body).
    pub fn settle_obstacle(&self) -> Option<String> {
        let g = &self.fluid.gravity;
        if g.iter().all(|&x| x == 0.0) {
            return Some("the case has no gravity".into());
        }
        if self.flux.is_some() {
            return Some("the case has a flux-driving force ([flux])".into());
        }
        if let Some(domain) = &self.domain {
            if let Some(&axis) = domain
                .periodic_axes()
                .iter()
                .find(|&&k| g.get(k).is_some_and(|&x| x != 0.0))
            {
                let name = ["x", "y", "z"][axis];
                return Some(format!("gravity has a part along the periodic axis {name}"));
            }
        }
        for (k, block) in self.fluid_block.iter().enumerate() {
            if block
                .velocity
                .as_ref()
                .is_some_and(|v| v.iter().any(|&x| x != 0.0))
            {
                return Some(format!("fluid_block[{k}].velocity is not zero"));
            }
        }
        self.body
            .iter()
            .enumerate()
            .find(|(_, b)| b.motion.is_some() || b.piston.is_some() || b.free.is_some())
            .map(|(k, b)| format!("body[{k}] (\"{}\") moves", b.name))
    }

    /// The equation of state in force: `fluid.eos`, or the wall model's (Tait for `usaw`).
    pub fn eos_name(&self) -> EosName {
        self.fluid.eos.unwrap_or(match self.boundary {
            BoundaryName::Usaw => EosName::Tait,
            BoundaryName::Energy | BoundaryName::Bi => EosName::Linear,
        })
    }

    /// The mass rule of block `block`: `mass`, or `"initial"` (volumes that tile the lattice).
    pub fn mass_rule(&self, block: &FluidBlock) -> MassRule {
        block.mass.unwrap_or(MassRule::Initial)
    }

    /// `true` when block `block` is relaxed to fit usaw walls before the run: `fill = "usaw"`,
    /// or, with `boundary = "usaw"` in 2-D, a lattice block whose `fill` is left out (on the
    /// bare lattice the usaw operators are far from rest next to the walls).
    pub fn fills_for_usaw(&self, block: &FluidBlock) -> bool {
        match block.fill {
            Some(fill) => fill == FillName::Usaw,
            None => {
                self.boundary == BoundaryName::Usaw
                    && self.dim == 2
                    && block.shape != BlockShape::Particles
                    && !block.solid
            }
        }
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
    /// particle has moved half the skin, or longer while few have and none has come within
    /// reach of a partner the list lacks (0 = search the cell grid at every step; default
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
    /// Past iterations Anderson's mixing combines (0: the plain or relaxed iteration).
    #[serde(default = "default_anderson_depth")]
    pub anderson_depth: u32,
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
fn default_anderson_depth() -> u32 {
    0
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
            anderson_depth: default_anderson_depth(),
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

/// `[diagnostics]`: divergence watches (see `bisph_io::run::diagnostics`).
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
    /// Most particles, as a fraction of the initial fluid, that may leave the domain (each
    /// removed as it leaves); one more stops the run (0: the first stops it).
    #[serde(default = "default_removed_fraction_max")]
    pub removed_fraction_max: f64,
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
fn default_removed_fraction_max() -> f64 {
    0.01
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
            removed_fraction_max: default_removed_fraction_max(),
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

/// Shape of a fluid block or of a hole cut out of one (`shape`).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum BlockShape {
    /// An axis-aligned box between `min` and `max`.
    Box,
    /// A polygon through `points` (2-D).
    Polygon,
    /// An open polyline through `points` (2-D; not a region: refused where one is needed).
    Polyline,
    /// A polygon read from `file` (2-D).
    PolygonFile,
    /// A closed triangle mesh read from an STL `file` (3-D).
    Stl,
    /// A generated closed sphere mesh (3-D).
    Sphere,
    /// A circle of `radius` about `centre` (2-D), drawn as a polygon.
    Circle,
    /// A closed cylinder of `radius` about the axis from `start` to `end` (3-D).
    Cylinder,
    /// Particle positions read from a CSV `file` (fluid blocks only).
    Particles,
    /// The fluid inside the case's walls below `level` (fluid blocks only).
    Walls,
}

impl BlockShape {
    /// The name a case file gives the shape.
    pub fn name(self) -> &'static str {
        match self {
            BlockShape::Box => "box",
            BlockShape::Polygon => "polygon",
            BlockShape::Polyline => "polyline",
            BlockShape::PolygonFile => "polygon_file",
            BlockShape::Stl => "stl",
            BlockShape::Sphere => "sphere",
            BlockShape::Circle => "circle",
            BlockShape::Cylinder => "cylinder",
            BlockShape::Particles => "particles",
            BlockShape::Walls => "walls",
        }
    }
}

/// How a fluid block's particles are placed (`fill`).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum FillName {
    /// On the lattice.
    Lattice,
    /// Packed with BIPI (paper 4) before the run.
    Bipi,
    /// The lattice relaxed to fit usaw walls (2-D, `boundary = "usaw"`).
    Usaw,
}

/// Shape of a `[[wall]]` (`shape`).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum WallShape {
    /// An axis-aligned box between `min` and `max`, sides optionally `open`.
    Box,
    /// An open polyline through `points` (2-D).
    Polyline,
    /// A closed polygon through `points` (2-D).
    Polygon,
    /// A triangle mesh read from an STL or OBJ `file` (3-D).
    Mesh,
    /// A generated Apollo-like `capsule` (3-D).
    Capsule,
    /// A circle of `radius` about `centre` (2-D), a closed polygon of elements.
    Circle,
    /// A sphere of `radius` about `centre` (3-D), a generated closed mesh.
    Sphere,
    /// A cylinder of `radius` about the axis from `start` to `end` (3-D), closed by end caps
    /// unless `open`.
    Cylinder,
}

impl WallShape {
    /// The name a case file gives the shape.
    pub fn name(self) -> &'static str {
        match self {
            WallShape::Box => "box",
            WallShape::Polyline => "polyline",
            WallShape::Polygon => "polygon",
            WallShape::Mesh => "mesh",
            WallShape::Capsule => "capsule",
            WallShape::Circle => "circle",
            WallShape::Sphere => "sphere",
            WallShape::Cylinder => "cylinder",
        }
    }

    /// `true` for the shapes generated from a centre or an axis and a radius (`circle`,
    /// `sphere`, `cylinder`): obstacles unless `fluid = "inside"`.
    pub fn is_round(self) -> bool {
        matches!(
            self,
            WallShape::Circle | WallShape::Sphere | WallShape::Cylinder
        )
    }
}

/// What a probe measures (`kind`).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ProbeKindName {
    /// Fluid pressure, Shepard-normalised.
    Pressure,
    /// Wall pressure, `2 sum p W V`.
    WallPressure,
    /// Water height of the vertical column through the position.
    Height,
}

/// `[[fluid_block]]`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FluidBlock {
    /// `"box"`, `"polygon"` (2-D), `"polygon_file"` (2-D), `"circle"` (2-D), `"stl"` (3-D),
    /// `"sphere"` (3-D, a generated closed mesh), `"cylinder"` (3-D), `"particles"`
    /// (positions from a CSV file) or `"walls"` (the fluid inside the case's walls below
    /// `level`).
    pub shape: BlockShape,
    /// `shape = "walls"`: the height along `-g` up to which the walls are filled.
    pub level: Option<f64>,
    /// `shape = "walls"`: the least distance of a particle from a wall, in units of the
    /// block's spacing (default 0.5).
    pub clearance: Option<f64>,
    /// Box lower corner.
    pub min: Option<Vec<f64>>,
    /// Box upper corner.
    pub max: Option<Vec<f64>>,
    /// Polygon vertices.
    pub points: Option<Vec<Vec<f64>>>,
    /// Geometry or particle file, relative to the case file's folder.
    pub file: Option<String>,
    /// Circle or sphere centre.
    pub centre: Option<Vec<f64>>,
    /// Circle, sphere or cylinder radius.
    pub radius: Option<f64>,
    /// Cylinder axis start.
    pub start: Option<Vec<f64>>,
    /// Cylinder axis end.
    pub end: Option<Vec<f64>>,
    /// Sphere mesh refinement (icosahedron subdivisions; default: edges of about `2 dx`).
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
    /// `"lattice"`, `"bipi"`: pack the block with BIPI before running, or `"usaw"` (2-D,
    /// `boundary = "usaw"`): relax the lattice so that the usaw operators' zero-order
    /// residual (vertex particles included) vanishes and, under gravity, so that still water
    /// is at rest (`bisph_core::walls::usaw::relax_positions`, `balance_positions`). Default:
    /// `"usaw"` for 2-D blocks with `boundary = "usaw"`, else `"lattice"`
    /// ([`Case::fills_for_usaw`]).
    pub fill: Option<FillName>,
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
    /// Particle masses: `"reference"` (`rho0 dx^d`) or `"initial"` (`rho dx^d` with the
    /// initial density, for a fluid that starts compressed). Default: `"initial"` (volumes
    /// that tile the lattice, so the hydrostatic start weighs what its pressure says and its
    /// densities agree with the particle spacing; [`Case::mass_rule`]). With `boundary =
    /// "usaw"` and every block `"initial"`, the vertex particles' masses follow: `rho_v V_v`
    /// with their initial extrapolated densities.
    pub mass: Option<MassRule>,
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
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum MassRule {
    /// `rho0 dx^d`.
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
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShapeSpec {
    /// `"box"`, `"polygon"`, `"polygon_file"`, `"circle"` (2-D), `"stl"`, `"sphere"` or
    /// `"cylinder"` (3-D).
    pub shape: BlockShape,
    /// Box lower corner.
    pub min: Option<Vec<f64>>,
    /// Box upper corner.
    pub max: Option<Vec<f64>>,
    /// Polygon vertices.
    pub points: Option<Vec<Vec<f64>>>,
    /// Geometry file, relative to the case file's folder.
    pub file: Option<String>,
    /// Circle or sphere centre.
    pub centre: Option<Vec<f64>>,
    /// Circle, sphere or cylinder radius.
    pub radius: Option<f64>,
    /// Cylinder axis start.
    pub start: Option<Vec<f64>>,
    /// Cylinder axis end.
    pub end: Option<Vec<f64>>,
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
            shape: self.shape,
            min: self.min.clone(),
            max: self.max.clone(),
            points: self.points.clone(),
            file: self.file.clone(),
            centre: self.centre.clone(),
            radius: self.radius,
            start: self.start.clone(),
            end: self.end.clone(),
            subdivisions: self.subdivisions,
            units: self.units.clone(),
            scale: self.scale,
            rotate: self.rotate.clone(),
            translate: self.translate.clone(),
        }
    }

    /// `true` when the block asks to be packed with BIPI.
    pub fn bipi(&self) -> bool {
        self.fill == Some(FillName::Bipi)
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
    /// `"box"`, `"polyline"`, `"polygon"` or `"circle"` (2-D); `"mesh"` (an STL or OBJ
    /// file), `"capsule"`, `"sphere"` or `"cylinder"` (3-D).
    pub shape: WallShape,
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
    /// Which side of a box, closed mesh, circle, sphere or cylinder the fluid is on:
    /// `"inside"` (a tank; the default of boxes and meshes) or `"outside"` (an obstacle or a
    /// floating body; the default of capsules, circles, spheres and cylinders). Closed meshes
    /// are oriented automatically.
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
    /// Box sides left open (`"-x"`, `"+x"`, `"-y"`, `"+y"`, `"-z"`, `"+z"`), or cylinder ends
    /// left without a cap (`"start"`, `"end"`).
    #[serde(default)]
    pub open: Vec<String>,
    /// Circle or sphere centre.
    pub centre: Option<Vec<f64>>,
    /// Circle, sphere or cylinder radius.
    pub radius: Option<f64>,
    /// Cylinder axis start.
    pub start: Option<Vec<f64>>,
    /// Cylinder axis end.
    pub end: Option<Vec<f64>>,
    /// Sphere mesh refinement (icosahedron subdivisions; default: edges of about twice the
    /// element size, as a sphere block's at that spacing).
    pub subdivisions: Option<u32>,
    /// Polyline / polygon vertices; the fluid lies on their left.
    pub points: Option<Vec<Vec<f64>>>,
    /// Owning body (default: the fixed walls).
    pub body: Option<String>,
    /// Stretch with a piston (the wall must lie along the piston axis).
    pub stretch: Option<StretchSpec>,
}

impl WallSpec {
    /// `true` when the fluid lies outside the wall's closed mesh (an obstacle or a body; the
    /// default for a capsule, a circle, a sphere and a cylinder).
    pub fn fluid_outside(&self) -> bool {
        match self.fluid.as_deref() {
            Some(f) => f == "outside",
            None => self.shape == WallShape::Capsule || self.shape.is_round(),
        }
    }
}

/// Most elements one mesh wall may make (a mesh in the wrong units, or a coordinate far off,
/// must be refused before the elements are allocated).
pub const MAX_MESH_ELEMENTS: f64 = 2e7;

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
    pub kind: ProbeKindName,
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
    /// How the `bi` walls' boundary term integrates the kernel over an element: `"exact"`
    /// (default in 2-D) or `"centre"` (the kernel at the element centre times its area;
    /// default in 3-D, where the exact polygon integrals cost several times the sweep)
    /// ([`Case::boundary_quadrature`]).
    pub boundary_quadrature: Option<BoundaryQuadratureName>,
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
    /// `true`: settle before the run (refused where the case cannot settle); `false`: never;
    /// left out: settle when the case can and its fluid rests against walls with a level free
    /// surface.
    pub enabled: Option<bool>,
    /// Damping rate `beta` [1/s] (default: twice the lowest sloshing frequency of the fluid,
    /// `2 sqrt(g k tanh(k H))` with `k = pi / L`, `L` and `H` its width and depth).
    pub damping: Option<f64>,
    /// At rest when speeds are below `tolerance sqrt(g H)` and accelerations below
    /// `tolerance sqrt(g H) beta` (default 1e-3).
    pub tolerance: Option<f64>,
    /// Most settling time [s] (default `200 / beta`).
    pub max_time: Option<f64>,
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
