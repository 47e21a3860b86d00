//! Scene files: TOML, SI units, every unit in the field name. Parsed with serde
//! (`deny_unknown_fields`), validated once at load, then turned into plain `Copy` parameter
//! structs for the kernels.

pub mod inlet;
pub mod load;
pub mod logged;
pub mod material;
pub mod overrides;
pub mod particle_limit;
mod serde_defaults;
pub mod settings;
pub mod setup;
pub mod toml_field;
mod validate;

pub use material::*;
use serde::{Deserialize, Serialize};
use serde_defaults::is_default;
pub use settings::*;
use std::fmt;

/// A user mistake in a scene: which file, which field, why. The CLI prints it and exits 2.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    pub file: String,
    pub field: String,
    pub reason: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}: {}", self.file, self.field, self.reason)
    }
}

impl std::error::Error for SceneError {}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Short name, used for the output folder.
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// Which experiment of the paper this reproduces, and for jets their Reynolds number and H/D.
    #[serde(default)]
    pub notes: String,
    pub material: Material,
    pub domain: Domain,
    pub simulation: SimulationSettings,
    #[serde(default)]
    pub output: Output,
    #[serde(default, rename = "fluid_block")]
    pub fluid_blocks: Vec<FluidBlock>,
    #[serde(default, rename = "fluid_torus")]
    pub fluid_tori: Vec<FluidTorus>,
    #[serde(default, rename = "fluid_cylinder")]
    pub fluid_cylinders: Vec<FluidCylinder>,
    #[serde(default, rename = "boundary")]
    pub boundaries: Vec<Boundary>,
    #[serde(default, rename = "inlet")]
    pub inlets: Vec<InletSettings>,
    /// Named `--set` combinations of this scene that reproduce other panels of a figure;
    /// `coil scenes` lists them with their commands.
    #[serde(default, rename = "variant")]
    pub variants: Vec<Variant>,
}

/// A named set of overrides of a scene.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    pub name: String,
    pub description: String,
    /// `KEY=VALUE` overrides, as given to `--set`.
    pub set: Vec<String>,
}

/// The box that holds every particle (m); particles that leave it are removed and counted.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Domain {
    pub min_m: [f64; 3],
    pub max_m: [f64; 3],
    /// Axes (x, y, z) along which the domain wraps around: a particle leaving through one face
    /// re-enters through the opposite one, and neighbors are found across the seam. Each such
    /// length must be at least 3 support radii and a whole number of particle spacings.
    #[serde(default)]
    pub periodic: [bool; 3],
}

impl Domain {
    pub fn is_periodic(&self) -> bool {
        self.periodic.iter().any(|&p| p)
    }

    /// Whether `p` (m) lies in the domain box, its faces included.
    pub fn contains(&self, p: [f64; 3]) -> bool {
        (0..3).all(|a| p[a] >= self.min_m[a] && p[a] <= self.max_m[a])
    }
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// Write a frame every this many simulated seconds.
    pub every_s: Option<f64>,
    /// Or every this many steps.
    pub every_steps: Option<u64>,
    /// File formats of each frame: `vtu` (with the `.pvd` series, for ParaView), `ply` (binary),
    /// `xyz` (positions as f32 triples, which splashsurf meshes directly).
    #[serde(default = "default_formats")]
    pub formats: Vec<FrameFormat>,
    /// How `.vtu` frames hold their arrays: `raw` (appended binary, for ParaView; the default)
    /// or `base64` (inline, which meshio and splashsurf also read).
    #[serde(default, skip_serializing_if = "is_default")]
    pub vtu_encoding: VtuEncoding,
}

/// How a `.vtu` frame holds its arrays.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VtuEncoding {
    /// Appended raw binary: the smallest and fastest to write; ParaView reads it, meshio and
    /// vtkio (splashsurf) do not.
    #[default]
    Raw,
    /// Each array inline in base64 (`format="binary"`, header and data in one stream, as VTK
    /// writes them): a third larger, and read by ParaView, meshio and vtkio alike.
    Base64,
}

/// A file format of output frames.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum FrameFormat {
    Vtu,
    Ply,
    Xyz,
    /// The free surface's mesh (`output::surface`), `frame_NNNNNN.surface.ply`.
    Surface,
}

fn default_formats() -> Vec<FrameFormat> {
    vec![FrameFormat::Vtu]
}

impl Default for Output {
    fn default() -> Self {
        Self { every_s: Some(0.01), every_steps: None, formats: default_formats(), vtu_encoding: VtuEncoding::Raw }
    }
}

/// A block of fluid on the particle lattice, at rest unless given a velocity.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FluidBlock {
    pub min_m: [f64; 3],
    pub max_m: [f64; 3],
    #[serde(default)]
    pub velocity_m_s: [f64; 3],
}

/// A ring of fluid with a vertical axis (the spreading torus of Fig. 3 and 4), on the particle
/// lattice: the points within `minor_radius_m` of the circle of `major_radius_m` around `centre_m`
/// in the horizontal plane.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FluidTorus {
    pub centre_m: [f64; 3],
    pub major_radius_m: f64,
    pub minor_radius_m: f64,
    #[serde(default)]
    pub velocity_m_s: [f64; 3],
}

/// An upright cylinder of fluid (Huppert's fixed-volume release): the lattice points within
/// `radius_m` of the vertical axis through `base_centre_m`, from its height up to
/// `height_m` above it.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FluidCylinder {
    pub base_centre_m: [f64; 3],
    pub radius_m: f64,
    pub height_m: f64,
    #[serde(default)]
    pub velocity_m_s: [f64; 3],
}

/// Walls of fixed virtual particles (paper Sec. III-B), in layers that cover the support.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields, tag = "shape", rename_all = "snake_case")]
pub enum Boundary {
    /// Walls around the interior `min_m`..`max_m`; `open_top` leaves out the lid (max y).
    Box {
        min_m: [f64; 3],
        max_m: [f64; 3],
        #[serde(default)]
        open_top: bool,
    },
    /// A horizontal plate whose top surface is at `height_m` (y), spanning x and z between
    /// `min_xz_m` and `max_xz_m` (default: the whole domain, a plane).
    Plate { height_m: f64, min_xz_m: Option<[f64; 2]>, max_xz_m: Option<[f64; 2]> },
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields, tag = "shape", rename_all = "snake_case")]
pub enum Nozzle {
    Circle {
        radius_m: f64,
    },
    /// `width_m` along the first in-plane axis, `depth_m` along the second (see `inlet`).
    Rectangle {
        width_m: f64,
        depth_m: f64,
    },
}

/// A jet inlet (paper Sec. III-C): layers of particles are injected each time the previous
/// layer has moved one layer spacing away, until the particle budget is reached.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InletSettings {
    pub nozzle: Nozzle,
    /// Nozzle centre at t = 0 (m).
    pub position_m: [f64; 3],
    /// Direction of the jet (normalised at load).
    pub direction: [f64; 3],
    /// Jet speed (m/s).
    pub speed_m_s: f64,
    /// Injection starts at this time (s).
    #[serde(default)]
    pub start_s: f64,
    /// Injection stops at this time (s).
    pub stop_s: Option<f64>,
    /// How the nozzle moves (stitching patterns, Fig. 9).
    pub motion: Option<NozzleMotion>,
    /// Largest sideways offset of a layer from the nozzle axis (m), drawn per layer from a
    /// fixed pseudo-random sequence: the nozzle's wobble. A jet that is symmetric to round-off
    /// buckles only after many seconds; a real jet always carries such noise.
    #[serde(default)]
    pub wobble_m: f64,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields, untagged)]
pub enum NozzleMotion {
    /// Constant velocity (m/s).
    Velocity { velocity_m_s: [f64; 3] },
    /// Piecewise-linear path through `[t_s, x_m, y_m, z_m]` waypoints, held at the ends.
    Waypoints { waypoints: Vec<[f64; 4]> },
}

/// A number as an error message prints it: plainly when that is short, else in scientific
/// notation to four digits (`1e308`, not 309 digits).
pub fn short(v: f64) -> String {
    let plain = v.to_string();
    if plain.len() <= 9 {
        return plain;
    }
    let rounded: f64 = format!("{v:.3e}").parse().unwrap_or(v);
    format!("{rounded:e}")
}
