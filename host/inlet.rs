//! Jet inlets (paper Sec. III-C): nozzle layers generated on the host and appended to the
//! preallocated tail of the particle arrays.

use crate::scene::{self, Nozzle, NozzleMotion};
use coil_kernels::Real;

use crate::particles::Particles;

/// A nozzle during a run.
#[derive(Debug, Clone)]
pub struct Inlet {
    /// Particle offsets from the nozzle centre in the nozzle plane (m).
    layer: Vec<[f64; 3]>,
    direction: [f64; 3],
    speed: f64,
    position: [f64; 3],
    start: f64,
    stop: f64,
    motion: Option<NozzleMotion>,
    /// Distance between layers (m), set so the inlet delivers exactly rho0 A U.
    layer_distance: f64,
    /// How far the newest layer has travelled from the nozzle (m).
    travelled: f64,
}

fn normalized(v: [f64; 3]) -> [f64; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|c| c / n)
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Two unit vectors spanning the plane normal to `d`. The first lies in the x-z plane when it
/// can, so a rectangle's width runs along x for a vertical jet.
fn nozzle_axes(d: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let helper = if d[1].abs() < 0.9 { [0.0, 1.0, 0.0] } else { [0.0, 0.0, 1.0] };
    let e1 = normalized(cross(helper, d));
    let e2 = cross(d, e1);
    (e1, e2)
}

impl Inlet {
    /// `mass` (kg) and `rest_density` (kg/m^3) fix the layer distance that makes the mass flow
    /// rate equal rho0 A U for the nozzle's nominal area A.
    pub fn new(config: &scene::Inlet, spacing: f64, mass: f64, rest_density: f64) -> Self {
        let direction = normalized(config.direction);
        let (e1, e2) = nozzle_axes(direction);
        let mut offsets = Vec::new();
        let area = match config.nozzle {
            Nozzle::Circle { radius_m } => {
                let n = (radius_m / spacing).floor() as i64;
                for j in -n..=n {
                    for i in -n..=n {
                        let (a, b) = (i as f64 * spacing, j as f64 * spacing);
                        if a * a + b * b <= radius_m * radius_m {
                            offsets.push((a, b));
                        }
                    }
                }
                std::f64::consts::PI * radius_m * radius_m
            }
            Nozzle::Rectangle { width_m, depth_m } => {
                let nw = ((width_m / spacing).round() as i64).max(1);
                let nd = ((depth_m / spacing).round() as i64).max(1);
                for j in 0..nd {
                    for i in 0..nw {
                        offsets.push(((i as f64 + 0.5) * spacing - 0.5 * width_m, (j as f64 + 0.5) * spacing - 0.5 * depth_m));
                    }
                }
                width_m * depth_m
            }
        };
        let layer: Vec<[f64; 3]> =
            offsets.iter().map(|&(a, b)| [0, 1, 2].map(|k| a * e1[k] + b * e2[k])).collect();
        let layer_distance = layer.len() as f64 * mass / (rest_density * area);
        Self {
            layer,
            direction,
            speed: config.speed_m_s,
            position: config.position_m,
            start: config.start_s,
            stop: config.stop_s.unwrap_or(f64::INFINITY),
            motion: config.motion.clone(),
            layer_distance,
            travelled: layer_distance,
        }
    }

    /// Particles per layer.
    pub fn layer_size(&self) -> usize {
        self.layer.len()
    }

    /// Jet speed (m/s).
    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// Nozzle centre (m) and velocity (m/s) at time `t` (s).
    pub fn nozzle(&self, t: f64) -> ([f64; 3], [f64; 3]) {
        match &self.motion {
            None => (self.position, [0.0; 3]),
            Some(NozzleMotion::Velocity { velocity_m_s: v }) => ([0, 1, 2].map(|k| self.position[k] + v[k] * t), *v),
            Some(NozzleMotion::Waypoints { waypoints: w }) => {
                let at = |p: &[f64; 4]| [p[1], p[2], p[3]];
                if t <= w[0][0] {
                    return (at(&w[0]), [0.0; 3]);
                }
                for seg in w.windows(2) {
                    let (a, b) = (&seg[0], &seg[1]);
                    if t < b[0] {
                        let f = (t - a[0]) / (b[0] - a[0]);
                        let pos = [0, 1, 2].map(|k| a[k + 1] + f * (b[k + 1] - a[k + 1]));
                        let vel = [0, 1, 2].map(|k| (b[k + 1] - a[k + 1]) / (b[0] - a[0]));
                        return (pos, vel);
                    }
                }
                (at(w.last().expect("validated non-empty")), [0.0; 3])
            }
        }
    }

    /// Advances the jet by `dt` from time `t` and appends every layer now due, while whole
    /// layers fit in `budget` more particles. Returns how many particles were added.
    pub fn inject<R: Real>(&mut self, t: f64, dt: f64, budget: usize, next_id: &mut u32, p: &mut Particles<R>) -> usize {
        if t + dt < self.start || t >= self.stop {
            return 0;
        }
        self.travelled += self.speed * dt;
        let (centre, nozzle_velocity) = self.nozzle(t + dt);
        let velocity = [0, 1, 2].map(|k| self.speed * self.direction[k] + nozzle_velocity[k]);
        let mut added = 0;
        while self.travelled >= self.layer_distance && added + self.layer.len() <= budget {
            self.travelled -= self.layer_distance;
            // The new layer has already moved `travelled` past the nozzle during this step.
            let ahead = self.travelled;
            for o in &self.layer {
                let x = [0, 1, 2].map(|k| centre[k] + o[k] + ahead * self.direction[k]);
                p.push(*next_id, x, velocity);
                *next_id += 1;
            }
            added += self.layer.len();
        }
        added
    }
}
