//! One full step of Algorithm 1 on the CPU for the dam break of the paper's Table I, at 16K and
//! 64K fluid particles, f32 and f64, with the paper's operator (Cross, K = 1) and with the
//! Newtonian Laplacian operator, h = 2 x spacing.

use coil::cpu::simulation::CpuSimulation;
use coil::scene::setup::initial_particles;
use coil::scene::Scene;
use coil::simulation::backend::Backend as _;
use coil::simulation::model::{cross_law, LaplacianModel, Model, StressModel};
use coil_kernels::cross_viscosity::{Cross, Newtonian};
use coil_kernels::velocity_gradient::KernelSum;
use coil_kernels::Real;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::path::Path;

/// The shipped dam break with the fluid cube resolved by `per_edge`^3 particles.
fn dam_break(per_edge: usize) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dam_break.toml");
    let text = std::fs::read_to_string(&path).expect("shipped scene");
    let spacing = 0.4 / per_edge as f64;
    let text = text.replace("particle_spacing_m = 0.02", &format!("particle_spacing_m = {spacing}"));
    Scene::parse(&text, "dam_break.toml").expect("valid")
}

fn bench_variant<R: Real, M: Model<R>>(c: &mut Criterion, label: &str, model: impl Fn(&Scene) -> M) {
    let mut group = c.benchmark_group(format!("dam_break_step/{label}/{}", R::NAME));
    group.sample_size(20);
    for per_edge in [25usize, 40] {
        let scene = dam_break(per_edge);
        let initial = initial_particles(&scene, "dam_break.toml").expect("valid");
        let mut sim = CpuSimulation::<R, M>::new(&scene, &initial, model(&scene));
        // Let the column start to fall so neighbor counts are those of a moving flow.
        for _ in 0..20 {
            sim.step().expect("stable");
        }
        let fluid = sim.run.fluid_count();
        eprintln!(
            "{label} {}: {fluid} fluid + {} boundary particles, {:.1} MiB",
            R::NAME,
            sim.run.boundary_count(),
            sim.backend.memory_bytes() as f64 / (1 << 20) as f64
        );
        group.throughput(Throughput::Elements(fluid as u64));
        group.bench_function(BenchmarkId::from_parameter(format!("{}K", (fluid + 500) / 1000)), |b| {
            b.iter(|| sim.step().expect("stable"))
        });
    }
    group.finish();
}

fn cross<R: Real>(scene: &Scene) -> StressModel<Cross<R>, KernelSum> {
    StressModel(cross_law(&scene.material.viscosity), KernelSum)
}

fn laplacian<R: Real>(scene: &Scene) -> LaplacianModel<R> {
    LaplacianModel(Newtonian { nu0: R::from_f64(scene.material.viscosity.nu0_m2_s) })
}

fn steps(c: &mut Criterion) {
    bench_variant::<f32, _>(c, "cross", cross::<f32>);
    bench_variant::<f64, _>(c, "cross", cross::<f64>);
    bench_variant::<f32, _>(c, "newtonian_laplacian", laplacian::<f32>);
    bench_variant::<f64, _>(c, "newtonian_laplacian", laplacian::<f64>);
}

criterion_group!(benches, steps);
criterion_main!(benches);
