//! What a scene's values must mean, checked once at load: one validator per section, each
//! refusing a value with the field named as `--set` spells it.

use super::overrides::Override;
use super::Variant;
use super::{short, Precision, Pressure, Scene, SceneError};
use simulation::step_at;
use toml::Value;

mod geometry;
mod material;
mod simulation;

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
