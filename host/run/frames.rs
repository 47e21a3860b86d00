//! The frames of a run: each one in every format the scene asks for, its `--preview` picture,
//! and its entry in the `.pvd` series.

use super::folder::{frame_name, series_path};
use super::summary::WrittenFile;
use super::{io_error, RunError, Tally};
use crate::output::frame::Frame;
use crate::output::preview::{own_range, render, speeds, Coloring, View};
use crate::output::surface::{mesh_path, reconstruct, Fluid, MeshFormat, SurfaceParameters};
use crate::output::vtu::PvdSeries;
use crate::output::write_atomically;
use crate::scene::{FrameFormat, Scene};
use crate::simulation::host_particles::HostParticles;
use crate::simulation::model::Model;
use crate::simulation::{Instability, RunState};
use coil_kernels::Real;
use std::path::{Path, PathBuf};

/// Pixels per panel of `--preview` pictures.
const PREVIEW_SIZE: usize = 480;

pub struct FrameWriter<'a> {
    scene: &'a Scene,
    dir: &'a Path,
    preview: bool,
    /// `None` where the scene writes no `.vtu` frames for a series to list.
    series: Option<PvdSeries>,
    frame: Frame,
    /// The surface meshes' settings, from the run's spacing and h.
    surface: SurfaceParameters,
}

impl<'a> FrameWriter<'a> {
    /// A writer that continues the series after the frames `tally` already counts.
    pub fn new(scene: &'a Scene, dir: &'a Path, preview: bool, tally: &Tally) -> Self {
        let series = scene.output.formats.contains(&FrameFormat::Vtu).then(|| {
            let listed = tally.frame_times.iter().enumerate().map(|(k, &t)| (t, frame_name(k))).collect();
            PvdSeries::new(series_path(dir, &scene.name), listed)
        });
        let surface = SurfaceParameters::of_scene(scene);
        Self { scene, dir, preview, series, frame: Frame::default(), surface }
    }

    /// The `.pvd` file, where the run writes one.
    pub fn series_path(&self) -> Option<PathBuf> {
        self.series.as_ref().map(|s| s.path().to_path_buf())
    }

    /// Gathers the next frame from the run; refuses, as an instability, a frame with a value
    /// that is not finite, so that none is ever written.
    pub fn capture<R: Real, M: Model<R>>(&mut self, run: &RunState<R, M>, host: &HostParticles<R>) -> Result<(), Instability> {
        self.frame.capture(run, host);
        match self.frame.non_finite() {
            None => Ok(()),
            Some((particles, what)) => Err(run.instability(particles, Some(what))),
        }
    }

    /// Writes the frame last captured, at simulated time `time` (s), and counts it in `tally`.
    pub fn write(&mut self, time: f64, tally: &mut Tally) -> Result<(), RunError> {
        let output = &self.scene.output;
        let name = frame_name(tally.frame_times.len());
        let path = self.dir.join(&name);
        for format in &output.formats {
            let surface;
            let (file, bytes) = match format {
                FrameFormat::Vtu => (path.clone(), self.frame.to_vtu(output.vtu_encoding)),
                FrameFormat::Ply => (path.with_extension("ply"), self.frame.to_ply()),
                FrameFormat::Xyz => (path.with_extension("xyz"), self.frame.to_xyz()),
                FrameFormat::Surface => {
                    let file = mesh_path(&path, MeshFormat::Ply);
                    let f = &self.frame;
                    let fluid =
                        Fluid { position: &f.position, density: &f.density, viscosity: &f.viscosity, velocity: &f.velocity };
                    let mesh =
                        reconstruct(fluid, &self.surface).map_err(|e| io_error("surface", &file, std::io::Error::other(e)))?;
                    surface = mesh.to_ply();
                    (file, surface.as_slice())
                }
            };
            write_atomically(&file, bytes).map_err(|e| io_error("frame", &file, e))?;
            let name = file.file_name().expect("a frame file has a name").to_string_lossy().into_owned();
            tally.frame_files.push(WrittenFile::of(name, bytes));
        }
        if self.preview {
            self.write_preview(&path.with_extension("png"))?;
        }
        if let Some(series) = &mut self.series {
            series.push(time, &name).map_err(|e| io_error("series", series.path(), e))?;
        }
        tally.frame_times.push(time);
        Ok(())
    }

    fn write_preview(&self, png: &Path) -> Result<(), RunError> {
        let (frame, v) = (&self.frame, &self.scene.material.viscosity);
        // The paper's colouring, nu_inf to nu0; a Newtonian fluid has one colour, so speed.
        let image = if v.nu_inf() < v.nu0_m2_s {
            render(&frame.position, &frame.viscosity, (v.nu_inf(), v.nu0_m2_s), View::Both, PREVIEW_SIZE)
        } else {
            let speed = speeds(&frame.velocity);
            render(&frame.position, &speed, own_range(Coloring::Speed, &speed), View::Both, PREVIEW_SIZE)
        };
        image.save(png).map_err(|e| io_error("preview", png, e))
    }
}
