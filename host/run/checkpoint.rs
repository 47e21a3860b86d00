//! `checkpoint.bin` in a run's output folder: the whole state of the run at its latest frame
//! (or where Ctrl-C stopped it), from which `coil resume` continues bit for bit as if the run
//! had never stopped.
//!
//! Only what a step reads from the step before is kept: the carried arrays of the live
//! particles in their current order (`simulation::carried_state`, whose list gives their order
//! here; the next sort is stable in that order), the clock and dt of the last step, the
//! diagnostics the next dt reads, each inlet's progress, and the frame schedule and running
//! figures of the summary (the solvers' iterations among them). Everything else (walls' mirror images, the grid, stresses, accelerations) is rebuilt from
//! the scene or recomputed by the next step.
//!
//! Layout, little-endian: magic, format version, bytes of a real (4 or 8), the scene's
//! fingerprint, the fields in the order `write` gives them, and an FNV-1a checksum of all the
//! bytes before it, so a damaged file is refused rather than misread.

use super::checkpoint_arrays::{ReadCarried, WriteCarried};
use super::checkpoint_bytes::{Reader, Writer};
use super::fields::fingerprint;
use super::summary::{Tally, WrittenFile};
use crate::fnv1a::fnv1a;
use crate::scene::Scene;
use crate::simulation::model::Model;
use crate::simulation::particles::Particles;
use crate::simulation::run_state::SolveStatistics;
use crate::simulation::{Diagnostics, RunState, Setup};
use crate::time_step::Limit;
use coil_kernels::Real;
use std::marker::PhantomData;
use std::path::Path;

const MAGIC: &[u8; 8] = b"COILCKPT";
/// 2: the fingerprint hashes the `fields::PHYSICS` fields only. 3: the frame files' sizes and
/// digests. 4: a flag after the densities, then the implicit solve's viscous change where it
/// is set (a version 3 checkpoint, which has neither, is read as unset). 5: then a flag and
/// the pressure solves' stiffness sums where pressure is solved. 6: then the iterations of the
/// run's implicit viscosity, divergence and density solves, which its summary reports.
const FORMAT_VERSION: u32 = 6;

/// The largest checkpoint read (bytes): a billion particles in f64.
const MAX_CHECKPOINT_BYTES: u64 = 1 << 37;

fn limit_code(limit: Limit) -> u8 {
    match limit {
        Limit::Acoustic => 0,
        Limit::Viscous => 1,
        Limit::Velocity => 2,
        Limit::Fixed => 3,
        Limit::Cfl => 4,
        Limit::Largest => 5,
    }
}

fn limit_from(code: u8) -> Option<Limit> {
    [Limit::Acoustic, Limit::Viscous, Limit::Velocity, Limit::Fixed, Limit::Cfl, Limit::Largest].get(usize::from(code)).copied()
}

/// A checkpoint read from disk, its particle arrays still encoded until they are restored into
/// a run of the right precision.
pub struct Checkpoint {
    /// Bytes of one real: 4 (f32) or 8 (f64).
    pub real_bytes: usize,
    pub fingerprint: u64,
    pub time: f64,
    pub steps: u64,
    previous_dt: Option<f64>,
    removed: u64,
    injected: u64,
    capacity_reached_at: Option<f64>,
    fluid_count: usize,
    next_id: u32,
    diagnostics: Diagnostics,
    last_dt: f64,
    last_limit: Limit,
    /// Each inlet's travelled distance (m) and layers injected.
    inlets: Vec<(f64, u64)>,
    pub tally: Tally,
    /// Live particles, boundary included.
    pub particles: usize,
    /// Where the particle arrays start and end in `bytes`.
    particle_data: std::ops::Range<usize>,
    /// The implicit viscosity, divergence and density solves of the run so far (none counted
    /// in a checkpoint before version 6).
    solves: [SolveStatistics; 3],
    /// The format version the checkpoint was written in.
    version: u32,
    bytes: Vec<u8>,
}

/// The checkpoint of the run `sim` with its particles `p` (current on the host) and the drive's
/// `tally`, as bytes.
pub fn encode<R: Real, M: Model<R>>(sim: &RunState<R, M>, p: &Particles<R>, scene: &Scene, tally: &Tally) -> Vec<u8> {
    let diagnostics = &sim.diagnostics;
    let n = p.len();
    let mut w = Writer(Vec::with_capacity(256 + n * (24 + 7 * std::mem::size_of::<R>() + 4)));
    w.0.extend_from_slice(MAGIC);
    w.u32(FORMAT_VERSION);
    w.u8(std::mem::size_of::<R>() as u8);
    w.u64(fingerprint(scene));
    w.f64(sim.time);
    w.u64(sim.steps);
    w.optional_f64(sim.previous_dt);
    w.u64(sim.removed);
    w.u64(sim.injected);
    w.optional_f64(sim.capacity_reached_at);
    w.u64(sim.fluid_count() as u64);
    w.u32(sim.next_id);
    w.f64(diagnostics.max_speed);
    w.f64(diagnostics.max_compression);
    w.u64(diagnostics.bad_particles);
    w.f64(sim.last_dt);
    w.u8(limit_code(sim.last_limit));
    w.u64(sim.inlets().len() as u64);
    for inlet in sim.inlets() {
        let (travelled, layers) = inlet.progress();
        w.f64(travelled);
        w.u64(layers);
    }
    w.u64(tally.frame_times.len() as u64);
    w.f64s(&tally.frame_times);
    w.u64(tally.frame_files.len() as u64);
    for file in &tally.frame_files {
        w.u64(file.name.len() as u64);
        w.0.extend_from_slice(file.name.as_bytes());
        w.u64(file.bytes);
        w.u64(file.digest);
    }
    w.f64(tally.next_frame_time);
    w.f64(tally.particle_steps);
    w.f64(tally.max_compression);
    w.f64(tally.max_speed);
    w.f64(tally.wall_s);
    w.u64(n as u64);
    crate::visit_carried!(ref &mut WriteCarried::<R> { w: &mut w, n, real: PhantomData }; p);
    for solves in [&sim.solves, &sim.divergence_solves, &sim.density_solves] {
        w.u64(solves.steps);
        w.u64(solves.iterations);
        w.u32(solves.largest_iterations);
        w.u64(solves.unconverged);
    }
    let sum = fnv1a(&w.0);
    w.u64(sum);
    w.0
}

/// Writes the checkpoint (see [`encode`]) to `dir` through a temporary name, so the one there
/// is always whole.
pub fn write<R: Real, M: Model<R>>(
    dir: &Path,
    sim: &RunState<R, M>,
    p: &Particles<R>,
    scene: &Scene,
    tally: &Tally,
) -> std::io::Result<()> {
    crate::output::write_atomically(&dir.join(super::folder::CHECKPOINT), &encode(sim, p, scene, tally))
}

impl Checkpoint {
    /// Reads and checks `path`; the error says what is wrong with the file.
    pub fn read(path: &Path) -> Result<Self, String> {
        let bytes = crate::regular_file::read(path, MAX_CHECKPOINT_BYTES).map_err(|e| format!("cannot be read: {e}"))?;
        Self::decode(bytes)
    }

    /// Parses a checkpoint's bytes, checking its magic, version and checksum.
    pub fn decode(bytes: Vec<u8>) -> Result<Self, String> {
        if bytes.len() < MAGIC.len() + 8 || &bytes[..MAGIC.len()] != MAGIC {
            return Err("is not a coil checkpoint".into());
        }
        let (body, sum) = bytes.split_at(bytes.len() - 8);
        if fnv1a(body) != u64::from_le_bytes(sum.try_into().expect("8 bytes")) {
            return Err("is damaged or cut short (its checksum does not match)".into());
        }
        let mut r = Reader { bytes: body, at: MAGIC.len() };
        let version = r.u32("the format version")?;
        if !(3..=FORMAT_VERSION).contains(&version) {
            return Err(format!("has format version {version}; this coil reads versions 3 to {FORMAT_VERSION}"));
        }
        let real_bytes = usize::from(r.u8("the precision")?);
        if real_bytes != 4 && real_bytes != 8 {
            return Err(format!("gives {real_bytes} bytes a real; only 4 (f32) and 8 (f64) exist"));
        }
        let fingerprint = r.u64("the scene's fingerprint")?;
        let time = r.f64("the time")?;
        let steps = r.u64("the step count")?;
        let previous_dt = r.optional_f64("the last dt")?;
        let removed = r.u64("the removed count")?;
        let injected = r.u64("the injected count")?;
        let capacity_reached_at = r.optional_f64("the capacity time")?;
        let fluid_count = r.u64("the fluid count")? as usize;
        let next_id = r.u32("the next id")?;
        let diagnostics = Diagnostics {
            max_speed: r.f64("the diagnostics")?,
            max_compression: r.f64("the diagnostics")?,
            bad_particles: r.u64("the diagnostics")?,
        };
        let last_dt = r.f64("the last dt")?;
        let code = r.u8("the dt limit")?;
        let last_limit = limit_from(code).ok_or_else(|| format!("gives an unknown dt limit {code}"))?;
        let inlet_count = r.count(16, "inlets")?;
        let inlets =
            (0..inlet_count).map(|_| Ok((r.f64("an inlet")?, r.u64("an inlet")?))).collect::<Result<Vec<_>, String>>()?;
        let frame_count = r.count(8, "frames")?;
        let frame_times = (0..frame_count).map(|_| r.f64("the frame times")).collect::<Result<Vec<_>, _>>()?;
        let file_count = r.count(24, "frame files")?;
        let frame_files = (0..file_count)
            .map(|_| {
                let length = r.count(1, "a frame file's name")?;
                let name = String::from_utf8(r.take(length, "a frame file's name")?.to_vec())
                    .map_err(|_| "gives a frame file's name that is not UTF-8".to_string())?;
                Ok(WrittenFile { name, bytes: r.u64("a frame file's size")?, digest: r.u64("a frame file's digest")? })
            })
            .collect::<Result<Vec<_>, String>>()?;
        let tally = Tally {
            frame_times,
            frame_files,
            next_frame_time: r.f64("the frame schedule")?,
            particle_steps: r.f64("the summary's figures")?,
            max_compression: r.f64("the summary's figures")?,
            max_speed: r.f64("the summary's figures")?,
            wall_s: r.f64("the summary's figures")?,
        };
        let particles = r.count(1, "particles")?;
        // The solves' iterations close the file, so the carried arrays (`carried_state`), which
        // `restore` reads, lie between.
        let solves_bytes = if version >= 6 { 3 * (8 + 8 + 4 + 8) } else { 0 };
        let end = body.len().checked_sub(solves_bytes).filter(|&e| e >= r.at).ok_or("ends inside the solves' iterations")?;
        let particle_data = r.at..end;
        r.at = end;
        let mut solves = [SolveStatistics::default(); 3];
        if version >= 6 {
            for s in &mut solves {
                s.steps = r.u64("the solves' iterations")?;
                s.iterations = r.u64("the solves' iterations")?;
                s.largest_iterations = r.u32("the solves' iterations")?;
                s.unconverged = r.u64("the solves' iterations")?;
            }
        }
        Ok(Self {
            real_bytes,
            fingerprint,
            time,
            steps,
            previous_dt,
            removed,
            injected,
            capacity_reached_at,
            fluid_count,
            next_id,
            diagnostics,
            last_dt,
            last_limit,
            inlets,
            tally,
            particles,
            particle_data,
            solves,
            version,
            bytes,
        })
    }

    /// Puts the checkpoint's state into `setup`, a run just set up from the scene it was taken
    /// from (the caller has compared fingerprints). The error names what does not fit.
    pub fn restore<R: Real, M: Model<R>>(&self, setup: &mut Setup<R, M>) -> Result<(), String> {
        let (sim, p) = (&mut setup.run, &mut setup.host.particles);
        if self.real_bytes != std::mem::size_of::<R>() {
            return Err(format!("holds {}-byte reals, and the run is {}", self.real_bytes, R::NAME));
        }
        let boundary = sim.boundary_count();
        if self.particles > p.capacity() || self.fluid_count + boundary != self.particles {
            return Err(format!(
                "holds {} particles ({} fluid) where the scene has {boundary} wall particles and room for {} in all",
                self.particles,
                self.fluid_count,
                p.capacity()
            ));
        }
        if self.inlets.len() != sim.inlets().len() {
            return Err(format!("holds {} inlets where the scene has {}", self.inlets.len(), sim.inlets().len()));
        }
        let n = self.particles;
        p.set_len(n);
        let bytes = &self.bytes[..self.particle_data.end];
        let mut read = ReadCarried::<R> {
            r: Reader { bytes, at: self.particle_data.start },
            n,
            real_bytes: self.real_bytes,
            version: self.version,
            result: Ok(()),
            real: PhantomData,
        };
        crate::visit_carried!(mut &mut read; p);
        read.result?;
        if read.r.at != bytes.len() {
            return Err(format!("has {} bytes past its particles", bytes.len() - read.r.at));
        }
        if p.id[..n].iter().any(|&id| id >= self.next_id) {
            return Err(format!("holds a particle id at or above its next id {}", self.next_id));
        }
        for (inlet, &(travelled, layers)) in sim.inlets.iter_mut().zip(&self.inlets) {
            inlet.set_progress(travelled, layers);
        }
        sim.restore_clock(self.time, self.steps, self.previous_dt, self.last_dt, self.last_limit);
        sim.restore_counts(self.fluid_count, self.removed, self.injected, self.next_id, self.capacity_reached_at);
        sim.diagnostics = self.diagnostics;
        [sim.solves, sim.divergence_solves, sim.density_solves] = self.solves;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simulation::carried_state::{Carried, VisitCarried};
    use crate::simulation::particle_array::ParticleArray;
    use crate::simulation::particles::ModelFields;

    /// The latest format version that kept each carried array.
    struct Latest(u32);

    impl<'a> VisitCarried<&'a [ParticleArray<f64>], &'a [ParticleArray<f64>], &'a [ParticleArray<u32>]> for Latest {
        fn wide(&mut self, array: Carried, _: &'a [ParticleArray<f64>]) {
            self.0 = self.0.max(array.since);
        }
        fn real(&mut self, array: Carried, _: &'a [ParticleArray<f64>]) {
            self.0 = self.0.max(array.since);
        }
        fn index(&mut self, array: Carried, _: &'a [ParticleArray<u32>]) {
            self.0 = self.0.max(array.since);
        }
    }

    /// An array added to the carried state names the format version that first keeps it, and
    /// the checkpoint writes that version or a later one.
    #[test]
    fn the_format_version_keeps_every_carried_array() {
        let every = ModelFields { density_rate: true, implicit: true, pressure_solve: true, ..ModelFields::default() };
        let p = Particles::<f64>::with_capacity(1, every);
        let mut latest = Latest(0);
        crate::visit_carried!(ref &mut latest; p);
        assert!(latest.0 <= FORMAT_VERSION, "an array kept since version {} > {FORMAT_VERSION}", latest.0);
        assert!(latest.0 >= 5, "the pressure solves' state, since version 5, is visited");
    }
}
