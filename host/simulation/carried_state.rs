//! The state a step carries to the next, declared once: [`crate::visit_carried!`] lists every array
//! whose values a step reads from the step before. The CPU's sort, the device's upload, sort,
//! inlet append and download, a new particle's start and the checkpoint all follow that list,
//! so an array added to it is reordered, copied and kept everywhere, and a storage that lacks
//! it does not compile.
//!
//! Everything else a particle has (acceleration, stress, the solves' scratch vectors) is
//! recomputed by the next step before it is read.

/// One carried array: what it holds and how it is kept.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Carried {
    /// What it holds, for messages ("the particles' positions").
    pub what: &'static str,
    /// Whether every run reads it from the step before.
    pub state: State,
    /// What a particle an inlet adds starts with.
    pub start: Start,
    /// The checkpoint format version that first kept it (`run::checkpoint`).
    pub since: u32,
}

/// Which runs read an array from the step before.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum State {
    /// Every run that allocates it.
    Always,
    /// Runs that integrate density (the continuity equation); others recompute it each step
    /// from positions, and the sort leaves it alone.
    WithDensityRate,
}

/// What an array holds for a particle an inlet adds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Start {
    /// The particle's position, by axis.
    Position,
    /// The particle's velocity, by axis.
    Velocity,
    /// The particle's id.
    Id,
    /// Zero: no history yet.
    Zero,
    /// What the inlet sets after the particle is added.
    Inlet,
}

impl Carried {
    /// Whether a run whose particles allocate a density rate (`density_rate`) reads this array
    /// from the step before.
    pub fn is_state(self, density_rate: bool) -> bool {
        match self.state {
            State::Always => true,
            State::WithDensityRate => density_rate,
        }
    }
}

/// What is done with each carried array of one storage, by element type: wide (`f64`
/// positions), real (the run's precision) and index (`u32` ids). An array comes with all its
/// components (axes, sums) as a slice, shared or mutable as the visit asks: `W`, `X` and `I` are
/// the slice references.
pub trait VisitCarried<W, X, I> {
    fn wide(&mut self, array: Carried, components: W);
    fn real(&mut self, array: Carried, components: X);
    fn index(&mut self, array: Carried, components: I);
    /// An array only some runs allocate: `None` where this one does not.
    fn real_where(&mut self, array: Carried, components: Option<X>) {
        if let Some(components) = components {
            self.real(array, components);
        }
    }
}

/// What is done with each carried array of two storages side by side (a device's and the
/// host's, say), as [`VisitCarried`].
pub trait VisitCarriedPair<W, X, I, W2, X2, I2> {
    fn wide(&mut self, array: Carried, a: W, b: W2);
    fn real(&mut self, array: Carried, a: X, b: X2);
    fn index(&mut self, array: Carried, a: I, b: I2);
    /// An array only some runs allocate, visited where both storages hold it (a storage's
    /// arrays follow the run's fields, so both hold it or neither does).
    fn real_where(&mut self, array: Carried, a: Option<X>, b: Option<X2>) {
        if let (Some(a), Some(b)) = (a, b) {
            self.real(array, a, b);
        }
    }
}

/// Calls the visitor `$visit` (a `&mut` to a [`VisitCarried`], or to a [`VisitCarriedPair`]
/// with two storages) once for every carried array of the storages `$storage`, in the
/// checkpoint's order, each array's components borrowed `mut` or `ref` as the first word says.
/// A storage names its arrays as `Particles` does: `position`, `velocity`, `velocity_half`,
/// `id`, `density`, and `implicit.viscous_change` and `pressure_solve.stiffness_sums` in its
/// optional solves' arrays.
///
/// This is the one list of the carried state.
#[macro_export]
macro_rules! visit_carried {
    (mut $visit:expr; $($storage:expr),+ $(,)?) => {
        $crate::visit_carried!(@list carried_mut, as_mut, from_mut; $visit; $($storage),+)
    };
    (ref $visit:expr; $($storage:expr),+ $(,)?) => {
        $crate::visit_carried!(@list carried_ref, as_ref, from_ref; $visit; $($storage),+)
    };
    (@list $take:ident, $optional:ident, $one:ident; $visit:expr; $($storage:expr),+) => {{
        // Whichever of the two the visitor is.
        #[allow(unused_imports)]
        use $crate::simulation::carried_state::{Carried, Start, State, VisitCarried as _, VisitCarriedPair as _};
        let visit = $visit;
        visit.wide(
            Carried { what: "the particles' positions", state: State::Always, start: Start::Position, since: 1 },
            $($crate::$take!($storage.position[..])),+
        );
        visit.real(
            Carried { what: "the particles' velocities", state: State::Always, start: Start::Velocity, since: 1 },
            $($crate::$take!($storage.velocity[..])),+
        );
        visit.real(
            Carried { what: "the half-step velocities", state: State::Always, start: Start::Velocity, since: 1 },
            $($crate::$take!($storage.velocity_half[..])),+
        );
        visit.index(
            Carried { what: "the particles' ids", state: State::Always, start: Start::Id, since: 1 },
            $(::core::slice::$one($crate::$take!($storage.id))),+
        );
        visit.real(
            Carried { what: "the particles' densities", state: State::WithDensityRate, start: Start::Inlet, since: 1 },
            $(::core::slice::$one($crate::$take!($storage.density))),+
        );
        visit.real_where(
            Carried { what: "the implicit viscosity solve's state", state: State::Always, start: Start::Zero, since: 4 },
            $($storage.implicit.$optional().map(|s| $crate::$take!(s.viscous_change[..]))),+
        );
        visit.real_where(
            Carried { what: "the pressure solves' state", state: State::Always, start: Start::Zero, since: 5 },
            $($storage.pressure_solve.$optional().map(|s| $crate::$take!(s.stiffness_sums[..]))),+
        );
    }};
}

/// `&mut` the place: [`visit_carried!`]'s `mut` borrow.
#[doc(hidden)]
#[macro_export]
macro_rules! carried_mut {
    ($place:expr) => {
        &mut $place
    };
}

/// `&` the place: [`visit_carried!`]'s `ref` borrow.
#[doc(hidden)]
#[macro_export]
macro_rules! carried_ref {
    ($place:expr) => {
        &$place
    };
}
