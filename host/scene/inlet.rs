//! Jet inlets (paper Sec. III-C): nozzle layers generated on the host and appended to the
//! preallocated tail of the particle arrays, born inside the nozzle's tube
//! (`coil_kernels::nozzle`) one support radius upstream of the exit.

use crate::scene::{self, Nozzle, NozzleMotion};
use crate::splitmix64::{SplitMix64, GOLDEN_GAMMA};
use coil_kernels::nozzle::NozzleTube;
use coil_kernels::Real;

/// Where an inlet's new particles go: the solver's particles, or a device run's staging.
pub trait NewParticles {
    /// Adds a particle with its id, position (m), velocity (m/s) and density (kg/m^3).
    fn add(&mut self, id: u32, position: [f64; 3], velocity: [f64; 3], density: f64);
}

/// A nozzle during a run.
#[derive(Debug, Clone)]
pub struct Inlet {
    /// Particle offsets from the nozzle centre in the nozzle plane (m).
    layer: Vec<[f64; 3]>,
    direction: [f64; 3],
    across: [[f64; 3]; 2],
    /// Half-extents of the bore with clearance (m), see `NozzleTube::half_extent`.
    half_extent: [f64; 2],
    round: bool,
    /// Length of the tube upstream of the exit, where layers are born (m).
    tube_length: f64,
    spacing: f64,
    speed: f64,
    position: [f64; 3],
    start: f64,
    stop: f64,
    motion: Option<NozzleMotion>,
    /// Distance between layers (m), set so the inlet delivers exactly the volume A U at rest
    /// density.
    layer_distance: f64,
    /// How far the newest layer has travelled from the nozzle (m).
    travelled: f64,
    wobble: f64,
    /// Layers injected so far, which seeds each layer's wobble.
    layers: u64,
    /// rho0 (kg/m^3), the density a new particle starts at.
    rest_density: f64,
}

/// A point of the unit disc for layer `n`, from SplitMix64: the same sequence on every machine
/// and thread count.
fn wobble(n: u64) -> [f64; 2] {
    let mut stream = SplitMix64(n.wrapping_mul(GOLDEN_GAMMA));
    let mut next = || (stream.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
    loop {
        let (a, b) = (next(), next());
        if a * a + b * b <= 1.0 {
            return [a, b];
        }
    }
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
    /// `rest_volume` (m^3, `setup::rest_volume`), the volume a particle fills at rho0, fixes the
    /// layer distance that makes the volume flow rate A U for the nozzle's nominal area A, so
    /// that the inlet delivers rho0 A U of fluid at rest density; new particles start at
    /// `rest_density` (kg/m^3). The tube is one support radius `support_radius` (m) long, so the
    /// first free layer below the exit has full support.
    pub fn new(config: &scene::InletSettings, spacing: f64, support_radius: f64, rest_volume: f64, rest_density: f64) -> Self {
        let direction = normalized(config.direction);
        let (e1, e2) = nozzle_axes(direction);
        let mut offsets = Vec::new();
        let clearance = 0.5 * spacing + config.wobble_m;
        let (area, half_extent, round) = match config.nozzle {
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
                (std::f64::consts::PI * radius_m * radius_m, [radius_m + clearance; 2], true)
            }
            Nozzle::Rectangle { width_m, depth_m } => {
                let nw = ((width_m / spacing).round() as i64).max(1);
                let nd = ((depth_m / spacing).round() as i64).max(1);
                for j in 0..nd {
                    for i in 0..nw {
                        offsets.push(((i as f64 + 0.5) * spacing - 0.5 * width_m, (j as f64 + 0.5) * spacing - 0.5 * depth_m));
                    }
                }
                (width_m * depth_m, [0.5 * width_m + clearance, 0.5 * depth_m + clearance], false)
            }
        };
        let layer: Vec<[f64; 3]> = offsets.iter().map(|&(a, b)| [0, 1, 2].map(|k| a * e1[k] + b * e2[k])).collect();
        let layer_distance = layer.len() as f64 * rest_volume / area;
        Self {
            layer,
            direction,
            across: [e1, e2],
            half_extent,
            round,
            tube_length: support_radius,
            spacing,
            speed: config.speed_m_s,
            position: config.position_m,
            start: config.start_s,
            stop: config.stop_s.unwrap_or(f64::INFINITY),
            motion: config.motion.clone(),
            layer_distance,
            travelled: layer_distance,
            wobble: config.wobble_m,
            layers: 0,
            rest_density,
        }
    }

    /// Particles per layer.
    pub fn layer_size(&self) -> usize {
        self.layer.len()
    }

    /// Distance (m) the jet travels between layers: the layer's mass over rho0 times the
    /// nozzle's area.
    pub fn layer_distance(&self) -> f64 {
        self.layer_distance
    }

    /// Particles injected per second while the jet runs.
    pub fn particles_per_second(&self) -> f64 {
        self.layer.len() as f64 * self.speed / self.layer_distance
    }

    /// When the jet starts and stops (s).
    pub fn active(&self) -> (f64, f64) {
        (self.start, self.stop)
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

    /// Where a layer's particles can be at time `t` (s): at the nozzle's exit and at its
    /// tube's upstream end, where layers are born, each shifted by up to the wobble.
    pub fn reach(&self, t: f64) -> impl Iterator<Item = [f64; 3]> + '_ {
        let (centre, _) = self.nozzle(t);
        let shifts =
            [(0.0, 0.0), (1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)].map(|(a, b)| (a * self.wobble, b * self.wobble));
        [0.0, -self.tube_length].into_iter().flat_map(move |along| {
            shifts.into_iter().flat_map(move |(a, b)| {
                self.layer.iter().map(move |o| {
                    [0, 1, 2]
                        .map(|k| centre[k] + o[k] + along * self.direction[k] + a * self.across[0][k] + b * self.across[1][k])
                })
            })
        })
    }

    /// The times from `start` to `stop` (s) at which the nozzle is at the ends of its straight
    /// segments: between them it moves in a line, so checking its reach there covers its path.
    pub fn turning_times(&self, start: f64, stop: f64) -> Vec<f64> {
        let mut times = vec![start, stop];
        if let Some(NozzleMotion::Waypoints { waypoints }) = &self.motion {
            times.extend(waypoints.iter().map(|w| w[0]).filter(|&t| t > start && t < stop));
        }
        times
    }

    /// Velocity of the fluid leaving a nozzle that moves at `nozzle_velocity` (m/s).
    fn jet_velocity(&self, nozzle_velocity: [f64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|k| self.speed * self.direction[k] + nozzle_velocity[k])
    }

    /// The nozzle's tube at time `t` (s), for the nozzle pass.
    pub fn tube<R: Real>(&self, t: f64) -> NozzleTube<R> {
        let (exit, nozzle_velocity) = self.nozzle(t);
        NozzleTube {
            exit,
            axis: self.direction,
            across: self.across,
            half_extent: self.half_extent,
            round: u32::from(self.round),
            length: self.tube_length + 0.5 * self.spacing,
            velocity: self.jet_velocity(nozzle_velocity).map(R::from_f64),
        }
    }

    /// How far the newest layer has travelled (m) and how many layers the jet has injected: all
    /// of its state that a run changes.
    pub fn progress(&self) -> (f64, u64) {
        (self.travelled, self.layers)
    }

    /// Sets the state [`Inlet::progress`] gave, to resume a run.
    pub(crate) fn set_progress(&mut self, travelled: f64, layers: u64) {
        self.travelled = travelled;
        self.layers = layers;
    }

    /// Whether a layer is due that `room` more particles cannot take: the run's fluid capacity
    /// has stopped this jet.
    pub fn starved(&self, room: usize) -> bool {
        self.travelled >= self.layer_distance && self.layer.len() > room
    }

    /// Advances the jet by `dt` from time `t` and appends every layer now due, while whole
    /// layers fit in `budget` more particles. Returns how many particles were added.
    pub fn inject(&mut self, t: f64, dt: f64, budget: usize, next_id: &mut u32, p: &mut impl NewParticles) -> usize {
        if t + dt < self.start || t >= self.stop {
            return 0;
        }
        self.travelled += self.speed * dt;
        let (centre, nozzle_velocity) = self.nozzle(t + dt);
        let velocity = self.jet_velocity(nozzle_velocity);
        let mut added = 0;
        while self.travelled >= self.layer_distance && added + self.layer.len() <= budget {
            self.travelled -= self.layer_distance;
            // The new layer is born at the tube's upstream end and has already moved
            // `travelled` during this step.
            let along = self.travelled - self.tube_length;
            let [a, b] = wobble(self.layers).map(|u| u * self.wobble);
            self.layers += 1;
            let shift = [0, 1, 2].map(|k| along * self.direction[k] + a * self.across[0][k] + b * self.across[1][k]);
            for o in &self.layer {
                let x = [0, 1, 2].map(|k| centre[k] + o[k] + shift[k]);
                p.add(*next_id, x, velocity, self.rest_density);
                *next_id += 1;
            }
            added += self.layer.len();
        }
        added
    }
}
