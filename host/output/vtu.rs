//! VTK XML unstructured-grid frames (`.vtu`, appended raw binary or inline base64) and their
//! `.pvd` series.

use super::write_atomically;
use crate::scene::VtuEncoding;
use std::fmt::Write as _;
use std::io;
use std::path::{Path, PathBuf};

/// One per-particle array of a frame.
pub enum Field<'a> {
    Scalar(&'a str, &'a [f32]),
    Vector(&'a str, &'a [[f32; 3]]),
    Id(&'a str, &'a [u32]),
}

/// One array's bytes, as its UInt64 block header announces them.
fn array_bytes(f: &Field, bytes: &mut Vec<u8>) {
    match f {
        Field::Scalar(_, v) => v.iter().for_each(|x| bytes.extend_from_slice(&x.to_le_bytes())),
        Field::Vector(_, v) => v.iter().flatten().for_each(|x| bytes.extend_from_slice(&x.to_le_bytes())),
        Field::Id(_, v) => v.iter().for_each(|x| bytes.extend_from_slice(&x.to_le_bytes())),
    }
}

/// Encodes a frame of particles as vertex cells with point data, its arrays held as
/// `encoding` says. `bytes` is reused between frames so writing allocates nothing once it has
/// grown (in the raw encoding).
pub fn encode(positions: &[[f64; 3]], fields: &[Field], encoding: VtuEncoding, bytes: &mut Vec<u8>) {
    let n = positions.len();
    // Each array: its VTK type, name and components, and a writer of its bytes.
    type Write<'f> = Box<dyn Fn(&mut Vec<u8>) + 'f>;
    let mut arrays: Vec<(&str, &str, usize, Write)> = Vec::with_capacity(fields.len() + 4);
    for f in fields {
        let (ty, name, comps) = match f {
            Field::Scalar(name, _) => ("Float32", *name, 1),
            Field::Vector(name, _) => ("Float32", *name, 3),
            Field::Id(name, _) => ("UInt32", *name, 1),
        };
        arrays.push((ty, name, comps, Box::new(move |b: &mut Vec<u8>| array_bytes(f, b))));
    }
    let point_data = arrays.len();
    arrays.push((
        "Float64",
        "position",
        3,
        Box::new(|b: &mut Vec<u8>| positions.iter().flatten().for_each(|x| b.extend_from_slice(&x.to_le_bytes()))),
    ));
    arrays.push((
        "Int32",
        "connectivity",
        1,
        Box::new(move |b: &mut Vec<u8>| (0..n as i32).for_each(|k| b.extend_from_slice(&k.to_le_bytes()))),
    ));
    arrays.push((
        "Int32",
        "offsets",
        1,
        Box::new(move |b: &mut Vec<u8>| (1..=n as i32).for_each(|k| b.extend_from_slice(&k.to_le_bytes()))),
    ));
    // VTK_VERTEX
    arrays.push(("UInt8", "types", 1, Box::new(move |b: &mut Vec<u8>| b.extend(std::iter::repeat_n(1u8, n)))));
    let size = |ty: &str| match ty {
        "Float64" => 8,
        "UInt8" => 1,
        _ => 4,
    };

    bytes.clear();
    bytes.extend_from_slice(b"<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n");
    let _ = write!(Text(bytes), "    <Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n}\">\n      <PointData>\n");
    let mut offset = 0usize;
    let mut scratch = Vec::new();
    for (k, (ty, name, comps, write)) in arrays.iter().enumerate() {
        match k {
            _ if k == point_data => bytes.extend_from_slice(b"      </PointData>\n      <Points>\n"),
            _ if k == point_data + 1 => bytes.extend_from_slice(b"      </Points>\n      <Cells>\n"),
            _ => {}
        }
        let len = n * comps * size(ty);
        match encoding {
            VtuEncoding::Raw => {
                let _ = writeln!(
                    Text(bytes),
                    r#"        <DataArray type="{ty}" Name="{name}" NumberOfComponents="{comps}" format="appended" offset="{offset}"/>"#
                );
                offset += 8 + len;
            }
            VtuEncoding::Base64 => {
                let _ = write!(
                    Text(bytes),
                    r#"        <DataArray type="{ty}" Name="{name}" NumberOfComponents="{comps}" format="binary">"#
                );
                scratch.clear();
                scratch.extend_from_slice(&(len as u64).to_le_bytes());
                write(&mut scratch);
                base64_into(&scratch, bytes);
                bytes.extend_from_slice(b"</DataArray>\n");
            }
        }
    }
    bytes.extend_from_slice(b"      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n");
    if encoding == VtuEncoding::Raw {
        bytes.extend_from_slice(b"  <AppendedData encoding=\"raw\">\n   _");
        for (ty, _, comps, write) in &arrays {
            bytes.extend_from_slice(&((n * comps * size(ty)) as u64).to_le_bytes());
            write(bytes);
        }
        bytes.extend_from_slice(b"\n  </AppendedData>\n");
    }
    bytes.extend_from_slice(b"</VTKFile>\n");
}

/// Appends the standard base64 encoding of `data` (padded) to `out`.
fn base64_into(data: &[u8], out: &mut Vec<u8>) {
    use base64::Engine as _;
    let start = out.len();
    out.resize(start + data.len().div_ceil(3) * 4, 0);
    let written =
        base64::engine::general_purpose::STANDARD.encode_slice(data, &mut out[start..]).expect("sized for the padded encoding");
    out.truncate(start + written);
}

/// `write!` into a byte buffer.
struct Text<'a>(&'a mut Vec<u8>);

impl std::fmt::Write for Text<'_> {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.0.extend_from_slice(s.as_bytes());
        Ok(())
    }
}

/// A `.pvd` collection listing every frame written so far.
pub struct PvdSeries {
    path: PathBuf,
    entries: Vec<(f64, String)>,
}

impl PvdSeries {
    /// A series that already lists `earlier`: (time (s), file) of the frames a resumed run
    /// wrote before it stopped. It grows a frame at a time, never by the run's length.
    pub fn new(path: PathBuf, earlier: Vec<(f64, String)>) -> Self {
        Self { path, entries: earlier }
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
