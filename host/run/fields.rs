//! Which fields of a scene a checkpoint holds to and which a resumed run may change: the
//! scene's physics and its fingerprint, and the rest.

use crate::fnv1a::fnv1a;
use crate::scene::Scene;

/// Fields of a scene that a resumed run may change, as `--set` spells them (a section stands for
/// every field in it): how far it runs, how it picks dt, and how far its solvers iterate (to get
/// past an instability or an unconverged solve from the last good frame), and what it writes.
/// The numerical controls of the solves change how closely a step meets the equations, not
/// which equations: what a wall pushes with (`divergence_free.wall_pressure`) is physics, and
/// stays.
pub const RESUMABLE: [&str; 13] = [
    "simulation.end_time_s",
    "simulation.time_step",
    "simulation.divergence_free.density_tolerance",
    "simulation.divergence_free.divergence_tolerance",
    "simulation.divergence_free.max_iterations",
    "simulation.divergence_free.min_iterations",
    "simulation.divergence_free.relaxation",
    "simulation.divergence_free.chebyshev_radius",
    "simulation.divergence_free.on_no_convergence",
    "simulation.divergence_free.cfl_factor",
    "simulation.divergence_free.max_time_step_s",
    "material.viscosity.implicit",
    "output",
];

/// The fields that fix what a step computes, as `--set` spells them: a checkpoint resumes only a
/// scene that agrees with the one it was taken from on each (array sections as a whole). A field
/// added to the scene joins this list only if it changes the physics, and must then be left out
/// of the serialized scene at its default, so that checkpoints taken before it existed resume.
pub const PHYSICS: [&str; 32] = [
    "material.rest_density_kg_m3",
    "material.sound_speed_m_s",
    "material.clamp_negative_pressure",
    "material.pressure_gradient",
    "material.density_kernel",
    "material.density_equation",
    "material.density_diffusion",
    "material.particle_spacing_m",
    "material.support_radius_factor",
    "material.gravity_m_s2",
    "material.viscosity.operator",
    "material.viscosity.nu0_m2_s",
    "material.viscosity.nu_inf_m2_s",
    "material.viscosity.cross_k_s",
    "material.viscosity.cross_n",
    "material.viscosity.hourglass_control",
    "material.viscosity.velocity_gradient",
    "material.viscosity.solver",
    "domain.min_m",
    "domain.max_m",
    "domain.periodic",
    "simulation.precision",
    "simulation.max_fluid_particles",
    "simulation.walls",
    "simulation.particle_shifting",
    "simulation.pressure",
    "simulation.divergence_free.wall_pressure",
    "fluid_block",
    "fluid_torus",
    "fluid_cylinder",
    "boundary",
    "inlet",
];

/// Identifies the physics of `scene` (resolved, as `run.json` logs it): a hash of the
/// [`PHYSICS`] fields, each with its name, in that order.
pub fn fingerprint(scene: &Scene) -> u64 {
    let json = serde_json::to_value(super::run_log::resolved(scene)).expect("a scene serialises");
    let mut bytes = Vec::new();
    for field in PHYSICS {
        let value = field.split('.').try_fold(&json, |v, key| v.get(key));
        if let Some(value) = value.filter(|v| !v.is_null()) {
            bytes.extend_from_slice(field.as_bytes());
            bytes.push(b'=');
            serde_json::to_writer(&mut bytes, value).expect("a value serialises");
            bytes.push(b'\n');
        }
    }
    fnv1a(&bytes)
}
