//! Every shipped scene loads, validates and runs a few steps; bad input exits with code 2.

use crate::common;

use coil::cpu::simulation::CpuSimulation;
use coil::scene::setup::initial_particles;
use coil::scene::Scene;
use coil::simulation::model::StressModel;
use coil_kernels::cross_viscosity::Newtonian;
use coil_kernels::velocity_gradient::KernelSum;
use common::coil;
use std::path::Path;

fn shipped_scenes() -> Vec<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut scenes: Vec<_> = std::fs::read_dir(dir).expect("scenes/").map(|e| e.expect("entry").path()).collect();
    scenes.retain(|p| p.extension().is_some_and(|e| e == "toml"));
    scenes.sort();
    scenes
}

#[test]
fn every_shipped_scene_loads_and_steps() {
    let scenes = shipped_scenes();
    assert!(scenes.len() >= 6);
    for path in scenes {
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        for v in &scene.variants {
            let sets: Vec<_> = v.set.iter().map(|s| coil::scene::overrides::Override::parse(s).expect(s)).collect();
            Scene::load_with(&path, &sets).unwrap_or_else(|e| panic!("variant {}: {e}", v.name));
        }
        let initial = initial_particles(&scene, &path.display().to_string()).unwrap_or_else(|e| panic!("{e}"));
        let nu0 = scene.material.viscosity.nu0_m2_s;
        let mut sim = CpuSimulation::<f32, _>::new(&scene, &initial, StressModel(Newtonian { nu0: nu0 as f32 }, KernelSum));
        for _ in 0..3 {
            sim.step().unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        }
        assert_eq!(sim.run.removed, 0, "{}", path.display());
    }
}

#[test]
fn bad_scenes_exit_2_naming_file_and_field() {
    let dir = std::env::temp_dir().join(format!("coil-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let good = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dam_break.toml")).expect("scene");
    let cases = [
        ("nu0_m2_s = 0.05", "nu0_m2_s = -0.05", "material.viscosity.nu0_m2_s"),
        ("nu_inf_m2_s = 0.005", "nu_inf_m2_s = 0.5", "material.viscosity.nu_inf_m2_s"),
        ("cross_n = 1.0", "cross_n = 0.0", "material.viscosity.cross_n"),
        ("cross_n = 1.0", "cross_nn = 1.0", "did you mean `cross_n`?"),
        ("nu0_m2_s = 0.05", "nu0_m2s = 0.05", "did you mean `nu0_m2_s`?"),
        ("cross_k_s = 1.0", "cross_k = 1.0", "did you mean `cross_k_s`?"),
        ("particle_spacing_m = 0.02", "particle_spacing_m = 0.0", "material.particle_spacing_m"),
        (
            "max_m = [0.4, 0.4, 0.4]",
            "max_m = [0.4, 0.4, 0.4]\n[[fluid_block]]\nmin_m = [-0.1, 0.0, 0.0]\nmax_m = [0.0, 0.1, 0.1]",
            "fluid_block[1]",
        ),
        ("end_time_s = 1.0", "end_time_s = 1.0\nmax_fluid_particles = 7999", "simulation.max_fluid_particles"),
        ("sound_speed_m_s = 20.0", "sound_speed_m_s = 0.0", "material.sound_speed_m_s"),
        ("nu0_m2_s = 0.05", "nu0_m2_s = 0.0", "material.viscosity.nu0_m2_s"),
        ("end_time_s = 1.0", "", "missing field `end_time_s`"),
        ("end_time_s = 1.0", "end_time_s = 1.0\nparticle_shifting = -2.0", "simulation.particle_shifting"),
        ("end_time_s = 1.0", "end_time_s = 1.0\nparticle_shifting = inf", "simulation.particle_shifting"),
        ("cross_n = 1.0", "cross_n = 1.0\nhourglass_control = -1.0", "material.viscosity.hourglass_control"),
        ("cross_n = 1.0", "cross_n = 1.0\nhourglass_control = 2.5", "material.viscosity.hourglass_control"),
        ("operator = \"stress\"", "operator = \"morris\"\nhourglass_control = 1.0", "material.viscosity.hourglass_control"),
        (
            "operator = \"stress\"",
            "operator = \"morris\"\nvelocity_gradient = \"renormalized\"",
            "material.viscosity.velocity_gradient",
        ),
        ("operator = \"stress\"", "operator = \"stress\"\nvelocity_gradient = \"bonet\"", "velocity_gradient"),
        ("operator = \"stress\"", "operator = \"stress\"\nsolver = \"implicit\"", "material.viscosity.solver"),
        (
            "operator = \"stress\"",
            "operator = \"stress\"\nvelocity_gradient = \"own_density\"\nsolver = \"implicit\"\nimplicit = { tolerance = 2.0 }",
            "material.viscosity.implicit.tolerance",
        ),
        (
            "operator = \"stress\"",
            "operator = \"stress\"\nvelocity_gradient = \"own_density\"\nsolver = \"implicit\"\nimplicit = { max_iterations = 0 }",
            "material.viscosity.implicit.max_iterations",
        ),
        (
            "operator = \"stress\"",
            "operator = \"stress\"\nvelocity_gradient = \"own_density\"\nsolver = \"implicit\"\nimplicit = { picard_iterations = 101 }",
            "material.viscosity.implicit.picard_iterations",
        ),
    ];
    // Müller's Laplacian takes a Newtonian fluid only, which the scene above is not.
    let laplacian = common::set(
        &common::box_scene(0.02, [0.2; 3], [0.1; 3], ""),
        &["material.viscosity.operator=\"laplacian\"", "material.viscosity.solver=\"implicit\""],
    );
    let error = Scene::parse(&laplacian, "laplacian.toml").expect_err("Müller's Laplacian is not solved implicitly");
    assert!(error.to_string().contains("material.viscosity.solver"), "{error}");
    for (k, (from, to, field)) in cases.iter().enumerate() {
        assert!(good.contains(from), "{from}");
        let path = dir.join(format!("bad{k}.toml"));
        std::fs::write(&path, good.replacen(from, to, 1)).expect("write");
        let out = coil(&["run", path.to_str().expect("utf-8"), "--out", dir.join("out").to_str().expect("utf-8"), "--quiet"]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "case {k}: {stderr}");
        assert!(stderr.contains(path.to_str().expect("utf-8")) && stderr.contains(field), "case {k}: {stderr}");
        assert!(!stderr.contains("panicked"), "case {k}: {stderr}");
    }
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dam_break.toml");
    let scene = scene.to_str().expect("utf-8");
    let solved = ["simulation.pressure=divergence_free", "material.density_equation=summation", "material.density_kernel=spiky"];
    let refused = [
        (&["material.density_equation=continuity", "material.density_diffusion=0.1"][..], "material.density_diffusion"),
        (
            &["simulation.walls=mirrored", "simulation.time_step.viscous_velocity=half_step"],
            "simulation.time_step.viscous_velocity",
        ),
        (&["material.density_kernel=poly6"], "material.density_kernel"),
        (&["simulation.divergence_free.relaxation=1.0"], "simulation.divergence_free.relaxation"),
        (&["simulation.divergence_free.relaxation=0"], "simulation.divergence_free.relaxation"),
        (&["simulation.divergence_free.chebyshev_radius=1"], "simulation.divergence_free.chebyshev_radius"),
        (&["simulation.divergence_free.chebyshev_radius=-0.5"], "simulation.divergence_free.chebyshev_radius"),
        (&["simulation.divergence_free.min_iterations=101"], "simulation.divergence_free.min_iterations"),
        (&["simulation.divergence_free.density_tolerance=0.5"], "simulation.divergence_free.density_tolerance"),
        (&["simulation.divergence_free.cfl_factor=1.5"], "simulation.divergence_free.cfl_factor"),
    ];
    for (sets, field) in refused {
        let mut args = vec!["check", scene];
        let all: Vec<&str> = solved.iter().chain(sets.iter()).copied().collect();
        for set in all {
            args.extend(["--set", set]);
        }
        let out = coil(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{sets:?}: {stderr}");
        assert!(stderr.contains("dam_break.toml") && stderr.contains(field), "{sets:?}: {stderr}");
    }
    let mut args = vec!["check", scene];
    for set in solved.iter().chain(&["material.density_equation=continuity", "material.density_diffusion=0"]) {
        args.extend(["--set", set]);
    }
    let out = coil(&args);
    assert_eq!(out.status.code(), Some(0), "the continuity density without diffusion: {}", String::from_utf8_lossy(&out.stderr));
    let missing = coil(&["run", dir.join("missing.toml").to_str().expect("utf-8")]);
    assert_eq!(missing.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).ok();
}

/// A second run into a folder holding an earlier one is refused, leaving it as it was; with
/// `--overwrite` the earlier run's files go (no stale frame past the new run's last survives,
/// nor the meshes, pictures and movie drawn from its frames) and the user's own files stay.
#[test]
fn an_earlier_run_is_kept_unless_overwrite_is_given() {
    let dir = std::env::temp_dir().join(format!("coil-overwrite-{}", std::process::id()));
    let out = dir.join("out");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dam_break.toml");
    let run = |end: &str, extra: &[&str]| {
        let mut args = vec!["run", scene.to_str().expect("utf-8"), "--out", out.to_str().expect("utf-8"), "--quiet"];
        args.extend(["--backend", "cpu", "--set", end, "--set", "output.every_s=0.002"]);
        args.extend(extra);
        coil(&args)
    };
    let first = run("simulation.end_time_s=0.004", &[]);
    assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
    std::fs::write(out.join("notes.txt"), "mine").expect("a file of the user's");
    let frame = std::fs::read(out.join("frame_000002.vtu")).expect("the first run's last frame");
    let again = run("simulation.end_time_s=0.002", &[]);
    let message = String::from_utf8_lossy(&again.stderr);
    assert_eq!(again.status.code(), Some(2), "{message}");
    assert!(message.contains("--out") && message.contains("earlier run") && message.contains("--overwrite"), "{message}");
    assert_eq!(std::fs::read(out.join("frame_000002.vtu")).expect("kept"), frame, "the refused run touched the folder");
    for derived in ["frame_000002.surface.ply", "frame_000002.render.png", "frame_000002.pov", "render.gif"] {
        std::fs::write(out.join(derived), "drawn from the earlier run").expect("written");
    }
    let replaced = run("simulation.end_time_s=0.002", &["--overwrite"]);
    assert!(replaced.status.success(), "{}", String::from_utf8_lossy(&replaced.stderr));
    assert!(!out.join("frame_000002.vtu").exists(), "a stale frame of the earlier run survived");
    for derived in ["frame_000002.surface.ply", "frame_000002.render.png", "frame_000002.pov", "render.gif"] {
        assert!(!out.join(derived).exists(), "{derived}, drawn from the earlier run, survived");
    }
    assert!(out.join("frame_000001.vtu").is_file());
    assert_eq!(std::fs::read_to_string(out.join("notes.txt")).expect("the user's file"), "mine");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_short_run_writes_a_frame_series() {
    let dir = std::env::temp_dir().join(format!("coil-run-{}", std::process::id()));
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dam_break.toml");
    let text =
        common::set(&std::fs::read_to_string(scene).expect("scene"), &["simulation.end_time_s=0.004", "output.every_s=0.002"]);
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("short.toml");
    std::fs::write(&path, text).expect("write");
    let out =
        coil(&["run", path.to_str().expect("utf-8"), "--out", dir.join("out").to_str().expect("utf-8"), "--quiet", "--preview"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for k in 0..3 {
        let png = std::fs::read(dir.join(format!("out/frame_{k:06}.png"))).expect("a preview per frame");
        assert_eq!(&png[1..4], b"PNG");
    }
    let shown = coil(&[
        "preview",
        dir.join("out").to_str().expect("utf-8"),
        "--view",
        "top",
        "--range",
        "0.005,0.05",
        "-o",
        dir.join("top.png").to_str().expect("utf-8"),
    ]);
    assert!(shown.status.success() && dir.join("top.png").is_file(), "{}", String::from_utf8_lossy(&shown.stderr));
    let reversed = coil(&["preview", dir.join("out").to_str().expect("utf-8"), "--range", "0.05,0.005"]);
    assert_eq!(reversed.status.code(), Some(2), "a range with MIN > MAX is refused");
    let log: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("out/run.json")).expect("run log")).expect("JSON");
    assert_eq!(log["status"], "completed");
    assert_eq!(log["backend"], "cpu");
    assert_eq!(log["summary"]["frames"], 3);
    // The logged scene is the run's scene with every default written out: it reproduces the run.
    let logged: Scene = serde_json::from_value(log["scene"].clone()).expect("a scene");
    let mut expected = Scene::load(&path).expect("valid");
    expected.material.viscosity.nu_inf_m2_s = Some(expected.material.viscosity.nu_inf());
    assert_eq!(logged, expected);
    // `coil run run.json` repeats the run bit for bit.
    let again = dir.join("again");
    let rerun =
        coil(&["run", dir.join("out/run.json").to_str().expect("utf-8"), "--out", again.to_str().expect("utf-8"), "--quiet"]);
    assert!(rerun.status.success(), "{}", String::from_utf8_lossy(&rerun.stderr));
    assert_eq!(
        std::fs::read(again.join("frame_000002.vtu")).expect("rerun frame"),
        std::fs::read(dir.join("out/frame_000002.vtu")).expect("frame")
    );
    let pvd = std::fs::read_to_string(dir.join("out/dam_break.pvd")).expect("series");
    assert_eq!(pvd.matches("<DataSet").count(), 3, "frames at t = 0, 0.002, 0.004 s: {pvd}");
    let frame = std::fs::read(dir.join("out/frame_000002.vtu")).expect("frame");
    let head = String::from_utf8_lossy(&frame[..frame.len().min(2000)]);
    assert!(head.contains("NumberOfPoints=\"8000\""), "{head}");
    assert!(!dir.join("out").read_dir().expect("out").any(|e| e.expect("entry").path().extension().is_some_and(|x| x == "tmp")));
    std::fs::remove_dir_all(&dir).ok();
}

/// The shipped round jet's TOML.
fn round_jet_text() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/round_jet.toml")).expect("scene")
}

/// The error of the shipped round jet, parsed as `jet.toml`, with its first `from` replaced by
/// `to`.
fn round_jet_edited(from: &str, to: &str) -> coil::scene::SceneError {
    let good = round_jet_text();
    assert!(good.contains(from), "{from}");
    Scene::parse(&good.replacen(from, to, 1), "jet.toml").expect_err(to)
}

/// Each `(from, to, field, reason)` edit of the round jet is refused in `jet.toml`, naming
/// `field`, with `reason` in the message.
fn round_jet_edits_are_refused(cases: &[(&str, &str, &str, &str)]) {
    for &(from, to, field, reason) in cases {
        let e = round_jet_edited(from, to);
        assert!(e.file == "jet.toml" && e.field == field && e.reason.contains(reason), "{to}: {e}");
    }
}

#[test]
fn a_nozzle_wobbling_a_spacing_or_a_tube_outside_the_domain_is_refused() {
    let cases = [
        ("wobble_m = 0.001", "wobble_m = 0.004", "inlet[0].wobble_m", "below the particle spacing"),
        ("wobble_m = 0.001", "wobble_m = -0.001", "inlet[0].wobble_m", "at least 0"),
        // The exit is inside the domain (top at 0.23 m) but the tube, h = 0.008 m long, is not.
        ("position_m = [0.0, 0.2, 0.0]", "position_m = [0.0, 0.225, 0.0]", "inlet[0].position_m", "tube"),
        ("position_m = [0.0, 0.2, 0.0]", "position_m = [0.5, 0.2, 0.0]", "inlet[0].position_m", "outside the domain"),
    ];
    round_jet_edits_are_refused(&cases);
    // Below a radius of one spacing (4 mm) the section holds one lattice point, and rho0 A U
    // puts the layers 1 / (pi (r/s)^2) spacings apart: 0.8 at 2.5 mm, 0.41 at 3.5 mm, 504 at
    // 0.1 mm. A jet is refused outside 0.5 to 2.
    let good = round_jet_text();
    for (radius, apart) in
        [("0.0025", None), ("0.0035", Some("0.41 spacings")), ("0.0001", Some("504.37 spacings")), ("0.004", None)]
    {
        let text = common::set(&good, &[&format!("inlet[0].nozzle.radius_m={radius}")]);
        let scene = Scene::parse(&text, "jet.toml").expect("a positive radius parses");
        match (initial_particles(&scene, "jet.toml"), apart) {
            (Ok(_), None) => {}
            (Err(e), Some(apart)) => assert!(e.field == "inlet[0].nozzle" && e.reason.contains(apart), "{radius}: {e}"),
            (result, _) => panic!("radius {radius} m: {:?}", result.err()),
        }
    }
}

#[test]
fn a_plate_of_no_extent_or_at_no_height_is_refused() {
    let cases = [
        ("height_m = 0.0", "height_m = inf", "boundary[0].height_m", "finite"),
        ("height_m = 0.0", "height_m = 0.0\nmin_xz_m = [0.05, 0.0]\nmax_xz_m = [-0.05, 0.01]", "boundary[0].max_xz_m", "along x"),
        ("height_m = 0.0", "height_m = 0.0\nmax_xz_m = [0.05, -0.08]", "boundary[0].max_xz_m", "along z"),
    ];
    round_jet_edits_are_refused(&cases);
}

/// A capacity or a shape too large for the machine is refused before anything is allocated,
/// with the numbers: the ids limit is the same everywhere; the memory limit is that of a 1 GiB
/// machine, on which the f32 round jet's 124 + 56 + 192 bytes a particle (arrays, setup and
/// grid, and the CPU backend's neighbor list) allow 2.9e6 particles.
#[test]
fn a_run_too_large_for_the_machine_is_refused_before_it_allocates() {
    use coil::scene::particle_limit::ParticleLimit;
    use coil::scene::setup::initial_particles_within;
    let scene = Scene::parse(&round_jet_text(), "jet.toml").expect("round jet");
    let huge = |capacity: usize| {
        let mut s = scene.clone();
        s.simulation.max_fluid_particles = Some(capacity);
        s
    };
    let e = initial_particles_within(&huge(5_000_000_000), "jet.toml", &ParticleLimit::with_memory(&scene, None))
        .expect_err("beyond 32-bit ids");
    assert!(e.field == "simulation.max_fluid_particles" && e.reason.contains("32-bit"), "{e}");

    let gib = ParticleLimit::with_memory(&scene, Some(1 << 30));
    assert!((gib.most - (1u64 << 30) as f64 / 372.0).abs() < 1.0, "{gib:?}");
    initial_particles_within(&huge(2_800_000), "jet.toml", &gib).expect("2.8e6 particles fit 1 GiB");
    let e = initial_particles_within(&huge(3_000_000), "jet.toml", &gib).expect_err("3.0e6 do not");
    assert!(e.field == "simulation.max_fluid_particles" && e.reason.contains("1.0 GiB"), "{e}");

    let mut block = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dam_break.toml")).expect("scene");
    block = common::set(&block, &["material.particle_spacing_m=0.002"]);
    let fine = Scene::parse(&block, "dam.toml").expect("8e6 particles at 2 mm");
    let e = initial_particles_within(&fine, "dam.toml", &ParticleLimit::with_memory(&fine, Some(1 << 30)))
        .expect_err("a 0.4 m cube at 2 mm holds 8e6 particles");
    assert!(e.field == "fluid_block[0]" && e.reason.contains("8.000e6") && e.reason.contains("particle_spacing_m"), "{e}");
}

/// Mistakes serde finds by position (an unknown field, a wrong type, an unknown variant, a
/// missing field) name the field as `--set` spells it, with the line; broken TOML is a syntax
/// error at its line.
#[test]
fn a_mistyped_field_is_named_as_set_spells_it() {
    let cases = [
        ("sound_speed_m_s = ", "sound_speed_ms = ", "material.sound_speed_ms", "unknown field"),
        ("precision = \"f32\"", "precision = \"f16\"", "simulation.precision", "unknown variant `f16`"),
        ("speed_m_s = 1.0", "speed_m_s = \"fast\"", "inlet[0].speed_m_s", "expected f64"),
        ("shape = \"circle\"", "shape = \"hexagon\"", "inlet[0].nozzle.shape", "unknown variant `hexagon`"),
        ("particle_spacing_m = 0.004\n", "", "material.particle_spacing_m", "missing field `particle_spacing_m`"),
        ("[simulation]", "[simulation", "(syntax)", "table header"),
    ];
    for (from, to, field, reason) in cases {
        let e = round_jet_edited(from, to);
        assert!(
            e.file == "jet.toml" && e.field == field && e.reason.contains(reason) && e.reason.contains("(at line"),
            "{to}: {e}"
        );
    }
}

/// A period written in decimal as exactly 3 h (0.0003 m for h = 2 x 5e-5 m) is 3 h less a
/// rounding in binary; it is accepted and split into 3 cells. A period a spacing short is not.
#[test]
fn a_period_of_three_support_radii_written_in_decimal_is_accepted() {
    use coil::simulation::sorted_grid::SortedGrid;
    let text = |length: &str| {
        format!(
            "name = \"channel\"\n[material]\nparticle_spacing_m = 5e-5\n[material.viscosity]\nnu0_m2_s = 1e-6\n\
             [domain]\nmin_m = [0.0, 0.0, 0.0]\nmax_m = [{length}, 0.001, {length}]\nperiodic = [true, false, true]\n\
             [simulation]\nend_time_s = 0.1\n[[fluid_block]]\nmin_m = [0.0, 0.0, 0.0]\nmax_m = [{length}, 0.001, {length}]\n"
        )
    };
    #[allow(clippy::assertions_on_constants, reason = "the premise is about binary rounding, checked at compile time")]
    const {
        assert!(0.0003 < 3.0 * (5e-5 * 2.0), "the decimal period is below 3 h in binary")
    };
    let scene = Scene::parse(&text("0.0003"), "channel.toml").expect("a period of 3 h is valid");
    let d = &scene.domain;
    let grid = SortedGrid::new(d.min_m, d.max_m, scene.support_radius(), d.periodic);
    assert_eq!((grid.grid.dims[0], grid.grid.dims[2]), (3, 3));
    let e = Scene::parse(&text("0.00025"), "channel.toml").expect_err("5 spacings is 2.5 h");
    assert!(e.field == "domain.periodic" && e.reason.contains("less than 3 support radii"), "{e}");
}

#[test]
fn set_overrides_any_field_with_the_files_validation() {
    use coil::scene::overrides::Override;
    let jet = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/round_jet.toml");
    let sets = |given: &[&str]| given.iter().map(|g| Override::parse(g).expect(g)).collect::<Vec<_>>();
    let scene = Scene::load_with(
        &jet,
        &sets(&[
            "material.viscosity.cross_k_s=10",
            "inlet[0].speed_m_s = 0.5",
            "simulation.precision=f64",
            "output.every_steps=7",
        ]),
    )
    .expect("valid overrides");
    assert_eq!(scene.material.viscosity.cross_k_s, 10.0);
    assert_eq!(scene.inlets[0].speed_m_s, 0.5);
    assert_eq!(scene.simulation.precision, coil::scene::Precision::F64);
    assert_eq!(scene.output.every_steps, Some(7));
    let untouched = Scene::load(&jet).expect("valid");
    assert_eq!(scene.material.particle_spacing_m, untouched.material.particle_spacing_m);

    // The same checks as the file: a bad value, a misspelled field, a missing list entry.
    let cases: [(&str, &str); 4] = [
        ("material.viscosity.nu0_m2_s=-1", "material.viscosity.nu0_m2_s"),
        ("material.viscosity.cross_kk=1", "cross_kk"),
        ("inlet[3].speed_m_s=1", "inlet[3].speed_m_s"),
        ("material.sound_speed_m_s", "material.sound_speed_m_s"),
    ];
    for (given, field) in cases {
        let e = Override::parse(given).and_then(|o| Scene::load_with(&jet, &[o])).expect_err(given);
        assert!(e.to_string().contains(field), "{given}: {e}");
    }
    let out = coil(&["run", jet.to_str().expect("utf-8"), "--set", "material.particle_spacing_m=0", "--quiet"]);
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn check_reports_counts_the_equation_10_bound_and_a_calibrated_estimate() {
    use coil::check::check;
    use coil::time_step::Limit;
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let dam = Scene::load(&dir.join("dam_break.toml")).expect("valid");
    let r = check(&dam, "dam_break.toml", None, std::time::Duration::from_millis(200)).expect("valid");
    assert_eq!((r.initial_fluid, r.inlet_rate), (8000, 0.0));
    // h = 0.04 m, c = 20 m/s, nu0 = 0.05 m^2/s: 0.1 h/c = 2e-4 s below 0.1 h^2/(8 nu0) = 4e-4 s.
    assert!((r.dt_s - 2e-4).abs() < 1e-15 && r.limit == Limit::Acoustic, "{r}");
    assert_eq!(r.steps, (dam.simulation.end_time_s / 2e-4).ceil());
    assert_eq!(r.particle_steps, r.steps * (8000 + r.boundary) as f64);
    // At least two steps whatever the machine's load; how many fit in the 200 ms depends on it.
    assert!(r.seconds_per_particle_step > 0.0 && r.calibration_steps >= 2);
    assert!((r.estimated_wall_s - r.particle_steps * r.seconds_per_particle_step).abs() < 1e-9);

    // The jet: no fluid at t = 0; the inlet delivers rho0 A U / m particles per second.
    let jet = Scene::load(&dir.join("round_jet.toml")).expect("valid");
    let r = check(&jet, "round_jet.toml", None, std::time::Duration::from_millis(200)).expect("valid");
    let mass = coil::scene::setup::calibrated_mass(1000.0, 0.004, 0.008, coil::scene::DensityKernelKind::Poly6);
    let rate = 1000.0 * std::f64::consts::PI * 0.01 * 0.01 * 1.0 / mass;
    assert!(r.initial_fluid == 0 && (r.inlet_rate - rate).abs() < 1e-9 * rate, "{} vs {rate}", r.inlet_rate);
    assert_eq!(r.final_fluid, ((rate * 0.8) as usize).min(4200));
    assert!(r.limit == Limit::Viscous && (r.dt_s - 8e-6).abs() < 1e-18, "{r}");
    // U = 1 m/s from the nozzle, and free fall through the domain's 0.25 m height at 9.8 m/s^2.
    let fastest = (1.0f64 + 2.0 * 9.8 * 0.25).sqrt();
    let (speed, mach) = (r.speed_bound_m_s.expect("no periodic axis"), r.mach_bound.expect("no periodic axis"));
    assert!((speed - fastest).abs() < 1e-12 && (mach - fastest / 20.0).abs() < 1e-12, "{r}");
    assert!(!r.to_string().contains("warning"), "{r}");
    // The paper's c = sqrt(1.5) m/s puts it at Mach 2.
    let mut paper = jet.clone();
    paper.material.sound_speed_m_s = 1.5f64.sqrt();
    let r = check(&paper, "round_jet.toml", None, std::time::Duration::ZERO).expect("valid");
    assert!(r.mach_bound > Some(1.9) && r.to_string().contains("warning            above Mach 1"), "{r}");
    // Viscosity solved implicitly: sound bounds dt, 0.1 h / c = 0.1 * 0.008 / 20 = 4e-5 s.
    let mut implicit = jet.clone();
    implicit.material.viscosity.solver = coil::scene::ViscositySolver::Implicit;
    implicit.material.viscosity.velocity_gradient = coil::scene::VelocityGradient::OwnDensity;
    let r = check(&implicit, "round_jet.toml", None, std::time::Duration::ZERO).expect("valid");
    assert!(r.limit == Limit::Acoustic && (r.dt_s - 4e-5).abs() < 1e-18, "{r}");
    assert!(r.to_string().contains("viscous: none (solved implicitly)"), "{r}");
    // Pressure solved too: the CFL step at the fastest speed the jet can reach,
    // 0.2 s / |v| = 0.2 * 0.004 / 2.43 m/s.
    let mut solved = implicit.clone();
    solved.simulation.pressure = coil::scene::Pressure::DivergenceFree;
    solved.material.density_equation = coil::scene::DensityEquation::Summation;
    solved.material.density_kernel = coil::scene::DensityKernelKind::Spiky;
    let r = check(&solved, "round_jet.toml", None, std::time::Duration::ZERO).expect("valid");
    assert!(r.limit == Limit::Cfl && (r.dt_s - 0.2 * 0.004 / fastest).abs() < 1e-15, "{r}");
    assert!(r.to_string().contains("Eq. (10) bound     none: acoustic: none (pressure solved)"), "{r}");
    // A channel driven along its periodic axis has no height to fall through.
    let channel = Scene::parse(
        "name = \"channel\"\n[material]\nparticle_spacing_m = 0.001\ngravity_m_s2 = [1e-3, 0.0, 0.0]\n\
         [material.viscosity]\nnu0_m2_s = 1e-6\n[domain]\nmin_m = [0.0, 0.0, 0.0]\nmax_m = [0.01, 0.01, 0.01]\n\
         periodic = [true, false, true]\n[simulation]\nend_time_s = 0.01\n[[fluid_block]]\nmin_m = [0.0, 0.0, 0.0]\n\
         max_m = [0.01, 0.005, 0.01]\n",
        "channel.toml",
    )
    .expect("a periodic channel");
    let r = check(&channel, "channel.toml", None, std::time::Duration::ZERO).expect("valid");
    assert!(r.speed_bound_m_s.is_none() && r.to_string().contains("bounded only by viscosity"), "{r}");
}

#[test]
fn an_output_folder_that_cannot_be_created_exits_2_naming_it() {
    // A folder inside a regular file cannot be created, even by root.
    let file = std::env::temp_dir().join(format!("coil-not-a-dir-{}", std::process::id()));
    std::fs::write(&file, b"").expect("temp file");
    let out_dir = file.join("out");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dam_break.toml");
    let out = coil(&["run", scene.to_str().expect("utf-8"), "--quiet", "--out", out_dir.to_str().expect("utf-8")]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--out") && stderr.contains(out_dir.to_str().expect("utf-8")) && !stderr.contains("panicked"),
        "{stderr}"
    );
    std::fs::remove_file(&file).ok();
}

/// `coil scenes` prints each variant's command as `coil run SCENE --variant NAME`, and such a
/// run writes to an output folder of its own, named after the scene and the variant, so that
/// running one variant after another is not refused.
#[test]
fn coil_scenes_gives_each_variant_its_own_output_folder() {
    let out = common::coil(&["scenes", concat!(env!("CARGO_MANIFEST_DIR"), "/scenes")]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let printed = String::from_utf8_lossy(&out.stdout);
    let runs: Vec<&str> = printed.lines().map(str::trim_start).filter(|l| l.starts_with("coil run ")).collect();
    let variants: Vec<&str> = runs.iter().filter_map(|l| l.split(" --variant ").nth(1)).collect();
    assert_eq!(variants.len(), runs.len(), "{printed}");
    let jet = concat!("coil run ", env!("CARGO_MANIFEST_DIR"), "/scenes/newtonian_jet.toml --variant divergence_free");
    assert!(runs.contains(&jet), "{printed}");
    let dir = std::env::temp_dir().join(format!("coil-variants-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temporary folder");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/newtonian_jet.toml");
    let short = ["--set", "simulation.end_time_s=0.002", "--set", "output.every_s=0.002", "--quiet"];
    for variant in ["paper", "divergence_free"] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_coil"))
            .args(["run", scene, "--variant", variant])
            .args(short)
            .current_dir(&dir)
            .output()
            .expect("coil runs");
        assert!(out.status.success(), "{variant}: {}", String::from_utf8_lossy(&out.stderr));
        let log = dir.join(format!("out/newtonian_jet-{variant}/run.json"));
        let text = std::fs::read_to_string(&log).unwrap_or_else(|e| panic!("{}: {e}", log.display()));
        let overrides = text.split("\"overrides\"").nth(1).and_then(|t| t.split(']').next()).expect("overrides logged");
        assert!(overrides.contains("simulation.particle_shifting=0") == (variant == "paper"), "{variant}: {overrides}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// An unknown `--variant` is bad input: exit 2, naming the scene file, the variant and the
/// variants the scene has.
#[test]
fn an_unknown_variant_is_refused_naming_the_ones_there_are() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/newtonian_jet.toml");
    for command in ["run", "check"] {
        let out = common::coil(&[command, scene, "--variant", "papr"]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{command}: {stderr}");
        assert!(
            stderr.contains("newtonian_jet.toml") && stderr.contains("--variant papr") && stderr.contains("laplacian, paper"),
            "{command}: {stderr}"
        );
    }
}

/// `coil scenes | head -1`: once the reader of stdout has gone, coil ends as Unix filters do
/// (by SIGPIPE), never with a panic. The read end is closed before coil starts, so its first
/// line meets the closed pipe every time.
#[cfg(unix)]
#[test]
fn a_closed_stdout_pipe_ends_coil_without_a_panic() {
    use std::os::unix::process::ExitStatusExt;
    let (reader, writer) = std::io::pipe().expect("pipe");
    drop(reader);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_coil"))
        .args(["scenes", "scenes"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(writer)
        .output()
        .expect("coil runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.signal(), Some(libc::SIGPIPE), "{:?}: {stderr}", out.status);
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// Asking for a GPU where there is none (no `cuda` feature in this build, or no driver) is a
/// clear error with exit code 2, never a panic; `auto` falls back to the CPU and says why.
#[test]
fn backend_cuda_without_a_device_exits_2_and_auto_falls_back_to_the_cpu() {
    let out = std::env::temp_dir().join(format!("coil_backend_{}", std::process::id()));
    let out_arg = out.display().to_string();
    let common = ["scenes/dam_break.toml", "--out", &out_arg, "--set", "simulation.end_time_s=0.0005"];
    let cuda = coil(&[&["run", "--backend", "cuda"], &common[..]].concat());
    let stderr = String::from_utf8_lossy(&cuda.stderr);
    if cuda.status.success() {
        println!("skipped: a CUDA device is present");
        return;
    }
    assert_eq!(cuda.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--backend cuda:") && !stderr.contains("panicked"), "{stderr}");
    let auto = coil(&[&["run", "--backend", "auto"], &common[..]].concat());
    let stderr = String::from_utf8_lossy(&auto.stderr);
    assert!(auto.status.success(), "{stderr}");
    assert!(stderr.contains("backend: cpu ("), "auto must say it chose the CPU and why: {stderr}");
    std::fs::remove_dir_all(&out).ok();
}

/// Each wall particle's mirror image lies inside the walls, and the midpoint of the two is the
/// nearest point of the wall surface: a face, an edge or a corner of a box, or a plate's top.
#[test]
fn wall_particles_mirror_through_the_nearest_point_of_their_wall() {
    let box_m = [0.2, 0.3, 0.16];
    let text = common::box_scene(0.02, box_m, [0.1, 0.1, 0.1], "");
    let p = coil::scene::setup::initial_particles(&common::scene(&text), "test.toml").expect("valid");
    assert_eq!(p.boundary.len(), p.boundary_mirror.len());
    for (x, m) in p.boundary.iter().zip(&p.boundary_mirror) {
        let surface = [0, 1, 2].map(|a| x[a].clamp(0.0, box_m[a]));
        for a in 0..3 {
            assert!((0.5 * (x[a] + m[a]) - surface[a]).abs() < 1e-12, "{x:?} mirrors to {m:?}");
            assert!(m[a] > 0.0 && m[a] < box_m[a], "{x:?} mirrors to {m:?}, outside the box");
        }
    }
    let plate = r#"
name = "plate"
[material]
particle_spacing_m = 0.02
[material.viscosity]
nu0_m2_s = 0.01
[domain]
min_m = [0.0, -0.1, 0.0]
max_m = [0.2, 0.3, 0.2]
[simulation]
end_time_s = 1.0
[[boundary]]
shape = "plate"
height_m = 0.0
min_xz_m = [0.04, 0.04]
max_xz_m = [0.16, 0.16]
[[fluid_block]]
min_m = [0.06, 0.0, 0.06]
max_m = [0.14, 0.08, 0.14]
"#;
    let p = coil::scene::setup::initial_particles(&common::scene(plate), "test.toml").expect("valid");
    assert!(!p.boundary.is_empty());
    for (x, m) in p.boundary.iter().zip(&p.boundary_mirror) {
        assert!(x[1] < 0.0 && (m[1] + x[1]).abs() < 1e-12, "{x:?} mirrors to {m:?}");
        assert!((m[0] - x[0]).abs() < 1e-12 && (m[2] - x[2]).abs() < 1e-12, "{x:?} mirrors to {m:?}");
    }
}

/// A `[[fluid_cylinder]]` fills its volume pi r^2 h with lattice particles (to within the
/// lattice's staircase at the rim, a few percent at 10 across the radius); a bad one is named.
#[test]
fn a_fluid_cylinder_fills_its_volume_and_a_bad_one_is_named() {
    let torus = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/torus.toml")).expect("scene");
    let ring = "[[fluid_torus]]\ncentre_m = [0.0, 0.08, 0.0]\nmajor_radius_m = 0.2\nminor_radius_m = 0.08\n";
    assert!(torus.contains(ring));
    let cylinder = "[[fluid_cylinder]]\nbase_centre_m = [0.0, 0.0, 0.0]\nradius_m = 0.2\nheight_m = 0.1\n";
    let scene = Scene::parse(&torus.replacen(ring, cylinder, 1), "cylinder.toml").expect("valid");
    let fluid = coil::scene::setup::initial_particles(&scene, "cylinder.toml").expect("fills").fluid.len();
    let expected = std::f64::consts::PI * 0.2 * 0.2 * 0.1 / 0.02f64.powi(3);
    assert!((fluid as f64 / expected - 1.0).abs() < 0.05, "{fluid} particles against {expected:.0}");
    let cases = [
        ("radius_m = 0.2", "radius_m = 0.0", "fluid_cylinder[0].radius_m"),
        ("height_m = 0.1", "height_m = -0.1", "fluid_cylinder[0].height_m"),
        ("radius_m = 0.2", "radius_m = 0.5", "fluid_cylinder[0]"),
    ];
    for (from, to, field) in cases {
        let e = Scene::parse(&torus.replacen(ring, &cylinder.replacen(from, to, 1), 1), "cylinder.toml").expect_err(to);
        assert!(e.file == "cylinder.toml" && e.field == field, "{to}: {e}");
    }
}

/// A checkpoint resumes only the scene whose fingerprint it holds, a hash of the resolved scene
/// with its time step at the default: that default must serialise as it did before
/// `viscous_velocity` existed, or every checkpoint taken before would be refused.
#[test]
fn the_default_time_step_serialises_as_before_viscous_velocity_existed() {
    use coil::scene::{TimeStep, ViscousVelocity};
    let json = serde_json::to_string(&TimeStep::default()).expect("serialises");
    assert_eq!(json, r#"{"safety_factor":1.0,"fixed_s":null,"allow_above_stability_bound":false}"#);
    let half = TimeStep { viscous_velocity: ViscousVelocity::HalfStep, ..TimeStep::default() };
    let json = serde_json::to_string(&half).expect("serialises");
    assert!(json.contains(r#""viscous_velocity":"half_step""#), "{json}");
}

/// Every field of a scene either fixes its physics (and so its checkpoints' fingerprint), may
/// change on resume, or only describes the run: a field added to the scene must be put in one.
#[test]
fn every_scene_field_is_physics_resumable_or_description() {
    use coil::run::fields::{PHYSICS, RESUMABLE};
    const DESCRIPTION: [&str; 4] = ["name", "description", "notes", "variant"];
    fn leaves(value: &serde_json::Value, path: String, out: &mut Vec<String>) {
        match value {
            serde_json::Value::Object(map) => {
                for (key, v) in map {
                    leaves(v, if path.is_empty() { key.clone() } else { format!("{path}.{key}") }, out);
                }
            }
            _ => out.push(path),
        }
    }
    let covers = |list: &[&str], field: &str| list.iter().any(|f| field == *f || field.starts_with(&format!("{f}.")));
    for entry in std::fs::read_dir("scenes").expect("scenes/") {
        let path = entry.expect("an entry").path();
        let scene = Scene::load(&path).expect("a shipped scene loads");
        // Each variant too, with every field of the solvers' sections written out.
        let solver_sections = [
            "simulation.divergence_free={ chebyshev_radius = 0.5, wall_pressure = \"mirrored\" }",
            "material.viscosity.implicit={ picard_iterations = 1 }",
        ];
        let variants = scene.variants.iter().map(|v| v.set.iter().map(String::as_str).chain(solver_sections).collect::<Vec<_>>());
        for set in std::iter::once(Vec::new()).chain(variants) {
            let overrides: Vec<_> =
                set.iter().map(|o| coil::scene::overrides::Override::parse(o).expect("an override")).collect();
            let scene = Scene::load_with(&path, &overrides).expect("a shipped variant loads");
            let mut fields = Vec::new();
            leaves(&serde_json::to_value(coil::run::run_log::resolved(&scene)).expect("serialises"), String::new(), &mut fields);
            for field in fields {
                let kinds = [covers(&PHYSICS, &field), covers(&RESUMABLE, &field), covers(&DESCRIPTION, &field)];
                assert_eq!(kinds.iter().filter(|&&k| k).count(), 1, "{} {set:?}: {field} is in {kinds:?}", path.display());
            }
        }
    }
}

#[test]
fn the_fingerprint_follows_physics_and_ignores_the_rest() {
    use coil::run::fields::fingerprint;
    let scene = Scene::load(std::path::Path::new("scenes/round_jet.toml")).expect("loads");
    let base = fingerprint(&scene);
    let mut renamed = scene.clone();
    renamed.name = "another".into();
    renamed.description = "told otherwise".into();
    renamed.output.every_s = Some(0.5);
    renamed.simulation.end_time_s *= 2.0;
    assert_eq!(fingerprint(&renamed), base);
    let mut thicker = scene.clone();
    thicker.material.viscosity.nu0_m2_s *= 1.5;
    assert_ne!(fingerprint(&thicker), base);
    let mut moved = scene.clone();
    moved.inlets[0].position_m[0] += 0.001;
    assert_ne!(fingerprint(&moved), base);
}

/// An implicit viscosity solve held below its tolerance stops the run with exit 3 and a
/// diagnosis naming what to change; told to go on, the run finishes and counts such steps.
#[test]
fn an_unconverged_implicit_solve_stops_the_run_or_is_counted() {
    let dir = std::env::temp_dir().join(format!("coil-unconverged-{}", std::process::id()));
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/newtonian_jet.toml");
    let run = |on: &str, out: &str| {
        coil(&[
            "run",
            scene.to_str().expect("utf-8"),
            "--out",
            dir.join(out).to_str().expect("utf-8"),
            "--quiet",
            "--set",
            "simulation.end_time_s=0.01",
            "--set",
            "material.viscosity.solver=implicit",
            "--set",
            "material.viscosity.velocity_gradient=own_density",
            "--set",
            "material.viscosity.implicit={ tolerance = 1e-6, max_iterations = 1 }",
            "--set",
            &format!("material.viscosity.implicit.on_no_convergence={on}"),
        ])
    };
    let stopped = run("stop", "stopped");
    let stderr = String::from_utf8_lossy(&stopped.stderr);
    assert_eq!(stopped.status.code(), Some(3), "{stderr}");
    assert!(stderr.contains("did not converge") && stderr.contains("material.viscosity.implicit.max_iterations"), "{stderr}");
    assert!(dir.join("stopped/frame_000000.vtu").is_file(), "the first frame is kept");
    let warned = run("warn", "warned");
    let stdout = String::from_utf8_lossy(&warned.stdout);
    assert!(warned.status.success(), "{}", String::from_utf8_lossy(&warned.stderr));
    let line = stdout.lines().find(|l| l.starts_with("implicit viscosity")).expect("the summary's solve line");
    assert!(line.contains("1 at most") && !line.contains(" 0 step(s) unconverged"), "{line}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `simulation.refinement = 2` on the round jet: half the spacing (10 particles across D), eight
/// times the capacity, so the inlets stall at the same time, and half the wobble; the resolved
/// scene holds those values and no factor, so it loads as the same scene again. Out of range or
/// not a number, it is refused, naming the field.
#[test]
fn refinement_scales_spacing_capacity_and_wobble_once() {
    use coil::scene::overrides::Override;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/round_jet.toml");
    let base = Scene::load(&path).expect("shipped");
    let refined = Scene::load_with(&path, &[Override::parse("simulation.refinement=2").expect("an override")]).expect("valid");
    assert_eq!(refined.material.particle_spacing_m, 0.5 * base.material.particle_spacing_m);
    assert_eq!(refined.simulation.max_fluid_particles, base.simulation.max_fluid_particles.map(|c| 8 * c));
    assert_eq!(refined.inlets[0].wobble_m, 0.5 * base.inlets[0].wobble_m);
    assert_eq!(refined.simulation.refinement, 1.0);
    let resolved = toml::to_string(&refined).expect("serializes");
    assert!(!resolved.contains("refinement"), "{resolved}");
    assert_eq!(Scene::parse(&resolved, "run.json").expect("valid"), refined);
    for bad in ["9", "0", "nan"] {
        let e = Scene::load_with(&path, &[Override::parse(&format!("simulation.refinement={bad}")).expect("an override")])
            .expect_err("refused");
        assert_eq!(e.field, "simulation.refinement", "{bad}: {e}");
    }
}
