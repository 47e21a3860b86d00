//! What a scene's values must mean, checked once at load: one validator per section, each
//! refusing a value with the field named as `--set` spells it.

use super::overrides::Override;
use super::Variant;
use super::{
    short, Boundary, Domain, InletSettings, Material, Nozzle, NozzleMotion, Output, Scene, SceneError, VelocityGradient,
    ViscosityOperator, ViscositySolver,
};
use super::{
    DensityEquation, DensityKernelKind, DivergenceFree, ImplicitViscosity, Precision, Pressure, SimulationSettings,
    ViscousVelocity, Walls, MAX_HOURGLASS_CONTROL, MAX_PARTICLE_SHIFTING,
};
use crate::simulation::time_step::{Cfl, Limit, StabilityBound, TimeStepper};
use toml::Value;

/// Iterations an implicit solve may be allowed: a solve needing more at the chosen dt is
/// better served by a smaller dt.
const MAX_IMPLICIT_ITERATIONS: u32 = 10_000;
/// The most Picard iterations a step may take.
const MAX_PICARD_ITERATIONS: u32 = 100;
/// The smallest tolerance of a solve (the implicit viscosity's, and the pressure solves'): about
/// 8 times f32's epsilon, below which rounding, not the solver, decides when a solve stops.
const MIN_TOLERANCE: f64 = 1e-6;
/// The relaxation of the pressure solves' Jacobi sweeps: above 2 / 2.65 = 0.755 they diverge
/// on a lattice at h = 2 spacings; below 0.01 a sweep moves the pressure a hundredth of the way,
/// and a solve needs hundreds.
const RELAXATION: (f64, f64) = (0.01, 0.75);
/// The CFL factor under solved pressure: at 1 the fastest particle crosses a spacing a step;
/// below 1e-3 a step moves it a thousandth of one, and the run's steps are wasted.
const CFL_FACTOR: (f64, f64) = (1e-3, 1.0);
/// The largest `max_time_step_s` (s): the step that holds while the fluid is at rest.
const MAX_TIME_STEP_S: f64 = 1.0;

/// Rest densities a scene may give (kg/m^3): from a thin gas to past any liquid, so that the
/// pressure c^2 rho0 and the pair terms m / rho^2 stay normal numbers in f32.
pub const REST_DENSITY_KG_M3: (f64, f64) = (1e-3, 1e6);
/// Sound speeds (m/s): the squares in Eq. (6) stay finite and normal in f32 with any rest
/// density above (a micro-channel's flow of 1e-5 m/s is run at c = 2.5e-4 m/s).
pub const SOUND_SPEED_M_S: (f64, f64) = (1e-9, 1e5);
/// Support radii h (m) in f32 and in f64: the kernels' coefficients 315 / (64 pi h^9) and
/// 45 / (pi h^6) stay finite and normal (in f32 the first overflows below h = 5.5e-5 m).
pub const SUPPORT_RADIUS_M_F32: (f64, f64) = (7e-5, 1e3);
pub const SUPPORT_RADIUS_M_F64: (f64, f64) = (1e-9, 1e9);
/// Kinematic viscosities (m^2/s): from below water's to past pitch's.
pub const VISCOSITY_M2_S: (f64, f64) = (1e-9, 1e9);
/// The largest Cross K (s) and rate index n: K times a shear rate stays finite in f32.
pub const MAX_CROSS_K_S: f64 = 1e6;
pub const MAX_CROSS_N: f64 = 100.0;
/// The fastest a scene may start or drive fluid (m/s), and the strongest gravity (m/s^2):
/// beyond anything a liquid does; Mach numbers are `coil check`'s to judge.
pub const MAX_SPEED_M_S: f64 = 1e4;
pub const MAX_GRAVITY_M_S2: f64 = 1e4;
/// The most steps a run may need to reach its end time at its largest dt: about a day at a
/// GPU's 0.1 ms a step.
pub const MAX_STEPS: f64 = 1e9;
/// The most frames a run may write.
pub const MAX_FRAMES: f64 = 1e5;
/// The longest scene name (characters); it names the output folder and the series.
const MAX_NAME_CHARS: usize = 100;

impl Scene {
    /// Refuses a support radius whose kernel coefficients `precision` cannot hold: checked at
    /// load for the scene's precision, and again where a run or check overrides it.
    pub fn check_precision(&self, precision: Precision, file: &str) -> Result<(), SceneError> {
        let (lo, hi, name) = match precision {
            Precision::F32 => (SUPPORT_RADIUS_M_F32.0, SUPPORT_RADIUS_M_F32.1, "f32"),
            Precision::F64 => (SUPPORT_RADIUS_M_F64.0, SUPPORT_RADIUS_M_F64.1, "f64"),
        };
        let h = self.support_radius();
        if h >= lo && h <= hi {
            return Ok(());
        }
        Check { file }.fail(
            "material.particle_spacing_m",
            format!(
                "gives the support radius h = {} m, outside {} to {} m, where the kernels' coefficients stay finite in {name}",
                short(h),
                short(lo),
                short(hi)
            ),
        )
    }

    /// The fastest the scene's fluid can move (m/s) with all the height it can fall turned into
    /// speed: its fastest jet or initial velocity U, and free fall g through the domain's
    /// extent along gravity, sqrt(U^2 + 2 g extent); along a periodic axis the free fall is
    /// left out, so the speed is a lower bound there.
    pub fn fastest_speed(&self) -> f64 {
        let norm = |v: [f64; 3]| v.iter().map(|c| c * c).sum::<f64>().sqrt();
        let start = self
            .inlets
            .iter()
            .map(|i| i.speed_m_s)
            .chain(self.fluid_blocks.iter().map(|b| norm(b.velocity_m_s)))
            .chain(self.fluid_tori.iter().map(|t| norm(t.velocity_m_s)))
            .chain(self.fluid_cylinders.iter().map(|c| norm(c.velocity_m_s)))
            .fold(0.0, f64::max);
        let (g, d) = (self.material.gravity_m_s2, &self.domain);
        let g_norm = norm(g);
        let drop = if g_norm > 0.0 && !(0..3).any(|a| d.periodic[a] && g[a] != 0.0) {
            (0..3).map(|a| g[a].abs() / g_norm * (d.max_m[a] - d.min_m[a])).sum::<f64>()
        } else {
            0.0
        };
        (start * start + 2.0 * g_norm * drop).sqrt()
    }

    /// `given`: the scene as its text reads, before serde filled the fields.
    pub(super) fn validate(&self, given: &toml::Table, file: &str) -> Result<(), SceneError> {
        let check = Check { file };
        let written = Value::try_from(self).map_err(|e| SceneError {
            file: file.into(),
            field: "(scene)".into(),
            reason: format!("cannot be written out: {e}"),
        })?;
        check.array_lengths(given, &written)?;
        check.name("name", &self.name)?;
        check.variants(&self.variants)?;
        check.finite(&written)?;
        check.material(&self.material)?;
        self.check_precision(self.simulation.precision, file)?;
        check.domain(&self.domain, &self.material, self.support_radius())?;
        check.simulation(&self.simulation, &self.material, self.support_radius())?;
        let (dt, _) = step_at(&self.simulation, &self.material, self.support_radius(), 0.0);
        check.output(&self.output, self.simulation.end_time_s, self.simulation.end_time_s / dt)?;
        check.fluid(self)?;
        check.boundaries(&self.boundaries, &self.domain)?;
        check.inlets(self)?;
        // Solved pressure steps by the flow's speed: its steps are counted at the fastest the
        // fluid, checked above, can move.
        if self.simulation.pressure == Pressure::DivergenceFree {
            check.steps(&self.simulation, &self.material, self.support_radius(), self.fastest_speed())?;
        }
        Ok(())
    }
}

/// The file whose values are checked, named in every error.
struct Check<'a> {
    file: &'a str,
}

type Checked = Result<(), SceneError>;

impl Check<'_> {
    fn fail(&self, field: &str, reason: String) -> Checked {
        Err(SceneError { file: self.file.into(), field: field.into(), reason })
    }

    fn positive(&self, field: &str, v: f64) -> Checked {
        if v > 0.0 && v.is_finite() {
            Ok(())
        } else {
            self.fail(field, format!("must be a positive number, got {}", short(v)))
        }
    }

    /// `v` within `range`, whose reason `why` gives.
    fn within(&self, field: &str, v: f64, (lo, hi): (f64, f64), why: &str) -> Checked {
        if v >= lo && v <= hi {
            Ok(())
        } else {
            self.fail(field, format!("must be from {} to {} ({why}), got {}", short(lo), short(hi), short(v)))
        }
    }

    /// A vector's length at most `most`.
    fn magnitude(&self, field: &str, v: [f64; 3], most: f64, what: &str) -> Checked {
        let length = v.iter().map(|c| c * c).sum::<f64>().sqrt();
        if length <= most {
            Ok(())
        } else {
            self.fail(field, format!("{what} of {} is beyond any liquid's; at most {}", short(length), short(most)))
        }
    }

    /// The name becomes the output folder and the series' file name, so it must be a plain file
    /// name: nothing a path could climb out of the output folder with.
    fn name(&self, field: &str, name: &str) -> Checked {
        let plain = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.';
        if name.is_empty() || name.starts_with('.') || !name.chars().all(plain) || name.chars().count() > MAX_NAME_CHARS {
            return self.fail(
                field,
                format!(
                    "must be a plain file name of 1 to {MAX_NAME_CHARS} letters, digits, '_', '-' or '.', not starting with '.', got {name:?}"
                ),
            );
        }
        Ok(())
    }

    /// A variant's name joins the output folder's (`out/<name>-<variant>`), so it is a plain
    /// file name as the scene's is, and it picks one variant, so no two share it; each of its
    /// overrides is a `KEY=VALUE` that `--set` would take.
    fn variants(&self, variants: &[Variant]) -> Checked {
        for (k, v) in variants.iter().enumerate() {
            self.name(&format!("variant[{k}].name"), &v.name)?;
            if let Some(j) = variants[..k].iter().position(|earlier| earlier.name == v.name) {
                return self.fail(
                    &format!("variant[{k}].name"),
                    format!("{:?} is the name of variant[{j}] too; --variant picks one by its name", v.name),
                );
            }
            for given in &v.set {
                Override::parse(given).map_err(|e| SceneError {
                    file: self.file.into(),
                    field: format!("variant[{k}].set"),
                    reason: format!("{given:?}: {}", e.reason),
                })?;
            }
        }
        Ok(())
    }

    /// Refuses an array of `given` longer or shorter than the field of `written` (the scene as
    /// serde writes it back) that it fills: serde fills a fixed-size array from the first
    /// elements and drops the rest.
    fn array_lengths(&self, given: &toml::Table, written: &Value) -> Checked {
        match first_length_mismatch(&Value::Table(given.clone()), written, String::new()) {
            Some((field, got, expected)) => self.fail(&field, format!("must have {expected} elements, got {got}")),
            None => Ok(()),
        }
    }

    /// Every number of `scene` (as serde writes it back) is finite.
    fn finite(&self, scene: &Value) -> Checked {
        match first_non_finite(scene, String::new()) {
            Some((field, v)) => self.fail(&field, format!("must be a finite number, got {v}")),
            None => Ok(()),
        }
    }

    fn material(&self, m: &Material) -> Checked {
        self.within("material.rest_density_kg_m3", m.rest_density_kg_m3, REST_DENSITY_KG_M3, "kg/m^3")?;
        self.within("material.sound_speed_m_s", m.sound_speed_m_s, SOUND_SPEED_M_S, "m/s")?;
        self.positive("material.particle_spacing_m", m.particle_spacing_m)?;
        if !(m.support_radius_factor > 1.0 && m.support_radius_factor <= 4.0) {
            return self.fail(
                "material.support_radius_factor",
                format!(
                    "must be above 1 (walls one spacing away would be invisible) and at most 4; 2 gives about 33 neighbors, got {}",
                    m.support_radius_factor
                ),
            );
        }
        self.magnitude("material.gravity_m_s2", m.gravity_m_s2, MAX_GRAVITY_M_S2, "a gravity")?;
        self.within(
            "material.density_diffusion",
            m.density_diffusion,
            (0.0, 1.0),
            "dimensionless; 0.1 is Molteni and Colagrossi's",
        )?;
        let v = &m.viscosity;
        self.within("material.viscosity.nu0_m2_s", v.nu0_m2_s, VISCOSITY_M2_S, "m^2/s")?;
        self.within("material.viscosity.nu_inf_m2_s", v.nu_inf(), VISCOSITY_M2_S, "m^2/s")?;
        if v.nu_inf() > v.nu0_m2_s {
            return self.fail(
                "material.viscosity.nu_inf_m2_s",
                format!("must not exceed nu0_m2_s ({}): the Cross model is shear-thinning, got {}", v.nu0_m2_s, v.nu_inf()),
            );
        }
        self.within("material.viscosity.cross_k_s", v.cross_k_s, (0.0, MAX_CROSS_K_S), "s; 0 is Newtonian")?;
        self.positive("material.viscosity.cross_n", v.cross_n)?;
        if v.cross_n > MAX_CROSS_N {
            return self.fail("material.viscosity.cross_n", format!("must be at most {MAX_CROSS_N}, got {}", short(v.cross_n)));
        }
        if v.operator == ViscosityOperator::Laplacian && !v.is_newtonian() {
            return self.fail(
                "material.viscosity.operator",
                "the Laplacian operator is Newtonian (nu0 only); set cross_k_s = 0, or use operator = \"morris\" or \"stress\" for a Cross fluid".into(),
            );
        }
        if !(0.0..=MAX_HOURGLASS_CONTROL).contains(&v.hourglass_control) {
            return self.fail(
                "material.viscosity.hourglass_control",
                format!("must be from 0 to {MAX_HOURGLASS_CONTROL}, got {}", v.hourglass_control),
            );
        }
        if v.hourglass_control > 0.0 && v.operator != ViscosityOperator::Stress {
            return self.fail(
                "material.viscosity.hourglass_control",
                "controls the paper's operator (operator = \"stress\"); the Laplacian operators have no odd-even mode to control"
                    .into(),
            );
        }
        if v.velocity_gradient != VelocityGradient::Sph && (v.operator != ViscosityOperator::Stress || v.hourglass_control > 0.0)
        {
            return self.fail(
                "material.viscosity.velocity_gradient",
                "\"renormalized\" and \"own_density\" apply to the paper's operator (operator = \"stress\") without hourglass control"
                    .into(),
            );
        }
        if v.solver == ViscositySolver::Implicit {
            let symmetric = match v.operator {
                ViscosityOperator::Stress => v.velocity_gradient == VelocityGradient::OwnDensity && v.hourglass_control == 0.0,
                ViscosityOperator::Morris => true,
                ViscosityOperator::Laplacian => false,
            };
            if !symmetric {
                return self.fail(
                    "material.viscosity.solver",
                    "\"implicit\" solves the paper's operator with velocity_gradient = \"own_density\" (operator = \"stress\") \
                     or Morris's (operator = \"morris\"), the forms whose matrices are symmetric, as conjugate gradients need; \
                     set one of those, or solver = \"explicit\""
                        .into(),
                );
            }
        }
        self.implicit_viscosity(&v.implicit)
    }

    /// The implicit solve's settings, checked whichever solver the scene picks: a `--set` of
    /// the solver must not bring an unchecked value to life.
    fn implicit_viscosity(&self, i: &ImplicitViscosity) -> Checked {
        if !(i.tolerance >= MIN_TOLERANCE && i.tolerance < 1.0) {
            return self.fail(
                "material.viscosity.implicit.tolerance",
                format!(
                    "must be from {} to below 1 (a fraction of the first residual; 1e-3 is the default, and below {} f32 rounding decides whether a solve converges), got {}",
                    short(MIN_TOLERANCE),
                    short(MIN_TOLERANCE),
                    short(i.tolerance)
                ),
            );
        }
        if !(1..=MAX_IMPLICIT_ITERATIONS).contains(&i.max_iterations) {
            return self.fail(
                "material.viscosity.implicit.max_iterations",
                format!("must be from 1 to {MAX_IMPLICIT_ITERATIONS}, got {}", i.max_iterations),
            );
        }
        if i.picard_iterations > MAX_PICARD_ITERATIONS {
            return self.fail(
                "material.viscosity.implicit.picard_iterations",
                format!("must be from 0 to {MAX_PICARD_ITERATIONS}, got {}", i.picard_iterations),
            );
        }
        Ok(())
    }

    /// `h`: the support radius (m).
    fn domain(&self, d: &Domain, m: &Material, h: f64) -> Checked {
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
    fn simulation(&self, s: &SimulationSettings, m: &Material, h: f64) -> Checked {
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
    fn steps(&self, s: &SimulationSettings, m: &Material, h: f64, speed_m_s: f64) -> Checked {
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

    fn divergence_free(&self, s: &SimulationSettings, m: &Material) -> Checked {
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
    fn divergence_free_settings(&self, d: &DivergenceFree) -> Checked {
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
    fn output(&self, o: &Output, end_time_s: f64, steps: f64) -> Checked {
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

    /// The initial fluid: blocks, tori and cylinders, each inside the domain.
    fn fluid(&self, scene: &Scene) -> Checked {
        let inside = |p: [f64; 3]| scene.domain.contains(p);
        for (k, b) in scene.fluid_blocks.iter().enumerate() {
            for a in 0..3 {
                if !(b.min_m[a] < b.max_m[a]) {
                    return self.fail(&format!("fluid_block[{k}].max_m"), format!("must exceed min_m on every axis (axis {a})"));
                }
            }
            if !inside(b.min_m) || !inside(b.max_m) {
                return self.fail(&format!("fluid_block[{k}]"), "lies outside the domain box".into());
            }
            self.magnitude(&format!("fluid_block[{k}].velocity_m_s"), b.velocity_m_s, MAX_SPEED_M_S, "a speed")?;
        }
        for (k, t) in scene.fluid_tori.iter().enumerate() {
            let field = |f: &str| format!("fluid_torus[{k}].{f}");
            self.positive(&field("major_radius_m"), t.major_radius_m)?;
            self.positive(&field("minor_radius_m"), t.minor_radius_m)?;
            if t.minor_radius_m >= t.major_radius_m {
                return self.fail(
                    &field("minor_radius_m"),
                    format!("must be below major_radius_m ({}) for a ring with a hole", t.major_radius_m),
                );
            }
            let (c, reach) = (t.centre_m, t.major_radius_m + t.minor_radius_m);
            let (lo, hi) =
                ([c[0] - reach, c[1] - t.minor_radius_m, c[2] - reach], [c[0] + reach, c[1] + t.minor_radius_m, c[2] + reach]);
            if !inside(lo) || !inside(hi) {
                return self.fail(&format!("fluid_torus[{k}]"), "lies outside the domain box".into());
            }
            self.magnitude(&field("velocity_m_s"), t.velocity_m_s, MAX_SPEED_M_S, "a speed")?;
        }
        for (k, c) in scene.fluid_cylinders.iter().enumerate() {
            let field = |f: &str| format!("fluid_cylinder[{k}].{f}");
            self.positive(&field("radius_m"), c.radius_m)?;
            self.positive(&field("height_m"), c.height_m)?;
            let (b, r) = (c.base_centre_m, c.radius_m);
            if !inside([b[0] - r, b[1], b[2] - r]) || !inside([b[0] + r, b[1] + c.height_m, b[2] + r]) {
                return self.fail(&format!("fluid_cylinder[{k}]"), "lies outside the domain box".into());
            }
            self.magnitude(&field("velocity_m_s"), c.velocity_m_s, MAX_SPEED_M_S, "a speed")?;
        }
        Ok(())
    }

    fn boundaries(&self, boundaries: &[Boundary], d: &Domain) -> Checked {
        for (k, b) in boundaries.iter().enumerate() {
            match *b {
                Boundary::Box { min_m, max_m, .. } => {
                    for a in 0..3 {
                        if !(min_m[a] < max_m[a]) {
                            return self
                                .fail(&format!("boundary[{k}].max_m"), format!("must exceed min_m on every axis (axis {a})"));
                        }
                        let spans = (min_m[a] - d.min_m[a]).abs() < 1e-9 && (max_m[a] - d.max_m[a]).abs() < 1e-9;
                        if d.periodic[a] && !spans {
                            return self.fail(
                                &format!("boundary[{k}]"),
                                format!("axis {a} is periodic, so the box must span the domain along it (it has no walls there)"),
                            );
                        }
                    }
                }
                Boundary::Plate { height_m, min_xz_m, max_xz_m } => {
                    if !height_m.is_finite() {
                        return self.fail(&format!("boundary[{k}].height_m"), format!("must be a finite number, got {height_m}"));
                    }
                    let (lo, hi) = (min_xz_m.unwrap_or([d.min_m[0], d.min_m[2]]), max_xz_m.unwrap_or([d.max_m[0], d.max_m[2]]));
                    if let Some(a) = (0..2).find(|&a| !(lo[a] < hi[a])) {
                        return self.fail(
                            &format!("boundary[{k}].max_xz_m"),
                            format!("must exceed min_xz_m along {} ({} against {})", ["x", "z"][a], hi[a], lo[a]),
                        );
                    }
                }
            }
        }
        Ok(())
    }

    fn inlets(&self, scene: &Scene) -> Checked {
        let h = scene.support_radius();
        let inside = |p: [f64; 3]| scene.domain.contains(p);
        for (k, inlet) in scene.inlets.iter().enumerate() {
            if let Some(j) = scene.inlets[..k].iter().position(|earlier| nozzles_overlap(earlier, inlet)) {
                return self.fail(
                    &format!("inlet[{k}]"),
                    format!(
                        "its nozzle overlaps that of inlet[{j}], moving alike, while both inject: the two would lay their particles on top of each other"
                    ),
                );
            }
            let field = |f: &str| format!("inlet[{k}].{f}");
            self.positive(&field("speed_m_s"), inlet.speed_m_s)?;
            if inlet.speed_m_s > MAX_SPEED_M_S {
                return self.fail(
                    &field("speed_m_s"),
                    format!("must be at most {} m/s, got {}", short(MAX_SPEED_M_S), short(inlet.speed_m_s)),
                );
            }
            let end = scene.simulation.end_time_s;
            if !(inlet.start_s >= 0.0 && inlet.start_s < end) {
                return self.fail(
                    &field("start_s"),
                    format!("must be from 0 to before simulation.end_time_s = {} s, got {}", short(end), short(inlet.start_s)),
                );
            }
            if let Some(stop) = inlet.stop_s.filter(|&stop| stop <= inlet.start_s) {
                return self
                    .fail(&field("stop_s"), format!("must be after start_s = {} s, got {}", short(inlet.start_s), short(stop)));
            }
            // Setup lays the nozzle's section on the lattice: it must fit the domain first.
            let d = &scene.domain;
            let extent = (0..3).map(|a| d.max_m[a] - d.min_m[a]).fold(0.0, f64::max);
            let sizes = match inlet.nozzle {
                Nozzle::Circle { radius_m } => vec![("nozzle.radius_m", radius_m, 2.0 * radius_m)],
                Nozzle::Rectangle { width_m, depth_m } => {
                    vec![("nozzle.width_m", width_m, width_m), ("nozzle.depth_m", depth_m, depth_m)]
                }
            };
            for (name, value, size) in sizes {
                self.positive(&field(name), value)?;
                if size > extent {
                    return self.fail(
                        &field(name),
                        format!("makes the nozzle {} m across, wider than the domain box ({} m)", short(size), short(extent)),
                    );
                }
            }
            if !(inlet.wobble_m >= 0.0 && inlet.wobble_m < scene.material.particle_spacing_m) {
                return self.fail(
                    &field("wobble_m"),
                    format!("must be at least 0 and below the particle spacing, got {}", inlet.wobble_m),
                );
            }
            let n2: f64 = inlet.direction.iter().map(|c| c * c).sum();
            if !(n2 > 0.0 && n2.is_finite()) {
                return self.fail(&field("direction"), "must be a non-zero vector".into());
            }
            if !inside(inlet.position_m) {
                return self.fail(&field("position_m"), format!("{:?} lies outside the domain box", inlet.position_m));
            }
            let d = inlet.direction.map(|c| c / n2.sqrt());
            let tube_start = [0, 1, 2].map(|a| inlet.position_m[a] - h * d[a]);
            if !inside(tube_start) {
                return self.fail(
                    &field("position_m"),
                    format!(
                        "the nozzle's tube reaches one support radius ({h} m) upstream of the exit, to {tube_start:?}, outside the domain box; move the nozzle or enlarge the domain"
                    ),
                );
            }
            if let Some(NozzleMotion::Velocity { velocity_m_s }) = &inlet.motion {
                self.magnitude(&field("motion.velocity_m_s"), *velocity_m_s, MAX_SPEED_M_S, "a speed")?;
            }
            if let Some(NozzleMotion::Waypoints { waypoints }) = &inlet.motion {
                if waypoints.is_empty() {
                    return self.fail(&field("motion.waypoints"), "needs at least one [t_s, x_m, y_m, z_m] point".into());
                }
                if waypoints.windows(2).any(|w| !(w[1][0] > w[0][0])) {
                    return self.fail(&field("motion.waypoints"), "times must increase".into());
                }
                if let Some(w) = waypoints.iter().find(|w| !inside([w[1], w[2], w[3]])) {
                    return self.fail(&field("motion.waypoints"), format!("{w:?} lies outside the domain box"));
                }
            }
        }
        Ok(())
    }
}

/// Whether nozzles `a` and `b` overlap while both inject: they move alike (both fixed, or on
/// the same motion), their injection times overlap, and their exits are closer than the sum of
/// their half-widths (a nozzle's exit lies within that distance of its centre whichever way it
/// points).
fn nozzles_overlap(a: &InletSettings, b: &InletSettings) -> bool {
    let half_width = |i: &InletSettings| match i.nozzle {
        Nozzle::Circle { radius_m } => radius_m,
        Nozzle::Rectangle { width_m, depth_m } => 0.5 * width_m.hypot(depth_m),
    };
    let (a_stop, b_stop) = (a.stop_s.unwrap_or(f64::INFINITY), b.stop_s.unwrap_or(f64::INFINITY));
    let together = a.start_s < b_stop && b.start_s < a_stop;
    let distance = (0..3).map(|k| (a.position_m[k] - b.position_m[k]).powi(2)).sum::<f64>().sqrt();
    a.motion == b.motion && together && distance < half_width(a) + half_width(b)
}

/// The dt a run of these settings takes (s) while its fastest particle moves at `speed_m_s`,
/// and what sets it: the fixed dt, or the Eq. (10) bound times the safety factor, or under
/// solved pressure the CFL step. At a speed of 0 it is the largest dt the run takes.
fn step_at(s: &SimulationSettings, m: &Material, h: f64, speed_m_s: f64) -> (f64, Limit) {
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

/// The first number in `value` that is not finite, with its field as `--set` spells it.
fn first_non_finite(value: &Value, path: String) -> Option<(String, f64)> {
    let join = |key: &str| if path.is_empty() { key.to_string() } else { format!("{path}.{key}") };
    match value {
        Value::Float(v) if !v.is_finite() => Some((path, *v)),
        Value::Table(table) => table.iter().find_map(|(key, v)| first_non_finite(v, join(key))),
        Value::Array(items) if items.iter().all(Value::is_table) => {
            items.iter().enumerate().find_map(|(k, v)| first_non_finite(v, format!("{path}[{k}]")))
        }
        Value::Array(items) => items.iter().find_map(|v| first_non_finite(v, path.clone())),
        _ => None,
    }
}

/// The first array of `given` whose counterpart in `written` (the parsed scene, serialized) has
/// another length: its field, and the two lengths.
fn first_length_mismatch(given: &Value, written: &Value, path: String) -> Option<(String, usize, usize)> {
    let join = |key: &str| if path.is_empty() { key.to_string() } else { format!("{path}.{key}") };
    match (given, written) {
        (Value::Table(g), Value::Table(w)) => {
            g.iter().find_map(|(key, gv)| w.get(key).and_then(|wv| first_length_mismatch(gv, wv, join(key))))
        }
        (Value::Array(g), Value::Array(w)) if g.len() != w.len() => Some((path, g.len(), w.len())),
        (Value::Array(g), Value::Array(w)) => g.iter().zip(w).enumerate().find_map(|(k, (gv, wv))| {
            let item = if gv.is_table() { format!("{path}[{k}]") } else { path.clone() };
            first_length_mismatch(gv, wv, item)
        }),
        _ => None,
    }
}
