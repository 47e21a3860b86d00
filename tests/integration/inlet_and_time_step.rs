//! Inlets deliver the mass flow rate they were given; dt follows Eq. (10) and refuses a step
//! above it, fixed or scaled, unless the scene overrides the bound.

use crate::common;

use coil::cpu::simulation::CpuSimulation;
use coil::scene::setup::initial_particles;
use coil::simulation::model::StressModel;
use coil::time_step::Limit;
use coil_kernels::cross_viscosity::Newtonian;
use coil_kernels::velocity_gradient::KernelSum;
use common::jet_scene;

fn delivered_mass_rate(text: &str, nominal_area: f64) {
    let scene = common::scene(text);
    let initial = initial_particles(&scene, "jet.toml").expect("valid");
    let mut sim = CpuSimulation::<f64, _>::new(&scene, &initial, StressModel(Newtonian { nu0: 0.001 }, KernelSum));
    let duration = 0.2;
    while sim.run.time < duration - 1e-12 {
        let (dt, limit) = sim.next_dt();
        sim.step_with(dt.min(duration - sim.run.time), limit).expect("stable");
    }
    let mass = sim.run.injected as f64 * sim.run.fluid.mass;
    let nominal = 1000.0 * nominal_area * 0.5 * duration;
    // Layers arrive whole: the delivered mass is within one layer of rho0 A U t.
    let layer_mass = sim.run.fluid.mass * layer_size(&scene);
    assert!((mass - nominal).abs() <= layer_mass, "delivered {mass} kg, nominal {nominal} kg, layer {layer_mass} kg");
    assert!(layer_mass < 0.05 * nominal, "the test resolves the rate to 5 %");
}

fn layer_size(scene: &coil::scene::Scene) -> f64 {
    let inlet =
        coil::scene::inlet::Inlet::new(&scene.inlets[0], scene.material.particle_spacing_m, scene.support_radius(), 1.0, 1.0);
    inlet.layer_size() as f64
}

#[test]
fn circular_inlet_delivers_rho0_area_speed() {
    let r = 0.007;
    delivered_mass_rate(
        &jet_scene(&format!("nozzle = {{ shape = \"circle\", radius_m = {r} }}"), ""),
        std::f64::consts::PI * r * r,
    );
}

#[test]
fn rectangular_inlet_delivers_rho0_area_speed() {
    delivered_mass_rate(&jet_scene("nozzle = { shape = \"rectangle\", width_m = 0.013, depth_m = 0.005 }", ""), 0.013 * 0.005);
}

#[test]
fn the_nozzle_tube_pushes_the_jet_at_its_speed_when_the_jet_is_blocked() {
    // A plate 3 support radii below the exit stops the jet; the fluid in the tube still moves at
    // exactly the jet velocity, so the layers keep their spacing and the flow rate holds.
    let text = common::set(
        &jet_scene("nozzle = { shape = \"circle\", radius_m = 0.006 }", "[[boundary]]\nshape = \"plate\"\nheight_m = -0.012"),
        &["material.viscosity.nu0_m2_s=0.01"],
    );
    let scene = common::scene(&text);
    let initial = initial_particles(&scene, "jet.toml").expect("valid");
    let mut sim = CpuSimulation::<f64, _>::new(&scene, &initial, StressModel(Newtonian { nu0: 0.01 }, KernelSum));
    while sim.run.time < 0.1 {
        sim.step().expect("stable");
    }
    let tube = sim.run.inlet_tubes().next().expect("one inlet");
    let p = sim.particles();
    let x = p.position_view();
    let inside: Vec<usize> = (0..p.len()).filter(|&i| !sim.run.fluid.is_boundary(p.id[i]) && tube.contains(x.at(i))).collect();
    // The tube is h = 0.004 m long and layers are about one spacing (0.002 m) apart: whole
    // layers, two or three of them, none crushed together.
    let layers = inside.len() as f64 / layer_size(&scene);
    assert!(layers.fract() == 0.0 && (2.0..=3.0).contains(&layers), "{layers} layers in the tube");
    for &i in &inside {
        let v = [p.velocity[0][i], p.velocity[1][i], p.velocity[2][i]];
        assert_eq!(v, [0.0, -0.5, 0.0], "particle {i} in the tube");
    }
    // Below the exit the jet has slowed down against the plate.
    let slowest = (0..p.len())
        .filter(|&i| !sim.run.fluid.is_boundary(p.id[i]))
        .map(|i| p.velocity[1][i].abs())
        .fold(f64::INFINITY, f64::min);
    assert!(slowest < 0.25, "the plate stops the jet (slowest {slowest} m/s)");
}

/// With implicit viscosity the fluid in the tube is a fixed value of the solve, as walls are:
/// the solve leaves it at the jet velocity (no viscous change), while the fluid below, slowed
/// by the plate, still drags on its neighbors.
#[test]
fn the_implicit_solve_holds_the_tube_fluid_at_the_jet_velocity() {
    use coil::simulation::implicit_weiler2018::{ImplicitModel, StressOperator};
    let text = common::set(
        &jet_scene("nozzle = { shape = \"circle\", radius_m = 0.006 }", "[[boundary]]\nshape = \"plate\"\nheight_m = -0.012"),
        &[
            "material.viscosity.nu0_m2_s=0.01",
            "material.viscosity.solver=\"implicit\"",
            "material.viscosity.velocity_gradient=\"own_density\"",
        ],
    );
    let scene = common::scene(&text);
    let initial = initial_particles(&scene, "jet.toml").expect("valid");
    let model = ImplicitModel {
        operator: StressOperator(Newtonian { nu0: 0.01 }),
        tolerance: 1e-6,
        max_iterations: 1000,
        picard_iterations: 0,
    };
    let mut sim = CpuSimulation::<f64, _>::new(&scene, &initial, model);
    while sim.run.time < 0.05 {
        sim.step().expect("stable");
    }
    // The solve of the last step saw the tubes of that step's start; the particles moved since.
    let tube = sim.run.inlet_tubes().next().expect("one inlet");
    let p = sim.particles();
    let x = p.position_view();
    let change = &p.implicit.as_ref().expect("allocated").viscous_change;
    let size = |i: usize| (0..3).map(|k| change[k][i] * change[k][i]).sum::<f64>().sqrt();
    let fluid: Vec<usize> = (0..p.len()).filter(|&i| !sim.run.fluid.is_boundary(p.id[i])).collect();
    // One spacing (2 mm) inside the exit, the particles were in the tube at the last solve too.
    let deep: Vec<usize> = fluid
        .iter()
        .copied()
        .filter(|&i| {
            let [a, b, c] = x.at(i);
            tube.contains([a, b - 0.002, c])
        })
        .collect();
    assert!(!deep.is_empty(), "fluid in the tube");
    for &i in &deep {
        assert_eq!(size(i), 0.0, "particle {i} in the tube changed by viscosity");
    }
    let largest = fluid.iter().map(|&i| size(i)).fold(0.0, f64::max);
    assert!(largest > 1e-4, "the solve slows the jet below the exit (largest change {largest} m/s)");
}

#[test]
fn inlet_stops_at_the_particle_budget_and_moving_nozzle_follows_waypoints() {
    let text = common::set(
        &jet_scene(
            "nozzle = { shape = \"circle\", radius_m = 0.004 }",
            "motion = { waypoints = [[0.0, 0.0, 0.0, 0.0], [0.1, 0.02, 0.0, 0.0]] }",
        ),
        &["simulation.max_fluid_particles=500"],
    );
    let scene = common::scene(&text);
    let inlet = coil::scene::inlet::Inlet::new(&scene.inlets[0], 0.002, 0.004, 1.0, 1.0);
    let (mid, v) = inlet.nozzle(0.05);
    assert!((mid[0] - 0.01).abs() < 1e-12 && (v[0] - 0.2).abs() < 1e-12);
    assert_eq!(inlet.nozzle(0.5).0, [0.02, 0.0, 0.0], "held at the last waypoint");
    let initial = initial_particles(&scene, "jet.toml").expect("valid");
    let mut sim = CpuSimulation::<f64, _>::new(&scene, &initial, StressModel(Newtonian { nu0: 0.001 }, KernelSum));
    while sim.run.time < 0.2 {
        sim.step().expect("stable");
    }
    let layer = inlet.layer_size();
    assert_eq!(sim.run.fluid_count(), 500 / layer * layer, "whole layers up to the budget");
    // The first layer is due at t = 0, so the first that does not fit, number 500 / layer from
    // 0, is due that many layer periods later; the step that finds it so is noted.
    let period = layer as f64 / sim.run.inlets()[0].particles_per_second();
    let due = (500 / layer) as f64 * period;
    let reached = sim.run.capacity_reached_at.expect("the budget stopped the inlet");
    assert!((reached - due).abs() <= sim.run.last_dt + 1e-12, "noted at {reached} s, the layer was due at {due} s");
}

#[test]
fn particles_leaving_the_domain_are_removed_and_counted() {
    // The jet runs out of the bottom of the domain 0.2 m below the nozzle after 0.4 s.
    let text = jet_scene("nozzle = { shape = \"circle\", radius_m = 0.004 }", "");
    let scene = common::scene(&text);
    let initial = initial_particles(&scene, "jet.toml").expect("valid");
    let mut sim = CpuSimulation::<f64, _>::new(&scene, &initial, StressModel(Newtonian { nu0: 0.001 }, KernelSum));
    while sim.run.time < 0.6 {
        sim.step().expect("stable");
    }
    assert!(sim.run.removed > 0);
    assert_eq!(sim.run.capacity_reached_at, None, "the capacity of 200 000 never stopped the inlet");
    let p = sim.particles();
    assert!((0..p.len()).all(|i| p.position[1][i] >= -0.2), "no particle below the domain is kept");
}

#[test]
fn automatic_dt_follows_equation_10() {
    let text = common::box_scene(0.02, [0.2; 3], [0.2; 3], "");
    let scene = common::scene(&text);
    let initial = initial_particles(&scene, "box.toml").expect("valid");
    let sim = CpuSimulation::<f64, _>::new(&scene, &initial, StressModel(Newtonian { nu0: 0.01 }, KernelSum));
    // h = 0.04 m, c = 20 m/s, nu0 = 0.01 m^2/s: 0.1 h / c = 2e-4 s, 0.1 h^2 / (8 nu0) = 2e-3 s.
    let (dt, limit) = sim.next_dt();
    assert!((dt - 2e-4).abs() < 1e-15 && limit == Limit::Acoustic, "{dt} {limit:?}");
    let viscous = common::scene(&common::set(&text, &["material.viscosity.nu0_m2_s=1.0"]));
    let sim = CpuSimulation::<f64, _>::new(&viscous, &initial, StressModel(Newtonian { nu0: 1.0 }, KernelSum));
    let (dt, limit) = sim.next_dt();
    assert!((dt - 2e-5).abs() < 1e-15 && limit == Limit::Viscous, "{dt} {limit:?}");
}

/// The box of `automatic_dt_follows_equation_10` (bound 2e-4 s, acoustic) with `time_step`
/// overrides, each `field=value` of `simulation.time_step`.
fn box_with_time_step(time_step: &[&str]) -> String {
    let set: Vec<String> = time_step.iter().map(|o| format!("simulation.time_step.{o}")).collect();
    common::set(&common::box_scene(0.02, [0.2; 3], [0.2; 3], ""), &set.iter().map(String::as_str).collect::<Vec<_>>())
}

#[test]
fn fixed_dt_above_the_bound_is_refused_unless_overridden() {
    let above = box_with_time_step(&["fixed_s=3e-4"]);
    let err = coil::scene::Scene::parse(&above, "box.toml").expect_err("refused");
    assert_eq!(err.field, "simulation.time_step.fixed_s");
    assert!(err.reason.contains("Eq. (10)") && err.reason.contains("2.000e-4"), "{}", err.reason);
    let allowed = box_with_time_step(&["fixed_s=3e-4", "allow_above_stability_bound=true"]);
    assert!(coil::scene::Scene::parse(&allowed, "box.toml").is_ok());
}

#[test]
fn a_safety_factor_above_one_is_refused_unless_overridden_and_then_scales_the_bound() {
    let above = box_with_time_step(&["safety_factor=4.0"]);
    let err = coil::scene::Scene::parse(&above, "box.toml").expect_err("refused");
    assert_eq!(err.field, "simulation.time_step.safety_factor");
    assert!(err.reason.contains("Eq. (10)") && err.reason.contains("allow_above_stability_bound"), "{}", err.reason);
    let negative = box_with_time_step(&["safety_factor=-1.0"]);
    assert_eq!(
        coil::scene::Scene::parse(&negative, "box.toml").expect_err("refused").field,
        "simulation.time_step.safety_factor"
    );
    let allowed = common::scene(&box_with_time_step(&["safety_factor=4.0", "allow_above_stability_bound=true"]));
    let initial = initial_particles(&allowed, "box.toml").expect("particles");
    let sim = CpuSimulation::<f64, _>::new(
        &allowed,
        &initial,
        StressModel(Newtonian { nu0: allowed.material.viscosity.nu0_m2_s }, KernelSum),
    );
    let (bound, _) = sim.run.stepper.bound.dt();
    let (dt, _) = sim.next_dt();
    assert!((dt - 4.0 * bound).abs() < 1e-12 * bound, "{dt} against 4 x {bound}");
}

/// The ETA counts the particles a jet will add: a run at 1e6 particle-steps/s, 1000 particles
/// and 1e-4 s steps with 0.5 s left takes 5 s as it stands, and 10 s if its fluid grows by
/// 4000 particles a simulated second with room for all of them (the mean count over what is
/// left is 2000), 7.1875 s if it fills at 1500 (0.125 s growing from 1000, then 0.375 s full).
#[test]
fn the_eta_counts_the_particles_a_jet_will_add() {
    use coil::run::progress::{estimate, short_duration, ProgressSample};
    let at = |wall_s: f64, time_s: f64, fluid_particles: usize| ProgressSample {
        wall_s,
        time_s,
        steps: (time_s / 1e-4).round() as u64,
        particle_steps: wall_s * 1e6,
        fluid_particles,
    };
    let eta = |first, last, capacity| estimate(&first, &last, 0.8, capacity).expect("an estimate").remaining_s;
    // 1e6 particle-steps/s at 1000 particles a step: 1000 steps a second, 0.1 simulated s.
    let steady = eta(at(10.0, 0.2, 1000), at(11.0, 0.3, 1000), 10_000);
    assert!((steady - 5.0).abs() < 1e-9, "{steady}");
    let growing = eta(at(10.0, 0.2, 600), at(11.0, 0.3, 1000), 10_000);
    assert!((growing - 10.0).abs() < 1e-9, "{growing}");
    let filling = eta(at(10.0, 0.2, 600), at(11.0, 0.3, 1000), 1500);
    assert!((filling - 7.1875).abs() < 1e-9, "{filling}");
    assert_eq!(estimate(&at(10.0, 0.2, 1000), &at(10.0, 0.2, 1000), 0.8, 1000), None);
    assert_eq!([short_duration(42.4), short_duration(185.0), short_duration(3725.0)], ["42s", "3m05s", "1h02m"]);
}

/// Where density is summed the inlet spaces its layers by a lattice cell, so the fluid in the
/// nozzle sums to rho0 and a pressure solve has nothing to release at the exit. Spaced by
/// m / rho0 (0.81 s^3 with the spiky kernel's calibrated mass) the nozzle's fluid summed to
/// 1.09 to 1.12 rho0 and the divergence-free solve kicked the layer below the exit from 1 to
/// 1.6 m/s: over this run (the first 0.1 s of the jet) the largest compression was 12 % and the
/// fastest particle ran at 1.76 m/s, where now they are 0 and 1.41 m/s (the front, falling from
/// 0.2 m).
#[test]
fn a_divergence_free_jet_leaves_the_nozzle_at_rest_density_and_speed() {
    let out = std::env::temp_dir().join(format!("coil-df-nozzle-{}", std::process::id()));
    let run = common::run_divergence_free_jet(
        &out,
        &["material.viscosity.implicit.tolerance=1e-2", "simulation.end_time_s=0.1", "output.every_s=0.1"],
    );
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let log: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).expect("run log")).expect("json");
    std::fs::remove_dir_all(&out).ok();
    let summary = &log["summary"];
    let (compression, speed) =
        (summary["max_compression"].as_f64().expect("compression"), summary["max_speed_m_s"].as_f64().expect("speed"));
    assert!(compression < 0.03, "largest compression {compression}");
    assert!(speed < 1.6, "fastest particle {speed} m/s");
}
