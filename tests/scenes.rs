//! Every shipped scene loads, validates and runs a few steps; bad input exits with code 2.

use coil::model::StressModel;
use coil::scene::Scene;
use coil::setup::initial_particles;
use coil::simulation::Simulation;
use coil_kernels::cross_viscosity::Newtonian;
use std::path::Path;
use std::process::Command;

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
    assert!(scenes.len() >= 2);
    for path in scenes {
        let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
        let initial = initial_particles(&scene, &path.display().to_string()).unwrap_or_else(|e| panic!("{e}"));
        let nu0 = scene.material.viscosity.nu0_m2_s;
        let mut sim = Simulation::<f32, _>::new(&scene, &initial, StressModel(Newtonian { nu0: nu0 as f32 }));
        for _ in 0..3 {
            sim.step().unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        }
        assert_eq!(sim.removed, 0, "{}", path.display());
    }
}

fn coil(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_coil")).args(args).output().expect("coil runs")
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
        ("cross_n = 1.0", "cross_nn = 1.0", "cross_nn"),
        ("particle_spacing_m = 0.02", "particle_spacing_m = 0.0", "material.particle_spacing_m"),
        (
            "max_m = [0.4, 0.4, 0.4]",
            "max_m = [0.4, 0.4, 0.4]\n[[fluid_block]]\nmin_m = [-0.1, 0.0, 0.0]\nmax_m = [0.0, 0.1, 0.1]",
            "fluid_block[1]",
        ),
    ];
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
    let missing = coil(&["run", dir.join("missing.toml").to_str().expect("utf-8")]);
    assert_eq!(missing.status.code(), Some(2));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_short_run_writes_a_frame_series() {
    let dir = std::env::temp_dir().join(format!("coil-run-{}", std::process::id()));
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dam_break.toml");
    let text = std::fs::read_to_string(scene)
        .expect("scene")
        .replace("end_time_s = 1.0", "end_time_s = 0.004")
        .replace("every_s = 0.02", "every_s = 0.002");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("short.toml");
    std::fs::write(&path, text).expect("write");
    let out = coil(&["run", path.to_str().expect("utf-8"), "--out", dir.join("out").to_str().expect("utf-8"), "--quiet"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let pvd = std::fs::read_to_string(dir.join("out/dam_break.pvd")).expect("series");
    assert_eq!(pvd.matches("<DataSet").count(), 3, "frames at t = 0, 0.002, 0.004 s: {pvd}");
    let frame = std::fs::read(dir.join("out/frame_000002.vtu")).expect("frame");
    let head = String::from_utf8_lossy(&frame[..frame.len().min(2000)]);
    assert!(head.contains("NumberOfPoints=\"8000\""), "{head}");
    assert!(!dir.join("out").read_dir().expect("out").any(|e| e.expect("entry").path().extension().is_some_and(|x| x == "tmp")));
    std::fs::remove_dir_all(&dir).ok();
}
