//! The carried state's checks shared by the CPU's and the device's tests: a scene that carries
//! every array, and visitors (`coil::visit_carried!`) that read, mark, permute and check it.

use coil::scene::Scene;
use coil::simulation::carried_state::{Carried, Start, VisitCarried};
use coil::simulation::particle_array::ParticleArray;
use coil::simulation::particles::Particles;
use coil_kernels::Real;
use std::collections::HashMap;
use std::marker::PhantomData;

/// A jet whose run carries every optional array: density from the continuity equation,
/// pressure solved, viscosity implicit (the README's main job's solvers).
pub fn carrying_scene(precision: &str) -> Scene {
    let jet = super::jet_scene("nozzle = { shape = \"circle\", radius_m = 0.004 }", "");
    super::scene(&super::set(
        &jet,
        &[
            "simulation.pressure=divergence_free",
            "material.density_equation=continuity",
            "material.density_kernel=spiky",
            "material.density_diffusion=0",
            "material.viscosity.solver=implicit",
            "material.viscosity.velocity_gradient=own_density",
            &format!("simulation.precision={precision}"),
        ],
    ))
}

/// Every carried array's entries of one particle, in the list's order, as f64 (exact for every
/// element type), and the optional arrays the storage lacks.
struct Entries<R> {
    i: usize,
    values: Vec<f64>,
    missing: Vec<&'static str>,
    real: PhantomData<R>,
}

impl<'a, R: Real> VisitCarried<&'a [ParticleArray<f64>], &'a [ParticleArray<R>], &'a [ParticleArray<u32>]> for Entries<R> {
    fn wide(&mut self, _: Carried, components: &'a [ParticleArray<f64>]) {
        self.values.extend(components.iter().map(|c| c[self.i]));
    }
    fn real(&mut self, _: Carried, components: &'a [ParticleArray<R>]) {
        self.values.extend(components.iter().map(|c| c[self.i].to_f64()));
    }
    fn index(&mut self, _: Carried, components: &'a [ParticleArray<u32>]) {
        self.values.extend(components.iter().map(|c| f64::from(c[self.i])));
    }
    fn real_where(&mut self, array: Carried, components: Option<&'a [ParticleArray<R>]>) {
        match components {
            Some(components) => self.real(array, components),
            None => self.missing.push(array.what),
        }
    }
}

/// Every live particle's carried entries by id; fails where the run lacks an optional array.
pub fn by_id<R: Real>(p: &Particles<R>) -> HashMap<u32, Vec<u64>> {
    (0..p.len())
        .map(|i| {
            let mut entries = Entries::<R> { i, values: Vec::new(), missing: Vec::new(), real: PhantomData };
            coil::visit_carried!(ref &mut entries; p);
            assert!(entries.missing.is_empty(), "the run lacks {:?}", entries.missing);
            (p.id[i], entries.values.iter().map(|v| v.to_bits()).collect())
        })
        .collect()
}

/// Gives every real carried array of every particle a value of its own (its id and the
/// component's place in the list), so that an array left behind or mixed up shows; positions
/// and ids are kept.
pub struct Mark<R> {
    pub ids: Vec<u32>,
    pub component: u32,
    pub real: PhantomData<R>,
}

impl<'a, R: Real> VisitCarried<&'a mut [ParticleArray<f64>], &'a mut [ParticleArray<R>], &'a mut [ParticleArray<u32>]>
    for Mark<R>
{
    fn wide(&mut self, _: Carried, components: &'a mut [ParticleArray<f64>]) {
        self.component += components.len() as u32;
    }
    fn real(&mut self, _: Carried, components: &'a mut [ParticleArray<R>]) {
        for c in components {
            for (v, &id) in c.iter_mut().zip(&self.ids) {
                // Below 2^24: exact in f32.
                *v = R::from_f64(f64::from(id * 32 + self.component));
            }
            self.component += 1;
        }
    }
    fn index(&mut self, _: Carried, components: &'a mut [ParticleArray<u32>]) {
        self.component += components.len() as u32;
    }
}

/// Moves particle `order[k]` to place `k` in every carried array.
pub struct Permute<'o, R> {
    pub order: &'o [usize],
    pub real: PhantomData<R>,
}

impl<R> Permute<'_, R> {
    fn permute<T: Copy>(&self, components: &mut [ParticleArray<T>]) {
        for c in components {
            let old: Vec<T> = self.order.iter().map(|&k| c[k]).collect();
            c[..old.len()].copy_from_slice(&old);
        }
    }
}

impl<'a, R: Real> VisitCarried<&'a mut [ParticleArray<f64>], &'a mut [ParticleArray<R>], &'a mut [ParticleArray<u32>]>
    for Permute<'_, R>
{
    fn wide(&mut self, _: Carried, components: &'a mut [ParticleArray<f64>]) {
        self.permute(components);
    }
    fn real(&mut self, _: Carried, components: &'a mut [ParticleArray<R>]) {
        self.permute(components);
    }
    fn index(&mut self, _: Carried, components: &'a mut [ParticleArray<u32>]) {
        self.permute(components);
    }
}

/// What a new particle's carried arrays hold: each `Start` but the inlet's own (the density).
pub struct Starts<R> {
    pub i: usize,
    pub wrong: Vec<String>,
    pub real: PhantomData<R>,
}

impl<R> Starts<R> {
    fn check(&mut self, array: Carried, values: Vec<f64>, position: [f64; 3], velocity: [f64; 3], id: u32) {
        let expected: Vec<Option<f64>> = (0..values.len())
            .map(|a| match array.start {
                Start::Position => Some(position[a]),
                Start::Velocity => Some(velocity[a]),
                Start::Id => Some(f64::from(id)),
                Start::Zero => Some(0.0),
                Start::Inlet => None,
            })
            .collect();
        for (v, e) in values.iter().zip(expected) {
            if e.is_some_and(|e| e != *v) {
                self.wrong.push(format!("{} starts at {v}, not {e:?}", array.what));
            }
        }
    }
}

/// The test's new particle.
pub const NEW_ID: u32 = 4_000_000;
pub const NEW_POSITION: [f64; 3] = [0.001, -0.01, 0.002];
pub const NEW_VELOCITY: [f64; 3] = [0.125, -0.5, 0.25];

impl<'a, R: Real> VisitCarried<&'a [ParticleArray<f64>], &'a [ParticleArray<R>], &'a [ParticleArray<u32>]> for Starts<R> {
    fn wide(&mut self, array: Carried, components: &'a [ParticleArray<f64>]) {
        let values = components.iter().map(|c| c[self.i]).collect();
        self.check(array, values, NEW_POSITION, NEW_VELOCITY, NEW_ID);
    }
    fn real(&mut self, array: Carried, components: &'a [ParticleArray<R>]) {
        // The velocity as the run's precision holds it.
        let velocity = NEW_VELOCITY.map(|v| R::from_f64(v).to_f64());
        let values = components.iter().map(|c| c[self.i].to_f64()).collect();
        self.check(array, values, NEW_POSITION, velocity, NEW_ID);
    }
    fn index(&mut self, array: Carried, components: &'a [ParticleArray<u32>]) {
        let values = components.iter().map(|c| f64::from(c[self.i])).collect();
        self.check(array, values, NEW_POSITION, NEW_VELOCITY, NEW_ID);
    }
}

/// Marks every real carried array of the live particles `p` (`Mark`) and reverses their order
/// (`Permute`): returns each particle's carried entries by id, and the ids in the reversed
/// order, from which a sort must move them.
pub fn mark_and_reverse<R: Real>(p: &mut Particles<R>) -> (HashMap<u32, Vec<u64>>, Vec<u32>) {
    let n = p.len();
    let ids = p.id[..n].to_vec();
    coil::visit_carried!(mut &mut Mark::<R> { ids, component: 0, real: PhantomData }; p);
    let before = by_id(p);
    let reversed: Vec<usize> = (0..n).rev().collect();
    coil::visit_carried!(mut &mut Permute::<R> { order: &reversed, real: PhantomData }; p);
    (before, p.id[..n].to_vec())
}
