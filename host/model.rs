//! The physics variant of a run, chosen once from the scene: the paper's stress operator with a
//! Newtonian or Cross rheology, or Müller's Laplacian. Each is a type, so the CPU loops and the
//! GPU kernels of a run contain only the physics it uses.

use crate::neighbor_grid::NeighborGrid;
use crate::parallel::launch;
use crate::particles::{vec3_view, vec3_view_mut, view_mut, Particles};
use crate::scene::{Scene, ViscosityOperator};
use coil_kernels::acceleration::{acceleration_pass, AccelerationArgs, StressDivergence, VelocityLaplacian};
use coil_kernels::cross_viscosity::{Cross, Newtonian, Rheology};
use coil_kernels::fluid::Fluid;
use coil_kernels::velocity_gradient::{stress_pass, StressArgs};
use coil_kernels::view::{SymTensorView, SymTensorViewMut, View};
use coil_kernels::Real;

/// A viscosity operator and law, fixed for a run.
pub trait Model<R: Real>: Copy + Send + Sync + 'static {
    /// Whether the run stores a stress tensor per particle.
    const USES_STRESS: bool;
    /// Kinematic viscosity (m^2/s) at a shear rate (1/s), for output.
    fn viscosity(&self, shear_rate: R) -> R;
    /// Largest viscosity the run can reach (m^2/s), for the Eq. (10) bound.
    fn max_viscosity(&self) -> R;
    /// Velocity gradient and stress (when used), then accelerations, for all particles.
    fn accelerations(&self, grid: &NeighborGrid, fluid: &Fluid<R>, p: &mut Particles<R>);
}

/// Work done once per physics variant, monomorphised for it (`run`, `check`).
pub trait WithModel {
    type Output;
    fn with<R: Real, M: Model<R>>(self, model: M) -> Self::Output;
}

/// Picks the physics variant of `scene` once, outside every particle loop, and hands it to `work`.
pub fn with_model<R: Real, W: WithModel>(scene: &Scene, work: W) -> W::Output {
    let v = &scene.material.viscosity;
    let nu0 = R::from_f64(v.nu0_m2_s);
    match (v.operator, v.is_newtonian()) {
        (ViscosityOperator::Laplacian, _) => work.with::<R, _>(LaplacianModel(Newtonian { nu0 })),
        (ViscosityOperator::Stress, true) => work.with::<R, _>(StressModel(Newtonian { nu0 })),
        (ViscosityOperator::Stress, false) => {
            let cross = Cross { nu0, nu_inf: R::from_f64(v.nu_inf()), k: R::from_f64(v.cross_k_s), n: R::from_f64(v.cross_n) };
            work.with::<R, _>(StressModel(cross))
        }
    }
}

/// The paper's operator, Eq. (8), (2), (9), with rheology `Rh`.
#[derive(Clone, Copy, Debug)]
pub struct StressModel<Rh>(pub Rh);

/// Müller et al. 2003's Laplacian operator (Newtonian, nu0).
#[derive(Clone, Copy, Debug)]
pub struct LaplacianModel<R>(pub Newtonian<R>);

fn stress_views<R: Real>(s: &mut [Vec<R>; 6], n: usize) -> SymTensorViewMut<'_, R> {
    let [xx, yy, zz, xy, xz, yz] = s;
    SymTensorViewMut {
        xx: view_mut(xx, n),
        yy: view_mut(yy, n),
        zz: view_mut(zz, n),
        xy: view_mut(xy, n),
        xz: view_mut(xz, n),
        yz: view_mut(yz, n),
    }
}

fn stress_read<R: Real>(s: &[Vec<R>; 6], n: usize) -> SymTensorView<'_, R> {
    SymTensorView {
        xx: View::new(&s[0][..n]),
        yy: View::new(&s[1][..n]),
        zz: View::new(&s[2][..n]),
        xy: View::new(&s[3][..n]),
        xz: View::new(&s[4][..n]),
        yz: View::new(&s[5][..n]),
    }
}

impl<R: Real, Rh: Rheology<R> + 'static> Model<R> for StressModel<Rh> {
    const USES_STRESS: bool = true;
    fn viscosity(&self, shear_rate: R) -> R {
        self.0.viscosity(shear_rate)
    }
    fn max_viscosity(&self) -> R {
        self.0.max_viscosity()
    }
    fn accelerations(&self, grid: &NeighborGrid, fluid: &Fluid<R>, p: &mut Particles<R>) {
        let n = p.len();
        let neighborhood = grid.neighborhood(vec3_view(&p.position, n));
        let mut stress = p.stress.take().expect("the stress operator allocates stress");
        {
            let args = StressArgs {
                neighborhood,
                fluid: *fluid,
                rheology: self.0,
                velocity: vec3_view(&p.velocity, n),
                density: View::new(&p.density[..n]),
                stress: stress_views(&mut stress, n),
            };
            launch(n, |i| stress_pass(i, &args));
        }
        {
            let args = AccelerationArgs {
                neighborhood,
                fluid: *fluid,
                viscous: StressDivergence { stress: stress_read(&stress, n) },
                id: View::new(&p.id[..n]),
                density: View::new(&p.density[..n]),
                acceleration: vec3_view_mut(&mut p.acceleration, n),
            };
            launch(n, |i| acceleration_pass(i, &args));
        }
        p.stress = Some(stress);
    }
}

impl<R: Real> Model<R> for LaplacianModel<R> {
    const USES_STRESS: bool = false;
    fn viscosity(&self, shear_rate: R) -> R {
        self.0.viscosity(shear_rate)
    }
    fn max_viscosity(&self) -> R {
        self.0.max_viscosity()
    }
    fn accelerations(&self, grid: &NeighborGrid, fluid: &Fluid<R>, p: &mut Particles<R>) {
        let n = p.len();
        let neighborhood = grid.neighborhood(vec3_view(&p.position, n));
        let args = AccelerationArgs {
            neighborhood,
            fluid: *fluid,
            viscous: VelocityLaplacian { nu0: self.0.nu0, velocity: vec3_view(&p.velocity, n) },
            id: View::new(&p.id[..n]),
            density: View::new(&p.density[..n]),
            acceleration: vec3_view_mut(&mut p.acceleration, n),
        };
        launch(n, |i| acceleration_pass(i, &args));
    }
}
