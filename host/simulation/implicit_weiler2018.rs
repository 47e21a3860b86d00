//! The implicit viscosity step (`coil_kernels::viscosity::implicit_weiler2018`): pressure and
//! gravity explicit, then (I - dt A) v = v* solved by preconditioned conjugate gradients, written
//! once over the backend's passes.

use crate::simulation::backend::Passes;
use crate::simulation::model::{ImplicitStep, Model, ModelFields, ParticleState, SolveReport};
use coil_kernels::cell_grid::Neighbors;
use coil_kernels::cross_viscosity::{Newtonian, Rheology};
use coil_kernels::nozzle::{NozzleArgs, NozzleShiftArgs};
use coil_kernels::topology::Topology;
use coil_kernels::velocity_gradient::{GradientEstimate, KernelSum, OwnDensity};
use coil_kernels::view::{Vec3View, Vec3ViewMut, ViewMut};
use coil_kernels::viscosity::implicit_weiler2018::{
    CgDirectionArgs, CgStartArgs, CgStepArgs, DotArgs, ImplicitStressArgs, LaggedViscosityArgs, PredictorArgs,
    PressureAndGravity, SystemBlockArgs, SystemProductArgs, ViscousAccelerationArgs,
};
use coil_kernels::viscosity::laplacian_morris1997::{
    MorrisSystemBlockArgs, MorrisSystemProductArgs, MorrisViscosity, ParticleViscosity, ShearViscosityArgs,
};
use coil_kernels::Real;

/// A viscous operator A the implicit solve can invert: symmetric and negative semidefinite, its
/// viscosity held through a step.
pub trait ImplicitOperator<R: Real>: Copy + Send + Sync + 'static {
    /// Whether it needs each particle's stress and viscosity arrays.
    const STRESS: bool;
    const VISCOSITY: bool;
    /// Its rheology, for the time step and `coil check`.
    type Law: Rheology<R>;
    fn law(&self) -> Self::Law;
    /// Its velocity gradient estimate, for the diagnostics.
    type Gradient: GradientEstimate;
    /// The step's viscosity from the solve's first guess, then the 3x3 diagonal blocks of
    /// I - dt A into the preconditioner.
    fn blocks<T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: &ParticleState<'_, R, N>,
        step: &ImplicitStep<'_, R>,
    );
    /// (I - dt A) `velocity` into the product array.
    fn product<T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: &ParticleState<'_, R, N>,
        step: &ImplicitStep<'_, R>,
        velocity: Vec3View<'_, R>,
    );
}

/// Viscosity integrated by backward Euler with operator `Op`.
#[derive(Clone, Copy, Debug)]
pub struct ImplicitModel<Op> {
    pub operator: Op,
    /// Relative residual at which a solve stops.
    pub tolerance: f64,
    pub max_iterations: u32,
    /// Times a step may read the viscosity again from the solution and solve again.
    pub picard_iterations: u32,
}

impl<R: Real, Op: ImplicitOperator<R>> Model<R> for ImplicitModel<Op> {
    const FIELDS: ModelFields = ModelFields {
        stress: Op::STRESS,
        viscosity: Op::VISCOSITY,
        velocity_gradient: false,
        density_rate: false,
        shift: false,
        implicit: true,
        pressure_solve: false,
    };
    type Law = Op::Law;
    fn law(&self) -> Self::Law {
        self.operator.law()
    }
    type Gradient = Op::Gradient;
    fn accelerations<T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: ParticleState<'_, R, N>,
    ) -> Option<SolveReport> {
        let step = s.implicit.expect("the implicit solve allocates its arrays");
        Some(self.solve(backend, s, step))
    }
}

/// The paper's operator, Eq. (8) at the own density, (2), (3), (9), with rheology `Rh`: two
/// neighbor passes a product, the stress of the velocity and its divergence.
#[derive(Clone, Copy, Debug)]
pub struct StressOperator<Rh>(pub Rh);

impl<R: Real, Rh: Rheology<R> + 'static> ImplicitOperator<R> for StressOperator<Rh> {
    const STRESS: bool = true;
    const VISCOSITY: bool = true;
    type Law = Rh;
    fn law(&self) -> Rh {
        self.0
    }
    type Gradient = OwnDensity;
    fn blocks<T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: &ParticleState<'_, R, N>,
        step: &ImplicitStep<'_, R>,
    ) {
        let viscosity = s.viscosity.expect("the implicit solve allocates viscosity");
        backend.lagged_viscosity(LaggedViscosityArgs {
            neighborhood: s.neighborhood,
            fluid: s.fluid,
            rheology: self.0,
            velocity: step.arrays.solution.read(),
            density: s.density,
            viscosity,
        });
        backend.system_block(SystemBlockArgs {
            neighborhood: s.neighborhood,
            fluid: s.fluid,
            kick_dt: step.kick_dt,
            id: s.id,
            density: s.density,
            viscosity: viscosity.read(),
            block: step.arrays.block,
        });
    }
    fn product<T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: &ParticleState<'_, R, N>,
        step: &ImplicitStep<'_, R>,
        velocity: Vec3View<'_, R>,
    ) {
        let stress = s.stress.expect("the implicit solve allocates stress");
        let viscosity = s.viscosity.expect("the implicit solve allocates viscosity").read();
        backend.implicit_stress(ImplicitStressArgs {
            neighborhood: s.neighborhood,
            fluid: s.fluid,
            velocity,
            density: s.density,
            viscosity,
            stress,
        });
        backend.system_product(SystemProductArgs {
            neighborhood: s.neighborhood,
            fluid: s.fluid,
            kick_dt: step.kick_dt,
            id: s.id,
            stress: stress.read(),
            velocity,
            product: step.arrays.product,
        });
    }
}

/// Morris et al.'s operator (`coil_kernels::viscosity::laplacian_morris1997`) with a constant
/// viscosity: one neighbor pass a product.
#[derive(Clone, Copy, Debug)]
pub struct MorrisOperator<R>(pub Newtonian<R>);

impl<R: Real> ImplicitOperator<R> for MorrisOperator<R> {
    const STRESS: bool = false;
    const VISCOSITY: bool = false;
    type Law = Newtonian<R>;
    fn law(&self) -> Newtonian<R> {
        self.0
    }
    type Gradient = KernelSum;
    fn blocks<T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: &ParticleState<'_, R, N>,
        step: &ImplicitStep<'_, R>,
    ) {
        morris_blocks(backend, s, step, self.0);
    }
    fn product<T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: &ParticleState<'_, R, N>,
        step: &ImplicitStep<'_, R>,
        velocity: Vec3View<'_, R>,
    ) {
        morris_product(backend, s, step, MorrisViscosity { velocity, viscosity: self.0 });
    }
}

/// Morris et al.'s operator with each particle's viscosity from rheology `Rh` at the shear rate
/// of the solve's first guess (Eq. 8, 2, 3), held through the step.
#[derive(Clone, Copy, Debug)]
pub struct ShearThinningMorrisOperator<Rh>(pub Rh);

impl<R: Real, Rh: Rheology<R> + 'static> ImplicitOperator<R> for ShearThinningMorrisOperator<Rh> {
    const STRESS: bool = false;
    const VISCOSITY: bool = true;
    type Law = Rh;
    fn law(&self) -> Rh {
        self.0
    }
    type Gradient = KernelSum;
    fn blocks<T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: &ParticleState<'_, R, N>,
        step: &ImplicitStep<'_, R>,
    ) {
        let viscosity = s.viscosity.expect("the shear-thinning Morris operator allocates viscosity");
        backend.shear_viscosity(ShearViscosityArgs {
            neighborhood: s.neighborhood,
            fluid: s.fluid,
            rheology: self.0,
            velocity: step.arrays.solution.read(),
            density: s.density,
            viscosity,
        });
        morris_blocks(backend, s, step, viscosity.read());
    }
    fn product<T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: &ParticleState<'_, R, N>,
        step: &ImplicitStep<'_, R>,
        velocity: Vec3View<'_, R>,
    ) {
        let viscosity = s.viscosity.expect("the shear-thinning Morris operator allocates viscosity").read();
        morris_product(backend, s, step, MorrisViscosity { velocity, viscosity });
    }
}

fn morris_blocks<R: Real, T: Topology, N: Neighbors, P: Passes<R, T, N>, Nu: ParticleViscosity<R>>(
    backend: &mut P,
    s: &ParticleState<'_, R, N>,
    step: &ImplicitStep<'_, R>,
    viscosity: Nu,
) {
    backend.morris_system_block(MorrisSystemBlockArgs {
        neighborhood: s.neighborhood,
        fluid: s.fluid,
        kick_dt: step.kick_dt,
        id: s.id,
        density: s.density,
        viscosity,
        block: step.arrays.block,
    });
}

fn morris_product<R: Real, T: Topology, N: Neighbors, P: Passes<R, T, N>, Nu: ParticleViscosity<R>>(
    backend: &mut P,
    s: &ParticleState<'_, R, N>,
    step: &ImplicitStep<'_, R>,
    operator: MorrisViscosity<'_, R, Nu>,
) {
    backend.morris_system_product(MorrisSystemProductArgs {
        neighborhood: s.neighborhood,
        fluid: s.fluid,
        kick_dt: step.kick_dt,
        id: s.id,
        density: s.density,
        operator,
        product: step.arrays.product,
    });
}

impl<Op> ImplicitModel<Op> {
    /// One step's accelerations: pressure and gravity, plus the viscous acceleration that takes
    /// the half-step velocity to the solution of (I - dt A) v = v*.
    fn solve<R: Real, T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: ParticleState<'_, R, N>,
        step: ImplicitStep<'_, R>,
    ) -> SolveReport
    where
        Op: ImplicitOperator<R>,
    {
        let (fluid, id, kick_dt) = (s.fluid, s.id, step.kick_dt);
        let x = step.arrays;
        backend.acceleration(s.acceleration_args(PressureAndGravity));
        backend.predictor(PredictorArgs {
            fluid,
            kick_dt,
            id,
            velocity_half: step.velocity_half,
            velocity: step.velocity,
            acceleration: s.acceleration.read(),
            viscous_change: x.viscous_change.read(),
            predicted: x.predicted,
            solution: x.solution,
        });
        // The fluid inside a nozzle's tube moves at the tube's velocity (`coil_kernels::nozzle`),
        // so its rows are fixed values, as boundary rows are: v* and the first guess are the
        // tube's velocity, and the residual, the search direction and the product stay zero
        // there. The nozzle pass after the solve then finds the step it asks for.
        let tubes = || step.tubes();
        for tube in tubes() {
            for velocity in [x.predicted, x.solution] {
                backend.nozzle(NozzleArgs {
                    fluid,
                    tube,
                    id,
                    position: step.position,
                    acceleration: s.acceleration,
                    velocity_half: velocity,
                });
            }
        }
        let fix = |backend: &mut P, vectors: &[Vec3ViewMut<'_, R>]| {
            for tube in tubes() {
                for &shift in vectors {
                    backend.nozzle_shift(NozzleShiftArgs { fluid, tube, id, position: step.position, shift });
                }
            }
        };
        let op = self.operator;
        op.blocks(backend, &s, &step);
        let product = |backend: &mut P, velocity: Vec3View<'_, R>| op.product(backend, &s, &step, velocity);
        let dots = |backend: &mut P, a, b, c, d, partial: ViewMut<'_, [f64; 2]>| backend.dots(DotArgs { a, b, c, d }, partial);
        let start = |backend: &mut P| {
            backend.cg_start(CgStartArgs {
                fluid,
                id,
                predicted: x.predicted.read(),
                product: x.product.read(),
                block: x.block.read(),
                residual: x.residual,
                preconditioned: x.preconditioned,
                direction: x.direction,
            })
        };
        let (r, z, p, ap) = (x.residual.read(), x.preconditioned.read(), x.direction.read(), x.product.read());
        // The tolerance is relative to the residual of v* itself, the velocity change an
        // explicit step would make, not to that of the warm start, which may be far smaller.
        product(backend, x.predicted.read());
        start(backend);
        fix(backend, &[x.residual]);
        let [_, explicit] = dots(backend, r, r, r, r, x.partial_dots);
        let target = self.tolerance * self.tolerance * explicit;
        let (mut iterations, mut picard) = (0, 0);
        let mut rr;
        loop {
            product(backend, x.solution.read());
            start(backend);
            fix(backend, &[x.residual, x.preconditioned, x.direction]);
            let [mut rz, first] = dots(backend, r, z, r, r, x.partial_dots);
            rr = first;
            while rr > target && iterations < self.max_iterations {
                product(backend, p);
                fix(backend, &[x.product]);
                let [curvature, _] = dots(backend, p, ap, p, ap, x.partial_dots);
                if !(curvature > 0.0) {
                    break;
                }
                backend.cg_step(CgStepArgs {
                    alpha: R::from_f64(rz / curvature),
                    direction: p,
                    product: ap,
                    block: x.block.read(),
                    solution: x.solution,
                    residual: x.residual,
                    preconditioned: x.preconditioned,
                });
                let [rz_next, rr_next] = dots(backend, r, z, r, r, x.partial_dots);
                iterations += 1;
                backend.cg_direction(CgDirectionArgs {
                    beta: R::from_f64(rz_next / rz),
                    preconditioned: z,
                    direction: x.direction,
                });
                rz = rz_next;
                rr = rr_next;
            }
            // Picard: the viscosity read again from the solution, and solved again from it,
            // until the solution meets the tolerance at its own viscosity.
            if picard == self.picard_iterations || rr > target || (picard > 0 && first <= target) {
                break;
            }
            picard += 1;
            op.blocks(backend, &s, &step);
        }
        backend.viscous_acceleration(ViscousAccelerationArgs {
            fluid,
            kick_dt,
            id,
            predicted: x.predicted.read(),
            solution: x.solution.read(),
            acceleration: s.acceleration,
            viscous_change: x.viscous_change,
        });
        SolveReport {
            iterations,
            relative_residual: if explicit > 0.0 { (rr / explicit).sqrt() } else { 0.0 },
            converged: rr <= target,
        }
    }
}
