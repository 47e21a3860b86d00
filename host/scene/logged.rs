//! Scenes read back from the `run.json` of an earlier run, whose resolved scene (every default
//! written out) reproduces that run.

use super::{Scene, SceneError};
use serde::de::DeserializeOwned;
use serde::Deserialize;
use std::path::Path;

/// The largest run log read (bytes): its scene, overrides and summary take a few KiB.
const MAX_LOG_BYTES: u64 = 16 << 20;

/// The JSON file `path` (a run log, or the part of one that `T` takes) as `T`; the error names
/// the file and the field that does not fit.
pub fn read_json<T: DeserializeOwned>(path: &Path) -> Result<T, SceneError> {
    let file = path.display().to_string();
    let bad = |field: String, reason: String| SceneError { file: file.clone(), field, reason };
    let text =
        crate::regular_file::read_text(path, MAX_LOG_BYTES).map_err(|e| bad("(file)".into(), format!("cannot be read: {e}")))?;
    let json = &mut serde_json::Deserializer::from_str(&text);
    serde_path_to_error::deserialize(json).map_err(|e| {
        let field = e.path().to_string();
        let inner = e.into_inner();
        match inner.classify() {
            serde_json::error::Category::Data if field != "." => bad(field, inner.to_string()),
            _ => bad("(syntax)".into(), inner.to_string()),
        }
    })
}

/// The part of a run log that holds its scene.
#[derive(Deserialize)]
struct Logged {
    scene: Scene,
}

/// The scene the run log `path` holds, as TOML.
pub(super) fn logged_scene_text(path: &Path) -> Result<String, SceneError> {
    scene_as_toml(&read_json::<Logged>(path)?.scene, path)
}

/// `scene`, logged in `path`, as TOML.
pub(super) fn scene_as_toml(scene: &Scene, path: &Path) -> Result<String, SceneError> {
    toml::to_string(scene).map_err(|e| SceneError {
        file: path.display().to_string(),
        field: "scene".into(),
        reason: e.to_string(),
    })
}
