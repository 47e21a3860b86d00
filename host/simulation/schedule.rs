//! Algorithm 1's step schedule, written once for every backend: density (or the continuity
//! equation's rate), the solves, viscosity, accelerations, nozzles, shifting and leap-frog, in
//! the domain's topology.

use crate::scene::{DensityKernelKind, ViscousVelocity};
use crate::simulation::backend::{Backend, ParticleViews, Passes, Schedule};
use crate::simulation::dfsph_bender2017::PressureSolve;
use crate::simulation::model::Model;
use crate::simulation::model::{ImplicitStep, ParticleState, SolveReport};
use crate::simulation::run_state::RunState;
use coil_kernels::cell_grid::Neighbors;
use coil_kernels::continuity_molteni2009::{ContinuityArgs, DensityIntegrationArgs};
use coil_kernels::density::{DensityArgs, DensityKernel, Poly6, Spiky};
use coil_kernels::leapfrog::LeapfrogArgs;
use coil_kernels::mirrored_wall::MirroredWallArgs;
use coil_kernels::nozzle::{NozzleArgs, NozzleShiftArgs};
use coil_kernels::shifting_sun2017::{ShiftArgs, ShiftingArgs};
use coil_kernels::topology::{Open, Topology};
use coil_kernels::Real;

/// Runs `schedule` on `backend` in the domain's topology: the periodic neighbor loops only where
/// an axis wraps.
pub(super) fn in_topology<R: Real, B: Backend<R>, S: Schedule<R>>(backend: &mut B, schedule: S) -> Result<(), B::Fault> {
    match backend.periodic() {
        Some(periodic) => backend.run(periodic, schedule),
        None => backend.run(Open, schedule),
    }
}

/// Algorithm 1, lines 5-8: density (pressure is evaluated from it where it is read), or, with
/// the continuity equation, the fluid's density rate and the walls' density; where pressure is
/// solved on the continuity density, the walls' density and the fluid's raised to its sum (the
/// density solve predicts the rate).
pub(super) struct DensityPass<'r, R: Real, M: Model<R>> {
    pub(super) run: &'r RunState<R, M>,
}

impl<R: Real, M: Model<R>> Schedule<R> for DensityPass<'_, R, M> {
    fn run<T: Topology, N: Neighbors, P: Passes<R, T, N>>(self, v: ParticleViews<'_, R, T, N>, passes: &mut P) {
        density(self.run, &v, passes);
    }
}

fn density<R: Real, M: Model<R>, T: Topology, N: Neighbors, P: Passes<R, T, N>>(
    run: &RunState<R, M>,
    v: &ParticleViews<'_, R, T, N>,
    passes: &mut P,
) {
    match run.density_kernel {
        DensityKernelKind::Poly6 => density_with::<R, M, Poly6, T, N, P>(run, v, passes),
        DensityKernelKind::Spiky => density_with::<R, M, Spiky, T, N, P>(run, v, passes),
    }
}

fn density_with<R: Real, M: Model<R>, K: DensityKernel, T: Topology, N: Neighbors, P: Passes<R, T, N>>(
    run: &RunState<R, M>,
    v: &ParticleViews<'_, R, T, N>,
    passes: &mut P,
) {
    let density_args = DensityArgs { neighborhood: v.neighbors, fluid: run.fluid, id: v.id, density: v.density };
    match v.density_rate {
        Some(_) if run.pressure_solve.is_some() => passes.continuity_floor(density_args),
        Some(density_rate) => passes.continuity::<K>(ContinuityArgs {
            neighborhood: v.neighbors,
            fluid: run.fluid,
            diffusivity: run.density_diffusivity,
            id: v.id,
            velocity: v.velocity.read(),
            density: v.density,
            density_rate,
        }),
        None => passes.density::<K>(density_args),
    }
}

/// Algorithm 1, lines 5-19: density, mirrored walls (when the scene asks), velocity gradient
/// and stress, accelerations, nozzles and leap-frog.
pub(super) struct ForcesAndMotion<'r, R: Real, M: Model<R>> {
    pub(super) run: &'r RunState<R, M>,
    /// This step (s).
    pub(super) dt: f64,
    /// Leap-frog's kick (s).
    pub(super) kick_dt: f64,
    /// How the implicit viscosity solve went, where there is one.
    pub(super) solve: &'r mut Option<SolveReport>,
    /// How the divergence and density solves went, where pressure is solved.
    pub(super) pressure_solves: &'r mut Option<[SolveReport; 2]>,
}

impl<R: Real, M: Model<R>> Schedule<R> for ForcesAndMotion<'_, R, M> {
    fn run<T: Topology, N: Neighbors, P: Passes<R, T, N>>(self, v: ParticleViews<'_, R, T, N>, passes: &mut P) {
        let run = self.run;
        let fluid = run.fluid;
        // Lines 5-8.
        density(run, &v, passes);
        let pressure_solve = run.pressure_solve.zip(v.pressure_solve).map(|(settings, arrays)| PressureSolve {
            settings,
            neighborhood: v.neighbors,
            fluid,
            dt: R::from_f64(self.dt),
            kick_dt: R::from_f64(self.kick_dt),
            id: v.id,
            position: v.position.read(),
            density: v.density.read(),
            velocity_half: v.velocity_half,
            acceleration: v.acceleration,
            continuity: v.density_rate.is_some(),
            arrays,
            inlets: run.inlets(),
            time: run.time,
        });
        let divergence = pressure_solve.as_ref().map(|solve| {
            solve.factors(passes);
            solve.divergence(passes)
        });
        let viscous_velocity = match run.viscous_velocity {
            ViscousVelocity::FullStep => v.velocity,
            ViscousVelocity::HalfStep => v.velocity_half,
        };
        if let Some(mirror) = v.wall_mirror {
            passes.mirrored_wall(MirroredWallArgs {
                neighborhood: v.grid,
                fluid,
                id: v.id,
                mirror,
                velocity: viscous_velocity,
                density: v.density,
            });
        }
        // Lines 9-16: velocity gradient and stress, accelerations.
        *self.solve = run.model.accelerations(
            passes,
            ParticleState {
                neighborhood: v.neighbors,
                fluid,
                id: v.id,
                velocity: viscous_velocity.read(),
                density: v.density.read(),
                stress: v.stress,
                viscosity: v.viscosity,
                velocity_gradient: v.velocity_gradient,
                acceleration: v.acceleration,
                implicit: v.implicit.map(|arrays| ImplicitStep {
                    kick_dt: R::from_f64(self.kick_dt),
                    velocity_half: v.velocity_half.read(),
                    velocity: viscous_velocity.read(),
                    arrays,
                    position: v.position.read(),
                    inlets: run.inlets(),
                    time: run.time,
                }),
            },
        );
        // Fluid inside a nozzle's tube moves with the jet (paper Sec. III-C; see `nozzle`).
        for tube in run.inlet_tubes() {
            passes.nozzle(NozzleArgs {
                fluid,
                tube,
                id: v.id,
                position: v.position.read(),
                acceleration: v.acceleration,
                velocity_half: v.velocity_half,
            });
        }
        // Pressure last: the density the step ends at counts gravity and viscosity.
        if let (Some(solve), Some(divergence)) = (&pressure_solve, divergence) {
            *self.pressure_solves = Some([divergence, solve.density(passes)]);
        }
        // The continuity equation's density after the accelerations have read this step's;
        // where pressure is solved, the density the solve predicted.
        if let Some(density_rate) = v.density_rate {
            if let Some(solve) = &pressure_solve {
                solve.density_rate(passes, density_rate);
            }
            passes.density_integration(DensityIntegrationArgs {
                fluid,
                dt: R::from_f64(self.dt),
                id: v.id,
                density_rate: density_rate.read(),
                density: v.density,
            });
        }
        // Shifts over this step's positions, which leap-frog is about to move.
        let shift = v.shift.zip(run.shifting);
        if let Some((shift, shifting)) = shift {
            passes.shifting(ShiftingArgs {
                neighborhood: v.neighbors,
                fluid,
                shifting,
                dt: R::from_f64(self.dt),
                id: v.id,
                velocity: v.velocity.read(),
                shift,
            });
            for tube in run.inlet_tubes() {
                passes.nozzle_shift(NozzleShiftArgs { fluid, tube, id: v.id, position: v.position.read(), shift });
            }
        }
        // Lines 17-19: leap-frog.
        passes.leapfrog(LeapfrogArgs {
            fluid,
            dt: R::from_f64(self.dt),
            kick_dt: R::from_f64(self.kick_dt),
            id: v.id,
            acceleration: v.acceleration.read(),
            position: v.position,
            velocity_half: v.velocity_half,
            velocity: v.velocity,
            topology: v.topology,
        });
        if let Some((shift, _)) = shift {
            passes.shift(ShiftArgs { topology: v.topology, shift: shift.read(), position: v.position });
        }
    }
}
