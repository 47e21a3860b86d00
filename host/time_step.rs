//! Choosing dt: the paper's stability bound, Eq. (10), the velocity CFL condition, or a fixed
//! step the user asked for; with divergence-free pressure, the flow's CFL condition and a
//! largest step.

use std::fmt;

/// What limits dt.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Limit {
    /// 0.1 h / c, the acoustic term of Eq. (10).
    Acoustic,
    /// 0.1 h^2 / (8 nu0), the viscous term of Eq. (10).
    Viscous,
    /// 0.1 h / max |v|, the velocity CFL condition.
    Velocity,
    /// The scene's fixed dt.
    Fixed,
    /// cfl_factor s / max |v|, the divergence-free pressure's CFL condition.
    Cfl,
    /// The scene's largest dt under divergence-free pressure.
    Largest,
}

impl fmt::Display for Limit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Limit::Acoustic => "acoustic term h/c of Eq. (10)",
            Limit::Viscous => "viscous term h^2/(8 nu0) of Eq. (10)",
            Limit::Velocity => "velocity CFL h/|v|max",
            Limit::Fixed => "fixed by the scene",
            Limit::Cfl => "CFL condition s/|v|max",
            Limit::Largest => "largest dt of the scene",
        })
    }
}

impl Limit {
    /// One word for the progress line.
    pub fn short(&self) -> &'static str {
        match self {
            Limit::Acoustic => "acoustic",
            Limit::Viscous => "viscous",
            Limit::Velocity => "velocity",
            Limit::Fixed => "fixed",
            Limit::Cfl => "CFL",
            Limit::Largest => "largest",
        }
    }
}

/// Eq. (10): dt <= 0.1 min(h / c, h^2 / (8 nu0)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StabilityBound {
    /// 0.1 h / c (s).
    pub acoustic_s: f64,
    /// 0.1 h^2 / (8 nu0) (s), with nu0 the largest viscosity of the Cross model.
    pub viscous_s: f64,
}

impl StabilityBound {
    pub fn new(support_radius: f64, sound_speed: f64, max_viscosity: f64) -> Self {
        let h = support_radius;
        Self { acoustic_s: 0.1 * h / sound_speed, viscous_s: 0.1 * h * h / (8.0 * max_viscosity) }
    }

    /// The bound without its acoustic term: pressure solved, not from a sound speed.
    pub fn incompressible(self) -> Self {
        Self { acoustic_s: f64::INFINITY, ..self }
    }

    /// The bound (s) and its limiting term.
    pub fn dt(&self) -> (f64, Limit) {
        if self.acoustic_s <= self.viscous_s {
            (self.acoustic_s, Limit::Acoustic)
        } else {
            (self.viscous_s, Limit::Viscous)
        }
    }
}

/// How a run picks each step's dt.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeStepper {
    pub bound: StabilityBound,
    pub support_radius: f64,
    pub safety_factor: f64,
    pub fixed: Option<f64>,
    /// The CFL condition that replaces the acoustic term under divergence-free pressure.
    pub cfl: Option<Cfl>,
}

/// dt <= min(factor s / max |v|, largest), for divergence-free pressure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cfl {
    pub factor: f64,
    /// The particle spacing s (m).
    pub spacing_m: f64,
    /// The largest dt (s).
    pub largest_s: f64,
}

impl Cfl {
    /// dt (s) at the largest particle speed `max_speed` (m/s), and what limits it.
    pub fn dt(&self, max_speed: f64) -> (f64, Limit) {
        let cfl = self.factor * self.spacing_m / max_speed;
        if cfl < self.largest_s {
            (cfl, Limit::Cfl)
        } else {
            (self.largest_s, Limit::Largest)
        }
    }
}

impl TimeStepper {
    /// dt (s) for the next step, given the largest particle speed (m/s), and what limits it.
    pub fn next(&self, max_speed: f64) -> (f64, Limit) {
        if let Some(dt) = self.fixed {
            return (dt, Limit::Fixed);
        }
        let (bound, limit) = self.bound.dt();
        if let Some(cfl) = self.cfl {
            let (dt, cfl_limit) = cfl.dt(max_speed);
            let bound = self.safety_factor * bound;
            return if dt <= bound { (dt, cfl_limit) } else { (bound, limit) };
        }
        let cfl = if max_speed > 0.0 { 0.1 * self.support_radius / max_speed } else { f64::INFINITY };
        let (dt, limit) = if cfl < bound { (cfl, Limit::Velocity) } else { (bound, limit) };
        (self.safety_factor * dt, limit)
    }
}
