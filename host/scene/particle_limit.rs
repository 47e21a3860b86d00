//! How many particles a run can hold on this machine. Particle ids are 32-bit, and every
//! particle's arrays must fit in memory. Setup checks both before it allocates, so an
//! oversized scene (a misplaced zero in `max_fluid_particles`, a spacing ten times too fine)
//! is refused with its numbers instead of aborting in the allocator.

use crate::scene::Scene;
use crate::simulation::model::Model;
use crate::simulation::particles::Particles;
use crate::simulation::variant::{with_precision_and_model, WithModel};
use coil_kernels::neighbor_list::NEIGHBOR_SLOTS;
use coil_kernels::Real;

/// Bytes per particle beyond its arrays while the run allocates them: setup's position and
/// velocity (or mirror image) in f64, the neighbor grid's cell key and sorted order (u32), and
/// the CPU backend's neighbor list (a device run's host holds no list: the limit is the CPU's).
const SETUP_AND_GRID_BYTES: usize = 2 * 3 * 8 + 2 * 4 + 4 * NEIGHBOR_SLOTS;

/// The most particles, walls and fluid capacity together, a run of one scene can hold here.
#[derive(Debug, Clone)]
pub struct ParticleLimit {
    pub most: f64,
    /// What sets `most`, for the error.
    pub why: String,
}

impl ParticleLimit {
    /// The limit on this machine.
    pub fn of(scene: &Scene) -> Self {
        Self::with_memory(scene, memory_bytes())
    }

    /// The limit with `memory` bytes of memory (`None`: unknown, so only the ids limit).
    pub fn with_memory(scene: &Scene, memory: Option<u64>) -> Self {
        let per_particle =
            with_precision_and_model(scene.simulation.precision, scene, BytesPerParticle(scene)) + SETUP_AND_GRID_BYTES;
        let ids = u32::MAX as f64;
        match memory.map(|bytes| (bytes, bytes as f64 / per_particle as f64)) {
            Some((bytes, fit)) if fit < ids => Self {
                most: fit,
                why: format!(
                    "at about {per_particle} bytes a particle (this precision, viscosity operator and formulation), this machine's {:.1} GiB of memory holds about {fit:.3e} particles",
                    bytes as f64 / (1u64 << 30) as f64
                ),
            },
            _ => Self { most: ids, why: format!("particle ids are 32-bit, so a run holds at most {} particles", u32::MAX) },
        }
    }
}

struct BytesPerParticle<'a>(&'a Scene);

impl WithModel for BytesPerParticle<'_> {
    type Output = usize;
    fn with<R: Real, M: Model<R>>(self, _model: M) -> usize {
        Particles::<R>::bytes_per_particle_with(M::FIELDS.with_scene(self.0))
    }
}

/// This machine's memory (bytes), or the container's limit where that is lower; `None` where
/// neither can be read (outside Linux).
fn memory_bytes() -> Option<u64> {
    let total = std::fs::read_to_string("/proc/meminfo").ok().and_then(|info| {
        let kib =
            info.lines().find_map(|l| l.strip_prefix("MemTotal:"))?.trim().strip_suffix("kB")?.trim().parse::<u64>().ok()?;
        Some(kib * 1024)
    });
    let container = std::fs::read_to_string("/sys/fs/cgroup/memory.max").ok().and_then(|m| m.trim().parse::<u64>().ok());
    match (total, container) {
        (Some(t), Some(c)) => Some(t.min(c)),
        (t, c) => t.or(c),
    }
}
