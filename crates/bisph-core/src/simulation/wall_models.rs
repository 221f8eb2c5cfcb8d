//! Which wall model a case uses, and the one place that turns that choice into a
//! [`WallModel`], so that every sweep over the particles is monomorphised for it.

use crate::dim::Vector;
use crate::walls::energy_bi::{EnergyConservingWalls, ListedEnergyWalls};
use crate::walls::shepard::{Shepard, ShepardKind};
use crate::walls::shepard_bi::{BoundaryQuadrature, ShepardWalls};
use crate::walls::usaw::{UsawWalls, Vertices, WallInterpolation};
use crate::walls::WallModel;

/// Which wall model a case uses (chosen once; the sweep is monomorphised for it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum WallModelChoice {
    /// Energy-conserving boundary integrals (paper 1). The default.
    #[default]
    Energy,
    /// Classic boundary integrals with Shepard renormalisation (paper 1, eqs 24-25), and how
    /// their boundary term integrates the kernel over an element.
    ShepardBi(ShepardKind, BoundaryQuadrature),
    /// Unified semi-analytical walls with vertex particles (paper 3), 2-D.
    Usaw(UsawParams),
}

impl WallModelChoice {
    /// The Shepard strategy of a renormalised wall model (none for the energy-conserving
    /// walls): the semi-analytical walls' particles always carry gamma, integrated in time
    /// (paper 3, eq 4) or geometric.
    pub fn shepard(&self) -> Option<Shepard> {
        match self {
            WallModelChoice::Energy => None,
            WallModelChoice::ShepardBi(kind, _) => Some(Shepard::of(*kind)),
            WallModelChoice::Usaw(p) => Some(Shepard::of(if p.geometric_gamma {
                ShepardKind::Geometric
            } else {
                ShepardKind::Integrated
            })),
        }
    }

    /// `true` when the particles carry gamma (paper 3, eq 4).
    pub fn needs_gamma(&self) -> bool {
        self.shepard().is_some_and(|s| s.carried())
    }

    /// `true` when the walls' part of the continuity equation is `-rho dln(gamma)/dt` of the
    /// gamma the particles carry: the classic boundary integrals with the geometric or
    /// integrated gamma and the element integrals `int_{S_k} W dS` (exact, or within 1e-3 by
    /// the Gauss rule), whose sum `sum_k n_k int_{S_k} W dS` is `-grad gamma` (paper 3, eq 9).
    /// The centre rule's sum is not, and the semi-analytical walls' vertex particles add
    /// terms of their own.
    pub fn wall_divergence_is_gamma_rate(&self) -> bool {
        matches!(self, WallModelChoice::ShepardBi(kind, quadrature)
            if *kind != ShepardKind::Discrete && *quadrature != BoundaryQuadrature::Centre)
    }

    /// `true` when the walls carry vertex particles (paper 3, table 1), which also makes
    /// summation densities (eq 84) available.
    pub fn has_vertex_particles(&self) -> bool {
        matches!(self, WallModelChoice::Usaw(_))
    }

    /// The density power `k` of paper 3, eqs 37-38: the semi-analytical walls' choice, 0
    /// (paper 1, eqs 10-11) for the other models.
    pub fn density_power(&self) -> u8 {
        match self {
            WallModelChoice::Usaw(p) => p.density_power,
            _ => 0,
        }
    }

    /// `true` when the densities come from summation over fluid and vertex particles
    /// (paper 3, eqs 13 and 84): the semi-analytical walls' choice.
    pub fn summation_density(&self) -> bool {
        matches!(self, WallModelChoice::Usaw(p) if p.summation_density)
    }

    /// `true` when the wall model itself evaluates the geometric Shepard factor (paper 2):
    /// geometric renormalisation, or gamma of the semi-analytical or integrated walls.
    pub fn evaluates_geometric_gamma(&self) -> bool {
        self.shepard()
            .is_some_and(|s| s.kind != ShepardKind::Discrete)
    }
}

/// Options of the semi-analytical walls.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct UsawParams {
    /// How vertex pressures are extrapolated (paper 3, eqs 16-17, 82, 83).
    pub interpolation: WallInterpolation,
    /// Recompute gamma geometrically (paper 2) every step instead of integrating eq 4.
    pub geometric_gamma: bool,
    /// Walls push but never pull: the wall terms use the non-negative parts of the particle,
    /// vertex and segment pressures ([`crate::walls::usaw::UsawWalls::no_tension`]).
    pub no_wall_tension: bool,
    /// The density power `k` of paper 3, eqs 37-38 (0 or 1).
    pub density_power: u8,
    /// Density by summation, `gamma rho = sum_P m W + C` (paper 3, eqs 13 and 84; explicit
    /// Verlet), instead of the continuity equation (eq 12).
    pub summation_density: bool,
}

/// Work done with the wall model in use, whatever its type.
pub(crate) trait WallModelTask<V: Vector> {
    /// What the work returns.
    type Output;
    /// Does the work with `wall_model`.
    fn run<W: WallModel<V>>(self, wall_model: &W) -> Self::Output;
}

/// What the wall models are built from besides the choice itself.
pub(crate) struct WallModelInputs<'a, V: Vector> {
    /// Gravity (the hydrostatic correction of the extrapolated wall pressure).
    pub gravity: V,
    /// The vertex particles of the semi-analytical walls.
    pub vertices: &'a Vertices<V>,
    /// The energy-conserving walls' listed pairs, when listed (inside a midpoint step).
    pub listed: Option<ListedEnergyWalls<'a, V>>,
}

impl WallModelChoice {
    /// Runs `task` with the wall model of this choice built from `inputs`.
    pub(crate) fn run<V: Vector, T: WallModelTask<V>>(
        self,
        inputs: WallModelInputs<'_, V>,
        task: T,
    ) -> T::Output {
        match self {
            WallModelChoice::Energy => match inputs.listed {
                Some(listed) => task.run(&listed),
                None => task.run(&EnergyConservingWalls),
            },
            WallModelChoice::ShepardBi(kind, quadrature) => task.run(&ShepardWalls {
                gravity: inputs.gravity,
                shepard: Shepard::of(kind),
                quadrature,
            }),
            WallModelChoice::Usaw(params) => task.run(&UsawWalls {
                vertices: inputs.vertices,
                density_power: params.density_power,
                no_tension: params.no_wall_tension,
            }),
        }
    }
}
