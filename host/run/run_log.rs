//! `run.json` in the output folder: everything needed to reproduce a run and read its outcome.
//! Written when the run starts (status "running") and again when it ends, through a temporary
//! name and a rename, so a killed run still leaves a readable log.

use super::summary::Summary;
use crate::output::write_atomically;
use crate::scene::{Precision, Scene, SceneError};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The scene with every default written out.
pub fn resolved(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    let v = &mut s.material.viscosity;
    v.nu_inf_m2_s = Some(v.nu_inf());
    s
}

/// Where `coil resume` took a run up again.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Resumed {
    pub step: u64,
    pub time_s: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    Running,
    Completed,
    Unstable,
    /// Ctrl-C or SIGTERM.
    Interrupted,
    /// Output could not be written, or the device failed.
    Failed,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BackendName {
    Cpu,
    Cuda,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunLog {
    pub coil_version: String,
    pub scene_file: String,
    /// The `--set` overrides, already applied to `scene`.
    pub overrides: Vec<String>,
    pub backend: BackendName,
    pub precision: Precision,
    pub threads: usize,
    pub status: Status,
    /// Why the run stopped early, if it did.
    pub diagnosis: Option<String>,
    /// Each time `coil resume` continued the run, in order; absent for a run never stopped.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub resumed: Vec<Resumed>,
    /// The summary printed at the end (None while running); a resumed run's covers it all.
    pub summary: Option<Summary>,
    /// Resolved: every default written out.
    pub scene: Scene,
}

impl RunLog {
    pub fn write(&self, dir: &Path) -> std::io::Result<()> {
        let json = serde_json::to_vec_pretty(self).map_err(std::io::Error::other)?;
        write_atomically(&dir.join(super::folder::LOG), &json)
    }

    /// Reads a run log; the error names the file and the field that does not fit.
    pub fn read(path: &Path) -> Result<RunLog, SceneError> {
        crate::scene::logged::read_json(path)
    }
}
