//! The CUDA backend against the CPU backend. Built only with `--features cuda`.
//!
//! The PTX argument layouts are checked everywhere (no GPU needed). The rest runs on the
//! emulated device everywhere (`Gpu::emulated`: the backend's host side launching the kernels'
//! host builds), and again on a CUDA device where one is present; without one each test prints
//! "skipped: no CUDA device", or fails where `COIL_REQUIRE_GPU=1` (on a GPU machine, so that a
//! driver that cannot be reached is not mistaken for a pass).
#![cfg(feature = "cuda")]

mod common;

use coil::cpu::simulation::CpuSimulation;
use coil::cuda::device_array::{vec3_view, vec3_view_mut, DeviceArray};
use coil::cuda::gpu::{ByValue, PTX};
use coil::cuda::{Gpu, GpuSimulation};
use coil::scene::setup::initial_particles;
use coil::scene::Scene;
use coil::simulation::backend::Backend as _;
use coil::simulation::model::{
    cross_law, HourglassStressModel, LaplacianModel, Model, MorrisModel, ShearThinningMorrisModel, StressModel,
};
use coil::simulation::particles::Particles;
use coil_kernels::acceleration::AccelerationArgs;
use coil_kernels::cell_grid::{HashArgs, Neighborhood};
use coil_kernels::continuity_molteni2009::{ContinuityArgs, DensityIntegrationArgs};
use coil_kernels::counting_sort::{Counters, Gathered, ReorderArgs};
use coil_kernels::cross_viscosity::{Cross, Newtonian};
use coil_kernels::density::DensityArgs;
use coil_kernels::dfsph_bender2017::{
    DensityErrorArgs, DensityRateArgs, DivergenceErrorArgs, ErrorSumArgs, FactorArgs, PressureChangeArgs, WarmStartArgs,
};
use coil_kernels::diagnostics::{DiagnosticsArgs, StateFigures};
use coil_kernels::fluid_cells::{HoldsFluidArgs, NearFluidArgs};
use coil_kernels::leapfrog::LeapfrogArgs;
use coil_kernels::mirrored_wall::MirroredWallArgs;
use coil_kernels::nozzle::{NozzleArgs, NozzleShiftArgs};
use coil_kernels::renormalization_bonet1999::Renormalized;
use coil_kernels::shifting_sun2017::{ShiftArgs, ShiftingArgs};
use coil_kernels::topology::{Open, Periodic, Topology};
use coil_kernels::velocity_gradient::{GradientEstimate, KernelSum, OwnDensity};
use coil_kernels::view::{View, ViewMut};
use coil_kernels::viscosity::hourglass_ganzenmuller2015::{HourglassControlledStress, VelocityGradientArgs};
use coil_kernels::viscosity::implicit_weiler2018::{
    CgDirectionArgs, CgStartArgs, CgStepArgs, DotArgs, ImplicitStressArgs, LaggedViscosityArgs, PredictorArgs,
    PressureAndGravity, SystemBlockArgs, SystemProductArgs, ViscousAccelerationArgs,
};
use coil_kernels::viscosity::laplacian_morris1997::{
    MorrisSystemBlockArgs, MorrisSystemProductArgs, MorrisViscosity, ShearViscosityArgs,
};
use coil_kernels::viscosity::laplacian_muller2003::VelocityLaplacian;
use coil_kernels::viscosity::stress_andrade2014::StressArgs;
use coil_kernels::viscosity::stress_andrade2014::StressDivergence;
use coil_kernels::Real;
use common::{quiet_run_options, uniform};
use std::collections::HashMap;
use std::mem::size_of;
use std::path::Path;

/// Each PTX entry's parameter sizes in bytes, as ptxas sees them.
fn ptx_parameters() -> HashMap<String, Vec<usize>> {
    let mut entries = HashMap::new();
    let mut current: Option<(String, Vec<usize>)> = None;
    for line in PTX.lines().map(str::trim) {
        if let Some(rest) = line.strip_prefix(".visible .entry ") {
            current = Some((rest.trim_end_matches('(').to_string(), Vec::new()));
        } else if let (Some((_, params)), Some(decl)) = (current.as_mut(), line.strip_prefix(".param ")) {
            let size = if let Some(open) = decl.find('[') {
                decl[open + 1..decl.find(']').expect("closing bracket")].parse().expect("a byte count")
            } else if decl.starts_with(".u32") || decl.starts_with(".b32") {
                4
            } else {
                8
            };
            params.push(size);
        } else if line.starts_with(')') {
            if let Some((name, params)) = current.take() {
                entries.insert(name, params);
            }
        }
    }
    entries
}

type Count = View<'static, u32>;

/// The host's argument types of every entry, by size: a field added to a kernel argument struct
/// on one side only, or a changed signature, shows here without a GPU.
#[test]
fn ptx_entry_parameters_match_the_host_argument_layouts() {
    /// The entries of the passes that loop over neighbors (through the grid, as on the device)
    /// or wrap, in topology `T`.
    fn per_topology<R: Real, T: Topology>(expected: &mut Vec<(String, Vec<usize>)>) {
        let name = |stem: &str| [stem, T::NAME, R::NAME].iter().filter(|p| !p.is_empty()).copied().collect::<Vec<_>>().join("_");
        let count = size_of::<Count>();
        let mut add = |stem: &str, args: usize| expected.push((name(stem), vec![count, args]));
        add("density", size_of::<DensityArgs<R, Neighborhood<T>>>());
        add("density_spiky", size_of::<DensityArgs<R, Neighborhood<T>>>());
        add("continuity_floor_spiky", size_of::<DensityArgs<R, Neighborhood<T>>>());
        add("continuity", size_of::<ContinuityArgs<R, Neighborhood<T>>>());
        add("continuity_spiky", size_of::<ContinuityArgs<R, Neighborhood<T>>>());
        add("stress_newtonian", size_of::<StressArgs<R, Newtonian<R>, KernelSum, Neighborhood<T>>>());
        add("stress_cross", size_of::<StressArgs<R, Cross<R>, KernelSum, Neighborhood<T>>>());
        add("stress_newtonian_renormalized", size_of::<StressArgs<R, Newtonian<R>, Renormalized, Neighborhood<T>>>());
        add("stress_cross_renormalized", size_of::<StressArgs<R, Cross<R>, Renormalized, Neighborhood<T>>>());
        add("stress_newtonian_own_density", size_of::<StressArgs<R, Newtonian<R>, OwnDensity, Neighborhood<T>>>());
        add("stress_cross_own_density", size_of::<StressArgs<R, Cross<R>, OwnDensity, Neighborhood<T>>>());
        add("acceleration_stress", size_of::<AccelerationArgs<R, StressDivergence<R>, Neighborhood<T>>>());
        add("acceleration_laplacian", size_of::<AccelerationArgs<R, VelocityLaplacian<R>, Neighborhood<T>>>());
        add("shear_viscosity_cross", size_of::<ShearViscosityArgs<R, Cross<R>, Neighborhood<T>>>());
        add("acceleration_morris", size_of::<AccelerationArgs<R, MorrisViscosity<R, Newtonian<R>>, Neighborhood<T>>>());
        add("acceleration_morris_shear", size_of::<AccelerationArgs<R, MorrisViscosity<R, View<R>>, Neighborhood<T>>>());
        add("velocity_gradient_newtonian", size_of::<VelocityGradientArgs<R, Newtonian<R>, Neighborhood<T>>>());
        add("velocity_gradient_cross", size_of::<VelocityGradientArgs<R, Cross<R>, Neighborhood<T>>>());
        add("acceleration_hourglass", size_of::<AccelerationArgs<R, HourglassControlledStress<R>, Neighborhood<T>>>());
        add("mirrored_wall", size_of::<MirroredWallArgs<R, T>>());
        add("leapfrog", size_of::<LeapfrogArgs<R, T>>());
        add("shifting", size_of::<ShiftingArgs<R, Neighborhood<T>>>());
        add("shift", size_of::<ShiftArgs<R, T>>());
        add("acceleration_pressure", size_of::<AccelerationArgs<R, PressureAndGravity, Neighborhood<T>>>());
        add("lagged_viscosity_newtonian", size_of::<LaggedViscosityArgs<R, Newtonian<R>, Neighborhood<T>>>());
        add("lagged_viscosity_cross", size_of::<LaggedViscosityArgs<R, Cross<R>, Neighborhood<T>>>());
        add("implicit_stress", size_of::<ImplicitStressArgs<R, Neighborhood<T>>>());
        add("system_block", size_of::<SystemBlockArgs<R, Neighborhood<T>>>());
        add("system_product", size_of::<SystemProductArgs<R, Neighborhood<T>>>());
        add("system_block_morris", size_of::<MorrisSystemBlockArgs<R, Newtonian<R>, Neighborhood<T>>>());
        add("system_block_morris_shear", size_of::<MorrisSystemBlockArgs<R, View<R>, Neighborhood<T>>>());
        add("system_product_morris", size_of::<MorrisSystemProductArgs<R, Newtonian<R>, Neighborhood<T>>>());
        add("system_product_morris_shear", size_of::<MorrisSystemProductArgs<R, View<R>, Neighborhood<T>>>());
        add("dfsph_factor", size_of::<FactorArgs<R, Neighborhood<T>>>());
        add("divergence_error", size_of::<DivergenceErrorArgs<R, Neighborhood<T>>>());
        add("density_error", size_of::<DensityErrorArgs<R, Neighborhood<T>>>());
        add("dfsph_density_rate", size_of::<DensityRateArgs<R, Neighborhood<T>>>());
        add("pressure_change", size_of::<PressureChangeArgs<R, Neighborhood<T>>>());
    }
    fn per_precision<R: Real>(expected: &mut Vec<(String, Vec<usize>)>) {
        per_topology::<R, Open>(expected);
        per_topology::<R, Periodic>(expected);
        let r = R::NAME;
        let count = size_of::<Count>();
        let mut add = |name: String, sizes: Vec<usize>| expected.push((name, sizes));
        add(format!("nozzle_{r}"), vec![count, size_of::<NozzleArgs<R>>()]);
        add(format!("nozzle_shift_{r}"), vec![count, size_of::<NozzleShiftArgs<R>>()]);
        add(format!("density_integration_{r}"), vec![count, size_of::<DensityIntegrationArgs<R>>()]);
        add(format!("reorder_{r}"), vec![count, size_of::<ReorderArgs<R>>()]);
        add(format!("append_{r}"), vec![count, 4, size_of::<View<R>>(), size_of::<ViewMut<R>>()]);
        add(format!("diagnostics_{r}"), vec![count, 4, size_of::<DiagnosticsArgs<R>>(), size_of::<ViewMut<StateFigures>>()]);
        add(format!("predictor_{r}"), vec![count, size_of::<PredictorArgs<R>>()]);
        add(format!("cg_start_{r}"), vec![count, size_of::<CgStartArgs<R>>()]);
        add(format!("cg_step_{r}"), vec![count, size_of::<CgStepArgs<R>>()]);
        add(format!("cg_direction_{r}"), vec![count, size_of::<CgDirectionArgs<R>>()]);
        add(format!("viscous_acceleration_{r}"), vec![count, size_of::<ViscousAccelerationArgs<R>>()]);
        add(format!("dots_{r}"), vec![count, size_of::<DotArgs<R>>(), size_of::<ViewMut<[f64; 2]>>()]);
        add(format!("warm_start_{r}"), vec![count, size_of::<WarmStartArgs<R>>()]);
        add(format!("error_sums_{r}"), vec![count, size_of::<ErrorSumArgs<R>>(), size_of::<ViewMut<[f64; 2]>>()]);
    }
    let view = size_of::<View<u32>>();
    let mut expected = vec![
        ("hash".to_string(), vec![view, size_of::<HashArgs>()]),
        ("count_particles".into(), vec![view, view, size_of::<Counters>()]),
        ("scan_chunk_totals".into(), vec![4, 4, size_of::<Counters>(), view]),
        ("scan_offsets".into(), vec![view]),
        ("scan_sum_chunks".into(), vec![4, view, view]),
        ("scan_chunks_in_place".into(), vec![4, view, view]),
        ("scan_chunks".into(), vec![4, 4, view, size_of::<Counters>(), view]),
        ("scatter_particles".into(), vec![view, view, size_of::<Counters>(), view]),
        ("sort_buckets".into(), vec![4, view, view]),
        ("holds_fluid".into(), vec![4, size_of::<HoldsFluidArgs>()]),
        ("near_fluid".into(), vec![4, size_of::<NearFluidArgs<Open>>()]),
        ("near_fluid_periodic".into(), vec![4, size_of::<NearFluidArgs<Periodic>>()]),
        ("set_count".into(), vec![view, view, 4]),
        ("grow_count".into(), vec![view, 4]),
        ("append_u32".into(), vec![view, 4, view, view]),
    ];
    per_precision::<f32>(&mut expected);
    per_precision::<f64>(&mut expected);
    let ptx = ptx_parameters();
    for (name, sizes) in &expected {
        let found = ptx.get(name).unwrap_or_else(|| panic!("PTX has no entry {name}; it has {:?}", ptx.keys()));
        assert_eq!(found, sizes, "{name}: PTX parameter sizes against the host's argument types");
    }
    assert_eq!(ptx.len(), expected.len(), "an entry without a layout check: {:?}", ptx.keys());
}

/// The words of the u32 array `name` the PTX defines, from its bytes (little-endian; the
/// initializer leaves trailing zero bytes out).
fn ptx_words(name: &str) -> Vec<u32> {
    let declared = format!(" {name}[");
    let line = PTX
        .lines()
        .find(|l| l.starts_with(".visible .global") && l.contains(&declared))
        .unwrap_or_else(|| panic!("the PTX defines no {name}"));
    let length = &line[line.find(&declared).expect("found") + declared.len()..];
    let length: usize = length[..length.find(']').expect("a closing bracket")].parse().expect("a byte count");
    let mut bytes: Vec<u8> = line[line.find('{').expect("an initializer") + 1..line.rfind('}').expect("its end")]
        .split(',')
        .map(|b| b.trim().parse().expect("a byte"))
        .collect();
    assert!(bytes.len() <= length, "{name}: {} bytes in an array of {length}", bytes.len());
    bytes.resize(length, 0);
    bytes.chunks(4).map(|w| u32::from_le_bytes(w.try_into().expect("whole words"))).collect()
}

/// Size, alignment and every field's offset of each struct a kernel takes, as the nightly lays
/// them out for nvptx64 (exported in the PTX) and as the host's compiler does: a field the two
/// order or pad differently would read another field's bytes on a GPU, whatever the sizes say.
#[test]
fn device_and_host_lay_out_every_argument_struct_alike() {
    use coil_kernels::abi::{layouts, LAYOUT_NAMES, LAYOUT_WORDS};
    for (precision, device, host) in
        [("f32", ptx_words("COIL_LAYOUTS_F32"), layouts::<f32>()), ("f64", ptx_words("COIL_LAYOUTS_F64"), layouts::<f64>())]
    {
        assert_eq!(device.len(), LAYOUT_WORDS, "{precision}: the device's table has another length: a stale PTX?");
        let mut k = 0;
        for (name, fields) in LAYOUT_NAMES {
            let what = ["size", "alignment"].into_iter().chain(fields.iter().copied());
            for (word, what) in what.enumerate() {
                assert_eq!(
                    device[k + word],
                    host[k + word],
                    "{name} at {precision}: {what} is {} bytes on the device and {} on the host",
                    device[k + word],
                    host[k + word]
                );
            }
            k += 2 + fields.len();
        }
        assert_eq!(k, LAYOUT_WORDS);
    }
}

/// Every `repr(C)` struct of the kernels crate is in the layout table, but those only the CPU
/// backend reads (its neighbor lists), so a new argument struct cannot go unchecked.
#[test]
fn the_layout_table_lists_every_repr_c_struct() {
    let cpu_only = ["NeighborListArgs", "ListedNeighborhood"];
    let listed: Vec<&str> = coil_kernels::abi::LAYOUT_NAMES
        .iter()
        .map(|(name, _)| match *name {
            "O" | "P" => "Neighborhood",
            name => name.split('<').next().expect("a name").trim(),
        })
        .collect();
    let mut sources = vec![Path::new(env!("CARGO_MANIFEST_DIR")).join("kernels/src")];
    let mut checked = 0;
    while let Some(path) = sources.pop() {
        if path.is_dir() {
            sources.extend(std::fs::read_dir(&path).expect("a source folder").map(|e| e.expect("an entry").path()));
            continue;
        }
        let text = std::fs::read_to_string(&path).expect("a source file");
        for (at, _) in text.match_indices("#[repr(C)]") {
            let after = &text[at..];
            let name = after[after.find("pub struct ").expect("a struct after repr(C)") + 11..]
                .split(|c: char| !c.is_alphanumeric() && c != '_')
                .next()
                .expect("a name");
            checked += 1;
            assert!(
                listed.contains(&name) || cpu_only.contains(&name),
                "{name} ({}) is repr(C) but not in coil_kernels::abi's table",
                path.display()
            );
        }
    }
    assert!(checked > 50, "only {checked} repr(C) structs found");
}

/// The emulated device knows every PTX entry by its name, and no other.
#[test]
fn every_ptx_entry_has_its_host_build() {
    let mut emulated: Vec<&str> = Vec::new();
    coil_kernels::ptx::for_each_entry(|name, _| emulated.push(name));
    let ptx = ptx_parameters();
    let mut on_device: Vec<&str> = ptx.keys().map(String::as_str).collect();
    emulated.sort_unstable();
    on_device.sort_unstable();
    assert_eq!(emulated, on_device);
}

/// What a test runs on: the emulated device, then a CUDA device where one is present.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Engine {
    Emulated,
    Cuda,
}

impl Engine {
    fn open(self) -> Gpu {
        match self {
            Engine::Emulated => Gpu::emulated(),
            Engine::Cuda => Gpu::open().expect("a device was found"),
        }
    }

    /// How far apart (m) CPU and device f64 positions may be after 50 steps. The emulated
    /// device runs the CPU's own machine code in the CPU's order, so it must agree to the bit;
    /// a GPU contracts a*b+c into one rounding, so every sum differs in its last bits (1e-16
    /// relative), which over 50 steps stays many orders below the spacing (0.04 m).
    fn f64_tolerance_m(self) -> f64 {
        match self {
            Engine::Emulated => 0.0,
            Engine::Cuda => 1e-10,
        }
    }
}

/// The emulated device, and a CUDA device or a visible skip (a failure where
/// `COIL_REQUIRE_GPU=1`).
fn engines() -> Vec<Engine> {
    match Gpu::open() {
        Ok(_) => vec![Engine::Emulated, Engine::Cuda],
        Err(e) if std::env::var("COIL_REQUIRE_GPU").is_ok_and(|v| v == "1") => panic!("COIL_REQUIRE_GPU=1: {e}"),
        Err(e) => {
            println!("skipped: no CUDA device ({e}); ran on the emulated device only");
            vec![Engine::Emulated]
        }
    }
}

/// The shipped dam break, coarse: 10^3 fluid particles in a closed box.
fn dam_break() -> Scene {
    // At run time first: `scripts/gpu run` runs this binary in a checkout elsewhere.
    let root = std::env::var("CARGO_MANIFEST_DIR").unwrap_or_else(|_| env!("CARGO_MANIFEST_DIR").into());
    let path = Path::new(&root).join("scenes/dam_break.toml");
    let text = std::fs::read_to_string(&path).expect("shipped scene");
    Scene::parse(&common::set(&text, &["material.particle_spacing_m=0.04"]), "dam_break.toml").expect("valid")
}

fn cross<R: Real>(scene: &Scene) -> StressModel<Cross<R>, KernelSum> {
    StressModel(cross_law(&scene.material.viscosity), KernelSum)
}

/// Fluid positions (m) and velocities (m/s) by particle id.
fn state_by_id<R: Real>(p: &Particles<R>) -> Vec<(u32, [f64; 3], [f64; 3])> {
    let mut out: Vec<_> = (0..p.len())
        .map(|i| (p.id[i], [0, 1, 2].map(|a| p.position[a][i]), [0, 1, 2].map(|a| p.velocity[a][i].to_f64())))
        .collect();
    out.sort_by_key(|s| s.0);
    out
}

/// The largest difference of any coordinate (m) between two `state_by_id`s of the same
/// particles.
fn largest_position_difference(c: &[(u32, [f64; 3], [f64; 3])], g: &[(u32, [f64; 3], [f64; 3])]) -> f64 {
    assert_eq!(c.len(), g.len(), "particle counts");
    c.iter()
        .zip(g)
        .map(|(a, b)| {
            assert_eq!(a.0, b.0, "particle ids");
            (0..3).map(|k| (a.1[k] - b.1[k]).abs()).fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}

/// `steps` fixed steps of `dt` (s) on the CPU and on `gpu` from the same start.
fn both_with<R: Real, M: Model<R>>(
    gpu: Gpu,
    scene: &Scene,
    model: M,
    steps: usize,
    dt: f64,
) -> (CpuSimulation<R, M>, GpuSimulation<R, M>) {
    let initial = initial_particles(scene, "test scene").expect("valid");
    let mut cpu = CpuSimulation::<R, M>::new(scene, &initial, model);
    let mut on_gpu = GpuSimulation::<R, M>::new_on_gpu(scene, &initial, model, gpu).expect("device state");
    on_gpu.backend.check_every = 1;
    for _ in 0..steps {
        cpu.step_with(dt, coil::time_step::Limit::Acoustic).expect("stable on the CPU");
        on_gpu.step_with(dt, coil::time_step::Limit::Acoustic).expect("stable on the device");
    }
    on_gpu.sync().expect("download");
    (cpu, on_gpu)
}

/// `steps` steps of 2e-4 s, the dam break's acoustic bound.
fn both<R: Real, M: Model<R>>(gpu: Gpu, scene: &Scene, model: M, steps: usize) -> (CpuSimulation<R, M>, GpuSimulation<R, M>) {
    both_with(gpu, scene, model, steps, 2e-4)
}

/// The largest f64 position difference (m) between the CPU and `engine` after 50 steps of
/// `scene` with `model`.
fn f64_difference_after_50_steps<M: Model<f64>>(engine: Engine, scene: &Scene, model: M) -> f64 {
    let (cpu, on_gpu) = both::<f64, _>(engine.open(), scene, model, 50);
    largest_position_difference(&state_by_id(cpu.particles()), &state_by_id(on_gpu.particles()))
}

/// One step: the sort is integer work on identical positions, so the particle order must be
/// identical; the floats differ only by the device's fused multiply-adds (not at all on the
/// emulated device).
#[test]
fn one_gpu_step_sorts_exactly_like_the_cpu() {
    for engine in engines() {
        let scene = dam_break();
        let (cpu, on_gpu) = both::<f64, _>(engine.open(), &scene, cross::<f64>(&scene), 1);
        let (c, g) = (&cpu.particles(), &on_gpu.particles());
        assert_eq!(c.len(), g.len());
        assert_eq!(c.id[..c.len()], g.id[..g.len()], "{engine:?}: particle order after the sort");
        let relative = if engine == Engine::Emulated { 0.0 } else { 1e-12 };
        for i in 0..c.len() {
            let (dc, dg) = (c.density[i], g.density[i]);
            assert!((dc - dg).abs() <= relative * dc, "{engine:?}: density of particle {i}: CPU {dc}, device {dg}");
        }
    }
}

/// A whole scene for 50 steps, in f64 and in f32 (whose sums differ on a GPU by 6e-8 relative
/// in their last bits: 1e-5 m, still far below the 0.04 m spacing).
#[test]
fn a_scene_on_the_gpu_agrees_with_the_cpu() {
    fn compare<R: Real>(engine: Engine, position_tolerance_m: f64) {
        let scene = dam_break();
        let (cpu, on_gpu) = both::<R, _>(engine.open(), &scene, cross::<R>(&scene), 50);
        let worst = largest_position_difference(&state_by_id(cpu.particles()), &state_by_id(on_gpu.particles()));
        println!("{engine:?}, {}: largest position difference after 50 steps {worst:.3e} m", R::NAME);
        assert!(worst <= position_tolerance_m, "{engine:?}, {}: positions differ by {worst:.3e} m", R::NAME);
    }
    for engine in engines() {
        compare::<f64>(engine, engine.f64_tolerance_m());
        compare::<f32>(engine, if engine == Engine::Emulated { 0.0 } else { 1e-5 });
    }
}

/// Asserts that `engine` ran `what` in f64 within its tolerance of the CPU.
fn assert_f64_agreement(engine: Engine, what: &str, worst: f64) {
    println!("{engine:?}, {what}, f64: largest position difference after 50 steps {worst:.3e} m");
    assert!(worst <= engine.f64_tolerance_m(), "{engine:?}, {what}: positions differ by {worst:.3e} m");
}

/// The dam break with mirrored walls: the wall pass reads the fluid around each mirror image in
/// the same order on both, so f64 positions agree as closely as without it.
#[test]
fn mirrored_walls_on_the_gpu_agree_with_the_cpu() {
    let mut scene = dam_break();
    scene.simulation.walls = coil::scene::Walls::Mirrored;
    for engine in engines() {
        assert_f64_agreement(engine, "mirrored walls", f64_difference_after_50_steps(engine, &scene, cross::<f64>(&scene)));
    }
}

/// The dam break with the spiky density (its own PTX entry): f64 positions agree as closely as
/// with poly6.
#[test]
fn the_spiky_density_on_the_gpu_agrees_with_the_cpu() {
    let mut scene = dam_break();
    scene.material.density_kernel = coil::scene::DensityKernelKind::Spiky;
    for engine in engines() {
        assert_f64_agreement(engine, "spiky density", f64_difference_after_50_steps(engine, &scene, cross::<f64>(&scene)));
    }
}

/// Morris's operator, with a constant viscosity and with each particle's Cross viscosity (the
/// extra shear-viscosity pass): f64 positions agree as closely as under the paper's operator.
#[test]
fn morris_operators_on_the_gpu_agree_with_the_cpu() {
    let scene = dam_break();
    let newtonian = MorrisModel(Newtonian { nu0: scene.material.viscosity.nu0_m2_s });
    let thinning = ShearThinningMorrisModel(cross_law::<f64>(&scene.material.viscosity));
    for engine in engines() {
        assert_f64_agreement(engine, "Morris, nu0", f64_difference_after_50_steps(engine, &scene, newtonian));
        assert_f64_agreement(engine, "Morris, Cross", f64_difference_after_50_steps(engine, &scene, thinning));
    }
}

/// The paper's operator with hourglass control (the velocity-gradient pass and its own
/// acceleration entry), Newtonian and Cross: f64 positions agree as closely as without it.
#[test]
fn hourglass_control_on_the_gpu_agrees_with_the_cpu() {
    let scene = dam_break();
    let newtonian = HourglassStressModel { rheology: Newtonian { nu0: scene.material.viscosity.nu0_m2_s }, coefficient: 1.0 };
    let thinning = HourglassStressModel { rheology: cross_law::<f64>(&scene.material.viscosity), coefficient: 1.0 };
    for engine in engines() {
        assert_f64_agreement(engine, "hourglass control, nu0", f64_difference_after_50_steps(engine, &scene, newtonian));
        assert_f64_agreement(engine, "hourglass control, Cross", f64_difference_after_50_steps(engine, &scene, thinning));
    }
}

/// Runs are deterministic on the device too: the scatter's atomics only decide the order
/// within a cell, which the per-cell sort then fixes. The emulated device runs each launch's
/// threads in parallel in no set order, so it tests that fix as well.
#[test]
fn two_gpu_runs_are_bit_identical() {
    let scene = dam_break();
    let laplacian = LaplacianModel(Newtonian { nu0: scene.material.viscosity.nu0_m2_s as f32 });
    let bits = |s: &[(u32, [f64; 3], [f64; 3])]| {
        s.iter().map(|p| (p.0, p.1.map(f64::to_bits), p.2.map(f64::to_bits))).collect::<Vec<_>>()
    };
    for engine in engines() {
        let run = || {
            let (_, on_gpu) = both::<f32, _>(engine.open(), &scene, laplacian, 30);
            bits(&state_by_id(on_gpu.particles()))
        };
        assert!(run() == run(), "{engine:?}: two runs differ");
    }
}

/// A run that goes unstable on the device stops with the CPU's diagnosis.
#[test]
fn an_unstable_gpu_run_is_stopped_by_the_guard() {
    for engine in engines() {
        let scene = dam_break();
        let initial = initial_particles(&scene, "dam_break.toml").expect("valid");
        let model = cross::<f32>(&scene);
        let mut sim = GpuSimulation::<f32, _>::new_on_gpu(&scene, &initial, model, engine.open()).expect("device state");
        sim.backend.check_every = 1;
        let bound = sim.run.stepper.bound.dt().0;
        let stopped = (0..2000).find_map(|_| sim.step_with(50.0 * bound, coil::time_step::Limit::Fixed).err());
        match stopped {
            Some(coil::cuda::GpuStepError::Unstable(i)) => assert!(i.dt_s > i.stability_bound_s),
            other => panic!("{engine:?}: expected the guard to stop the run, got {other:?}"),
        }
    }
}

/// A round jet of D = 8 mm in a 4 cm box under gravity at c = 2 m/s, with room for 20 000
/// particles.
fn small_jet() -> Scene {
    let mut scene = common::scene(&common::jet_scene("nozzle = { shape = \"circle\", radius_m = 0.004 }", ""));
    scene.material.sound_speed_m_s = 2.0;
    scene.material.gravity_m_s2 = [0.0, -9.81, 0.0];
    scene.domain.min_m = [-0.02; 3];
    scene.domain.max_m = [0.02; 3];
    scene.simulation.max_fluid_particles = Some(20_000);
    scene
}

/// A jet (the paper's operator, a nozzle, gravity) that falls out of the bottom of the domain:
/// inlet layers staged on the host and appended on the device, the nozzle pass, and particles
/// dropped by the sort. dt = 2e-4 s is the Eq. (10) bound of both its terms (c = 2 m/s,
/// nu = 1e-3 m^2/s, h = 4 mm); 300 steps take the head 0.03 m below the nozzle's exit.
#[test]
fn a_jet_on_the_gpu_agrees_with_the_cpu() {
    let scene = small_jet();
    let model = StressModel(Newtonian { nu0: 0.001 }, KernelSum);
    for engine in engines() {
        let (cpu, on_gpu) = both_with::<f64, _>(engine.open(), &scene, model, 300, 2e-4);
        assert!(cpu.run.removed > 0, "no particle left the domain: the test would not see the drop");
        assert_eq!(on_gpu.run.removed, cpu.run.removed, "{engine:?}: particles removed");
        assert_eq!(on_gpu.run.fluid_count(), cpu.run.fluid_count(), "{engine:?}: fluid particles");
        let worst = largest_position_difference(&state_by_id(cpu.particles()), &state_by_id(on_gpu.particles()));
        println!("{engine:?}, jet: {} removed, largest position difference after 300 steps {worst:.3e} m", cpu.run.removed);
        assert!(worst <= engine.f64_tolerance_m(), "{engine:?}, jet: positions differ by {worst:.3e} m");
    }
}

/// The jet with implicit viscosity: the solve's passes, its fixed-order dot products read back
/// every iteration, and its arrays on the device move the particles as on the CPU; with the
/// paper's operator and with Morris's, constant and shear-thinning.
#[test]
fn implicit_viscosity_on_the_gpu_agrees_with_the_cpu() {
    use coil::scene::{ViscosityOperator, ViscositySolver};
    use coil::simulation::implicit_weiler2018::{ImplicitModel, MorrisOperator, ShearThinningMorrisOperator, StressOperator};
    fn agree<M: Model<f64>>(scene: &Scene, operator: M, what: &str) {
        for engine in engines() {
            let (cpu, on_gpu) = both_with::<f64, _>(engine.open(), scene, operator, 300, 2e-4);
            assert!(cpu.run.solves.iterations > 0, "{what}: the solve never iterated: the test would not see it");
            if matches!(engine, Engine::Emulated) {
                assert_eq!(on_gpu.run.solves, cpu.run.solves, "{engine:?}, {what}: the solves' iterations and residuals");
            }
            let worst = largest_position_difference(&state_by_id(cpu.particles()), &state_by_id(on_gpu.particles()));
            println!(
                "{engine:?}, implicit jet, {what}: {:.1} iterations a step, largest position difference after 300 steps {worst:.3e} m",
                cpu.run.solves.mean_iterations()
            );
            assert!(worst <= engine.f64_tolerance_m(), "{engine:?}, implicit jet, {what}: positions differ by {worst:.3e} m");
        }
    }
    let (tolerance, max_iterations) = (1e-3, 100);
    let mut paper = small_jet();
    paper.material.viscosity.solver = ViscositySolver::Implicit;
    paper.material.viscosity.velocity_gradient = coil::scene::VelocityGradient::OwnDensity;
    let operator = StressOperator(Newtonian { nu0: 0.001 });
    agree(&paper, ImplicitModel { operator, tolerance, max_iterations, picard_iterations: 0 }, "paper's operator");
    let mut morris = small_jet();
    morris.material.viscosity.solver = ViscositySolver::Implicit;
    morris.material.viscosity.operator = ViscosityOperator::Morris;
    let operator = MorrisOperator(Newtonian { nu0: 0.001 });
    agree(&morris, ImplicitModel { operator, tolerance, max_iterations, picard_iterations: 0 }, "Morris");
    morris.material.viscosity.cross_k_s = 1.0;
    morris.material.viscosity.nu_inf_m2_s = Some(1e-4);
    let operator = ShearThinningMorrisOperator(coil::simulation::model::cross_law::<f64>(&morris.material.viscosity));
    agree(&morris, ImplicitModel { operator, tolerance, max_iterations, picard_iterations: 3 }, "Morris, Cross, Picard");
}

/// Divergence-free pressure: the factors, both solves' sweeps, their error sums read back every
/// sweep, and their warm starts (state the sort gathers and the inlet appends at zero) move the
/// particles as on the CPU; a jet held by its nozzle's tube with implicit viscosity, on the
/// paper's plate and a mirrored one, and a block falling in a closed box, whose walls make the
/// solves sweep.
#[test]
fn divergence_free_pressure_on_the_gpu_agrees_with_the_cpu() {
    use coil::scene::{DensityEquation, Pressure, ViscositySolver};
    use coil::simulation::implicit_weiler2018::{ImplicitModel, StressOperator};
    fn agree<M: Model<f64>>(scene: &Scene, model: M, what: &str) {
        for engine in engines() {
            let (cpu, on_gpu) = both_with::<f64, _>(engine.open(), scene, model, 300, 2e-4);
            let sweeps = cpu.run.divergence_solves.iterations + cpu.run.density_solves.iterations;
            assert!(sweeps > 0, "{what}: the solves never swept: the test would not see them");
            if matches!(engine, Engine::Emulated) {
                assert_eq!(on_gpu.run.density_solves, cpu.run.density_solves, "{engine:?}, {what}: density solves");
                assert_eq!(on_gpu.run.divergence_solves, cpu.run.divergence_solves, "{engine:?}, {what}: divergence solves");
            }
            let worst = largest_position_difference(&state_by_id(cpu.particles()), &state_by_id(on_gpu.particles()));
            println!(
                "{engine:?}, divergence-free {what}: {sweeps} sweeps, largest position difference after 300 steps {worst:.3e} m"
            );
            assert!(worst <= engine.f64_tolerance_m(), "{engine:?}, divergence-free {what}: positions differ by {worst:.3e} m");
        }
    }
    let mut jet = small_jet();
    jet.simulation.pressure = Pressure::DivergenceFree;
    jet.material.density_equation = DensityEquation::Summation;
    jet.material.viscosity.solver = ViscositySolver::Implicit;
    jet.material.viscosity.velocity_gradient = coil::scene::VelocityGradient::OwnDensity;
    let operator = StressOperator(Newtonian { nu0: 0.001 });
    let implicit = ImplicitModel { operator, tolerance: 1e-3, max_iterations: 100, picard_iterations: 0 };
    agree(&jet, implicit, "jet");
    jet.simulation.walls = coil::scene::Walls::Mirrored;
    agree(&jet, implicit, "jet on a mirrored plate");
    let falling = common::set(
        &common::box_scene(0.02, [0.3, 0.3, 0.2], [0.12, 0.2, 0.2], ""),
        &[
            "material.gravity_m_s2=[0.0,-9.81,0.0]",
            "simulation.pressure=\"divergence_free\"",
            "material.density_kernel=\"spiky\"",
        ],
    );
    agree(&common::scene(&falling), StressModel(Newtonian { nu0: 0.01 }, KernelSum), "block in a box");
}

/// The jet with density from the continuity equation: its density is state that the sort
/// gathers, the inlet appends at rho0 and two more passes integrate, so positions and densities
/// agree as in the jet above.
#[test]
fn the_continuity_density_on_the_gpu_agrees_with_the_cpu() {
    let mut scene = small_jet();
    scene.material.density_equation = coil::scene::DensityEquation::Continuity;
    let model = StressModel(Newtonian { nu0: 0.001 }, KernelSum);
    for engine in engines() {
        let (cpu, on_gpu) = both_with::<f64, _>(engine.open(), &scene, model, 300, 2e-4);
        assert!(cpu.run.removed > 0, "no particle left the domain: the test would not see the drop");
        assert_eq!(on_gpu.run.fluid_count(), cpu.run.fluid_count(), "{engine:?}: fluid particles");
        let worst = largest_position_difference(&state_by_id(cpu.particles()), &state_by_id(on_gpu.particles()));
        let density_by_id = |p: &Particles<f64>| {
            let mut d: Vec<(u32, f64)> = (0..p.len()).map(|i| (p.id[i], p.density[i])).collect();
            d.sort_by_key(|e| e.0);
            d
        };
        let (dc, dg) = (density_by_id(cpu.particles()), density_by_id(on_gpu.particles()));
        let rho_worst =
            dc.iter().zip(&dg).map(|(c, g)| if c.0 == g.0 { (c.1 - g.1).abs() } else { f64::INFINITY }).fold(0.0, f64::max);
        let spread = dc.iter().map(|c| (c.1 - 1000.0).abs()).fold(0.0, f64::max);
        println!("{engine:?}, continuity jet: largest position difference {worst:.3e} m, density {rho_worst:.3e} kg/m^3 (spread {spread:.3e})");
        assert!(spread > 1e-3, "the density never left rho0: the test would not see it");
        assert!(worst <= engine.f64_tolerance_m(), "{engine:?}, continuity jet: positions differ by {worst:.3e} m");
        assert!(rho_worst <= 1e-9 * 1000.0, "{engine:?}, continuity jet: densities differ by {rho_worst:.3e} kg/m^3");
    }
}

/// The jet with particle shifting: three more passes (the shifts over neighbors, the nozzle's
/// tube kept unshifted, the shifts applied after leap-frog) and the shift's own device arrays.
/// The shifts move the jet measurably (against the same run unshifted) but not the fluid inside
/// the tube, and the device moves it the same.
#[test]
fn particle_shifting_on_the_gpu_agrees_with_the_cpu() {
    let mut scene = small_jet();
    scene.simulation.particle_shifting = 2.0;
    let model = StressModel(Newtonian { nu0: 0.001 }, KernelSum);
    let initial = initial_particles(&small_jet(), "test scene").expect("valid");
    let mut unshifted = CpuSimulation::<f64, _>::new(&small_jet(), &initial, model);
    for _ in 0..300 {
        unshifted.step_with(2e-4, coil::time_step::Limit::Acoustic).expect("stable");
    }
    for engine in engines() {
        let (cpu, on_gpu) = both_with::<f64, _>(engine.open(), &scene, model, 300, 2e-4);
        assert_eq!(on_gpu.run.fluid_count(), cpu.run.fluid_count(), "{engine:?}: fluid particles");
        let shifted = state_by_id(cpu.particles());
        let plain: std::collections::HashMap<u32, [f64; 3]> =
            state_by_id(unshifted.particles()).into_iter().map(|(id, x, _)| (id, x)).collect();
        let moved = shifted
            .iter()
            .filter_map(|(id, x, _)| plain.get(id).map(|y| (0..3).map(|k| (x[k] - y[k]).abs()).fold(0.0, f64::max)))
            .fold(0.0, f64::max);
        let worst = largest_position_difference(&shifted, &state_by_id(on_gpu.particles()));
        println!("{engine:?}, shifted jet: {moved:.3e} m from the unshifted jet, {worst:.3e} m between backends");
        assert!(moved > 1e-5, "the shifts moved the jet by {moved:.3e} m only: the test would not see them");
        let tube = cpu.run.inlet_tubes().next().expect("a nozzle");
        let in_tube: Vec<_> = shifted.iter().filter(|(_, x, _)| tube.contains(*x)).collect();
        assert!(in_tube.len() > 10, "{} particles in the tube", in_tube.len());
        for (id, x, _) in in_tube {
            assert_eq!(Some(x), plain.get(id), "particle {id} in the tube was shifted");
        }
        assert!(worst <= engine.f64_tolerance_m(), "{engine:?}, shifted jet: positions differ by {worst:.3e} m");
    }
}

/// The jet with the paper's operator reading the velocity gradient `estimate` (`choice` in the
/// scene) runs on the device as on the CPU, and the estimate moves the jet measurably against
/// Eq. (8) as printed.
fn a_gradient_estimate_on_the_gpu_agrees_with_the_cpu<G: GradientEstimate>(choice: coil::scene::VelocityGradient, estimate: G) {
    let mut scene = small_jet();
    scene.material.viscosity.velocity_gradient = choice;
    let model = StressModel(Newtonian { nu0: 0.001 }, estimate);
    let initial = initial_particles(&small_jet(), "test scene").expect("valid");
    let mut printed = CpuSimulation::<f64, _>::new(&small_jet(), &initial, StressModel(Newtonian { nu0: 0.001 }, KernelSum));
    for _ in 0..300 {
        printed.step_with(2e-4, coil::time_step::Limit::Acoustic).expect("stable");
    }
    let printed: std::collections::HashMap<u32, [f64; 3]> =
        state_by_id(printed.particles()).into_iter().map(|(id, x, _)| (id, x)).collect();
    for engine in engines() {
        let (cpu, on_gpu) = both_with::<f64, _>(engine.open(), &scene, model, 300, 2e-4);
        assert_eq!(on_gpu.run.fluid_count(), cpu.run.fluid_count(), "{engine:?}: fluid particles");
        let estimated = state_by_id(cpu.particles());
        let moved = estimated
            .iter()
            .filter_map(|(id, x, _)| printed.get(id).map(|y| (0..3).map(|k| (x[k] - y[k]).abs()).fold(0.0, f64::max)))
            .fold(0.0, f64::max);
        let worst = largest_position_difference(&estimated, &state_by_id(on_gpu.particles()));
        println!("{engine:?}, {choice:?} jet: {moved:.3e} m from Eq. (8)'s, {worst:.3e} m between backends");
        assert!(moved > 1e-6, "{choice:?} moved the jet by {moved:.3e} m only: the test would not see it");
        assert!(worst <= engine.f64_tolerance_m(), "{engine:?}, {choice:?} jet: positions differ by {worst:.3e} m");
    }
}

/// The renormalized gradient's own stress entries, whose second moment sum and 3x3 inverse the
/// device runs as the CPU does.
#[test]
fn the_renormalized_gradient_on_the_gpu_agrees_with_the_cpu() {
    a_gradient_estimate_on_the_gpu_agrees_with_the_cpu(coil::scene::VelocityGradient::Renormalized, Renormalized);
}

/// The own-density gradient's stress entries.
#[test]
fn the_own_density_gradient_on_the_gpu_agrees_with_the_cpu() {
    a_gradient_estimate_on_the_gpu_agrees_with_the_cpu(coil::scene::VelocityGradient::OwnDensity, OwnDensity);
}

/// A channel periodic in x and z (Morris et al.'s, 10 across, mirrored walls), its fluid
/// started at 0.01 m/s along x and 0.004 m/s along z so that particles cross the periodic faces
/// within the 50 steps (c = 0.1 m/s for Mach 0.1 and an acoustic dt bound of 2e-4 s). A missed
/// wrap moves a particle by a period (0.6 mm) and a neighbor missed across the seam changes the
/// density there by a tenth, both far above the tolerance: a millionth of the spacing (1e-10 m)
/// for f64, orders above the fused multiply-adds' rounding.
#[test]
fn periodic_channels_on_the_gpu_agree_with_the_cpu() {
    use coil::scene::ViscosityOperator;
    use coil::simulation::model::ShearThinningMorrisModel;
    use coil::validation::poiseuille::{Channel, CrossLaw};
    let mut channel = Channel::morris(10, ViscosityOperator::Stress);
    channel.cross = Some(CrossLaw { nu_inf_m2_s: 2.5e-7, k_s: 10.0, n: 0.5 });
    let mut scene = channel.scene(1.0);
    scene.material.sound_speed_m_s = 0.1;
    scene.fluid_blocks[0].velocity_m_s = [0.01, 0.0, 0.004];
    let initial = initial_particles(&scene, "channel").expect("valid");
    fn worst<M: Model<f64>>(engine: Engine, scene: &Scene, initial: &[(u32, [f64; 3], [f64; 3])], model: M) -> (f64, usize) {
        let (cpu, on_gpu) = both::<f64, _>(engine.open(), scene, model, 50);
        let c = state_by_id(cpu.particles());
        // Particles that crossed the face at x = L came back in at x = 0.
        let wrapped = c.iter().zip(initial).filter(|(now, start)| now.0 == start.0 && now.1[0] < start.1[0]).count();
        (largest_position_difference(&c, &state_by_id(on_gpu.particles())), wrapped)
    }
    let start = {
        let cpu = CpuSimulation::<f64, _>::new(&scene, &initial, cross::<f64>(&scene));
        state_by_id(cpu.particles())
    };
    let morris = ShearThinningMorrisModel(cross_law::<f64>(&scene.material.viscosity));
    for engine in engines() {
        let (paper, wrapped) = worst(engine, &scene, &start, cross::<f64>(&scene));
        let (thinning, _) = worst(engine, &scene, &start, morris);
        println!("{engine:?}, periodic channel, f64: largest position difference after 50 steps {paper:.3e} m (paper's operator), {thinning:.3e} m (Morris, Cross); {wrapped} particles wrapped");
        assert!(wrapped > 0, "no particle crossed a periodic face: the test would not see the wrap");
        let tolerance = engine.f64_tolerance_m();
        assert!(paper <= tolerance && thinning <= tolerance, "{engine:?}: positions differ by {paper:.3e} / {thinning:.3e} m");
    }
}

/// `coil bench`'s GPU path on the emulated device: a step's launches as the profile counts
/// them, device bytes per particle, the memory floor, and the report's kernel section. The
/// times are the host's and mean nothing for a GPU; the bookkeeping is what is tested.
#[test]
fn the_bench_profiles_every_launch_of_a_gpu_step() {
    use coil::bench::{bench_on, precision_name, BenchBackend, BenchOptions, TABLE_I};
    use coil::scene::Precision;
    let options = BenchOptions {
        sizes: vec![TABLE_I[0]],
        precisions: vec![Precision::F32, Precision::F64],
        backends: vec![BenchBackend::Cpu, BenchBackend::Cuda],
        steps: 4,
        cpu_large_steps: 4,
        warmup: 1,
        profile_steps: 2,
    };
    let report = bench_on(Some(Gpu::emulated()), &options, |_| {}).expect("the bench runs");
    assert_eq!(report.measurements.len(), 4, "two precisions on two backends");
    for pair in report.measurements.chunks(2) {
        let (cpu, m) = (&pair[0], &pair[1]);
        assert_eq!((cpu.backend, m.backend), (BenchBackend::Cpu, BenchBackend::Cuda));
        assert_eq!((m.fluid, m.boundary), (cpu.fluid, cpu.boundary), "the same dam break on both");
        let r = precision_name(m.precision);
        let launches = |k: &str| m.kernels.iter().find(|s| s.kernel == k).map_or(0.0, |s| s.launches_per_step);
        // The dam break is the paper's operator with the Cross model: one of each pass a step.
        for k in ["hash", "count_particles", "scan_offsets", "scatter_particles", "sort_buckets"] {
            assert_eq!(launches(k), 1.0, "{r}: {k}");
        }
        for stem in ["density", "stress_cross", "acceleration_stress", "leapfrog"] {
            assert_eq!(launches(&format!("{stem}_{r}")), 1.0, "{r}: {stem}");
        }
        // One launch an axis reorders the position, both velocities and (with the first) the ids.
        assert_eq!(launches(&format!("reorder_{r}")), 3.0, "{r}: reorder");
        // Every particle holds at least its position (24 bytes), id (4), velocity, half-step
        // velocity, acceleration, density and stress (16 numbers of R).
        let real = if r == "f32" { 4.0 } else { 8.0 };
        let state = (28.0 + 16.0 * real) * (m.fluid + m.boundary) as f64 / m.fluid as f64;
        assert!(m.bytes_per_fluid_particle >= state, "{r}: {} bytes per particle", m.bytes_per_fluid_particle);
        assert!(m.memory_floor_ms.is_some_and(|f| f > 0.0), "{r}: a floor from the measured copy bandwidth");
        assert_eq!(m.operations, cpu.operations, "{r}: one count of a step's operations for both backends");
        assert!(m.operations.is_some_and(|o| o.physics > 0.0 && o.candidates > 0.0), "{r}: {:?}", m.operations);
        assert_eq!(m.arithmetic_floor_ms, None, "{r}: the emulated device has no peak rate");
    }
    let md = coil::bench::report::markdown(&report, &options);
    assert!(md.contains("## GPU kernels at 1K"), "{md}");
}

/// An array on `gpu` holding `host`.
fn on_device<T: Copy>(gpu: &Gpu, host: &[T]) -> DeviceArray<T> {
    let mut a = DeviceArray::zeros(gpu, host.len(), "test input").expect("allocation");
    a.upload(gpu, host).expect("upload");
    a
}

/// The first `len` entries of `a`.
fn to_host<T: Copy + Default>(gpu: &Gpu, a: &DeviceArray<T>, len: usize) -> Vec<T> {
    let mut host = vec![T::default(); len];
    a.download(gpu, &mut host).expect("download");
    host
}

/// The emulated device runs a launch at the next copy or synchronisation, not when the host
/// queues it, as a GPU's stream does: a host read of device memory that does not wait reads the
/// bytes from before the launch.
#[test]
fn the_emulated_device_runs_launches_when_the_host_waits() {
    let mut gpu = Gpu::emulated();
    let n = 1000usize;
    let array = |values: &[u32]| {
        let mut a = DeviceArray::<u32>::zeros(&gpu, values.len(), "test array").expect("allocation");
        a.upload(&gpu, values).expect("upload");
        a
    };
    let count = array(&[n as u32]);
    let order = array(&(0..n as u32).rev().collect::<Vec<_>>());
    let unsorted = array(&(0..n as u32).map(|k| 7 * k).collect::<Vec<_>>());
    let sorted = array(&vec![0; n]);
    let args = ReorderArgs::<f32> {
        order: order.view(n),
        wide: Gathered::none(),
        first: Gathered::none(),
        second: Gathered::none(),
        index: Gathered::new(unsorted.view(n), sorted.view_mut(n)),
    };
    // SAFETY: reorder_f32(count, args), each array of its length.
    unsafe { gpu.launch("reorder_f32", n as u32, &[&ByValue(count.view(1)), &ByValue(args)]).expect("launch") };
    let unwaited = sorted.view(n);
    assert!((0..n).all(|k| unwaited.at(k) == 0), "the launch ran before the host waited");
    let gathered = to_host(&gpu, &sorted, n);
    assert_eq!(gathered, (0..n as u32).rev().map(|k| 7 * k).collect::<Vec<_>>());
}

/// Each stage of a step, launched alone on random particles, against the CPU: the cell key of
/// each particle from the same `hash` function, its histogram, the exclusive scan of that (in
/// chunks of 2 buckets, so the scan of the chunk totals takes two levels), the stable order by
/// key, the reorder and the live count, and the cells holding and near fluid, which are what
/// those stages are defined to give; then
/// the density, stress and acceleration passes against the same functions run on the CPU. 4000 particles over a
/// 8 x 6 x 5 grid of 0.1 m cells (about 17 to a cell, some cells nearly empty) and its margins,
/// so that about a tenth fall outside and must sort last. The integer stages must agree
/// exactly on any device; the float passes as `random_stages` says.
#[test]
fn each_stage_on_random_particles_matches_the_cpu() {
    for engine in engines() {
        for seed in [1, 2, 3] {
            random_stages(engine, seed);
        }
    }
}

fn random_stages(engine: Engine, seed: u64) {
    use coil_kernels::acceleration::acceleration_pass;
    use coil_kernels::cell_grid::{hash, CellGrid, Neighborhood};
    use coil_kernels::density::{density_pass, Poly6};
    use coil_kernels::view::{SymTensorViewMut, Vec3View, Vec3ViewMut, ViewMut};
    use coil_kernels::viscosity::stress_andrade2014::stress_pass;
    let mut gpu = engine.open();
    let grid = CellGrid { origin: [0.0; 3], inverse_cell_size: [10.0; 3], dims: [8, 6, 5] };
    let (n, cells) = (4000usize, grid.cell_count() as usize);
    let buckets = cells + 1;
    let mut rng = seed;
    // 1.8 % of each edge beyond each face: 1 - 1/1.036^3, about a tenth, lies outside.
    let position: [Vec<f64>; 3] = [0, 1, 2].map(|a| {
        let edge = grid.dims[a] as f64 * 0.1;
        (0..n).map(|_| edge * (1.036 * uniform(&mut rng) - 0.018)).collect()
    });
    let positions = Vec3View::new(&position[0], &position[1], &position[2]);

    // The CPU's answers.
    let key: Vec<u32> = (0..n).map(|i| hash(i, &grid, &positions)).collect();
    let mut histogram = vec![0u32; buckets];
    key.iter().for_each(|&k| histogram[k as usize] += 1);
    let start: Vec<u32> =
        std::iter::once(0).chain(histogram.iter().scan(0, |sum, &c| Some(*sum + c).inspect(|s| *sum = *s))).collect();
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_by_key(|&i| key[i as usize]);
    let live = start[cells] as usize;
    assert!(live < n && live > n * 8 / 10, "about a tenth outside: {live} of {n} inside");

    // The device's, stage by stage.
    let x = position.each_ref().map(|p| on_device(&gpu, p));
    let count = on_device(&gpu, &[n as u32]);
    let cell_key = on_device(&gpu, &vec![0u32; n]);
    let counters = on_device(&gpu, &vec![0u32; buckets]);
    let cell_start = on_device(&gpu, &vec![0u32; buckets + 1]);
    // Chunks of 2 buckets: 121 chunk totals, whose scan takes two levels.
    let chunk_len = 2usize;
    let chunks = buckets.div_ceil(chunk_len);
    let totals = on_device(&gpu, &vec![0u32; coil_kernels::counting_sort::scan_levels_len(chunks)]);
    let sorted_order = on_device(&gpu, &vec![0u32; n]);
    let sorted = [0, 1, 2].map(|_| on_device(&gpu, &vec![0f64; n]));
    let sorted_key = on_device(&gpu, &vec![0u32; n]);
    let c = ByValue(count.view(1));
    let (keys, counts) = (ByValue(cell_key.view(n)), ByValue(counters.counters()));
    let (chunk_count, chunk) = (ByValue(chunks as u32), ByValue(chunk_len as u32));
    // SAFETY: each argument list is its entry's, over arrays of the lengths the views claim.
    unsafe {
        let hash_args = HashArgs { grid, position: vec3_view(&x, n), cell_key: cell_key.view_mut(n) };
        gpu.launch("hash", n as u32, &[&c, &ByValue(hash_args)]).expect("hash");
        assert!(to_host(&gpu, &cell_key, n) == key, "{engine:?}, seed {seed}: hash");
        gpu.launch("count_particles", n as u32, &[&c, &keys, &counts]).expect("count");
        assert!(to_host(&gpu, &counters, buckets) == histogram, "{engine:?}, seed {seed}: histogram");
        let t = ByValue(totals.view_mut(chunks));
        gpu.launch("scan_chunk_totals", chunks as u32, &[&chunk_count, &chunk, &counts, &t]).expect("totals");
        coil::cuda::scan::scan_chunk_totals(&mut gpu, &totals, chunks).expect("offsets");
        let starts = ByValue(cell_start.view_mut(buckets + 1));
        gpu.launch("scan_chunks", chunks as u32, &[&chunk_count, &chunk, &ByValue(totals.view(chunks)), &counts, &starts])
            .expect("scan");
        assert!(to_host(&gpu, &cell_start, buckets + 1) == start, "{engine:?}, seed {seed}: scan");
        gpu.launch("scatter_particles", n as u32, &[&c, &keys, &counts, &ByValue(sorted_order.view_mut(n))]).expect("scatter");
        let starts = ByValue(cell_start.view(buckets + 1));
        gpu.launch("sort_buckets", cells as u32, &[&ByValue(cells as u32), &starts, &ByValue(sorted_order.view_mut(n))])
            .expect("per-cell sort");
        // Particles outside the domain are dropped, so their bucket is left in the scatter's
        // order: only its members must match.
        let mut device_order = to_host(&gpu, &sorted_order, n);
        assert!(device_order[..live] == order[..live], "{engine:?}, seed {seed}: order of the live particles");
        device_order[live..].sort_unstable();
        let mut outside = order[live..].to_vec();
        outside.sort_unstable();
        assert!(device_order[live..] == outside, "{engine:?}, seed {seed}: the particles outside");
        gpu.launch("set_count", 1, &[&ByValue(count.view_mut(1)), &starts, &ByValue(cells as u32)]).expect("count");
        assert_eq!(to_host(&gpu, &count, 1), [live as u32], "{engine:?}, seed {seed}: live count");
        let reorder = ReorderArgs {
            order: sorted_order.view(n),
            wide: Gathered::new(x[0].view(n), sorted[0].view_mut(n)),
            first: Gathered::new(x[1].view(n), sorted[1].view_mut(n)),
            second: Gathered::new(x[2].view(n), sorted[2].view_mut(n)),
            index: Gathered::new(cell_key.view(n), sorted_key.view_mut(n)),
        };
        gpu.launch("reorder_f64", n as u32, &[&c, &ByValue(reorder)]).expect("reorder");
        for a in 0..3 {
            let gathered: Vec<f64> = order[..live].iter().map(|&i| position[a][i as usize]).collect();
            assert!(to_host(&gpu, &sorted[a], live) == gathered, "{engine:?}, seed {seed}: reorder of axis {a}");
        }
        let gathered: Vec<u32> = order[..live].iter().map(|&i| key[i as usize]).collect();
        assert!(to_host(&gpu, &sorted_key, live) == gathered, "{engine:?}, seed {seed}: reorder of the keys");
    }

    // The cells holding and near fluid, with all but 6 particles as wall particles, so that
    // some cells lie away from fluid (a cell near no fluid holds walls only; an empty one
    // counts as near).
    let walls = n as u32 - 6;
    let holds: Vec<u8> =
        (0..cells).map(|c| order[start[c] as usize..start[c + 1] as usize].iter().any(|&i| i >= walls) as u8).collect();
    let coords = |c: usize| [c % 8, c / 8 % 6, c / 48].map(|k| k as i64);
    let near: Vec<u8> = (0..cells)
        .map(|c| {
            let empty = start[c] == start[c + 1];
            let around = (0..cells).any(|d| holds[d] == 1 && (0..3).all(|a| (coords(c)[a] - coords(d)[a]).abs() <= 1));
            (empty || around) as u8
        })
        .collect();
    assert!(near.contains(&0) && near.contains(&1), "seed {seed}: cells both near and away from fluid");
    let sorted_id = on_device(&gpu, &order[..live]);
    let holds_on_device = on_device(&gpu, &vec![0u8; cells]);
    let near_on_device = on_device(&gpu, &vec![0u8; cells]);
    let holds_args = HoldsFluidArgs {
        cell_start: cell_start.view(buckets + 1),
        id: sorted_id.view(live),
        boundary_count: walls,
        holds_fluid: holds_on_device.view_mut(cells),
    };
    let near_args = NearFluidArgs {
        grid,
        topology: Open,
        cell_start: cell_start.view(buckets + 1),
        holds_fluid: holds_on_device.view(cells),
        near_fluid: near_on_device.view_mut(cells),
    };
    // SAFETY: holds_fluid(cells, args) and near_fluid(cells, args) over the grid's cells.
    unsafe {
        gpu.launch("holds_fluid", cells as u32, &[&ByValue(cells as u32), &ByValue(holds_args)]).expect("holds fluid");
        gpu.launch("near_fluid", cells as u32, &[&ByValue(cells as u32), &ByValue(near_args)]).expect("near fluid");
    }
    assert!(to_host(&gpu, &holds_on_device, cells) == holds, "{engine:?}, seed {seed}: cells holding fluid");
    assert!(to_host(&gpu, &near_on_device, cells) == near, "{engine:?}, seed {seed}: cells near fluid");

    // The float passes over the live particles, sorted, with the dam break's constants (h =
    // 0.08 m, within the 0.1 m cells, the Cross law) and random velocities up to 0.5 m/s; a
    // quarter of them (ids below n / 4) are wall particles, whose acceleration is zero and whose
    // density is floored at rho0.
    let scene = dam_break();
    let initial = initial_particles(&scene, "dam_break.toml").expect("valid");
    let mut fluid = CpuSimulation::<f64, _>::new(&scene, &initial, cross::<f64>(&scene)).run.fluid;
    fluid.boundary_count = n as u32 / 4;
    fluid.wall_density_floor = fluid.rest_density;
    let rheology = cross_law::<f64>(&scene.material.viscosity);
    let sorted: [Vec<f64>; 3] = [0, 1, 2].map(|a| order[..live].iter().map(|&i| position[a][i as usize]).collect());
    let velocity: [Vec<f64>; 3] = [0, 1, 2].map(|_| (0..live).map(|_| uniform(&mut rng) - 0.5).collect());
    let id = &order[..live];
    let mut density = vec![0f64; live];
    let mut stress: [Vec<f64>; 6] = std::array::from_fn(|_| vec![0f64; live]);
    let mut acceleration: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0f64; live]);
    // The wall particles move here, so every cell counts as near fluid.
    let everywhere = vec![1u8; cells];
    {
        let neighborhood = Neighborhood {
            grid,
            cell_start: View::new(&start),
            position: Vec3View::new(&sorted[0], &sorted[1], &sorted[2]),
            topology: Open,
            near_fluid: View::new(&everywhere),
        };
        let density_args = DensityArgs { neighborhood, fluid, id: View::new(id), density: ViewMut::new(&mut density) };
        (0..live).for_each(|i| density_pass::<f64, Poly6, _>(i, &density_args));
        let [xx, yy, zz, xy, xz, yz] = &mut stress;
        let stress_view = SymTensorViewMut {
            xx: ViewMut::new(xx),
            yy: ViewMut::new(yy),
            zz: ViewMut::new(zz),
            xy: ViewMut::new(xy),
            xz: ViewMut::new(xz),
            yz: ViewMut::new(yz),
        };
        let stress_args = StressArgs {
            neighborhood,
            gradient: KernelSum,
            fluid,
            rheology,
            velocity: Vec3View::new(&velocity[0], &velocity[1], &velocity[2]),
            density: View::new(&density),
            stress: stress_view,
        };
        (0..live).for_each(|i| stress_pass::<f64, Cross<f64>, KernelSum, _>(i, &stress_args));
        let [ax, ay, az] = &mut acceleration;
        let acceleration_args = AccelerationArgs {
            neighborhood,
            fluid,
            viscous: StressDivergence { stress: stress_view.read() },
            id: View::new(id),
            density: View::new(&density),
            acceleration: Vec3ViewMut::new(ax, ay, az),
        };
        (0..live).for_each(|i| acceleration_pass::<f64, StressDivergence<f64>, _>(i, &acceleration_args));
    }

    let sorted_on_device = sorted.each_ref().map(|p| on_device(&gpu, p));
    let velocity_on_device = velocity.each_ref().map(|v| on_device(&gpu, v));
    let id_on_device = on_device(&gpu, id);
    let everywhere_on_device = on_device(&gpu, &everywhere);
    let device_density = on_device(&gpu, &vec![0f64; live]);
    let device_stress: [DeviceArray<f64>; 6] = std::array::from_fn(|_| on_device(&gpu, &vec![0f64; live]));
    let device_acceleration: [DeviceArray<f64>; 3] = std::array::from_fn(|_| on_device(&gpu, &vec![0f64; live]));
    let neighborhood = Neighborhood {
        grid,
        cell_start: cell_start.view(buckets + 1),
        position: vec3_view(&sorted_on_device, live),
        topology: Open,
        near_fluid: everywhere_on_device.view(cells),
    };
    let [xx, yy, zz, xy, xz, yz] = &device_stress;
    let stress_view = SymTensorViewMut {
        xx: xx.view_mut(live),
        yy: yy.view_mut(live),
        zz: zz.view_mut(live),
        xy: xy.view_mut(live),
        xz: xz.view_mut(live),
        yz: yz.view_mut(live),
    };
    let density_args = DensityArgs { neighborhood, fluid, id: id_on_device.view(live), density: device_density.view_mut(live) };
    let stress_args = StressArgs {
        neighborhood,
        gradient: KernelSum,
        fluid,
        rheology,
        velocity: vec3_view(&velocity_on_device, live),
        density: device_density.view(live),
        stress: stress_view,
    };
    let acceleration_args = AccelerationArgs {
        neighborhood,
        fluid,
        viscous: StressDivergence { stress: stress_view.read() },
        id: id_on_device.view(live),
        density: device_density.view(live),
        acceleration: vec3_view_mut(&device_acceleration, live),
    };
    // SAFETY: each entry's (count, args), the count now the live one.
    unsafe {
        gpu.launch("density_f64", live as u32, &[&c, &ByValue(density_args)]).expect("density");
        gpu.launch("stress_cross_f64", live as u32, &[&c, &ByValue(stress_args)]).expect("stress");
        gpu.launch("acceleration_stress_f64", live as u32, &[&c, &ByValue(acceleration_args)]).expect("acceleration");
    }
    // Each value is a sum over ~40 neighbors; a GPU rounds each product-sum once instead of
    // twice, which moves a sum by about 1e-16 of its largest terms. Against the largest value
    // of the field, 1e-12 leaves four orders of room, while a missed or extra neighbor moves a
    // value by a whole term. The emulated device runs the CPU's code and must match it exactly.
    let tolerance = if engine == Engine::Emulated { 0.0 } else { 1e-12 };
    let compare = |what: &str, cpu: &[f64], device: &DeviceArray<f64>| {
        let scale = cpu.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 0.0, "{what}: all zero, the comparison would see nothing");
        for (i, (&on_cpu, on_device)) in cpu.iter().zip(to_host(&gpu, device, live)).enumerate() {
            assert!(
                (on_cpu - on_device).abs() <= tolerance * scale,
                "{engine:?}, seed {seed}: {what} of particle {i}: CPU {on_cpu}, device {on_device}"
            );
        }
    };
    compare("density", &density, &device_density);
    for (k, name) in ["xx", "yy", "zz", "xy", "xz", "yz"].iter().enumerate() {
        compare(&format!("stress {name}"), &stress[k], &device_stress[k]);
    }
    for (a, name) in ["x", "y", "z"].iter().enumerate() {
        compare(&format!("acceleration {name}"), &acceleration[a], &device_acceleration[a]);
    }
}

/// The device's scan of the chunk totals by levels against prefix sums: 300 000 random totals,
/// four levels (the 2 million cells of Table I's 1M size make 34 000 chunks, three levels).
#[test]
fn the_scan_of_many_chunk_totals_on_the_gpu_gives_the_prefix_sums() {
    use coil_kernels::counting_sort::scan_levels_len;
    let totals = 300_000;
    let mut state = 13u64;
    let values: Vec<u32> = (0..totals).map(|_| (uniform(&mut state) * 40.0) as u32).collect();
    let prefix: Vec<u32> = values.iter().scan(0, |sum, &v| Some(std::mem::replace(sum, *sum + v))).collect();
    for engine in engines() {
        let mut gpu = engine.open();
        let mut levels = DeviceArray::<u32>::zeros(&gpu, scan_levels_len(totals), "levels").expect("allocation");
        levels.upload(&gpu, &values).expect("upload");
        coil::cuda::scan::scan_chunk_totals(&mut gpu, &levels, totals).expect("scan");
        assert!(to_host(&gpu, &levels, totals) == prefix, "{engine:?}: the scanned totals are not the prefix sums");
    }
}

/// The files of a run's folder, by name, with their bytes.
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .expect("output folder")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "vtu" || e == "pvd"))
        .map(|p| (p.file_name().expect("a name").to_string_lossy().into_owned(), std::fs::read(&p).expect("readable")))
        .collect();
    files.sort();
    files
}

/// Bytes the device holds once `model`'s run of `scene` is on it, and what the run counts (the figure `coil run` prints and docs/benchmark.md's memory table comes from).
fn held_and_counted<R: Real, M: Model<R>>(scene: &Scene, model: M) -> (usize, usize) {
    let initial = initial_particles(scene, "dam_break.toml").expect("particles");
    let mut on_gpu =
        GpuSimulation::<R, M>::new_on_gpu(scene, &initial, model, Gpu::emulated_with_memory(usize::MAX)).expect("device state");
    let (free, total) = on_gpu.backend.gpu().memory();
    (total - free, on_gpu.backend.memory_bytes())
}

/// The device memory a run reports is every byte it allocates (the emulated device counts the
/// bytes each allocation asks for), with each optional field (stress, viscosity, velocity
/// gradient, wall mirror images) and in both precisions; `coil check` reports the same figure.
#[test]
fn the_device_memory_a_run_reports_is_all_it_allocates() {
    let mut scene = dam_break();
    let newtonian = Newtonian { nu0: scene.material.viscosity.nu0_m2_s };
    let mut cases = vec![
        ("paper's operator, Cross, f32", held_and_counted::<f32, _>(&scene, cross::<f32>(&scene))),
        ("Laplacian, f32", held_and_counted::<f32, _>(&scene, LaplacianModel(Newtonian { nu0: newtonian.nu0 as f32 }))),
        (
            "Morris's, Cross, f64",
            held_and_counted::<f64, _>(&scene, ShearThinningMorrisModel(cross_law::<f64>(&scene.material.viscosity))),
        ),
        (
            "hourglass control, f64",
            held_and_counted::<f64, _>(&scene, HourglassStressModel { rheology: newtonian, coefficient: 1.0 }),
        ),
    ];
    scene.simulation.walls = coil::scene::Walls::Mirrored;
    cases.push(("mirrored walls, f64", held_and_counted::<f64, _>(&scene, cross::<f64>(&scene))));
    let dam_break_f32 = cases[0].1 .1;
    for (case, (held, counted)) in cases {
        assert_eq!(held, counted, "{case}: bytes the device holds, and the run counts");
    }
    // `coil check` tells it before a run.
    let report = coil::check::check(&dam_break(), "dam_break.toml", Some(coil::scene::Precision::F32), std::time::Duration::ZERO)
        .expect("a valid scene");
    assert_eq!(report.device_memory_bytes, Some(dam_break_f32), "coil check's device memory");
}

/// A run that does not fit its device stops before its first step with the device's numbers:
/// the array it could not allocate, the bytes that needed, and the bytes free of the total; it
/// logs that diagnosis, and points an f64 run to f32. With exactly the memory it holds, the
/// same run completes.
#[test]
fn a_run_too_large_for_its_device_says_what_it_needed() {
    let mut scene = dam_break();
    scene.simulation.end_time_s = 0.002;
    let (held, _) = held_and_counted::<f32, _>(&scene, cross::<f32>(&scene));
    let root = std::env::temp_dir().join(format!("coil-cuda-memory-{}", std::process::id()));
    let fits = coil::run::run_on(
        Some(Gpu::emulated_with_memory(held)),
        &scene,
        "dam_break.toml",
        &quiet_run_options(&root.join("fits")),
    );
    assert!(fits.is_ok(), "a device of exactly the run's {held} bytes: {:?}", fits.err().map(|e| e.to_string()));
    let small = held - 4096;
    let out = root.join("small");
    match coil::run::run_on(Some(Gpu::emulated_with_memory(small)), &scene, "dam_break.toml", &quiet_run_options(&out)) {
        Err(coil::run::RunError::Backend(message)) => {
            assert!(message.starts_with("out of device memory allocating "), "{message}");
            // "…: N bytes needed, F of T bytes free; …"
            let numbers: Vec<usize> = message
                .split_once(": ")
                .and_then(|(_, rest)| rest.split_once(';'))
                .map(|(figures, _)| figures.split([' ', ',']).filter_map(|w| w.parse().ok()).collect())
                .unwrap_or_default();
            let [needed, free, total] = numbers[..] else { panic!("needed, free and total bytes in: {message}") };
            assert_eq!(total, small, "{message}");
            assert!(needed > free, "{message}");
            assert!(!message.contains("--precision f32"), "an f32 run is told to run in f32: {message}");
            let log = std::fs::read_to_string(out.join("run.json")).expect("run log");
            assert!(log.contains("\"status\": \"failed\"") && log.contains("out of device memory"), "{log}");
        }
        other => panic!("a device of {small} bytes, 4096 short: {:?}", other.map_err(|e| e.to_string())),
    }
    // In f64 the state the f32 run fits into is too small, and f32 is the way out.
    let in_f64 = coil::run::RunOptions { precision: Some(coil::scene::Precision::F64), ..quiet_run_options(&root.join("f64")) };
    match coil::run::run_on(Some(Gpu::emulated_with_memory(held)), &scene, "dam_break.toml", &in_f64) {
        Err(coil::run::RunError::Backend(message)) => {
            assert!(message.starts_with("out of device memory") && message.contains("--precision f32"), "{message}")
        }
        other => panic!("f64 on the f32 run's device: {:?}", other.map_err(|e| e.to_string())),
    }
    std::fs::remove_dir_all(&root).ok();
}

/// `coil run`'s loop on the device, where frames are downloaded and the diagnostics read every
/// 10 steps: the dam break for 0.04 s, a frame every 0.01 s. dt stays the acoustic term (the
/// fluid moves at under 1 m/s, c is 20 m/s), so the device's 10-step-old speed cannot change
/// it, and the emulated device must write the CPU's frames byte for byte; a GPU the same
/// frames, its positions within the scene tests' 1e-5 m in f32.
#[test]
fn a_run_on_the_gpu_writes_the_cpus_frames() {
    let mut scene = dam_break();
    scene.simulation.end_time_s = 0.04;
    scene.output.every_s = Some(0.01);
    let root = std::env::temp_dir().join(format!("coil-cuda-run-{}", std::process::id()));
    let cpu_out = root.join("cpu");
    let cpu = coil::run::run_on(None, &scene, "dam_break.toml", &quiet_run_options(&cpu_out)).expect("the CPU run");
    assert_eq!(cpu.frames, 5, "frames at 0, 0.01, ..., 0.04 s: {cpu:?}");
    for engine in engines() {
        let out = root.join(format!("{engine:?}"));
        let on_gpu = coil::run::run_on(Some(engine.open()), &scene, "dam_break.toml", &quiet_run_options(&out)).expect("the run");
        assert_eq!((on_gpu.steps, on_gpu.frames, on_gpu.fluid_particles), (cpu.steps, cpu.frames, cpu.fluid_particles));
        let (c, g) = (files(&cpu_out), files(&out));
        assert!(c.len() > cpu.frames, "the frames and the series file: {:?}", c.iter().map(|f| &f.0).collect::<Vec<_>>());
        assert_eq!(c.iter().map(|f| &f.0).collect::<Vec<_>>(), g.iter().map(|f| &f.0).collect::<Vec<_>>(), "{engine:?}");
        if engine == Engine::Emulated {
            assert!(c == g, "the emulated device's frames differ from the CPU's");
        } else {
            for ((name, _), _) in c.iter().zip(&g).filter(|(f, _)| f.0.ends_with(".vtu")) {
                let (a, b) = (read_frame(&cpu_out.join(name)), read_frame(&out.join(name)));
                let worst =
                    a.iter().zip(&b).map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0, f64::max)).fold(0.0, f64::max);
                assert!(worst <= 1e-5, "{engine:?}, {name}: positions differ by {worst:.3e} m");
            }
        }
    }
    std::fs::remove_dir_all(&root).ok();
}

/// Positions of a frame by particle id.
fn read_frame(path: &Path) -> Vec<[f64; 3]> {
    let frame = coil::output::vtu_read::read_frame(path).expect("a whole frame");
    let mut by_id: Vec<_> = frame.id.iter().zip(&frame.position).map(|(&i, &p)| (i, p)).collect();
    by_id.sort_by_key(|f| f.0);
    by_id.into_iter().map(|f| f.1).collect()
}

/// A run that goes unstable on the device stops with the guard's diagnosis, logs it, and keeps
/// every frame written before it, none of them with a non-finite position.
#[test]
fn an_unstable_run_on_the_gpu_keeps_its_frames() {
    let mut scene = dam_break();
    let bound = scene.support_radius() * 0.1 / scene.material.sound_speed_m_s;
    scene.simulation.time_step.fixed_s = Some(50.0 * bound);
    scene.simulation.time_step.allow_above_stability_bound = true;
    scene.simulation.end_time_s = 10.0;
    scene.output.every_s = Some(0.01);
    for engine in engines() {
        let out = std::env::temp_dir().join(format!("coil-cuda-unstable-{}-{engine:?}", std::process::id()));
        match coil::run::run_on(Some(engine.open()), &scene, "dam_break.toml", &quiet_run_options(&out)) {
            Err(coil::run::RunError::Unstable(instability, summary)) => {
                assert!(instability.dt_s > instability.stability_bound_s, "{engine:?}: {instability}");
                assert!(summary.frames >= 1, "{engine:?}: the frame at t = 0 is kept: {summary:?}");
                let frames = files(&out).into_iter().filter(|f| f.0.starts_with("frame_")).collect::<Vec<_>>();
                assert_eq!(frames.len(), summary.frames, "{engine:?}");
                for (name, _) in frames {
                    assert!(read_frame(&out.join(&name)).iter().flatten().all(|x| x.is_finite()), "{engine:?}, {name}");
                }
                let log = std::fs::read_to_string(out.join("run.json")).expect("run log");
                assert!(log.contains("\"status\": \"unstable\""), "{engine:?}: {log}");
            }
            other => panic!("{engine:?}: expected the guard to stop the run, got {other:?}"),
        }
        std::fs::remove_dir_all(&out).ok();
    }
}

/// A run on the device stopped by its program waits for the step at which the device's figures
/// come back (the 10th), checkpoints there, and resumed on the device writes the frames of a run
/// never stopped, byte for byte (on a GPU too: two runs there are bit-identical).
#[test]
fn a_run_stopped_on_the_gpu_resumes_to_the_frames_of_one_never_stopped() {
    use std::sync::atomic::AtomicBool;
    let mut scene = dam_break();
    scene.simulation.end_time_s = 0.04;
    scene.output.every_s = Some(0.01);
    let stop: &'static AtomicBool = Box::leak(Box::new(AtomicBool::new(true)));
    for engine in engines() {
        let root = std::env::temp_dir().join(format!("coil-cuda-resume-{}-{engine:?}", std::process::id()));
        let (whole, stopped) = (root.join("whole"), root.join("stopped"));
        let done = coil::run::run_on(Some(engine.open()), &scene, "dam_break.toml", &quiet_run_options(&whole)).expect("the run");
        let options = coil::run::RunOptions { stop: Some(stop), ..quiet_run_options(&stopped) };
        match coil::run::run_on(Some(engine.open()), &scene, "dam_break.toml", &options) {
            Err(coil::run::RunError::Interrupted(s)) => assert_eq!(s.steps, 10, "{engine:?}: {s:?}"),
            other => panic!("{engine:?}: expected the stop, got {other:?}"),
        }
        let resume =
            coil::run::ResumeOptions { backend: coil::run::Backend::Cuda, quiet: true, preview: false, set: vec![], stop: None };
        let resumed = coil::run::resume_on(Some(engine.open()), &stopped, &resume).expect("the resumed run");
        assert_eq!((resumed.steps, resumed.frames), (done.steps, done.frames), "{engine:?}");
        assert!(files(&whole) == files(&stopped), "{engine:?}: the resumed run's frames differ");
        std::fs::remove_dir_all(&root).ok();
    }
}

/// Every driver function this build links through cudarc (each a lazily loaded static named
/// after it in the binary's symbols, `<len><name>2_S17h...`) is one `Gpu::open` looks up first,
/// so that no call in a run meets a function the driver lacks.
#[test]
fn the_driver_functions_looked_up_at_open_are_all_that_the_build_calls() {
    let binary = std::fs::read(std::env::current_exe().expect("this test's binary")).expect("readable");
    let marker = b"2_S17h";
    let mut linked = std::collections::BTreeSet::new();
    for end in (0..binary.len().saturating_sub(marker.len())).filter(|&k| binary[k..].starts_with(marker)) {
        // The name is the `len` bytes before the marker, preceded by `len` in decimal.
        for len in 3..48.min(end) {
            let (name, before) = (&binary[end - len..end], &binary[..end - len]);
            let digits = len.to_string();
            if before.ends_with(digits.as_bytes())
                && name.starts_with(b"cu")
                && name[2].is_ascii_uppercase()
                && name.iter().all(|b| b.is_ascii_alphanumeric() || *b == b'_')
            {
                linked.insert(String::from_utf8_lossy(name).into_owned());
            }
        }
    }
    assert!(linked.contains("cuLaunchKernel") && linked.len() > 20, "the symbols were not found: {linked:?}");
    let missing: Vec<_> = linked.iter().filter(|f| !coil::cuda::gpu::DRIVER_FUNCTIONS.contains(&f.as_str())).collect();
    assert!(missing.is_empty(), "linked but not looked up at open: {missing:?}");
}

/// The `coil` binary: this build's, or `COIL_BIN` (the GPU bundle's, on a machine without the
/// build).
fn coil_binary() -> std::path::PathBuf {
    std::env::var_os("COIL_BIN").map(Into::into).unwrap_or_else(|| env!("CARGO_BIN_EXE_coil").into())
}

/// A fresh folder holding a stand-in `libcuda.so`, compiled with `cc` from C `source`; `None`
/// on a GPU machine (`COIL_REQUIRE_GPU=1`) that has no C compiler.
fn stand_in_driver(name: &str, source: &str) -> Option<std::path::PathBuf> {
    if std::env::var_os("COIL_REQUIRE_GPU").is_some() && std::process::Command::new("cc").arg("--version").output().is_err() {
        eprintln!("skipped: no C compiler for the stand-in driver on this machine");
        return None;
    }
    let dir = std::env::temp_dir().join(format!("coil-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a folder for the stand-in driver");
    let file = dir.join("cuda.c");
    std::fs::write(&file, source).expect("the stand-in's source");
    let built = std::process::Command::new("cc")
        .args(["-shared", "-fPIC", "-o"])
        .arg(dir.join("libcuda.so"))
        .arg(&file)
        .status()
        .expect("cc runs (Rust links with it)");
    assert!(built.success());
    std::fs::copy(dir.join("libcuda.so"), dir.join("libcuda.so.1")).expect("the versioned name too");
    Some(dir)
}

/// A driver library that lacks most functions (a stand-in built here with `cc`) gives
/// `--backend cuda` a clear error naming the first missing function, and `--backend auto` the
/// CPU with that reason: never a panic.
#[test]
fn an_old_driver_is_an_error_not_a_panic() {
    let Some(dir) = stand_in_driver(
        "old-driver",
        "int cuInit(unsigned int flags) { return 0; }\nint cuDeviceGetCount(int *n) { *n = 1; return 0; }\n",
    ) else {
        return;
    };
    let cuda = run_on_driver(&dir, &dir.join("out-cuda"), "cuda", &[]);
    let stderr = String::from_utf8_lossy(&cuda.stderr);
    assert_eq!(cuda.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("the CUDA driver lacks cu") && stderr.contains("--backend cpu"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let auto = run_on_driver(&dir, &dir.join("out-auto"), "auto", &[]);
    let stderr = String::from_utf8_lossy(&auto.stderr);
    assert!(auto.status.success(), "{stderr}");
    assert!(stderr.contains("backend: cpu (the CUDA driver lacks cu"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The stand-in driver of `tests/fake-cuda`, built once (in its own target folder: this test's
/// cargo holds `target/`'s lock) for the tests that run `coil` on it; on a machine without the
/// build, the GPU bundle's copy that `COIL_FAKE_CUDA_DIR` names.
fn fake_driver() -> &'static Path {
    static DIR: std::sync::OnceLock<std::path::PathBuf> = std::sync::OnceLock::new();
    DIR.get_or_init(|| {
        if let Some(dir) = std::env::var_os("COIL_FAKE_CUDA_DIR") {
            return dir.into();
        }
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let target = root.join("target/fake-cuda");
        let built = std::process::Command::new(env!("CARGO"))
            .args(["build", "--release", "--quiet", "-p", "fake-cuda", "--target-dir"])
            .arg(&target)
            .current_dir(root)
            .status()
            .expect("cargo runs");
        assert!(built.success(), "the fake driver builds");
        let dir = target.join("release");
        std::fs::copy(dir.join("libcuda.so"), dir.join("libcuda.so.1")).expect("the versioned name too");
        dir
    })
}

/// `coil run` of the dam break at 0.04 m spacing to 4 ms, a frame every 2 ms, on `backend`,
/// into `out`, the driver library in `driver` found first, with `env` set.
fn run_on_driver(driver: &Path, out: &Path, backend: &str, env: &[(&str, &str)]) -> std::process::Output {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dam_break.toml");
    std::process::Command::new(coil_binary())
        .arg("run")
        .arg(&scene)
        .args(["--backend", backend, "--overwrite", "--set", "simulation.end_time_s=0.004"])
        .args(["--set", "output.every_s=0.002", "--set", "material.particle_spacing_m=0.04", "--out"])
        .arg(out)
        .env("LD_LIBRARY_PATH", driver)
        .envs(env.iter().copied())
        .output()
        .expect("coil runs")
}

/// [`run_on_driver`] on the fake driver.
fn run_on_fake(out: &Path, backend: &str, env: &[(&str, &str)]) -> std::process::Output {
    run_on_driver(fake_driver(), out, backend, env)
}

/// What coil says of how the kernels reached the device, as the build made them.
fn kernel_code_line() -> &'static str {
    if coil::cuda::gpu::FATBIN.is_empty() {
        "kernels JIT-compiled from PTX (built without ptxas)"
    } else {
        "kernels compiled ahead of time for sm_90"
    }
}

/// Through cudarc and a driver (the fake one: device memory in host memory, work queued until
/// a synchronisation, the kernels' host builds launched by name with the parameter sizes its
/// PTX declares), `--backend cuda` writes the CPU's frames byte for byte and says it loaded the
/// fatbin's sm_90 cubin. Where the driver refuses the fatbin, as one older than the ptxas that
/// compiled it does, the run JIT-compiles the PTX instead, says why, and writes the same frames.
/// `coil bench` times the kernels there with the driver's events.
#[test]
fn the_driver_path_writes_the_cpus_frames() {
    let root = std::env::temp_dir().join(format!("coil-fake-driver-{}", std::process::id()));
    let cpu = run_on_fake(&root.join("cpu"), "cpu", &[]);
    assert!(cpu.status.success(), "{}", String::from_utf8_lossy(&cpu.stderr));
    let frames = files(&root.join("cpu"));
    assert_eq!(frames.iter().filter(|f| f.0.starts_with("frame_")).count(), 3, "frames at 0, 2 and 4 ms");
    let cuda = run_on_fake(&root.join("cuda"), "cuda", &[]);
    let stderr = String::from_utf8_lossy(&cuda.stderr);
    assert!(cuda.status.success(), "{stderr}");
    assert!(stderr.contains(&format!("backend: cuda, coil fake CUDA device (sm_90), {}", kernel_code_line())), "{stderr}");
    assert!(files(&root.join("cuda")) == frames, "the frames through the driver differ from the CPU's");
    if !coil::cuda::gpu::FATBIN.is_empty() {
        let refused = run_on_fake(&root.join("refused"), "cuda", &[("FAKE_CUDA_REFUSE", "fatbin")]);
        let stderr = String::from_utf8_lossy(&refused.stderr);
        assert!(refused.status.success(), "{stderr}");
        assert!(
            stderr.contains("kernels JIT-compiled from PTX (the driver refused the fatbin: ")
                && stderr.contains("no kernel image is available"),
            "{stderr}"
        );
        assert!(files(&root.join("refused")) == frames, "the frames from the PTX differ from the CPU's");
    }
    // `coil bench` times each kernel with the driver's events and probes its copy bandwidth.
    let bench = std::process::Command::new(coil_binary())
        .args(["bench", "--backend", "cuda", "--sizes", "1K", "--precision", "f32", "--steps", "3", "--out"])
        .arg(root.join("bench"))
        .env("LD_LIBRARY_PATH", fake_driver())
        .output()
        .expect("coil runs");
    assert!(bench.status.success(), "{}", String::from_utf8_lossy(&bench.stderr));
    let report = std::fs::read_to_string(root.join("bench/bench.md")).expect("the bench report");
    assert!(report.contains("## GPU kernels at 1K (f32), CUDA events") && report.contains("| reorder_f32 | 3.0 |"), "{report}");
    std::fs::remove_dir_all(&root).ok();
}

/// The fatbin holds cubins for sm_80 and sm_90 and the PTX (read from its headers), or there is
/// none and the build says it embeds the PTX alone.
#[test]
fn the_fatbin_holds_cubins_for_sm_80_and_sm_90_and_the_ptx() {
    let fatbin = coil::cuda::gpu::FATBIN;
    if fatbin.is_empty() {
        assert_eq!(coil::cuda::gpu::CUBIN_ARCHS, "", "cubins listed without a fatbin");
        eprintln!("skipped: built without ptxas, the PTX alone");
        return;
    }
    let word = |at: usize| u32::from_le_bytes(fatbin[at..at + 4].try_into().expect("4 bytes"));
    let long = |at: usize| u64::from_le_bytes(fatbin[at..at + 8].try_into().expect("8 bytes")) as usize;
    assert_eq!(word(0), 0xBA55_ED50, "the fatbin magic");
    let header = u16::from_le_bytes([fatbin[6], fatbin[7]]) as usize;
    assert_eq!(header + long(8), fatbin.len(), "the header's size covers the images");
    let mut images = Vec::new();
    let mut at = header;
    while at < fatbin.len() {
        let (kind, entry, bytes, sm) =
            (u16::from_le_bytes([fatbin[at], fatbin[at + 1]]), word(at + 4) as usize, long(at + 8), word(at + 28));
        let payload = &fatbin[at + entry..at + entry + bytes];
        images.push((kind, sm, payload.starts_with(b"\x7fELF"), payload.windows(8).any(|w| w == b".version")));
        at += entry + bytes;
    }
    // Kind 2 is a cubin (ELF), 1 the PTX (text), for the PTX target sm_70.
    assert_eq!(images, [(2, 80, true, false), (2, 90, true, false), (1, 70, false, true)]);
    assert_eq!(coil::cuda::gpu::CUBIN_ARCHS, "80,90");
}

/// A driver that refuses the PTX (as one older than its ISA does) gives `--backend cuda` an
/// error with the JIT compiler's own words, from the log buffer of a second load; one with no
/// device says so. Both exit 2, and `--backend auto` runs on the CPU instead.
#[test]
fn a_driver_that_refuses_the_ptx_shows_its_jit_log() {
    let root = std::env::temp_dir().join(format!("coil-fake-refusing-{}", std::process::id()));
    let all = [("FAKE_CUDA_REFUSE", "all")];
    let cuda = run_on_fake(&root.join("cuda"), "cuda", &all);
    let stderr = String::from_utf8_lossy(&cuda.stderr);
    assert_eq!(cuda.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("could not load coil's PTX"), "{stderr}");
    assert!(
        stderr.contains("its JIT compiler says: ptxas application ptx input, line 3; fatal   : Unsupported .version 7.0"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    let auto = run_on_fake(&root.join("auto"), "auto", &all);
    let stderr = String::from_utf8_lossy(&auto.stderr);
    assert!(auto.status.success(), "{stderr}");
    assert!(stderr.contains("backend: cpu (the CUDA driver could not load coil's PTX"), "{stderr}");
    let none = run_on_fake(&root.join("none"), "cuda", &[("FAKE_CUDA_DEVICES", "0")]);
    let stderr = String::from_utf8_lossy(&none.stderr);
    assert_eq!(none.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("the CUDA driver reports no device"), "{stderr}");
    std::fs::remove_dir_all(&root).ok();
}

/// A device that runs out of memory at an allocation stops the run before its first step with
/// exit 2, naming the array and the device's figures; one that faults (an illegal address,
/// reported at a synchronisation, as a GPU reports it) stops it with exit 1, naming the kernel
/// it reached, and keeps the frames written before it, all finite. With `COIL_CUDA_SYNC=1` the
/// error names the kernel that faulted.
#[test]
fn device_faults_give_clear_errors() {
    let root = std::env::temp_dir().join(format!("coil-fake-faults-{}", std::process::id()));
    let oom = run_on_fake(&root.join("oom"), "cuda", &[("FAKE_CUDA_OOM_AT", "5")]);
    let stderr = String::from_utf8_lossy(&oom.stderr);
    assert_eq!(oom.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("out of device memory allocating ") && stderr.contains("bytes free"), "{stderr}");
    let out = root.join("fault");
    let fault = run_on_fake(&out, "cuda", &[("FAKE_CUDA_ILLEGAL_ADDRESS_AT_SYNC", "40")]);
    let stderr = String::from_utf8_lossy(&fault.stderr);
    assert_eq!(fault.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("or a kernel before it failed") && stderr.contains("an illegal memory access"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let frames: Vec<_> = files(&out).into_iter().filter(|f| f.0.starts_with("frame_")).collect();
    assert!(!frames.is_empty(), "the frame at t = 0 is kept");
    for (name, _) in frames {
        assert!(read_frame(&out.join(&name)).iter().flatten().all(|x| x.is_finite()), "{name}");
    }
    let log = std::fs::read_to_string(out.join("run.json")).expect("run log");
    assert!(log.contains("\"status\": \"failed\"") && log.contains("illegal memory access"), "{log}");
    let named =
        run_on_fake(&root.join("named"), "cuda", &[("FAKE_CUDA_ILLEGAL_ADDRESS_AT_LAUNCH", "100"), ("COIL_CUDA_SYNC", "1")]);
    let stderr = String::from_utf8_lossy(&named.stderr);
    let faulted = stderr.lines().find_map(|l| l.strip_prefix("fake CUDA: kernel ")?.strip_suffix(" faulted"));
    let faulted = faulted.unwrap_or_else(|| panic!("the stand-in names the kernel it faulted: {stderr}"));
    assert_eq!(named.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains(&format!("error: CUDA kernel {faulted} failed: ")), "{stderr}");
    std::fs::remove_dir_all(&root).ok();
}

/// The carried state (`coil::visit_carried!`) on the device: a run's every carried array,
/// marked, scrambled and resumed onto each engine, is uploaded, sorted and downloaded with each
/// entry following its particle, and a particle an inlet appends starts as the list says.
#[test]
fn every_carried_array_follows_its_particle_on_the_device() {
    use coil::run::checkpoint::{encode, Checkpoint};
    use coil::simulation::variant::{with_precision_and_model, WithModel};
    use coil::simulation::Setup;
    use common::carried::{by_id, carrying_scene, mark_and_reverse, Starts, NEW_ID, NEW_POSITION, NEW_VELOCITY};
    use std::marker::PhantomData;

    struct OnDevice<'a>(&'a Scene, Engine);
    impl WithModel for OnDevice<'_> {
        type Output = ();
        fn with<R: Real, M: Model<R>>(self, model: M) {
            let (scene, engine) = (self.0, self.1);
            let initial = initial_particles(scene, "jet").expect("valid");
            let mut cpu = CpuSimulation::<R, M>::new(scene, &initial, model);
            for _ in 0..30 {
                cpu.step().expect("stable");
            }
            let n = cpu.particles().len();
            let (before, scrambled) = mark_and_reverse(cpu.particles_mut());

            let bytes = encode(&cpu.run, cpu.particles(), scene, &coil::run::Tally::default());
            let mut setup = Setup::<R, M>::new(scene, &initial, model);
            Checkpoint::decode(bytes).expect("a checkpoint").restore(&mut setup).expect("it fits the scene");
            let mut gpu = GpuSimulation::<R, M>::on_gpu(setup, engine.open()).expect("device state");
            gpu.backend.sort_and_reorder().expect("the device's sort");
            gpu.backend.download().expect("download");
            let p = &gpu.backend.host().particles;
            assert_ne!(p.id[..n], scrambled[..], "{engine:?}: the sort moved the particles");
            assert_eq!(by_id(p), before, "{engine:?}: every carried entry followed its particle");

            let (staging, _) = gpu.backend.inlet_staging();
            staging.push(NEW_ID, NEW_POSITION, NEW_VELOCITY);
            gpu.backend.append_staged(1).expect("append");
            gpu.backend.download().expect("download");
            let p = &gpu.backend.host().particles;
            assert_eq!(p.len(), n + 1);
            let mut starts = Starts::<R> { i: n, wrong: Vec::new(), real: PhantomData };
            coil::visit_carried!(ref &mut starts; p);
            assert!(starts.wrong.is_empty(), "{engine:?}: {:?}", starts.wrong);
        }
    }

    for engine in engines() {
        for precision in ["f32", "f64"] {
            let scene = carrying_scene(precision);
            with_precision_and_model(scene.simulation.precision, &scene, OnDevice(&scene, engine));
        }
    }
}
