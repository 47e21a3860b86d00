//! The floating-point operations of a step, counted rather than estimated: the step runs once
//! with [`Counted`], an f64 that counts every add, subtract, multiply, divide, square root,
//! exp2 and log2 it does, on the CPU backend, which runs the very kernels the GPU runs. With a
//! device's peak rate this gives the step's arithmetic floor (`coil bench`).

use crate::cpu::simulation::CpuSimulation;
use crate::scene::setup::InitialParticles;
use crate::scene::Scene;
use crate::simulation::model::Model;
use crate::simulation::variant::{with_model, WithModel};
use coil_kernels::real::Real;
use std::cell::Cell;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

thread_local! {
    /// Operations of the physics precision done on this thread.
    static OPERATIONS: Cell<u64> = const { Cell::new(0) };
    /// Neighbor candidates this thread's loops filtered.
    static CANDIDATES: Cell<u64> = const { Cell::new(0) };
}

/// Operations the neighbor loops do in f64 for each candidate, whatever the precision: the
/// distance squared from f64 positions (3 differences, 3 products, 2 sums).
pub const F64_OPERATIONS_PER_CANDIDATE: f64 = 8.0;

/// An f64 that counts its arithmetic on the thread doing it.
#[derive(Clone, Copy, Debug, Default, PartialEq, PartialOrd)]
pub struct Counted(pub f64);

#[inline(always)]
fn tally(n: u64) {
    OPERATIONS.with(|c| c.set(c.get() + n));
}

macro_rules! counted_operator {
    ($trait:ident, $method:ident, $op:tt, $assign_trait:ident, $assign_method:ident) => {
        impl $trait for Counted {
            type Output = Counted;
            #[inline(always)]
            fn $method(self, o: Counted) -> Counted {
                tally(1);
                Counted(self.0 $op o.0)
            }
        }
        impl $assign_trait for Counted {
            #[inline(always)]
            fn $assign_method(&mut self, o: Counted) {
                tally(1);
                self.0 = self.0 $op o.0;
            }
        }
    };
}
counted_operator!(Add, add, +, AddAssign, add_assign);
counted_operator!(Sub, sub, -, SubAssign, sub_assign);
counted_operator!(Mul, mul, *, MulAssign, mul_assign);

impl Div for Counted {
    type Output = Counted;
    #[inline(always)]
    fn div(self, o: Counted) -> Counted {
        tally(1);
        Counted(self.0 / o.0)
    }
}

/// A sign flip, not counted: it is a bit operation on every GPU.
impl Neg for Counted {
    type Output = Counted;
    #[inline(always)]
    fn neg(self) -> Counted {
        Counted(-self.0)
    }
}

impl Real for Counted {
    const ZERO: Self = Counted(0.0);
    const ONE: Self = Counted(1.0);
    const NAME: &'static str = "counted";

    fn from_f64(v: f64) -> Self {
        Counted(v)
    }
    fn to_f64(self) -> f64 {
        self.0
    }
    fn sqrt(self) -> Self {
        tally(1);
        Counted(self.0.sqrt())
    }
    fn exp2(self) -> Self {
        tally(1);
        Counted(self.0.exp2())
    }
    fn log2(self) -> Self {
        tally(1);
        Counted(self.0.log2())
    }
    fn abs(self) -> Self {
        Counted(self.0.abs())
    }
    fn is_finite(self) -> bool {
        self.0.is_finite()
    }
    fn tally_candidates(n: usize) {
        CANDIDATES.with(|c| c.set(c.get() + n as u64));
    }
}

/// The floating-point work of one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepOperations {
    /// Operations in the run's precision (f32 or f64): the physics.
    pub physics: f64,
    /// Neighbor candidates filtered by distance, in f64 whatever the precision.
    pub candidates: f64,
}

impl StepOperations {
    /// The f64 operations of the candidates' filter.
    pub fn filter_f64(&self) -> f64 {
        self.candidates * F64_OPERATIONS_PER_CANDIDATE
    }

    /// Seconds the step takes at least on a device doing `physics_rate` operations a second
    /// in the run's precision and `f64_rate` in f64: every operation at its unit's peak.
    pub fn floor_s(&self, physics_rate: f64, f64_rate: f64) -> f64 {
        self.physics / physics_rate + self.filter_f64() / f64_rate
    }
}

/// Takes and sums what every thread of the pool, and this one, counted.
fn take_counts() -> (u64, u64) {
    let take = || (OPERATIONS.with(|c| c.replace(0)), CANDIDATES.with(|c| c.replace(0)));
    let (mut ops, mut candidates) = take();
    for (o, c) in rayon::broadcast(|_| take()) {
        ops += o;
        candidates += c;
    }
    (ops, candidates)
}

/// Runs `work` and counts the operations it does with [`Counted`], on this thread and on
/// the threads of the current rayon pool.
pub fn counting<T>(work: impl FnOnce() -> T) -> (T, StepOperations) {
    take_counts();
    let value = work();
    let (physics, candidates) = take_counts();
    (value, StepOperations { physics: physics as f64, candidates: candidates as f64 })
}

/// The operations of the second step of `scene` (the first also sets up what later steps
/// reuse): the device's kernels run on the CPU, visiting neighbors through the grid as the
/// device does (`Simulation::for_device`), not through the CPU backend's lists.
pub fn count_step_operations(scene: &Scene, initial: &InitialParticles) -> Result<StepOperations, String> {
    with_model::<Counted, _>(scene, CountStep { scene, initial })
}

struct CountStep<'a> {
    scene: &'a Scene,
    initial: &'a InitialParticles,
}

impl WithModel for CountStep<'_> {
    type Output = Result<StepOperations, String>;
    fn with<R: Real, M: Model<R>>(self, model: M) -> Self::Output {
        let mut sim = CpuSimulation::<R, M>::for_device(self.scene, self.initial, model);
        let step = |sim: &mut CpuSimulation<R, M>| {
            let (dt, limit) = sim.next_dt();
            sim.step_with(dt, limit).map_err(|i| format!("the counted step went unstable: {i}"))
        };
        step(&mut sim)?;
        let (second, operations) = counting(|| step(&mut sim));
        second.map(|()| operations)
    }
}
