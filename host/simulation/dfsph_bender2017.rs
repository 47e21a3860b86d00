//! The divergence-free pressure solves of a step (`coil_kernels::dfsph_bender2017`), written
//! once over the backend's passes: the factors, the divergence solve on the half-step velocity
//! before the model's accelerations, the density solve on the acceleration after them, and,
//! with the continuity density, the density rate the density solve predicts.

use crate::scene::inlet::Inlet;
use crate::scene::DivergenceFree;
use crate::simulation::backend::Passes;
use crate::simulation::model::SolveReport;
use crate::simulation::particles::PressureViews;
use coil_kernels::cell_grid::Neighbors;
use coil_kernels::dfsph_bender2017::{
    DensityErrorArgs, DensityRateArgs, DivergenceErrorArgs, ErrorSumArgs, FactorArgs, PressureChangeArgs, Sweep, WarmStartArgs,
};
use coil_kernels::fluid::Fluid;
use coil_kernels::nozzle::{NozzleArgs, NozzleShiftArgs};
use coil_kernels::topology::Topology;
use coil_kernels::view::{Vec3View, Vec3ViewMut, View, ViewMut};
use coil_kernels::Real;

/// The share of the last step's stiffness that a solve starts from, SPlisHSPlasH's: in a
/// resting tank half and none give the same layer pressures within 0.5 % of rho0 g D, while
/// all of it carries the last step's errors over and reads them 3 % to 60 % low.
const WARM_START_SHARE: f64 = 0.5;

/// The sweeps of a solve that stay plain Jacobi before Chebyshev's weights start. A resting
/// tank's solves meet their tolerance within two sweeps; weighting the second as well (radius
/// 0.85 to 0.97) set its layers 0.09 to 0.4 of rho0 g D off and stirred it.
const PLAIN_SWEEPS: u32 = 2;

/// Chebyshev's weight omega for the update after sweep `sweep` of a solve (Wang 2015, "A
/// Chebyshev semi-iterative approach for accelerating projective and position-based dynamics"),
/// from the last update's `omega`, for sweeps whose spectral radius is `radius`: 1 through
/// [`PLAIN_SWEEPS`], then 2 / (2 - radius^2), then 4 / (4 - radius^2 omega). With radius 0 every
/// weight is exactly 1: plain Jacobi.
fn chebyshev_omega(radius: f64, sweep: u32, omega: f64) -> f64 {
    let radius2 = radius * radius;
    match sweep.cmp(&PLAIN_SWEEPS) {
        std::cmp::Ordering::Less => 1.0,
        std::cmp::Ordering::Equal => 2.0 / (2.0 - radius2),
        std::cmp::Ordering::Greater => 4.0 / (4.0 - radius2 * omega),
    }
}

/// What a solve's sweeps push: `scale` times the pressure acceleration is added to `values`,
/// and the first sweep adds `wall_head` times the walls' hydrostatic head.
#[derive(Clone, Copy)]
struct Target<'v, R> {
    values: Vec3ViewMut<'v, R>,
    scale: R,
    wall_head: R,
}

/// What one step's pressure solves read and write.
pub struct PressureSolve<'a, R, N> {
    pub settings: DivergenceFree,
    pub neighborhood: N,
    pub fluid: Fluid<R>,
    /// The step's drift (s).
    pub dt: R,
    /// The step's kick (s).
    pub kick_dt: R,
    pub id: View<'a, u32>,
    pub position: Vec3View<'a, f64>,
    pub density: View<'a, R>,
    /// v_{n-1/2} (m/s), which the divergence solve corrects.
    pub velocity_half: Vec3ViewMut<'a, R>,
    /// The step's acceleration (m/s^2), which the density solve corrects.
    pub acceleration: Vec3ViewMut<'a, R>,
    /// Whether the density is the continuity equation's, on which the density solve may pull
    /// (`coil_kernels::dfsph_bender2017`); otherwise it is summed and pressure only pushes.
    pub continuity: bool,
    pub arrays: PressureViews<'a, R>,
    /// The run's inlets, whose tubes set the velocity of the fluid inside them.
    pub inlets: &'a [Inlet],
    /// The step's start (s), where the tubes are.
    pub time: f64,
}

impl<R: Real, N: Neighbors> PressureSolve<'_, R, N> {
    /// Each particle's factor, Eq. (8), from this step's positions and densities; none inside
    /// a nozzle's tube.
    pub fn factors<T: Topology, P: Passes<R, T, N>>(&self, backend: &mut P) {
        backend.dfsph_factor(FactorArgs {
            neighborhood: self.neighborhood,
            fluid: self.fluid,
            id: self.id,
            density: self.density,
            factor: self.arrays.factor,
        });
        // The fluid inside a nozzle's tube moves as the pipe imposes it: like a wall, it takes
        // no stiffness of its own and carries none from step to step, and its error, which no
        // sweep can change, does not count.
        let x = self.arrays;
        for inlet in self.inlets {
            backend.nozzle_shift(NozzleShiftArgs {
                fluid: self.fluid,
                tube: inlet.tube(self.time),
                id: self.id,
                position: self.position,
                shift: Vec3ViewMut { x: x.factor, y: x.divergence_sum, z: x.density_sum },
            });
        }
    }

    /// Makes v_{n-1/2} divergence free where it compresses, Eq. (9), to the scene's divergence
    /// tolerance.
    pub fn divergence<T: Topology, P: Passes<R, T, N>>(&self, backend: &mut P) -> SolveReport {
        let x = self.arrays;
        let error = |backend: &mut P, sweep: Sweep<R>| {
            backend.divergence_error(DivergenceErrorArgs {
                neighborhood: self.neighborhood,
                fluid: self.fluid,
                sweep,
                dt: self.dt,
                kick_dt: self.kick_dt,
                id: self.id,
                density: self.density,
                factor: x.factor.read(),
                velocity_half: self.velocity_half.read(),
                stiffness_sum: x.divergence_sum.read(),
                stiffness: x.stiffness,
                error: x.error,
            })
        };
        let target = Target { values: self.velocity_half, scale: self.kick_dt, wall_head: R::ZERO };
        self.sweeps(backend, self.settings.divergence_tolerance, error, target, x.divergence_sum)
    }

    /// Corrects the step's acceleration so that the density the step ends at is rho0, to the
    /// scene's density tolerance.
    pub fn density<T: Topology, P: Passes<R, T, N>>(&self, backend: &mut P) -> SolveReport {
        let x = self.arrays;
        let error = |backend: &mut P, sweep: Sweep<R>| {
            backend.density_error(DensityErrorArgs {
                neighborhood: self.neighborhood,
                fluid: self.fluid,
                sweep,
                dt: self.dt,
                kick_dt: self.kick_dt,
                id: self.id,
                density: self.density,
                factor: x.factor.read(),
                velocity_half: self.velocity_half.read(),
                acceleration: self.acceleration.read(),
                least_stiffness: if self.continuity { R::from_f64(f64::NEG_INFINITY) } else { R::ZERO },
                stiffness_sum: x.density_sum.read(),
                stiffness: x.stiffness,
                error: x.error,
            })
        };
        let target = Target { values: self.acceleration, scale: R::ONE, wall_head: self.fluid.wall_stiffness_share };
        self.sweeps(backend, self.settings.density_tolerance, error, target, x.density_sum)
    }

    /// The continuity equation's density rate over the step as the density solve predicts it,
    /// for the density to end the step where the solve put it.
    pub fn density_rate<T: Topology, P: Passes<R, T, N>>(&self, backend: &mut P, density_rate: ViewMut<'_, R>) {
        backend.dfsph_density_rate(DensityRateArgs {
            neighborhood: self.neighborhood,
            fluid: self.fluid,
            kick_dt: self.kick_dt,
            id: self.id,
            factor: self.arrays.factor.read(),
            velocity_half: self.velocity_half.read(),
            acceleration: self.acceleration.read(),
            density_rate,
        });
    }

    /// Jacobi sweeps, warm started from a share of `stiffness_sum` and weighted by the scene's
    /// `chebyshev_radius`: each pushes `target` with the stiffness change the last error pass
    /// found, at least `min_iterations` times and until the fluid's mean error over rho0 is
    /// within `tolerance`; `stiffness_sum` ends with what was applied.
    fn sweeps<T: Topology, P: Passes<R, T, N>>(
        &self,
        backend: &mut P,
        tolerance: f64,
        error: impl Fn(&mut P, Sweep<R>),
        target: Target<'_, R>,
        stiffness_sum: ViewMut<'_, R>,
    ) -> SolveReport {
        let x = self.arrays;
        let rest_density = self.fluid.rest_density.to_f64();
        let apply = |backend: &mut P, wall_head: R| {
            backend.pressure_change(PressureChangeArgs {
                neighborhood: self.neighborhood,
                fluid: self.fluid,
                id: self.id,
                density: self.density,
                stiffness: x.stiffness.read(),
                wall_head,
                scale: target.scale,
                target: target.values,
                stiffness_sum,
            });
            self.hold_tubes(backend);
        };
        let mean_error = |backend: &mut P, omega: f64| {
            let relaxation = R::from_f64(omega * self.settings.relaxation);
            error(backend, Sweep { relaxation, momentum: R::from_f64(omega - 1.0) });
            let sums = ErrorSumArgs { fluid: self.fluid, id: self.id, error: x.error.read() };
            let [sum, count] = backend.error_sums(sums, x.partial_sums);
            if count > 0.0 {
                sum / count / rest_density
            } else {
                0.0
            }
        };
        let share = R::from_f64(WARM_START_SHARE);
        backend.warm_start(WarmStartArgs { share, stiffness_sum, stiffness: x.stiffness });
        apply(backend, target.wall_head);
        let radius = self.settings.chebyshev_radius;
        let mut omega = 1.0;
        let mut mean = mean_error(backend, omega);
        let mut iterations = 0;
        let (min, max) = (self.settings.min_iterations, self.settings.max_iterations);
        while (mean > tolerance || iterations < min) && iterations < max {
            apply(backend, R::ZERO);
            iterations += 1;
            omega = chebyshev_omega(radius, iterations, omega);
            mean = mean_error(backend, omega);
        }
        SolveReport { iterations, relative_residual: mean, converged: mean <= tolerance }
    }

    /// The fluid inside a nozzle's tube keeps the tube's velocity through the sweeps: its
    /// neighbors see it as the pipe imposes it (`coil_kernels::nozzle`).
    fn hold_tubes<T: Topology, P: Passes<R, T, N>>(&self, backend: &mut P) {
        for inlet in self.inlets {
            backend.nozzle(NozzleArgs {
                fluid: self.fluid,
                tube: inlet.tube(self.time),
                id: self.id,
                position: self.position,
                acceleration: self.acceleration,
                velocity_half: self.velocity_half,
            });
        }
    }
}
