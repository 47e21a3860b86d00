//! The physics variant of a run, chosen once from the scene: the paper's stress operator with a
//! Newtonian or Cross rheology, Eq. (8) as printed or renormalized, without or with hourglass
//! control, Müller's Laplacian (Newtonian), or Morris's operator with a constant viscosity or a
//! shear-thinning one per particle. Each is a type, so the CPU loops and the GPU kernels of a run contain only the
//! physics it uses.

use crate::scene::inlet::Inlet;
use crate::scene::Viscosity;
use crate::simulation::backend::Passes;
use crate::simulation::particles::ImplicitViews;
pub use crate::simulation::particles::ModelFields;
use coil_kernels::acceleration::AccelerationArgs;
use coil_kernels::cell_grid::{Neighborhood, Neighbors};
use coil_kernels::cross_viscosity::{Cross, Newtonian, Rheology};
use coil_kernels::fluid::Fluid;
use coil_kernels::nozzle::NozzleTube;
use coil_kernels::topology::{Open, Topology};
use coil_kernels::velocity_gradient::{GradientEstimate, KernelSum};
use coil_kernels::view::{Mat3ViewMut, SymTensorViewMut, Vec3View, Vec3ViewMut, View, ViewMut};
use coil_kernels::viscosity::hourglass_ganzenmuller2015::{HourglassControlledStress, VelocityGradientArgs};
use coil_kernels::viscosity::laplacian_morris1997::MorrisViscosity;
use coil_kernels::viscosity::laplacian_morris1997::ShearViscosityArgs;
use coil_kernels::viscosity::laplacian_muller2003::VelocityLaplacian;
use coil_kernels::viscosity::stress_andrade2014::StressArgs;
use coil_kernels::viscosity::stress_andrade2014::StressDivergence;
use coil_kernels::viscosity::ViscousOperator;
use coil_kernels::Real;

/// A viscosity operator and law, fixed for a run.
pub trait Model<R: Real>: Copy + Send + Sync + 'static {
    /// The per-particle arrays the run allocates beyond the particles' state.
    const FIELDS: ModelFields;
    /// The viscosity law: its viscosity at a shear rate for output, its largest for the
    /// Eq. (10) bound.
    type Law: Rheology<R>;
    fn law(&self) -> Self::Law;
    /// How the run estimates velocity gradients (its own, and the shear rate of output frames).
    type Gradient: GradientEstimate;
    /// Velocity gradient and stress (when used), then accelerations, for all particles of
    /// `state`, run by `backend`, visiting neighbors through `N`; with the implicit solve, how
    /// it went.
    fn accelerations<T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        state: ParticleState<'_, R, N>,
    ) -> Option<SolveReport>;
}

/// How one step's implicit viscosity solve went.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveReport {
    /// Conjugate-gradient iterations.
    pub iterations: u32,
    /// The last residual's norm over the first's.
    pub relative_residual: f64,
    /// Whether the residual met the tolerance.
    pub converged: bool,
}

/// What the implicit solve reads beyond the explicit operators' state.
#[derive(Clone, Copy)]
pub struct ImplicitStep<'a, R> {
    /// Leap-frog's kick (s).
    pub kick_dt: R,
    /// v_{n-1/2} (m/s).
    pub velocity_half: Vec3View<'a, R>,
    /// The velocity the viscous terms read, which boundary particles keep: at rest, or their
    /// mirror images' ghost velocity under mirrored walls (m/s).
    pub velocity: Vec3View<'a, R>,
    pub arrays: ImplicitViews<'a, R>,
    /// Particle positions (m), which say who is inside a nozzle's tube.
    pub position: Vec3View<'a, f64>,
    /// The run's inlets, whose tubes set the velocity of the fluid inside them.
    pub inlets: &'a [Inlet],
    /// The step's start (s), where the tubes are.
    pub time: f64,
}

impl<R: Real> ImplicitStep<'_, R> {
    /// Each inlet's nozzle tube at the step's start.
    pub fn tubes(&self) -> impl Iterator<Item = NozzleTube<R>> + '_ {
        self.inlets.iter().map(|inlet| inlet.tube(self.time))
    }
}

/// What the acceleration passes read and write, as views a backend built over its own memory.
#[derive(Clone, Copy)]
pub struct ParticleState<'a, R, N = Neighborhood<'a, Open>> {
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    pub id: View<'a, u32>,
    /// Velocity the viscous terms read (m/s): see `coil_kernels::leapfrog`.
    pub velocity: Vec3View<'a, R>,
    pub density: View<'a, R>,
    /// Present when the model uses stress (`Model::FIELDS`).
    pub stress: Option<SymTensorViewMut<'a, R>>,
    /// Present when the model uses a viscosity per particle (`Model::FIELDS`).
    pub viscosity: Option<ViewMut<'a, R>>,
    /// Present when the model uses the velocity gradient (`Model::FIELDS`).
    pub velocity_gradient: Option<Mat3ViewMut<'a, R>>,
    pub acceleration: Vec3ViewMut<'a, R>,
    /// Present where viscosity is solved implicitly.
    pub implicit: Option<ImplicitStep<'a, R>>,
}

impl<'a, R: Real, N: Neighbors> ParticleState<'a, R, N> {
    /// The acceleration pass's arguments with viscous operator `viscous`.
    pub fn acceleration_args<Op: ViscousOperator<R>>(&self, viscous: Op) -> AccelerationArgs<'a, R, Op, N> {
        AccelerationArgs {
            neighborhood: self.neighborhood,
            fluid: self.fluid,
            viscous,
            id: self.id,
            density: self.density,
            acceleration: self.acceleration,
        }
    }
}

/// The scene's Cross model, Eq. (3), in precision `R` (whatever its K: K = 0 is Newtonian).
pub fn cross_law<R: Real>(v: &Viscosity) -> Cross<R> {
    Cross {
        nu0: R::from_f64(v.nu0_m2_s),
        nu_inf: R::from_f64(v.nu_inf()),
        k: R::from_f64(v.cross_k_s),
        n: R::from_f64(v.cross_n),
    }
}

/// The paper's operator, Eq. (8), (2), (9), with rheology `Rh` and the velocity gradient
/// estimated by `G` (Eq. (8) as printed, or renormalized).
#[derive(Clone, Copy, Debug)]
pub struct StressModel<Rh, G>(pub Rh, pub G);

/// The paper's operator with hourglass control (`coil_kernels::hourglass_control`) of weight
/// `coefficient`, with rheology `Rh`.
#[derive(Clone, Copy, Debug)]
pub struct HourglassStressModel<Rh, R> {
    pub rheology: Rh,
    pub coefficient: R,
}

/// Müller et al. 2003's Laplacian operator (Newtonian, nu0).
#[derive(Clone, Copy, Debug)]
pub struct LaplacianModel<R>(pub Newtonian<R>);

/// Morris, Fox & Zhu 1997's operator with a constant viscosity nu0.
#[derive(Clone, Copy, Debug)]
pub struct MorrisModel<R>(pub Newtonian<R>);

/// Morris, Fox & Zhu 1997's operator with each particle's viscosity from rheology `Rh` at its
/// shear rate (Eq. (8), (2), (3)).
#[derive(Clone, Copy, Debug)]
pub struct ShearThinningMorrisModel<Rh>(pub Rh);

impl<R: Real, Rh: Rheology<R> + 'static, G: GradientEstimate> Model<R> for StressModel<Rh, G> {
    const FIELDS: ModelFields = ModelFields {
        stress: true,
        viscosity: false,
        velocity_gradient: false,
        density_rate: false,
        shift: false,
        implicit: false,
        pressure_solve: false,
    };
    type Law = Rh;
    fn law(&self) -> Self::Law {
        self.0
    }
    type Gradient = G;
    fn accelerations<T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: ParticleState<'_, R, N>,
    ) -> Option<SolveReport> {
        let stress = s.stress.expect("the stress operator allocates stress");
        backend.stress(StressArgs {
            neighborhood: s.neighborhood,
            gradient: self.1,
            fluid: s.fluid,
            rheology: self.0,
            velocity: s.velocity,
            density: s.density,
            stress,
        });
        backend.acceleration(s.acceleration_args(StressDivergence { stress: stress.read() }));
        None
    }
}

impl<R: Real, Rh: Rheology<R> + 'static> Model<R> for HourglassStressModel<Rh, R> {
    const FIELDS: ModelFields = ModelFields {
        stress: false,
        viscosity: true,
        velocity_gradient: true,
        density_rate: false,
        shift: false,
        implicit: false,
        pressure_solve: false,
    };
    type Law = Rh;
    fn law(&self) -> Self::Law {
        self.rheology
    }
    type Gradient = KernelSum;
    fn accelerations<T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: ParticleState<'_, R, N>,
    ) -> Option<SolveReport> {
        let gradient = s.velocity_gradient.expect("hourglass control allocates the velocity gradient");
        let viscosity = s.viscosity.expect("hourglass control allocates viscosity");
        backend.velocity_gradient(VelocityGradientArgs {
            neighborhood: s.neighborhood,
            fluid: s.fluid,
            rheology: self.rheology,
            velocity: s.velocity,
            density: s.density,
            gradient,
            viscosity,
        });
        backend.acceleration(s.acceleration_args(HourglassControlledStress {
            coefficient: self.coefficient,
            velocity: s.velocity,
            gradient: gradient.read(),
            viscosity: viscosity.read(),
        }));
        None
    }
}

impl<R: Real> Model<R> for LaplacianModel<R> {
    const FIELDS: ModelFields = ModelFields {
        stress: false,
        viscosity: false,
        velocity_gradient: false,
        density_rate: false,
        shift: false,
        implicit: false,
        pressure_solve: false,
    };
    type Law = Newtonian<R>;
    fn law(&self) -> Self::Law {
        self.0
    }
    type Gradient = KernelSum;
    fn accelerations<T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: ParticleState<'_, R, N>,
    ) -> Option<SolveReport> {
        let mu0 = self.0.nu0 * s.fluid.rest_density;
        backend.acceleration(s.acceleration_args(VelocityLaplacian { mu0, velocity: s.velocity }));
        None
    }
}

impl<R: Real> Model<R> for MorrisModel<R> {
    const FIELDS: ModelFields = ModelFields {
        stress: false,
        viscosity: false,
        velocity_gradient: false,
        density_rate: false,
        shift: false,
        implicit: false,
        pressure_solve: false,
    };
    type Law = Newtonian<R>;
    fn law(&self) -> Self::Law {
        self.0
    }
    type Gradient = KernelSum;
    fn accelerations<T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: ParticleState<'_, R, N>,
    ) -> Option<SolveReport> {
        backend.acceleration(s.acceleration_args(MorrisViscosity { velocity: s.velocity, viscosity: self.0 }));
        None
    }
}

impl<R: Real, Rh: Rheology<R> + 'static> Model<R> for ShearThinningMorrisModel<Rh> {
    const FIELDS: ModelFields = ModelFields {
        stress: false,
        viscosity: true,
        velocity_gradient: false,
        density_rate: false,
        shift: false,
        implicit: false,
        pressure_solve: false,
    };
    type Law = Rh;
    fn law(&self) -> Self::Law {
        self.0
    }
    type Gradient = KernelSum;
    fn accelerations<T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: ParticleState<'_, R, N>,
    ) -> Option<SolveReport> {
        let viscosity = s.viscosity.expect("the shear-thinning Morris operator allocates viscosity");
        backend.shear_viscosity(ShearViscosityArgs {
            neighborhood: s.neighborhood,
            fluid: s.fluid,
            rheology: self.0,
            velocity: s.velocity,
            density: s.density,
            viscosity,
        });
        backend.acceleration(s.acceleration_args(MorrisViscosity { velocity: s.velocity, viscosity: viscosity.read() }));
        None
    }
}
