//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod carried;

use coil::scene::overrides::Override;
use coil::scene::Scene;
use std::process::{Command, Output};

/// A scene from TOML text, validated like a file.
pub fn scene(text: &str) -> Scene {
    Scene::parse(text, "test.toml").unwrap_or_else(|e| panic!("test scene invalid: {e}"))
}

/// `text` with `--set` overrides applied in order, by the code that applies the user's: each
/// names its field, so a template that changes makes a test fail, never edits nothing.
pub fn set(text: &str, overrides: &[&str]) -> String {
    let overrides: Vec<Override> = overrides.iter().map(|o| Override::parse(o).expect("a key=value override")).collect();
    coil::scene::overrides::apply(text, "test.toml", &overrides).unwrap_or_else(|e| panic!("override refused: {e}"))
}

/// A closed box of interior `box_m` (from the origin) holding a block of fluid of `fluid_m`.
pub fn box_scene(spacing: f64, box_m: [f64; 3], fluid_m: [f64; 3], extra: &str) -> String {
    let pad = 5.0 * spacing;
    format!(
        r#"
name = "test"
[material]
clamp_negative_pressure = true
particle_spacing_m = {spacing}
sound_speed_m_s = 20.0
gravity_m_s2 = [0.0, 0.0, 0.0]
[material.viscosity]
nu0_m2_s = 0.01
[domain]
min_m = [{m}, {m}, {m}]
max_m = [{x}, {y}, {z}]
[simulation]
end_time_s = 1.0
precision = "f64"
[[boundary]]
shape = "box"
min_m = [0.0, 0.0, 0.0]
max_m = [{bx}, {by}, {bz}]
[[fluid_block]]
min_m = [0.0, 0.0, 0.0]
max_m = [{fx}, {fy}, {fz}]
{extra}
"#,
        m = -pad,
        x = box_m[0] + pad,
        y = box_m[1] + pad,
        z = box_m[2] + pad,
        bx = box_m[0],
        by = box_m[1],
        bz = box_m[2],
        fx = fluid_m[0],
        fy = fluid_m[1],
        fz = fluid_m[2],
    )
}

/// A downward jet from a nozzle at the origin (0.5 m/s, 2 mm spacing, c = 20 m/s, no gravity)
/// into a domain reaching 0.2 m below it; `nozzle` and `extra` are TOML lines.
pub fn jet_scene(nozzle: &str, extra: &str) -> String {
    format!(
        r#"
name = "jet"
[material]
particle_spacing_m = 0.002
clamp_negative_pressure = true
sound_speed_m_s = 20.0
gravity_m_s2 = [0.0, 0.0, 0.0]
[material.viscosity]
nu0_m2_s = 0.001
[domain]
min_m = [-0.05, -0.2, -0.05]
max_m = [0.05, 0.05, 0.05]
[simulation]
end_time_s = 1.0
precision = "f64"
max_fluid_particles = 200000
[[inlet]]
{nozzle}
position_m = [0.0, 0.0, 0.0]
direction = [0.0, -1.0, 0.0]
speed_m_s = 0.5
{extra}
"#
    )
}

/// Runs the `coil` binary with `args`.
pub fn coil<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_coil")).args(args).output().expect("coil runs")
}

/// `coil` with `args` and the folder `first` searched before the PATH, where a test puts a
/// program coil runs (a stand-in ffmpeg).
pub fn coil_with_path_first<S: AsRef<std::ffi::OsStr>>(first: &std::path::Path, args: &[S]) -> Output {
    let path = std::env::join_paths(
        std::iter::once(first.to_path_buf()).chain(std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())),
    )
    .expect("a joinable PATH");
    Command::new(env!("CARGO_BIN_EXE_coil")).args(args).env("PATH", path).output().expect("coil runs")
}

/// A fixed pseudo-random sequence in [0, 1) (a 64-bit LCG's top 53 bits).
pub fn uniform(state: &mut u64) -> f64 {
    *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

/// Options for a quiet run into `out`, on the CPU unless `run_on` is given a device.
pub fn quiet_run_options(out: &std::path::Path) -> coil::run::RunOptions {
    coil::run::RunOptions {
        backend: coil::run::Backend::Cpu,
        out_dir: out.to_path_buf(),
        precision: None,
        quiet: true,
        preview: false,
        overrides: vec![],
        overwrite: false,
        stop: None,
    }
}

/// Runs `coil run scenes/newtonian_jet.toml` into `out` with divergence-free pressure and
/// implicit viscosity (the settings of its `divergence_free_summed` variant but the viscosity
/// tolerance) and the `extra` settings.
pub fn run_divergence_free_jet(out: &std::path::Path, extra: &[&str]) -> Output {
    let sets = [
        "simulation.pressure=divergence_free",
        "material.density_equation=summation",
        "material.density_kernel=spiky",
        "material.viscosity.solver=implicit",
        "material.viscosity.velocity_gradient=own_density",
        "simulation.particle_shifting=0",
    ];
    let mut args = vec!["run", "scenes/newtonian_jet.toml", "--quiet", "--overwrite", "--out", out.to_str().expect("utf-8")];
    for set in sets.iter().chain(extra) {
        args.extend(["--set", set]);
    }
    coil(&args)
}
