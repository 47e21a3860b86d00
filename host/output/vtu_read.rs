//! Reads back the `.vtu` frames that `vtu::encode` writes (appended raw binary or inline base64,
//! UInt64 block headers) and the `.pvd` series that lists them, for the commands that read
//! frames back (render, surface, pov, axis, preview) and the round-trip test. Other VTK
//! writers' files are refused with a reason rather than misread, and so is a frame no run
//! writes.

use crate::scene::Scene;
use std::collections::BTreeMap;
use std::path::Path;

/// The particles of one frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrameData {
    /// m
    pub position: Vec<[f64; 3]>,
    /// Per-particle scalars by name (`density`, `pressure`, `viscosity`, `shear_rate`).
    pub scalars: BTreeMap<String, Vec<f32>>,
    /// Per-particle vectors by name (`velocity`).
    pub vectors: BTreeMap<String, Vec<[f32; 3]>>,
    pub id: Vec<u32>,
}

struct ArrayHeader<'a> {
    ty: String,
    name: String,
    components: usize,
    /// Where its block starts in the appended data, or its inline base64 text.
    place: Place<'a>,
}

enum Place<'a> {
    Appended(usize),
    Inline(&'a str),
}

fn attribute(tag: &str, name: &str) -> Option<String> {
    let start = tag.find(&format!(" {name}=\""))? + name.len() + 3;
    let end = start + tag[start..].find('"')?;
    Some(tag[start..end].to_string())
}

/// The largest frame file read (bytes): a frame of a billion particles.
const MAX_FRAME_BYTES: u64 = 1 << 36;
/// The largest `.pvd` series read (bytes): a run writes at most 1e5 frames, under 100 bytes each
/// in its series.
const MAX_SERIES_BYTES: u64 = 64 << 20;

/// Reads a frame file; the error names the file and says why it cannot be read.
pub fn read_frame(path: &Path) -> Result<FrameData, String> {
    let bytes =
        crate::regular_file::read(path, MAX_FRAME_BYTES).map_err(|e| format!("{}: cannot be read: {e}", path.display()))?;
    parse(&bytes).map_err(|e| format!("{}: {e}", path.display()))
}

/// Reads a frame of the run of `scene` (as its `run.json` logs it): beyond [`read_frame`]'s
/// checks, every particle must lie in the run's domain, where a run keeps its particles (a
/// particle that leaves it is removed), within one support radius.
pub fn read_run_frame(path: &Path, scene: &Scene) -> Result<FrameData, String> {
    let frame = read_frame(path)?;
    let margin = scene.support_radius();
    let d = &scene.domain;
    let outside =
        frame.position.iter().position(|p| (0..3).any(|a| !(p[a] >= d.min_m[a] - margin && p[a] <= d.max_m[a] + margin)));
    match outside {
        Some(k) => Err(format!(
            "{}: {} lies at {:?} m, outside the run's domain {:?} to {:?} m: not a frame of this run",
            path.display(),
            particle_name(&frame, k),
            frame.position[k],
            d.min_m,
            d.max_m
        )),
        None => Ok(frame),
    }
}

/// "particle K (id I)", or "particle K" in a frame without ids.
fn particle_name(frame: &FrameData, k: usize) -> String {
    match frame.id.get(k) {
        Some(id) => format!("particle {k} (id {id})"),
        None => format!("particle {k}"),
    }
}

/// The frames a `.pvd` series lists, in its order: (simulated time (s), file name relative to
/// the series).
pub fn read_series(path: &Path) -> Result<Vec<(f64, String)>, String> {
    let text =
        crate::regular_file::read_text(path, MAX_SERIES_BYTES).map_err(|e| format!("{}: cannot be read: {e}", path.display()))?;
    text.split("<DataSet")
        .skip(1)
        .map(|tag| {
            let tag = &tag[..tag.find('>').unwrap_or(tag.len())];
            let time = attribute(tag, "timestep").and_then(|t| t.parse().ok()).ok_or("a DataSet without a numeric timestep")?;
            let file = attribute(tag, "file").ok_or("a DataSet without a file")?;
            Ok((time, file))
        })
        .collect::<Result<_, &str>>()
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// Parses the bytes of a frame file.
pub fn parse(bytes: &[u8]) -> Result<FrameData, String> {
    let marker = b"<AppendedData encoding=\"raw\">";
    let appended = bytes.windows(marker.len()).position(|w| w == marker);
    let header = std::str::from_utf8(&bytes[..appended.unwrap_or(bytes.len())])
        .map_err(|_| "not a coil frame: no raw appended data, and not text as base64 arrays are (was it written by coil?)")?;
    if !header.contains("header_type=\"UInt64\"") {
        return Err("not a coil frame: block headers are not UInt64".into());
    }
    let data = match appended {
        Some(at) => {
            let underscore = bytes[at..].iter().position(|&b| b == b'_').ok_or("appended data has no '_' start")?;
            &bytes[at + underscore + 1..]
        }
        None => &[],
    };
    let n: usize = header
        .find("<Piece ")
        .and_then(|p| attribute(&header[p..], "NumberOfPoints"))
        .and_then(|v| v.parse().ok())
        .ok_or("no NumberOfPoints")?;
    // Each point takes 24 bytes of positions at least (more in base64): a header that claims
    // more points than that is refused before anything is sized by it.
    if n > bytes.len() / 24 {
        return Err(format!("claims {n} points, more than its {} bytes can hold", bytes.len()));
    }
    let arrays: Vec<ArrayHeader> = header
        .split("<DataArray")
        .skip(1)
        .map(|tag| {
            let end = tag.find('>').unwrap_or(tag.len());
            let (attributes, rest) = (&tag[..end], &tag[(end + 1).min(tag.len())..]);
            let place = match attribute(attributes, "format").as_deref() {
                Some("binary") => {
                    Place::Inline(rest[..rest.find("</DataArray>").ok_or("an inline DataArray not closed")?].trim())
                }
                _ => Place::Appended(
                    attribute(attributes, "offset").and_then(|c| c.parse().ok()).ok_or("DataArray without offset")?,
                ),
            };
            Ok(ArrayHeader {
                ty: attribute(attributes, "type").ok_or("DataArray without type")?,
                name: attribute(attributes, "Name").ok_or("DataArray without Name")?,
                components: attribute(attributes, "NumberOfComponents").and_then(|c| c.parse().ok()).unwrap_or(1),
                place,
            })
        })
        .collect::<Result<_, &str>>()?;
    let block = |a: &ArrayHeader, size: usize| -> Result<Vec<u8>, String> {
        let expected = n
            .checked_mul(a.components)
            .and_then(|v| v.checked_mul(size))
            .filter(|&e| e <= bytes.len())
            .ok_or(format!("array {} claims more bytes than the file holds", a.name))?;
        let (len, block) = match a.place {
            Place::Appended(offset) => {
                let past = || format!("array {} lies past the end of the file", a.name);
                let len_bytes = data.get(offset..offset.checked_add(8).ok_or_else(past)?).ok_or_else(past)?;
                let len = u64::from_le_bytes(len_bytes.try_into().expect("8 bytes")) as usize;
                (
                    len,
                    data.get(offset + 8..offset + 8 + len.min(expected))
                        .ok_or(format!("array {} is truncated", a.name))?
                        .to_vec(),
                )
            }
            Place::Inline(text) => {
                use base64::Engine as _;
                let mut block =
                    base64::engine::general_purpose::STANDARD.decode(text).map_err(|e| format!("array {}: {e}", a.name))?;
                if block.len() < 8 {
                    return Err(format!("array {} is truncated", a.name));
                }
                let len = u64::from_le_bytes(block[..8].try_into().expect("8 bytes")) as usize;
                block.drain(..8);
                (len, block)
            }
        };
        if len != expected || block.len() != expected {
            return Err(format!("array {} holds {len} bytes, expected {expected}", a.name));
        }
        Ok(block)
    };
    let mut frame = FrameData::default();
    for a in &arrays {
        match (a.ty.as_str(), a.name.as_str(), a.components) {
            ("Float64", "position", 3) => {
                frame.position = block(a, 8)?
                    .chunks_exact(24)
                    .map(|c| [0, 1, 2].map(|k| f64::from_le_bytes(c[8 * k..8 * k + 8].try_into().expect("8 bytes"))))
                    .collect();
            }
            ("Float32", name, 1) => {
                let v = block(a, 4)?.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes"))).collect();
                frame.scalars.insert(name.to_string(), v);
            }
            ("Float32", name, 3) => {
                let v = block(a, 4)?
                    .chunks_exact(12)
                    .map(|c| [0, 1, 2].map(|k| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().expect("4 bytes"))))
                    .collect();
                frame.vectors.insert(name.to_string(), v);
            }
            ("UInt32", "id", 1) => {
                frame.id = block(a, 4)?.chunks_exact(4).map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes"))).collect();
            }
            _ => {}
        }
    }
    if frame.position.len() != n {
        return Err("no Float64 position array".into());
    }
    if let Some(what) = first_non_finite(&frame) {
        return Err(format!("{what}: a coil run writes only finite values"));
    }
    Ok(frame)
}

/// The first value of `frame` that is not finite, as "the NAME of particle K (id I) is V".
fn first_non_finite(frame: &FrameData) -> Option<String> {
    let at = |name: &str, k: usize, value: String| Some(format!("the {name} of {} is {value}", particle_name(frame, k)));
    if let Some(k) = frame.position.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
        return at("position", k, format!("{:?}", frame.position[k]));
    }
    for (name, values) in &frame.scalars {
        if let Some(k) = values.iter().position(|x| !x.is_finite()) {
            return at(name, k, values[k].to_string());
        }
    }
    for (name, values) in &frame.vectors {
        if let Some(k) = values.iter().position(|v| !v.iter().all(|x| x.is_finite())) {
            return at(name, k, format!("{:?}", values[k]));
        }
    }
    None
}
