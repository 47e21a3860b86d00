//! The physics variant a scene asks for, picked once outside every particle loop: an explicit
//! model (`model`) or a solved viscosity (`implicit_weiler2018`), in the scene's precision.

use crate::scene::{Precision, Scene, VelocityGradient, Viscosity, ViscosityOperator, ViscositySolver};
use crate::simulation::implicit_weiler2018::{ImplicitModel, MorrisOperator, ShearThinningMorrisOperator, StressOperator};
use crate::simulation::model::{
    cross_law, HourglassStressModel, LaplacianModel, Model, MorrisModel, ShearThinningMorrisModel, StressModel,
};
use coil_kernels::cross_viscosity::Newtonian;
use coil_kernels::renormalization_bonet1999::Renormalized;
use coil_kernels::velocity_gradient::{KernelSum, OwnDensity};
use coil_kernels::Real;

/// Work done once per physics variant, monomorphised for it (`run`, `check`).
pub trait WithModel {
    type Output;
    fn with<R: Real, M: Model<R>>(self, model: M) -> Self::Output;
}

/// Picks the physics variant of `scene` once, outside every particle loop, and hands it to `work`.
pub fn with_model<R: Real, W: WithModel>(scene: &Scene, work: W) -> W::Output {
    let v = &scene.material.viscosity;
    let nu0 = R::from_f64(v.nu0_m2_s);
    let hourglass = R::from_f64(v.hourglass_control);
    if v.solver == ViscositySolver::Implicit {
        return match (v.operator, v.is_newtonian()) {
            (ViscosityOperator::Morris, true) => work.with::<R, _>(implicit(MorrisOperator(Newtonian { nu0 }), v)),
            (ViscosityOperator::Morris, false) => work.with::<R, _>(implicit(ShearThinningMorrisOperator(cross_law(v)), v)),
            (_, true) => work.with::<R, _>(implicit(StressOperator(Newtonian { nu0 }), v)),
            (_, false) => work.with::<R, _>(implicit(StressOperator(cross_law(v)), v)),
        };
    }
    match (v.operator, v.is_newtonian()) {
        (ViscosityOperator::Stress, true) if v.hourglass_control > 0.0 => {
            work.with::<R, _>(HourglassStressModel { rheology: Newtonian { nu0 }, coefficient: hourglass })
        }
        (ViscosityOperator::Stress, false) if v.hourglass_control > 0.0 => {
            work.with::<R, _>(HourglassStressModel { rheology: cross_law(v), coefficient: hourglass })
        }
        (ViscosityOperator::Laplacian, _) => work.with::<R, _>(LaplacianModel(Newtonian { nu0 })),
        (ViscosityOperator::Morris, true) => work.with::<R, _>(MorrisModel(Newtonian { nu0 })),
        (ViscosityOperator::Morris, false) => work.with::<R, _>(ShearThinningMorrisModel(cross_law(v))),
        (ViscosityOperator::Stress, true) => match v.velocity_gradient {
            VelocityGradient::Sph => work.with::<R, _>(StressModel(Newtonian { nu0 }, KernelSum)),
            VelocityGradient::Renormalized => work.with::<R, _>(StressModel(Newtonian { nu0 }, Renormalized)),
            VelocityGradient::OwnDensity => work.with::<R, _>(StressModel(Newtonian { nu0 }, OwnDensity)),
        },
        (ViscosityOperator::Stress, false) => match v.velocity_gradient {
            VelocityGradient::Sph => work.with::<R, _>(StressModel(cross_law(v), KernelSum)),
            VelocityGradient::Renormalized => work.with::<R, _>(StressModel(cross_law(v), Renormalized)),
            VelocityGradient::OwnDensity => work.with::<R, _>(StressModel(cross_law(v), OwnDensity)),
        },
    }
}

/// Viscosity `v` solved implicitly with `operator`, as the scene sets the solve.
fn implicit<Op>(operator: Op, v: &Viscosity) -> ImplicitModel<Op> {
    ImplicitModel {
        operator,
        tolerance: v.implicit.tolerance,
        max_iterations: v.implicit.max_iterations,
        // A Newtonian fluid's viscosity does not depend on the flow: nothing to read again.
        picard_iterations: if v.is_newtonian() { 0 } else { v.implicit.picard_iterations },
    }
}

/// [`with_model`] in `precision`: the float type and the physics variant, both picked once.
pub fn with_precision_and_model<W: WithModel>(precision: Precision, scene: &Scene, work: W) -> W::Output {
    match precision {
        Precision::F32 => with_model::<f32, _>(scene, work),
        Precision::F64 => with_model::<f64, _>(scene, work),
    }
}
