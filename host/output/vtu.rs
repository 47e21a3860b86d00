//! VTK XML unstructured-grid frames (`.vtu`, appended raw binary) and their `.pvd` series.

use super::write_atomically;
use std::fmt::Write as _;
use std::io;
use std::path::{Path, PathBuf};

/// One per-particle array of a frame.
pub enum Field<'a> {
    Scalar(&'a str, &'a [f32]),
    Vector(&'a str, &'a [[f32; 3]]),
    Id(&'a str, &'a [u32]),
}

/// Encodes a frame of particles as vertex cells with point data. `bytes` is reused between
/// frames so writing allocates nothing once it has grown.
pub fn encode(positions: &[[f64; 3]], fields: &[Field], bytes: &mut Vec<u8>) {
    let n = positions.len();
    let mut header = String::new();
    let mut offset = 0usize;
    let mut array = |header: &mut String, ty: &str, name: &str, comps: usize, size: usize| {
        let _ = writeln!(
            header,
            r#"        <DataArray type="{ty}" Name="{name}" NumberOfComponents="{comps}" format="appended" offset="{offset}"/>"#
        );
        offset += 8 + n * comps * size;
    };
    header.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n");
    let _ = writeln!(header, r#"    <Piece NumberOfPoints="{n}" NumberOfCells="{n}">"#);
    header.push_str("      <PointData>\n");
    for f in fields {
        match f {
            Field::Scalar(name, _) => array(&mut header, "Float32", name, 1, 4),
            Field::Vector(name, _) => array(&mut header, "Float32", name, 3, 4),
            Field::Id(name, _) => array(&mut header, "UInt32", name, 1, 4),
        }
    }
    header.push_str("      </PointData>\n      <Points>\n");
    array(&mut header, "Float64", "position", 3, 8);
    header.push_str("      </Points>\n      <Cells>\n");
    array(&mut header, "Int32", "connectivity", 1, 4);
    array(&mut header, "Int32", "offsets", 1, 4);
    array(&mut header, "UInt8", "types", 1, 1);
    header.push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _");

    bytes.clear();
    bytes.extend_from_slice(header.as_bytes());
    let block = |bytes: &mut Vec<u8>, len: usize| bytes.extend_from_slice(&(len as u64).to_le_bytes());
    for f in fields {
        match f {
            Field::Scalar(_, v) => {
                block(bytes, 4 * n);
                v.iter().for_each(|x| bytes.extend_from_slice(&x.to_le_bytes()));
            }
            Field::Vector(_, v) => {
                block(bytes, 12 * n);
                v.iter().flatten().for_each(|x| bytes.extend_from_slice(&x.to_le_bytes()));
            }
            Field::Id(_, v) => {
                block(bytes, 4 * n);
                v.iter().for_each(|x| bytes.extend_from_slice(&x.to_le_bytes()));
            }
        }
    }
    block(bytes, 24 * n);
    positions.iter().flatten().for_each(|x| bytes.extend_from_slice(&x.to_le_bytes()));
    block(bytes, 4 * n);
    (0..n as i32).for_each(|k| bytes.extend_from_slice(&k.to_le_bytes()));
    block(bytes, 4 * n);
    (1..=n as i32).for_each(|k| bytes.extend_from_slice(&k.to_le_bytes()));
    block(bytes, n);
    // VTK_VERTEX
    bytes.extend(std::iter::repeat_n(1u8, n));
    bytes.extend_from_slice(b"\n  </AppendedData>\n</VTKFile>\n");
}

/// The `.pvd` series of a run of scene `scene_name` in output folder `dir`.
pub fn series_path(dir: &Path, scene_name: &str) -> PathBuf {
    dir.join(format!("{scene_name}.pvd"))
}

/// A `.pvd` collection listing every frame written so far.
pub struct Series {
    path: PathBuf,
    entries: Vec<(f64, String)>,
}

impl Series {
    /// A series with room for `capacity` frames that already lists `earlier`: (time (s), file)
    /// of the frames a resumed run wrote before it stopped.
    pub fn new(path: PathBuf, capacity: usize, earlier: Vec<(f64, String)>) -> Self {
        let mut entries = earlier;
        entries.reserve(capacity.saturating_sub(entries.len()));
        Self { path, entries }
    }

    /// Records a frame file (relative to the series file) at simulated time `t` (s) and
    /// rewrites the series.
    pub fn push(&mut self, t: f64, file: &str) -> io::Result<()> {
        self.entries.push((t, file.to_string()));
        let mut s = String::from("<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n");
        for (t, f) in &self.entries {
            let _ = writeln!(s, r#"    <DataSet timestep="{t:e}" part="0" file="{f}"/>"#);
        }
        s.push_str("  </Collection>\n</VTKFile>\n");
        write_atomically(&self.path, s.as_bytes())
    }

    pub fn path(&self) -> &Path {
        &self.path
    }
}
