//! The implicit viscosity step (`coil_kernels::viscosity::implicit_weiler2018`): pressure and
//! gravity explicit, then (I - dt A) v = v* solved by preconditioned conjugate gradients, written
//! once over the backend's passes.

use crate::simulation::backend::Passes;
use crate::simulation::model::{ImplicitStep, Model, ModelFields, ParticleState, SolveReport};
use coil_kernels::cell_grid::Neighbors;
use coil_kernels::cross_viscosity::Rheology;
use coil_kernels::topology::Topology;
use coil_kernels::velocity_gradient::OwnDensity;
use coil_kernels::view::{SymTensorViewMut, Vec3View, ViewMut};
use coil_kernels::viscosity::implicit_weiler2018::{
    CgDirectionArgs, CgStartArgs, CgStepArgs, DotArgs, ImplicitStressArgs, LaggedViscosityArgs, PredictorArgs,
    PressureAndGravity, SystemBlockArgs, SystemProductArgs, ViscousAccelerationArgs,
};
use coil_kernels::Real;

/// The paper's operator (Eq. 8 at the own density, 2, 3, 9) with rheology `Rh`, integrated by
/// backward Euler.
#[derive(Clone, Copy, Debug)]
pub struct ImplicitStressModel<Rh> {
    pub rheology: Rh,
    /// Relative residual at which a solve stops.
    pub tolerance: f64,
    pub max_iterations: u32,
}

impl<R: Real, Rh: Rheology<R> + 'static> Model<R> for ImplicitStressModel<Rh> {
    const FIELDS: ModelFields = ModelFields {
        stress: true,
        viscosity: true,
        velocity_gradient: false,
        density_rate: false,
        shift: false,
        implicit: true,
    };
    type Law = Rh;
    fn law(&self) -> Self::Law {
        self.rheology
    }
    type Gradient = OwnDensity;
    fn accelerations<T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: ParticleState<'_, R, N>,
    ) -> Option<SolveReport> {
        let step = s.implicit.expect("the implicit solve allocates its arrays");
        Some(self.solve(backend, s, step))
    }
}

impl<Rh> ImplicitStressModel<Rh> {
    /// One step's accelerations: pressure and gravity, plus the viscous acceleration that takes
    /// the half-step velocity to the solution of (I - dt A) v = v*.
    fn solve<R: Real, T: Topology, N: Neighbors, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        s: ParticleState<'_, R, N>,
        step: ImplicitStep<'_, R>,
    ) -> SolveReport
    where
        Rh: Rheology<R>,
    {
        let (fluid, id, density, kick_dt) = (s.fluid, s.id, s.density, step.kick_dt);
        let x = step.arrays;
        let stress = s.stress.expect("the implicit solve allocates stress");
        let viscosity = s.viscosity.expect("the implicit solve allocates viscosity");
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
        backend.lagged_viscosity(LaggedViscosityArgs {
            neighborhood: s.neighborhood,
            fluid,
            rheology: self.rheology,
            velocity: x.solution.read(),
            density,
            viscosity,
        });
        backend.system_block(SystemBlockArgs {
            neighborhood: s.neighborhood,
            fluid,
            kick_dt,
            id,
            density,
            viscosity: viscosity.read(),
            block: x.block,
        });
        let product = |backend: &mut P, velocity: Vec3View<'_, R>, stress: SymTensorViewMut<'_, R>| {
            backend.implicit_stress(ImplicitStressArgs {
                neighborhood: s.neighborhood,
                fluid,
                velocity,
                density,
                viscosity: viscosity.read(),
                stress,
            });
            backend.system_product(SystemProductArgs {
                neighborhood: s.neighborhood,
                fluid,
                kick_dt,
                id,
                density,
                stress: stress.read(),
                velocity,
                product: x.product,
            });
        };
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
        product(backend, x.predicted.read(), stress);
        start(backend);
        let [_, explicit] = dots(backend, r, r, r, r, x.partial_dots);
        product(backend, x.solution.read(), stress);
        start(backend);
        let [mut rz, mut rr] = dots(backend, r, z, r, r, x.partial_dots);
        let target = self.tolerance * self.tolerance * explicit;
        let mut iterations = 0;
        while rr > target && iterations < self.max_iterations {
            product(backend, p, stress);
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
            backend.cg_direction(CgDirectionArgs { beta: R::from_f64(rz_next / rz), preconditioned: z, direction: x.direction });
            rz = rz_next;
            rr = rr_next;
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
