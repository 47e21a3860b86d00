//! The spreading torus of the paper's Fig. 3: the shipped `torus` scene with Cross K = 0, 1, 10
//! and 100 s. More shear thinning (larger K) lowers the viscosity at the shear rates of the
//! spreading, so at a fixed time the torus must have spread further the larger K is.

use super::snapshot::{snapshots, Snapshot};
use crate::scene::Scene;

/// The outer radius of a spreading torus (m): the mean horizontal distance from the axis of its
/// outermost tenth of particles, which follows the rim without hanging on one straggler.
pub fn spread_radius(snapshot: &Snapshot) -> f64 {
    let mut r: Vec<f64> = snapshot.position.iter().map(|x| (x[0] * x[0] + x[2] * x[2]).sqrt()).collect();
    r.sort_by(|a, b| b.total_cmp(a));
    let outer = &r[..(r.len() / 10).max(1)];
    outer.iter().sum::<f64>() / outer.len() as f64
}

/// The shipped torus at `spacing_m` with Cross K = `k_s`, run to `time_s`: its spread radius
/// then and at t = 0 (m).
pub fn spread(torus: &Scene, spacing_m: f64, k_s: f64, time_s: f64) -> Result<(f64, f64), String> {
    let mut scene = torus.clone();
    scene.material.particle_spacing_m = spacing_m;
    scene.material.viscosity.cross_k_s = k_s;
    scene.simulation.end_time_s = time_s;
    scene.name = format!("torus K = {k_s} s");
    let s = snapshots(&scene, &[0.0, time_s], None)?;
    Ok((spread_radius(&s[0]), spread_radius(&s[1])))
}
