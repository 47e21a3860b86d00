//! The domain, the `[simulation]` table and its solvers, the steps a run takes and its output.

use super::{Check, Checked};
use super::{CFL_FACTOR, MAX_FRAMES, MAX_IMPLICIT_ITERATIONS, MAX_STEPS, MAX_TIME_STEP_S, MIN_TOLERANCE, RELAXATION};
use crate::scene::material::{DensityEquation, DensityKernelKind, Material, MAX_PARTICLE_SHIFTING};
use crate::scene::settings::{DivergenceFree, Pressure, SimulationSettings, ViscousVelocity, Walls};
use crate::scene::{short, Domain, Output};
use crate::time_step::{Cfl, Limit, StabilityBound, TimeStepper};

impl Check<'_> {
    /// `h`: the support radius (m).
    pub(super) fn domain(&self, d: &Domain, m: &Material, h: f64) -> Checked {
        for a in 0..3 {
            if !(d.min_m[a] < d.max_m[a]) || !d.min_m[a].is_finite() || !d.max_m[a].is_finite() {
                return self.fail("domain.max_m", format!("must exceed domain.min_m on every axis (axis {a})"));
            }
        }
        let cells: f64 = (0..3).map(|a| ((d.max_m[a] - d.min_m[a]) / h).ceil().max(1.0)).product();
        if cells > 2.0e8 {
            return self.fail(
                "domain",
                format!("needs {cells:.3e} grid cells of edge h = {h} m; shrink the domain or coarsen the spacing"),
            );
        }
        for a in (0..3).filter(|&a| d.periodic[a]) {
            let length = d.max_m[a] - d.min_m[a];
            if length * (1.0 + coil_kernels::topology::PERIODIC_ROUNDING) < 3.0 * h {
                return self.fail(
                    "domain.periodic",
                    format!(
                        "axis {a} is periodic but the domain is {length} m long along it, less than 3 support radii ({} m)",
                        3.0 * h
                    ),
                );
            }
            let spacings = length / m.particle_spacing_m;
            if (spacings - spacings.round()).abs() > 1e-6 * spacings {
                return self.fail(
                    "domain.periodic",
                    format!(
                        "axis {a} is periodic, so its length {length} m must be a whole number of particle spacings ({} m) for the lattice to close across the seam; it is {spacings:.4} spacings",
                        m.particle_spacing_m
                    ),
                );
            }
        }
        Ok(())
    }

    /// `h`: the support radius (m).
    pub(super) fn simulation(&self, s: &SimulationSettings, m: &Material, h: f64) -> Checked {
        self.positive("simulation.end_time_s", s.end_time_s)?;
        self.within(
            "simulation.particle_shifting",
            s.particle_shifting,
            (0.0, MAX_PARTICLE_SHIFTING),
            "dimensionless; 0 turns it off, 2 is Skillen et al.'s",
        )?;
        if s.pressure == Pressure::DivergenceFree {
            self.divergence_free(s, m)?;
        }
        self.divergence_free_settings(&s.divergence_free)?;
        let ts = &s.time_step;
        self.positive("simulation.time_step.safety_factor", ts.safety_factor)?;
        if ts.safety_factor > 1.0 && !ts.allow_above_stability_bound {
            return self.fail(
                "simulation.time_step.safety_factor",
                format!(
                    "{} would put dt above the stability bound of Eq. (10); use at most 1, or set \
                     simulation.time_step.allow_above_stability_bound = true to run anyway",
                    ts.safety_factor
                ),
            );
        }
        if let Some(dt) = ts.fixed_s {
            self.positive("simulation.time_step.fixed_s", dt)?;
            let (limit_dt, limit) = stability_bound(s, m, h, m.viscosity.nu0_m2_s).dt();
            if dt > limit_dt && !ts.allow_above_stability_bound {
                return self.fail(
                    "simulation.time_step.fixed_s",
                    format!(
                        "{dt:e} s is above the stability bound of Eq. (10), {limit_dt:.3e} s (set by the {limit}); \
                         above it explicit leap-frog is not known to be stable. Lower it, remove it for the automatic step, or set \
                         simulation.time_step.allow_above_stability_bound = true to run anyway"
                    ),
                );
            }
        }
        self.steps(s, m, h, 0.0)
    }

    /// The steps to the end time at the dt of a run whose fastest particle moves at `speed_m_s`
    /// (m/s) are at most [`MAX_STEPS`]; else the field that makes them so many is named.
    pub(super) fn steps(&self, s: &SimulationSettings, m: &Material, h: f64, speed_m_s: f64) -> Checked {
        let ts = &s.time_step;
        let (dt, limit) = step_at(s, m, h, speed_m_s);
        let steps = s.end_time_s / dt;
        if !(steps <= MAX_STEPS) {
            let field = match limit {
                Limit::Fixed => "simulation.time_step.fixed_s",
                Limit::Cfl => "simulation.divergence_free.cfl_factor",
                Limit::Largest => "simulation.divergence_free.max_time_step_s",
                _ if ts.safety_factor < 1.0 && steps * ts.safety_factor <= MAX_STEPS => "simulation.time_step.safety_factor",
                _ => "simulation.end_time_s",
            };
            return self.fail(
                field,
                format!(
                    "the run would need {} steps of at most {} s ({}) to reach simulation.end_time_s = {} s; at most {} can be run",
                    short(steps.ceil()),
                    short(dt),
                    limit,
                    short(s.end_time_s),
                    short(MAX_STEPS)
                ),
            );
        }
        Ok(())
    }

    pub(super) fn divergence_free(&self, s: &SimulationSettings, m: &Material) -> Checked {
        if m.density_equation == DensityEquation::Continuity && m.density_diffusion != 0.0 {
            return self.fail(
                "material.density_diffusion",
                format!(
                    "must be 0 with simulation.pressure = \"divergence_free\": the continuity density then follows the density solve's prediction, which diffusion would move it off (the jets went unstable at the nozzle), got {}",
                    short(m.density_diffusion)
                ),
            );
        }
        if s.walls == Walls::Mirrored && s.time_step.viscous_velocity == ViscousVelocity::HalfStep {
            return self.fail(
                "simulation.time_step.viscous_velocity",
                "mirrored walls write their ghost velocities into the velocity the viscous terms read, and \"divergence_free\" needs the walls' half-step velocity at rest; set it to \"full_step\" or simulation.walls = \"paper\"".into(),
            );
        }
        if m.density_kernel != DensityKernelKind::Spiky {
            return self.fail(
                "simulation.pressure",
                "\"divergence_free\" predicts each density change with the spiky gradient, so the density it corrects must be summed with the spiky kernel (with poly6 a closed channel of fluid at rest blew up within 300 steps); set material.density_kernel = \"spiky\"".into(),
            );
        }
        Ok(())
    }

    /// The pressure solves' settings, checked whichever pressure the scene picks, as the
    /// implicit viscosity's are.
    pub(super) fn divergence_free_settings(&self, d: &DivergenceFree) -> Checked {
        let tolerance = "a fraction of rho0";
        self.within("simulation.divergence_free.density_tolerance", d.density_tolerance, (MIN_TOLERANCE, 0.1), tolerance)?;
        self.within("simulation.divergence_free.divergence_tolerance", d.divergence_tolerance, (MIN_TOLERANCE, 0.1), tolerance)?;
        if !(1..=MAX_IMPLICIT_ITERATIONS).contains(&d.max_iterations) {
            return self.fail(
                "simulation.divergence_free.max_iterations",
                format!("must be from 1 to {MAX_IMPLICIT_ITERATIONS}, got {}", d.max_iterations),
            );
        }
        if d.min_iterations > d.max_iterations {
            return self.fail(
                "simulation.divergence_free.min_iterations",
                format!("must be at most max_iterations ({}), got {}", d.max_iterations, d.min_iterations),
            );
        }
        self.within(
            "simulation.divergence_free.relaxation",
            d.relaxation,
            RELAXATION,
            "dimensionless; Jacobi sweeps diverge above 0.755, and below 0.01 a sweep hardly moves the pressure",
        )?;
        if !(0.0..1.0).contains(&d.chebyshev_radius) {
            return self.fail(
                "simulation.divergence_free.chebyshev_radius",
                format!(
                    "must be at least 0 and below 1 (a spectral radius; 0 sweeps plain Jacobi), got {}",
                    short(d.chebyshev_radius)
                ),
            );
        }
        self.within(
            "simulation.divergence_free.cfl_factor",
            d.cfl_factor,
            CFL_FACTOR,
            "dimensionless, the particle spacings the fastest particle may move in a step",
        )?;
        self.positive("simulation.divergence_free.max_time_step_s", d.max_time_step_s)?;
        self.within("simulation.divergence_free.max_time_step_s", d.max_time_step_s, (0.0, MAX_TIME_STEP_S), "s")
    }

    /// `steps`: the fewest steps the run can take (at its largest dt).
    pub(super) fn output(&self, o: &Output, end_time_s: f64, steps: f64) -> Checked {
        if o.every_s.is_some() && o.every_steps.is_some() {
            return self.fail("output.every_steps", "and output.every_s both given: keep one of them".into());
        }
        if let Some(e) = o.every_s {
            self.positive("output.every_s", e)?;
            if end_time_s / e > MAX_FRAMES {
                return self.fail(
                    "output.every_s",
                    format!(
                        "{} s would write {} frames by simulation.end_time_s = {} s; at most {} may be written",
                        short(e),
                        short((end_time_s / e).floor() + 1.0),
                        short(end_time_s),
                        short(MAX_FRAMES)
                    ),
                );
            }
        }
        if o.every_steps == Some(0) {
            return self.fail("output.every_steps", "must be at least 1".into());
        }
        if let Some(k) = o.every_steps.filter(|&k| steps / k as f64 > MAX_FRAMES) {
            return self.fail(
                "output.every_steps",
                format!(
                    "{k} would write at least {} frames over the run's {} steps or more; at most {} may be written",
                    short((steps / k as f64).floor()),
                    short(steps.ceil()),
                    short(MAX_FRAMES)
                ),
            );
        }
        if o.formats.is_empty() {
            return self.fail("output.formats", "must name at least one of \"vtu\", \"ply\", \"xyz\"".into());
        }
        Ok(())
    }
}

/// The dt a run of these settings takes (s) while its fastest particle moves at `speed_m_s`,
/// and what sets it: the fixed dt, or the Eq. (10) bound times the safety factor, or under
/// solved pressure the CFL step. At a speed of 0 it is the largest dt the run takes.
pub(super) fn step_at(s: &SimulationSettings, m: &Material, h: f64, speed_m_s: f64) -> (f64, Limit) {
    match s.time_step.fixed_s {
        Some(dt) => (dt, Limit::Fixed),
        None => {
            let v = &m.viscosity;
            let bound = stability_bound(s, m, h, v.nu0_m2_s.max(v.nu_inf()));
            let cfl = (s.pressure == Pressure::DivergenceFree).then_some(Cfl {
                factor: s.divergence_free.cfl_factor,
                spacing_m: m.particle_spacing_m,
                largest_s: s.divergence_free.max_time_step_s,
            });
            TimeStepper { bound, support_radius: h, safety_factor: s.time_step.safety_factor, fixed: None, cfl }.next(speed_m_s)
        }
    }
}

/// Eq. (10) for the scene, at the largest viscosity `nu` (m^2/s): without its acoustic term
/// where pressure is solved.
fn stability_bound(s: &SimulationSettings, m: &Material, h: f64, nu: f64) -> StabilityBound {
    let bound = StabilityBound::new(h, m.sound_speed_m_s, m.viscosity.bounding_viscosity(nu));
    match s.pressure {
        Pressure::WeaklyCompressible => bound,
        Pressure::DivergenceFree => bound.incompressible(),
    }
}
