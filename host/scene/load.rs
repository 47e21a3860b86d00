//! Reading a scene: its file (TOML, or an earlier run's `run.json`), `--set` overrides,
//! serde's errors turned into the field they name, refinement, then validation.

use crate::scene::overrides::{self, Override};
use crate::scene::{logged, Scene, SceneError};
use std::path::Path;

/// The TOML text of a scene file; a `run.json` gives its `scene`, written back as TOML.
fn scene_text(path: &Path) -> Result<String, SceneError> {
    if path.extension().is_some_and(|x| x == "json") {
        return logged::logged_scene_text(path);
    }
    crate::regular_file::read_text(path, MAX_SCENE_BYTES).map_err(|e| SceneError {
        file: path.display().to_string(),
        field: "(file)".into(),
        reason: format!("cannot be read: {e}"),
    })
}

/// The largest scene file read (bytes): the shipped scenes are about 2 KiB.
const MAX_SCENE_BYTES: u64 = 1 << 20;

/// For serde's "unknown field `x`, expected one of `a`, `b`" (or "expected `a` or `b`"): the
/// valid name that adds a unit to `x` (`cross_k` for `cross_k_s`: the unit is what users leave
/// out), else the nearest valid name, when it is a plausible typo.
fn suggestion(message: &str) -> String {
    let Some(rest) = message.strip_prefix("unknown field `") else { return String::new() };
    let Some((unknown, expected)) = rest.split_once('`') else { return String::new() };
    let names = || expected.split('`').skip(1).step_by(2);
    let with_unit = names().find(|name| name.strip_prefix(unknown).is_some_and(|unit| unit.starts_with('_')));
    let nearest = || {
        names()
            .map(|name| (strsim::levenshtein(unknown, name), name))
            .min()
            .filter(|&(d, name)| d <= 1 + name.len().max(unknown.len()) / 3)
            .map(|(_, name)| name)
    };
    with_unit.or_else(nearest).map(|name| format!("; did you mean `{name}`?")).unwrap_or_default()
}

impl Scene {
    /// Reads and validates a scene file: TOML, or the `run.json` of an earlier run, whose
    /// resolved scene reproduces that run.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Self::load_with(path, &[])
    }

    /// Reads a scene file, applies `--set` overrides in order, and validates the result as one.
    pub fn load_with(path: &Path, overrides: &[Override]) -> Result<Scene, SceneError> {
        Self::with_overrides(&scene_text(path)?, &path.display().to_string(), overrides)
    }

    /// The scene `logged` in the run log `path`, with `--set` overrides applied in order and
    /// validated as one.
    pub fn from_log(logged: &Scene, path: &Path, overrides: &[Override]) -> Result<Scene, SceneError> {
        Self::with_overrides(&logged::scene_as_toml(logged, path)?, &path.display().to_string(), overrides)
    }

    fn with_overrides(text: &str, file: &str, overrides: &[Override]) -> Result<Scene, SceneError> {
        if overrides.is_empty() {
            return Self::parse(text, file);
        }
        Self::parse(&overrides::apply(text, file, overrides)?, &format!("{file} with --set")).map_err(|mut e| {
            // Line numbers would point into the rewritten text, not the user's file.
            if let Some(at) = e.reason.find(" (at line ") {
                e.reason.truncate(at);
            }
            e
        })
    }

    /// Parses and validates scene text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Scene, SceneError> {
        let scene: Scene = toml::from_str(text).map_err(|e| {
            let mut field =
                e.span().and_then(|s| crate::scene::toml_field::field_at(text, s.start)).unwrap_or_else(|| "(syntax)".into());
            // serde points a missing field at the table that lacks it: name the field itself.
            let missing = e.message().strip_prefix("missing field `").and_then(|rest| rest.strip_suffix('`'));
            if let Some(name) = missing {
                field = if field == "(syntax)" || field.is_empty() { name.to_string() } else { format!("{field}.{name}") };
            }
            SceneError {
                file: file.into(),
                field,
                reason: e.message().to_string()
                    + &suggestion(e.message())
                    + &e.span().map(|s| format!(" (at line {})", 1 + text[..s.start].matches('\n').count())).unwrap_or_default(),
            }
        })?;
        let given: toml::Table = toml::from_str(text).map_err(|e| SceneError {
            file: file.into(),
            field: "(syntax)".into(),
            reason: e.message().to_string(),
        })?;
        let mut scene = scene;
        scene.refine(file)?;
        scene.validate(&given, file)?;
        Ok(scene)
    }

    /// Applies `simulation.refinement` and sets it back to 1.
    fn refine(&mut self, file: &str) -> Result<(), SceneError> {
        let r = self.simulation.refinement;
        if r == 1.0 {
            return Ok(());
        }
        if !(0.25..=8.0).contains(&r) {
            return Err(SceneError {
                file: file.into(),
                field: "simulation.refinement".into(),
                reason: format!("must be from 0.25 to 8 (the spacing's divisor), got {r}"),
            });
        }
        self.material.particle_spacing_m /= r;
        if let Some(capacity) = &mut self.simulation.max_fluid_particles {
            *capacity = (*capacity as f64 * r * r * r).ceil() as usize;
        }
        for inlet in &mut self.inlets {
            inlet.wobble_m /= r;
        }
        self.simulation.refinement = 1.0;
        Ok(())
    }

    /// Support radius h (m).
    pub fn support_radius(&self) -> f64 {
        self.material.particle_spacing_m * self.material.support_radius_factor
    }
}
