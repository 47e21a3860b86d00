//! The carried state (`coil::visit_carried!`, the one list of the arrays a step reads from the
//! step before) survives every way it travels on the CPU: the sort, an inlet's new particles,
//! and a checkpoint read back into a fresh run.

use crate::common::carried::{by_id, carrying_scene, mark_and_reverse, Starts, NEW_ID, NEW_POSITION, NEW_VELOCITY};
use coil::cpu::simulation::CpuSimulation;
use coil::run::checkpoint::{encode, Checkpoint};
use coil::run::Tally;
use coil::scene::setup::{initial_particles, InitialParticles};
use coil::scene::Scene;
use coil::simulation::backend::Backend as _;
use coil::simulation::model::Model;
use coil::simulation::variant::{with_precision_and_model, WithModel};
use coil::simulation::Setup;
use coil_kernels::Real;
use std::marker::PhantomData;

struct Survives<'a>(&'a Scene, &'a InitialParticles);

impl WithModel for Survives<'_> {
    type Output = ();
    fn with<R: Real, M: Model<R>>(self, model: M) {
        let (scene, initial) = (self.0, self.1);
        let mut sim = CpuSimulation::<R, M>::new(scene, initial, model);
        for _ in 0..30 {
            sim.step().expect("stable");
        }
        let n = sim.particles().len();
        assert!(n > 40, "the inlet added {n} particles: several layers");

        // The sort: every particle's carried entries follow it, from an order far from sorted.
        let (before, scrambled) = mark_and_reverse(sim.particles_mut());
        assert_eq!(sim.backend.sort_and_reorder().expect("the CPU's sort"), 0, "every particle stays in the domain");
        assert_ne!(sim.particles().id[..n], scrambled[..], "the sort moved the particles");
        assert_eq!(by_id(sim.particles()), before, "the sort kept every carried entry with its particle");

        // A checkpoint read back into a fresh run of the scene holds every carried entry.
        let bytes = encode(&sim.run, sim.particles(), scene, &Tally::default());
        let mut setup = Setup::<R, M>::new(scene, initial, model);
        Checkpoint::decode(bytes).expect("a checkpoint").restore(&mut setup).expect("it fits the scene");
        assert_eq!(by_id(&setup.host.particles), before, "the checkpoint kept every carried entry");

        // A new particle: each carried array starts as its `Start` says.
        let p = sim.particles_mut();
        p.push(NEW_ID, NEW_POSITION, NEW_VELOCITY);
        let mut starts = Starts::<R> { i: p.len() - 1, wrong: Vec::new(), real: PhantomData };
        coil::visit_carried!(ref &mut starts; p);
        assert!(starts.wrong.is_empty(), "{:?}", starts.wrong);
    }
}

#[test]
fn every_carried_array_follows_its_particle_through_the_sort_an_inlet_and_a_checkpoint() {
    for precision in ["f32", "f64"] {
        let scene = carrying_scene(precision);
        let initial = initial_particles(&scene, "jet").expect("valid");
        with_precision_and_model(scene.simulation.precision, &scene, Survives(&scene, &initial));
    }
}
