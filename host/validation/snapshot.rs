//! Runs a validation scene on the CPU and samples its fluid at given times, in f64 whatever the
//! run's precision, so each case compares plain numbers with its reference.

use crate::cpu::simulation::CpuSimulation;
use crate::scene::setup::{initial_particles, InitialParticles};
use crate::scene::Scene;
use crate::simulation::model::Model;
use crate::simulation::variant::{with_precision_and_model, WithModel};
use coil_kernels::{Real, Vec3};

/// The fluid particles of a run at one time.
#[derive(Debug, Clone, Default)]
pub struct Snapshot {
    /// Simulated time (s).
    pub time_s: f64,
    /// Positions (m).
    pub position: Vec<[f64; 3]>,
    /// Velocities at the full step (m/s).
    pub velocity: Vec<[f64; 3]>,
    /// Pressure by Eq. (6) (Pa).
    pub pressure: Vec<f64>,
    /// Density (kg/m^3).
    pub density: Vec<f64>,
}

impl Snapshot {
    /// The largest fluid speed (m/s).
    pub fn max_speed(&self) -> f64 {
        self.velocity.iter().map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()).fold(0.0, f64::max)
    }
}

/// Gravity (m/s^2) as a function of time (s), for cases that ramp it up.
pub type GravitySchedule<'a> = &'a (dyn Fn(f64) -> [f64; 3] + Sync);

/// Runs `scene` (in its precision) and takes a snapshot at each of `times` (s, increasing),
/// stepping exactly onto them; `gravity`, when given, replaces the scene's g before each step.
/// Errors name the scene and the instability.
pub fn snapshots(scene: &Scene, times: &[f64], gravity: Option<GravitySchedule>) -> Result<Vec<Snapshot>, String> {
    let initial = initial_particles(scene, &scene.name).map_err(|e| e.to_string())?;
    snapshots_from(scene, &initial, times, gravity)
}

/// [`snapshots`] from given initial particles (for fields a scene file cannot describe).
pub fn snapshots_from(
    scene: &Scene,
    initial: &InitialParticles,
    times: &[f64],
    gravity: Option<GravitySchedule>,
) -> Result<Vec<Snapshot>, String> {
    let run = Sample { scene, initial, times, gravity };
    with_precision_and_model(scene.simulation.precision, scene, run).map_err(|e| format!("{}: {e}", scene.name))
}

struct Sample<'a> {
    scene: &'a Scene,
    initial: &'a InitialParticles,
    times: &'a [f64],
    gravity: Option<GravitySchedule<'a>>,
}

impl WithModel for Sample<'_> {
    type Output = Result<Vec<Snapshot>, String>;
    fn with<R: Real, M: Model<R>>(self, model: M) -> Self::Output {
        let mut sim = CpuSimulation::<R, M>::new(self.scene, self.initial, model);
        let mut out = Vec::with_capacity(self.times.len());
        for &t in self.times {
            while sim.run.time < t * (1.0 - 1e-12) {
                if let Some(g) = self.gravity {
                    let [x, y, z] = g(sim.run.time).map(R::from_f64);
                    sim.run.fluid.gravity = Vec3::new(x, y, z);
                }
                let (dt, limit) = sim.next_dt();
                sim.step_with(dt.min(t - sim.run.time), limit).map_err(|e| e.to_string())?;
            }
            out.push(snapshot(&sim));
        }
        Ok(out)
    }
}

fn snapshot<R: Real, M: Model<R>>(sim: &CpuSimulation<R, M>) -> Snapshot {
    let host = sim.host();
    let (p, neighborhood) = (&host.particles, host.neighborhood());
    let mut s = Snapshot { time_s: sim.run.time, ..Snapshot::default() };
    for i in (0..p.len()).filter(|&i| !sim.run.fluid.is_boundary(p.id[i])) {
        s.position.push([0, 1, 2].map(|a| p.position[a][i]));
        s.velocity.push([0, 1, 2].map(|a| p.velocity[a][i].to_f64()));
        s.pressure.push(host.pressure(i, &sim.run.fluid, &neighborhood).to_f64());
        s.density.push(p.density[i].to_f64());
    }
    s
}
