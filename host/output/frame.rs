//! Per-particle output fields of the fluid, gathered from a run into reusable buffers.

use crate::output::points::{encode_ply, encode_xyz};
use crate::output::vtu::{encode, Field};
use crate::scene::VtuEncoding;
use crate::simulation::host_particles::HostParticles;
use crate::simulation::model::Model;
use crate::simulation::particles::vec3_view;
use crate::simulation::RunState;
use coil_kernels::cross_viscosity::Rheology;
use coil_kernels::velocity_gradient::{rate_of_deformation, shear_rate, GradientEstimate};
use coil_kernels::view::View;
use coil_kernels::Real;
use rayon::prelude::*;

/// The fluid particles of one frame. Buffers keep their capacity from frame to frame.
#[derive(Default)]
pub struct Frame {
    pub position: Vec<[f64; 3]>,
    pub velocity: Vec<[f32; 3]>,
    /// kg/m^3
    pub density: Vec<f32>,
    /// Pa, Eq. (6), or the solved pressure's field
    pub pressure: Vec<f32>,
    /// Kinematic viscosity nu (m^2/s), Eq. (3)
    pub viscosity: Vec<f32>,
    /// Shear rate D (1/s), Eq. (2)
    pub shear_rate: Vec<f32>,
    pub id: Vec<u32>,
    /// Each particle's shear rate and pressure, which take neighbor loops, in index order.
    shear_rate_and_pressure: Vec<[f32; 2]>,
    bytes: Vec<u8>,
}

impl Frame {
    /// Reads the fluid particles `host` of the run `run`, computing shear rate (Eq. 8, 2, with the
    /// run's velocity gradient) and viscosity (Eq. 3) with the kernels' own functions.
    pub fn capture<R: Real, M: Model<R>>(&mut self, run: &RunState<R, M>, host: &HostParticles<R>) {
        let p = &host.particles;
        let n = p.len();
        let fluid = run.fluid;
        let neighborhood = host.neighborhood();
        let velocity = vec3_view(&p.velocity, n);
        let density = View::new(&p.density[..n]);
        self.shear_rate_and_pressure.resize(n, [0.0; 2]);
        self.shear_rate_and_pressure.par_iter_mut().enumerate().with_min_len(256).for_each(|(i, out)| {
            // Boundary particles are not written; their neighbor loops would be wasted.
            if fluid.is_boundary(p.id[i]) {
                return;
            }
            let grad = M::Gradient::velocity_gradient(i, &neighborhood, &velocity, &density, &fluid);
            let pressure = host.pressure(i, &fluid, &neighborhood);
            *out = [shear_rate(rate_of_deformation(grad)).to_f64() as f32, pressure.to_f64() as f32];
        });
        self.position.clear();
        self.velocity.clear();
        self.density.clear();
        self.pressure.clear();
        self.viscosity.clear();
        self.shear_rate.clear();
        self.id.clear();
        for i in 0..n {
            if fluid.is_boundary(p.id[i]) {
                continue;
            }
            let rho = p.density[i];
            let [d, pressure] = self.shear_rate_and_pressure[i];
            self.position.push([0, 1, 2].map(|a| p.position[a][i]));
            self.velocity.push([0, 1, 2].map(|a| p.velocity[a][i].to_f64() as f32));
            self.density.push(rho.to_f64() as f32);
            self.pressure.push(pressure);
            self.viscosity.push(run.model.law().viscosity(R::from_f64(d as f64)).to_f64() as f32);
            self.shear_rate.push(d);
            self.id.push(p.id[i]);
        }
    }

    /// How many particles hold a value that is not finite, and the first such value (its
    /// field, the particle's id, the value), or `None` where every value is finite.
    pub fn non_finite(&self) -> Option<(usize, String)> {
        let bad = |k: usize| -> Option<(&str, f64)> {
            let scalars = [
                ("density", self.density[k]),
                ("pressure", self.pressure[k]),
                ("viscosity", self.viscosity[k]),
                ("shear_rate", self.shear_rate[k]),
            ];
            let vectors = self.position[k]
                .iter()
                .map(|&x| ("position", x))
                .chain(self.velocity[k].iter().map(|&v| ("velocity", f64::from(v))));
            scalars.into_iter().map(|(name, v)| (name, f64::from(v))).chain(vectors).find(|(_, v)| !v.is_finite())
        };
        let mut found = (0..self.id.len()).filter_map(|k| bad(k).map(|b| (k, b)));
        let (k, (field, value)) = found.next()?;
        Some((1 + found.count(), format!("{field} of particle {} is {value}", self.id[k])))
    }

    /// The frame as a binary `.ply` file's bytes.
    pub fn to_ply(&mut self) -> &[u8] {
        let scalars = [
            ("density", &self.density[..]),
            ("pressure", &self.pressure[..]),
            ("viscosity", &self.viscosity[..]),
            ("shear_rate", &self.shear_rate[..]),
        ];
        encode_ply(&self.position, &self.velocity, scalars, &self.id, &mut self.bytes);
        &self.bytes
    }

    /// The frame as a splashsurf `.xyz` file's bytes.
    pub fn to_xyz(&mut self) -> &[u8] {
        encode_xyz(&self.position, &mut self.bytes);
        &self.bytes
    }

    /// The frame as a `.vtu` file's bytes, its arrays held as `encoding` says.
    pub fn to_vtu(&mut self, encoding: VtuEncoding) -> &[u8] {
        let fields = [
            Field::Vector("velocity", &self.velocity),
            Field::Scalar("density", &self.density),
            Field::Scalar("pressure", &self.pressure),
            Field::Scalar("viscosity", &self.viscosity),
            Field::Scalar("shear_rate", &self.shear_rate),
            Field::Id("id", &self.id),
        ];
        encode(&self.position, &fields, encoding, &mut self.bytes);
        &self.bytes
    }
}
