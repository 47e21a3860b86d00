//! Structure-of-arrays particle storage, allocated once to the run's capacity.

use std::marker::PhantomData;
use std::ops::{Deref, DerefMut};

use crate::scene::inlet::NewParticles;
use crate::scene::Pressure;
use crate::scene::{DensityEquation, Scene};
use crate::simulation::carried_state::{Carried, Start, VisitCarried};
use crate::simulation::particle_array::ParticleArray;
use coil_kernels::dfsph_bender2017::ERROR_RANGE;
use coil_kernels::view::{Mat3ViewMut, SymTensorViewMut, Vec3View, Vec3ViewMut, View, ViewMut};
use coil_kernels::viscosity::implicit_weiler2018::DOT_RANGE;
use coil_kernels::Real;

/// The per-particle arrays a physics variant needs beyond the particles' state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ModelFields {
    /// Shear stress tau, six components (the paper's operator).
    pub stress: bool,
    /// Kinematic viscosity nu(D) (Morris's operator with a Cross fluid; the paper's operator
    /// with hourglass control).
    pub viscosity: bool,
    /// Velocity gradient, nine components (the paper's operator with hourglass control).
    pub velocity_gradient: bool,
    /// d rho / dt, where density comes from the continuity equation; density then carries
    /// state from step to step.
    pub density_rate: bool,
    /// Each fluid particle's shift in this step, where the scene shifts particles.
    pub shift: bool,
    /// The implicit viscosity solve's vectors and preconditioner blocks.
    pub implicit: bool,
    /// The divergence-free pressure solves' factors, stiffnesses and errors.
    pub pressure_solve: bool,
}

impl ModelFields {
    /// These fields with what `scene` adds to its model's: the density rate where density
    /// comes from the continuity equation, the shift where particles are shifted.
    pub fn with_scene(self, scene: &Scene) -> Self {
        Self {
            density_rate: scene.material.density_equation == DensityEquation::Continuity,
            shift: scene.simulation.particle_shifting > 0.0,
            pressure_solve: scene.simulation.pressure == Pressure::DivergenceFree,
            ..self
        }
    }
}

/// The implicit viscosity solve's per-particle arrays (`coil_kernels::viscosity::implicit_weiler2018`).
pub struct ImplicitArrays<R> {
    /// The last step's viscous change of velocity v - v* (m/s): the next solve's warm start,
    /// state that the sort reorders and checkpoints keep.
    pub viscous_change: [ParticleArray<R>; 3],
    /// v* (m/s).
    pub predicted: [ParticleArray<R>; 3],
    /// The solve's iterate, the new half-step velocity (m/s).
    pub solution: [ParticleArray<R>; 3],
    pub residual: [ParticleArray<R>; 3],
    pub preconditioned: [ParticleArray<R>; 3],
    pub direction: [ParticleArray<R>; 3],
    /// (I - dt A) times the search direction.
    pub product: [ParticleArray<R>; 3],
    /// Diagonal blocks of I - dt A: xx, yy, zz, xy, xz, yz.
    pub block: [ParticleArray<R>; 6],
    /// One pair of partial dot products per range of `DOT_RANGE` particles.
    pub partial_dots: ParticleArray<[f64; 2]>,
}

impl<R: Real> ImplicitArrays<R> {
    /// Seven vectors and a symmetric block per particle (the partial dots, one pair per
    /// `DOT_RANGE` particles, add a sixteenth of a byte).
    pub const BYTES_PER_PARTICLE: usize = (7 * 3 + 6) * std::mem::size_of::<R>();

    pub fn with_capacity(capacity: usize) -> Self {
        let v3 = || core::array::from_fn(|_| zeros(capacity));
        Self {
            viscous_change: v3(),
            predicted: v3(),
            solution: v3(),
            residual: v3(),
            preconditioned: v3(),
            direction: v3(),
            product: v3(),
            block: core::array::from_fn(|_| zeros(capacity)),
            partial_dots: zeros(capacity.div_ceil(DOT_RANGE)),
        }
    }

    /// The arrays as views over the first `n` particles.
    pub fn views(&mut self, n: usize) -> ImplicitViews<'_, R> {
        ImplicitViews {
            viscous_change: vec3_view_mut(&mut self.viscous_change, n),
            predicted: vec3_view_mut(&mut self.predicted, n),
            solution: vec3_view_mut(&mut self.solution, n),
            residual: vec3_view_mut(&mut self.residual, n),
            preconditioned: vec3_view_mut(&mut self.preconditioned, n),
            direction: vec3_view_mut(&mut self.direction, n),
            product: vec3_view_mut(&mut self.product, n),
            block: stress_view_mut(&mut self.block, n),
            partial_dots: view_mut(&mut self.partial_dots, n.div_ceil(DOT_RANGE)),
        }
    }
}

/// The divergence-free pressure solves' per-particle arrays (`coil_kernels::dfsph_bender2017`).
pub struct PressureArrays<R> {
    /// alpha_i (m^5/kg).
    pub factor: ParticleArray<R>,
    /// This sweep's stiffness p / rho^2 (m^5/(kg s^2)).
    pub stiffness: ParticleArray<R>,
    /// This sweep's density error (kg/m^3).
    pub error: ParticleArray<R>,
    /// The last step's stiffness sums of the divergence and the density solve, each solve's
    /// warm start: state that the sort reorders and checkpoints keep. rho^2 times the density
    /// solve's is the pressure the frames show.
    pub stiffness_sums: [ParticleArray<R>; 2],
    /// One pair (error sum, fluid count) per range of `ERROR_RANGE` particles.
    pub partial_sums: ParticleArray<[f64; 2]>,
}

impl<R: Real> PressureArrays<R> {
    /// Five scalars per particle (the partial sums, one pair per `ERROR_RANGE` particles, add a
    /// sixteenth of a byte).
    pub const BYTES_PER_PARTICLE: usize = 5 * std::mem::size_of::<R>();

    pub fn with_capacity(capacity: usize) -> Self {
        Self {
            factor: zeros(capacity),
            stiffness: zeros(capacity),
            error: zeros(capacity),
            stiffness_sums: [zeros(capacity), zeros(capacity)],
            partial_sums: zeros(capacity.div_ceil(ERROR_RANGE)),
        }
    }

    /// The arrays as views over the first `n` particles.
    pub fn views(&mut self, n: usize) -> PressureViews<'_, R> {
        let [divergence_sum, density_sum] = &mut self.stiffness_sums;
        PressureViews {
            factor: view_mut(&mut self.factor, n),
            stiffness: view_mut(&mut self.stiffness, n),
            error: view_mut(&mut self.error, n),
            divergence_sum: view_mut(divergence_sum, n),
            density_sum: view_mut(density_sum, n),
            partial_sums: view_mut(&mut self.partial_sums, n.div_ceil(ERROR_RANGE)),
        }
    }
}

/// Every per-particle array of a run. Arrays hold `capacity` entries; the first `len` are live.
/// Boundary particles come first by id (ids below `boundary_count`), but after the first sort
/// they are interleaved with the fluid in cell order.
pub struct Particles<R> {
    len: usize,
    capacity: usize,
    /// Position (m), f64 in both precisions (see `leapfrog`).
    pub position: [ParticleArray<f64>; 3],
    /// Velocity at the full step (m/s).
    pub velocity: [ParticleArray<R>; 3],
    /// Velocity at the half step (m/s).
    pub velocity_half: [ParticleArray<R>; 3],
    /// Stable particle identity, kept through sorting.
    pub id: ParticleArray<u32>,
    /// Density (kg/m^3).
    pub density: ParticleArray<R>,
    /// Acceleration (m/s^2).
    pub acceleration: [ParticleArray<R>; 3],
    /// Shear stress tau (Pa): xx, yy, zz, xy, xz, yz. Allocated only for the paper's operator.
    pub stress: Option<[ParticleArray<R>; 6]>,
    /// Kinematic viscosity nu(D) (m^2/s). Allocated only for Morris's operator with a Cross
    /// fluid and for the paper's operator with hourglass control.
    pub viscosity: Option<ParticleArray<R>>,
    /// Velocity gradient grad v (1/s) by rows, `[a][b]` = d v_a / d x_b. Allocated only for the
    /// paper's operator with hourglass control.
    pub velocity_gradient: Option<[[ParticleArray<R>; 3]; 3]>,
    /// d rho / dt (kg/(m^3 s)). Allocated only where density comes from the continuity
    /// equation.
    pub density_rate: Option<ParticleArray<R>>,
    /// This step's shift (m), computed over the step's positions and applied after leap-frog.
    /// Allocated only where the scene shifts particles.
    pub shift: Option<[ParticleArray<R>; 3]>,
    /// The implicit viscosity solve's arrays, scratch within a step. Allocated only where
    /// viscosity is solved implicitly.
    pub implicit: Option<ImplicitArrays<R>>,
    /// The pressure solves' arrays, scratch within a step. Allocated only where pressure is
    /// solved for a divergence-free flow.
    pub pressure_solve: Option<PressureArrays<R>>,
    /// Targets of the reorder, swapped with the field they receive.
    pub(crate) scratch_f64: ParticleArray<f64>,
    pub(crate) scratch_real: ParticleArray<R>,
    pub(crate) scratch_u32: ParticleArray<u32>,
}

fn zeros<T: Clone + Default>(n: usize) -> ParticleArray<T> {
    ParticleArray::zeros(n)
}

impl<R: Real> Particles<R> {
    pub fn with_capacity(capacity: usize, fields: ModelFields) -> Self {
        Self {
            len: 0,
            capacity,
            position: [zeros(capacity), zeros(capacity), zeros(capacity)],
            velocity: [zeros(capacity), zeros(capacity), zeros(capacity)],
            velocity_half: [zeros(capacity), zeros(capacity), zeros(capacity)],
            id: zeros(capacity),
            density: zeros(capacity),
            acceleration: [zeros(capacity), zeros(capacity), zeros(capacity)],
            stress: fields.stress.then(|| core::array::from_fn(|_| zeros(capacity))),
            viscosity: fields.viscosity.then(|| zeros(capacity)),
            velocity_gradient: fields
                .velocity_gradient
                .then(|| core::array::from_fn(|_| core::array::from_fn(|_| zeros(capacity)))),
            density_rate: fields.density_rate.then(|| zeros(capacity)),
            shift: fields.shift.then(|| core::array::from_fn(|_| zeros(capacity))),
            implicit: fields.implicit.then(|| ImplicitArrays::with_capacity(capacity)),
            pressure_solve: fields.pressure_solve.then(|| PressureArrays::with_capacity(capacity)),
            scratch_f64: zeros(capacity),
            scratch_real: zeros(capacity),
            scratch_u32: zeros(capacity),
        }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn capacity(&self) -> usize {
        self.capacity
    }

    pub(crate) fn set_len(&mut self, len: usize) {
        assert!(len <= self.capacity);
        self.len = len;
    }

    /// Appends a particle; its carried arrays start as `carried_state::Start` says (its
    /// density is the density pass's to set, or, where density comes from the continuity
    /// equation, the caller's). The caller keeps within capacity (budgets are checked before
    /// injection).
    pub fn push(&mut self, id: u32, position: [f64; 3], velocity: [f64; 3]) {
        assert!(self.len < self.capacity, "particle capacity {} exceeded", self.capacity);
        let i = self.len;
        for a in 0..3 {
            self.acceleration[a][i] = R::ZERO;
        }
        crate::visit_carried!(mut &mut NewParticle::<R> { i, id, position, velocity, real: PhantomData }; self);
        self.len += 1;
    }

    /// The optional arrays allocated.
    pub fn fields(&self) -> ModelFields {
        ModelFields {
            stress: self.stress.is_some(),
            viscosity: self.viscosity.is_some(),
            velocity_gradient: self.velocity_gradient.is_some(),
            density_rate: self.density_rate.is_some(),
            shift: self.shift.is_some(),
            implicit: self.implicit.is_some(),
            pressure_solve: self.pressure_solve.is_some(),
        }
    }

    /// Whether density carries state from step to step (the continuity equation), so that the
    /// sort reorders it.
    pub fn density_is_state(&self) -> bool {
        self.density_rate.is_some()
    }

    /// Bytes allocated per particle of capacity.
    pub fn bytes_per_particle(&self) -> usize {
        Self::bytes_per_particle_with(self.fields())
    }

    /// Bytes each particle takes in a run whose model allocates `fields`.
    pub fn bytes_per_particle_with(fields: ModelFields) -> usize {
        let r = std::mem::size_of::<R>();
        let position = 3 * 8;
        let velocities_and_acceleration = 3 * 3 * r;
        let stress = if fields.stress { 6 * r } else { 0 };
        let viscosity = if fields.viscosity { r } else { 0 };
        let gradient = if fields.velocity_gradient { 9 * r } else { 0 };
        let density_rate = if fields.density_rate { r } else { 0 };
        let shift = if fields.shift { 3 * r } else { 0 };
        let implicit = if fields.implicit { ImplicitArrays::<R>::BYTES_PER_PARTICLE } else { 0 };
        let pressure_solve = if fields.pressure_solve { PressureArrays::<R>::BYTES_PER_PARTICLE } else { 0 };
        let scratch = 8 + r + 4;
        position
            + velocities_and_acceleration
            + 4
            + r
            + stress
            + viscosity
            + gradient
            + density_rate
            + shift
            + implicit
            + pressure_solve
            + scratch
    }

    pub fn position_view(&self) -> Vec3View<'_, f64> {
        vec3_view(&self.position, self.len)
    }

    pub fn velocity_view(&self) -> Vec3View<'_, R> {
        vec3_view(&self.velocity, self.len)
    }

    pub fn density_view(&self) -> View<'_, R> {
        View::new(&self.density[..self.len])
    }

    pub fn id_view(&self) -> View<'_, u32> {
        View::new(&self.id[..self.len])
    }
}

impl<R: Real> NewParticles for Particles<R> {
    fn add(&mut self, id: u32, position: [f64; 3], velocity: [f64; 3], density: f64) {
        self.push(id, position, velocity);
        self.density[self.len - 1] = R::from_f64(density);
    }
}

/// Writes a new particle's entry `i` of every carried array.
struct NewParticle<R> {
    i: usize,
    id: u32,
    position: [f64; 3],
    velocity: [f64; 3],
    real: PhantomData<R>,
}

impl<R> NewParticle<R> {
    /// Component `a` of an array that starts as `start`; `None` where the inlet sets it. Every
    /// start is exact in f64 (ids are below 2^32).
    fn value(&self, start: Start, a: usize) -> Option<f64> {
        match start {
            Start::Position => Some(self.position[a]),
            Start::Velocity => Some(self.velocity[a]),
            Start::Id => Some(f64::from(self.id)),
            Start::Zero => Some(0.0),
            Start::Inlet => None,
        }
    }

    fn write<T>(&self, start: Start, components: &mut [ParticleArray<T>], from: impl Fn(f64) -> T) {
        for (a, c) in components.iter_mut().enumerate() {
            if let Some(v) = self.value(start, a) {
                c[self.i] = from(v);
            }
        }
    }
}

impl<'a, R: Real> VisitCarried<&'a mut [ParticleArray<f64>], &'a mut [ParticleArray<R>], &'a mut [ParticleArray<u32>]>
    for NewParticle<R>
{
    fn wide(&mut self, array: Carried, components: &'a mut [ParticleArray<f64>]) {
        self.write(array.start, components, |v| v);
    }
    fn real(&mut self, array: Carried, components: &'a mut [ParticleArray<R>]) {
        self.write(array.start, components, R::from_f64);
    }
    fn index(&mut self, array: Carried, components: &'a mut [ParticleArray<u32>]) {
        self.write(array.start, components, |v| v as u32);
    }
}

pub fn vec3_view<T: Copy, A: Deref<Target = [T]>>(a: &[A; 3], len: usize) -> Vec3View<'_, T> {
    Vec3View::new(&a[0][..len], &a[1][..len], &a[2][..len])
}

pub fn vec3_view_mut<T: Copy, A: DerefMut<Target = [T]>>(a: &mut [A; 3], len: usize) -> Vec3ViewMut<'_, T> {
    let [x, y, z] = a;
    Vec3ViewMut::new(&mut x[..len], &mut y[..len], &mut z[..len])
}

pub fn view_mut<T: Copy>(a: &mut [T], len: usize) -> ViewMut<'_, T> {
    ViewMut::new(&mut a[..len])
}

pub fn stress_view_mut<R: Copy>(s: &mut [ParticleArray<R>; 6], n: usize) -> SymTensorViewMut<'_, R> {
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

pub fn mat3_view_mut<R: Copy>(m: &mut [[ParticleArray<R>; 3]; 3], n: usize) -> Mat3ViewMut<'_, R> {
    let [x, y, z] = m;
    Mat3ViewMut { rows: [vec3_view_mut(x, n), vec3_view_mut(y, n), vec3_view_mut(z, n)] }
}

/// The implicit viscosity solve's arrays as views (`coil_kernels::viscosity::implicit_weiler2018`).
#[derive(Clone, Copy)]
pub struct ImplicitViews<'a, R> {
    /// The last step's v - v*, carried from step to step (m/s).
    pub viscous_change: Vec3ViewMut<'a, R>,
    pub predicted: Vec3ViewMut<'a, R>,
    pub solution: Vec3ViewMut<'a, R>,
    pub residual: Vec3ViewMut<'a, R>,
    pub preconditioned: Vec3ViewMut<'a, R>,
    pub direction: Vec3ViewMut<'a, R>,
    pub product: Vec3ViewMut<'a, R>,
    pub block: SymTensorViewMut<'a, R>,
    /// One entry per range of `DOT_RANGE` particles.
    pub partial_dots: ViewMut<'a, [f64; 2]>,
}

/// The divergence-free pressure solves' arrays as views (`coil_kernels::dfsph_bender2017`).
#[derive(Clone, Copy)]
pub struct PressureViews<'a, R> {
    pub factor: ViewMut<'a, R>,
    pub stiffness: ViewMut<'a, R>,
    pub error: ViewMut<'a, R>,
    /// The divergence solve's stiffness sums, carried from step to step.
    pub divergence_sum: ViewMut<'a, R>,
    /// The density solve's stiffness sums, carried from step to step: p / rho^2.
    pub density_sum: ViewMut<'a, R>,
    /// One entry per range of `ERROR_RANGE` particles.
    pub partial_sums: ViewMut<'a, [f64; 2]>,
}
