//! The free surface of a frame's fluid: marching cubes over an SPH density field of the particles
//! (`splashsurf_lib`, Löschner et al.'s splashsurf), with the viscosity and speed of the fluid
//! interpolated to the vertices so a mesh can be coloured as the particles are. Written as
//! binary PLY (vertices with normals and both fields, triangles) or OBJ.

use crate::output::vtu_read::FrameData;
use splashsurf_lib::nalgebra::Vector3;
use splashsurf_lib::sph_interpolation::SphInterpolator;
use splashsurf_lib::{reconstruct_surface, Parameters, SpatialDecomposition};
use std::fmt::Write as _;
use std::path::Path;

/// What the reconstruction takes from the run, and its own knobs, in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceParameters {
    /// Radius of the sphere of each particle's volume (m): (3/(4 pi))^(1/3) spacings, so that
    /// the spheres hold the fluid's volume.
    pub particle_radius_m: f64,
    /// Support radius of the density field's kernel (m): the run's h.
    pub support_radius_m: f64,
    /// Edge of the marching cubes (m).
    pub cube_size_m: f64,
    /// The surface is where the density field reaches this fraction of rho0.
    pub iso_threshold: f64,
    /// rho0 (kg/m^3), and the particle mass (kg), for the interpolation of the fields.
    pub rest_density: f64,
    pub particle_mass: f64,
}

impl SurfaceParameters {
    /// Defaults for a run of particle `spacing_m` and support radius `h_m`: cubes of half a
    /// spacing and the iso-surface at 0.6 rho0 (splashsurf's own default).
    pub fn for_run(spacing_m: f64, h_m: f64, rest_density: f64) -> Self {
        Self {
            particle_radius_m: spacing_m * (3.0 / (4.0 * std::f64::consts::PI)).cbrt(),
            support_radius_m: h_m,
            cube_size_m: 0.5 * spacing_m,
            iso_threshold: 0.6,
            rest_density,
            particle_mass: rest_density * spacing_m.powi(3),
        }
    }
}

impl SurfaceParameters {
    /// [`SurfaceParameters::for_run`] of `scene`'s spacing, h and rho0.
    pub fn of_scene(scene: &crate::scene::Scene) -> Self {
        let material = &scene.material;
        Self::for_run(material.particle_spacing_m, scene.support_radius(), material.rest_density_kg_m3)
    }
}

/// A triangle mesh with a normal and the fluid's viscosity (m^2/s) and speed (m/s) at each
/// vertex; triangles wind counter-clockwise seen from outside the fluid.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SurfaceMesh {
    pub vertices: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub viscosity: Vec<f32>,
    pub speed: Vec<f32>,
    pub triangles: Vec<[u32; 3]>,
}

/// The fluid particles a surface is made from.
#[derive(Debug, Clone, Copy)]
pub struct Fluid<'a> {
    /// m
    pub position: &'a [[f64; 3]],
    /// kg/m^3
    pub density: &'a [f32],
    /// m^2/s
    pub viscosity: &'a [f32],
    /// m/s
    pub velocity: &'a [[f32; 3]],
}

impl<'a> Fluid<'a> {
    /// The fluid of a frame read back; its arrays must be there.
    pub fn of(frame: &'a FrameData) -> Result<Self, String> {
        let scalar = |name: &str| frame.scalars.get(name).map(Vec::as_slice).ok_or(format!("the frame has no {name} array"));
        Ok(Fluid {
            position: &frame.position,
            density: scalar("density")?,
            viscosity: scalar("viscosity")?,
            velocity: frame.vectors.get("velocity").map(Vec::as_slice).ok_or("the frame has no velocity array")?,
        })
    }
}

/// The surface of `fluid`; an empty mesh where there is no fluid.
pub fn reconstruct(fluid: Fluid<'_>, p: &SurfaceParameters) -> Result<SurfaceMesh, String> {
    if fluid.position.is_empty() {
        return Ok(SurfaceMesh::default());
    }
    let positions: Vec<Vector3<f32>> =
        fluid.position.iter().map(|x| Vector3::new(x[0] as f32, x[1] as f32, x[2] as f32)).collect();
    let mut parameters = Parameters::new(p.particle_radius_m as f32, p.support_radius_m as f32, p.cube_size_m as f32);
    parameters.rest_density = p.rest_density as f32;
    parameters.iso_surface_threshold = p.iso_threshold as f32;
    // Frames are meshed in parallel, one a thread.
    parameters.enable_multi_threading = false;
    parameters.spatial_decomposition = SpatialDecomposition::None;
    let surface = reconstruct_surface::<i64, f32>(&positions, &parameters).map_err(|e| format!("surface reconstruction: {e}"))?;
    let mesh = surface.mesh;
    u32::try_from(mesh.vertices.len()).map_err(|_| "more than 2^32 vertices".to_string())?;
    let interpolator = SphInterpolator::new(&positions, fluid.density, p.particle_mass as f32, p.support_radius_m as f32);
    let normals = interpolator.interpolate_normals(&mesh.vertices);
    let field = |values: &[f32]| interpolator.interpolate_scalar_quantity(values, &mesh.vertices, true);
    Ok(SurfaceMesh {
        vertices: mesh.vertices.iter().map(|v| [v.x, v.y, v.z]).collect(),
        normals: normals.iter().map(|n| [n.x, n.y, n.z]).collect(),
        viscosity: field(fluid.viscosity),
        speed: field(&crate::output::preview::speeds(fluid.velocity)),
        triangles: mesh.triangles.iter().map(|t| t.map(|k| k as u32)).collect(),
    })
}

impl SurfaceMesh {
    /// Binary little-endian PLY: x y z nx ny nz viscosity speed per vertex, then the triangles.
    pub fn to_ply(&self) -> Vec<u8> {
        let mut out = String::new();
        let _ = write!(
            out,
            "ply\nformat binary_little_endian 1.0\ncomment coil free surface: viscosity in m^2/s, speed in m/s\n\
             element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
             property float nx\nproperty float ny\nproperty float nz\nproperty float viscosity\nproperty float speed\n\
             element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
            self.vertices.len(),
            self.triangles.len()
        );
        let mut bytes = out.into_bytes();
        for k in 0..self.vertices.len() {
            let values = [self.vertices[k].as_slice(), self.normals[k].as_slice(), &[self.viscosity[k], self.speed[k]]].concat();
            for v in values {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        for t in &self.triangles {
            bytes.push(3);
            for k in t {
                bytes.extend_from_slice(&k.to_le_bytes());
            }
        }
        bytes
    }

    /// Wavefront OBJ: vertices, normals and triangles.
    pub fn to_obj(&self) -> Vec<u8> {
        let mut out = String::from("# coil free surface, m\n");
        for v in &self.vertices {
            let _ = writeln!(out, "v {} {} {}", v[0], v[1], v[2]);
        }
        for n in &self.normals {
            let _ = writeln!(out, "vn {} {} {}", n[0], n[1], n[2]);
        }
        for t in &self.triangles {
            let [a, b, c] = t.map(|k| k + 1);
            let _ = writeln!(out, "f {a}//{a} {b}//{b} {c}//{c}");
        }
        out.into_bytes()
    }
}

/// Mesh formats `coil surface` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    Ply,
    Obj,
}

impl MeshFormat {
    pub fn extension(self) -> &'static str {
        match self {
            MeshFormat::Ply => "ply",
            MeshFormat::Obj => "obj",
        }
    }
}

/// The mesh file beside frame `frame`: `frame_0040.vtu` gives `frame_0040.surface.ply`.
pub fn mesh_path(frame: &Path, format: MeshFormat) -> std::path::PathBuf {
    frame.with_extension(format!("surface.{}", format.extension()))
}
