//! `--set key=value`: edits a scene's TOML before it is parsed, so an override passes through the
//! same deserialisation and validation as the file itself.
//!
//! Keys are dotted paths as the scene file spells them; an array of tables takes an index:
//! `material.viscosity.cross_k_s=10`, `inlet[0].speed_m_s=0.5`, `simulation.precision=f64`.

use crate::scene::SceneError;
use toml::{Table, Value};

/// One `key=value` override.
#[derive(Debug, Clone, PartialEq)]
pub struct Override {
    /// The text the user gave, for error messages.
    pub given: String,
    path: Vec<Step>,
    value: Value,
}

#[derive(Debug, Clone, PartialEq)]
enum Step {
    Key(String),
    Index(String, usize),
}

impl Override {
    /// Parses `key=value`. The value is read as a TOML value (`1e-3`, `true`, `[0.0, 1.0, 0.0]`,
    /// `"f64"`); anything that is not one is taken as a string, so `precision=f64` works.
    pub fn parse(given: &str) -> Result<Self, SceneError> {
        let bad = |reason: String| SceneError { file: "--set".into(), field: given.into(), reason };
        let (key, value) = given.split_once('=').ok_or_else(|| bad("expected key=value".into()))?;
        let (key, value) = (key.trim(), value.trim());
        let mut path = Vec::new();
        for part in key.split('.') {
            let step = match part.split_once('[') {
                None => Step::Key(part.to_string()),
                Some((name, rest)) => {
                    let index = rest
                        .strip_suffix(']')
                        .and_then(|i| i.parse().ok())
                        .ok_or_else(|| bad(format!("`{part}`: an index is written name[N]")))?;
                    Step::Index(name.to_string(), index)
                }
            };
            let name = match &step {
                Step::Key(n) | Step::Index(n, _) => n,
            };
            if name.is_empty() {
                return Err(bad(format!("`{key}` has an empty part")));
            }
            path.push(step);
        }
        // The variant is applied from the file before any override, so an edit of it would do
        // nothing.
        if matches!(&path[0], Step::Key(name) | Step::Index(name, _) if name == "variant") {
            return Err(bad(
                "`variant` lists the scene's variants, which --variant NAME applies before any --set: an override of it would do nothing".into(),
            ));
        }
        let value = match toml::from_str::<Table>(&format!("v = {value}")) {
            Ok(mut t) => t.remove("v").expect("the key just parsed"),
            // A number TOML cannot hold (1e400, 2^64) would otherwise be taken as a string.
            Err(_) if value.parse::<f64>().is_ok() => {
                return Err(bad(format!(
                    "`{value}` is out of range: a number must be finite in double precision (below about 1.8e308) and a whole number at most 2^63 - 1"
                )))
            }
            Err(_) => Value::String(value.to_string()),
        };
        Ok(Self { given: given.to_string(), path, value })
    }

    /// Writes the value into `scene`, creating tables on the way.
    fn apply(&self, scene: &mut Table, file: &str) -> Result<(), SceneError> {
        let bad = |reason: String| SceneError { file: file.into(), field: format!("--set {}", self.given), reason };
        let mut table = scene;
        let (last, parents) = self.path.split_last().expect("parse gives at least one part");
        for step in parents {
            table = match step {
                Step::Key(name) => table
                    .entry(name.clone())
                    .or_insert_with(|| Value::Table(Table::new()))
                    .as_table_mut()
                    .ok_or_else(|| bad(format!("`{name}` is a value, not a table")))?,
                Step::Index(name, i) => {
                    let array = table
                        .get_mut(name)
                        .and_then(Value::as_array_mut)
                        .ok_or_else(|| bad(format!("the scene has no [[{name}]] list")))?;
                    let len = array.len();
                    array
                        .get_mut(*i)
                        .and_then(Value::as_table_mut)
                        .ok_or_else(|| bad(format!("[[{name}]] has {len} entries, index {i} is out of range")))?
                }
            };
        }
        match last {
            Step::Key(name) => {
                table.insert(name.clone(), self.value.clone());
            }
            Step::Index(name, i) => {
                let array =
                    table.get_mut(name).and_then(Value::as_array_mut).ok_or_else(|| bad(format!("`{name}` is not a list")))?;
                let len = array.len();
                *array.get_mut(*i).ok_or_else(|| bad(format!("`{name}` has {len} entries, index {i} is out of range")))? =
                    self.value.clone();
            }
        }
        Ok(())
    }
}

/// Fields of a section of which a scene gives one or the other: an override of one removes the
/// other, so that `--set output.every_steps=1` works on a scene that writes by time.
const EITHER: [(&str, &str, &str); 1] = [("output", "every_s", "every_steps")];

/// Scene text with `overrides` applied in order, as TOML text again.
pub fn apply(text: &str, file: &str, overrides: &[Override]) -> Result<String, SceneError> {
    if overrides.is_empty() {
        return Ok(text.to_string());
    }
    let mut table: Table = toml::from_str(text).map_err(|e| SceneError {
        file: file.into(),
        field: "(syntax)".into(),
        reason: e.message().to_string(),
    })?;
    for o in overrides {
        o.apply(&mut table, file)?;
        if let [Step::Key(section), Step::Key(name)] = o.path.as_slice() {
            for &(s, a, b) in EITHER.iter().filter(|(s, ..)| s == section) {
                let other = if name == a {
                    b
                } else if name == b {
                    a
                } else {
                    continue;
                };
                if let Some(t) = table.get_mut(s).and_then(Value::as_table_mut) {
                    t.remove(other);
                }
            }
        }
    }
    Ok(toml::to_string(&table).expect("a TOML table serialises"))
}
